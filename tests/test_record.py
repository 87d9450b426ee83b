"""A record a diagnosis cannot learn from is refused with the reason, before any fit: a stuck
indoor sensor, or no measured days on one side of the train/test boundary."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from rcengine.building import Building
from rcengine.cli import app
from rcengine.columns import T_IN
from rcengine.diagnose import diagnose
from rcengine.exceptions import DataValidationError
from rcengine.io.timeseries import read_timeseries, write_timeseries
from rcengine.record import MIN_T_IN_STD_K, check_diagnosable, t_in_spread

CASE = Path(__file__).resolve().parents[1] / "data" / "testbed" / "light-torino-null"
DAYS = 20


@pytest.fixture(scope="module")
def frame() -> pd.DataFrame:
    """Twenty days of a test-bed building (30-minute rows)."""
    full = read_timeseries(CASE / "data.csv")
    return full[full.index < full.index[0] + pd.Timedelta(days=DAYS)]


@pytest.fixture(scope="module")
def boundary(frame) -> pd.Timestamp:
    return frame.index[0] + pd.Timedelta(days=DAYS / 2)


def test_a_moving_record_passes(frame, boundary):
    assert t_in_spread(frame) > 10 * MIN_T_IN_STD_K
    check_diagnosable(frame, boundary)


def test_a_stuck_sensor_is_refused(frame, boundary):
    stuck = frame.assign(**{T_IN: 20.0 + 0.01 * np.sign(np.sin(np.arange(len(frame))))})
    with pytest.raises(DataValidationError, match="stuck sensor") as refused:
        check_diagnosable(stuck, boundary)
    assert refused.value.problems[0].column == T_IN
    assert "varies by 0.010 K" in str(refused.value)


def test_no_measurement_after_the_boundary_is_refused(frame, boundary):
    blind = frame.assign(**{T_IN: frame[T_IN].where(frame.index < boundary)})
    with pytest.raises(DataValidationError, match=r"0\.0 day\(s\) .* in the test period"):
        check_diagnosable(blind, boundary)


def test_diagnose_refuses_before_fitting(frame):
    building = Building.from_json(CASE / "building.json")
    with pytest.raises(DataValidationError, match="stuck sensor"):
        diagnose(frame.assign(**{T_IN: 21.0}), building)


def test_the_cli_names_the_column_and_writes_no_report(frame, tmp_path):
    data = tmp_path / "stuck.csv"
    write_timeseries(frame.assign(**{T_IN: 21.0}), data, "Europe/Rome")
    report = tmp_path / "report.json"
    result = CliRunner().invoke(
        app,
        ["diagnose", str(data), "--building", str(CASE / "building.json"), "--json", str(report)],
    )
    assert result.exit_code != 0
    assert "column 't_in'" in result.output and "stuck sensor" in result.output
    assert "Traceback" not in result.output
    assert not report.exists()
