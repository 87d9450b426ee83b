"""A calibration job: fit on the last N days, score on the held-out day, promote if no worse.

Timeline, ending at the last measured ``t_in`` (``end`` = its time + one step)::

    |<-------- days × 24 h: training -------->|<---- 24 h: held out ---->|
    train_start                          holdout_start                  end

The new set is fitted on the training rows. Both the new and the current set then forecast the
held-out day the way the service forecasts (Kalman-filtered state from the rows before it, open
loop over the day's inputs); the new set becomes current only if its RMSE there is no worse.
A failed fit or a worse set never replaces the current one; both are stored with their reason.

``run_job`` is the entry point of the worker process; ``execute`` runs a job in the caller's
process (the CLI, and the server when ``RCSERVICE_WORKERS=0``).
"""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass, replace
from datetime import datetime
from typing import Any

import pandas as pd

from rcengine.building import Building
from rcengine.columns import T_IN
from rcengine.estimation.estimator import Estimator
from rcengine.exceptions import ConvergenceWarning, RCEngineError
from rcengine.forecast import forecast
from rcengine.metrics import FitMetrics, evaluate
from rcengine.models import get_model
from rcengine.parameter_set import ParameterSet
from rcengine.signals import prepare

from . import bridge, repository
from .core.db import Database
from .errors import CalibrationError
from .models import FAILED, PROMOTED, REJECTED, SUCCEEDED

HOLDOUT_H = 24.0
# Measured training data needed at least, besides the held-out day. [h]
MIN_TRAINING_H = 24.0
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CalibrationOptions:
    """Estimator settings passed to the worker (picklable)."""

    preset: str = "default"
    random_state: int = 0
    holdout_h: float = HOLDOUT_H


@dataclass(frozen=True)
class Window:
    """Training and held-out periods (UTC) and the step of the series. [s]"""

    train_start: pd.Timestamp
    holdout_start: pd.Timestamp
    end: pd.Timestamp
    step_s: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "train_start": self.train_start.isoformat(),
            "holdout_start": self.holdout_start.isoformat(),
            "end": self.end.isoformat(),
            "step_s": self.step_s,
        }


@dataclass(frozen=True)
class Outcome:
    """A fitted set, its and the current set's held-out metrics, and the decision."""

    parameter_set: ParameterSet
    window: Window
    holdout_new: FitMetrics
    holdout_current: FitMetrics | None
    current_id: int | None
    promote: bool
    reason: str
    warnings: list[str]


def run_job(database_url: str, job_id: int, options: CalibrationOptions) -> None:
    """Worker entry: its own database engine, then :func:`execute`."""
    db = Database(database_url)
    try:
        execute(db, job_id, options)
    finally:
        db.dispose()


def execute(db: Database, job_id: int, options: CalibrationOptions) -> str:
    """Run a queued job to its end; returns its final status. Never raises for a failed fit."""
    started = time.perf_counter()
    with db.write() as session:
        job = repository.start_job(session, job_id)
        building_id, model, days = job.building_id, job.model, job.days
    log.info("calibration started", extra={"job_id": job_id, "building_id": building_id})
    try:
        outcome = calibrate(db, building_id, model, days, options)
    except Exception as exc:  # every failure is stored with its reason; the current set stays
        error = describe(exc)
        with db.write() as session:
            repository.finish_job(session, job_id, FAILED, error=error)
        log.warning(
            "calibration failed",
            extra={"job_id": job_id, "building_id": building_id, "error": error},
            exc_info=not isinstance(exc, RCEngineError | CalibrationError),
        )
        return FAILED
    with db.write() as session:
        record = repository.add_parameter_set(
            session,
            bridge.parameter_set_record(
                outcome.parameter_set,
                building_id,
                job_id,
                None if outcome.promote else outcome.reason,
            ),
            outcome.promote,
        )
        details = _details(outcome, record.id, time.perf_counter() - started)
        repository.finish_job(
            session,
            job_id,
            SUCCEEDED,
            outcome=PROMOTED if outcome.promote else REJECTED,
            details=details,
        )
    log.info(
        "calibration finished",
        extra={
            "job_id": job_id,
            "building_id": building_id,
            "outcome": PROMOTED if outcome.promote else REJECTED,
            "parameter_set_id": record.id,
            "rmse_holdout": outcome.holdout_new.rmse,
            "duration_s": round(time.perf_counter() - started, 3),
        },
    )
    return SUCCEEDED


def calibrate(
    db: Database, building_id: int, model: str, days: int, options: CalibrationOptions
) -> Outcome:
    """Fit, score against the current set on the held-out day, decide."""
    with db.session() as session:
        building_row = repository.get_building(session, building_id)
        building = bridge.building_of(building_row.description)
        window = _window(
            building_row.last_measured_at,
            building_row.step_s,
            days,
            options.holdout_h,
        )
        frame = bridge.load_frame(session, building_id, window.train_start, window.end)
        current = repository.current_parameter_set(session, building_id)
        current_set = None if current is None else bridge.parameter_set_of(current)
    training = frame.loc[frame.index < window.holdout_start]
    _check_enough(training, window)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        fitted = fit_parameter_set(training, building, model, options)
    new_score = holdout_score(fitted, frame, window)
    fitted = replace(fitted, metrics={**fitted.metrics, "holdout": new_score.to_dict()})
    current_score, note = _score_current(current_set, frame, window)
    promote = current_score is None or new_score.rmse <= current_score.rmse
    reason = note or _verdict(new_score, current_score)
    return Outcome(
        fitted,
        window,
        new_score,
        current_score,
        None if current is None else current.id,
        promote,
        reason,
        [str(w.message) for w in caught],
    )


def fit_parameter_set(
    training: pd.DataFrame, building: Building, model: str, options: CalibrationOptions
) -> ParameterSet:
    """The engine's GA + GPS fit of ``model`` on the training rows."""
    network = get_model(model, building, training.columns)
    data = prepare(training, building, network.compile().input_names)
    estimator = Estimator(network, preset=options.preset, random_state=options.random_state)
    estimator.fit(data)
    return ParameterSet.from_estimator(estimator, data, building, model)


def holdout_score(pset: ParameterSet, frame: pd.DataFrame, window: Window) -> FitMetrics:
    """Metrics of a day-ahead forecast of the held-out day against its measured ``t_in``."""
    hours = (window.end - window.holdout_start).total_seconds() / 3600.0
    data = pset.prepare(frame)
    predicted = forecast(pset.compiled, pset.values, data, window.holdout_start, hours)
    measured = frame[T_IN].reindex(predicted.times).to_numpy(dtype=float)
    return evaluate(measured, predicted.t_in_pred)


def describe(exc: BaseException) -> str:
    """A failure as one line for the job record."""
    return f"{type(exc).__name__}: {exc}"


def _window(
    last_measured: datetime | None, step_s: float | None, days: int, holdout_h: float
) -> Window:
    if last_measured is None or step_s is None:
        raise CalibrationError("no measured t_in stored yet; upload measurements first")
    end = pd.Timestamp(last_measured) + pd.Timedelta(seconds=step_s)
    holdout_start = end - pd.Timedelta(hours=holdout_h)
    return Window(holdout_start - pd.Timedelta(days=days), holdout_start, end, step_s)


def _check_enough(training: pd.DataFrame, window: Window) -> None:
    measured = int(training[T_IN].notna().sum())
    if measured * window.step_s < MIN_TRAINING_H * 3600.0:
        raise CalibrationError(
            f"not enough measured data: the fit needs at least {MIN_TRAINING_H:g} h of measured "
            f"t_in before the held-out day {window.holdout_start.isoformat()}–"
            f"{window.end.isoformat()}; found {measured} row(s) since "
            f"{window.train_start.isoformat()}"
        )


def _score_current(
    current: ParameterSet | None, frame: pd.DataFrame, window: Window
) -> tuple[FitMetrics | None, str | None]:
    if current is None:
        return None, "no current parameter set"
    try:
        return holdout_score(current, frame, window), None
    except RCEngineError as exc:
        return None, f"the current set cannot forecast the held-out day ({exc})"


def _verdict(new: FitMetrics, current: FitMetrics | None) -> str:
    if current is None:
        return "no current parameter set"
    relation = "no worse than" if new.rmse <= current.rmse else "worse than"
    return (
        f"held-out day RMSE {new.rmse:.3f} K is {relation} the current set's {current.rmse:.3f} K"
    )


def _details(outcome: Outcome, set_id: int, duration_s: float) -> dict[str, Any]:
    fit = outcome.parameter_set.fit
    return {
        "parameter_set_id": set_id,
        "reason": outcome.reason,
        "window": outcome.window.to_dict(),
        "training_rows": fit["rows"],
        "holdout": {
            "new": outcome.holdout_new.to_dict(),
            "current": None
            if outcome.holdout_current is None
            else outcome.holdout_current.to_dict(),
            "current_parameter_set_id": outcome.current_id,
        },
        "n_simulations": fit["n_simulations"],
        "fit_wall_time_s": fit["wall_time_s"],
        "duration_s": round(duration_s, 3),
        "warnings": outcome.warnings,
    }
