"""Effective sky temperature for long-wave exchange of the envelope with the sky.

Clear-sky emissivity from the dew point (Clark & Allen 1978, as EnergyPlus computes it where a
weather file has no infrared field), raised for cloud cover (Clark & Allen), with the cloud cover
estimated from how much of the clear-sky irradiance reached the ground during the day (Kasten &
Czeplak 1980); nights take the cloudiness of the surrounding daylight hours. Where the data
carry the contract's optional ``cloud_cover`` column (a weather service's or station's cloud
cover, %), that cover is used instead (``sky_delta(..., cloud="column")``): the daylight index
says nothing of a night, and against the weather files' own infrared field the estimated cover
leaves R² ≈ 0.5 where the files' recorded cover reaches 0.95 (``benchmarks/sky_temperature.py``).
The contract has no humidity column: the dew point is taken as the lowest air temperature of the
surrounding 24 h, the approximation FAO-56 (Allen et al. 1998, Eq. 48) makes where humidity is
not measured — the air cools at night to about its dew point. Swinbank's (1963) emissivity from
the air temperature alone, which the engine used before, stays available (``SKY_EMISSIVITY``):
against the infrared field of the project's six weather files it ran 2–6 K colder over the
heating season and tracked it less well (``benchmarks/sky_temperature.py``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.building import Location
from rcengine.columns import CLOUD_COVER, T_OUT

KELVIN = 273.15
SWINBANK = 9.365e-6  # [1/K²]
# Clear-sky emissivity models by name: "clark_allen" (from the dew point), "swinbank" (from the
# air temperature; parameter sets stored before the dew point was estimated use it).
SKY_EMISSIVITY = ("clark_allen", "swinbank")
# Window over which the lowest air temperature stands for the dew point (FAO-56 Eq. 48).
DEW_POINT_WINDOW = "24h"
# Daylight rows used to judge cloudiness: sun high enough for the clear-sky index to mean much.
MIN_CLEAR_GHI_W_M2 = 50.0
# Where the cloud cover comes from: "estimated" from the daylight clear-sky index, or "column",
# the data's ``cloud_cover`` (rows without it take the estimate).
CLOUD_SOURCES = ("estimated", "column")


def cloud_cover_from_index(clear_sky_index: np.ndarray) -> np.ndarray:
    """Opaque sky cover in tenths (0–10) from the clear-sky index G/G_clear (Kasten & Czeplak:
    G/G_clear = 1 − 0.75 (N/8)^3.4, N in octas)."""
    k = np.clip(np.asarray(clear_sky_index, dtype=float), 0.0, 1.0)
    octas = 8.0 * (np.clip(1.0 - k, 0.0, 0.75) / 0.75) ** (1.0 / 3.4)
    return octas * 10.0 / 8.0


def clear_sky_emissivity(
    t_out: np.ndarray, t_dew: np.ndarray | None = None, model: str = "clark_allen"
) -> np.ndarray:
    """Emissivity of the cloudless sky. [-]

    "clark_allen": ε = 0.787 + 0.764 ln(T_dew / 273) (T_dew in K; ``t_dew`` required);
    "swinbank": ε = 9.365e-6 · T² (T the air temperature in K).
    """
    if model == "swinbank":
        return SWINBANK * (np.asarray(t_out, dtype=float) + KELVIN) ** 2
    if model != "clark_allen":
        raise ValueError(f"unknown sky emissivity model {model!r}; use one of {SKY_EMISSIVITY}")
    if t_dew is None:
        raise ValueError("the Clark & Allen sky emissivity needs the dew point")
    return 0.787 + 0.764 * np.log((np.asarray(t_dew, dtype=float) + KELVIN) / 273.0)


def sky_temperature(
    t_out: np.ndarray,
    cloud_tenths: np.ndarray,
    t_dew: np.ndarray | None = None,
    model: str = "clark_allen",
) -> np.ndarray:
    """Effective sky temperature. [°C]

    ε = ε_clear (1 + 0.0224 N − 0.0035 N² + 0.00028 N³) with N the cloud cover in tenths (Clark
    & Allen) and ε_clear from ``clear_sky_emissivity``; T_sky = ε^¼ · T (T the air temperature).
    """
    t = np.asarray(t_out, dtype=float) + KELVIN
    n = np.clip(np.asarray(cloud_tenths, dtype=float), 0.0, 10.0)
    clear = clear_sky_emissivity(t_out, t_dew, model)
    emissivity = clear * (1.0 + 0.0224 * n - 0.0035 * n**2 + 0.00028 * n**3)
    return np.minimum(emissivity, 1.0) ** 0.25 * t - KELVIN


def dew_point_estimate(t_out: pd.Series) -> np.ndarray:
    """Dew point where humidity is not measured: the lowest air temperature of the
    ``DEW_POINT_WINDOW`` centred on each row (so never above the row's own; FAO-56 Eq. 48). [°C]"""
    return t_out.rolling(DEW_POINT_WINDOW, center=True, min_periods=1).min().to_numpy(dtype=float)


def sky_delta(
    frame: pd.DataFrame, location: Location, model: str = "clark_allen", cloud: str = "estimated"
) -> np.ndarray:
    """T_sky − t_out: the cloud cover by ``cloud`` (``cloud_cover``), the dew point from the
    day's lowest air temperature (``dew_point_estimate``), the clear sky's emissivity by
    ``model``. [K]"""
    t_out = frame[T_OUT].astype(float)
    cover = cloud_cover(frame, location, cloud)
    t_sky = sky_temperature(t_out.to_numpy(), cover, dew_point_estimate(t_out), model)
    return t_sky - t_out.to_numpy()


def cloud_cover(frame: pd.DataFrame, location: Location, cloud: str = "estimated") -> np.ndarray:
    """Cloud cover per row [tenths]: the data's ``cloud_cover`` [%] where ``cloud`` is "column"
    (``ValueError`` if the frame has none; rows without a value take the estimate), else the
    estimate from the daylight clear-sky index (``daily_cloud_cover``)."""
    if cloud not in CLOUD_SOURCES:
        raise ValueError(f"unknown cloud cover source {cloud!r}; use one of {CLOUD_SOURCES}")
    if cloud == "estimated":
        return daily_cloud_cover(frame, location)
    if CLOUD_COVER not in frame.columns or not frame[CLOUD_COVER].notna().any():
        raise ValueError(
            f"the sky's cloud cover is read from '{CLOUD_COVER}', absent from the data"
        )
    measured = frame[CLOUD_COVER].to_numpy(dtype=float) / 10.0
    if np.isfinite(measured).all():
        return measured
    return np.where(np.isfinite(measured), measured, daily_cloud_cover(frame, location))


def daily_cloud_cover(frame: pd.DataFrame, location: Location) -> np.ndarray:
    """Cloud cover (tenths) per row: the daylight mean of each local day, spread over the day and
    interpolated between days so nights inherit the neighbouring days' cloudiness."""
    from rcengine.signals.solar import clear_sky_ghi

    clear = clear_sky_ghi(frame.index, location)
    day = frame.index.tz_convert(location.timezone).normalize()
    lit = clear > MIN_CLEAR_GHI_W_M2
    ghi = frame["ghi"].to_numpy(dtype=float)
    per_day = (
        pd.DataFrame(
            {"ghi": np.where(lit, ghi, np.nan), "clear": np.where(lit, clear, np.nan), "day": day}
        )
        .groupby("day")
        .sum(min_count=1)
    )
    index = (per_day["ghi"] / per_day["clear"]).clip(0.0, 1.0)
    cover = pd.Series(cloud_cover_from_index(index.to_numpy()), index=index.index)
    # Centre each day's value at local noon and interpolate in time across nights.
    noon = cover.index + pd.Timedelta(hours=12)
    series = pd.Series(cover.to_numpy(), index=noon.tz_convert("UTC"))
    grid = series.reindex(series.index.union(frame.index)).interpolate("time").ffill().bfill()
    return grid.reindex(frame.index).fillna(5.0).to_numpy()
