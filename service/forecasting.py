"""Forecasts, MPC candidate trajectories and the state-space model, with the current set.

A forecast is a pure function of (parameter set, stored rows, start, horizon). Every upload
increments the building's ``data_revision``, so results are cached under
(set id, revision, start, horizon) and stay exact: a hit costs one small query. Parsed parameter
sets and their compiled networks are cached per set id (sets never change once stored).
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from typing import NamedTuple

import numpy as np
import pandas as pd

from rcengine.columns import TIME
from rcengine.dataset import Dataset
from rcengine.exceptions import DataValidationError, Problem
from rcengine.forecast import (
    DEFAULT_HISTORY_H,
    forecast_frame,
    future_inputs,
    initial_state,
    trajectories,
)
from rcengine.io.timeseries import format_times
from rcengine.kalman import Noise
from rcengine.models.spec import check_future_columns
from rcengine.network import CompiledNetwork
from rcengine.parameter_set import ParameterSet
from rcengine.signals import mask_measured
from rcengine.statespace import DiscreteStateSpace

from . import bridge, repository
from .cache import LRUCache
from .core.db import Database
from .errors import NoParameterSetError
from .models import ParameterSetRecord

# Parameter sets kept parsed and compiled in memory.
SET_CACHE_SIZE = 64


@dataclass(frozen=True)
class SetInfo:
    """What a response says about the parameter set it used."""

    id: int
    model: str
    created_at: datetime
    train_start: datetime
    train_end: datetime
    rmse_train: float | None
    rmse_holdout: float | None
    engine_version: str

    @classmethod
    def of(cls, record: ParameterSetRecord) -> SetInfo:
        return cls(
            record.id,
            record.model,
            record.created_at,
            record.train_start,
            record.train_end,
            record.rmse_train,
            record.rmse_holdout,
            record.engine_version,
        )


@dataclass(frozen=True)
class LoadedSet:
    info: SetInfo
    pset: ParameterSet
    compiled: CompiledNetwork
    noise: Noise | None


@dataclass(frozen=True)
class Prediction:
    """A forecast: UTC and local times, t_in_pred [°C], its standard deviation t_in_std [K]
    (the set's fitted noise model, else the filter's fixed defaults), the start state [°C], the
    discrete model and the dataset it ran on."""

    parameter_set: SetInfo
    timezone: str
    times: pd.DatetimeIndex
    local_times: list[str]
    t_in_pred: np.ndarray
    t_in_std: np.ndarray
    state0: np.ndarray
    model: DiscreteStateSpace
    data: Dataset

    def inputs(self) -> np.ndarray:
        """The future inputs (H, m) in the model's input order."""
        return future_inputs(self.data, self.times[0], len(self.times), self.model.input_names)[1]


@dataclass(frozen=True)
class ModelState:
    """The discrete model of the current set, the filtered state at ``at`` and the rows it was
    loaded with (those after ``at`` too, when asked for)."""

    parameter_set: SetInfo
    timezone: str
    model: DiscreteStateSpace
    at: pd.Timestamp
    state: np.ndarray
    covariance: np.ndarray
    data: Dataset

    def inputs_from_state(self, steps: int, decided: str) -> tuple[pd.DatetimeIndex, np.ndarray]:
        """Stored inputs (steps, m) from ``at`` in the model's order, with the ``decided``
        input (an MPC's decision, which need not be stored) set to zero."""
        names = self.model.input_names
        known = tuple(n for n in names if n != decided)
        times, values = future_inputs(self.data, self.at, steps, known)
        u = np.zeros((steps, len(names)))
        u[:, [names.index(n) for n in known]] = values
        return times, u


class ForecastKey(NamedTuple):
    """Everything a forecast depends on: the same key, the same answer."""

    set_id: int
    data_revision: int
    start: pd.Timestamp
    hours: float
    timezone: str


class Forecaster:
    """Forecasts for the routers; one per server process (owned by the app's lifespan)."""

    def __init__(self, db: Database, cache_size: int, history_h: float = DEFAULT_HISTORY_H):
        self.db = db
        self.history_h = history_h
        self._predictions: LRUCache[Prediction] = LRUCache(cache_size)
        self._sets: LRUCache[LoadedSet] = LRUCache(SET_CACHE_SIZE)
        self._discrete: LRUCache[DiscreteStateSpace] = LRUCache(SET_CACHE_SIZE)

    def forecast(self, building_id: int, start: pd.Timestamp | None, hours: float) -> Prediction:
        """Indoor temperature for ``hours`` from ``start`` (default: one step after the last
        measured ``t_in``) with the stored future inputs.

        Raises
        ------
        NoParameterSetError, NotFoundError; DataValidationError naming missing columns/times.
        """
        key = self._key(building_id, start, hours)
        return self._predictions.get_or_compute(
            key, lambda: self._predict(building_id, key.set_id, key.timezone, key.start, hours)
        )

    def cached(
        self, building_id: int, start: pd.Timestamp | None, hours: float
    ) -> Prediction | None:
        """The forecast if it is in the cache (one small query, no computation), else None."""
        return self._predictions.get(self._key(building_id, start, hours))

    def _key(self, building_id: int, start: pd.Timestamp | None, hours: float) -> ForecastKey:
        with self.db.connect() as connection:
            row = repository.forecast_key(connection, building_id)
        if row.set_id is None:
            raise NoParameterSetError(building_id)
        start = start if start is not None else _after_last_measured(row)
        return ForecastKey(row.set_id, row.data_revision, start, float(hours), row.timezone)

    def simulate(
        self, building_id: int, start: pd.Timestamp | None, q_hvac: np.ndarray
    ) -> tuple[Prediction, np.ndarray]:
        """Indoor temperature (N, H) for N candidate ``q_hvac`` trajectories (N, H) [W]."""
        with self.db.connect() as connection:
            step_s = repository.forecast_key(connection, building_id).step_s
        hours = q_hvac.shape[1] * (step_s or 0.0) / 3600.0
        prediction = self.forecast(building_id, start, hours)
        outputs = trajectories(prediction.model, prediction.state0, prediction.inputs(), q_hvac)
        return prediction, outputs

    def model_state(
        self, building_id: int, at: pd.Timestamp | None, hours: float = 0.0
    ) -> ModelState:
        """Discrete (A, B, C, D) of the current set and the Kalman state at ``at`` (default:
        one step after the last measured ``t_in``) from the measurements before it; the rows
        of the ``hours`` after ``at`` come along for a plan."""
        with self.db.session() as session:
            key = repository.forecast_key(session, building_id)
            if key.set_id is None:
                raise NoParameterSetError(building_id)
            at = at if at is not None else _after_last_measured(key)
            frame = bridge.load_frame(
                session,
                building_id,
                at - pd.Timedelta(hours=self.history_h),
                at + pd.Timedelta(hours=hours),
            )
        loaded = self._loaded(building_id, key.set_id)
        _require_rows(frame, at - pd.Timedelta(hours=self.history_h), at)
        data = loaded.pset.prepare(mask_measured(frame, at))
        model = self._discrete.get_or_compute(
            (key.set_id, data.step_s),
            lambda: loaded.compiled.discrete(loaded.pset.values, data.step_s, data.hold),
        )
        filtered = initial_state(model, data, at, self.history_h)
        return ModelState(
            loaded.info, key.timezone, model, at, filtered.state, filtered.covariance, data
        )

    def _predict(
        self, building_id: int, set_id: int, timezone: str, start: pd.Timestamp, hours: float
    ) -> Prediction:
        first = start - pd.Timedelta(hours=self.history_h)
        end = start + pd.Timedelta(hours=hours)
        with self.db.session() as session:
            frame = bridge.load_frame(session, building_id, first, end)
        loaded = self._loaded(building_id, set_id)
        _require_rows(frame, first, end)
        # Named by the columns to upload, not by the derived inputs computed from them.
        check_future_columns(frame, loaded.compiled.input_names, start, end, loaded.pset.signals)
        result, data = forecast_frame(
            loaded.compiled,
            loaded.pset.values,
            frame,
            loaded.pset.prepare,
            start,
            hours,
            self.history_h,
            loaded.noise,
        )
        return Prediction(
            loaded.info,
            timezone,
            result.times,
            format_times(result.times, timezone),
            result.t_in_pred,
            result.t_in_std,
            result.state0,
            result.model,
            data,
        )

    def _loaded(self, building_id: int, set_id: int) -> LoadedSet:
        def load() -> LoadedSet:
            with self.db.session() as session:
                record = repository.get_parameter_set(session, building_id, set_id)
                pset = bridge.parameter_set_of(record)
                return LoadedSet(SetInfo.of(record), pset, pset.compiled, pset.noise)

        return self._sets.get_or_compute(set_id, load)


def _after_last_measured(key) -> pd.Timestamp:
    if key.last_measured_at is None or key.step_s is None:
        raise DataValidationError(
            [Problem(None, "t_in", "no measured t_in stored yet; give 'start' or upload data")]
        )
    return pd.Timestamp(key.last_measured_at) + pd.Timedelta(seconds=key.step_s)


def _require_rows(frame: pd.DataFrame, first: pd.Timestamp, end: pd.Timestamp) -> None:
    if len(frame) < 2:
        raise DataValidationError(
            [
                Problem(
                    None,
                    TIME,
                    f"{len(frame)} stored row(s) between {first.isoformat()} and "
                    f"{end.isoformat()}; the forecast needs the measurements before its start "
                    "and the inputs over its horizon",
                )
            ]
        )
