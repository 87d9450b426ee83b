"""Job leases with fencing (issue 13, defect 5): a run whose lease was taken over writes nothing,
an expired lease is reclaimed, and a job's worker process dies with the server."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from datetime import UTC, datetime

import pytest

import service.jobs
from service import repository
from service.core.db import Database
from service.errors import ConflictError, LeaseLostError
from service.jobs import LeaseTerms, execute, fail_abandoned, fail_interrupted
from service.models import CALIBRATION, FAILED, RUNNING, ParameterSetRecord

# Job storage tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True


@pytest.fixture
def job_id(db) -> int:
    with db.write() as session:
        building = repository.add_building(session, "b", {}, "Europe/Rome", "h" * 64)
        return repository.add_job(session, building.id, "api", "basic", 1, CALIBRATION).id


def job(db: Database, job_id: int):
    with db.session() as session:
        return repository.get_job(session, job_id)


def test_starting_a_job_takes_a_lease_with_a_new_fencing_token(db, job_id):
    with db.write() as session:
        lease = repository.start_job(session, job_id, "server-a", 30.0)
    stored = job(db, job_id)
    assert (stored.status, stored.lease_owner, stored.lease_token) == (RUNNING, "server-a", 1)
    assert lease.token == 1 and stored.lease_expires_at > stored.heartbeat_at
    with db.write() as session:
        assert repository.renew_lease(session, lease, 30.0)


def test_a_run_whose_lease_expired_can_neither_renew_nor_finish(db, job_id):
    with db.write() as session:
        lease = repository.start_job(session, job_id, "dead-server", 0.0)
    assert fail_abandoned(db) == [job_id]  # what the restarted server's reaper does
    with db.write() as session:
        assert not repository.renew_lease(session, lease, 30.0)
    with pytest.raises(LeaseLostError, match="no longer holds it"), db.write() as session:
        repository.finish_job(session, job_id, "succeeded", outcome="promoted", lease=lease)
    stored = job(db, job_id)
    assert (stored.status, stored.outcome) == (FAILED, None)
    assert stored.error.startswith("interrupted") and stored.lease_token == 2


def test_an_unexpired_lease_is_not_reclaimed(db, job_id):
    with db.write() as session:
        repository.start_job(session, job_id, "live-server", 60.0)
    assert fail_interrupted(db) == [] and fail_abandoned(db) == []
    assert job(db, job_id).status == RUNNING


@dataclass(frozen=True)
class Promoting:
    """A product that promotes a set: what a fenced-off run must not leave behind."""

    outcome: str = "promoted"

    def save(self, session, job) -> dict:
        session.execute(
            ParameterSetRecord.__table__.insert().values(
                building_id=job.building_id,
                job_id=job.id,
                model="basic",
                engine_version="0",
                status="current",
                is_current=True,
                train_start=job.created_at,
                train_end=job.created_at,
                metrics={},
                document={},
                created_at=job.created_at,
            )
        )
        return {}


def test_an_orphan_run_that_finishes_after_the_restart_stores_nothing(db, job_id, monkeypatch):
    # The orphan's server is dead, and its heartbeat thread with it: nothing renews the lease
    # (a live heartbeat beating every 0.3 ms could keep a 1 ms lease held, making this a race).
    monkeypatch.setattr(service.jobs._Heartbeat, "_beat", lambda self: None)
    abandoned: list[int] = []

    def orphan(db, job, options):
        # The restarted server finds the lease expired and fails the job.
        time.sleep(0.05)
        abandoned.extend(fail_abandoned(db))
        return Promoting()

    with pytest.raises(LeaseLostError):
        execute(db, job_id, orphan, None, LeaseTerms("orphan", seconds=0.001))
    assert abandoned == [job_id]
    stored = job(db, job_id)
    assert (stored.status, stored.outcome) == (FAILED, None)
    with db.session() as session:
        assert repository.list_parameter_sets(session, stored.building_id) == []


def test_a_live_run_renews_its_lease_while_it_works(db, job_id):
    def slow(db, job, options):
        time.sleep(2.5)
        return Promoting(outcome="rejected")

    assert execute(db, job_id, slow, None, LeaseTerms("live", seconds=1.5)) == "succeeded"
    assert fail_abandoned(db) == []


@dataclass(frozen=True)
class Fitted:
    """A product that fitted, and stores a set of, a model with a long name."""

    model: str
    outcome: str = "rejected"

    def save(self, session, job) -> dict:
        when = datetime(2017, 1, 30, tzinfo=UTC)
        record = ParameterSetRecord(
            building_id=job.building_id,
            job_id=job.id,
            model=self.model,
            engine_version="test",
            train_start=when,
            train_end=when,
            rmse_train=0.1,
            rmse_holdout=None,
            metrics={},
            document={},
        )
        repository.add_parameter_set(session, record, promote=False)
        return {"model": self.model}


def test_a_job_records_and_stores_a_model_name_of_any_length(db, job_id):
    """An extended model's name grows with each effect it adopts; PostgreSQL refused one past
    the 100 characters the tables once held, after the set was fitted (migration 0006)."""
    long_name = "basic+" + "+".join(["wind_infiltration", "ventilation_schedule"] * 6)
    assert len(long_name) > 200
    run = execute(db, job_id, lambda *_: Fitted(long_name), None, LeaseTerms("live", 60.0))
    assert run == "succeeded"
    assert job(db, job_id).model == long_name
    with db.session() as session:
        stored = repository.list_parameter_sets(session, job(db, job_id).building_id)
    assert [s.model for s in stored] == [long_name]


WORKER_SCRIPT = textwrap.dedent(
    """
    import os, subprocess, sys, time
    from service.pool import make_executor

    def job():  # a job that starts a process of its own, as the engine's pools do
        return os.getpid(), subprocess.Popen(["sleep", "60"]).pid

    if __name__ == "__main__":
        pool = make_executor(1, "WARNING")
        print(*pool.submit(job).result(), flush=True)
        time.sleep(60)
    """
)


def test_a_worker_process_and_its_children_die_with_the_server(tmp_path):
    script = tmp_path / "server.py"
    script.write_text(WORKER_SCRIPT)
    server = subprocess.Popen(
        [sys.executable, str(script)], stdout=subprocess.PIPE, text=True, cwd=os.getcwd()
    )
    processes = [int(pid) for pid in server.stdout.readline().split()]
    assert all(_alive(pid) for pid in processes)
    os.kill(server.pid, signal.SIGKILL)
    server.wait()
    deadline = time.monotonic() + 5.0
    while any(_alive(pid) for pid in processes) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(pid) for pid in processes), "the job's processes outlived the server"


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().split(") ")[1][0] != "Z"  # a zombie is dead
    except FileNotFoundError:
        return False


def test_a_job_queued_by_another_process_at_the_same_moment_is_named(db, monkeypatch):
    """Two processes queue a calibration at once: both see none active, the database's unique
    index refuses the second, and its 409 names the first (it said only "an active calibration",
    no job to poll)."""
    with db.write() as session:
        building = repository.add_building(session, "b", {}, "Europe/Rome", "h" * 64)
        first = repository.add_job(session, building.id, "api", "basic", 1, CALIBRATION)
    looked = []
    real = repository.active_job

    def first_look_misses(session, building_id, kind=CALIBRATION):
        looked.append(kind)
        return None if len(looked) == 1 else real(session, building_id, kind)

    monkeypatch.setattr(repository, "active_job", first_look_misses)
    named = f"job {first.id} queued; poll GET /jobs/{first.id}"
    with pytest.raises(ConflictError, match=named), db.write() as session:
        repository.add_job(session, building.id, "api", "basic", 1, CALIBRATION)
    assert len(looked) == 2
