"""Reference linear MPC over a calibrated discrete model: the heat plan of least energy (or cost
under a price) that keeps the indoor temperature in a comfort band.

Over a horizon of H steps from the filtered state x₀, the model is linear in the heat, so the
indoor temperature at the end of step k is (see :func:`rcengine.forecast.trajectories`)

    t_in[k+1] = t_free[k+1] + Σ_{j≤k} G[k+1, j] q[j],

with t_free the response with no heat and G the heat's impulse response. The plan solves the
linear programme

    min  Σ_k p[k] q[k] Δt  +  w Σ_k (s⁻[k] + s⁺[k]) Δt
    s.t. t_in[k+1] + s⁻[k] ≥ t_min[k] + margin,   t_in[k+1] − s⁺[k] ≤ t_max[k] − margin,
         0 ≤ q[k] ≤ q_max,   s⁻, s⁺ ≥ 0,

with HiGHS (``scipy.optimize.linprog``). The band is soft: the slacks s⁻, s⁺ [K] make every
request solvable. Their weight w is set so that one K·h outside the band costs more than running
the heater at full power for ``LEXICOGRAPHIC_H`` hours — longer than any horizon — so the plan
first leaves the band as little as the heater allows (the least-violation plan) and only then
spends the least. ``margin`` [K] aims inside the band, a back-off against model error.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from rcengine.columns import Q_HVAC
from rcengine.exceptions import ModelError
from rcengine.forecast import trajectories
from rcengine.statespace import DiscreteStateSpace

S_PER_H = 3600.0
W_PER_KW = 1000.0
# Hours of full-power heating that one K·h of discomfort outweighs (longer than any horizon).
LEXICOGRAPHIC_H = 1000.0
# Slack below which the band counts as met [K] (HiGHS's default feasibility tolerance is 1e-7).
BAND_TOLERANCE_K = 1e-3


@dataclass(frozen=True)
class Plan:
    """The planned heat and what the model predicts with it.

    q_hvac (H,): heat of each step [W]; t_in (H+1,): indoor temperature at each row start,
    t_in[0] now [°C]; setpoint (H,): the thermostat setpoint that gives the same heat — t_in at
    the end of each heated step, the band's lower edge (NaN: none) where the plan does not heat
    [°C]; below, above (H,): how far t_in[k+1] leaves the band [K]; energy_kwh: heat over the
    horizon [kWh]; cost: under the price [price unit]; solve_s: solver time [s]; q_max: heater
    capacity [W]; step_s: the model's step [s].
    """

    q_hvac: np.ndarray
    t_in: np.ndarray
    setpoint: np.ndarray
    below: np.ndarray
    above: np.ndarray
    energy_kwh: float
    cost: float
    solve_s: float
    q_max: float
    step_s: float

    @property
    def violation_kh(self) -> float:
        """Time-integrated distance outside the band over the horizon. [K·h]"""
        return float((self.below + self.above).sum() * self.step_s / S_PER_H)

    @property
    def feasible(self) -> bool:
        """Whether the band is met at every step (within ``BAND_TOLERANCE_K``)."""
        return bool(
            max(self.below.max(initial=0.0), self.above.max(initial=0.0)) <= BAND_TOLERANCE_K
        )

    def message(self) -> str:
        """Plain words on whether the band is met, and if not why and where."""
        if self.feasible:
            return "the comfort band is met at every step"
        parts = []
        if (cold := np.flatnonzero(self.below > BAND_TOLERANCE_K)).size:
            parts.append(
                f"unreachable with the heater's capacity of {self.q_max / W_PER_KW:g} kW: up to "
                f"{self.below.max():.2f} K below the band, first at the end of step {cold[0]}"
            )
        if (warm := np.flatnonzero(self.above > BAND_TOLERANCE_K)).size:
            parts.append(
                f"up to {self.above.max():.2f} K above the band without any heat (no cooling), "
                f"first at the end of step {warm[0]}"
            )
        return "comfort band " + "; ".join(parts) + "; this is the plan of least violation"


def plan(
    model: DiscreteStateSpace,
    x0: np.ndarray,
    u: np.ndarray,
    t_min: np.ndarray,
    t_max: np.ndarray,
    q_max: float,
    price: np.ndarray | None = None,
    margin: float = 0.0,
) -> Plan:
    """The heat plan of least cost that keeps t_in in the band (soft), see the module docstring.

    Parameters
    ----------
    model : the discrete model; it must have the input ``q_hvac``.
    x0 : (n,) state at the first step, e.g. from :func:`rcengine.forecast.initial_state`. [°C]
    u : (H, m) inputs over the horizon in ``model.input_names`` order (weather and gains
        forecast); the ``q_hvac`` column is ignored. The last row is held for the end state.
    t_min, t_max : (H,) band for t_in at the end of each step; NaN: no edge. [°C]
    q_max : heater capacity. [W]
    price : (H,) energy price per step [price unit / kWh]; None: 1, i.e. minimise energy.
    margin : back-off inside the band. [K]
    """
    u = np.asarray(u, dtype=float)
    steps = u.shape[0]
    t_min, t_max, price = _checked(steps, t_min, t_max, q_max, price, margin)
    dt_h = model.dt / S_PER_H
    # One more row than decisions: t_in at the end of the last step, its inputs held.
    rows = np.vstack([u, u[-1:]])
    pulses = np.vstack([np.zeros(steps + 1), np.eye(steps + 1)[:steps]])
    outputs = trajectories(model, x0, rows, pulses * W_PER_KW, Q_HVAC)
    t_free = outputs[0]
    response = (outputs[1:] - t_free).T[1:]  # (H, H): t_in[k+1] per kW in step j
    started = time.perf_counter()
    q_kw = _solve(response, t_free[1:], t_min + margin, t_max - margin, q_max, price, dt_h)
    solve_s = time.perf_counter() - started
    t_in = t_free + np.concatenate([[0.0], response @ q_kw])
    heated = q_kw > 1e-6 * q_max / W_PER_KW
    q_hvac = q_kw * W_PER_KW
    return Plan(
        q_hvac=q_hvac,
        t_in=t_in,
        setpoint=np.where(heated, t_in[1:], t_min),
        below=np.where(np.isfinite(t_min), np.maximum(t_min - t_in[1:], 0.0), 0.0),
        above=np.where(np.isfinite(t_max), np.maximum(t_in[1:] - t_max, 0.0), 0.0),
        energy_kwh=float(q_kw.sum() * dt_h),
        cost=float(price @ q_kw * dt_h),
        solve_s=solve_s,
        q_max=float(q_max),
        step_s=model.dt,
    )


def _checked(
    steps: int,
    t_min: np.ndarray,
    t_max: np.ndarray,
    q_max: float,
    price: np.ndarray | None,
    margin: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The band and price as float arrays of ``steps``; ModelError naming what is wrong."""
    if steps < 1:
        raise ModelError("the horizon needs at least one step")
    if not (np.isfinite(q_max) and q_max > 0.0):
        raise ModelError(f"heater capacity q_max must be positive and finite, got {q_max} W")
    if not (np.isfinite(margin) and margin >= 0.0):
        raise ModelError(f"margin must be non-negative, got {margin} K")
    price = np.ones(steps) if price is None else np.asarray(price, dtype=float)
    t_min, t_max = np.asarray(t_min, dtype=float), np.asarray(t_max, dtype=float)
    for name, values in (("t_min", t_min), ("t_max", t_max), ("price", price)):
        if values.shape != (steps,):
            raise ModelError(f"{name} has shape {values.shape}, the horizon {steps} steps")
    if not np.isfinite(price).all():
        raise ModelError("price must be finite at every step")
    with np.errstate(invalid="ignore"):
        crossed = np.flatnonzero(t_min + margin > t_max - margin)
    if crossed.size:
        k = crossed[0]
        raise ModelError(
            f"empty comfort band at step {k}: t_min {t_min[k]:g} °C + margin above "
            f"t_max {t_max[k]:g} °C − margin"
        )
    return t_min, t_max, price


def _solve(
    response: np.ndarray,
    t_free: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    q_max: float,
    price: np.ndarray,
    dt_h: float,
) -> np.ndarray:
    """The heat [kW] from the linear programme over x = (q [kW], s⁻ [K], s⁺ [K]), one block of
    H each (the slacks are reported against the band itself, without the margin)."""
    steps = len(t_free)
    weight = LEXICOGRAPHIC_H * max(np.abs(price).max(), 1e-9) * q_max / W_PER_KW
    cost = np.concatenate([price * dt_h, np.full(2 * steps, weight * dt_h)])
    eye, zero = np.eye(steps), np.zeros((steps, steps))
    has_min, has_max = np.isfinite(lower), np.isfinite(upper)
    # t_free + G q + s⁻ ≥ lower  ⇔  −G q − s⁻ ≤ t_free − lower;  t_free + G q − s⁺ ≤ upper.
    a_ub = np.vstack(
        [np.hstack([-response, -eye, zero])[has_min], np.hstack([response, zero, -eye])[has_max]]
    )
    b_ub = np.concatenate([(t_free - lower)[has_min], (upper - t_free)[has_max]])
    bounds = [(0.0, q_max / W_PER_KW)] * steps + [(0.0, None)] * (2 * steps)
    result = linprog(
        cost,
        A_ub=a_ub if len(b_ub) else None,
        b_ub=b_ub if len(b_ub) else None,
        bounds=bounds,
        method="highs",
    )
    if result.status != 0:
        raise ModelError(f"the MPC's linear programme failed in HiGHS: {result.message}")
    return result.x[:steps]
