"""kill -9 of a real server during a calibration (issue 13, defect 5): at random points of the
job, the server is killed and restarted. The job ends failed or succeeded exactly once (it never
flips afterwards), the current set changes at most once and only by the run that held the
lease, and no process of the dead server remains."""

from __future__ import annotations

import os
import random
import signal
import time
from datetime import UTC, datetime
from pathlib import Path

import pytest

from .conftest import LiveServer, register

LEASE_S = 2.0
KILL_POINTS = 5
FINISHED = ("succeeded", "failed")


def descendants(pid: int) -> set[int]:
    """Every live process below ``pid``."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if fields[0] != "Z":
                children.setdefault(int(fields[1]), []).append(int(entry.name))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def alive(pids: set[int]) -> set[int]:
    return {pid for pid in pids if Path(f"/proc/{pid}").exists() and not _zombie(pid)}


def survivors(pids: set[int], seconds: float = 5.0) -> set[int]:
    """The processes of ``pids`` still alive after up to ``seconds``: a worker that dies with its
    parent (and the pool's resource tracker, which exits when its pipe closes) goes a moment
    after the parent, not at the same instant."""
    deadline = time.monotonic() + seconds
    while alive(pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return alive(pids)


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def state(client, building_id: int, job_id: int, headers: dict) -> tuple[dict, dict]:
    job = client.get(f"/jobs/{job_id}", headers=headers).json()
    sets = client.get(f"/buildings/{building_id}/parameters", headers=headers).json()
    return job, sets


def wait_finished(server: LiveServer, building_id, job_id, headers, timeout_s=60.0):
    deadline = time.monotonic() + timeout_s
    with server.client() as client:
        while time.monotonic() < deadline:
            job, sets = state(client, building_id, job_id, headers)
            if job["status"] in FINISHED:
                return job, sets
            time.sleep(0.1)
    raise AssertionError(f"job {job_id} did not finish after the restart: {job}")


def eight_days(raw) -> str:
    """Eight days of the EnergyPlus office as CSV: seven fitted, one held out."""
    days = raw[(raw.index >= "2017-01-21T23:00:00Z") & (raw.index < "2017-01-29T23:00:00Z")]
    return days.to_csv(index=False)


def start_calibration(server: LiveServer, description: dict, body: str) -> tuple[int, dict, int]:
    """A new building with ``body`` stored and a calibration just started running."""
    with server.client() as client:
        building_id, headers = register(client, description)
        url = f"/buildings/{building_id}"
        csv = {**headers, "Content-Type": "text/csv"}
        assert client.post(f"{url}/measurements", content=body, headers=csv).is_success
        job_id = client.post(f"{url}/calibrations", headers=headers).json()["id"]
        while client.get(f"/jobs/{job_id}", headers=headers).json()["status"] == "queued":
            time.sleep(0.01)
    return building_id, headers, job_id


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc").exists(), reason="reads the process table in /proc")
def test_a_graceful_stop_lets_the_running_calibration_finish(tmp_path, office):
    description, raw = office
    server = LiveServer(tmp_path, RCSERVICE_WORKERS="1").start()
    try:
        building_id, headers, job_id = start_calibration(server, description, eight_days(raw))
        family = descendants(server.process.pid)
        server.stop()  # SIGINT, as Ctrl-C or a service manager's stop
        assert not (left := survivors(family)), f"processes of the stopped server remain: {left}"
        server.start()
        job, _ = wait_finished(server, building_id, job_id, headers)
        assert (job["status"], job["outcome"]) == ("succeeded", "promoted"), job
    finally:
        server.stop()


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc").exists(), reason="reads the process table in /proc")
def test_kill_9_at_random_points_of_a_calibration(tmp_path, office):
    description, raw = office
    body = eight_days(raw)
    settings = {"RCSERVICE_JOB_LEASE_S": str(LEASE_S), "RCSERVICE_PRESET": "thesis"}
    server = LiveServer(tmp_path, RCSERVICE_WORKERS="1", **settings)
    server.start()
    # Seconds after the job started running (a calibration here lasts about 0.3–0.5 s).
    points = random.Random(13).sample([0.02 * k for k in range(20)], KILL_POINTS)
    outcomes, seen = [], []
    try:
        for delay in sorted(points):
            building_id, headers, job_id = start_calibration(server, description, body)
            time.sleep(delay)
            with server.client() as client:
                seen.append(client.get(f"/jobs/{job_id}", headers=headers).json()["status"])
            family = descendants(server.process.pid)
            killed_at = datetime.now(UTC)
            os.kill(server.process.pid, signal.SIGKILL)
            server.process.wait()
            assert not (left := survivors(family)), f"processes of the dead server remain: {left}"
            server.stop()
            server.start()
            job, sets = wait_finished(server, building_id, job_id, headers)
            time.sleep(2 * LEASE_S)  # a late writer would have flipped it by now
            with server.client() as client:
                assert state(client, building_id, job_id, headers) == (job, sets)
            outcomes.append(job["status"])
            current = [s for s in sets["items"] if s["is_current"]]
            assert len(current) <= 1
            if job["status"] == "succeeded":  # only by the run that held the lease, before
                assert datetime.fromisoformat(job["finished_at"]) < killed_at
            if current:  # promoted by this job's run, in the transaction that ended it
                assert (job["status"], job["outcome"]) == ("succeeded", "promoted")
                assert current[0]["id"] == job["parameter_set_id"] == sets["current_id"]
            else:
                assert job["status"] == "failed" or job["outcome"] == "rejected"
    finally:
        server.stop()
    print(f"kill -9 {sorted(points)} s after the job started; job then {seen}, ended {outcomes}")
