"""Batched cost of parameter sets on segmented data, with unmeasured initial states profiled out.

The output is linear in the initial state, y = y_forced(θ) + O(θ) δ, where δ are the initial
temperatures of the unmeasured nodes (wall, internal mass) relative to a prior (every node at the
first measured indoor temperature). For every candidate θ and every segment the best δ is
therefore a small linear least-squares problem (variable projection, Golub & Pereyra 1973):

    δ*(θ) = argmin ‖y − y_forced − O δ‖² + ρ ‖δ‖²,

solved in closed form. The initial states are thus estimated from the data as extra parameters,
exactly and at the cost of one extra free-response evaluation, instead of being guessed or added
to the search space. The ridge ρ only matters for states the output barely sees (it then keeps
them at the prior instead of letting them wander).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcengine.dataset import Dataset
from rcengine.exceptions import DataValidationError, Problem
from rcengine.network import CompiledNetwork
from rcengine.simulate import ModalSystem, free_response, modal_system, simulate_modal

COSTS = ("mse", "nmse")
# Relative ridge on the profiled initial states [1/step]; see module docstring.
_RIDGE_PER_STEP = 1e-6
# Profiled initial temperatures stay within this band around the prior. [K]
_MAX_INITIAL_OFFSET_K = 20.0
# Work budget per population chunk: candidates × time steps.
_CHUNK_ELEMENTS = 1_500_000


@dataclass(frozen=True)
class Segment:
    u: np.ndarray  # (T, m) inputs
    y: np.ndarray  # (T,) measured output, NaN where missing
    start: int  # first row in the dataset

    @property
    def mask(self) -> np.ndarray:
        return np.isfinite(self.y)

    @property
    def observed(self) -> np.ndarray | slice:
        """Index of the measured rows; a plain slice when every row is (indexing then copies
        nothing)."""
        mask = self.mask
        return slice(None) if mask.all() else mask


@dataclass(frozen=True)
class Trajectory:
    """Simulated output and estimated initial node temperatures of one parameter set."""

    y: np.ndarray  # (T,) over all dataset rows [°C]
    initial_states: list[np.ndarray]  # per segment, (n,) [°C]


class Objective:
    """Cost of parameter sets ``theta`` (S, p) on ``data`` for ``network``.

    Parameters
    ----------
    network : compiled RC network.
    data : dataset holding every input of the network and measured ``t_in``.
    cost : "mse" (thesis Eq. 9) or "nmse" (Eq. 10, MSE / mean(y)²).
    """

    def __init__(self, network: CompiledNetwork, data: Dataset, cost: str = "mse"):
        if cost not in COSTS:
            raise ValueError(f"invalid cost {cost!r}; choose from {COSTS}")
        self.network = network
        self.step_s, self.hold = data.step_s, data.hold
        self.cost = cost
        u = data.inputs(network.input_names)
        y = data.measured
        self.segments = [Segment(u[s], y[s], s.start) for s in data.segments]
        self.n_rows = len(data)
        self.n_obs = int(np.isfinite(y).sum())
        if self.n_obs == 0:
            raise DataValidationError([Problem(None, "t_in", "no measured indoor temperature")])
        mean_y = float(np.nanmean(y))
        self._normaliser = self.n_obs * (mean_y**2 if cost == "nmse" else 1.0)
        self.n_evaluations = 0

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """Cost of each parameter set (S,); infinite for an invalid or unstable set."""
        theta = self.network.as_theta(theta)
        chunk = max(1, _CHUNK_ELEMENTS // max(1, self.n_rows))
        costs = np.concatenate(
            [self._sse(theta[i : i + chunk]) for i in range(0, theta.shape[0], chunk)]
        )
        costs = costs / self._normaliser
        return np.where(np.isfinite(costs), costs, np.inf)

    def _sse(self, theta: np.ndarray) -> np.ndarray:
        resid = self.residuals(theta)
        return np.einsum("st,st->s", resid, resid)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """Measured − simulated at every measured row (S, n_obs); NaN for an invalid set."""
        theta = self.network.as_theta(theta)
        self.n_evaluations += theta.shape[0]
        system = modal_system(self.network.rc_matrices(theta), self.step_s, self.hold)
        parts = []
        for seg in self.segments:
            y_fit, _ = self._fit_segment(system, seg)
            parts.append((seg.y - y_fit)[:, seg.observed])
        resid = np.concatenate(parts, axis=1)
        resid[~system.valid] = np.nan
        return resid

    def _fit_segment(self, system: ModalSystem, seg: Segment) -> tuple[np.ndarray, np.ndarray]:
        """Best output (S, T) and initial node temperatures (S, n) for one segment."""
        S, n = system.decay.shape
        y0 = seg.y[seg.mask][0] if seg.mask.any() else float(np.nan)
        prior = np.full((S, n), y0)
        profiled = self._profiled_nodes(seg)
        y_forced = simulate_modal(system, seg.u, system.modal_state(prior, seg.u[0]))
        if not profiled or not seg.mask.any():
            return y_forced, prior
        sensitivity = free_response(system, seg.u.shape[0], profiled)
        seen = sensitivity[:, seg.observed, :]
        r = (seg.y - y_forced)[:, seg.observed]
        seen_t = np.swapaxes(seen, 1, 2)
        gram = seen_t @ seen
        gram += _RIDGE_PER_STEP * seg.u.shape[0] * np.eye(len(profiled))
        rhs = (seen_t @ r[:, :, None])[:, :, 0]
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(gram).all((1, 2)) & np.isfinite(rhs).all(1)
            delta = np.zeros_like(rhs)
            delta[ok] = np.linalg.solve(gram[ok], rhs[ok][..., None])[..., 0]
        delta = np.clip(delta, -_MAX_INITIAL_OFFSET_K, _MAX_INITIAL_OFFSET_K)
        x0 = prior.copy()
        x0[:, profiled] += delta
        return y_forced + (sensitivity @ delta[:, :, None])[:, :, 0], x0

    def _profiled_nodes(self, seg: Segment) -> list[int]:
        """Nodes whose initial temperature is estimated: all but a measured output state."""
        states = self.network.state_names
        everything = list(range(len(states)))
        if self.network.output_node in states and seg.mask[0]:
            everything.remove(states.index(self.network.output_node))
        return everything

    def trajectory(self, theta: np.ndarray | dict) -> Trajectory:
        """Simulated output over every row of the data, with the profiled initial states."""
        theta = self.network.as_theta(theta)[:1]
        system = modal_system(self.network.rc_matrices(theta), self.step_s, self.hold)
        y = np.full(self.n_rows, np.nan)
        states = []
        for seg in self.segments:
            y_fit, x0 = self._fit_segment(system, seg)
            y[seg.start : seg.start + seg.y.size] = y_fit[0]
            states.append(x0[0])
        return Trajectory(y, states)
