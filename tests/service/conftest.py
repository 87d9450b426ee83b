"""Fixtures of the service tests: an in-process app on a fresh SQLite file, data, a real server.

In-process tests use FastAPI's TestClient with calibrations on a thread (``workers=0``), so that a
test can monkeypatch the calibration; the live-server tests run ``rcservice serve`` in a
subprocess with its real process pool.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

import httpx
import numpy as np
import pandas as pd
import pytest
from alembic.config import Config
from fastapi.testclient import TestClient
from sqlalchemy import text

from rcengine.io.timeseries import format_times
from service.core.config import Settings
from service.core.db import Database, alembic_config
from service.main import create_app

from ..synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains
from .postgres import PostgresServer

ADMIN_TOKEN = "test-admin-token-0123456789abcdef"
ADMIN = {"Authorization": f"Bearer {ADMIN_TOKEN}"}
TIMEZONE = "Europe/Rome"
SYNTHETIC_BUILDING = {**BUILDING.to_dict(), "name": "synthetic-office"}
ROOT = Path(__file__).resolve().parents[2]
OFFICE = ROOT / "data" / "energyplus" / "office"


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def json_rows(frame: pd.DataFrame, timezone: str = TIMEZONE) -> list[dict]:
    """Contract rows as the JSON upload carries them: local times with offset, null for NaN."""
    times = format_times(frame.index, timezone)
    rows = []
    for t, values in zip(times, frame.to_dict("records"), strict=True):
        rows.append({"time": t, **{k: (None if pd.isna(v) else v) for k, v in values.items()}})
    return rows


# --- databases --------------------------------------------------------------------------------
BACKENDS = ("sqlite", "postgresql")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    """Tests of a module with ``ON_BOTH_DATABASES = True`` run on SQLite and on PostgreSQL."""
    if getattr(metafunc.module, "ON_BOTH_DATABASES", False) and (
        "database_url" in metafunc.fixturenames
    ):
        metafunc.parametrize("backend", BACKENDS, indirect=True)


@pytest.fixture
def backend(request: pytest.FixtureRequest) -> str:
    return getattr(request, "param", "sqlite")


@pytest.fixture(scope="session")
def postgres() -> Iterator[PostgresServer]:
    server = PostgresServer()
    try:
        yield server
    finally:
        server.stop()


@pytest.fixture
def database_url(backend: str, tmp_path: Path, request: pytest.FixtureRequest) -> Iterator[str]:
    """A fresh empty database of the test's backend."""
    if backend == "sqlite":
        yield f"sqlite:///{tmp_path / 'rcservice.db'}"
        return
    server: PostgresServer = request.getfixturevalue("postgres")
    name = server.create()
    try:
        yield server.url(name)
    finally:
        server.drop(name)


# --- in-process app -------------------------------------------------------------------------
def app_settings(database_url: str, **overrides: Any) -> Settings:
    """Settings of an in-process test app: the test admin token, jobs on a thread (so that a
    test can monkeypatch them), no scheduler; ``overrides`` for the rest."""
    return Settings(
        database_url=database_url,
        admin_token=ADMIN_TOKEN,
        workers=0,
        scheduler_enabled=False,
        **overrides,
    )


def module_client(name: str, **overrides: Any) -> Any:
    """A module-scoped ``client`` fixture: one app on a SQLite file in a fresh folder ``name``,
    with the settings ``overrides``, shared by the module's tests (``client = module_client(...)``
    in the module)."""

    @pytest.fixture(scope="module")
    def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
        folder = tmp_path_factory.mktemp(name)
        settings = app_settings(f"sqlite:///{folder / 'rcservice.db'}", **overrides)
        with TestClient(create_app(settings)) as test_client:
            yield test_client

    return client


@pytest.fixture
def settings(database_url: str) -> Settings:
    return app_settings(database_url, max_body_bytes=200_000)


def migrate(db: Database, step: Callable[[Config, str], None], revision: str) -> None:
    """``step`` (alembic upgrade or downgrade) on the service's own connection (foreign keys on)."""
    with db.engine.begin() as connection:
        config = alembic_config(db.url)
        config.attributes["connection"] = connection
        step(config, revision)


def schema_revision(db: Database) -> str:
    """The migration the database is at."""
    with db.session() as session:
        return session.execute(text("SELECT version_num FROM alembic_version")).scalar()


@pytest.fixture
def db(settings: Settings) -> Iterator[Database]:
    """The test's database, migrated, without an app."""
    database = Database(settings.database_url)
    database.migrate()
    yield database
    database.dispose()


@pytest.fixture
def client(settings: Settings) -> Iterator[TestClient]:
    with TestClient(create_app(settings)) as test_client:
        yield test_client


def register(
    client: TestClient | httpx.Client, description: dict | None = None
) -> tuple[int, dict]:
    """Register a building with the admin token; returns its id and auth headers."""
    response = client.post("/buildings", json=description or SYNTHETIC_BUILDING, headers=ADMIN)
    assert response.status_code == 201, response.text
    body = response.json()
    return body["id"], bearer(body["token"])


def assert_refused(response, field: str) -> None:
    """422 in the documented shape: a text detail and problems naming ``field``."""
    assert response.status_code == 422, response.text
    body = response.json()
    assert isinstance(body["detail"], str) and field in body["detail"]
    assert any(p["column"] == field for p in body["problems"]), body


def wait_for_job(client: TestClient | httpx.Client, job_id: int, headers: dict, timeout_s=60.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        job = client.get(f"/jobs/{job_id}", headers=headers).json()
        if job["status"] in ("succeeded", "failed"):
            return job
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} did not finish in {timeout_s} s: {job}")


# --- data -------------------------------------------------------------------------------------
# Rows of one day at 15 min.
DAY = 96


@pytest.fixture(scope="session")
def synthetic() -> pd.DataFrame:
    """Four days at 15 min with t_in from the hand-written 3R3C reference (tests/synthetic.py)."""
    frame = weather_and_gains(days=4, seed=5)
    frame["t_in"] = basic_reference(frame, TRUTH_BASIC, x0=(8.0, 19.0, 18.5))
    return frame[["t_in", "t_out", "ghi", "q_hvac", "q_occ", "q_light"]]


@pytest.fixture(scope="session")
def three_days_measured(synthetic) -> pd.DataFrame:
    """The synthetic days with t_in measured on days 1–3; day 4 holds future inputs only."""
    frame = synthetic.copy()
    frame.iloc[3 * DAY :, frame.columns.get_loc("t_in")] = np.nan
    return frame


@pytest.fixture
def measured(client, three_days_measured) -> tuple[int, dict]:
    """A registered building with ``three_days_measured`` uploaded: its id and headers."""
    building_id, headers = register(client)
    response = client.post(
        f"/buildings/{building_id}/measurements",
        json={"rows": json_rows(three_days_measured)},
        headers=headers,
    )
    assert response.status_code == 200, response.text
    return building_id, headers


@pytest.fixture
def calibrated(client, measured) -> tuple[int, dict]:
    """Days 1–3 measured, day 4 future inputs only, a current set fitted on day 2."""
    building_id, headers = measured
    job = client.post(f"/buildings/{building_id}/calibrations", json={"days": 1}, headers=headers)
    assert wait_for_job(client, job.json()["id"], headers)["outcome"] == "promoted"
    return building_id, headers


@pytest.fixture(scope="session")
def office() -> tuple[dict, pd.DataFrame]:
    """The EnergyPlus office: building JSON and the heating-season CSV, cells as text."""
    csv, building = OFFICE / "heating.csv", OFFICE / "building.json"
    if not (csv.exists() and building.exists()):
        pytest.skip(f"EnergyPlus reference data not found in {OFFICE}")
    raw = pd.read_csv(csv, dtype=str, keep_default_na=False)
    raw.index = pd.to_datetime(raw["time"], utc=True)
    return json.loads(building.read_text()), raw


# --- a real server ----------------------------------------------------------------------------
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LiveServer:
    """``rcservice serve`` in a subprocess on a SQLite file; stderr goes to a log file."""

    def __init__(self, folder: Path, **env: str):
        self.folder = folder
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = {
            **os.environ,
            "RCSERVICE_DATABASE_URL": f"sqlite:///{folder / 'rcservice.db'}",
            "RCSERVICE_ADMIN_TOKEN": ADMIN_TOKEN,
            "RCSERVICE_SCHEDULER_ENABLED": "false",
            **env,
        }
        self.process: subprocess.Popen | None = None
        self.starts = 0
        self._log: IO[str] | None = None

    def start(self) -> LiveServer:
        self.starts += 1
        self._log = (self.folder / f"server-{self.starts}.log").open("w")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "service.cli", "serve", "--port", str(self.port)],
            env=self.env,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            cwd=self.folder,
        )
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"server exited: {self.log()}")
            try:
                if httpx.get(f"{self.url}/health", timeout=1.0).status_code == 200:
                    return self
            except httpx.TransportError:
                time.sleep(0.1)
        raise RuntimeError(f"server did not answer /health in 30 s: {self.log()}")

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self._log is not None:
            self._log.close()

    def log(self) -> str:
        return (self.folder / f"server-{self.starts}.log").read_text()[-4000:]

    def client(self, **kwargs) -> httpx.Client:
        return httpx.Client(base_url=self.url, timeout=60.0, **kwargs)


@pytest.fixture
def live_server(tmp_path: Path) -> Iterator[LiveServer]:
    server = LiveServer(tmp_path)
    try:
        yield server.start()
    finally:
        server.stop()


def run_docs_session(folder: Path, heading: str, **env: str) -> str:
    """Run the first bash block after ``heading`` in docs/service.md as written, against a live
    server in ``folder`` with the repository's data beside it and the fast "modestpy" preset for
    diagnoses; its output, once it has succeeded (else the test fails with the server's log).

    No admin token is given: the server generates one into rcservice-admin-token beside its
    database, as for `make run`, and the session reads it from there."""
    docs = (ROOT / "docs" / "service.md").read_text()
    after = docs[docs.index(heading) :]
    block = re.search(r"```bash\n(.*?)```", after, re.DOTALL).group(1)
    (folder / "data").symlink_to(ROOT / "data")
    server = LiveServer(folder, RCSERVICE_DIAGNOSIS_PRESET="modestpy", **env)
    server.env.pop("RCSERVICE_ADMIN_TOKEN")
    server.start()
    try:
        run = subprocess.run(
            ["bash", "-c", "set -euo pipefail\n" + block.replace("localhost:8000", server.url)],
            cwd=folder,
            capture_output=True,
            text=True,
            timeout=600,
            env={**os.environ, "PATH": f"{Path(sys.executable).parent}:{os.environ['PATH']}"},
        )
    finally:
        server.stop()
    assert run.returncode == 0, f"{run.stdout[-3000:]}\n{run.stderr[-2000:]}\n{server.log()}"
    return run.stdout


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) ** 2)))
