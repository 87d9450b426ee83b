"""From an IDF to the committed files: simulate, convert, trim to the period, write CSV / JSON."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Iterable, Mapping
from datetime import timedelta
from pathlib import Path

import pandas as pd

from rcengine.building import Building
from rcengine.io.energyplus import read_eplusout, read_rates, write_contract_csv

from .geometry import VerticalRect
from .idf import RunPeriod, SiteInfo
from .run import WEATHER, run_energyplus

TIMEZONE = "Europe/Rome"


def simulate(
    idf_text: str, site: SiteInfo, period: RunPeriod, zones: Mapping[str, float] | None = None
) -> pd.DataFrame:
    """Run EnergyPlus on the Torino weather and return the contract frame of exactly ``period``
    (UTC index), standard-time days of the site (``simulate_with_rates`` for another weather or
    civil days)."""
    return simulate_with_rates(idf_text, site, period, zones)[0]


def simulate_with_rates(
    idf_text: str,
    site: SiteInfo,
    period: RunPeriod,
    zones: Mapping[str, float] | None = None,
    epw: Path = WEATHER,
    timezone: str | None = None,
    rates: Iterable[str] = (),
) -> tuple[pd.DataFrame, dict[str, pd.DataFrame]]:
    """Run EnergyPlus on the weather ``epw``; the contract frame of exactly ``period`` (UTC
    index), whose days are local civil days of ``timezone`` (IANA) if given, else standard-time
    days of the site, and each variable of ``rates`` that the run reports, one column per key
    (``read_rates``), on the same rows."""
    with tempfile.TemporaryDirectory(prefix="eplus-") as tmp:
        csv = run_energyplus(idf_text, Path(tmp), epw)
        year = period.simulated[0].year
        frame = read_eplusout(csv, zones, year=year, tz_offset_h=site.tz_offset_h)
        reported = {
            v: read_rates(csv, v, year=year, tz_offset_h=site.tz_offset_h).loc[frame.index]
            for v in rates
        }
    frame = trim(frame, period, site.tz_offset_h, timezone)
    return frame, {v: r.loc[frame.index] for v, r in reported.items()}


def trim(
    frame: pd.DataFrame, period: RunPeriod, tz_offset_h: float, timezone: str | None = None
) -> pd.DataFrame:
    """Rows whose start lies on the period's days — local standard-time days, or the civil
    days of ``timezone`` (IANA) if given; all must be there."""
    zone = timezone or timezone_of_offset(tz_offset_h)
    start = pd.Timestamp(period.first_day).tz_localize(zone).tz_convert("UTC")
    end = pd.Timestamp(period.last_day + timedelta(days=1)).tz_localize(zone).tz_convert("UTC")
    keep = (frame.index >= start) & (frame.index < end)
    out = frame[keep]
    expected = pd.date_range(start, end, freq=frame.index[1] - frame.index[0], inclusive="left")
    if len(out) != len(expected) or not (out.index == expected).all():
        raise RuntimeError(
            f"EnergyPlus output covers {len(out)} of the {len(expected)} rows of "
            f"{period.first_day} – {period.last_day}"
        )
    return out


def timezone_of_offset(tz_offset_h: float) -> str:
    """The fixed-offset IANA zone of a standard time ``tz_offset_h`` hours east of UTC."""
    if tz_offset_h != int(tz_offset_h):
        raise ValueError(f"no Etc/GMT zone for a UTC offset of {tz_offset_h} h")
    return f"Etc/GMT{-int(tz_offset_h):+d}"


def write_csv(frame: pd.DataFrame, path: Path, site: SiteInfo) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_contract_csv(frame, path, site.tz_offset_h)


def building_description(
    name: str,
    site: SiteInfo,
    *,
    floor_area: float,
    volume: float,
    wall_area: float,
    internal_mass_area: float,
    windows: Iterable[VerticalRect],
    walls: Iterable[VerticalRect],
    roof_area: float = 0.0,
    timezone: str = TIMEZONE,
) -> dict:
    """Building JSON (CONTRACT.md §2); ``walls`` are the gross exterior walls, ``windows`` the
    glazing in them: the JSON lists the glazing and the net opaque area per orientation, plus
    a flat roof (tilt 0) of ``roof_area`` where the roof is exposed to sun and sky. [m²]
    ``timezone``: IANA zone of the site's civil time."""
    windows, walls = list(windows), list(walls)
    glazing = _by_azimuth(windows)
    opaque = {az: area - glazing.get(az, 0.0) for az, area in _by_azimuth(walls).items()}
    data = {
        "name": name,
        "location": {
            "latitude": site.latitude,
            "longitude": site.longitude,
            "altitude": site.elevation,
            "timezone": timezone,
        },
        "floor_area": round(floor_area, 2),
        "volume": round(volume, 2),
        "wall_area": round(wall_area, 2),
        "internal_mass_area": round(internal_mass_area, 2),
        "windows": _surfaces(glazing),
        "walls": _surfaces(opaque)
        + ([{"azimuth": 180.0, "tilt": 0.0, "area": round(roof_area, 2)}] if roof_area else []),
    }
    Building.from_dict(data)  # what we commit must pass the engine's own validation
    return data


def write_json(data: dict | list, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def _by_azimuth(rects: Iterable[VerticalRect]) -> dict[float, float]:
    out: dict[float, float] = {}
    for r in rects:
        az = round(r.azimuth, 1) % 360.0
        out[az] = out.get(az, 0.0) + r.area
    return out


def _surfaces(areas: dict[float, float]) -> list[dict]:
    return [
        {"azimuth": az, "tilt": 90.0, "area": round(area, 2)}
        for az, area in sorted(areas.items())
        if area > 0.0
    ]
