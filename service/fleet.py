"""``rcservice retrain-all``: one nightly pass over the fleet, with a progress bar and a summary.

The pass is the scheduler's (``jobs.queue_retraining``, then ``JobRunner.drain`` on every slot of
the backend), so it can run beside live replicas: they claim from the same queue, and the summary
covers every job of the night queued when the pass started, whichever process ran it.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import asdict, dataclass
from typing import Any

from sqlalchemy import func, select
from tqdm import tqdm

from .backends import Backend
from .core.config import Settings
from .core.db import Database
from .jobs import JobRunner, queue_retraining
from .models import ACTIVE_JOB_STATUSES, CALIBRATION, FAILED, PROMOTED, QUEUED, JobRecord

# How often the progress bar asks the database how many jobs ended. [s]
POLL_S = 0.5


@dataclass(frozen=True)
class FleetSummary:
    """What a pass did: jobs by decision, its wall time and the cores it ran on."""

    jobs: int
    promoted: int
    kept: int
    refused: int
    failed: int
    wall_s: float
    cores: int
    backend: str

    @property
    def buildings_per_core_hour(self) -> float:
        core_hours = self.wall_s * self.cores / 3600.0
        return self.jobs / core_hours if core_hours > 0 else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "buildings_per_core_hour": round(self.buildings_per_core_hour)}

    def lines(self) -> list[str]:
        return [
            f"{self.jobs} job(s) run on {self.backend} ({self.cores} core(s)) "
            f"in {self.wall_s:.1f} s: {self.buildings_per_core_hour:,.0f} buildings per core-hour",
            f"  promoted {self.promoted}  kept {self.kept} (current set no worse)  "
            f"refused {self.refused} (promotion gate)  failed {self.failed}",
        ]


def retrain_all(
    settings: Settings,
    db: Database,
    backend: Backend,
    trigger: str = "cli",
    progress: bool = True,
) -> FleetSummary:
    """Queue every due building, run the queue on ``backend`` until it is empty, wait for the
    night's jobs other processes run, and sum them up."""
    runner = JobRunner(settings, db, backend)
    try:
        queue_retraining(db, settings, trigger)
        job_ids = _queued_calibrations(db)
        started = time.perf_counter()
        slots = runner.drain(CALIBRATION)
        with tqdm(total=len(job_ids), unit="building", disable=not progress) as bar:
            while (ended := _ended(db, job_ids)) < len(job_ids) or not all(f.done() for f in slots):
                bar.update(ended - bar.n)
                time.sleep(POLL_S)
            bar.update(ended - bar.n)
        wall_s = time.perf_counter() - started
        return summarize(db, job_ids, wall_s, backend)
    finally:
        runner.shutdown()


def summarize(db: Database, job_ids: list[int], wall_s: float, backend: Backend) -> FleetSummary:
    """Jobs by decision: promoted; kept (no better than the current set); refused (by the
    promotion gate); failed."""
    counts: Counter[str] = Counter()
    with db.session() as session:
        for chunk in _chunks(job_ids):
            for job in session.scalars(select(JobRecord).where(JobRecord.id.in_(chunk))):
                counts[_decision(job)] += 1
    return FleetSummary(
        len(job_ids),
        counts["promoted"],
        counts["kept"],
        counts["refused"],
        counts["failed"],
        round(wall_s, 3),
        backend.cores(),
        backend.name,
    )


def _decision(job: JobRecord) -> str:
    if job.status == FAILED:
        return "failed"
    if job.outcome == PROMOTED:
        return "promoted"
    gate = (job.details or {}).get("gate") or {}
    return "kept" if gate.get("passed", True) else "refused"


def _queued_calibrations(db: Database) -> list[int]:
    with db.session() as session:
        query = select(JobRecord.id).where(
            JobRecord.kind == CALIBRATION, JobRecord.status == QUEUED
        )
        return list(session.scalars(query.order_by(JobRecord.id)))


def _ended(db: Database, job_ids: list[int]) -> int:
    active = 0
    with db.session() as session:
        for chunk in _chunks(job_ids):
            active += session.scalar(
                select(func.count()).where(
                    JobRecord.id.in_(chunk), JobRecord.status.in_(ACTIVE_JOB_STATUSES)
                )
            )
    return len(job_ids) - active


def _chunks(ids: list[int], size: int = 1000) -> list[list[int]]:
    return [ids[i : i + size] for i in range(0, len(ids), size)]
