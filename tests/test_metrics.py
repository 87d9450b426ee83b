"""Metrics against hand-computed values (thesis Eq. 19–20, ASHRAE Guideline 14)."""

import warnings

import numpy as np
import pytest

from rcengine.metrics import (
    cv_rmse,
    effective_count,
    evaluate,
    lag1_autocorrelation,
    mbe,
    nmbe,
    rmse,
)


def test_values_by_hand():
    y = np.array([20.0, 21.0, 22.0, 23.0])
    y_hat = np.array([21.0, 21.0, 21.0, 25.0])
    # errors y − ŷ: −1, 0, 1, −2
    assert rmse(y, y_hat) == pytest.approx(np.sqrt(6 / 4))
    assert mbe(y, y_hat) == pytest.approx(-0.5)
    assert nmbe(y, y_hat) == pytest.approx(-2 / 86 * 100)
    assert cv_rmse(y, y_hat) == pytest.approx(np.sqrt(1.5) / 21.5 * 100)


def test_nan_pairs_are_ignored_and_shapes_checked():
    assert rmse([1.0, np.nan, 3.0], [1.0, 5.0, 4.0]) == pytest.approx(np.sqrt(0.5))
    with pytest.raises(ValueError, match="shapes differ"):
        rmse([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="no pair"):
        rmse([np.nan], [1.0])


def test_ashrae_guideline_14_limits():
    y = np.full(100, 20.0)
    assert evaluate(y, y + 0.5).ashrae14_pass  # NMBE −2.5 %, CV 2.5 %
    assert not evaluate(y, y + 2.5).ashrae14_pass  # NMBE −12.5 % breaks the ±10 % limit
    m = evaluate(y, y + 0.5).to_dict()
    assert set(m) == {"rmse", "mbe", "nmbe", "cv_rmse", "n", "ashrae14_pass"}


def test_rmse_of_an_absurd_prediction_is_finite_and_exact():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning on the way
        value = rmse([20.0, 21.0], [7e304, 20.0])
    assert np.isfinite(value)
    assert value == pytest.approx(7e304 / np.sqrt(2.0), rel=1e-12)


def test_an_ar1_series_is_worth_fewer_independent_values():
    """x_t = 0.8 x_{t−1} + e_t: its lag-1 autocorrelation reads 0.8, and 10 000 values are worth
    10 000 × 0.2 / 1.8 ≈ 1 111 independent ones; NaNs are skipped, a constant series reads 0."""
    rng = np.random.default_rng(3)
    x = np.zeros(10_000)
    for t in range(1, x.size):
        x[t] = 0.8 * x[t - 1] + rng.normal()
    x[::97] = np.nan
    rho = lag1_autocorrelation(x)
    assert rho == pytest.approx(0.8, abs=0.02)
    assert effective_count(10_000, 0.8) == pytest.approx(1111.1, abs=0.1)
    assert lag1_autocorrelation(np.ones(50)) == 0.0
