"""EPW reader on the Torino IWEC file: size, site, energy, and the start-of-interval shift."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from zoneinfo import ZoneInfo

import numpy as np
import pandas as pd
import pytest

from rcengine.exceptions import DataValidationError
from rcengine.io.epw import read_epw

TORINO = "weather/ITA_Torino.160590_IWEC.epw"
HEADER_LINES = 8
GHI_FIELD, TEMP_FIELD = 13, 6  # 0-based positions in an EPW data line


@pytest.fixture(scope="module")
def torino(shared_data: Path) -> Path:
    return shared_data / TORINO


@pytest.fixture(scope="module")
def hourly(torino: Path):
    return read_epw(torino)


def data_lines(path: Path) -> list[list[str]]:
    return [line.split(",") for line in path.read_text().splitlines()[HEADER_LINES:]]


def test_one_year_of_hourly_rows_on_a_utc_index(hourly):
    frame, _ = hourly
    assert len(frame) == 8760
    assert list(frame.columns) == ["t_out", "ghi", "dni", "dhi", "wind_speed"]
    assert frame.index.name == "time" and str(frame.index.tz) == "UTC"
    assert (np.diff(frame.index.asi8) == 3600 * 10**9).all()
    # First row: 1 January 00:00 local standard time (UTC+1) is 31 December 23:00 UTC.
    assert frame.index[0] == pd.Timestamp("2016-12-31T23:00Z")


def test_location_from_the_header(hourly):
    _, location = hourly
    assert (location.latitude, location.longitude, location.altitude) == (45.22, 7.65, 287.0)
    assert location.timezone == "Etc/GMT-1"
    offset = datetime(2017, 7, 1, tzinfo=ZoneInfo(location.timezone)).utcoffset()
    assert offset.total_seconds() == 3600.0  # UTC+1 all year: standard time, as EPW stamps


def test_annual_irradiation_matches_the_file_and_the_climate(hourly, torino):
    frame, _ = hourly
    from_file = sum(float(fields[GHI_FIELD]) for fields in data_lines(torino))  # Wh/m²
    assert frame["ghi"].sum() == pytest.approx(from_file)  # 1-h rows: W/m² × 1 h = Wh/m²
    # Torino, horizontal: ~1,300 kWh/m² a year in this typical year (PVGIS: ~1,400).
    assert 1150.0 < frame["ghi"].sum() / 1000.0 < 1550.0


def test_row_time_is_the_start_of_the_interval(hourly, torino):
    frame, _ = hourly
    lines = {(int(f[1]), int(f[2]), int(f[3])): f for f in data_lines(torino)}
    hour_9, hour_10 = lines[(1, 1, 9)], lines[(1, 1, 10)]
    # Hand-read: "1986,1,1,10,60,...,1.6,0.9,95,97000,247,1415,294,30,0,30,..." — the 30 Wh/m²
    # fell during 09:00–10:00 local (08:00–09:00 UTC); the temperature is 1.5 °C at 09:00 and
    # 1.6 °C at 10:00 local.
    assert (float(hour_10[GHI_FIELD]), float(hour_9[TEMP_FIELD])) == (30.0, 1.5)
    row = frame.loc[pd.Timestamp("2017-01-01T08:00Z")]
    assert row["ghi"] == 30.0
    assert row["t_out"] == pytest.approx((1.5 + 1.6) / 2)  # mean over the hour of the line
    assert frame.loc[pd.Timestamp("2017-01-01T07:00Z"), "ghi"] == float(hour_9[GHI_FIELD])


def test_quarter_hours_keep_each_hour_and_interpolate_temperature(hourly, torino):
    frame, _ = hourly
    fine, _ = read_epw(torino, step_s=900)
    assert len(fine) == 4 * 8760 and fine.index[0] == frame.index[0]
    per_hour = {c: fine[c].to_numpy().reshape(-1, 4).mean(axis=1) for c in fine.columns}
    for column in frame.columns:  # energy of every hour, and every hourly mean, unchanged
        np.testing.assert_allclose(per_hour[column], frame[column].to_numpy(), atol=1e-12)
    # 08:00–08:15 UTC: the straight line from 1.5 °C (08:00) to 1.6 °C (09:00) at 08:07:30.
    assert fine.loc[pd.Timestamp("2017-01-01T08:00Z"), "t_out"] == pytest.approx(1.5125)
    assert (fine.loc["2017-01-01T08:00Z":"2017-01-01T08:45Z", "ghi"] == 30.0).all()


@pytest.mark.parametrize("step_s", [30, 420, 7200])
def test_invalid_step_is_refused(torino, step_s):
    with pytest.raises(ValueError, match="step_s"):
        read_epw(torino, step_s=step_s)


def _edited_copy(torino: Path, tmp_path: Path, tz: str, bad_row: int | None = None) -> Path:
    lines = torino.read_text().splitlines()
    location = lines[0].split(",")
    location[8] = tz
    lines[0] = ",".join(location)
    if bad_row is not None:
        fields = lines[HEADER_LINES + bad_row].split(",")
        fields[GHI_FIELD] = "9999"  # EPW "missing"
        lines[HEADER_LINES + bad_row] = ",".join(fields)
    path = tmp_path / "edited.epw"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_western_zone_and_half_hour_offset(torino, tmp_path):
    frame, location = read_epw(_edited_copy(torino, tmp_path, "-5.0"))
    assert location.timezone == "Etc/GMT+5"
    assert frame.index[0] == pd.Timestamp("2017-01-01T05:00Z")
    with pytest.raises(ValueError, match="not a whole hour"):
        read_epw(_edited_copy(torino, tmp_path, "5.5"))


def test_missing_code_names_row_and_line(torino, tmp_path):
    with pytest.raises(DataValidationError) as caught:
        read_epw(_edited_copy(torino, tmp_path, "1.0", bad_row=100))
    (problem,) = caught.value.problems
    assert (problem.row, problem.column) == (100, "ghi")
    assert "line 109 of the file" in problem.message
