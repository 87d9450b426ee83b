"""Fleet scale-out (issue 14): the Dask backend fits what the pool fits, a worker lost mid-run
costs no decision and makes none twice, several service processes on one PostgreSQL re-estimate
each building once, and a dead replica's claims are released when its lease expires."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import select

from benchmarks.fleet import FleetMaker, store_fleet
from service import diagnosis, repository
from service.backends import PoolBackend
from service.core.config import Settings
from service.core.db import Database
from service.diagnosis import DiagnosisSpec
from service.fleet import retrain_all
from service.jobs import INTERRUPTED, JobRunner, announce_mode, kinds, queue_retraining
from service.models import (
    CALIBRATION,
    DIAGNOSIS,
    FAILED,
    QUEUED,
    RUNNING,
    SUCCEEDED,
    BuildingRecord,
    JobRecord,
    ParameterSetRecord,
)

from .conftest import ADMIN_TOKEN, OFFICE

pytestmark = pytest.mark.skipif(
    not (OFFICE / "heating.csv").exists(), reason="EnergyPlus office data not found"
)
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def fleet() -> tuple[dict, list]:
    """Twelve perturbed offices of three days (their description, their frames)."""
    maker = FleetMaker(seed=3)
    return maker.description, [maker.variant(days=3) for _ in range(12)]


@pytest.fixture(scope="module")
def cluster() -> Iterator[object]:
    """A LocalCluster of two single-threaded worker processes, shared by the module."""
    from service.backends.dask import DaskBackend

    backend = DaskBackend("local", n_workers=2)
    try:
        yield backend
    finally:
        backend.close()


def fleet_settings(database_url: str, **changes: object) -> Settings:
    chosen = {
        "admin_token": ADMIN_TOKEN,
        "workers": 0,
        "scheduler_enabled": False,
        "training_days": 2,
        "preset": "study",
        "log_level": "WARNING",
        **changes,
    }
    return Settings(database_url=database_url, **chosen)


def stored(url: str, fleet: tuple[dict, list], buildings: int) -> Database:
    db = Database(url)
    db.migrate()
    description, frames = fleet
    store_fleet(db, description, frames[:buildings])
    return db


def parameter_sets(db: Database) -> dict[str, list[dict]]:
    """Every stored set's values, by building name."""
    with db.session() as session:
        rows = session.execute(
            select(BuildingRecord.name, ParameterSetRecord.document).join(
                ParameterSetRecord, ParameterSetRecord.building_id == BuildingRecord.id
            )
        ).all()
    sets: dict[str, list[dict]] = {}
    for name, document in rows:
        values = {k: v["value"] for k, v in document["parameters"].items()}
        sets.setdefault(name, []).append(values)
    return sets


def calibrations(db: Database) -> list[JobRecord]:
    with db.session() as session:
        query = select(JobRecord).where(JobRecord.kind == CALIBRATION).order_by(JobRecord.id)
        return list(session.scalars(query))


def test_dask_fits_the_same_parameter_sets_as_the_pool(tmp_path, fleet, cluster):
    source = stored(f"sqlite:///{tmp_path / 'pool.db'}", fleet, 4)
    source.dispose()
    shutil.copy(tmp_path / "pool.db", tmp_path / "dask.db")
    results = {}
    for name, backend in (("pool", None), ("dask", _Unclosed(cluster))):
        settings = fleet_settings(f"sqlite:///{tmp_path / name}.db")
        db = Database(settings.database_url)
        summary = retrain_all(settings, db, backend or PoolBackend(settings), progress=False)
        assert (summary.jobs, summary.failed, summary.backend) == (4, 0, name)
        results[name] = parameter_sets(db)
        db.dispose()
    assert len(results["pool"]) == 4
    assert results["dask"] == results["pool"]


@pytest.mark.slow
def test_a_worker_killed_mid_run_still_gives_one_decision_per_building(tmp_path, fleet, cluster):
    settings = fleet_settings(f"sqlite:///{tmp_path / 'fleet.db'}", preset="default")
    db = stored(settings.database_url, fleet, 8)
    killed: list[int] = []
    killer = threading.Thread(target=_kill_a_busy_worker, args=(cluster.client, killed))
    killer.start()
    try:
        summary = retrain_all(settings, db, _Unclosed(cluster), progress=False)
    finally:
        killer.join()
    assert killed, "no worker was busy to be killed"
    assert (summary.jobs, summary.failed) == (8, 0)
    jobs = calibrations(db)
    assert Counter(j.building_id for j in jobs) == Counter(range(1, 9))
    assert {j.status for j in jobs} == {SUCCEEDED}
    assert all(len(sets) == 1 for sets in parameter_sets(db).values())
    assert len(parameter_sets(db)) == 8
    db.dispose()


class _Unclosed:
    """The module's cluster as a backend that the pass must not close."""

    def __init__(self, backend: object):
        self._backend = backend

    def __getattr__(self, name: str) -> object:
        return getattr(self._backend, name)

    def close(self) -> None:
        return None


def _kill_a_busy_worker(client: object, killed: list[int]) -> None:
    """SIGKILL the process of a worker while it runs a task (its nanny starts a new one)."""
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline:
        busy = [address for address, keys in client.processing().items() if keys]
        if busy:
            pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
            time.sleep(0.05)  # into the fit
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
            return
        time.sleep(0.01)


# --- several replicas on one PostgreSQL --------------------------------------------------------
@pytest.fixture
def postgres_url(postgres) -> Iterator[str]:
    name = postgres.create()
    try:
        yield postgres.url(name)
    finally:
        postgres.drop(name)


def test_claiming_skips_the_jobs_another_transaction_is_claiming(postgres_url, fleet):
    db = stored(postgres_url, fleet, 2)
    settings = fleet_settings(postgres_url)
    first, second = queue_retraining(db, settings, "schedule")
    with db.write() as a:  # a replica's claim, not yet committed
        held = repository.claim_next_job(a, CALIBRATION, "replica-a", 30.0)
        with db.write() as b:  # another replica: no wait, the next job
            other = repository.claim_next_job(b, CALIBRATION, "replica-b", 30.0)
            assert other is not None and other.job_id == second
            assert repository.claim_next_job(b, CALIBRATION, "replica-b", 30.0) is None
    assert held is not None and held.job_id == first
    db.dispose()


REPLICA = textwrap.dedent(
    """
    import sys
    from service.cli import app
    sys.argv = ["rcservice", "retrain-all", "--no-progress"]
    app()
    """
)


@pytest.mark.slow
def test_two_service_processes_run_the_nightly_pass_once_per_building(postgres_url, fleet):
    db = stored(postgres_url, fleet, 12)
    env = {
        **os.environ,
        "RCSERVICE_DATABASE_URL": postgres_url,
        "RCSERVICE_ADMIN_TOKEN": ADMIN_TOKEN,
        "RCSERVICE_WORKERS": "0",
        "RCSERVICE_TRAINING_DAYS": "2",
        "RCSERVICE_PRESET": "study",
        "RCSERVICE_LOG_LEVEL": "WARNING",
    }
    replicas = [
        subprocess.Popen(
            [sys.executable, "-c", REPLICA], env=env, cwd=ROOT, stdout=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    outputs = [replica.communicate(timeout=120)[0] for replica in replicas]
    assert [replica.returncode for replica in replicas] == [0, 0], outputs
    jobs = calibrations(db)
    assert Counter(j.building_id for j in jobs) == Counter(range(1, 13))  # one job each
    assert {j.status for j in jobs} == {SUCCEEDED}
    assert sorted(len(sets) for sets in parameter_sets(db).values()) == [1] * 12
    db.dispose()


STUCK_REPLICA = textwrap.dedent(
    """
    import os, sys, threading, time
    from service.core.db import Database
    from service.jobs import LeaseTerms, drain

    def stuck(db, job, options):  # a fit that never ends
        # One write per line: print's separate writes of the id and the newline interleave
        # between the two threads.
        os.write(1, f"{job.id}\\n".encode())
        time.sleep(3600)

    db = Database(sys.argv[1])
    terms = LeaseTerms("replica-a", seconds=2.0)
    for _ in range(2):  # two slots: two claims held
        threading.Thread(target=drain, args=(db, "calibration", stuck, None, terms)).start()
    time.sleep(3600)
    """
)


@pytest.mark.slow
def test_a_killed_replicas_claims_are_released_when_its_lease_expires(postgres_url, fleet):
    settings = fleet_settings(postgres_url, job_lease_s=2.0)
    db = stored(postgres_url, fleet, 3)
    queue_retraining(db, settings, "schedule")
    replica = subprocess.Popen(
        [sys.executable, "-c", STUCK_REPLICA, postgres_url],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    claimed = sorted(int(replica.stdout.readline()) for _ in range(2))
    replica.kill()
    replica.wait()
    held = [j for j in calibrations(db) if j.status == RUNNING]
    assert [j.id for j in held] == claimed and {j.lease_owner for j in held} == {"replica-a"}
    runner = JobRunner(settings, db)  # the surviving replica
    try:
        assert [j.status for j in calibrations(db)].count(RUNNING) == 2  # still leased
        runner.drain(CALIBRATION)  # the job nobody claimed
        deadline = time.monotonic() + 60.0
        while _succeeded_buildings(db) < 3 and time.monotonic() < deadline:
            time.sleep(0.2)  # the reaper: expired leases failed, their buildings run again
    finally:
        runner.shutdown()
    jobs = calibrations(db)
    dead = [j for j in jobs if j.id in claimed]
    assert {(j.status, j.error) for j in dead} == {(FAILED, INTERRUPTED)}
    assert all(j.lease_token == 2 for j in dead)  # its late writes are fenced off
    assert _succeeded_buildings(db) == 3 and QUEUED not in {j.status for j in jobs}
    assert sorted(len(sets) for sets in parameter_sets(db).values()) == [1, 1, 1]
    db.dispose()


def _succeeded_buildings(db: Database) -> int:
    return len({j.building_id for j in calibrations(db) if j.status == SUCCEEDED})


def test_sqlite_says_it_runs_one_process_when_another_shares_the_file(tmp_path, caplog):
    settings = fleet_settings(f"sqlite:///{tmp_path / 'one.db'}")
    db = Database(settings.database_url)
    db.migrate()
    with caplog.at_level("INFO", logger="service.jobs"):
        announce_mode(settings, db, "me")
    assert "single-process mode" in caplog.text and "WARNING" not in caplog.text
    with db.write() as session:
        building = repository.add_building(session, "b", {}, "Europe/Rome", "h" * 64)
        job = repository.add_job(session, building.id, "api", "basic", 1, CALIBRATION)
        repository.start_job(session, job.id, "other-host:42", 60.0)
    caplog.clear()
    with caplog.at_level("INFO", logger="service.jobs"):
        announce_mode(settings, db, "me")
    assert "need PostgreSQL" in caplog.text and "WARNING" in caplog.text
    db.dispose()


def test_a_dask_scheduler_must_be_an_address_or_local():
    assert fleet_settings("sqlite://", dask_scheduler="local").dask_scheduler == "local"
    with pytest.raises(ValueError, match="tcp://host:8786"):
        fleet_settings("sqlite://", dask_scheduler="scheduler-host")


@pytest.mark.slow
def test_a_diagnosis_on_dask_reports_what_the_service_process_reports(tmp_path, fleet, cluster):
    """The service reads the rows and stores the report; the diagnosis itself runs on a Dask
    worker, which touches no database, and gives the report the in-process run gives."""
    settings = fleet_settings(f"sqlite:///{tmp_path / 'fleet.db'}", diagnosis_preset="modestpy")
    db = stored(settings.database_url, fleet, 1)
    runner = JobRunner(settings, db, _Unclosed(cluster))
    try:
        with db.session() as session:
            building_id = session.scalars(select(BuildingRecord.id)).one()
        job = runner.create_diagnosis(building_id, "basic", DiagnosisSpec(), "api")
        deadline = time.monotonic() + 120.0
        while (record := _job(db, job.id)).status in (QUEUED, RUNNING):
            assert time.monotonic() < deadline, "the diagnosis on Dask did not finish"
            time.sleep(0.2)
        assert record.status == SUCCEEDED, record.error
        with db.session() as session:
            on_dask = repository.latest_diagnosis(session, building_id).report
        here = diagnosis.work(db, record, kinds(settings)[DIAGNOSIS][1])
    finally:
        runner.shutdown()
        db.dispose()
    for key in ("verdict", "baseline", "findings", "final"):
        assert _without_times(on_dask[key]) == _without_times(here.record.report[key]), key


def _job(db: Database, job_id: int) -> JobRecord:
    with db.session() as session:
        return session.get(JobRecord, job_id)


def _without_times(value: object) -> object:
    """``value`` without wall-clock durations, which differ between two runs of one diagnosis."""
    if isinstance(value, dict):
        return {k: _without_times(v) for k, v in value.items() if not k.startswith("wall_time")}
    if isinstance(value, list):
        return [_without_times(v) for v in value]
    return value
