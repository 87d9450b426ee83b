"""A real ``rcservice serve`` (uvicorn subprocess, SQLite file, process pool for calibrations).

- End to end on the EnergyPlus office: three weeks measured plus the next day's inputs, a
  calibration, a 24 h forecast within 1 °C RMSE of EnergyPlus, then a restart that changes
  nothing.
- Concurrency: overlapping uploads from several clients at once, and a calibration running in
  its worker process while uploads and forecasts go on.
"""

from __future__ import annotations

import statistics
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pandas as pd
import pytest

from .conftest import LiveServer, json_rows, register, rmse, wait_for_job

FIRST_DAY = pd.Timestamp("2017-01-09T00:00:00+01:00")
FORECAST_DAY = pd.Timestamp("2017-01-30T00:00:00+01:00")
DAY = pd.Timedelta(hours=24)


def test_office_end_to_end_and_restart(tmp_path, office):
    description, raw = office
    past = raw[(raw.index >= FIRST_DAY) & (raw.index < FORECAST_DAY)]
    future = raw[(raw.index >= FORECAST_DAY) & (raw.index < FORECAST_DAY + DAY)].copy()
    held_back = future["t_in"].astype(float).to_numpy()
    future["t_in"] = ""  # the next day: weather and planned q_hvac only
    body = pd.concat([past, future]).to_csv(index=False)
    assert len(past) == 21 * 96 and len(future) == 96

    server = LiveServer(tmp_path).start()
    try:
        with server.client() as client:
            building_id, headers = register(client, description)
            upload = client.post(
                f"/buildings/{building_id}/measurements",
                content=body,
                headers={**headers, "content-type": "text/csv"},
            )
            assert upload.status_code == 200, upload.text
            assert (upload.json()["inserted"], upload.json()["updated"]) == (22 * 96, 0)
            started = client.post(f"/buildings/{building_id}/calibrations", headers=headers)
            job = wait_for_job(client, started.json()["id"], headers)
            assert (job["status"], job["outcome"], job["days"]) == ("succeeded", "promoted", 7)
            params = {"start": FORECAST_DAY.isoformat(), "hours": 24}
            forecast = client.get(
                f"/buildings/{building_id}/forecast", params=params, headers=headers
            )
            assert forecast.status_code == 200
            predicted = forecast.json()
            assert predicted["times"][0] == "2017-01-30T00:00:00+01:00"
            error = rmse(predicted["t_in_pred"], held_back)
            print(f"office day-ahead forecast RMSE vs EnergyPlus: {error:.3f} °C")
            assert error <= 1.0
            before = snapshot(client, building_id, headers, params)
    finally:
        server.stop()

    server.start()  # the same SQLite file
    try:
        with server.client() as client:
            after = snapshot(client, building_id, headers, params)
    finally:
        server.stop()
    assert after["measurements"] == before["measurements"]
    assert after["parameters"] == before["parameters"]
    assert after["forecast"] == before["forecast"]
    assert after["job"] == before["job"]


def snapshot(client, building_id, headers, params) -> dict:
    def get(path, **kwargs):
        response = client.get(path, headers=headers, **kwargs)
        assert response.status_code == 200, response.text
        return response.json()

    jobs = get(f"/buildings/{building_id}/calibrations")["items"]
    return {
        "measurements": get(f"/buildings/{building_id}/measurements")["rows"],
        "parameters": get(f"/buildings/{building_id}/parameters"),
        "forecast": get(f"/buildings/{building_id}/forecast", params=params),
        "job": get(f"/jobs/{jobs[0]['id']}"),
    }


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    live = LiveServer(tmp_path_factory.mktemp("concurrency"))
    try:
        yield live.start()
    finally:
        live.stop()


def test_parallel_overlapping_uploads_keep_every_row_exactly_once(server, synthetic):
    with server.client() as client:
        building_id, headers = register(client)
    windows = [synthetic.iloc[offset : offset + 96] for offset in range(0, len(synthetic) - 95, 24)]
    tasks = [json_rows(w) for w in windows] * 2  # every window twice, from different clients

    def upload(rows):
        with server.client() as own:
            return own.post(
                f"/buildings/{building_id}/measurements", json={"rows": rows}, headers=headers
            )

    with ThreadPoolExecutor(max_workers=6) as pool:
        responses = list(pool.map(upload, tasks))
    assert [r.status_code for r in responses] == [200] * len(tasks)
    counts = [r.json() for r in responses]
    assert sum(c["inserted"] for c in counts) == len(synthetic)  # each time inserted once
    assert sum(c["inserted"] + c["updated"] for c in counts) == 96 * len(tasks)
    assert sorted(c["data_revision"] for c in counts) == list(range(1, len(tasks) + 1))
    with server.client() as client:
        stored = client.get(f"/buildings/{building_id}/measurements", headers=headers).json()[
            "rows"
        ]
    assert len(stored) == len(synthetic)
    assert [r["time"] for r in stored] == [r["time"] for r in json_rows(synthetic)]
    values = pd.DataFrame(stored).drop(columns="time").to_numpy(dtype=float)
    np.testing.assert_array_equal(
        values, synthetic[list(pd.DataFrame(stored).columns[1:])].to_numpy()
    )


def test_calibration_runs_while_uploads_and_forecasts_go_on(server, synthetic):
    day = 96
    frame = synthetic.copy()
    frame.iloc[3 * day :, frame.columns.get_loc("t_in")] = np.nan
    future = json_rows(frame.iloc[3 * day :])
    with server.client() as client:
        building_id, headers = register(client)
        client.post(
            f"/buildings/{building_id}/measurements",
            json={"rows": json_rows(frame)},
            headers=headers,
        )
        # The current set is of another model, so the job below searches from scratch: one
        # seeded with the current set can end before any forecast sees it running.
        first = client.post(
            f"/buildings/{building_id}/calibrations",
            json={"days": 1, "model": "2r2c"},
            headers=headers,
        )
        assert wait_for_job(client, first.json()["id"], headers)["status"] == "succeeded"
        job_id = client.post(
            f"/buildings/{building_id}/calibrations", json={"days": 2}, headers=headers
        ).json()["id"]

    done = threading.Event()
    uploads: list[int] = []

    def keep_uploading():
        with server.client() as own:
            while not done.is_set():
                response = own.post(
                    f"/buildings/{building_id}/measurements", json={"rows": future}, headers=headers
                )
                uploads.append(response.status_code)

    uploader = threading.Thread(target=keep_uploading)
    uploader.start()
    forecasts: list[tuple[int, float, str]] = []  # status, latency [ms], job status seen after
    try:
        with server.client() as client:
            deadline = time.monotonic() + 60.0
            status = "queued"
            while status in ("queued", "running") and time.monotonic() < deadline:
                hours = 6 + len(forecasts) % 18  # a new horizon each time: not served from cache
                began = time.perf_counter()
                response = client.get(
                    f"/buildings/{building_id}/forecast",
                    params={"start": "2017-01-12T01:00:00+01:00", "hours": hours},
                    headers=headers,
                )
                latency = (time.perf_counter() - began) * 1000.0
                status = client.get(f"/jobs/{job_id}", headers=headers).json()["status"]
                forecasts.append((response.status_code, latency, status))
    finally:
        done.set()
        uploader.join()
    assert status == "succeeded"
    assert {code for code, _, _ in forecasts} == {200}
    assert uploads and set(uploads) == {200}
    during = [ms for _, ms, seen in forecasts if seen == "running"]
    assert during, "no forecast was answered while the calibration was running"
    print(
        f"{len(during)} forecasts while the job ran: median {statistics.median(during):.1f} ms, "
        f"max {max(during):.1f} ms; {len(uploads)} uploads meanwhile"
    )
