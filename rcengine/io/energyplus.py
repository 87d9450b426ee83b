"""EnergyPlus results (``eplusout.csv``) → the contract frame.

Reads the timestep CSV that EnergyPlus writes itself (``OutputControl:Files``) or that
ReadVarsESO makes from ``eplusout.eso``, and returns one row per timestep, indexed by UTC time,
with the contract columns.

Timestamps
----------
EnergyPlus stamps a row with the END of its timestep, ``MM/DD  hh:mm:ss`` in local standard time
(no year, no daylight saving; midnight is ``24:00:00`` of the day before). A rate variable is
the mean over that timestep and every boundary condition (weather, sun position) is the value
EnergyPlus applied during it; ``Zone Mean Air Temperature`` is the air temperature at the end of
the timestep. The contract stamps a row with the START of its interval, inputs being means over
[t, t + dt) and ``t_in`` the value at t. Hence

* an averaged variable stamped ``00:15`` goes to the contract row ``00:00``;
* the temperature stamped ``00:15`` goes to the row ``00:15``.

The first simulated instant has no temperature and the last one no inputs; only rows that have
both are kept. EnergyPlus's own CSV writer sorts rows by their ``MM/DD hh:mm`` text, which puts
January before October in a heating-season run; ReadVarsESO keeps simulation order. Either way
the run is one contiguous stretch shorter than a year, so it starts right after the longest gap
of the circular calendar (a whole-year run is taken to start on 1 January).

Columns
-------
``t_in``: floor-area-weighted mean of ``Zone Mean Air Temperature``; ``q_occ``: sum of ``Zone
People Sensible Heating Rate``; ``q_light``: sum of ``Zone Lights Total Heating Rate``;
``q_hvac``: ideal-loads sensible heating minus cooling plus radiant-system heating minus
cooling (``Zone Radiant HVAC Heating/Cooling Rate``), summed over the building, 0 where the
model has no HVAC at all (a model without HVAC truly delivers none); ``t_out``, ``dni``,
``dhi``, ``wind_speed``: the ``Site`` weather variables; ``ghi = dhi + dni · sin(altitude)``
with the ``Site Solar Altitude Angle`` EnergyPlus used for the same timestep. EnergyPlus
evaluates the sun at the END of each timestep, 15 min (one step) after the contract row time
and 7.5 min after the interval's middle: a solar model on pvlib that places the sun at the row
time or the middle of the interval sees it slightly earlier than EnergyPlus did.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from rcengine.columns import (
    DHI,
    DNI,
    GHI,
    Q_HVAC,
    Q_LIGHT,
    Q_OCC,
    T_IN,
    T_OUT,
    TIME,
    WIND_SPEED,
)

ZONE_AIR = "Zone Mean Air Temperature"
PEOPLE = "Zone People Sensible Heating Rate"
LIGHTS = "Zone Lights Total Heating Rate"
IDEAL_HEATING = "Zone Ideal Loads Zone Sensible Heating Rate"
IDEAL_COOLING = "Zone Ideal Loads Zone Sensible Cooling Rate"
RADIANT_HEATING = "Zone Radiant HVAC Heating Rate"
RADIANT_COOLING = "Zone Radiant HVAC Cooling Rate"
SITE = {
    T_OUT: "Site Outdoor Air Drybulb Temperature",
    DNI: "Site Direct Solar Radiation Rate per Area",
    DHI: "Site Diffuse Solar Radiation Rate per Area",
    WIND_SPEED: "Site Wind Speed",
}
SOLAR_ALTITUDE = "Site Solar Altitude Angle"

# Decimals of the written CSV: 0.001 °C, 0.1 W, 0.1 W/m², 0.01 m/s.
DECIMALS = {
    T_IN: 3,
    T_OUT: 3,
    GHI: 1,
    DNI: 1,
    DHI: 1,
    Q_HVAC: 1,
    Q_OCC: 1,
    Q_LIGHT: 1,
    WIND_SPEED: 2,
}
CONTRACT_ORDER = (T_IN, T_OUT, GHI, DNI, DHI, Q_HVAC, Q_OCC, Q_LIGHT, WIND_SPEED)

_HEADER = re.compile(r"^(?P<key>.*?):(?P<var>[^:\[]+?) \[(?P<unit>[^\]]*)\]\((?P<freq>[^)]*)\)$")
_STAMP = re.compile(r"^\s*(\d{1,2})/(\d{1,2})\s+(\d{1,2}):(\d{2}):(\d{2})\s*$")
# A leap reference year, so that 02/29 of a leap run has a place on the circular calendar.
_REFERENCE_YEAR = 2000


def read_eplusout(
    path: str | Path,
    zones: Mapping[str, float] | None = None,
    *,
    year: int,
    tz_offset_h: float,
) -> pd.DataFrame:
    """Contract frame from an EnergyPlus timestep CSV.

    Parameters
    ----------
    path : ``eplusout.csv`` with timestep (or regular) frequency outputs.
    zones : zone name → floor area, the weights of ``t_in``. [m²] Names match EnergyPlus's
        (case-insensitive). None: every zone in the file, which must then be only one.
    year : calendar year of the first simulated day (the CSV has none).
    tz_offset_h : offset of the model's standard time from UTC, hours east (``Site:Location``
        time zone; +1 for Torino). [h]

    Returns
    -------
    DataFrame indexed by UTC times (start of each interval) with ``t_in``, ``t_out``, ``ghi``,
    ``dni``, ``dhi``, ``q_hvac`` and, when the model has them, ``q_occ``, ``q_light``,
    ``wind_speed``. [°C, W/m², W, m/s]

    Raises
    ------
    ValueError : a needed variable is missing, a zone is unknown, or the steps are irregular.
    """
    raw, columns, local, step = _read_in_order(path, year)
    averaged = _averaged_variables(raw, columns)
    t_in = _zone_temperature(raw, columns, zones)

    # Averages belong to the interval that ends at their stamp; the temperature to its stamp.
    inputs = pd.DataFrame(averaged, index=local - step)
    state = pd.Series(t_in, index=local, name=T_IN)
    frame = inputs.join(state, how="inner")
    frame.index = _utc(frame.index, tz_offset_h)
    return frame[[c for c in CONTRACT_ORDER if c in frame.columns]]


def read_rates(path: str | Path, variable: str, *, year: int, tz_offset_h: float) -> pd.DataFrame:
    """One averaged EnergyPlus variable (e.g. ``Zone Ideal Loads Zone Sensible Heating Rate``)
    of every key that reports it, one column per key (upper case, as EnergyPlus writes it),
    indexed by the UTC start of each interval. ``year`` and ``tz_offset_h`` as for
    :func:`read_eplusout`.

    Raises
    ------
    ValueError : no key reports ``variable``, or the steps are irregular.
    """
    raw, columns, local, step = _read_in_order(path, year)
    rates = _select(raw, columns, variable)
    if rates.empty:
        raise ValueError(f"eplusout.csv has no '{variable}' output")
    rates.index = _utc(local - step, tz_offset_h)
    return rates


def write_contract_csv(frame: pd.DataFrame, path: str | Path, tz_offset_h: float) -> None:
    """Write a contract frame as the CSV of CONTRACT.md §1.

    Times in ISO 8601 at the site's standard-time offset (``2017-01-09T06:15:00+01:00``);
    values rounded to ``DECIMALS`` (0.001 °C, 0.1 W, 0.1 W/m²).
    """
    offset = pd.Timedelta(hours=tz_offset_h)
    sign = "+" if offset >= pd.Timedelta(0) else "-"
    minutes = int(abs(offset).total_seconds() // 60)
    suffix = f"{sign}{minutes // 60:02d}:{minutes % 60:02d}"
    local = frame.index.tz_convert("UTC").tz_localize(None) + offset
    out = pd.DataFrame({TIME: local.strftime("%Y-%m-%dT%H:%M:%S") + suffix})
    for name in frame.columns:
        out[name] = _compact(frame[name].to_numpy(dtype=float), DECIMALS.get(name, 3))
    out.to_csv(path, index=False)


def _compact(values: np.ndarray, decimals: int) -> list[str]:
    """Fixed decimals without trailing zeros ("21", "14.35", "0"); NaN as an empty field."""
    rounded = values.round(decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
    return ["" if np.isnan(v) else f"{v:.{decimals}f}".rstrip("0").rstrip(".") for v in rounded]


# --- helpers --------------------------------------------------------------------------------


def _read_in_order(
    path: str | Path, year: int
) -> tuple[pd.DataFrame, list[tuple[str, str]], pd.DatetimeIndex, pd.Timedelta]:
    """Rows in simulation order, (key, variable) of each data column, local standard-time end
    of each row's timestep, the timestep."""
    raw = pd.read_csv(path)
    ends, order = _end_times(raw.iloc[:, 0], year)
    raw = raw.iloc[order].reset_index(drop=True)
    step = _regular_step(ends)
    return raw, _parse_header(raw.columns[1:]), pd.DatetimeIndex(ends), step


def _utc(local: pd.DatetimeIndex, tz_offset_h: float) -> pd.DatetimeIndex:
    """Local standard times as a UTC index named ``time``."""
    out = (local - pd.Timedelta(hours=tz_offset_h)).tz_localize("UTC")
    out.name = TIME
    return out


def _parse_header(names: pd.Index) -> list[tuple[str, str]]:
    """(key, variable) of each data column, e.g. ("WEST ROOM", "Zone Mean Air Temperature")."""
    parsed = []
    for name in names:
        m = _HEADER.match(str(name).strip())
        if m is None:
            raise ValueError(f"unexpected EnergyPlus column {name!r}")
        parsed.append((m["key"].strip().upper(), m["var"].strip()))
    return parsed


def _end_times(stamps: pd.Series, year: int) -> tuple[np.ndarray, np.ndarray]:
    """Local end-of-timestep times in simulation order, and the row order giving it."""
    parts = stamps.astype(str).str.extract(_STAMP)
    bad = parts[0].isna()
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ValueError(f"row {row}: unreadable EnergyPlus time {stamps.iloc[row]!r}")
    month, day, hour, minute, second = (parts[i].astype(int).to_numpy() for i in range(5))
    seconds = hour * 3600 + minute * 60 + second
    reference = (
        pd.to_datetime({"year": _REFERENCE_YEAR, "month": month, "day": day})
        + pd.to_timedelta(seconds, unit="s")
    ).to_numpy()
    order = np.argsort(reference, kind="stable")
    ordered = reference[order]
    if len(np.unique(ordered)) < len(ordered):
        raise ValueError("repeated EnergyPlus times: runs longer than a year are not supported")
    year_span = np.timedelta64(366, "D")
    gaps = np.diff(np.concatenate([ordered, ordered[:1] + year_span]))
    start = (int(np.argmax(gaps)) + 1) % len(ordered)
    order = np.roll(order, -start)
    # Calendar of the run: the year steps up each time the month-day goes back.
    month, day, seconds = month[order], day[order], seconds[order]
    key = month * 100 + day + seconds / 86400.0
    years = year + np.concatenate([[0], np.cumsum(np.diff(key) < 0)])
    ends = (
        pd.to_datetime({"year": years, "month": month, "day": day})
        + pd.to_timedelta(seconds, unit="s")
    ).to_numpy()
    return ends, order


def _regular_step(ends: np.ndarray) -> pd.Timedelta:
    steps = np.diff(ends)
    if len(steps) == 0 or np.any(steps != steps[0]):
        raise ValueError("EnergyPlus times are not on a regular step (report at Timestep)")
    return pd.Timedelta(steps[0])


def _select(raw: pd.DataFrame, columns: list[tuple[str, str]], variable: str) -> pd.DataFrame:
    """The columns of one variable, named by their keys (zone or equipment names)."""
    picked = [i for i, (_, var) in enumerate(columns) if var == variable]
    return raw.iloc[:, [i + 1 for i in picked]].set_axis([columns[i][0] for i in picked], axis=1)


def _zone_temperature(
    raw: pd.DataFrame, columns: list[tuple[str, str]], zones: Mapping[str, float] | None
) -> np.ndarray:
    temps = _select(raw, columns, ZONE_AIR)
    if temps.empty:
        raise ValueError(f"eplusout.csv has no '{ZONE_AIR}' output")
    if zones is None:
        if temps.shape[1] > 1:
            raise ValueError(
                f"several zones {sorted(temps.columns)}: give their floor areas as `zones`"
            )
        return temps.iloc[:, 0].to_numpy(dtype=float)
    areas = {name.upper(): float(area) for name, area in zones.items()}
    unknown = sorted(set(areas) - set(temps.columns))
    if unknown:
        raise ValueError(f"zones {unknown} not in eplusout.csv (it has {sorted(temps.columns)})")
    weights = np.array([areas[name] for name in areas])
    values = temps[list(areas)].to_numpy(dtype=float)
    return values @ weights / weights.sum()


def _averaged_variables(raw: pd.DataFrame, columns: list[tuple[str, str]]) -> dict:
    out: dict[str, np.ndarray] = {}
    for name, variable in SITE.items():
        site = _select(raw, columns, variable)
        if not site.empty:
            out[name] = site.iloc[:, 0].to_numpy(dtype=float)
    for name in (T_OUT, DNI, DHI):
        if name not in out:
            raise ValueError(f"eplusout.csv has no '{SITE[name]}' output")
    altitude = _select(raw, columns, SOLAR_ALTITUDE)
    if altitude.empty:
        raise ValueError(f"eplusout.csv has no '{SOLAR_ALTITUDE}' output (needed for ghi)")
    sin_altitude = np.clip(np.sin(np.radians(altitude.iloc[:, 0].to_numpy(dtype=float))), 0, 1)
    out[GHI] = out[DHI] + out[DNI] * sin_altitude

    heating = sum(_select(raw, columns, v).sum(axis=1) for v in (IDEAL_HEATING, RADIANT_HEATING))
    cooling = sum(_select(raw, columns, v).sum(axis=1) for v in (IDEAL_COOLING, RADIANT_COOLING))
    out[Q_HVAC] = (heating - cooling).to_numpy(dtype=float)
    for name, variable in ((Q_OCC, PEOPLE), (Q_LIGHT, LIGHTS)):
        gains = _select(raw, columns, variable)
        if not gains.empty:
            out[name] = gains.sum(axis=1).to_numpy(dtype=float)
    return out
