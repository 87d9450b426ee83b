"""Forecasts with a calibrated model: state from past measurements, then open loop over future
inputs (weather forecast, planned HVAC heat).

The state at the forecast start comes from a Kalman filter over the contiguous measurements just
before it (:mod:`rcengine.kalman`), never from a guess. Its covariance, carried through the
horizon with the process noise, plus the sensor noise, gives ``t_in_std``: the standard deviation
of the measured indoor temperature about the forecast — the noise model fitted by maximum
likelihood when given, else the filter's fixed defaults (then only nominal). Parameter
uncertainty is not included.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rcengine.columns import Q_HVAC, T_IN, VENT_LOSS, WIND_LOSS
from rcengine.dataset import Dataset, bridge_short_gaps
from rcengine.exceptions import DataValidationError, ModelError, Problem
from rcengine.io.instants import parse_instant
from rcengine.kalman import MEASUREMENT_STD_K, FilterResult, Noise, kalman_filter
from rcengine.network import CompiledNetwork
from rcengine.signals.derived import mask_measured
from rcengine.statespace import DiscreteStateSpace

DEFAULT_HISTORY_H = 48.0
# Passes re-linearising a forecast's air-exchange losses at its own t_in, and the change of the
# forecast [K] below which they stop: the loss coefficient is a small share of the envelope's
# conductance, so each pass shrinks the change several-fold.
LINEARISATION_PASSES = 20
LINEARISATION_TOL_K = 1e-10


@dataclass(frozen=True)
class Forecast:
    """times: forecast rows (UTC); t_in_pred [°C]; state0: node temperatures at the start [°C];
    model: the discrete model used; filter: the Kalman pass over the history; t_in_std: standard
    deviation of the measured t_in about t_in_pred [K] (see the module docstring)."""

    times: pd.DatetimeIndex
    t_in_pred: np.ndarray
    state0: np.ndarray
    model: DiscreteStateSpace
    filter: FilterResult
    t_in_std: np.ndarray

    def to_frame(self, std: bool = False) -> pd.DataFrame:
        """``t_in_pred`` by time (CONTRACT.md §3), and ``t_in_std`` beside it if ``std``."""
        columns = {"t_in_pred": self.t_in_pred} | ({"t_in_std": self.t_in_std} if std else {})
        return pd.DataFrame(columns, index=self.times.rename("time"))


def initial_state(
    model: DiscreteStateSpace,
    data: Dataset,
    start: pd.Timestamp,
    history_h: float,
    process_cov: np.ndarray | None = None,
    measurement_std: float = MEASUREMENT_STD_K,
) -> FilterResult:
    """Kalman filter over the contiguous rows in [start − history_h, start) ending at start
    (``process_cov`` [K²] and ``measurement_std`` [K] as in :func:`kalman_filter`)."""
    past = data.frame.loc[(data.frame.index < start)]
    # A dropped reading hours before the start would otherwise cut the filter's run there, and
    # the slow states be estimated from the few hours after it (a day-ahead RMSE 12 % higher with
    # one row missing 3 h before the start, test bed); across a bridged gap the filter predicts
    # on interpolated inputs and the next measurement corrects it.
    past = bridge_short_gaps(
        past.loc[past.index >= start - pd.Timedelta(hours=history_h)], step_s=data.step_s
    )
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
    history = Dataset(past, data.step_s, data.hold)
    last = history.segments[-1]
    rows = history.frame.iloc[last]
    measured = rows["t_in"].to_numpy(dtype=float) if "t_in" in rows else np.array([np.nan])
    if not np.isfinite(measured).any():
        raise DataValidationError(
            [Problem(None, "t_in", f"no measured t_in in the {history_h:g} h before {start}")]
        )
    u = Dataset(rows, data.step_s, data.hold).inputs(model.input_names)
    return kalman_filter(
        model, u, measured, process_cov=process_cov, measurement_std=measurement_std
    )


def output_std(model: DiscreteStateSpace, filtered: FilterResult, steps: int) -> np.ndarray:
    """Standard deviation of the measured output over an open-loop horizon [K]: the filter's state
    covariance at the start, carried by P ← A P Aᵀ + Q, seen through y = C x + v:
    var y[k] = C P[k] Cᵀ + R."""
    std = np.empty(steps)
    P = filtered.covariance
    for k in range(steps):
        std[k] = np.sqrt(model.C @ P @ model.C + filtered.measurement_var)
        P = model.A @ P @ model.A.T + filtered.process_cov
    return std


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
    noise: Noise | None = None,
) -> Forecast:
    """Indoor temperature for ``hours`` from ``start`` using the inputs already in ``data``;
    ``noise``: the fitted noise model (``Estimator.noise_``), None for the filter's defaults."""
    start = parse_instant(start, "start")
    steps = round(hours * 3600.0 / data.step_s)
    if steps < 1:
        raise ModelError(f"forecast horizon {hours} h is shorter than one step")
    model = network.discrete(params, data.step_s, data.hold)
    if noise is None:
        filtered = initial_state(model, data, start, history_h)
    else:
        process_cov = noise.process_cov(network, params, data.step_s)
        filtered = initial_state(model, data, start, history_h, process_cov, noise.measurement_std)
    times, u = future_inputs(data, start, steps, model.input_names)
    y, _ = model.simulate(u, filtered.state)
    return Forecast(times, y, filtered.state, model, filtered, output_std(model, filtered, steps))


def forecast_frame(
    network: CompiledNetwork,
    params: dict[str, float],
    frame: pd.DataFrame,
    prepare: Callable[[pd.DataFrame], Dataset],
    start: pd.Timestamp,
    hours: float,
    history_h: float = DEFAULT_HISTORY_H,
    noise: Noise | None = None,
) -> tuple[Forecast, Dataset]:
    """``forecast`` from a contract ``frame`` (``prepare`` derives the model's inputs): the t_in
    measured in the horizon withheld (``mask_measured``), and the inputs that depend on the indoor
    temperature — the air-exchange losses n·ρc_pV/3600·(t_in − t_out) — linearised at the
    forecast's own t_in, pass after pass to a fixed point. Returns the forecast and the dataset
    of its last pass."""
    frame = mask_measured(frame, start)
    data = prepare(frame)
    result = forecast(network, params, data, start, hours, history_h, noise)
    if not set(network.input_names) & {VENT_LOSS, WIND_LOSS}:
        return result, data
    for _ in range(LINEARISATION_PASSES):
        frame.loc[result.times, T_IN] = result.t_in_pred
        data = prepare(frame)
        latest = forecast(network, params, data, start, hours, history_h, noise)
        moved = float(np.max(np.abs(latest.t_in_pred - result.t_in_pred), initial=0.0))
        result = latest
        if moved < LINEARISATION_TOL_K:
            break
    return result, data


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
