"""A slowly varying ground temperature for floors in contact with the soil.

Below a slab the soil damps the daily and weekly swings of the air temperature and lags its
seasonal swing (Kusuda & Achenbach 1965). Two estimates:

- ``seasonal_ground_temperature``: the outdoor annual cycle T_m − A·cos(ω(t − t_cold)), read from
  the record, carried down into the soil as a periodic wave: T_g(t) = T_m − A·e^(−z/δ)·cos(ω(t −
  t_cold) − z/δ) (the solution of the 1-D heat equation in a semi-infinite soil, ISO 13370:2017
  Annex; Kusuda & Achenbach 1965), with δ = √(λ·P/(π·ρc)) the periodic penetration depth. The
  diagnosis fits the mean on top of it (a heated building warms the soil under it);
- ``ground_temperature``: an exponentially weighted running mean of the outdoor temperature (a
  month's time constant), the older, shorter-memory estimate.

``annual_mean_uncertainty`` says how well a record of a few months knows the annual mean it reads:
a bound on the soil temperature read from it must be as loose as the mean is uncertain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.signal import lfilter

from rcengine.metrics import effective_count, lag1_autocorrelation

GROUND_TAU_DAYS = 30.0
# Annual period. [s]
YEAR_S = 365.2425 * 86400.0
# Sand or gravel, the soil ISO 13370:2017 (Table 7) and ISO 52016-1 take when the soil is
# unknown: conductivity [W/(mK)] and volumetric heat capacity [J/(m³K)].
SOIL_CONDUCTIVITY = 2.0
SOIL_HEAT_CAPACITY = 2.0e6
# Periodic penetration depth of the annual wave, δ = √(λ·P/(π·ρc)) (ISO 13370:2017 Table 7:
# 3.2 m in sand or gravel; 2.2 m in clay, 4.2 m in rock). [m]
SOIL_PENETRATION_DEPTH_M = float(np.sqrt(SOIL_CONDUCTIVITY * YEAR_S / (np.pi * SOIL_HEAT_CAPACITY)))
# Lag of a slab floor's ground heat flow behind the outdoor annual cycle. ISO 13370:2017's
# external phase shift for a slab on the ground, β = 1.5 − 0.42·ln(δ/d_t + 1) months (d_t: the
# floor's total equivalent thickness w + λ·(R_si + R_f + R_se)), runs from 0.8 months under a
# bare slab (d_t ≈ 0.7 m) through 1 month (d_t ≈ 1.4 m: a little insulation, or a slab on fill)
# and 1.3 months with 2 m²K/W of insulation to 1.5 in the limit of an insulated floor. The floor's
# construction is not in the building description: a month is the default, and the diagnosis
# tries the insulated end too (``GROUND_LAGS_S``). [s]
GROUND_LAG_S = YEAR_S / 12.0
INSULATED_GROUND_LAG_S = YEAR_S / 8.0
GROUND_LAGS_S = (GROUND_LAG_S, INSULATED_GROUND_LAG_S)


def ground_depth(lag_s: float) -> float:
    """The depth at which the annual wave lags by ``lag_s``, z = δ·2π·lag/year (a month: 1.66 m,
    its swing damped to e^(−z/δ) ≈ 0.59; a month and a half: 2.49 m, 0.46). [m]"""
    return SOIL_PENETRATION_DEPTH_M * 2.0 * np.pi * lag_s / YEAR_S


def ground_lag(depth_m: float) -> float:
    """The lag of the annual wave ``depth_m`` deep, the inverse of ``ground_depth``. [s]"""
    return depth_m * YEAR_S / (2.0 * np.pi * SOIL_PENETRATION_DEPTH_M)


GROUND_DEPTH_M = ground_depth(GROUND_LAG_S)
# Coldest day of the outdoor annual cycle: about 25 days after the winter solstice in mid-latitude
# climates (day of year, northern hemisphere; half a year later in the southern). [d]
COLDEST_DAY_OF_YEAR = 15.0
# The cycle's amplitude is read only from a record whose cos(2π(t − t_cold)/year) spans at least
# this much (about two months away from the coldest day): nearer, mean and amplitude are one
# number. [-]
MIN_CYCLE_SPREAD = 0.5
# Two-sided 95 % normal quantile: how far below an estimate a bound read from it may lie. [-]
ESTIMATE_Z = 1.96
# Largest annual amplitude of monthly mean air temperatures on Earth (≈ 30 K in eastern Siberia);
# a fit beyond it is the weather of one record, not a climate. [K]
MAX_ANNUAL_AMPLITUDE_K = 30.0


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


@dataclass(frozen=True)
class AnnualCycle:
    """Outdoor annual cycle T_m − A·cos(2π(t − coldest)/year): mean [°C], amplitude [K] (≥ 0)
    and the instant of its minimum."""

    mean: float
    amplitude: float
    coldest: pd.Timestamp

    def phase(self, times: pd.DatetimeIndex) -> np.ndarray:
        """2π(t − coldest)/year at ``times``. [rad]"""
        return 2.0 * np.pi * (times - self.coldest).total_seconds().to_numpy() / YEAR_S

    def to_dict(self) -> dict[str, float | str]:
        return {"mean": self.mean, "amplitude": self.amplitude, "coldest": self.coldest.isoformat()}

    @classmethod
    def from_dict(cls, data: dict) -> AnnualCycle:
        return cls(float(data["mean"]), float(data["amplitude"]), pd.Timestamp(data["coldest"]))


def annual_cycle(times: pd.DatetimeIndex, t_out: np.ndarray, latitude: float) -> AnnualCycle:
    """Least-squares mean and amplitude of the annual cycle through ``t_out`` [°C] at ``times``,
    its phase fixed by the hemisphere (``COLDEST_DAY_OF_YEAR``): a record of a few months cannot
    place the minimum, but can tell how much warmer its spring is than its winter.

    The amplitude is kept within 0–``MAX_ANNUAL_AMPLITUDE_K`` (a record whose trend runs against
    the season gives a flat cycle) and is 0 when the record spans too little of the cycle
    (``MIN_CYCLE_SPREAD``); the mean is then the one that goes with it.
    """
    days = COLDEST_DAY_OF_YEAR + (0.0 if latitude >= 0 else YEAR_S / 2 / 86400.0)
    first = times[0].tz_convert("UTC")
    coldest = pd.Timestamp(year=first.year, month=1, day=1, tz="UTC") + pd.Timedelta(days=days)
    cycle = AnnualCycle(0.0, 0.0, coldest)
    t_out = np.asarray(t_out, dtype=float)
    ok = np.isfinite(t_out)
    shape = np.cos(cycle.phase(times))[ok]
    amplitude = 0.0
    if np.ptp(shape) >= MIN_CYCLE_SPREAD:
        design = np.column_stack([np.ones(shape.size), -shape])
        amplitude = np.linalg.lstsq(design, t_out[ok], rcond=None)[0][1]
    amplitude = float(np.clip(amplitude, 0.0, MAX_ANNUAL_AMPLITUDE_K))
    return AnnualCycle(float(np.mean(t_out[ok] + amplitude * shape)), amplitude, coldest)


def annual_mean_uncertainty(
    times: pd.DatetimeIndex, t_out: np.ndarray, cycle: AnnualCycle
) -> float:
    """Standard error of ``cycle.mean`` as the annual mean of the weather. [K]

    A record of a few months reads the annual mean through its fitted cycle, and a mild or harsh
    spell moves it: from October–January of the TMY3 files that ship with EnergyPlus, Chicago's
    mean comes out 2.2 K above its full year's, Golden's 1.0 K below. The scatter of the daily
    means about the cycle gives the error of the least-squares mean, σ²·[(XᵀX)⁻¹]₀₀ with X the
    design [1, −cos(2π(t − t_cold)/year)] (only [1] when the cycle is flat), counting weather
    spells, not days: n(1 − ρ₁)/(1 + ρ₁) independent days for a lag-1 autocorrelation ρ₁ of the
    daily scatter (synoptic systems last several days). Returns ``inf`` when the days are too
    few to leave a scatter to read (no more than the fitted values plus one): such a record says
    nothing of the year.
    """
    series = pd.Series(np.asarray(t_out, dtype=float), index=times).dropna()
    daily = series.resample("1D").mean().dropna()
    n = len(daily)
    shape = np.cos(cycle.phase(daily.index + pd.Timedelta(hours=12)))
    design = np.column_stack([np.ones(n), -shape]) if cycle.amplitude > 0 else np.ones((n, 1))
    k = design.shape[1]
    if n <= k + 1:
        return float("inf")
    residual = daily.to_numpy() - (cycle.mean - cycle.amplitude * shape)
    rho = min(max(lag1_autocorrelation(residual), 0.0), 0.99)
    variance = float(residual @ residual) / (n - k)
    covariance = variance * np.linalg.inv(design.T @ design) * n / effective_count(n, rho)
    return float(np.sqrt(covariance[0, 0]))


def seasonal_ground_temperature(
    times: pd.DatetimeIndex,
    t_out: np.ndarray,
    latitude: float,
    depth_m: float = GROUND_DEPTH_M,
    cycle: AnnualCycle | None = None,
) -> np.ndarray:
    """The outdoor annual cycle damped and lagged ``depth_m`` into the soil. [°C]

    T_g(t) = T_m − A·e^(−z/δ)·cos(2π(t − t_cold)/year − z/δ), z = ``depth_m``, δ =
    ``SOIL_PENETRATION_DEPTH_M``, T_m, A and t_cold from ``annual_cycle`` — or ``cycle``, one
    fitted once on a long record: a stored model must see the same ground temperature in a
    one-day forecast as in the months it was fitted on.
    """
    cycle = cycle if cycle is not None else annual_cycle(times, t_out, latitude)
    depth = depth_m / SOIL_PENETRATION_DEPTH_M
    return cycle.mean - cycle.amplitude * np.exp(-depth) * np.cos(cycle.phase(times) - depth)
