"""The committed data sets: the thesis office and the shoebox variants, with their checks.

``make_office`` writes ``office/heating.csv``, ``office/freefloat.csv`` and
``office/building.json``; ``make_variants`` writes ``variants/<case>/data.csv`` and
``building.json`` and updates ``variants/manifest.json``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from . import office, shoebox
from .export import building_description, simulate, write_csv, write_json
from .idf import RunPeriod, SiteInfo

Log = Callable[[str], None]
STEP_H = 0.25
# Area-weighted setpoint of the office: (21 · 840 + 18 · 210) / 1050 m². [°C]
OFFICE_SETPOINT = 20.4


# --- office -----------------------------------------------------------------------------------


def office_frame(
    site: SiteInfo, period: RunPeriod = office.SEASON, heating: bool = True
) -> pd.DataFrame:
    return simulate(office.office_idf(site, period, heating), site, period, office.zone_areas())


def office_building(site: SiteInfo) -> dict:
    return building_description(
        "office-torino",
        site,
        floor_area=office.floor_area(),
        volume=office.volume(),
        wall_area=sum(w.area for w in office.exterior_walls()),
        internal_mass_area=office.INTERNAL_MASS_AREA,
        windows=office.windows(),
        walls=office.exterior_walls(),
    )


def make_office(out: Path, site: SiteInfo, log: Log = print) -> dict[str, float]:
    """Simulate the heated and the free-floating office, write them; return the checks."""
    heating = office_frame(site)
    log(f"office/heating.csv      {len(heating)} rows")
    freefloat = office_frame(site, heating=False)
    log(f"office/freefloat.csv    {len(freefloat)} rows")
    write_csv(heating, out / "office" / "heating.csv", site)
    write_csv(freefloat, out / "office" / "freefloat.csv", site)
    write_json(office_building(site), out / "office" / "building.json")
    checks = office_checks(heating, freefloat, site.tz_offset_h)
    for name, value in checks.items():
        log(f"  {name:32s} {value:10.2f}")
    return checks


def office_checks(
    heating: pd.DataFrame, freefloat: pd.DataFrame, tz_offset_h: float
) -> dict[str, float]:
    """Physics sanity figures of the office (see the docstring of ``office``)."""
    local = _local(heating.index, tz_offset_h)
    t_in = pd.Series(heating["t_in"].to_numpy(), index=local)
    hour = local.hour + local.minute / 60.0
    weekday = local.day_of_week < 5
    held = weekday & (hour >= 10) & (hour < 22)
    ua = office.design_ua()
    daily = (
        pd.DataFrame(
            {
                "q": (heating["q_hvac"] + heating["q_occ"] + heating["q_light"]).to_numpy(),
                "dt": (heating["t_in"] - heating["t_out"]).to_numpy(),
                "ghi": heating["ghi"].to_numpy(),
            },
            index=local,
        )
        .resample("D")
        .mean()
    )
    # Daily balance: gains + heating = UA (t_in - t_out) - A_sol ghi (storage averages out).
    ua_fit, aperture = np.linalg.lstsq(
        daily[["dt", "ghi"]].to_numpy(), daily["q"].to_numpy(), rcond=None
    )[0]
    ff_local = _local(freefloat.index, tz_offset_h)
    february = (ff_local >= "2017-02-01") & (ff_local < "2017-02-14")
    return {
        "heating_peak_kW": heating["q_hvac"].max() / 1e3,
        "heating_capacity_kW": office.HEATING_CAPACITY_W_M2 * office.floor_area() / 1e3,
        "heating_energy_MWh": heating["q_hvac"].sum() * STEP_H / 1e6,
        "heating_energy_kWh_per_m2": heating["q_hvac"].sum() * STEP_H / 1e3 / office.floor_area(),
        "held_share_weekday_10_22": float(np.mean(t_in[held] >= OFFICE_SETPOINT - 0.1)),
        "t_in_weekday_10_22_min_C": float(t_in[held].min()),
        "monday_recovery_median_h": _monday_recovery(t_in),
        "night_drop_22_to_06_mean_K": _night_drop(t_in).mean(),
        "night_drop_22_to_06_max_K": _night_drop(t_in).max(),
        "freefloat_mean_t_in_minus_t_out_K": float((freefloat["t_in"] - freefloat["t_out"]).mean()),
        "freefloat_feb_1_13_min_C": float(freefloat["t_in"][february].min()),
        "freefloat_feb_1_13_max_C": float(freefloat["t_in"][february].max()),
        "ua_design_W_K": sum(ua.values()),
        "ua_daily_regression_W_K": float(ua_fit),
        "solar_aperture_regression_m2": float(-aperture),
    }


def _local(index: pd.DatetimeIndex, tz_offset_h: float) -> pd.DatetimeIndex:
    return index.tz_localize(None) + pd.Timedelta(hours=tz_offset_h)


def _night_drop(t_in: pd.Series) -> np.ndarray:
    """t_in(22:00) − t_in(06:00 next day) over Monday–Thursday nights. [K]"""
    evenings = t_in[
        (t_in.index.hour == 22) & (t_in.index.minute == 0) & (t_in.index.day_of_week < 4)
    ]
    mornings = t_in.reindex(evenings.index + pd.Timedelta(hours=8))
    return evenings.to_numpy() - mornings.to_numpy()


def _monday_recovery(t_in: pd.Series) -> float:
    """Median hours from 06:00 on Mondays until the area-weighted setpoint is reached. [h]"""
    days = t_in.index.normalize().unique()
    hours = []
    for monday in days[days.day_of_week == 0]:
        start = monday + pd.Timedelta(hours=6)
        window = t_in[start : start + pd.Timedelta(hours=8)]
        reached = window[window >= OFFICE_SETPOINT - 0.1]
        if len(reached):
            hours.append((reached.index[0] - start).total_seconds() / 3600.0)
    return float(np.median(hours))


# --- variants ---------------------------------------------------------------------------------


def variant_frames(
    case: shoebox.Case, site: SiteInfo, period: RunPeriod = office.SEASON
) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """The variant's data and its reference run without the effect (None for plain)."""
    data = simulate(case.building.idf(site, period), site, period)
    if case.effect == "emitter_dynamics":
        heat = pd.Series(data["q_hvac"].to_numpy(), index=_local(data.index, site.tz_offset_h))
        replay = shoebox.with_replay(case.building, heat)
        # The replayed heat is the reference's heating, though no HVAC object reports it.
        return data, simulate(replay.idf(site, period), site, period).assign(q_hvac=data["q_hvac"])
    if case.reference is None:
        return data, None
    return data, simulate(case.reference.idf(site, period), site, period)


def strength(data: pd.DataFrame, reference: pd.DataFrame | None) -> dict[str, float]:
    """How much the effect changes t_in and the heating energy against the reference."""
    if reference is None:
        return {}
    diff = data["t_in"] - reference["t_in"]
    out = {
        "rms_t_in_K": float(np.sqrt(np.mean(diff**2))),
        "max_abs_t_in_K": float(diff.abs().max()),
        "heating_kWh": float(data["q_hvac"].sum() * STEP_H / 1e3),
        "heating_kWh_reference": float(reference["q_hvac"].sum() * STEP_H / 1e3),
    }
    if out["heating_kWh_reference"] > 0.0:
        out["heating_change_pct"] = 100.0 * (
            out["heating_kWh"] / out["heating_kWh_reference"] - 1.0
        )
    return {k: round(v, 3) for k, v in out.items()}


def variant_building(case: shoebox.Case, site: SiteInfo) -> dict:
    """Building JSON of a variant. A variant's window is its concealed glazing: the JSON lists the
    facade it is in as opaque wall, since glazing the description declares is given to the base
    model and is not what a diagnosis looks for."""
    box = case.building
    return building_description(
        f"shoebox-{case.name}",
        site,
        floor_area=shoebox.BOX.floor_area,
        volume=shoebox.BOX.volume,
        wall_area=sum(w.area for w in box.walls()),
        internal_mass_area=box.internal_mass_area,
        windows=[],
        walls=box.walls(),
        roof_area=shoebox.BOX.floor_area if box.exposed_roof else 0.0,
    )


def make_variants(
    out: Path, site: SiteInfo, names: Iterable[str] | None = None, log: Log = print
) -> list[dict]:
    """Simulate the chosen cases (all by default), write them, update the manifest."""
    wanted = set(names) if names is not None else {c.name for c in shoebox.CASES}
    manifest_path = out / "variants" / "manifest.json"
    entries = {e["case"]: e for e in _read_manifest(manifest_path)}
    for case in shoebox.CASES:
        if case.name not in wanted:
            continue
        data, reference = variant_frames(case, site)
        write_csv(data, out / "variants" / case.name / "data.csv", site)
        write_json(variant_building(case, site), out / "variants" / case.name / "building.json")
        entries[case.name] = {
            "case": case.name,
            "effect": case.effect,
            "model": case.model,
            "description": case.description,
            "reference": case.reference_description or None,
            "strength": strength(data, reference),
        }
        log(f"variants/{case.name:22s} {json.dumps(entries[case.name]['strength'])}")
    order = [c.name for c in shoebox.CASES]
    manifest = sorted(entries.values(), key=lambda e: order.index(e["case"]))
    write_json(manifest, manifest_path)
    return manifest


def _read_manifest(path: Path) -> list[dict]:
    return json.loads(path.read_text()) if path.exists() else []
