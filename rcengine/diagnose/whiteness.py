"""Residual whiteness: Ljung–Box test on hourly one-step-ahead errors.

A well-specified model leaves one-step-ahead (Kalman) errors that are white noise; structure left
in them — autocorrelation at lags up to a day — is physics the model misses. Ljung & Box (1978):
Q = n(n+2) Σ_{k=1}^{h} ρ_k² / (n − k), compared with χ²(h).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.stats import chi2


def ljung_box(errors: np.ndarray, times: pd.DatetimeIndex, lags: int = 24) -> dict[str, float]:
    """Ljung–Box on the hourly means of ``errors`` [K]; returns Q, p-value, lag-1 and lag-24 ρ."""
    hourly = pd.Series(errors, index=times).resample("1h").mean().dropna().to_numpy()
    n = hourly.size
    if n <= lags + 1:
        return {
            "q": float("nan"),
            "p_value": float("nan"),
            "lags": lags,
            "n": n,
            "rho_1h": float("nan"),
            "rho_24h": float("nan"),
        }
    x = hourly - hourly.mean()
    denom = float(x @ x)
    rho = np.array([float(x[:-k] @ x[k:]) / denom for k in range(1, lags + 1)])
    q = float(n * (n + 2) * np.sum(rho**2 / (n - np.arange(1, lags + 1))))
    return {
        "q": q,
        "p_value": float(chi2.sf(q, lags)),
        "lags": lags,
        "n": n,
        "rho_1h": float(rho[0]),
        "rho_24h": float(rho[min(23, lags - 1)]),
    }
