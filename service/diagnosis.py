"""A diagnosis job: the engine's mismatch diagnosis (``rcengine.diagnose``) on a window of the
stored measurements, its report (CONTRACT.md §3 JSON and the HTML page) stored for the building.

The window is fixed when the job is queued (:func:`plan`)::

    |<------ train_fraction: fitted ------>|<------ the rest: tested ------>|
    start                                                end = last measured t_in + one step

By default it covers ``diagnosis_days`` before ``end``, clipped to the stored rows; the engine
splits it at a local midnight. A job that raises is stored failed with its error and adds no
report, so the previous report stays the building's latest.

:func:`work` is what a diagnosis job runs (the job itself is handled by ``service.jobs``).
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from typing import Any

import pandas as pd
from sqlalchemy.orm import Session

from rcengine import __version__
from rcengine.building import Building
from rcengine.columns import T_IN
from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.exceptions import DataValidationError, Problem

from . import bridge, repository
from .core.db import Database
from .errors import DiagnosisError
from .models import DiagnosisRecord, JobRecord

# Measured data a diagnosis needs at least: whole days to fit and whole days to test. [d]
MIN_DIAGNOSIS_DAYS = 2
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class DiagnosisOptions:
    """Service-wide engine settings passed to the worker (picklable); preset None: the
    engine's."""

    preset: str | None = None
    random_state: int = 0


@dataclass(frozen=True)
class DiagnosisSpec:
    """What a client asked for: ``days`` before ``end`` or the window from ``start``; None
    leaves the choice to the service (window) or the engine (train_fraction, effects)."""

    days: int | None = None
    start: pd.Timestamp | None = None
    end: pd.Timestamp | None = None
    train_fraction: float | None = None
    effects: tuple[str, ...] | None = None


@dataclass(frozen=True)
class DiagnosisPlan:
    """The window (UTC) a job diagnoses and the engine choices it was asked for; stored as the
    job's ``options``."""

    start: pd.Timestamp
    end: pd.Timestamp
    train_fraction: float | None
    effects: tuple[str, ...] | None

    @property
    def days(self) -> int:
        return math.ceil((self.end - self.start) / pd.Timedelta(days=1))

    def to_dict(self) -> dict[str, Any]:
        return {
            "start": self.start.isoformat(),
            "end": self.end.isoformat(),
            "train_fraction": self.train_fraction,
            "effects": None if self.effects is None else list(self.effects),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> DiagnosisPlan:
        effects = data.get("effects")
        return cls(
            pd.Timestamp(data["start"]),
            pd.Timestamp(data["end"]),
            data.get("train_fraction"),
            None if effects is None else tuple(effects),
        )


def plan(
    spec: DiagnosisSpec,
    first_stored: datetime,
    last_measured: datetime,
    step_s: float,
    default_days: int,
) -> DiagnosisPlan:
    """The window of ``spec`` clipped to the stored rows up to the last measured ``t_in``.

    Raises
    ------
    DataValidationError : naming ``start`` or ``end`` when the window holds no measured row.
    """
    measured_end = pd.Timestamp(last_measured) + pd.Timedelta(seconds=step_s)
    asked_end = measured_end if spec.end is None else spec.end
    days = pd.Timedelta(days=spec.days or default_days)
    asked_start = asked_end - days if spec.start is None else spec.start
    end = min(asked_end, measured_end)
    start = max(asked_start, pd.Timestamp(first_stored))
    if end <= start:
        # The window asked for, as asked: the clipped one can come out inverted.
        raise DataValidationError(
            [
                Problem(
                    None,
                    "start" if spec.start is not None else "end",
                    f"the window {asked_start.isoformat()} to {asked_end.isoformat()} holds no "
                    f"measured data: rows are stored from "
                    f"{pd.Timestamp(first_stored).isoformat()}, t_in until "
                    f"{pd.Timestamp(last_measured).isoformat()}",
                )
            ]
        )
    return DiagnosisPlan(start, end, spec.train_fraction, spec.effects)


@dataclass(frozen=True)
class Diagnosed:
    """A finished diagnosis: its report as an unsaved row (diagnoses have no outcome)."""

    record: DiagnosisRecord
    outcome: None = None

    def save(self, session: Session, job: JobRecord) -> dict[str, Any]:
        """Store the report, the building's latest from now on; the job's details."""
        self.record.job_id = job.id
        repository.add_diagnosis(session, self.record)
        report = self.record.report
        return {
            "diagnosis_id": self.record.id,
            "window": {
                "start": pd.Timestamp(self.record.window_start).isoformat(),
                "end": pd.Timestamp(self.record.window_end).isoformat(),
            },
            "accepted": [f["effect"] for f in report["findings"] if f["accepted"]],
            "rmse_test": {
                "baseline": report["baseline"]["rmse_test"],
                "final": report["final"]["rmse_test"],
            },
            "final_model": report["final"]["model"],
        }


@dataclass(frozen=True)
class Inputs:
    """The building and the stored rows of the planned window, read by :func:`load`;
    :func:`compute` needs nothing else, so it runs anywhere, a Dask worker included."""

    building_id: int
    job_id: int
    model: str
    plan: DiagnosisPlan
    building: Building
    step_s: float | None  # None: every row deleted since the job was queued
    frame: pd.DataFrame


def work(db: Database, job: JobRecord, options: DiagnosisOptions) -> Diagnosed:
    """Diagnose the window planned for the job on the stored rows."""
    return compute(load(db, job, options), options)


def load(db: Database, job: JobRecord, options: DiagnosisOptions) -> Inputs:
    """The job's building and the stored rows of its planned window."""
    job_plan = DiagnosisPlan.from_dict(job.options)
    with db.session() as session:
        row = repository.get_building(session, job.building_id)
        building, step_s = bridge.building_of(row.description), row.step_s
        frame = bridge.load_frame(session, job.building_id, job_plan.start, job_plan.end)
    return Inputs(job.building_id, job.id, job.model, job_plan, building, step_s, frame)


def compute(inputs: Inputs, options: DiagnosisOptions) -> Diagnosed:
    """The engine's diagnosis on :func:`load`'s inputs (no database)."""
    job_plan, frame, step_s = inputs.plan, inputs.frame, inputs.step_s
    _check_enough(frame, job_plan, step_s)
    settings = engine_settings(job_plan, options)
    frame, left_out = bridge.whole_columns(frame)
    context = {"job_id": inputs.job_id, "building_id": inputs.building_id}
    report, page = diagnose_frame(
        frame,
        inputs.building,
        inputs.model,
        settings,
        lambda step: log.info("diagnosis progress", extra={**context, "step": step}),
    )
    record = DiagnosisRecord(
        building_id=inputs.building_id,
        model=inputs.model,
        window_start=bridge.to_datetime(frame.index[0]),
        window_end=bridge.to_datetime(frame.index[-1] + pd.Timedelta(seconds=step_s)),
        settings={
            "preset": settings.preset,
            "random_state": settings.random_state,
            "train_fraction": settings.train_fraction,
            "effects": list(settings.effects),
            "columns_left_out": left_out,
        },
        report=report,
        html=page,
        engine_version=__version__,
    )
    return Diagnosed(record)


def engine_settings(job_plan: DiagnosisPlan, options: DiagnosisOptions) -> DiagnoseSettings:
    """The service's seed and preset, and the job's choices where it made any (the engine's
    defaults elsewhere)."""
    chosen = {
        "preset": options.preset,
        "train_fraction": job_plan.train_fraction,
        "effects": job_plan.effects,
    }
    return DiagnoseSettings(
        random_state=options.random_state,
        **{name: value for name, value in chosen.items() if value is not None},
    )


def diagnose_frame(
    frame: pd.DataFrame,
    building: Building,
    model: str,
    settings: DiagnoseSettings,
    progress: Callable[[str], None],
) -> tuple[dict[str, Any], str]:
    """The engine's diagnosis: the CONTRACT.md §3 report (JSON values) and its HTML page."""
    # Imported here: matplotlib is needed only in the process that renders a report.
    from rcengine.diagnose.html import render

    report = diagnose(frame, building, model, settings, progress)
    return json.loads(report.to_json()), render(report)


def _check_enough(frame: pd.DataFrame, job_plan: DiagnosisPlan, step_s: float | None) -> None:
    """Enough measured rows in the window; ``step_s`` None: the rows were deleted after the
    job was queued (the building forgot its grid)."""
    measured = int(frame[T_IN].notna().sum()) if T_IN in frame else 0
    if step_s is None or measured * step_s < MIN_DIAGNOSIS_DAYS * 86400.0:
        raise DiagnosisError(
            f"not enough measured data: a diagnosis needs at least {MIN_DIAGNOSIS_DAYS} days of "
            f"measured t_in (whole days to fit, whole days to test); found {measured} row(s) "
            f"in {job_plan.start.isoformat()}–{job_plan.end.isoformat()}"
        )
