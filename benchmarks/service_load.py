"""Load test of the service on loopback: uploads, then forecasts from 20 concurrent clients.

Starts ``rcservice serve`` in a subprocess on a temporary SQLite file (``--database
postgresql``: a PostgreSQL server of the ``pgserver`` wheel, on its Unix socket), registers the
EnergyPlus office (synthetic data if the files are absent), uploads the heating season, measures
concurrent uploads (8 clients sending overlapping batches: rows/s, latency p50/p95), calibrates,
then drives forecasts for a bounded time in three phases:

1. ``forecast_*`` — the MPC pattern: 20 controllers ask for the 24 h forecast from the current
   step while one new measurement row arrives every second (each upload invalidates the cached
   forecast, so it is recomputed once per second and served to every client);
2. ``forecast_uncached_*`` — the worst case: every request a different start, nothing cached;
3. ``forecast_during_calibration_*`` — phase 1 while calibrations run back to back.

Latency is measured by the clients (request sent → answer read), on persistent connections.
At the end the building's ``data_revision`` must equal the number of accepted uploads (none lost
to concurrent writers). Prints a JSON line last. Targets on a 2-core machine: forecast p95 ≤ 50
ms at 20 clients, uploads ≥ 20,000 rows/s, no errors, revisions == uploads.

    python benchmarks/service_load.py [--clients 20] [--seconds 20] [--database postgresql]
"""

from __future__ import annotations

import argparse
import http.client
import json
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from urllib.parse import urlencode

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
OFFICE = ROOT / "data" / "energyplus" / "office"
ADMIN_TOKEN = "benchmark-admin-token-0123456789abcdef"
FORECAST_START = "2017-01-30T00:00:00+01:00"


class Server:
    def __init__(self, folder: Path, database_url: str):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        env = {
            **os.environ,
            "RCSERVICE_DATABASE_URL": database_url,
            "RCSERVICE_ADMIN_TOKEN": ADMIN_TOKEN,
            "RCSERVICE_SCHEDULER_ENABLED": "false",
        }
        self.log = open(folder / "server.log", "w")  # noqa: SIM115 - closed in stop()
        self.process = subprocess.Popen(
            [sys.executable, "-m", "service.cli", "serve", "--port", str(self.port)],
            env=env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
            cwd=folder,
        )
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                if request(self.port, "GET", "/health")[0] == 200:
                    return
            except OSError:
                time.sleep(0.1)
        raise RuntimeError("server did not start")

    def stop(self) -> None:
        self.process.send_signal(signal.SIGINT)
        self.process.wait(timeout=30)
        self.log.close()


def request(port, method, path, body=None, headers=None, connection=None):
    """(status, parsed JSON) over a new or the given keep-alive connection."""
    conn = connection or http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    conn.request(method, path, body=body, headers=headers or {})
    response = conn.getresponse()
    data = response.read()
    if connection is None:
        conn.close()
    kind = response.getheader("content-type", "")
    return response.status, json.loads(data) if kind.startswith("application/json") else data


def load_data() -> tuple[dict, pd.DataFrame, str]:
    """Building description, the season as a frame (UTC index), and where it came from."""
    if (OFFICE / "heating.csv").exists():
        from rcengine.io.timeseries import read_timeseries

        return (
            json.loads((OFFICE / "building.json").read_text()),
            read_timeseries(OFFICE / "heating.csv"),
            "energyplus-office",
        )
    sys.path.insert(0, str(ROOT))
    from tests.synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains

    frame = weather_and_gains(days=28, seed=1)
    frame.index = frame.index - pd.Timedelta(days=7)
    frame["t_in"] = basic_reference(frame, TRUTH_BASIC, x0=(8.0, 19.0, 18.5))
    return BUILDING.to_dict(), frame, "synthetic"


def json_body(frame: pd.DataFrame) -> bytes:
    from rcengine.io.timeseries import format_times

    rows = []
    for t, values in zip(
        format_times(frame.index, "Europe/Rome"), frame.to_dict("records"), strict=True
    ):
        rows.append({"time": t, **{k: (None if pd.isna(v) else v) for k, v in values.items()}})
    return json.dumps({"rows": rows}).encode()


def timed_upload(port, building_id, token, body, content_type) -> tuple[float, dict]:
    headers = {"Authorization": f"Bearer {token}", "Content-Type": content_type}
    began = time.perf_counter()
    status, answer = request(port, "POST", f"/buildings/{building_id}/measurements", body, headers)
    elapsed = time.perf_counter() - began
    if status != 200:
        raise RuntimeError(f"upload failed: {status} {answer}")
    return elapsed, answer


def calibrate(port, building_id, token, days=7) -> dict:
    headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/json"}
    status, job = request(
        port, "POST", f"/buildings/{building_id}/calibrations", json.dumps({"days": days}), headers
    )
    if status != 202:
        raise RuntimeError(f"calibration not started: {status} {job}")
    while job["status"] in ("queued", "running"):
        time.sleep(0.1)
        job = request(port, "GET", f"/jobs/{job['id']}", headers=headers)[1]
    return job


def drive(port, building_id, token, clients, seconds, paths) -> dict:
    """``clients`` threads asking for forecasts for ``seconds``; ``paths()`` gives each URL."""
    headers = {"Authorization": f"Bearer {token}"}
    latencies: list[list[float]] = [[] for _ in range(clients)]
    errors = [0] * clients
    stop_at = time.perf_counter() + seconds

    def client(i: int) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        while time.perf_counter() < stop_at:
            began = time.perf_counter()
            try:
                conn.request("GET", paths(), headers=headers)
                response = conn.getresponse()
                response.read()
                ok = response.status == 200
            except OSError:
                ok = False
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
            latencies[i].append((time.perf_counter() - began) * 1000.0)
            errors[i] += not ok
        conn.close()

    elapsed, every = run_clients(client, latencies)
    return {
        **percentiles(every),
        "rps": round(len(every) / elapsed, 1),
        "requests": len(every),
        "errors": int(sum(errors)),
    }


def run_clients(client, latencies: list[list[float]]) -> tuple[float, np.ndarray]:
    """``client(i)`` on one thread per list of ``latencies``; wall time [s] and every latency."""
    threads = [threading.Thread(target=client, args=(i,)) for i in range(len(latencies))]
    began = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return time.perf_counter() - began, np.concatenate([np.asarray(x) for x in latencies])


def percentiles(latencies_ms: np.ndarray) -> dict[str, float]:
    return {f"p{q}_ms": round(float(np.percentile(latencies_ms, q)), 2) for q in (50, 95)}


def background(stop: threading.Event, action, pause_s: float) -> threading.Thread:
    def loop() -> None:
        while not stop.is_set():
            action()
            stop.wait(pause_s)

    thread = threading.Thread(target=loop)
    thread.start()
    return thread


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=20.0, help="phase 1 duration [s]")
    parser.add_argument("--database", choices=("sqlite", "postgresql"), default="sqlite")
    args = parser.parse_args()
    description, frame, source = load_data()
    forecast_start = pd.Timestamp(FORECAST_START if source != "synthetic" else frame.index[-96])
    with tempfile.TemporaryDirectory() as folder, database(args.database, Path(folder)) as url:
        server = Server(Path(folder), url)
        try:
            results = run(server.port, description, frame, forecast_start, args)
        finally:
            server.stop()
    results["data"], results["database"] = source, args.database
    print(
        f"uploads: {results['upload_rows_per_s']:.0f} rows/s (JSON, insert), "
        f"{results['upload_csv_rows_per_s']:.0f} rows/s (CSV, update); concurrent: "
        f"{results['upload_concurrent_rows_per_s']:.0f} rows/s, p95 "
        f"{results['upload_p95_ms']} ms; revisions == uploads: {results['revisions_equal_uploads']}"
    )
    for phase in ("", "uncached_", "during_calibration_"):
        print(
            f"forecast {phase or 'mpc_'}: p50 {results[f'forecast_{phase}p50_ms']} ms, "
            f"p95 {results[f'forecast_{phase}p95_ms']} ms, {results[f'forecast_{phase}rps']} req/s"
        )
    print(json.dumps(results))


@contextmanager
def database(kind: str, folder: Path) -> Iterator[str]:
    """URL of an empty database of ``kind``: a SQLite file, or a PostgreSQL server started here."""
    if kind == "sqlite":
        yield f"sqlite:///{folder / 'bench.db'}"
        return
    sys.path.insert(0, str(ROOT))
    from tests.service.postgres import PostgresServer

    server = PostgresServer()
    try:
        yield server.url(server.create())
    finally:
        server.stop()


def concurrent_uploads(port, building_id, token, frame, clients=8, uploads=25) -> dict:
    """``clients`` threads each sending ``uploads`` overlapping 96-row batches (re-sent rows)."""
    headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/json"}
    bodies = [json_body(frame.iloc[48 * k : 48 * k + 96]) for k in range(clients)]
    latencies: list[list[float]] = [[] for _ in range(clients)]
    accepted = [0] * clients

    def client(i: int) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
        path = f"/buildings/{building_id}/measurements"
        for _ in range(uploads):
            began = time.perf_counter()
            status, _ = request(port, "POST", path, bodies[i], headers, conn)
            latencies[i].append((time.perf_counter() - began) * 1000.0)
            accepted[i] += status == 200
        conn.close()

    elapsed, every = run_clients(client, latencies)
    return {
        "rows_per_s": round(96 * sum(accepted) / elapsed),
        **percentiles(every),
        "accepted": sum(accepted),
        "errors": clients * uploads - sum(accepted),
    }


def forecast_phases(port, building_id, token, frame, forecast_start, args) -> tuple:
    """The three forecast phases of the module docstring; also the calibrations run during the
    third and whether each re-sent measurement was accepted."""
    query = urlencode({"start": forecast_start.isoformat(), "hours": 24})
    mpc_path = f"/buildings/{building_id}/forecast?{query}"
    # One new (re-sent) measurement row per second: the cached forecast is recomputed each time.
    step = frame.loc[[forecast_start - pd.Timedelta(minutes=15)]]
    step_body = json_body(step)
    upload_headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/json"}

    resent = []

    def new_measurement() -> None:
        path = f"/buildings/{building_id}/measurements"
        resent.append(request(port, "POST", path, step_body, upload_headers)[0] == 200)

    stop = threading.Event()
    uploader = background(stop, new_measurement, 1.0)
    mpc = drive(port, building_id, token, args.clients, args.seconds, lambda: mpc_path)
    stop.set()
    uploader.join()

    measured = frame.index[(frame.index >= frame.index[0] + pd.Timedelta(days=3))]
    starts = measured[measured <= frame.index[-1] - pd.Timedelta(hours=24)]
    rng = random.Random(0)

    def any_start() -> str:
        start = starts[rng.randrange(len(starts))]
        return f"/buildings/{building_id}/forecast?" + urlencode(
            {"start": start.isoformat(), "hours": 24}
        )

    uncached = drive(port, building_id, token, args.clients, args.seconds / 2, any_start)

    stop = threading.Event()
    calibrations = []
    calibrator = background(
        stop, lambda: calibrations.append(calibrate(port, building_id, token)), 0.0
    )
    during = drive(port, building_id, token, args.clients, args.seconds / 2, lambda: mpc_path)
    stop.set()
    calibrator.join()

    return mpc, uncached, during, calibrations, resent


def run(port, description, frame, forecast_start, args) -> dict:
    admin = {"Authorization": f"Bearer {ADMIN_TOKEN}", "Content-Type": "application/json"}
    status, created = request(port, "POST", "/buildings", json.dumps(description), admin)
    if status != 201:
        raise RuntimeError(f"registration failed: {status} {created}")
    building_id, token = created["id"], created["token"]
    body = json_body(frame)
    insert_s, inserted = timed_upload(port, building_id, token, body, "application/json")
    csv = frame.rename_axis("time").reset_index()
    csv["time"] = csv["time"].map(lambda t: t.isoformat())
    update_s, updated = timed_upload(
        port, building_id, token, csv.to_csv(index=False).encode(), "text/csv"
    )
    parallel = concurrent_uploads(port, building_id, token, frame)
    job = calibrate(port, building_id, token)
    if job["status"] != "succeeded":
        raise RuntimeError(f"calibration failed: {job}")

    mpc, uncached, during, calibrations, resent = forecast_phases(
        port, building_id, token, frame, forecast_start, args
    )
    uploads = 2 + parallel["accepted"] + sum(resent)
    auth = {"Authorization": f"Bearer {token}"}
    revision = request(port, "GET", f"/buildings/{building_id}", headers=auth)[1]
    results = {
        "forecast_p50_ms": mpc["p50_ms"],
        "forecast_p95_ms": mpc["p95_ms"],
        "forecast_rps": mpc["rps"],
        "upload_rows_per_s": round(inserted["rows"] / insert_s),
        "errors": mpc["errors"] + uncached["errors"] + during["errors"] + parallel["errors"],
        "upload_concurrent_rows_per_s": parallel["rows_per_s"],
        "upload_p50_ms": parallel["p50_ms"],
        "upload_p95_ms": parallel["p95_ms"],
        "uploads": uploads,
        "data_revision": revision["data_revision"],
        "revisions_equal_uploads": revision["data_revision"] == uploads,
        "clients": args.clients,
        "upload_rows": inserted["rows"],
        "upload_csv_rows_per_s": round(updated["rows"] / update_s),
        "forecast_uncached_p50_ms": uncached["p50_ms"],
        "forecast_uncached_p95_ms": uncached["p95_ms"],
        "forecast_uncached_rps": uncached["rps"],
        "forecast_during_calibration_p50_ms": during["p50_ms"],
        "forecast_during_calibration_p95_ms": during["p95_ms"],
        "forecast_during_calibration_rps": during["rps"],
        "calibrations_during": len(calibrations),
        "cpu_count": os.cpu_count(),
    }
    return results


if __name__ == "__main__":
    main()
