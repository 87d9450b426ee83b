"""Generalized pattern search (compass search with step halving) on the unit cube.

Each iteration polls x ± step·e_i for every coordinate i — all 2p points in one batched cost
evaluation — plus the Hooke–Jeeves pattern point x + (x − x_previous) after a success. The best
improving point is taken; without improvement the step is halved. Stops when the step falls
below ``tol`` or after ``max_iter`` iterations (Torczon 1997; ModestPy's PS is the opportunistic,
one-at-a-time variant of the same search).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

BatchCost = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class GPSSettings:
    """max_iter: iterations (polls) at most; tol: smallest step (unit cube); initial_step: first
    step (unit cube); expand: step multiplier after a success (1 keeps it)."""

    max_iter: int = 500
    tol: float = 1e-6
    initial_step: float = 0.05
    expand: float = 1.0


@dataclass(frozen=True)
class GPSResult:
    x: np.ndarray
    cost: float
    iterations: int
    evaluations: int
    final_step: float
    history: list[float]


def minimize(cost: BatchCost, x0: np.ndarray, cost0: float, settings: GPSSettings) -> GPSResult:
    """Minimise ``cost`` from ``x0`` (whose cost is ``cost0``) inside [0, 1]^p."""
    x = np.asarray(x0, dtype=float).copy()
    best = float(cost0)
    p = x.size
    directions = np.concatenate([np.eye(p), -np.eye(p)])
    step = settings.initial_step
    previous: np.ndarray | None = None
    evaluations = 0
    history = [best]
    iteration = 0
    while iteration < settings.max_iter and step >= settings.tol:
        iteration += 1
        polls = np.clip(x + step * directions, 0.0, 1.0)
        if previous is not None:
            polls = np.vstack([polls, np.clip(2 * x - previous, 0.0, 1.0)])
        costs = cost(polls)
        evaluations += len(polls)
        i = int(np.argmin(costs))
        if costs[i] < best:
            previous, x, best = x, polls[i].copy(), float(costs[i])
            step = min(1.0, step * settings.expand)
        else:
            previous = None
            step *= 0.5
        history.append(best)
    return GPSResult(x, best, iteration, evaluations, step, history)
