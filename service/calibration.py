"""A calibration job: fit on the last N days, score on the held-out day, promote if no worse.

Timeline, ending at the last measured ``t_in`` (``end`` = its time + one step)::

    |<-------- days × 24 h: training -------->|<---- 24 h: held out ---->|
    train_start                          holdout_start                  end

The new set is fitted on the training rows. Both the new and the current set then forecast the
held-out day the way the service forecasts (Kalman-filtered state from the rows before it, open
loop over the day's inputs); the new set becomes current only if its RMSE there is no worse
and it passes the promotion gate (``service.promotion``: no flat t_in, heating that varies,
parameters mostly inside their bounds, better than persistence, plausible predictions). A
failed fit, a worse or a refused set never replaces the current one; each is stored with its
reason (the job's ``details.gate`` names the checks that refused it).

:func:`work` is what a calibration job runs (the job itself is handled by ``service.jobs``):
:func:`load` reads what it needs, :func:`compute` fits and decides without the database (so that a
remote backend runs it where the data was sent).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from datetime import datetime
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy.orm import Session

from rcengine.building import Building
from rcengine.columns import T_IN
from rcengine.dataset import bridge_short_gaps
from rcengine.estimation.estimator import POLISH_TOL, Estimator
from rcengine.exceptions import ConvergenceWarning, RCEngineError
from rcengine.forecast import forecast
from rcengine.metrics import FitMetrics, evaluate
from rcengine.models import MODELS, get_model
from rcengine.models.spec import ModelSpec, check_columns
from rcengine.parameter_set import ParameterSet
from rcengine.signals import SignalOptions, prepare

from . import bridge, promotion, repository
from .core.db import Database
from .errors import CalibrationError
from .models import PROMOTED, REJECTED, JobRecord

HOLDOUT_H = 24.0
# Measured training data needed at least, besides the held-out day. [h]
MIN_TRAINING_H = 24.0


@dataclass(frozen=True)
class CalibrationOptions:
    """Estimator settings passed to the worker (picklable)."""

    preset: str = "default"
    random_state: int = 0
    holdout_h: float = HOLDOUT_H
    criterion: str = "output_error"


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


@dataclass
class Calibrated:
    """A fitted set, its and the current set's held-out metrics, and the decision (final once
    :meth:`save` has checked the building's model in the same transaction)."""

    parameter_set: ParameterSet
    window: Window
    holdout_new: FitMetrics
    holdout_current: FitMetrics | None
    current_id: int | None
    promote: bool
    reason: str
    warnings: list[str]
    gate: promotion.Verdict

    @property
    def outcome(self) -> str:
        return PROMOTED if self.promote else REJECTED

    def save(self, session: Session, job: JobRecord) -> dict[str, Any]:
        """Store the set (current if promoted, else rejected with its reason); the job's
        details. A set of a model the building no longer uses — adopted or reverted while the
        job ran — is stored rejected: promoted, a reverted model was served on, and every later
        base-model fit lost the held-out day to it."""
        building = repository.lock_building(session, job.building_id)
        in_use = _adopted(building.model_spec)
        fitted = self.parameter_set.model
        changed = (in_use is not None and fitted != in_use.name) or (
            in_use is None and fitted not in MODELS
        )
        if changed:
            now = in_use.name if in_use is not None else "the base model"
            self.promote = False
            self.reason = f"the building's model changed to {now} while this calibration ran"
        record = repository.add_parameter_set(
            session,
            bridge.parameter_set_record(
                self.parameter_set, job.building_id, job.id, None if self.promote else self.reason
            ),
            self.promote,
        )
        fit = self.parameter_set.fit
        return {
            "parameter_set_id": record.id,
            "model": self.parameter_set.model,
            "model_changed": changed,
            "reason": self.reason,
            "window": self.window.to_dict(),
            "training_rows": fit["rows"],
            "holdout": {
                "new": self.holdout_new.to_dict(),
                "current": None if self.holdout_current is None else self.holdout_current.to_dict(),
                "current_parameter_set_id": self.current_id,
            },
            "n_simulations": fit["n_simulations"],
            "fit_wall_time_s": fit["wall_time_s"],
            "warnings": self.warnings,
            "gate": self.gate.to_dict(),
        }


@dataclass(frozen=True)
class Inputs:
    """What :func:`compute` fits and scores, read by :func:`load`: the building, the rows of its
    window and its current set; nothing past here needs a connection (a Dask worker runs it)."""

    building: Building
    model: str
    window: Window
    frame: pd.DataFrame
    current_set: ParameterSet | None
    current_id: int | None
    # The building's adopted model (service.adoption), fitted instead of ``model``.
    spec: ModelSpec | None = None


def work(db: Database, job: JobRecord, options: CalibrationOptions) -> Calibrated:
    """Fit on the job's days, score against the current set on the held-out day, decide."""
    return compute(load(db, job, options), options)


def load(db: Database, job: JobRecord, options: CalibrationOptions) -> Inputs:
    """The job's building, window, stored rows and current set, in one read session."""
    with db.session() as session:
        building_row = repository.get_building(session, job.building_id)
        window = _window(
            building_row.last_measured_at,
            building_row.step_s,
            job.days,
            options.holdout_h,
        )
        frame = bridge.load_frame(session, job.building_id, window.train_start, window.end)
        current = repository.current_parameter_set(session, job.building_id)
        adopted = _adopted(building_row.model_spec)
        if adopted is None and job.model not in MODELS:
            raise CalibrationError(
                f"the adopted model {job.model} was reverted while this calibration waited; "
                "nothing was fitted (the next calibration fits the building's base model)"
            )
        return Inputs(
            bridge.building_of(building_row.description),
            job.model,
            window,
            frame,
            None if current is None else bridge.parameter_set_of(current),
            None if current is None else current.id,
            adopted,
        )


def compute(inputs: Inputs, options: CalibrationOptions) -> Calibrated:
    """The fit, both held-out scores and the gate on :func:`load`'s inputs (no database)."""
    frame, window = inputs.frame, inputs.window
    training, left_out = bridge.whole_columns(frame.loc[frame.index < window.holdout_start])
    _check_enough(training, window)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        fitted = fit_parameter_set(
            training, inputs.building, inputs.model, options, inputs.spec, _warm(inputs)
        )
    holdout, predicted = holdout_forecast(fitted, frame, window)
    new_score = evaluate(holdout[T_IN].to_numpy(dtype=float), predicted)
    fitted = replace(fitted, metrics={**fitted.metrics, "holdout": new_score.to_dict()})
    current_score, note = _score_current(inputs.current_set, frame, window)
    gate = promotion.judge(fitted, training, holdout, predicted)
    better = current_score is None or _no_worse(new_score, current_score)
    return Calibrated(
        fitted,
        window,
        new_score,
        current_score,
        inputs.current_id,
        better and gate.passed,
        gate.reason() if not gate.passed else note or _verdict(new_score, current_score),
        [*left_out, *(str(w.message) for w in caught)],
        gate,
    )


def _warm(inputs: Inputs) -> dict[str, float] | None:
    """The current set's parameters when it is of the model being fitted: last night's optimum
    seeded into the search's first generation, which its elitism keeps, so a night's single
    search cannot settle in a basin worse on its own window than the one it already had (one
    "default" search from a fresh start lands in a worse basin from some seeds:
    ``benchmarks/restarts.py``)."""
    current = inputs.current_set
    name = inputs.spec.name if inputs.spec is not None else inputs.model
    return None if current is None or current.model != name else dict(current.values)


def fit_parameter_set(
    training: pd.DataFrame,
    building: Building,
    model: str,
    options: CalibrationOptions,
    spec: ModelSpec | None = None,
    warm_start: dict[str, float] | None = None,
) -> ParameterSet:
    """The engine's GA + GPS fit of ``model``, or of the adopted model ``spec`` (its network
    and derived-signal settings), on the training rows; ``warm_start``: parameters (of the same
    network) seeded into the search."""
    if spec is None:
        network, signals = (
            get_model(model, building, training.columns),
            SignalOptions.for_columns(training.columns),
        )
    else:
        check_columns(spec, training.columns)
        network, signals, model = spec.network(building), spec.signals, spec.name
    data = prepare(bridge_short_gaps(training), building, network.compile().input_names, signals)
    # The set records its parameters on bounds (``fit.at_bounds``), which promotion reads.
    estimator = Estimator(
        network,
        preset=options.preset,
        random_state=options.random_state,
        criterion=options.criterion,
        warn_bounds=False,
        warm_start=[warm_start] if warm_start else None,
    )
    estimator.fit(data)
    return ParameterSet.from_estimator(estimator, data, building, model, signals)


def holdout_forecast(
    pset: ParameterSet, frame: pd.DataFrame, window: Window
) -> tuple[pd.DataFrame, np.ndarray]:
    """The held-out rows and the set's day-ahead forecast of their ``t_in``. [°C]"""
    hours = (window.end - window.holdout_start).total_seconds() / 3600.0
    data = pset.prepare(frame)
    predicted = forecast(
        pset.compiled, pset.values, data, window.holdout_start, hours, noise=pset.noise
    )
    return frame.reindex(predicted.times), predicted.t_in_pred


def holdout_score(pset: ParameterSet, frame: pd.DataFrame, window: Window) -> FitMetrics:
    """Metrics of a day-ahead forecast of the held-out day against its measured ``t_in``."""
    holdout, predicted = holdout_forecast(pset, frame, window)
    return evaluate(holdout[T_IN].to_numpy(dtype=float), predicted)


def days_used(
    requested: int,
    first_stored: datetime,
    last_measured: datetime,
    step_s: float,
    holdout_h: float = HOLDOUT_H,
) -> int:
    """The days a calibration asked for ``requested`` days fits: at most the whole or partial
    days stored before the held-out day (at least 1: too little data fails the job, saying so).
    """
    window = _window(last_measured, step_s, requested, holdout_h)
    stored = (window.holdout_start - pd.Timestamp(first_stored)) / pd.Timedelta(days=1)
    return max(1, min(requested, math.ceil(stored)))


def _window(
    last_measured: datetime | None, step_s: float | None, days: int, holdout_h: float
) -> Window:
    if last_measured is None or step_s is None:
        raise CalibrationError("no measured t_in stored yet; upload measurements first")
    end = pd.Timestamp(last_measured) + pd.Timedelta(seconds=step_s)
    holdout_start = end - pd.Timedelta(hours=holdout_h)
    return Window(holdout_start - pd.Timedelta(days=days), holdout_start, end, step_s)


def _adopted(document: dict[str, Any] | None) -> ModelSpec | None:
    return None if document is None else ModelSpec.from_dict(document)


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


def _no_worse(new: FitMetrics, current: FitMetrics) -> bool:
    """The new set's held-out RMSE is no worse than the current's, to the polish's relative
    tolerance: a night seeded with the current set that ends at the same optimum differs from it
    by the optimiser's last digits (2.6e-8 K on a 0.007 K day), not by the model."""
    return new.rmse <= current.rmse * (1.0 + POLISH_TOL)


def _verdict(new: FitMetrics, current: FitMetrics | None) -> str:
    if current is None:
        return "no current parameter set"
    relation = "no worse than" if _no_worse(new, current) else "worse than"
    return (
        f"held-out day RMSE {new.rmse:.3f} K is {relation} the current set's {current.rmse:.3f} K"
    )
