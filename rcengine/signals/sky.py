"""Effective sky temperature for long-wave exchange of the envelope with the sky.

Clear-sky emissivity from the air temperature (Swinbank 1963), raised for cloud cover (Clark &
Allen 1978, as in EnergyPlus), with the cloud cover estimated from how much of the clear-sky
irradiance reached the ground during the day (Kasten & Czeplak 1980). Nights take the cloudiness
of the surrounding daylight hours.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.building import Location

KELVIN = 273.15
SWINBANK = 9.365e-6  # [1/K²]
# Daylight rows used to judge cloudiness: sun high enough for the clear-sky index to mean much.
MIN_CLEAR_GHI_W_M2 = 50.0


def cloud_cover_from_index(clear_sky_index: np.ndarray) -> np.ndarray:
    """Opaque sky cover in tenths (0–10) from the clear-sky index G/G_clear (Kasten & Czeplak:
    G/G_clear = 1 − 0.75 (N/8)^3.4, N in octas)."""
    k = np.clip(np.asarray(clear_sky_index, dtype=float), 0.0, 1.0)
    octas = 8.0 * (np.clip(1.0 - k, 0.0, 0.75) / 0.75) ** (1.0 / 3.4)
    return octas * 10.0 / 8.0


def sky_temperature(t_out: np.ndarray, cloud_tenths: np.ndarray) -> np.ndarray:
    """Effective sky temperature. [°C]

    ε_clear = 9.365e-6 · T²  (T in K, Swinbank); ε = ε_clear (1 + 0.0224 N − 0.0035 N² +
    0.00028 N³) with N the cloud cover in tenths (Clark & Allen); T_sky = ε^¼ · T.
    """
    t = np.asarray(t_out, dtype=float) + KELVIN
    n = np.clip(np.asarray(cloud_tenths, dtype=float), 0.0, 10.0)
    emissivity = SWINBANK * t**2 * (1.0 + 0.0224 * n - 0.0035 * n**2 + 0.00028 * n**3)
    return np.minimum(emissivity, 1.0) ** 0.25 * t - KELVIN


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
