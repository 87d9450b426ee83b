"""Parameter estimation: genetic algorithm, then generalized pattern search, optional
least-squares polish — every population evaluated in one batched simulation.

The procedure of thesis §2.3.3/§2.4.2 (ModestPy: GA to find the basin, GPS to refine it), with
the unmeasured initial states profiled out exactly (:mod:`rcengine.estimation.objective`).
``criterion="likelihood"`` instead fits a stochastic model by maximum likelihood on the Kalman
filter's innovations (:mod:`rcengine.estimation.likelihood`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import KW_ONLY, dataclass, replace

import numpy as np
import scipy.optimize

from rcengine.dataset import Dataset
from rcengine.estimation import ga, pattern_search
from rcengine.estimation.ga import GASettings
from rcengine.estimation.likelihood import (
    LikelihoodFit,
    LikelihoodObjective,
    LikelihoodSpace,
    fit_likelihood,
)
from rcengine.estimation.objective import Objective, Trajectory
from rcengine.estimation.pattern_search import GPSSettings
from rcengine.estimation.presets import EstimatorSettings, settings_for
from rcengine.estimation.search_space import SearchSpace
from rcengine.exceptions import (
    ConvergenceWarning,
    DataValidationError,
    ModelError,
    NotFittedError,
    Problem,
)
from rcengine.kalman import Noise
from rcengine.metrics import rmse
from rcengine.network import CompiledNetwork, RCNetwork
from rcengine.parallel import one_blas_thread

# "output_error": least squares on the open-loop simulation (deterministic model);
# "likelihood": maximum likelihood of the stochastic model on the one-step innovations.
CRITERIA = ("output_error", "likelihood")


def check_criterion(criterion: str) -> str:
    """``criterion`` if it is one of :data:`CRITERIA`.

    Raises
    ------
    ModelError : naming the choices.
    """
    if criterion not in CRITERIA:
        raise ModelError(f"invalid criterion {criterion!r}; choose from {list(CRITERIA)}")
    return criterion


@dataclass(frozen=True)
class Identifiability:
    """singular_ratios: σ_k/σ_max of the relative-sensitivity Jacobian (keyed by the free parameter
    names only for reading; the directions are combinations); flat_directions: exponents w such
    that scaling each θ_j by exp(t·w_j) leaves the output unchanged."""

    singular_ratios: dict[str, float]
    flat_directions: list[dict[str, float]]

    @property
    def identifiable(self) -> bool:
        return not self.flat_directions


# Relative tolerances of the least-squares polish: far below any physical significance of the
# parameters, well above the round-off of the exact simulation.
POLISH_TOL = 1e-5


def _check_enough_measured(data: Dataset, n_params: int, n_states: int) -> None:
    """More measured t_in than unknowns (the parameters and each segment's initial
    temperatures): fitted on two rows, 8 parameters reproduced them exactly and the fit
    "passed" ASHRAE Guideline 14."""
    measured = int(np.isfinite(data.measured).sum())
    unknowns = n_params + n_states * len(data.segments)
    if measured <= unknowns:
        raise DataValidationError(
            [
                Problem(
                    None,
                    "t_in",
                    f"{measured} measured value(s) cannot calibrate {unknowns} unknowns "
                    f"({n_params} parameters, {n_states} initial temperatures per segment × "
                    f"{len(data.segments)} segment(s)); give a longer record",
                )
            ]
        )


def search(
    cost: Callable[[np.ndarray], np.ndarray],
    dim: int,
    settings: EstimatorSettings,
    rng: np.random.Generator,
    seeds: np.ndarray | None = None,
) -> tuple[ga.GAResult, pattern_search.GPSResult]:
    """GA over the unit cube (``seeds`` in its first generation), then GPS from its best
    individual (thesis §2.3.3)."""
    ga_result = ga.minimize(cost, dim, settings.ga, rng, seeds)
    gps_result = pattern_search.minimize(cost, ga_result.x, ga_result.cost, settings.gps)
    return ga_result, gps_result


# The settings are kept as given (no equality or repr of its own: an estimator is a thing that
# is fitted, not a value).
@dataclass(eq=False, repr=False)
class Estimator:
    """Calibrate an RC network's parameters on measured data.

    Parameters
    ----------
    network : the model (an ``RCNetwork`` or its compiled form).
    preset : "default", "thesis", "modestpy" or "study" (``presets.PRESETS``), or an
        ``EstimatorSettings``.
    ga, gps : override the preset's GA / GPS settings.
    cost : "mse" (thesis Eq. 9) or "nmse" (Eq. 10).
    known : parameters held fixed at these values.
    bounds : bounds overriding the model's defaults, ``{name: (lower, upper)}``.
    polish : after GPS, run ``scipy.optimize.least_squares`` (trust-region reflective) from the
        GPS optimum (and other GA basins, see ``EstimatorSettings``) and keep it if it lowers the
        cost; ``polish_`` reports whether it beat GPS. None: the preset decides.
    random_state : seed or Generator; the same seed gives the same result.
    warm_start : parameter sets (dicts, possibly partial) seeded into the GA's first generation;
        missing parameters start mid-range. Used to extend a fitted model without losing it.
    criterion : "output_error" (default) or "likelihood": process noise per state and sensor
        noise estimated with the parameters, by maximum likelihood (``preset.likelihood``
        settings; ``ga``, ``gps`` and ``polish`` do not apply; ``cost_`` is −ln L).
    initial : for "likelihood", the initial state "diffuse" (default) or "estimated".
    warn_bounds : warn (``ConvergenceWarning``) when a parameter ends on a bound; False for a
        caller that reads ``at_bounds_`` and reports it itself (a warning silenced around the call
        instead would not stay silenced: ``warnings.catch_warnings`` is process-wide state, and
        another thread leaving it restores the filters under a fit still running).

    Attributes (after ``fit``)
    --------------------------
    params_ : dict of every parameter value (SI units of each parameter).
    cost_ : final cost; rmse_ : training RMSE [K]; trajectory_ : simulated training output.
    initial_states_ : estimated node temperatures at the start of each segment [°C].
    n_simulations_ : parameter sets simulated; wall_time_s_ : fit duration [s].
    at_bounds_ : free parameters that ended on a bound.
    ga_, gps_ : optimiser results (of the best restart); polish_ : dict or None;
    restart_costs_ : the final cost of each independent search (``EstimatorSettings.restarts``).
    noise_ : the fitted ``Noise`` ("likelihood"; None otherwise); likelihood_ : ``LikelihoodFit``
        with standard errors, correlations and residual checks, or None.
    """

    network: RCNetwork | CompiledNetwork
    _: KW_ONLY
    preset: str | EstimatorSettings = "default"
    ga: GASettings | None = None
    gps: GPSSettings | None = None
    cost: str = "mse"
    known: Mapping[str, float] | None = None
    bounds: Mapping[str, tuple[float, float]] | None = None
    polish: bool | None = None
    random_state: int | np.random.Generator | None = None
    warm_start: list[Mapping[str, float]] | None = None
    criterion: str = "output_error"
    initial: str = "diffuse"
    warn_bounds: bool = True

    @property
    def compiled(self) -> CompiledNetwork:
        net = self.network
        return net.compile() if isinstance(net, RCNetwork) else net

    def _settings(self) -> EstimatorSettings:
        s = settings_for(self.preset)
        polish = s.polish if self.polish is None else self.polish
        return replace(s, ga=self.ga or s.ga, gps=self.gps or s.gps, polish=polish)

    def fit(self, data: Dataset) -> Estimator:
        """Estimate the parameters on ``data`` (every segment, measured ``t_in``); returns self."""
        started = time.perf_counter()
        check_criterion(self.criterion)
        settings = self._settings()
        network = self.compiled
        space = SearchSpace(network, self.known, self.bounds)
        _check_enough_measured(data, space.dim, network.n_states)
        objective = Objective(network, data, self.cost)
        rng = np.random.default_rng(self.random_state)
        self.ga_ = self.gps_ = self.polish_ = self.likelihood_ = self.noise_ = None
        self.restart_costs_: list[float] = []
        if self.criterion == "likelihood":
            theta, best = self._fit_likelihood(network, data, space, settings, rng)
        else:
            theta, best = self._fit_output_error(objective, space, settings, rng)
        self.space_ = space
        self.objective_ = objective
        self.params_ = space.as_dict(theta)
        self.cost_ = best
        self.trajectory_: Trajectory = objective.trajectory(theta)
        self.initial_states_ = self.trajectory_.initial_states
        if self.likelihood_ is not None:
            self.initial_states_ = self.likelihood_.initial_states
        self.rmse_ = rmse(data.measured, self.trajectory_.y)
        self.at_bounds_ = space.at_bounds(space.to_unit(theta[None])[0])
        self.n_simulations_ = objective.n_evaluations + (
            self.likelihood_.evaluations if self.likelihood_ else 0
        )
        self.wall_time_s_ = time.perf_counter() - started
        if self.at_bounds_ and self.warn_bounds:
            warnings.warn(
                f"{network.name}: parameter(s) {self.at_bounds_} ended on a bound; "
                "widen the bounds or question the model structure",
                ConvergenceWarning,
                stacklevel=2,
            )
        return self

    def _fit_output_error(
        self,
        objective: Objective,
        space: SearchSpace,
        settings: EstimatorSettings,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, float]:
        """GA, GPS and the optional polish on the output error; returns θ (p,) and the cost."""

        def cost(unit: np.ndarray) -> np.ndarray:
            return objective(space.to_physical(unit))

        if space.dim == 0:
            return space.to_physical(np.zeros(0))[0], float(cost(np.zeros((1, 0)))[0])
        seeds = space.seeds(self.warm_start or [])
        # The first search draws from ``rng`` alone, as a single search would: more restarts can
        # only lower the cost.
        streams = [rng]
        winner: tuple = ()
        for k in range(max(1, settings.restarts)):
            if k == 1:
                streams += rng.spawn(settings.restarts - 1)
            self.polish_ = None
            ga_result, gps_result = search(cost, space.dim, settings, streams[k], seeds)
            x, best = gps_result.x, gps_result.cost
            if settings.polish:
                starts = [x, *ga_result.archive[1 : settings.polish_starts]]
                x, best = self._polish(objective, space, starts, best)
            self.restart_costs_.append(best)
            if not winner or best < winner[1]:
                winner = (x, best, ga_result, gps_result, self.polish_)
        x, best, self.ga_, self.gps_, self.polish_ = winner
        return space.to_physical(x)[0], best

    def _fit_likelihood(
        self,
        network: CompiledNetwork,
        data: Dataset,
        space: SearchSpace,
        settings: EstimatorSettings,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, float]:
        """Maximum likelihood; sets ``likelihood_`` and ``noise_``; returns θ (p,) and −ln L."""
        likelihood_space = LikelihoodSpace(space, network.state_names)
        objective = LikelihoodObjective(network, data, likelihood_space, self.initial)
        seeds = space.seeds(self.warm_start or [])
        # Warm starts fix the physical parameters; their noise starts mid-range.
        seeds = np.hstack([seeds, np.full((len(seeds), network.n_states + 1), 0.5)])
        # Thousands of tiny batched products: one BLAS thread is several times faster.
        with one_blas_thread():
            fit: LikelihoodFit = fit_likelihood(objective, settings.likelihood, rng, seeds)
        self.likelihood_ = fit
        self.noise_: Noise | None = fit.noise
        return likelihood_space.split(fit.z)[0][0], fit.nll

    def _polish(
        self, objective: Objective, space: SearchSpace, starts: list[np.ndarray], best: float
    ) -> tuple[np.ndarray, float]:
        """Trust-region least squares from each start; the best result wins if it beats GPS."""
        h = 1e-6

        last: dict[bytes, np.ndarray] = {}

        def residuals(unit: np.ndarray) -> np.ndarray:
            res = np.nan_to_num(objective.residuals(space.to_physical(unit))[0], nan=1e3)
            last.clear()
            last[unit.tobytes()] = res
            return res

        def jacobian(unit: np.ndarray) -> np.ndarray:
            # All p forward differences in one batched simulation; the base point is the one
            # least_squares has just evaluated.
            steps = np.where(unit + h <= 1.0, h, -h)
            base = last.get(unit.tobytes())
            if base is None:
                base = residuals(unit)
            res = objective.residuals(space.to_physical(unit + np.diag(steps)))
            return ((np.nan_to_num(res, nan=1e3) - base) / steps[:, None]).T

        gps_x, gps_cost = starts[0], best
        x, after = gps_x, np.inf
        for start in starts:
            try:
                sol = scipy.optimize.least_squares(
                    residuals,
                    start,
                    jac=jacobian,
                    bounds=(0.0, 1.0),
                    method="trf",
                    ftol=POLISH_TOL,
                    xtol=POLISH_TOL,
                    gtol=POLISH_TOL,
                )
            except (np.linalg.LinAlgError, ValueError):
                continue
            candidate = np.clip(sol.x, 0.0, 1.0)
            cost = float(objective(space.to_physical(candidate))[0])
            if cost < after:
                x, after = candidate, cost
        improved = after < gps_cost
        self.polish_ = {"cost_gps": gps_cost, "cost_polished": after, "improved": bool(improved)}
        return (x, after) if improved else (gps_x, gps_cost)

    def identifiability(self, rel_step: float = 1e-5, threshold: float = 1e-4) -> Identifiability:
        """Which parameter combinations the data pin down, from the residual Jacobian.

        Columns are ∂r/∂ln θ_j (relative sensitivities, one batched simulation). A right singular
        vector v with σ/σ_max below ``threshold`` is a direction along which the output does not
        change: scaling the parameters by exp(t·v) leaves the fit intact, so only the products
        Π θ_j^{w_j} orthogonal to v are identifiable.
        """
        self._check_fitted()
        space, objective = self.space_, self.objective_
        theta = np.array([self.params_[p] for p in space.network.param_names])
        free = [space.network.param_names.index(p) for p in space.free]
        points = np.tile(theta, (len(free) + 1, 1))
        for row, j in enumerate(free, start=1):
            points[row, j] *= 1.0 + rel_step
        res = objective.residuals(points)
        jac = (res[1:] - res[0]) / np.log1p(rel_step)
        _, sv, vt = np.linalg.svd(jac.T, full_matrices=False)
        ratio = sv / sv[0] if sv[0] > 0 else np.zeros_like(sv)
        flat = [
            {name: float(c) for name, c in zip(space.free, v, strict=True) if abs(c) > 1e-3}
            for v, r in zip(vt, ratio, strict=True)
            if r < threshold
        ]
        return Identifiability(dict(zip(space.free, ratio.tolist(), strict=False)), flat)

    def _check_fitted(self) -> None:
        if not hasattr(self, "params_"):
            raise NotFittedError("call fit() before using the estimator")

    def simulate(self, data: Dataset) -> Trajectory:
        """Fitted model over ``data`` with initial states estimated from its measurements."""
        self._check_fitted()
        return Objective(self.compiled, data, self.cost).trajectory(self.params_)
