"""Defects found by probing a running server (nineteenth session): a device that uploads one row
at a time, a device whose clock is wrong, numbers and times at the edges of what Python and
pandas hold. None answers 500; every refusal names the field and stores nothing."""

from __future__ import annotations

import pandas as pd
import pytest

from service.jobs import queue_retraining

from .conftest import assert_refused, json_rows, register, wait_for_job

ON_BOTH_DATABASES = True


def summary(client, building_id, headers) -> dict:
    return client.get(f"/buildings/{building_id}", headers=headers).json()


def upload(client, building_id, headers, rows: list[dict]):
    return client.post(
        f"/buildings/{building_id}/measurements", json={"rows": rows}, headers=headers
    )


def row(time: str, t_in: float | None = 20.0) -> dict:
    return {"time": time, "t_in": t_in, "t_out": 5.0, "ghi": 0.0, "q_hvac": 0.0}


def test_a_series_streamed_one_row_at_a_time_gets_its_step_and_grid(client):
    building_id, headers = register(client)
    assert upload(client, building_id, headers, [row("2017-01-09T00:00:00Z")]).status_code == 200
    # One time stored: no step yet, so no job can be planned — a clear 409, not a 500.
    for kind in ("calibrations", "diagnoses"):
        answer = client.post(f"/buildings/{building_id}/{kind}", json={}, headers=headers)
        assert answer.status_code == 409, answer.text
        assert "no time step yet" in answer.json()["detail"]
    assert upload(client, building_id, headers, [row("2017-01-09T00:15:00Z")]).status_code == 200
    assert summary(client, building_id, headers)["step_s"] == 900.0
    before = summary(client, building_id, headers)
    off_grid = upload(client, building_id, headers, [row("2017-01-09T00:22:00Z")])
    assert off_grid.status_code == 422, off_grid.text
    assert "900-s grid" in off_grid.json()["detail"]
    assert summary(client, building_id, headers) == before


def test_one_building_without_a_step_does_not_stop_the_nightly_queue(
    client, db, settings, three_days_measured
):
    good, good_headers = register(client)
    upload(client, good, good_headers, json_rows(three_days_measured.iloc[:288]))
    single, single_headers = register(client)
    assert upload(client, single, single_headers, [row("2017-01-09T00:00:00Z")]).status_code == 200
    queued = queue_retraining(db, settings, "schedule")
    assert len(queued) == 1
    job = client.get(f"/jobs/{queued[0]}", headers=good_headers)
    assert job.status_code == 200 and job.json()["building_id"] == good


def test_a_measurement_from_the_future_is_refused_a_forecast_row_is_not(client, measured):
    building_id, headers = measured
    before = summary(client, building_id, headers)
    ahead = (pd.Timestamp.now(tz="UTC") + pd.Timedelta(days=2)).floor("D").isoformat()
    refused = upload(client, building_id, headers, [row(ahead)])
    assert refused.status_code == 422, refused.text
    assert "after the server's clock" in refused.json()["detail"]
    assert any(p["column"] == "t_in" for p in refused.json()["problems"])
    assert summary(client, building_id, headers) == before


@pytest.mark.parametrize("when", ["2199-12-31T23:45:00+00:00", "2262-04-11T23:45:00+00:00"])
def test_times_near_the_supported_edge_are_stored_and_shown_or_refused(client, when):
    """A row at 2262-04-11T23:45Z was stored, then every read of the building — and the admin
    list of all buildings — answered 500 (its Rome time overflowed). Now 2262 is refused and the
    last supported day is stored and shown in the building's zone."""
    building_id, headers = register(client)
    answer = upload(client, building_id, headers, [row(when, None)])
    if when.startswith("2262"):
        assert answer.status_code == 422 and "supported range" in answer.json()["detail"]
    else:
        assert answer.status_code == 200, answer.text
    assert client.get(f"/buildings/{building_id}", headers=headers).status_code == 200
    assert client.get(f"/buildings/{building_id}/measurements", headers=headers).status_code == 200


@pytest.mark.parametrize("digits", [401, 5001])
def test_an_integer_too_long_for_a_float_is_a_422(client, measured, digits):
    building_id, headers = measured
    before = summary(client, building_id, headers)
    body = '{"rows": [{"time": "2017-01-09T00:00:00Z", "t_in": 1' + "0" * digits + "}]}"
    answer = client.post(
        f"/buildings/{building_id}/measurements",
        content=body,
        headers={**headers, "Content-Type": "application/json"},
    )
    assert answer.status_code == 422, answer.text
    assert summary(client, building_id, headers) == before


def test_long_inputs_are_not_echoed_whole(client, measured):
    building_id, headers = measured
    long_time = "x" * 100_000
    answer = upload(client, building_id, headers, [row(long_time)])
    assert answer.status_code == 422
    assert len(answer.text) < 2_000
    echoed = client.get("/health", headers={"X-Request-ID": "y" * 8_000})
    assert len(echoed.headers["x-request-id"]) <= 128
    kept = client.get("/health", headers={"X-Request-ID": "trace-42"})
    assert kept.headers["x-request-id"] == "trace-42"


def test_a_train_fraction_the_engine_refuses_is_refused_with_the_request(client, measured):
    building_id, headers = measured
    for fraction in (0.01, 0.99):
        answer = client.post(
            f"/buildings/{building_id}/diagnoses",
            json={"train_fraction": fraction},
            headers=headers,
        )
        assert answer.status_code == 422, answer.text
        assert "train_fraction" in answer.text


def test_a_stray_row_is_taken_back_and_the_building_calibrates_again(client, measured):
    """A device a few years off: its row became the last measurement, every calibration then
    planned its window up to 2020, and no upload could take the row back."""
    building_id, headers = measured
    url = f"/buildings/{building_id}/measurements"
    before = summary(client, building_id, headers)
    assert upload(client, building_id, headers, [row("2020-01-01T00:00:00Z")]).status_code == 200
    assert summary(client, building_id, headers)["last_measured_time"].startswith("2020")
    removed = client.delete(
        url,
        params={"start": "2019-12-31T00:00:00Z", "end": "2020-01-02T00:00:00Z"},
        headers=headers,
    )
    assert removed.status_code == 200, removed.text
    body = removed.json()
    assert body["deleted"] == 1
    assert body["last_measured_time"] == before["last_measured_time"]
    after = summary(client, building_id, headers)
    assert after["data_revision"] == before["data_revision"] + 2
    job = client.post(f"/buildings/{building_id}/calibrations", json={"days": 1}, headers=headers)
    assert wait_for_job(client, job.json()["id"], headers)["status"] == "succeeded"


def test_deleting_every_row_forgets_the_grid_and_bounds_are_checked(client, measured):
    building_id, headers = measured
    url = f"/buildings/{building_id}/measurements"
    inverted = client.delete(
        url,
        params={"start": "2017-01-10T00:00:00Z", "end": "2017-01-09T00:00:00Z"},
        headers=headers,
    )
    assert_refused(inverted, "end")
    missing = client.delete(url, params={"start": "2017-01-10T00:00:00Z"}, headers=headers)
    assert missing.status_code == 422
    everything = {"start": "1900-01-01T00:00:00Z", "end": "2199-12-31T00:00:00Z"}
    assert client.delete(url, params=everything, headers=headers).json()["deleted"] == 4 * 96
    emptied = summary(client, building_id, headers)
    assert emptied["step_s"] is None and emptied["last_measured_time"] is None
    # A new series on another grid is accepted: the old one is gone.
    fresh = [row("2017-02-01T00:07:00Z"), row("2017-02-01T00:37:00Z")]
    assert upload(client, building_id, headers, fresh).status_code == 200
    assert summary(client, building_id, headers)["step_s"] == 1800.0


def test_a_diagnosis_whose_rows_were_deleted_while_queued_says_so():
    """Every row deleted after the job was queued: the building forgot its step, and the job
    failed with a TypeError (None × rows)."""
    from types import SimpleNamespace

    from service import diagnosis
    from service.errors import DiagnosisError

    window = SimpleNamespace(
        start=pd.Timestamp("2017-01-01", tz="UTC"), end=pd.Timestamp("2017-01-29", tz="UTC")
    )
    empty = pd.DataFrame({"t_in": []}, dtype=float)
    with pytest.raises(DiagnosisError, match="not enough measured data"):
        diagnosis._check_enough(empty, window, None)


def test_two_rows_days_apart_are_a_gap_not_a_step(client):
    building_id, headers = register(client)
    assert upload(client, building_id, headers, [row("2017-01-01T00:00:00Z")]).status_code == 200
    assert upload(client, building_id, headers, [row("2017-01-03T05:00:00Z")]).status_code == 200
    assert summary(client, building_id, headers)["step_s"] is None
    # The first interval a step can be sets it, on the grid of the first row.
    assert upload(client, building_id, headers, [row("2017-01-03T05:15:00Z")]).status_code == 200
    assert summary(client, building_id, headers)["step_s"] == 900.0


def test_bounds_finer_than_a_microsecond_keep_start_le_time_lt_end(client):
    building_id, headers = register(client)
    rows = [row(f"2017-01-09T00:{m:02d}:00Z") for m in (0, 15, 30)]
    assert upload(client, building_id, headers, rows).status_code == 200
    url = f"/buildings/{building_id}/measurements"
    window = {"start": "2017-01-09T00:00:00.000000001Z", "end": "2017-01-09T00:15:00.0000001Z"}
    read = client.get(url, params=window, headers=headers).json()["rows"]
    assert [r["time"][11:19] for r in read] == ["01:15:00"]  # 00:15 UTC in Rome
    assert client.delete(url, params=window, headers=headers).json()["deleted"] == 1
    left = client.get(url, headers=headers).json()["rows"]
    assert [r["time"][11:19] for r in left] == ["01:00:00", "01:30:00"]


def test_an_optional_column_sent_on_some_days_only_is_left_out_of_the_fit(
    client, three_days_measured
):
    """q_occ uploaded on days 1 and 3 only: the fit met missing inputs and failed naming row
    positions of its window; an upload cannot erase the column either."""
    building_id, headers = register(client)
    for day in range(4):
        rows = json_rows(three_days_measured.iloc[day * 96 : (day + 1) * 96])
        if day % 2:
            rows = [{k: v for k, v in r.items() if k != "q_occ"} for r in rows]
        assert upload(client, building_id, headers, rows).status_code == 200
    job = client.post(f"/buildings/{building_id}/calibrations", json={"days": 2}, headers=headers)
    done = wait_for_job(client, job.json()["id"], headers)
    assert done["status"] == "succeeded", done["error"]
    assert any("column 'q_occ' left out" in w for w in done["details"]["warnings"])
