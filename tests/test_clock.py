"""The building's summer-time readings re-aligned with the weather's clock before anything is
judged (``diagnose.clock``): a logger on standard time all year is read as a clock, not as
physics."""

import json

import numpy as np
import pandas as pd
import pytest

from rcengine.building import Building
from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.diagnose.clock import CLOCK_MARGIN, ClockCheck, read_later, realigned, summer_time
from rcengine.io.timeseries import read_timeseries


def _frame() -> pd.DataFrame:
    times = pd.date_range("2017-01-09", periods=8, freq="30min", tz="UTC")
    k = np.arange(8.0)
    return pd.DataFrame(
        {"t_in": 20 + k, "t_out": k, "ghi": 10 * k, "q_hvac": 100 * k, "q_occ": 5 * k},
        index=times,
    )


def test_read_later_moves_the_buildings_readings_and_leaves_the_weather():
    frame = _frame()
    later = read_later(frame, 1.0)
    assert later.index.equals(frame.index[:-2])
    assert later["t_in"].to_numpy() == pytest.approx(frame["t_in"].to_numpy()[2:])
    assert later["q_hvac"].to_numpy() == pytest.approx(frame["q_hvac"].to_numpy()[2:])
    assert later["q_occ"].to_numpy() == pytest.approx(frame["q_occ"].to_numpy()[2:])
    assert later["t_out"].to_numpy() == pytest.approx(frame["t_out"].to_numpy()[:-2])
    earlier = read_later(frame.drop(frame.index[3]), -1.0)
    # Rows whose reading an hour before is missing (the dropped row, the first hour) go.
    assert list(earlier.index) == [frame.index[i] for i in (2, 4, 6, 7)]


def test_a_logger_on_standard_time_is_moved_in_summer_time_alone():
    times = pd.date_range("2016-10-30T00:00", periods=8, freq="30min", tz="Europe/Rome")
    frame = pd.DataFrame({"t_in": np.arange(8.0), "t_out": np.arange(8.0)}, index=times)
    summer = summer_time(frame.index, "Europe/Rome")
    assert summer.tolist() == [True] * 6 + [False] * 2  # 03:00 summer time is 02:00 winter
    moved = realigned(frame, -1.0, "Europe/Rome")
    # Summer rows read an hour earlier (the first hour has no source and goes); winter stays.
    assert moved["t_in"].tolist() == [0.0, 1.0, 2.0, 3.0, 6.0, 7.0]
    assert moved["t_out"].tolist() == [2.0, 3.0, 4.0, 5.0, 6.0, 7.0]
    assert realigned(frame, 0.0, "Europe/Rome") is frame


def test_the_check_reads_its_offset_and_its_margin_in_words():
    kept = ClockCheck(0.0, {-1.0: 0.5, 0.0: 0.4, 1.0: 0.45})
    assert "as stamped" in kept.words() and kept.to_dict()["offset_h"] == 0.0
    check = ClockCheck(-1.0, {-1.0: 0.39, 0.0: 0.45, 1.0: 0.5})
    words = check.words()
    assert "1 h earlier than stamped in summer time" in words and "-13 %" in words
    assert "standard time all year" in words
    assert check.to_dict()["rmse_train_K"] == {"-1": 0.39, "+0": 0.45, "+1": 0.5}
    assert check.to_dict()["margin"] == CLOCK_MARGIN


@pytest.mark.slow
def test_a_logger_on_standard_time_is_re_aligned_and_a_null_stays_clean(project_data):
    """A main-bed null whose logger keeps standard time all year: its summer-time readings are
    stamped an hour early against the weather. The clock check re-aligns them (the training RMSE
    −15 %) and nothing is accepted."""
    case = project_data / "testbed" / "open_plan-chicago-null"
    building = Building.from_json(case / "building.json")
    whole = read_timeseries(case / "data.csv")
    early = read_later(whole, 1.0, summer_time(whole.index, building.location.timezone))
    report = diagnose(early, building, "basic", DiagnoseSettings(workers=1))
    assert report.clock is not None and report.clock.offset_h == -1.0
    rmse = report.clock.rmse_train
    assert rmse[-1.0] < (1 - CLOCK_MARGIN) * rmse[0.0]
    assert not report.accepted
    assert json.loads(report.to_json())["clock"]["offset_h"] == -1.0
