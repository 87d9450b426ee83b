"""The two measured buildings: sizes, steps, units against the raw files, the inputs as step means,
and the chosen clocks."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from pvlib.solarposition import get_solarposition

from rcengine.building import Building
from rcengine.io.measured import read_armadillo, read_syslab
from rcengine.io.timeseries import validate_frame

SYSLAB = "measured/syslab_inputPRBS1.csv"
ARMADILLO = "measured/armadillo_data_H2.csv"


@pytest.fixture(scope="module")
def syslab(shared_data: Path) -> pd.DataFrame:
    return read_syslab(shared_data / SYSLAB)


@pytest.fixture(scope="module")
def armadillo(shared_data: Path) -> pd.DataFrame:
    return read_armadillo(shared_data / ARMADILLO)


def first_line(path: Path, sep: str) -> list[float]:
    return [float(v) for v in path.read_text().splitlines()[1].split(sep)]


def steps_s(frame: pd.DataFrame) -> set[float]:
    return set(np.diff(frame.index.asi8) / 1e9)


def sun_fit(frame: pd.DataFrame, building: Building, shift_h: float) -> float:
    """Correlation of the irradiance with sin(sun elevation) at mid-interval, clock shifted."""
    step = frame.index[1] - frame.index[0]
    times = frame.index + pd.Timedelta(hours=shift_h) + step / 2
    loc = building.location
    elevation = get_solarposition(times, loc.latitude, loc.longitude)["elevation"].to_numpy()
    return float(np.corrcoef(np.sin(np.radians(np.clip(elevation, 0, None))), frame["ghi"])[0, 1])


# --- SYSLAB -----------------------------------------------------------------------------------
def test_syslab_rows_step_and_span(syslab):
    assert len(syslab) == 1691
    assert steps_s(syslab) == {300.0}
    assert syslab.index[0] == pd.Timestamp("2009-02-05T14:26:00Z")
    assert syslab.index[-1] - syslab.index[0] == pd.Timedelta(minutes=5 * 1690)
    assert list(syslab.columns) == ["t_in", "t_out", "ghi", "q_hvac"]


def test_syslab_units_against_the_raw_file(syslab, shared_data):
    t, ta, ps, ph, yti = first_line(shared_data / SYSLAB, ";")
    assert t == 0.0
    first = syslab.iloc[0]
    assert first["t_out"] == ta and first["t_in"] == yti
    assert first["ghi"] == pytest.approx(ps * 1000.0)  # kW/m² → W/m²
    assert first["q_hvac"] == pytest.approx(ph * 1000.0)  # kW → W


def test_syslab_value_ranges(syslab, shared_data):
    raw = pd.read_csv(shared_data / SYSLAB, sep=";")
    assert raw["Ps"].min() < 0  # night-time sensor offset in the raw file ...
    assert syslab["ghi"].min() == 0.0  # ... clipped, being within the noise level
    assert 10 < syslab["t_in"].min() < syslab["t_in"].max() < 25  # February, heated office
    assert -5 < syslab["t_out"].min() < syslab["t_out"].max() < 10
    assert syslab["q_hvac"].max() == pytest.approx(raw["Ph"].max() * 1000.0)
    assert syslab["q_hvac"].min() >= 0


def test_syslab_clock_is_utc(syslab, project_data):
    building = Building.from_json(project_data / "measured" / "syslab.json")
    chosen = sun_fit(syslab, building, 0.0)
    assert chosen > max(sun_fit(syslab, building, -1.0), sun_fit(syslab, building, 1.0))


# --- Armadillo --------------------------------------------------------------------------------
def test_armadillo_rows_step_and_span(armadillo):
    assert len(armadillo) == 233
    assert steps_s(armadillo) == {1800.0}
    assert armadillo.index[0] == pd.Timestamp("2015-08-18T22:00:00Z")  # local midnight, UTC+2
    assert armadillo.index[-1] - armadillo.index[0] == pd.Timedelta(seconds=417600)


def test_armadillo_units_against_the_raw_file(armadillo, shared_data):
    raw = pd.read_csv(shared_data / ARMADILLO)
    assert raw["Time"].iloc[0] == 0.0
    np.testing.assert_array_equal(armadillo["t_in"], raw["T_int"])  # samples at t, unchanged
    for column, source in [("t_out", "T_ext"), ("ghi", "I_sol"), ("q_hvac", "P_hea")]:
        samples = raw[source].to_numpy()
        assert armadillo[column].iloc[0] == pytest.approx((samples[0] + samples[1]) / 2)
        assert armadillo[column].iloc[-1] == samples[-1]


def test_armadillo_inputs_become_means_of_the_interpolated_samples(tmp_path):
    """Inputs: (s_k + s_k+1)/2, the mean over [t_k, t_k+1) of the samples joined linearly; the
    last row's samples held; the indoor temperature left as the sample at t."""
    csv = tmp_path / "box.csv"
    csv.write_text(
        "Time,T_ext,P_hea,I_sol,T_int\n"
        "0.0,10.0,0.0,0.0,20.0\n"
        "1800.0,12.0,1980.0,100.0,20.5\n"
        "3600.0,11.0,1920.0,300.0,21.5\n"
    )
    frame = read_armadillo(csv)
    assert frame.index[1] - frame.index[0] == pd.Timedelta(minutes=30)
    assert frame["t_in"].tolist() == [20.0, 20.5, 21.5]
    assert frame["t_out"].tolist() == [11.0, 11.5, 11.0]
    assert frame["q_hvac"].tolist() == [990.0, 1950.0, 1920.0]
    assert frame["ghi"].tolist() == [50.0, 200.0, 300.0]


def test_armadillo_value_ranges(armadillo):
    assert 25 < armadillo["t_in"].min() < armadillo["t_in"].max() < 45  # heated in summer
    assert 5 < armadillo["t_out"].min() < armadillo["t_out"].max() < 35
    assert 900 < armadillo["ghi"].max() < 1100  # clear midday sun on a horizontal sensor
    # Samples in 60 W steps, so their pairwise means in 30 W steps.
    assert set(np.unique(armadillo["q_hvac"])) <= set(np.arange(0.0, 2500.0, 30.0))


def test_armadillo_clock_is_french_summer_time(armadillo, project_data):
    building = Building.from_json(project_data / "measured" / "armadillo.json")
    chosen = sun_fit(armadillo, building, 0.0)
    assert chosen > max(sun_fit(armadillo, building, -1.0), sun_fit(armadillo, building, 1.0))


# --- both -------------------------------------------------------------------------------------
def test_frames_pass_the_contract_validation(syslab, armadillo):
    for frame in (syslab, armadillo):
        raw = frame.reset_index()
        pd.testing.assert_frame_equal(validate_frame(raw), frame)


def test_start_needs_an_offset(shared_data):
    with pytest.raises(ValueError, match="UTC offset"):
        read_syslab(shared_data / SYSLAB, start="2009-02-05T14:26:00")


def test_building_files_load_with_their_notes(project_data):
    for name, latitude in [("syslab", 55.6867), ("armadillo", 45.644)]:
        path = project_data / "measured" / f"{name}.json"
        building = Building.from_json(path)
        assert building.location.latitude == latitude
        assert json.loads(path.read_text())["notes"]  # assumptions stated
    assert Building.from_json(project_data / "measured" / "armadillo.json").floor_area == 42.0
