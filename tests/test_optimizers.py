"""GA and pattern search on functions with a known minimum."""

import itertools

import numpy as np
import pytest

from rcengine.estimation import ga, pattern_search
from rcengine.estimation.ga import GASettings
from rcengine.estimation.pattern_search import GPSSettings

TARGET = np.array([0.3, 0.7, 0.55])


def sphere(x: np.ndarray) -> np.ndarray:
    return np.sum((np.atleast_2d(x) - TARGET) ** 2, axis=1)


def test_ga_finds_the_basin_and_is_seeded():
    settings = GASettings(population=60, generations=30, tol=0.0, lhs=True)
    a = ga.minimize(sphere, 3, settings, np.random.default_rng(4))
    b = ga.minimize(sphere, 3, settings, np.random.default_rng(4))
    assert np.max(np.abs(a.x - TARGET)) < 0.05
    np.testing.assert_array_equal(a.x, b.x)
    assert a.evaluations == 60 + 59 * (len(a.history) - 1)  # the elite is not re-simulated
    assert all(h1 >= h2 for h1, h2 in itertools.pairwise(a.history))  # elitism: never worse


def test_ga_survives_infinite_costs():
    def cost(x):
        c = sphere(x)
        return np.where(np.atleast_2d(x)[:, 0] > 0.5, np.inf, c)

    res = ga.minimize(cost, 3, GASettings(population=40, generations=20), np.random.default_rng(0))
    assert np.isfinite(res.cost)


def test_ga_archive_holds_distinct_basins():
    def two_wells(x):
        x = np.atleast_2d(x)
        return np.minimum(np.sum((x - 0.2) ** 2, 1), np.sum((x - 0.8) ** 2, 1) + 0.01)

    res = ga.minimize(
        two_wells, 2, GASettings(population=80, generations=15, archive=4), np.random.default_rng(1)
    )
    centres = {tuple(np.round(a, 0)) for a in res.archive}
    assert len(res.archive) >= 2 and len(centres) >= 2


def test_pattern_search_converges_to_tolerance():
    x0 = np.array([0.9, 0.1, 0.1])
    res = pattern_search.minimize(sphere, x0, float(sphere(x0)[0]), GPSSettings(tol=1e-8))
    assert np.max(np.abs(res.x - TARGET)) < 1e-6
    assert res.final_step < 1e-8
    assert res.iterations < 500


def test_pattern_search_respects_bounds_and_iteration_limit():
    x0 = np.array([0.5, 0.5, 0.5])
    res = pattern_search.minimize(
        lambda x: -np.atleast_2d(x).sum(1), x0, -1.5, GPSSettings(max_iter=7)
    )
    assert res.iterations == 7
    assert np.all(res.x <= 1.0)
    assert res.cost == pytest.approx(-res.x.sum())
