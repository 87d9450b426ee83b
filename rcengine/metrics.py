"""Goodness-of-fit metrics for simulated vs measured temperatures.

Sign convention (ASHRAE Guideline 14 and the thesis Eq. 19–20): error = measured − simulated.
All functions ignore pairs where either value is NaN.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike

# ASHRAE Guideline 14-2014, calibration criteria for hourly data [%].
ASHRAE14_CV_RMSE_MAX = 30.0
ASHRAE14_NMBE_MAX = 10.0


def lag1_autocorrelation(errors: ArrayLike) -> float:
    """Correlation of consecutive errors (finite values, in order); 0 for fewer than three or a
    constant series."""
    e = np.asarray(errors, dtype=float)
    e = e[np.isfinite(e)]
    return float(np.corrcoef(e[:-1], e[1:])[0, 1]) if e.size > 2 and e.std() > 0 else 0.0


def effective_count(n: float, rho: float) -> float:
    """How many independent values ``n`` values with lag-1 autocorrelation ``rho`` are worth,
    n (1 − ρ)/(1 + ρ) (an AR(1) series' variance of the mean; Bartlett 1946)."""
    return n * (1.0 - rho) / (1.0 + rho)


def _pairs(measured: ArrayLike, simulated: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(measured, dtype=float)
    y_hat = np.asarray(simulated, dtype=float)
    if y.shape != y_hat.shape:
        raise ValueError(f"shapes differ: measured {y.shape}, simulated {y_hat.shape}")
    ok = np.isfinite(y) & np.isfinite(y_hat)
    if not ok.any():
        raise ValueError("no pair of finite measured and simulated values")
    return y[ok], y_hat[ok]


def rmse(measured: ArrayLike, simulated: ArrayLike) -> float:
    """Root-mean-square error, thesis Eq. 19. [same unit as input, K for temperatures]"""
    y, y_hat = _pairs(measured, simulated)
    error = y - y_hat
    with np.errstate(over="ignore"):
        value = np.sqrt(np.mean(error**2))
    if np.isinf(value):
        # Errors beyond ~1e154 (an absurd prediction) overflow when squared; scaled by the
        # largest one, the same RMSE stays finite wherever it is representable.
        scale = np.max(np.abs(error))
        value = scale * np.sqrt(np.mean((error / scale) ** 2))
    return float(value)


def mbe(measured: ArrayLike, simulated: ArrayLike) -> float:
    """Mean bias error, measured − simulated. [same unit as input]"""
    y, y_hat = _pairs(measured, simulated)
    return float(np.mean(y - y_hat))


def nmbe(measured: ArrayLike, simulated: ArrayLike) -> float:
    """Normalised mean bias error, thesis Eq. 19 ("MBS"): Σ(y − ŷ) / Σ y · 100. [%]"""
    y, y_hat = _pairs(measured, simulated)
    return float(np.sum(y - y_hat) / np.sum(y) * 100.0)


def cv_rmse(measured: ArrayLike, simulated: ArrayLike) -> float:
    """Coefficient of variation of the RMSE, thesis Eq. 20: RMSE / mean(y) · 100. [%]"""
    y, y_hat = _pairs(measured, simulated)
    return float(np.sqrt(np.mean((y - y_hat) ** 2)) / np.mean(y) * 100.0)


@dataclass(frozen=True)
class FitMetrics:
    """Every metric of one comparison; ``ashrae14_pass`` applies Guideline 14's hourly limits."""

    rmse: float
    mbe: float
    nmbe: float
    cv_rmse: float
    n: int
    ashrae14_pass: bool

    def to_dict(self) -> dict:
        return asdict(self)


def evaluate(measured: ArrayLike, simulated: ArrayLike) -> FitMetrics:
    """All metrics at once; pass/fail is |NMBE| ≤ 10 % and CV(RMSE) ≤ 30 % (Guideline 14)."""
    y, y_hat = _pairs(measured, simulated)
    n_mbe = nmbe(y, y_hat)
    cv = cv_rmse(y, y_hat)
    return FitMetrics(
        rmse=rmse(y, y_hat),
        mbe=mbe(y, y_hat),
        nmbe=n_mbe,
        cv_rmse=cv,
        n=int(y.size),
        ashrae14_pass=bool(abs(n_mbe) <= ASHRAE14_NMBE_MAX and cv <= ASHRAE14_CV_RMSE_MAX),
    )
