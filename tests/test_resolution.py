"""A record finer than the diagnosis needs is averaged into coarser interval means, which keep
every input's heat; a coarser record is left alone."""

import numpy as np
import pandas as pd
import pytest

from rcengine.dataset import Dataset, aggregated


def _frame(step_min: int, rows: int) -> pd.DataFrame:
    times = pd.date_range("2017-01-09 06:05", periods=rows, freq=f"{step_min}min", tz="UTC")
    rng = np.random.default_rng(0)
    return pd.DataFrame(
        {
            "t_in": 20.0 + rng.normal(0, 1, rows),
            "t_out": rng.normal(0, 3, rows),
            "q_hvac": rng.choice([0.0, 5000.0], rows),
        },
        index=times,
    )


def test_five_minute_rows_become_quarter_hour_means_keeping_the_heat():
    fine = _frame(5, 36)
    coarse = aggregated(fine, 900.0)
    assert len(coarse) == 12
    assert coarse.index[0] == fine.index[0]
    assert Dataset.from_frame(coarse).step_s == 900.0
    # Heat delivered over the record [J]
    assert coarse["q_hvac"].sum() * 900.0 == pytest.approx(fine["q_hvac"].sum() * 300.0)
    assert coarse["t_out"].iloc[1] == pytest.approx(fine["t_out"].iloc[3:6].mean())


def test_unmeasured_rows_and_gaps():
    fine = _frame(5, 36)
    fine.loc[fine.index[3:5], "t_in"] = np.nan
    fine = fine.drop(fine.index[9:15])  # two whole quarter-hours missing
    coarse = aggregated(fine, 900.0, record_step_s=300.0)
    assert len(coarse) == 10
    assert coarse["t_in"].iloc[1] == pytest.approx(fine["t_in"].iloc[5])
    assert len(Dataset.from_frame(coarse, step_s=900.0).segments) == 2


def test_a_step_that_does_not_divide_takes_the_next_whole_multiple():
    coarse = aggregated(_frame(7, 30), 900.0)
    assert Dataset.from_frame(coarse).step_s == 21 * 60


def test_a_record_as_coarse_as_asked_is_left_alone():
    frame = _frame(30, 10)
    assert aggregated(frame, 900.0) is frame
    assert aggregated(_frame(15, 10), 900.0).equals(_frame(15, 10))
