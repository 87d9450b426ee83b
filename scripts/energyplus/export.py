"""From an IDF to the committed files: simulate, convert, trim to the period, write CSV / JSON."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Iterable, Mapping
from datetime import timedelta
from pathlib import Path

import pandas as pd

from rcengine.building import Building
from rcengine.io.energyplus import read_eplusout, write_contract_csv

from .idf import RunPeriod, SiteInfo, VerticalRect
from .run import run_energyplus

TIMEZONE = "Europe/Rome"


def simulate(
    idf_text: str,
    site: SiteInfo,
    period: RunPeriod,
    zones: Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """Run EnergyPlus and return the contract frame of exactly ``period`` (UTC index)."""
    with tempfile.TemporaryDirectory(prefix="eplus-") as tmp:
        csv = run_energyplus(idf_text, Path(tmp))
        frame = read_eplusout(
            csv, zones, year=period.simulated[0].year, tz_offset_h=site.tz_offset_h
        )
    return trim(frame, period, site.tz_offset_h)


def trim(frame: pd.DataFrame, period: RunPeriod, tz_offset_h: float) -> pd.DataFrame:
    """Rows whose local standard-time start lies on the period's days; all must be there."""
    local = frame.index.tz_localize(None) + pd.Timedelta(hours=tz_offset_h)
    start = pd.Timestamp(period.first_day)
    end = pd.Timestamp(period.last_day + timedelta(days=1))
    keep = (local >= start) & (local < end)
    out = frame[keep]
    expected = pd.date_range(start, end, freq=frame.index[1] - frame.index[0], inclusive="left")
    if len(out) != len(expected) or not (local[keep] == expected).all():
        raise RuntimeError(
            f"EnergyPlus output covers {len(out)} of the {len(expected)} rows of "
            f"{period.first_day} – {period.last_day}"
        )
    return out


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
) -> dict:
    """Building JSON (CONTRACT.md §2); ``walls`` are the gross exterior walls, ``windows`` the
    glazing in them: the JSON lists the glazing and the net opaque area per orientation, plus
    a flat roof (tilt 0) of ``roof_area`` where the roof is exposed to sun and sky. [m²]"""
    windows, walls = list(windows), list(walls)
    glazing = _by_azimuth(windows)
    opaque = {az: area - glazing.get(az, 0.0) for az, area in _by_azimuth(walls).items()}
    data = {
        "name": name,
        "location": {
            "latitude": site.latitude,
            "longitude": site.longitude,
            "altitude": site.elevation,
            "timezone": TIMEZONE,
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
        az = round(r.azimuth, 1)
        out[az] = out.get(az, 0.0) + r.area
    return out


def _surfaces(areas: dict[float, float]) -> list[dict]:
    return [
        {"azimuth": az, "tilt": 90.0, "area": round(area, 2)}
        for az, area in sorted(areas.items())
        if area > 0.0
    ]
