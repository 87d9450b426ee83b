"""Cheap screening of candidates before any refit.

An input-type candidate adds heat ``θ · s(t)`` at a node. Passed through the fitted model's own
dynamics (the output's response to s at that node, y_s), it can only explain the part of the
training residual that lies along y_s: the non-negative least-squares fit r ≈ Σ θ_j y_j and the
share of the residual's energy it removes rank the candidates. A structural candidate (new node,
re-routed input) changes the dynamics themselves, so it is screened by a short local refit started
from the current parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from rcengine.dataset import Dataset
from rcengine.diagnose.candidates import Extension
from rcengine.diagnose.fitting import Fit, Split
from rcengine.diagnose.response import node_responses
from rcengine.estimation import Estimator, EstimatorSettings
from rcengine.estimation.ga import GASettings
from rcengine.estimation.pattern_search import GPSSettings
from rcengine.parallel import run_jobs

LOCAL_REFIT = EstimatorSettings(
    GASettings(population=16, generations=4, lhs=True),
    GPSSettings(max_iter=15, tol=1e-3, initial_step=0.05, expand=2.0),
    polish=True,
    polish_starts=2,
)


@dataclass(frozen=True)
class Screen:
    """explained: share of the training residual energy the candidate removes [0–1];
    response: its fitted contribution to the output on the training period [K]."""

    effect: str
    explained: float
    method: str
    coefficients: dict[str, float]
    response: np.ndarray


def screen(ext: Extension, base: Fit, split: Split, random_state: int) -> Screen:
    if ext.structural:
        return _local_refit(ext, base, split, random_state)
    return _projection(ext, base, split.train)


@dataclass(frozen=True)
class ScreenJob:
    """One ``screen`` call, so that a round's structural screens (each a short refit) can go to
    worker processes."""

    ext: Extension
    base: Fit
    split: Split
    random_state: int

    def run(self) -> Screen:
        return screen(self.ext, self.base, self.split, self.random_state)


def screen_all(
    extensions: list[Extension],
    base: Fit,
    splits: dict[str, Split],
    random_state: int,
    workers: int,
) -> dict[str, Screen]:
    """Every extension screened (by effect); the structural ones' refits on up to ``workers``
    processes, the projections, a least squares each, in this one."""
    jobs = {e.effect: ScreenJob(e, base, splits[e.effect], random_state) for e in extensions}
    refitted = [e.effect for e in extensions if e.structural]
    screens = dict(zip(refitted, run_jobs([jobs[e] for e in refitted], workers), strict=True))
    return {e.effect: screens.get(e.effect) or jobs[e.effect].run() for e in extensions}


def _projection(ext: Extension, base: Fit, train: Dataset) -> Screen:
    measured = _filled(train.measured)
    columns = []
    for signal, node in ext.inputs:
        heat = train.frame[signal].to_numpy(dtype=float)
        if signal in ext.network.temperatures:
            # A resistor to a new boundary adds (T_b − T_node)/R; near the fitted model the node
            # sits close to the measured indoor temperature.
            heat = heat - measured
        columns.append(node_responses(base.network, base.params, train, node, heat)[:, 0])
    mask = np.isfinite(base.residual_train)
    Y = np.column_stack(columns)
    r = base.residual_train
    theta, _ = nnls(Y[mask], r[mask])
    response = Y @ theta
    explained = 1.0 - np.sum((r[mask] - response[mask]) ** 2) / max(np.sum(r[mask] ** 2), 1e-12)
    coefficients = dict(zip(ext.new_parameters, theta.tolist(), strict=False))
    return Screen(ext.effect, float(explained), "projection", coefficients, response)


def _local_refit(ext: Extension, base: Fit, split: Split, random_state: int) -> Screen:
    est = Estimator(
        ext.network,
        preset=LOCAL_REFIT,
        random_state=random_state,
        warm_start=[{**base.params, **ext.neutral}, dict(base.params)],
        warn_bounds=False,
    ).fit(split.train)
    y = split.train.measured
    resid = y - est.trajectory_.y
    mask = np.isfinite(resid) & np.isfinite(base.residual_train)
    explained = 1.0 - np.sum(resid[mask] ** 2) / max(np.sum(base.residual_train[mask] ** 2), 1e-12)
    coefficients = {p: est.params_[p] for p in ext.new_parameters}
    response = est.trajectory_.y - base.simulated_train
    return Screen(ext.effect, float(explained), "local refit", coefficients, response)


def _filled(values: np.ndarray) -> np.ndarray:
    """NaN gaps linearly interpolated (ends held)."""
    idx = np.arange(values.size)
    ok = np.isfinite(values)
    return np.interp(idx, idx[ok], values[ok]) if ok.any() else np.zeros_like(values)
