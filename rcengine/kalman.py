"""Kalman filter for the unmeasured states of a fitted RC model.

Only the indoor air is measured; wall and internal-mass temperatures are hidden. Running the
filter over the measurements before a forecast gives the state at its start from data instead of a
guess, and its one-step-ahead innovations are the model's short-horizon errors (for diagnosis).

Model: x[k+1] = A x[k] + B u[k] + w,  w ~ N(0, Q);  y[k] = C x[k] + D u[k] + v,  v ~ N(0, R),
with Q = q² · dt/3600 · I (a random walk of q K per √hour on every node) and R = r².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcengine.statespace import DiscreteStateSpace

PROCESS_STD_K_PER_SQRT_H = 0.1
MEASUREMENT_STD_K = 0.1
# Prior spread of node temperatures not measured at the start [K].
INITIAL_STD_K = 5.0


@dataclass(frozen=True)
class FilterResult:
    """state: x at the step after the last row [°C]; covariance: its covariance [K²];
    innovations: y − ŷ⁻ per row (NaN where y is missing) [K]; innovation_var: their variance [K²];
    predicted: one-step-ahead output ŷ⁻ per row [°C]."""

    state: np.ndarray
    covariance: np.ndarray
    innovations: np.ndarray
    innovation_var: np.ndarray
    predicted: np.ndarray


def kalman_filter(
    model: DiscreteStateSpace,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray | None = None,
    process_std: float = PROCESS_STD_K_PER_SQRT_H,
    measurement_std: float = MEASUREMENT_STD_K,
) -> FilterResult:
    """Filter rows u (T, m), y (T,) from x0 (default: every node at the first measured y).

    Parameters
    ----------
    process_std : random-walk intensity of every node. [K/√h]
    measurement_std : indoor temperature sensor noise. [K]
    """
    n = model.A.shape[0]
    first = y[np.isfinite(y)]
    if x0 is None:
        x = np.full(n, first[0] if first.size else 20.0)
    else:
        x = np.asarray(x0, dtype=float).copy()
    P = np.eye(n) * INITIAL_STD_K**2
    Q = np.eye(n) * process_std**2 * model.dt / 3600.0
    R = measurement_std**2
    T = u.shape[0]
    innovations = np.full(T, np.nan)
    variances = np.full(T, np.nan)
    predicted = np.empty(T)
    for k in range(T):
        predicted[k] = model.C @ x + model.D @ u[k]
        if np.isfinite(y[k]):
            PC = P @ model.C
            s = float(model.C @ PC + R)
            gain = PC / s
            innovations[k] = y[k] - predicted[k]
            variances[k] = s
            x = x + gain * innovations[k]
            P = P - np.outer(gain, PC)
        x = model.A @ x + model.B @ u[k]
        P = model.A @ P @ model.A.T + Q
    return FilterResult(x, 0.5 * (P + P.T), innovations, variances, predicted)
