"""Maximum-likelihood estimation of stochastic grey-box RC models (continuous–discrete Kalman).

Model: the RC network with a Wiener process on every state and a noisy sensor (Itô form, inputs
held over each step),

    dx = (A x + B u) dt + diag(σ_w) dω,        y[k] = C x[k] + D u[k] + v[k],  v ~ N(0, σ_v²).

Exact discretisation: x[k+1] = A_d x[k] + B_d u[k] + w[k], w ~ N(0, Q_d), with
Q_d = ∫₀^dt e^{Aτ} Σ e^{Aᵀτ} dτ, here through the network's modes (:func:`discretize_modal`;
equal to Van Loan's ``statespace.discretize_stochastic`` to round-off, and cheaper). Under the
model the Kalman filter's innovations e[k] are independent N(0, s[k]), so (Schweppe 1965)

    −ln L(θ) = ½ Σ_k [ ln(2π s[k]) + e[k]² / s[k] ].

Initial state (de Jong 1991). The filter's mean carries n more columns, the response to an
offset β of the initial state (whose covariance given β is zero): e[k] = e⁰[k] + F[k] β. With
M = Σ F[k]ᵀF[k]/s[k] and r = Σ F[k]ᵀe⁰[k]/s[k], β̂ = −M⁻¹ r and

- ``initial="diffuse"`` (default): β has an infinitely wide prior; the exact diffuse likelihood
  is −ln L at β̂ plus ½ ln det M (the mean is known only through the data);
- ``initial="estimated"``: β is a parameter, profiled out (−ln L at β̂), and the initial state
  spreads around it by one step of process noise, P₀ = Q_d. (With no spread the first
  measurement would be fitted exactly and −ln L would fall without bound as σ_v → 0; the
  stationary covariance is unbounded for the slow modes of heavy walls.)

Coordinates z: ln θ for the free physical parameters with non-negative bounds (θ / span
otherwise), ln σ_w per state [K/√h], ln σ_v [K]. The search keeps θ within the model's bounds,
as the output-error fit does (unbounded, the likelihood can prefer an unphysical reservoir, e.g. a
wall of near-infinite capacity with large noise): it runs in ξ, the logit of each physical z's
position between its bounds (noise coordinates unchanged). One batched filter screens a Latin
hypercube (the GA's first generation; more generations are a setting), each point scored at its
best overall noise level; from the best distinct points a trust-region method (Nocedal & Wright
2006, Algorithm 4.1, the exact step of Moré & Sorensen) minimises −ln L over ξ with the gradient
by central differences and the Hessian by Fisher scoring,

    I(ξ) ≈ Σ_k [ ∂e ∂eᵀ / s + ½ ∂ln s ∂ln sᵀ ],

all starts in lockstep: each iteration runs one filter batched over the 2q + 1 perturbed sets of
every running start's trial point. Standard errors come from the observed information, a
finite-difference Hessian of −ln L at the optimum (one more batch).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.special
from scipy.stats import chi2

from rcengine.dataset import Dataset
from rcengine.estimation import ga
from rcengine.estimation.ga import GASettings
from rcengine.estimation.residuals import ResidualChecks, residual_checks
from rcengine.estimation.search_space import SearchSpace
from rcengine.exceptions import DataValidationError, ModelError, Problem
from rcengine.kalman import S_PER_H, Noise, filter_batch
from rcengine.network import CompiledNetwork, RCMatrices
from rcengine.simulate import modal_system

INITIAL = ("diffuse", "estimated")
# Central-difference steps in z. The filter's −ln L carries ~1e-11 of round-off: the gradient is
# then good to ~1e-7, the Hessian (larger step, second differences) to ~1e-5 relative.
GRADIENT_STEP = 1e-4
HESSIAN_STEP = 1e-3
# Where the screen draws the noise intensities: σ_w [K/√h], σ_v [K]. Not bounds of the fit.
PROCESS_STD_RANGE = (1e-3, 1.0)
MEASUREMENT_STD_RANGE = (1e-3, 0.3)
# ln σ is held within these: outside, the variances under- or overflow. [K/√h or K]
_NOISE_LIMITS = (1e-9, 1e3)
# Closest a search start comes to a bound (fraction of the span): the logit stays finite.
_EDGE = 1e-9
# A parameter whose 95 % interval spans more than this factor is practically non-identifiable.
IDENTIFIABLE_SPAN = 10.0
Z_95 = 1.96
# Accepted steps over which −ln L must fall by ftol for a local search to go on.
_PATIENCE = 3
# Trust region in ξ: the first radius, its limits, and the least ratio of actual to promised
# decrease for a step to be taken (the values of scipy's trust-region methods).
_INITIAL_RADIUS, _MAX_RADIUS, _MIN_RADIUS = 1.0, 1000.0, 1e-10
_ACCEPT = 0.15
# Newton iterations for the trust-region multiplier (converges from below, in a few).
_SECULAR_STEPS = 8
# Relative ridge on M, so a segment too short to see every initial state stays solvable.
_RIDGE = 1e-10


@dataclass(frozen=True)
class LikelihoodSettings:
    """screen: the GA over the unit cube that seeds the local searches (one Latin-hypercube
    generation by default); its ``archive`` is the number of starts. gtol: a local search stops
    when |∇(−ln L)| in ξ falls below it, or when −ln L fell by less than ftol over the last
    ``_PATIENCE`` accepted steps (a flat valley, often a noise intensity heading to 0); max_iter:
    trust-region iterations per start."""

    screen: GASettings = field(
        default_factory=lambda: GASettings(population=64, generations=1, lhs=True, archive=3)
    )
    gtol: float = 1e-3
    ftol: float = 1e-2
    max_iter: int = 100


class LikelihoodSpace:
    """The likelihood's coordinates z = (physical, ln σ_w per state, ln σ_v), see module doc."""

    def __init__(self, space: SearchSpace, state_names: tuple[str, ...]):
        self.space = space
        self.state_names = tuple(state_names)
        self.positive = (space.lower >= 0) & (space.upper > 0)
        span = space.upper - space.lower
        self.scale = np.where(self.positive | (span <= 0), 1.0, span)
        self._floor = 1e-9 * np.where(space.upper > 0, space.upper, 1.0)
        self._lower, self._upper = self._physical(space.lower), self._physical(space.upper)
        self.names = [
            *space.free,
            *(f"process_std_{s}" for s in self.state_names),
            "measurement_std",
        ]

    @property
    def dim(self) -> int:
        return len(self.names)

    @property
    def logarithmic(self) -> np.ndarray:
        """(q,) whether each coordinate is a logarithm (the noise intensities always are)."""
        return np.concatenate([self.positive, np.ones(len(self.state_names) + 1, dtype=bool)])

    def split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """z (S, q) → full θ (S, p), σ_w (S, n) [K/√h], σ_v (S,) [K]."""
        z = np.atleast_2d(z)
        f = self.space.dim
        # exp(±700) is the float range; beyond it a set is simply invalid.
        physical = np.clip(z[:, :f], -700.0, 700.0)
        free = np.where(self.positive, np.exp(physical), physical * self.scale)
        noise = np.exp(np.clip(z[:, f:], *np.log(_NOISE_LIMITS)))
        return self.space.full(free), noise[:, :-1], noise[:, -1]

    def values(self, z: np.ndarray) -> np.ndarray:
        """z (S, q) → the values named by ``names`` (S, q)."""
        theta, process, measurement = self.split(z)
        return np.hstack([self.space.free_values(theta), process, measurement[:, None]])

    def value_scale(self, z: np.ndarray) -> np.ndarray:
        """d value / d z at z (q,): the value for logarithmic coordinates, else the span."""
        scale = np.concatenate([self.scale, np.ones(len(self.state_names) + 1)])
        return np.where(self.logarithmic, self.values(z)[0], scale)

    def _physical(self, free: np.ndarray) -> np.ndarray:
        """Free parameter values (…, f) → their z coordinates."""
        return np.where(self.positive, np.log(np.maximum(free, self._floor)), free / self.scale)

    @property
    def widths(self) -> np.ndarray:
        """(q,) the width in z of each coordinate's range: the model's bounds, then the noise
        screening ranges."""
        noise = [PROCESS_STD_RANGE] * len(self.state_names) + [MEASUREMENT_STD_RANGE]
        return np.concatenate([self._upper - self._lower, np.log([hi / lo for lo, hi in noise])])

    def from_unit(self, unit: np.ndarray) -> np.ndarray:
        """Unit-cube points (S, q) — the model's bounds, then the noise screening ranges — → z."""
        unit = np.atleast_2d(unit)
        f = self.space.dim
        physical = self._physical(self.space.free_values(self.space.to_physical(unit[:, :f])))
        lo = np.log([PROCESS_STD_RANGE[0]] * len(self.state_names) + [MEASUREMENT_STD_RANGE[0]])
        hi = np.log([PROCESS_STD_RANGE[1]] * len(self.state_names) + [MEASUREMENT_STD_RANGE[1]])
        return np.hstack([physical, lo + unit[:, f:] * (hi - lo)])

    def to_search(self, z: np.ndarray) -> np.ndarray:
        """z → ξ: each physical coordinate's logit between its bounds; noise unchanged."""
        xi = np.array(z, dtype=float)
        f = self.space.dim
        span = np.where(self._upper > self._lower, self._upper - self._lower, 1.0)
        position = np.clip((xi[..., :f] - self._lower) / span, _EDGE, 1.0 - _EDGE)
        xi[..., :f] = np.log(position) - np.log1p(-position)
        return xi

    def from_search(self, xi: np.ndarray) -> np.ndarray:
        """ξ → z (the inverse of :meth:`to_search`)."""
        z = np.array(xi, dtype=float)
        f = self.space.dim
        z[..., :f] = self._lower + (self._upper - self._lower) * scipy.special.expit(xi[..., :f])
        return z


@dataclass(frozen=True)
class Evaluation:
    """nll (S,): −ln L, infinite for an invalid set; innovations (S, N) [K] and variances (S, N)
    [K²] at the measured rows of every segment, with the initial state at β̂; initial_states:
    per segment (S, n) [°C]."""

    nll: np.ndarray
    innovations: np.ndarray
    variances: np.ndarray
    initial_states: list[np.ndarray]
    n_diffuse: int

    def noise_scale(self) -> np.ndarray:
        """λ̂ (S,): the factor on every noise variance (Q, R and P₀ together) that maximises the
        likelihood of each set — Σ e²/s / (N − n_diffuse), as the innovations do not change."""
        return np.sum(self.innovations**2 / self.variances, axis=1) / (
            self.innovations.shape[1] - self.n_diffuse
        )

    def concentrated_nll(self) -> np.ndarray:
        """−ln L (S,) with every set's noise variances scaled by its λ̂ (Harvey 1989, §3.4)."""
        scale = self.noise_scale()
        return self.nll + 0.5 * (self.innovations.shape[1] - self.n_diffuse) * (
            np.log(scale) + 1.0 - scale
        )


def discretize_modal(
    rc: RCMatrices, process_std: np.ndarray, dt: float, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A_d, B_d, Q_d as :func:`rcengine.statespace.discretize_stochastic` gives them, which
    sets are valid, and the feedthrough D, from the modes of the RC systems
    (:func:`rcengine.simulate.modal_system`; under first-order hold B_d and D are those of the
    shifted state, which leaves the noise as it is).

    With z = W T the modes decouple (rates λ_i, a_i = e^{−λ_i dt}); a noise of intensity
    Σ_z = W Σ Wᵀ, Σ = diag(σ_w²)/3600, gathers (Σ_z)_ij (1 − a_i a_j)/(λ_i + λ_j) over one step.
    No exponential of a stiff matrix, and ~5× cheaper than Van Loan's. process_std (S, n)
    [K/√h]; dt [s]. Invalid sets (not finite, not passive) get a harmless stand-in system.
    """
    modes = modal_system(rc, dt, hold)
    W = modes.to_modal
    capacity = np.where(modes.valid[:, None], rc.capacity, 1.0)
    to_nodes = np.swapaxes(W / capacity[:, None, :], 1, 2)  # W⁻¹ = C^{-1/2} Q
    # λ_i from the transform itself (the decays underflow for fast modes, whose noise counts).
    conductance = np.where(modes.valid[:, None, None], rc.K, 0.0) / capacity[:, :, None]
    rate = np.maximum(np.einsum("sij,sjk,ski->si", W, conductance, to_nodes), 0.0)
    pair = rate[:, :, None] + rate[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        gathered = np.where(pair * dt > 1e-12, -np.expm1(-pair * dt) / pair, dt)
    sigma_z = (W * (process_std**2 / S_PER_H)[:, None, :]) @ np.swapaxes(W, 1, 2)
    Q = to_nodes @ (sigma_z * gathered) @ np.swapaxes(to_nodes, 1, 2)
    A_d = (to_nodes * modes.decay[:, None, :]) @ W
    B_d = to_nodes @ modes.input_map
    return A_d, B_d, 0.5 * (Q + np.swapaxes(Q, 1, 2)), modes.valid, modes.feedthrough


class LikelihoodObjective:
    """−ln L of parameter sets z (S, q) on ``data``, every segment from its own initial state."""

    def __init__(
        self,
        network: CompiledNetwork,
        data: Dataset,
        space: LikelihoodSpace,
        initial: str = "diffuse",
    ):
        if initial not in INITIAL:
            raise ModelError(f"invalid initial {initial!r}; choose from {INITIAL}")
        self.network, self.space, self.initial = network, space, initial
        self.step_s, self.hold = data.step_s, data.hold
        u, y = data.inputs(network.input_names), data.measured
        self.segments = [(u[s], y[s]) for s in data.segments if np.isfinite(y[s]).any()]
        self.n_obs = int(np.isfinite(y).sum())
        if self.n_obs == 0:
            raise DataValidationError([Problem(None, "t_in", "no measured indoor temperature")])
        self.n_evaluations = 0

    def __call__(self, z: np.ndarray) -> Evaluation:
        theta, process_std, measurement_std = self.space.split(z)
        self.n_evaluations += theta.shape[0]
        rc = self.network.rc_matrices(theta)
        A_d, B_d, Q, valid, D = discretize_modal(rc, process_std, self.step_s, self.hold)
        n = A_d.shape[1]
        C, D = np.where(valid[:, None], rc.c, 0.0), np.where(valid[:, None], D, 0.0)
        P0 = Q if self.initial == "estimated" else np.zeros_like(Q)
        parts = [
            self._segment(A_d, B_d, C, D, Q, measurement_std**2, P0, u, y) for u, y in self.segments
        ]
        nll = np.sum([p[0] for p in parts], axis=0)
        nll = np.where(valid & np.isfinite(nll), nll, np.inf)
        return Evaluation(
            nll,
            np.concatenate([p[1] for p in parts], axis=1),
            np.concatenate([p[2] for p in parts], axis=1),
            [p[3] for p in parts],
            n * len(self.segments) if self.initial == "diffuse" else 0,
        )

    def _segment(self, A_d, B_d, C, D, Q, R, P0, u: np.ndarray, y: np.ndarray) -> tuple:
        """−ln L, innovations, variances and initial state (see the module docstring)."""
        S, n = C.shape
        seen = np.isfinite(y)
        X0 = np.zeros((S, n, 1 + n))
        X0[:, :, 0] = y[seen][0]  # the prior mean: every node at the first measurement
        X0[:, :, 1:] = np.eye(n)
        forcing = np.swapaxes(u @ np.swapaxes(B_d, 1, 2), 0, 1)
        run = filter_batch(A_d, forcing, C, y[:, None] - u @ D.T, Q, R, X0, P0)
        e0, F = run.innovations[:, seen, 0], run.innovations[:, seen, 1:]
        weight = 1.0 / run.variances[:, seen]
        weighted_T = np.swapaxes(F * weight[:, :, None], 1, 2)
        M = weighted_T @ F
        M += _RIDGE * np.trace(M, axis1=1, axis2=2)[:, None, None] * np.eye(n)
        r = weighted_T @ e0[:, :, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            beta = -np.linalg.solve(M, r)[..., 0]
            e = e0 + (F @ beta[..., None])[..., 0]
            nll = 0.5 * np.sum(np.log(2 * np.pi / weight) + e * e * weight, axis=1)
            if self.initial == "diffuse":
                nll += 0.5 * np.linalg.slogdet(M)[1]
        return nll, e, run.variances[:, seen], X0[:, :, 0] + beta


def derivatives(
    objective: LikelihoodObjective, xi: np.ndarray, step: float = GRADIENT_STEP
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """−ln L (m,), its gradient (m, q) by central differences and the Fisher-scoring Hessian
    (m, q, q) at the points ξ (m, q), all m stencils of 2q + 1 sets in one batched filter."""
    m, q = xi.shape
    shifts = step * np.eye(q)
    stencil = np.concatenate([xi[:, None], xi[:, None] + shifts, xi[:, None] - shifts], axis=1)
    ev = objective(objective.space.from_search(stencil.reshape(-1, q)))
    nll = ev.nll.reshape(m, 2 * q + 1)
    e = ev.innovations.reshape(m, 2 * q + 1, -1)
    log_s = np.log(ev.variances.reshape(m, 2 * q + 1, -1))
    plus, minus = slice(1, q + 1), slice(q + 1, None)
    gradient = (nll[:, plus] - nll[:, minus]) / (2 * step)
    d_e = (e[:, plus] - e[:, minus]) / (2 * step)
    d_log_s = (log_s[:, plus] - log_s[:, minus]) / (2 * step)
    # A perturbed set that is invalid leaves its coordinate out of this step.
    ok = np.isfinite(gradient) & np.isfinite(d_e).all(axis=2) & np.isfinite(d_log_s).all(axis=2)
    d_e[~ok], d_log_s[~ok] = 0.0, 0.0
    fisher = (d_e * np.exp(-log_s[:, :1])) @ np.swapaxes(d_e, 1, 2)
    fisher += 0.5 * d_log_s @ np.swapaxes(d_log_s, 1, 2)
    fisher[:, np.arange(q), np.arange(q)] += ~ok
    valid = np.isfinite(nll[:, 0])
    fisher[~valid] = np.eye(q)
    return np.where(valid, nll[:, 0], np.inf), np.where(ok & valid[:, None], gradient, 0.0), fisher


def trust_steps(hessian: np.ndarray, gradient: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Per start, the d minimising gᵀd + ½ dᵀHd within |d| ≤ radius for a positive semi-definite
    H (m, q, q): d = −(H + μI)⁻¹ g with the smallest μ ≥ 0 that keeps |d| ≤ radius. μ by Newton's
    method on 1/|d(μ)| = 1/radius in the eigenbasis of H, which rises monotonically to the root
    from any μ with |d(μ)| > radius (Moré & Sorensen 1983)."""
    curvature, basis = np.linalg.eigh(hessian)
    # A flat direction keeps a tiny curvature: its step is then long, and μ takes it in (|g|/Δ
    # sets the scale when H is all flat).
    scale = np.maximum(np.abs(curvature).max(axis=1), np.linalg.norm(gradient, axis=1) / radius)
    curvature = np.maximum(curvature, 1e-12 * scale[:, None])
    g = (np.swapaxes(basis, 1, 2) @ gradient[..., None])[..., 0]
    mu = np.zeros(len(g))
    for _ in range(_SECULAR_STEPS):
        inverse = 1.0 / (curvature + mu[:, None])
        squared = np.sum((g * inverse) ** 2, axis=1)
        slope = np.sum(g**2 * inverse**3, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            rise = (np.sqrt(squared) / radius - 1.0) * squared / slope
        # The Newton step already within the region: μ stays 0.
        mu = np.maximum(mu + np.where(slope > 0, rise, 0.0), 0.0)
    return -(basis @ (g / (curvature + mu[:, None]))[..., None])[..., 0]


@dataclass
class LocalSearch:
    """One trust-region search: the point ξ, −ln L there with its gradient and Fisher matrix,
    the trust radius (in ξ), −ln L after each accepted step, the iterations (accepted or not)
    and why it stopped (None while it runs)."""

    xi: np.ndarray
    nll: float
    gradient: np.ndarray
    hessian: np.ndarray
    radius: float = _INITIAL_RADIUS
    history: list[float] = field(default_factory=list)
    iterations: int = 0
    message: str | None = None

    def __post_init__(self) -> None:
        self.history = [self.nll]

    def advance(
        self, step: np.ndarray, nll: float, gradient: np.ndarray, hessian: np.ndarray
    ) -> None:
        """Take or refuse the trial point ξ + step by the ratio of the actual decrease to the
        model's, and resize the trust region (Nocedal & Wright 2006, Algorithm 4.1)."""
        self.iterations += 1
        promised = -(self.gradient @ step + 0.5 * step @ self.hessian @ step)
        ratio = (self.nll - nll) / promised if promised > 0 else -np.inf
        if ratio < 0.25:
            self.radius *= 0.25
        elif ratio > 0.75 and np.linalg.norm(step) > 0.99 * self.radius:
            self.radius = min(2.0 * self.radius, _MAX_RADIUS)
        if ratio > _ACCEPT:
            self.xi = self.xi + step
            self.nll, self.gradient, self.hessian = nll, gradient, hessian
            self.history.append(nll)

    def check(self, settings: LikelihoodSettings) -> None:
        """Stop when |∇| < gtol, when −ln L fell by less than ftol over the last ``_PATIENCE``
        accepted steps, when the quadratic model promises less than ftol (Newton decrement),
        or after ``max_iter`` iterations."""
        history = self.history
        if not np.isfinite(self.nll):
            self.message = "no finite likelihood at the start"
        elif np.linalg.norm(self.gradient) < settings.gtol:
            self.message = "gradient below gtol"
        elif len(history) > _PATIENCE and history[-1 - _PATIENCE] - history[-1] < settings.ftol:
            self.message = f"−ln L fell by less than ftol over {_PATIENCE} steps"
        elif self.decrement() < settings.ftol:
            self.message = "the quadratic model promises less than ftol"
        elif self.iterations >= settings.max_iter:
            self.message = "max_iter reached"
        elif self.radius < _MIN_RADIUS:
            self.message = "trust region collapsed"

    def decrement(self) -> float:
        """½ gᵀH⁺g: the decrease the quadratic model still promises."""
        return 0.5 * self.gradient @ np.linalg.lstsq(self.hessian, self.gradient, rcond=1e-12)[0]


def local_searches(
    objective: LikelihoodObjective, xi0: np.ndarray, settings: LikelihoodSettings
) -> list[LocalSearch]:
    """Trust-region Fisher scoring over ξ from every start (m, q) in lockstep: each iteration
    filters the stencils of all running searches' trial points in one batch."""
    searches = [LocalSearch(*at) for at in zip(xi0, *derivatives(objective, xi0), strict=True)]
    for search in searches:
        search.check(settings)
    while running := [s for s in searches if s.message is None]:
        steps = trust_steps(
            np.array([s.hessian for s in running]),
            np.array([s.gradient for s in running]),
            np.array([s.radius for s in running]),
        )
        trial = derivatives(objective, np.array([s.xi for s in running]) + steps)
        for search, step, *at in zip(running, steps, *trial, strict=True):
            search.advance(step, *at)
            search.check(settings)
    return searches


def observed_information(
    objective: LikelihoodObjective, z: np.ndarray, step: float = HESSIAN_STEP
) -> np.ndarray:
    """Hessian of −ln L at z by central second differences, every stencil point in one batch."""
    q = z.size
    h = step * np.eye(q)
    i, j = np.triu_indices(q, 1)
    points = np.vstack(
        [z, z + h, z - h, z + h[i] + h[j], z + h[i] - h[j], z - h[i] + h[j], z - h[i] - h[j]]
    )
    f = objective(points).nll
    f0, plus, minus = f[0], f[1 : q + 1], f[q + 1 : 2 * q + 1]
    pp, pm, mp, mm = f[2 * q + 1 :].reshape(4, -1)
    hessian = np.diag((plus - 2 * f0 + minus) / step**2)
    hessian[i, j] = hessian[j, i] = (pp - pm - mp + mm) / (4 * step**2)
    return hessian


@dataclass(frozen=True)
class Uncertainty:
    """Estimates with standard errors from the observed information (Wald, asymptotic).

    names; estimates (value units); std_errors: by the delta method (inf where the data do not
    determine the parameter); coordinate_std_errors: in z (ln θ: relative); correlation (q, q);
    non_identifiable: parameters whose 95 % interval spans more than ``IDENTIFIABLE_SPAN``
    (logarithmic coordinates) or more than the bounds (linear ones), or that load on a flat
    direction of the Hessian.
    """

    names: list[str]
    estimates: np.ndarray
    std_errors: np.ndarray
    coordinate_std_errors: np.ndarray
    correlation: np.ndarray
    non_identifiable: list[str]

    @property
    def t_statistics(self) -> np.ndarray:
        """estimate / standard error: |t| < 2 means the data cannot tell the value from 0."""
        return self.estimates / self.std_errors

    def to_dict(self) -> dict:
        """Plain numbers (an undetermined standard error is inf; ``io.jsonable`` writes None)."""
        return {
            "parameters": {
                name: {"estimate": float(v), "std_error": float(se), "t": float(t)}
                for name, v, se, t in zip(
                    self.names, self.estimates, self.std_errors, self.t_statistics, strict=True
                )
            },
            "correlation": np.round(self.correlation, 4).tolist(),
            "non_identifiable": list(self.non_identifiable),
        }


def wald(hessian: np.ndarray, held: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covariance (q, q), standard errors (q,) and loading on flat directions (q,) from the
    Hessian of −ln L with the coordinates ``held`` fixed at their estimates (zero covariance).
    A coordinate loading more than 0.1 on a direction of (near-)zero curvature gets an infinite
    error."""
    free = ~held
    sub = hessian[np.ix_(free, free)]
    eigval, eigvec = np.linalg.eigh(0.5 * (sub + sub.T))
    determined = eigval > 1e-10 * max(float(eigval.max(initial=0.0)), 0.0)
    covariance = np.zeros_like(hessian)
    kept = eigvec[:, determined]
    covariance[np.ix_(free, free)] = (kept / eigval[determined]) @ kept.T
    loading = np.zeros(len(hessian))
    loading[free] = np.abs(eigvec[:, ~determined]).max(axis=1, initial=0.0)
    se = np.where(loading > 0.1, np.inf, np.sqrt(np.maximum(np.diag(covariance), 0.0)))
    return covariance, se, loading


def uncertainty(space: LikelihoodSpace, z: np.ndarray, hessian: np.ndarray) -> Uncertainty:
    """Standard errors and correlations from the Hessian of −ln L in z (its inverse is the
    asymptotic covariance); directions of (near-)zero curvature get infinite errors.

    A parameter whose 95 % interval is wider than its whole range (``LikelihoodSpace.widths``)
    carries no information: it is held at its estimate, the widest first, and the others' errors
    are computed again, as the pseudo-inverse does for a flat direction. Otherwise its trade-off
    with a determined parameter (e.g. a sensor noise heading to 0 against the air's process
    noise) widens that one's interval by an amount that depends on where along the flat valley
    the search stopped. A held parameter keeps the error it had when held; the correlations are
    those of the full covariance."""
    covariance, se_z, loading = wald(hessian, np.zeros(len(hessian), dtype=bool))
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = covariance / np.outer(se_z, se_z)
    # Directions of zero curvature are left out of the inverse already: hold their parameters.
    held, errors, se = loading > 0.1, se_z.copy(), se_z
    while True:
        excess = np.where(held, 0.0, 2 * Z_95 * se / space.widths)
        if excess.max(initial=0.0) <= 1.0:
            break
        held[np.argmax(excess)] = True
        _, se, _ = wald(hessian, held)
        errors[~held] = se[~held]
    width = 2 * Z_95 * errors
    wide = np.where(space.logarithmic, width > np.log(IDENTIFIABLE_SPAN), width > 1.0)
    return Uncertainty(
        names=list(space.names),
        estimates=space.values(z)[0],
        std_errors=errors * np.abs(space.value_scale(z)),
        coordinate_std_errors=errors,
        correlation=np.where(np.isfinite(correlation), correlation, np.nan),
        non_identifiable=[n for n, w in zip(space.names, wide | held, strict=True) if w],
    )


@dataclass(frozen=True)
class LikelihoodFit:
    """The maximum-likelihood fit: z, −ln L, the measured rows N, the number of estimated values
    (including the initial states when ``initial="estimated"``), the noise model, the initial
    states per segment [°C], uncertainty, residual checks of the innovations, and one record per
    local search, and the parameter sets filtered in all."""

    z: np.ndarray
    nll: float
    n_obs: int
    n_params: int
    initial: str
    noise: Noise
    initial_states: list[np.ndarray]
    uncertainty: Uncertainty
    residuals: ResidualChecks
    starts: list[dict]
    evaluations: int

    @property
    def aic(self) -> float:
        return 2.0 * self.nll + 2.0 * self.n_params

    @property
    def bic(self) -> float:
        return 2.0 * self.nll + self.n_params * np.log(self.n_obs)

    def to_dict(self) -> dict:
        return {
            "neg_log_likelihood": self.nll,
            "n_obs": self.n_obs,
            "n_params": self.n_params,
            "aic": self.aic,
            "bic": self.bic,
            "initial": self.initial,
            "uncertainty": self.uncertainty.to_dict(),
            "residuals": self.residuals.to_dict(),
            "starts": self.starts,
        }


def fit_likelihood(
    objective: LikelihoodObjective,
    settings: LikelihoodSettings,
    rng: np.random.Generator,
    seeds: np.ndarray | None = None,
) -> LikelihoodFit:
    """Screen, search locally from the best distinct starts, summarise the best optimum.

    ``seeds``: unit-cube points (model bounds, then noise ranges) put in the screen."""
    space = objective.space
    screen = ga.minimize(
        lambda unit: objective(space.from_unit(unit)).concentrated_nll(),
        space.dim,
        settings.screen,
        rng,
        seeds,
    )
    good = screen.archive[np.isfinite(screen.archive_costs)]
    if not good.size:
        raise ModelError("no parameter set of the screen gives a finite likelihood")
    starts = space.from_unit(good)
    # The screen scored every point at its best overall noise level: start there.
    starts[:, space.space.dim :] += 0.5 * np.log(objective(starts).noise_scale())[:, None]
    runs = local_searches(objective, space.to_search(starts), settings)
    best = min(runs, key=lambda r: r.nll)
    records = [
        {"nll": float(r.nll), "iterations": r.iterations, "message": r.message} for r in runs
    ]
    return summarise(objective, space.from_search(best.xi), records)


def summarise(objective: LikelihoodObjective, z: np.ndarray, starts: list[dict]) -> LikelihoodFit:
    """Noise model, uncertainty and residual checks at the optimum z."""
    space = objective.space
    ev = objective(z[None])
    _, process_std, measurement_std = space.split(z)
    standardised = ev.innovations[0] / np.sqrt(ev.variances[0])
    estimated_states = len(space.state_names) * len(objective.segments)
    return LikelihoodFit(
        z=z,
        nll=float(ev.nll[0]),
        n_obs=objective.n_obs,
        n_params=space.dim + (estimated_states if objective.initial == "estimated" else 0),
        initial=objective.initial,
        noise=Noise(tuple(process_std[0].tolist()), float(measurement_std[0])),
        initial_states=[x0[0] for x0 in ev.initial_states],
        uncertainty=uncertainty(space, z, observed_information(objective, z)),
        residuals=residual_checks(standardised, lags=round(86400.0 / objective.step_s)),
        starts=starts,
        evaluations=objective.n_evaluations,
    )


@dataclass(frozen=True)
class LikelihoodRatioTest:
    """statistic 2(ln L_full − ln L_restricted), df, p_value: small when the restricted model
    is rejected (Wilks 1938: the statistic is χ²(df) under the restricted model)."""

    statistic: float
    df: int
    p_value: float

    def rejects(self, level: float = 0.05) -> bool:
        return self.p_value < level


def likelihood_ratio_test(
    restricted: LikelihoodFit | float, full: LikelihoodFit | float, df: int | None = None
) -> LikelihoodRatioTest:
    """Test a model against a larger one that contains it (e.g. 2R2C against 3R3C, or a model
    without an effect against the model with it), from two fits or two values of −ln L.

    ``df``: the number of parameters the full model adds; by default the difference of the fits'
    ``n_params``. Both fits must use the same data and the same ``initial``; with ``"diffuse"``
    the two models should have the same states (the diffuse part differs otherwise), or use
    ``"estimated"``, whose ``n_params`` counts the initial states."""
    if df is None:
        if not (isinstance(restricted, LikelihoodFit) and isinstance(full, LikelihoodFit)):
            raise ValueError("give df when comparing two values of −ln L")
        df = full.n_params - restricted.n_params
    if df < 1:
        raise ValueError(f"the full model must have more parameters (df = {df})")
    nll_r = restricted.nll if isinstance(restricted, LikelihoodFit) else float(restricted)
    nll_f = full.nll if isinstance(full, LikelihoodFit) else float(full)
    statistic = max(2.0 * (nll_r - nll_f), 0.0)
    return LikelihoodRatioTest(statistic, int(df), float(chi2.sf(statistic, df)))
