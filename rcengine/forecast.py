"""Forecasts with a calibrated model: state from past measurements, then open loop over future
inputs (weather forecast, planned HVAC heat).

The state at the forecast start comes from a Kalman filter over the contiguous measurements just
before it (:mod:`rcengine.kalman`), never from a guess.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from rcengine.columns import Q_HVAC
from rcengine.dataset import Dataset
from rcengine.exceptions import DataValidationError, ModelError, Problem
from rcengine.kalman import FilterResult, kalman_filter
from rcengine.network import CompiledNetwork
from rcengine.statespace import DiscreteStateSpace

DEFAULT_HISTORY_H = 48.0


@dataclass(frozen=True)
class Forecast:
    """times: forecast rows (UTC); t_in_pred [°C]; state0: node temperatures at the start [°C];
    model: the discrete model used; filter: the Kalman pass over the history."""

    times: pd.DatetimeIndex
    t_in_pred: np.ndarray
    state0: np.ndarray
    model: DiscreteStateSpace
    filter: FilterResult

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame({"t_in_pred": self.t_in_pred}, index=self.times.rename("time"))


def initial_state(
    model: DiscreteStateSpace, data: Dataset, start: pd.Timestamp, history_h: float
) -> FilterResult:
    """Kalman filter over the contiguous rows in [start − history_h, start) ending at start."""
    past = data.frame.loc[(data.frame.index < start)]
    past = past.loc[past.index >= start - pd.Timedelta(hours=history_h)]
    step = pd.Timedelta(seconds=data.step_s)
    if past.empty or past.index[-1] != start - step:
        raise DataValidationError(
            [
                Problem(
                    None,
                    "t_in",
                    f"no measurements in the step before {start.isoformat()}; "
                    "the state at the forecast start is estimated from past measurements",
                )
            ]
        )
    history = Dataset(past, data.step_s)
    last = history.segments[-1]
    rows = history.frame.iloc[last]
    measured = rows["t_in"].to_numpy(dtype=float) if "t_in" in rows else np.array([np.nan])
    if not np.isfinite(measured).any():
        raise DataValidationError(
            [Problem(None, "t_in", f"no measured t_in in the {history_h:g} h before {start}")]
        )
    u = Dataset(rows, data.step_s).inputs(model.input_names)
    return kalman_filter(model, u, measured)


def future_inputs(
    data: Dataset, start: pd.Timestamp, steps: int, names: tuple[str, ...]
) -> tuple[pd.DatetimeIndex, np.ndarray]:
    """Input rows for ``steps`` steps from ``start``; errors name the missing columns and times."""
    times = pd.date_range(start, periods=steps, freq=pd.Timedelta(seconds=data.step_s))
    rows = data.frame.reindex(times)
    problems = [
        Problem(None, name, f"missing at {len(miss)} forecast time(s), first {miss[0].isoformat()}")
        for name in names
        if (miss := times[~np.isfinite(_column(rows, name))]).size
    ]
    if problems:
        raise DataValidationError(problems)
    return times, rows[list(names)].to_numpy(dtype=float)


def _column(rows: pd.DataFrame, name: str) -> np.ndarray:
    if name not in rows.columns:
        return np.full(len(rows), np.nan)
    return rows[name].to_numpy(dtype=float)


def forecast(
    network: CompiledNetwork,
    params: dict[str, float],
    data: Dataset,
    start: object,
    hours: float,
    history_h: float = DEFAULT_HISTORY_H,
) -> Forecast:
    """Indoor temperature for ``hours`` from ``start`` using the inputs already in ``data``."""
    start = _timestamp(start)
    steps = round(hours * 3600.0 / data.step_s)
    if steps < 1:
        raise ModelError(f"forecast horizon {hours} h is shorter than one step")
    model = network.discrete(params, data.step_s)
    filtered = initial_state(model, data, start, history_h)
    times, u = future_inputs(data, start, steps, model.input_names)
    y, _ = model.simulate(u, filtered.state)
    return Forecast(times, y, filtered.state, model, filtered)


def trajectories(
    model: DiscreteStateSpace,
    x0: np.ndarray,
    u: np.ndarray,
    candidates: np.ndarray,
    varied: str = Q_HVAC,
) -> np.ndarray:
    """Outputs for many candidate trajectories of one input (an MPC's decision), in one product.

    By linearity y_n = y(u with varied = 0) + H q_n, with H the lower-triangular Toeplitz matrix
    of the varied input's impulse response (Markov parameters C Aᵏ B_j).

    Parameters
    ----------
    u : (H, m) inputs; the varied column is ignored. candidates : (N, H) values of ``varied``.
    Returns (N, H) outputs. [°C]
    """
    if varied not in model.input_names:
        raise ModelError(f"the model has no input {varied!r}; inputs: {model.input_names}")
    j = model.input_names.index(varied)
    candidates = np.atleast_2d(np.asarray(candidates, dtype=float))
    horizon = u.shape[0]
    if candidates.shape[1] != horizon:
        raise ModelError(f"candidate length {candidates.shape[1]} ≠ horizon {horizon} steps")
    base_u = u.copy()
    base_u[:, j] = 0.0
    base, _ = model.simulate(base_u, x0)
    markov = np.empty(horizon)
    markov[0] = model.D[j]
    state = model.B[:, j].copy()
    for k in range(1, horizon):
        markov[k] = model.C @ state
        state = model.A @ state
    lag = np.arange(horizon)[:, None] - np.arange(horizon)[None, :]
    toeplitz = np.where(lag >= 0, markov[np.maximum(lag, 0)], 0.0)
    return base + candidates @ toeplitz.T


def _timestamp(value: object) -> pd.Timestamp:
    ts = pd.Timestamp(value)
    if ts.tzinfo is None:
        raise DataValidationError(
            [Problem(None, "start", f"start {value!r} needs a UTC offset, e.g. +01:00")]
        )
    return ts.tz_convert("UTC")
