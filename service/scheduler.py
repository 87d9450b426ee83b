"""Nightly re-estimation: an APScheduler cron job at ``retrain_hour`` in ``timezone``, run by every
replica of the service (they share the queue; see ``service.jobs``)."""

from __future__ import annotations

import logging

from apscheduler.schedulers.background import BackgroundScheduler
from apscheduler.triggers.cron import CronTrigger

from .core.config import Settings
from .core.db import Database
from .jobs import JobRunner, queue_retraining
from .models import CALIBRATION

log = logging.getLogger(__name__)
JOB_ID = "nightly-retrain"
# A run missed while the server was down is still made if it restarts within this time. [s]
MISFIRE_GRACE_S = 3600


def start_scheduler(settings: Settings, db: Database, runner: JobRunner) -> BackgroundScheduler:
    """A started scheduler that queues a calibration for every building with new data."""
    scheduler = BackgroundScheduler(timezone=settings.timezone)
    scheduler.add_job(
        retrain_due,
        CronTrigger(hour=settings.retrain_hour, minute=0, timezone=settings.timezone),
        args=(settings, db, runner),
        id=JOB_ID,
        coalesce=True,
        max_instances=1,
        misfire_grace_time=MISFIRE_GRACE_S,
    )
    scheduler.start()
    next_run = scheduler.get_job(JOB_ID).next_run_time
    log.info("nightly retraining scheduled", extra={"next_run": next_run.isoformat()})
    return scheduler


def retrain_due(settings: Settings, db: Database, runner: JobRunner) -> list[int]:
    """Queue what is due and claim queued calibrations on every slot of this process.

    Safe in every replica: a building is queued once (re-checked under its row lock) and a job
    is run by the one process that claims it, so replicas share the night's work."""
    job_ids = queue_retraining(db, settings, trigger="schedule")
    runner.drain(CALIBRATION)
    log.info("nightly retraining queued", extra={"job_ids": job_ids})
    return job_ids
