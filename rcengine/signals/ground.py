"""A slowly varying ground temperature for floors in contact with the soil.

Below a slab the soil damps the daily and weekly swings of the air temperature and lags its
seasonal swing (Kusuda & Achenbach 1965). Without soil data, an exponentially weighted running
mean of the outdoor temperature with a time constant of about a month reproduces that behaviour
at the shallow depths that exchange heat with a floor.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

GROUND_TAU_DAYS = 30.0


def ground_temperature(
    t_out: np.ndarray, step_s: float, tau_days: float = GROUND_TAU_DAYS
) -> np.ndarray:
    """Running mean of the outdoor temperature with time constant ``tau_days``.

    Parameters
    ----------
    t_out : outdoor dry-bulb temperature on a regular step. [°C]
    step_s : step. [s]
    tau_days : time constant of the soil response. [d]

    Returns
    -------
    Ground temperature estimate. [°C] It starts at the mean of the first ``tau_days`` so the
    first weeks are not pulled towards the first hour's weather.
    """
    t_out = np.asarray(t_out, dtype=float)
    n_tau = max(1, int(tau_days * 86400.0 / step_s))
    a = np.exp(-1.0 / n_tau)
    start = float(np.mean(t_out[:n_tau]))
    out, _ = lfilter([1.0 - a], [1.0, -a], t_out, zi=[a * start])
    return out
