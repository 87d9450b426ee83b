"""EnergyPlus reader (rcengine.io.energyplus) and the committed EnergyPlus data sets."""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rcengine.building import Building
from rcengine.columns import CLOUD_COVER, COLUMNS, TIME
from rcengine.io.energyplus import read_eplusout, write_contract_csv

CONTRACT_HEADER = "time,t_in,t_out,ghi,dni,dhi,q_hvac,q_occ,q_light,wind_speed"
# Effect vocabulary of CONTRACT.md §3.
EFFECTS = {
    "window_solar_gains",
    "opaque_solar_gains",
    "wind_infiltration",
    "ventilation_schedule",
    "ground_coupling",
    "sky_radiation",
    "unmetered_gains",
    "thermal_mass",
    "emitter_dynamics",
}

# --- a hand-made eplusout.csv ------------------------------------------------------------------
# Four timesteps of a run crossing the new year (year of the first day: 2016), UTC+1.
# Simulation order k = 0..3; every value is tied to k so the test sees where each stamp lands.
STAMPS = [" 12/31  23:45:00", " 12/31  24:00:00", " 01/01  00:15:00", " 01/01  00:30:00"]
HEADER = [
    "Date/Time",
    "Environment:Site Outdoor Air Drybulb Temperature [C](TimeStep)",
    "Environment:Site Wind Speed [m/s](TimeStep)",
    "Environment:Site Diffuse Solar Radiation Rate per Area [W/m2](TimeStep)",
    "Environment:Site Direct Solar Radiation Rate per Area [W/m2](TimeStep)",
    "Environment:Site Solar Altitude Angle [deg](TimeStep)",
    "ZONE A:Zone People Sensible Heating Rate [W](TimeStep)",
    "ZONE B:Zone People Sensible Heating Rate [W](TimeStep)",
    "ZONE A:Zone Lights Total Heating Rate [W](TimeStep)",
    "ZONE B:Zone Lights Total Heating Rate [W](TimeStep)",
    "ZONE A:Zone Mean Air Temperature [C](TimeStep)",
    "ZONE B:Zone Mean Air Temperature [C](TimeStep)",
    "ZONE A IDEAL LOADS:Zone Ideal Loads Zone Sensible Heating Rate [W](TimeStep)",
    "ZONE A IDEAL LOADS:Zone Ideal Loads Zone Sensible Cooling Rate [W](TimeStep)",
    "ZONE B IDEAL LOADS:Zone Ideal Loads Zone Sensible Heating Rate [W](TimeStep)",
    "ZONE B IDEAL LOADS:Zone Ideal Loads Zone Sensible Cooling Rate [W](TimeStep)",
]
ALTITUDE = [30.0, -5.0, 90.0, 10.0]  # [°]; -5: EnergyPlus interpolates some beam below sunrise
DNI = [400.0, 50.0, 200.0, 0.0]
DHI = [100.0, 10.0, 20.0, 0.0]


def _row(k: int) -> list[object]:
    return [
        STAMPS[k],
        10.0 + k,
        3.0 + k,
        DHI[k],
        DNI[k],
        ALTITUDE[k],
        70.0 + k,
        30.0,
        50.0,
        25.0 + k,
        20.0 + k,
        16.0 + k,
        1000.0 + k,
        0.0,
        500.0,
        200.0,
    ]


def _write(path: Path, order: list[int]) -> Path:
    pd.DataFrame([_row(k) for k in order], columns=HEADER).to_csv(path, index=False)
    return path


AREAS = {"Zone A": 300.0, "zone b": 100.0}  # names match case-insensitively


@pytest.fixture
def sorted_csv(tmp_path: Path) -> Path:
    """EnergyPlus's own CSV writer sorts rows by their MM/DD text: January before December."""
    return _write(tmp_path / "eplusout.csv", [2, 3, 0, 1])


def test_rows_start_at_interval_start_in_utc(sorted_csv: Path) -> None:
    frame = read_eplusout(sorted_csv, AREAS, year=2016, tz_offset_h=1.0)
    # Averages reach back one step, temperatures stay: rows where both exist are local
    # 23:45, 00:00 and 00:15, i.e. 22:45, 23:00 and 23:15 UTC on 31 Dec 2016.
    expected = pd.DatetimeIndex(
        ["2016-12-31 22:45", "2016-12-31 23:00", "2016-12-31 23:15"], tz="UTC"
    )
    assert frame.index.equals(expected)
    assert frame.index.name == TIME


def test_averages_shift_back_one_step_and_temperature_does_not(sorted_csv: Path) -> None:
    frame = read_eplusout(sorted_csv, AREAS, year=2016, tz_offset_h=1.0)
    # Row n holds the temperature stamped at its own time (k = n) and the averages stamped at
    # the end of its interval (k = n + 1).
    t_in = [(300.0 * (20 + n) + 100.0 * (16 + n)) / 400.0 for n in range(3)]  # 19, 20, 21
    np.testing.assert_allclose(frame["t_in"], t_in)
    np.testing.assert_allclose(frame["t_out"], [11.0, 12.0, 13.0])
    np.testing.assert_allclose(frame["wind_speed"], [4.0, 5.0, 6.0])


def test_24h_stamp_is_midnight_of_the_next_day(sorted_csv: Path) -> None:
    frame = read_eplusout(sorted_csv, AREAS, year=2016, tz_offset_h=1.0)
    # "12/31 24:00" (k = 1) is 1 Jan 2017 00:00 local = 31 Dec 23:00 UTC: its temperature is
    # that row's t_in, and its averages belong to the row before.
    midnight = pd.Timestamp("2016-12-31 23:00", tz="UTC")
    assert frame.loc[midnight, "t_in"] == pytest.approx((300 * 21 + 100 * 17) / 400)
    assert frame.loc[midnight - pd.Timedelta("15min"), "t_out"] == pytest.approx(11.0)


def test_gains_and_hvac_are_summed_over_zones(sorted_csv: Path) -> None:
    frame = read_eplusout(sorted_csv, AREAS, year=2016, tz_offset_h=1.0)
    ks = np.array([1, 2, 3])
    np.testing.assert_allclose(frame["q_occ"], 70.0 + ks + 30.0)
    np.testing.assert_allclose(frame["q_light"], 50.0 + 25.0 + ks)
    np.testing.assert_allclose(frame["q_hvac"], 1000.0 + ks + 500.0 - 200.0)


def test_ghi_from_beam_and_diffuse_with_energyplus_sun_altitude(sorted_csv: Path) -> None:
    frame = read_eplusout(sorted_csv, AREAS, year=2016, tz_offset_h=1.0)
    # k = 1: sun below the horizon, its beam adds nothing; k = 2: zenith sun; k = 3: no sun.
    expected = [10.0, 20.0 + 200.0, 0.0]
    np.testing.assert_allclose(frame["ghi"], expected, atol=1e-9)
    np.testing.assert_allclose(frame["dni"], [50.0, 200.0, 0.0])
    np.testing.assert_allclose(frame["dhi"], [10.0, 20.0, 0.0])


def test_radiant_system_power_is_q_hvac(tmp_path: Path) -> None:
    radiant = [
        h.replace(
            "ZONE A IDEAL LOADS:Zone Ideal Loads Zone Sensible", "FLOOR MAT:Zone Radiant HVAC"
        )
        for h in HEADER
    ]
    path = tmp_path / "radiant.csv"
    pd.DataFrame([_row(k) for k in range(4)], columns=radiant).to_csv(path, index=False)
    frame = read_eplusout(path, AREAS, year=2016, tz_offset_h=1.0)
    # Radiant heating (1000 + k) and ideal-loads heating of zone B (500 − 200) add up.
    np.testing.assert_allclose(frame["q_hvac"], 1000.0 + np.array([1, 2, 3]) + 300.0)


def test_simulation_order_gives_the_same_frame(sorted_csv: Path, tmp_path: Path) -> None:
    """ReadVarsESO keeps simulation order; the result must not depend on the row order."""
    chrono = _write(tmp_path / "readvars.csv", [0, 1, 2, 3])
    a = read_eplusout(sorted_csv, AREAS, year=2016, tz_offset_h=1.0)
    b = read_eplusout(chrono, AREAS, year=2016, tz_offset_h=1.0)
    pd.testing.assert_frame_equal(a, b)


def test_zone_errors_name_the_zones(sorted_csv: Path) -> None:
    with pytest.raises(ValueError, match="floor areas"):
        read_eplusout(sorted_csv, None, year=2016, tz_offset_h=1.0)
    with pytest.raises(ValueError, match="HALL"):
        read_eplusout(sorted_csv, {"Hall": 10.0}, year=2016, tz_offset_h=1.0)


def test_irregular_steps_are_rejected(tmp_path: Path) -> None:
    rows = [_row(k) for k in (0, 1, 3)]  # 00:15 missing
    path = tmp_path / "gap.csv"
    pd.DataFrame(rows, columns=HEADER).to_csv(path, index=False)
    with pytest.raises(ValueError, match="regular step"):
        read_eplusout(path, AREAS, year=2016, tz_offset_h=1.0)


def test_contract_csv_has_offset_times_and_rounded_values(tmp_path: Path) -> None:
    index = pd.DatetimeIndex(["2017-01-09 05:00", "2017-01-09 05:15"], tz="UTC")
    frame = pd.DataFrame(
        {"t_in": [19.12345, -0.0001], "ghi": [299.96, 12.34], "q_hvac": [1300.04, 1234.56]},
        index=index,
    )
    path = tmp_path / "out.csv"
    write_contract_csv(frame, path, tz_offset_h=1.0)
    assert path.read_text().splitlines() == [
        "time,t_in,ghi,q_hvac",
        "2017-01-09T06:00:00+01:00,19.123,300,1300",
        "2017-01-09T06:15:00+01:00,0,12.3,1234.6",
    ]


# --- the committed data ----------------------------------------------------------------------
CASES = [
    "plain",
    "window_solar_gains",
    "wind_infiltration",
    "ventilation_schedule",
    "unmetered_gains",
    "ground_coupling",
    "thermal_mass",
    "emitter_dynamics",
    "sky_radiation",
]
ROWS = 182 * 96  # 1 Oct 2016 – 31 Mar 2017, 15 minutes


@cache
def _load(path: Path) -> pd.DataFrame:
    frame = pd.read_csv(path)
    frame.index = pd.DatetimeIndex(pd.to_datetime(frame.pop(TIME), utc=True))
    return frame


def _local(frame: pd.DataFrame) -> pd.DatetimeIndex:
    return frame.index.tz_convert("Etc/GMT-1")  # Torino standard time, no daylight saving


def _committed(project_data: Path) -> list[Path]:
    office = [project_data / "energyplus" / "office" / f"{n}.csv" for n in ("heating", "freefloat")]
    variants = [project_data / "energyplus" / "variants" / c / "data.csv" for c in CASES]
    return office + variants


def test_committed_csvs_have_contract_columns_and_period(project_data: Path) -> None:
    for path in _committed(project_data):
        with path.open() as f:
            assert f.readline().strip() == CONTRACT_HEADER, path
            assert f.readline().startswith("2016-10-01T00:00:00+01:00,"), path
        frame = _load(path)
        assert len(frame) == ROWS, path
        assert (np.diff(frame.index) == pd.Timedelta("15min")).all(), path
        assert _local(frame)[-1] == pd.Timestamp("2017-03-31 23:45", tz="Etc/GMT-1")


def test_committed_values_are_physical(project_data: Path) -> None:
    for path in _committed(project_data):
        frame = _load(path)
        assert not frame.isna().any().any(), path
        # Every contract column but the optional cloud cover, which no export writes.
        for name, column in COLUMNS.items():
            if name == CLOUD_COVER:
                continue
            values = frame[name]
            assert values.between(column.lower, column.upper).all(), (path, name)
        assert (frame["q_hvac"] >= 0.0).all(), path  # heating only


def test_office_heating_holds_the_setpoint_in_office_hours(project_data: Path) -> None:
    frame = _load(project_data / "energyplus" / "office" / "heating.csv")
    local = _local(frame)
    hour = local.hour + local.minute / 60.0
    held = (local.day_of_week < 5) & (hour >= 10) & (hour < 22)
    # Area-weighted setpoint: (21 °C · 840 m² + 18 °C · 210 m²) / 1050 m² = 20.4 °C.
    assert frame["t_in"][held].min() >= 20.3
    # Heating is delivered only while available (weekdays 06-22, Saturdays 06-18).
    available = ((local.day_of_week < 5) & (hour >= 6) & (hour < 22)) | (
        (local.day_of_week == 5) & (hour >= 6) & (hour < 18)
    )
    assert (frame["q_hvac"][~available] == 0.0).all()
    assert frame["q_hvac"][available].mean() > 10e3


def test_sundays_have_no_heating_and_no_people(project_data: Path) -> None:
    for path in _committed(project_data):
        frame = _load(path)
        sunday = _local(frame).day_of_week == 6
        assert sunday.sum() == 26 * 96
        assert (frame["q_hvac"][sunday] == 0.0).all(), path
        assert (frame["q_occ"][sunday] == 0.0).all(), path


def test_freefloat_office_never_heats_and_is_colder(project_data: Path) -> None:
    free = _load(project_data / "energyplus" / "office" / "freefloat.csv")
    heated = _load(project_data / "energyplus" / "office" / "heating.csv")
    assert (free["q_hvac"] == 0.0).all()
    assert free["t_in"].mean() < heated["t_in"].mean() - 5.0
    pd.testing.assert_series_equal(free["t_out"], heated["t_out"])


def test_office_building_matches_the_thesis(project_data: Path) -> None:
    path = project_data / "energyplus" / "office" / "building.json"
    building = Building.from_json(path)
    assert building.floor_area == 1050.0
    assert building.wall_area == 455.0
    assert building.internal_mass_area == 560.0
    assert building.volume == pytest.approx(1050.0 * 3.5)
    assert building.location.timezone == "Europe/Rome"
    assert [(w.azimuth, w.tilt, w.area) for w in building.windows] == [
        (90.0, 90.0, 45.6),
        (270.0, 90.0, 45.6),
    ]
    walls = {w.azimuth: w.area for w in building.walls}
    assert walls == {0.0: 122.5, 90.0: 105.0 - 45.6, 180.0: 122.5, 270.0: 105.0 - 45.6}
    assert math.isclose(sum(walls.values()) + 2 * 45.6, 455.0)


def test_variants_manifest(project_data: Path) -> None:
    root = project_data / "energyplus" / "variants"
    manifest = json.loads((root / "manifest.json").read_text())
    assert [e["case"] for e in manifest] == CASES
    for entry in manifest:
        case = entry["case"]
        Building.from_json(root / case / "building.json")
        if case == "plain":
            assert entry["effect"] is None
            continue
        assert entry["effect"] in EFFECTS
        strength = entry["strength"]
        strong_t = strength["rms_t_in_K"] > 0.5
        strong_q = abs(strength.get("heating_change_pct", 0.0)) > 20.0
        assert strong_t or strong_q, case
    models = {e["case"]: e["model"] for e in manifest}
    assert models["thermal_mass"] == "1r1c"
    assert {m for c, m in models.items() if c != "thermal_mass"} == {"basic"}


def test_window_variant_conceals_its_glazing(project_data: Path) -> None:
    """No variant declares glazing: the window variant's 24 m² east window is in its data only,
    its facade listed whole as opaque wall (60 m², the plain box's)."""
    root = project_data / "energyplus" / "variants"
    for case in CASES:
        building = Building.from_json(root / case / "building.json")
        assert building.windows == ()
        east = sum(w.area for w in building.walls if w.azimuth == 90.0 and w.tilt == 90.0)
        assert east == 60.0, case
