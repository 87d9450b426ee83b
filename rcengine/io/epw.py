"""EnergyPlus weather files (EPW) → contract weather columns on a UTC index.

Time convention
---------------
An EPW row of hour ``h`` (1–24, local standard time, no daylight saving) carries

* irradiance (``ghi``, ``dni``, ``dhi``): the energy received during the hour *ending* at
  ``h:00``, i.e. the mean over [h−1, h) in W/m²;
* dry-bulb temperature and wind speed: the value *at* ``h:00``.

(EnergyPlus Auxiliary Programs, "Weather Data File (EPW)" field descriptions.)

The contract stamps a row with the START of its interval and takes inputs as means over
[t, t + dt). Hence the row of hour ``h`` starts at ``h−1:00``: irradiance goes there unchanged.
Temperature and wind are instants; they are joined by straight lines (as EnergyPlus does between
hourly values) and a row takes the mean of that line over its interval — the value at the
interval's midpoint. For the hourly rows that is (T(h−1) + T(h)) / 2. A whole (typical) year
is treated as circular: the value at 00:00 on 1 January is the file's last one (24:00 on 31
December); a shorter file holds its first value back to the start of its first hour.

Resampling to a finer step (``step_s``, a divisor of 3600 s): irradiance is held over its hour,
so every hour keeps its energy; temperature and wind follow the same straight lines, so each
hour's mean is unchanged too.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from pvlib.iotools import read_epw as pvlib_read_epw

from rcengine.building import Location
from rcengine.columns import COLUMNS, DHI, DNI, GHI, MIN_STEP_S, T_OUT, TIME, WIND_SPEED
from rcengine.exceptions import DataValidationError, Problem

# Contract column ← pvlib's name for the EPW field.
EPW_FIELDS = {T_OUT: "temp_air", GHI: "ghi", DNI: "dni", DHI: "dhi", WIND_SPEED: "wind_speed"}
INSTANT_COLUMNS = (T_OUT, WIND_SPEED)  # values at the hour stamp
HOUR_S = 3600
# Data row 0 of an EPW file is on line 9, below the eight header lines.
FIRST_DATA_LINE = 9


def read_epw(
    path: str | Path, step_s: int | None = None, *, year: int = 2017
) -> tuple[pd.DataFrame, Location]:
    """Weather of an EPW file as contract columns, and the site.

    Parameters
    ----------
    path : the ``.epw`` file.
    step_s : row step of the result; None or 3600 for hourly rows, or a divisor of 3600 of at
        least 60 (e.g. 900) to resample. [s]
    year : calendar year given to every row (typical-year files mix years month by month).
        Use a common year for a file without 29 February.

    Returns
    -------
    frame : indexed by UTC start-of-interval times named ``time``, columns ``t_out`` [°C],
        ``ghi``, ``dni``, ``dhi`` [W/m²], ``wind_speed`` [m/s]; see the module docstring.
    location : latitude, longitude, altitude and the file's standard-time zone as a fixed
        offset (``Etc/GMT-1`` for UTC+1: the sign of the ``Etc`` names is reversed).

    Raises
    ------
    ValueError : invalid ``step_s``, or a time-zone offset that is not a whole hour.
    DataValidationError : a value outside the physical range (EPW "missing" codes such as
        9999), naming the data row and the line of the file.
    """
    step_s = HOUR_S if step_s is None else int(step_s)
    if step_s < MIN_STEP_S or HOUR_S % step_s:
        raise ValueError(f"step_s must divide 3600 s and be at least {MIN_STEP_S} s, got {step_s}")
    data, meta = pvlib_read_epw(path, coerce_year=year)
    hourly = pd.DataFrame({name: data[field].to_numpy(float) for name, field in EPW_FIELDS.items()})
    _check_ranges(hourly)
    hour_ends = hour_ends_utc(data, meta["TZ"])
    return _resample(hourly, hour_ends, step_s), _location(meta)


def hour_ends_utc(data: pd.DataFrame, tz_offset_h: float) -> pd.DatetimeIndex:
    """UTC instants of the EPW stamps (end of each hour), from the file's own date fields."""
    days = pd.to_datetime(data[["year", "month", "day"]].astype(int))
    local = days + pd.to_timedelta(data["hour"].astype(int), unit="h")
    utc = local - pd.Timedelta(hours=tz_offset_h)
    return pd.DatetimeIndex(utc).as_unit("ns").tz_localize("UTC")


def _resample(hourly: pd.DataFrame, hour_ends: pd.DatetimeIndex, step_s: int) -> pd.DataFrame:
    start = hour_ends[0] - pd.Timedelta(seconds=HOUR_S)
    per_hour = HOUR_S // step_s
    offsets_s = np.arange(len(hourly) * per_hour) * float(step_s)
    index = pd.DatetimeIndex(start + pd.to_timedelta(offsets_s, unit="s"), name=TIME)
    # Straight lines through the instants. The value at the start is the last one of a whole
    # (circular) year, else the first one held.
    knots_s = np.r_[0.0, (hour_ends - start).total_seconds().to_numpy()]
    whole_year = round(knots_s[-1] / 86400.0) in (365, 366)
    midpoints_s = offsets_s + step_s / 2.0
    columns = {}
    for name in hourly.columns:
        values = hourly[name].to_numpy()
        if name in INSTANT_COLUMNS:
            at_start = values[-1] if whole_year else values[0]
            columns[name] = np.interp(midpoints_s, knots_s, np.r_[at_start, values])
        else:
            columns[name] = np.repeat(values, per_hour)
    return pd.DataFrame(columns, index=index)


def _check_ranges(hourly: pd.DataFrame) -> None:
    problems = []
    for name in hourly.columns:
        column = COLUMNS[name]
        values = hourly[name].to_numpy()
        for row in np.flatnonzero((values < column.lower) | (values > column.upper))[:100]:
            problems.append(
                Problem(
                    int(row),
                    name,
                    f"{values[row]:g} {column.unit} is outside [{column.lower:g}, "
                    f"{column.upper:g}] (an EPW missing-data code?) — line "
                    f"{row + FIRST_DATA_LINE} of the file",
                )
            )
    if problems:
        raise DataValidationError(problems)


def _location(meta: dict) -> Location:
    return Location(
        latitude=float(meta["latitude"]),
        longitude=float(meta["longitude"]),
        altitude=float(meta["altitude"]),
        timezone=_fixed_offset_zone(float(meta["TZ"])),
    )


def _fixed_offset_zone(tz_offset_h: float) -> str:
    """IANA name of a whole-hour standard-time offset: +1 → ``Etc/GMT-1`` (POSIX signs)."""
    if tz_offset_h != round(tz_offset_h):
        raise ValueError(
            f"time-zone offset {tz_offset_h:+g} h is not a whole hour; no Etc/GMT zone exists "
            "for it — set the building's timezone by hand"
        )
    hours = round(tz_offset_h)
    return "UTC" if hours == 0 else f"Etc/GMT{-hours:+d}"
