"""Genetic algorithm on the unit cube, one batched cost evaluation per generation.

In the spirit of ModestPy's GA (Arendt et al. 2018): tournament selection, uniform crossover,
random-reset and Gaussian mutation, elitism, optional Latin-hypercube start. Genes are the
parameters mapped to [0, 1] by :mod:`rcengine.estimation.search_space`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

BatchCost = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class GASettings:
    """population: individuals per generation; generations: at most this many;
    tol: stop when the best cost improved by less than this fraction over ``patience`` generations;
    tournament: individuals per tournament; crossover: probability a gene comes from parent 1;
    mutation_rate: probability a gene mutates; mutation_scale: σ of the Gaussian step (unit cube);
    reset_fraction: share of mutations that draw a fresh uniform value; elite: kept unchanged;
    lhs: Latin-hypercube start instead of uniform random; archive: how many of the best mutually
    distinct individuals seen in any generation to keep (local searches start from them)."""

    population: int = 20
    generations: int = 15
    tol: float = 1e-3
    patience: int = 3
    tournament: int = 3
    crossover: float = 0.5
    mutation_rate: float = 0.1
    mutation_scale: float = 0.1
    reset_fraction: float = 0.3
    elite: int = 1
    lhs: bool = False
    archive: int = 8


@dataclass(frozen=True)
class GAResult:
    x: np.ndarray  # best genes (p,)
    cost: float
    population: np.ndarray  # last generation (N, p), sorted by cost
    costs: np.ndarray
    history: list[float]  # best cost per generation
    evaluations: int
    archive: np.ndarray  # best mutually distinct individuals of the whole run, best first
    archive_costs: np.ndarray


def minimize(
    cost: BatchCost,
    n_genes: int,
    settings: GASettings,
    rng: np.random.Generator,
    initial: np.ndarray | None = None,
) -> GAResult:
    """Minimise ``cost`` over [0, 1]^n_genes; ``initial`` rows are seeded into generation 0."""
    pop = _initial_population(n_genes, settings, rng)
    if initial is not None and len(initial):
        pop[: len(initial)] = np.clip(initial, 0.0, 1.0)[: len(pop)]
    costs = cost(pop)
    evaluations = len(pop)
    pop, costs = _sorted(pop, costs)
    history = [float(costs[0])]
    archive, archive_costs = _distinct_best(pop, costs, settings.archive)
    for _ in range(settings.generations - 1):
        if _converged(history, settings):
            break
        children = _offspring(pop, costs, settings, rng)
        child_costs = cost(children)
        evaluations += len(children)
        pop, costs = _sorted(
            np.concatenate([pop[: settings.elite], children]),
            np.concatenate([costs[: settings.elite], child_costs]),
        )
        history.append(float(costs[0]))
        archive, archive_costs = _distinct_best(
            np.concatenate([archive, children]),
            np.concatenate([archive_costs, child_costs]),
            settings.archive,
        )
    return GAResult(
        pop[0], float(costs[0]), pop, costs, history, evaluations, archive, archive_costs
    )


def _initial_population(n: int, settings: GASettings, rng: np.random.Generator) -> np.ndarray:
    if settings.lhs:
        return qmc.LatinHypercube(d=n, rng=rng).random(settings.population)
    return rng.random((settings.population, n))


def _sorted(pop: np.ndarray, costs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(costs, kind="stable")
    return pop[order], costs[order]


def _distinct_best(
    pop: np.ndarray, costs: np.ndarray, k: int, radius: float = 0.3
) -> tuple[np.ndarray, np.ndarray]:
    """The k best individuals lying farther than ``radius`` (max-norm) from every better one."""
    pop, costs = _sorted(pop, costs)
    keep: list[int] = []
    for i in range(len(pop)):
        if len(keep) == k:
            break
        if all(np.max(np.abs(pop[i] - pop[j])) > radius for j in keep):
            keep.append(i)
    return pop[keep], costs[keep]


def _converged(history: list[float], settings: GASettings) -> bool:
    if len(history) <= settings.patience:
        return False
    old, new = history[-1 - settings.patience], history[-1]
    if not np.isfinite(old):
        return False
    return old - new <= settings.tol * abs(old)


def _offspring(
    pop: np.ndarray, costs: np.ndarray, settings: GASettings, rng: np.random.Generator
) -> np.ndarray:
    n_children = settings.population - settings.elite
    parents1 = pop[_tournament(costs, n_children, settings.tournament, rng)]
    parents2 = pop[_tournament(costs, n_children, settings.tournament, rng)]
    take_first = rng.random(parents1.shape) < settings.crossover
    children = np.where(take_first, parents1, parents2)
    mutate = rng.random(children.shape) < settings.mutation_rate
    reset = mutate & (rng.random(children.shape) < settings.reset_fraction)
    step = rng.normal(0.0, settings.mutation_scale, children.shape)
    children = np.where(mutate & ~reset, children + step, children)
    children = np.where(reset, rng.random(children.shape), children)
    return _reflect(children)


def _tournament(costs: np.ndarray, n: int, size: int, rng: np.random.Generator) -> np.ndarray:
    """Index of the fittest of ``size`` random contenders, ``n`` times (population is sorted)."""
    contenders = rng.integers(0, costs.size, size=(n, size))
    return contenders.min(axis=1)


def _reflect(x: np.ndarray) -> np.ndarray:
    """Fold values that stepped outside [0, 1] back inside (keeps the mutation distribution)."""
    x = np.abs(x)
    return np.where(x > 1.0, np.maximum(0.0, 2.0 - x), x)
