"""Kalman filter for the unmeasured states of a fitted RC model.

Only the indoor air is measured; wall and internal-mass temperatures are hidden. Running the
filter over the measurements before a forecast gives the state at its start from data instead of a
guess, and its one-step-ahead innovations are the model's short-horizon errors (for diagnosis).

Model: x[k+1] = A x[k] + B u[k] + w,  w ~ N(0, Q);  y[k] = C x[k] + D u[k] + v,  v ~ N(0, R).
Without a fitted noise model, Q = q² · dt/3600 · I (a random walk of q K per √hour on every node)
and R = r². A model fitted by maximum likelihood (:mod:`rcengine.estimation.likelihood`) carries
its own :class:`Noise`: a diffusion per state, Q from the continuous model by Van Loan's method.

:func:`filter_batch` is the one filter loop, vectorised over S systems; its mean may carry extra
columns that follow the response to unit initial offsets (de Jong 1991), which the likelihood uses
to estimate the initial state or treat it as diffuse.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rcengine.exceptions import ModelError
from rcengine.network import CompiledNetwork
from rcengine.statespace import DiscreteStateSpace, discretize_stochastic

PROCESS_STD_K_PER_SQRT_H = 0.1
MEASUREMENT_STD_K = 0.1
# Prior spread of node temperatures not measured at the start [K].
INITIAL_STD_K = 5.0
S_PER_H = 3600.0
# The gain counts as converged when P⁻ changes by less than this fraction in one step, checked
# every _STEADY_CHECK rows.
_STEADY_RTOL = 1e-13
_STEADY_CHECK = 4


@dataclass(frozen=True)
class Noise:
    """The stochastic part of a fitted model, dx = (A x + B u) dt + diag(σ_w) dω, y = C x + D u + v.

    process_std : σ_w of each state, in state order (a Wiener process per node). [K/√h]
    measurement_std : σ_v, the standard deviation of v. [K]
    """

    process_std: tuple[float, ...]
    measurement_std: float

    def process_cov(
        self, network: CompiledNetwork, params: Mapping[str, float] | np.ndarray, dt: float
    ) -> np.ndarray:
        """Q, the noise covariance gathered over one step of ``dt`` [s] (Van Loan). [K²]"""
        if len(self.process_std) != network.n_states:
            raise ModelError(
                f"{len(self.process_std)} process noise values for {network.n_states} states"
            )
        A = network.state_space(network.as_theta(params)[:1])[0][0]
        diffusion = np.diag(np.square(self.process_std) / S_PER_H)
        return discretize_stochastic(A, np.zeros((len(A), 0)), diffusion, dt)[2]

    def to_dict(self, state_names: Sequence[str]) -> dict:
        return {
            "process_std_K_per_sqrt_h": dict(zip(state_names, self.process_std, strict=True)),
            "measurement_std_K": self.measurement_std,
        }

    @classmethod
    def from_dict(cls, data: Mapping, state_names: Sequence[str]) -> Noise:
        process = data["process_std_K_per_sqrt_h"]
        return cls(tuple(float(process[s]) for s in state_names), float(data["measurement_std_K"]))


@dataclass(frozen=True)
class FilterResult:
    """state: x at the step after the last row [°C]; covariance: its covariance [K²];
    innovations: y − ŷ⁻ per row (NaN where y is missing) [K]; innovation_var: their variance [K²];
    predicted: one-step-ahead output ŷ⁻ per row [°C]; process_cov: the Q used [K²];
    measurement_var: the R used [K²]."""

    state: np.ndarray
    covariance: np.ndarray
    innovations: np.ndarray
    innovation_var: np.ndarray
    predicted: np.ndarray
    process_cov: np.ndarray
    measurement_var: float


@dataclass(frozen=True)
class BatchFilter:
    """Filter of S systems over T rows, mean with a columns (see :func:`filter_batch`).

    state (S,n,a): mean at the step after the last row; covariance (S,n,n); predicted (S,T,a):
    C x⁻ per row; innovations (S,T,a): target − C x⁻ in column 0, −C x⁻ in the others, NaN where
    the target is missing; variances (S,T): C P⁻ Cᵀ + R, NaN where missing.
    """

    state: np.ndarray
    covariance: np.ndarray
    predicted: np.ndarray
    innovations: np.ndarray
    variances: np.ndarray


def filter_batch(
    A: np.ndarray,
    forcing: np.ndarray,
    C: np.ndarray,
    target: np.ndarray,
    Q: np.ndarray,
    R: np.ndarray | float,
    X0: np.ndarray,
    P0: np.ndarray,
) -> BatchFilter:
    """Kalman filter of S discrete systems with a scalar output, in predictor form.

    x⁻[k+1] = A x⁻[k] + G[k] e[k] + f[k],   P⁻[k+1] = A P⁻[k] Aᵀ − G[k] s[k] G[k]ᵀ + Q,
    e[k] = target[k] − C x⁻[k],  s[k] = C P⁻[k] Cᵀ + R,  G[k] = A P⁻[k] Cᵀ / s[k].

    P⁻ does not depend on the data. Once it is unchanged to round-off and every remaining row is
    measured, the gain is constant and the rest is solved at once (:func:`_steady_rows`).

    Parameters
    ----------
    A : (S,n,n) discrete state matrices. forcing : (T,S,n) f[k] = B u[k].
    C : (S,n) output rows. target : (T,) or (T,S) y[k] − D u[k], NaN where not measured.
    Q : (S,n,n) process-noise covariance per step. R : (S,) or scalar measurement variance.
    X0 : (S,n,a) mean at the first row: column 0 the state, others carried along with
        no forcing and zero target (their innovations are −C times them).
    P0 : (S,n,n) covariance at the first row.
    """
    T = forcing.shape[0]
    S, n, a = X0.shape
    c = np.asarray(C, dtype=float)[:, None, :]
    cT = np.swapaxes(c, 1, 2)
    AT = np.swapaxes(A, 1, 2)
    R = np.broadcast_to(np.asarray(R, dtype=float), (S,)).reshape(S, 1, 1)
    goal = np.zeros((T, S, 1, a))
    goal[:, :, 0, 0] = np.broadcast_to(np.asarray(target, dtype=float).reshape(T, -1), (T, S))
    measured = np.isfinite(goal[:, 0, 0, 0])
    all_measured_from = T - int(np.argmin(measured[::-1])) if not measured.all() else 0
    X = np.array(X0, dtype=float)
    P = np.array(P0, dtype=float)
    predicted = np.empty((T, S, 1, a))
    innovations = np.full((T, S, 1, a), np.nan)
    variances = np.full((T, S, 1, 1), np.nan)
    for k in range(T):
        np.matmul(c, X, out=predicted[k])
        X_next = A @ X
        P_next = A @ P @ AT
        if measured[k]:
            e = np.subtract(goal[k], predicted[k], out=innovations[k])
            PC = P @ cT
            s = np.matmul(c, PC, out=variances[k])
            s += R
            H = A @ PC
            G = H / s
            X_next += G @ e
            P_next -= G * H.reshape(S, 1, n)
        X_next[:, :, 0] += forcing[k]
        P_next += Q
        steady = k >= all_measured_from and k % _STEADY_CHECK == 0 and k + 1 < T
        if (
            steady
            and (
                np.abs(P_next - P).max(axis=(1, 2)) <= _STEADY_RTOL * np.abs(P).max(axis=(1, 2))
            ).all()
        ):
            rest = slice(k + 1, T)
            predicted[rest], X_next = _steady_rows(A, c, G, goal[rest], forcing[rest], X_next)
            np.subtract(goal[rest], predicted[rest], out=innovations[rest])
            variances[rest] = s
            X, P = X_next, P_next
            break
        X, P = X_next, P_next
    return BatchFilter(
        X,
        0.5 * (P + np.swapaxes(P, 1, 2)),
        np.moveaxis(predicted[:, :, 0, :], 0, 1),
        np.moveaxis(innovations[:, :, 0, :], 0, 1),
        variances[:, :, 0, 0].T,
    )


def _steady_rows(
    A: np.ndarray,
    c: np.ndarray,
    G: np.ndarray,
    goal: np.ndarray,
    forcing: np.ndarray,
    X: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Mean over L rows with a constant gain G, from x⁻ = X at the first of them:
    x⁻[k+1] = F x⁻[k] + h[k],  F = A − G C,  h[k] = G target[k] + f[k].

    With h[−1] = X, x⁻[k] = Σ_{j<k} F^{k−1−j} h[j], a prefix sum weighted by powers of F, taken
    in log₂ L levels (Hillis & Steele 1986). F is the filter's closed loop (spectral radius < 1),
    so every power decays and the sum is as well conditioned as the recursion.
    Returns C x⁻ per row (L,S,1,a) and the mean after the last row (S,n,a).
    """
    L = goal.shape[0]
    S, n, a = X.shape
    # Rows on the third axis: each level is then one (n × n)·(n × L a) product per system.
    h = np.empty((S, n, L + 1, a))
    h[:, :, 0] = X
    h[:, :, 1:] = np.moveaxis(G[None] * goal, 0, 2)
    h[:, :, 1:, 0] += np.moveaxis(forcing, 0, 2)
    power, shift = A - G @ c, 1
    while shift <= L:
        # The right-hand side is evaluated before the in-place add, as the scan requires.
        h[:, :, shift:] += (power @ h[:, :, :-shift].reshape(S, n, -1)).reshape(S, n, -1, a)
        power = power @ power
        shift *= 2
    predicted = (c @ h[:, :, :-1].reshape(S, n, -1)).reshape(S, 1, L, a)
    return np.moveaxis(predicted, 2, 0), h[:, :, -1]


def kalman_filter(
    model: DiscreteStateSpace,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray | None = None,
    process_std: float = PROCESS_STD_K_PER_SQRT_H,
    measurement_std: float = MEASUREMENT_STD_K,
    process_cov: np.ndarray | None = None,
) -> FilterResult:
    """Filter rows u (T, m), y (T,) from x0 (default: every node at the first measured y).

    Parameters
    ----------
    process_std : random-walk intensity of every node, used when ``process_cov`` is None. [K/√h]
    measurement_std : indoor temperature sensor noise. [K]
    process_cov : (n, n) process-noise covariance per step, e.g. ``Noise.process_cov``. [K²]
    """
    n = model.A.shape[0]
    u = np.asarray(u, dtype=float)
    first = y[np.isfinite(y)]
    if x0 is None:
        x = np.full(n, first[0] if first.size else 20.0)
    else:
        x = np.asarray(x0, dtype=float).copy()
    if process_cov is None:
        process_cov = np.eye(n) * process_std**2 * model.dt / S_PER_H
    R = measurement_std**2
    run = filter_batch(
        model.A[None],
        (u @ model.B.T)[:, None, :],
        model.C[None],
        y - u @ model.D,
        process_cov[None],
        R,
        x[None, :, None],
        np.eye(n)[None] * INITIAL_STD_K**2,
    )
    return FilterResult(
        run.state[0, :, 0],
        run.covariance[0],
        run.innovations[0, :, 0],
        run.variances[0],
        run.predicted[0, :, 0] + u @ model.D,
        process_cov,
        R,
    )
