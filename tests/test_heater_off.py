"""The hours with the heater off that judge a gain the rolling folds rejected."""

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose.heater_off import MIN_OFF_HOURS, OFF_FOR_H, heater_off_change, off_rows

SIGNAL = "sched_gains"


def _frame(hours: int, heating: np.ndarray, schedule: np.ndarray) -> pd.DataFrame:
    index = pd.date_range("2024-03-04", periods=hours, freq="h", tz="UTC")
    return pd.DataFrame({"q_hvac": heating, SIGNAL: schedule}, index=index)


def _block(frame: pd.DataFrame, residual: np.ndarray) -> SimpleNamespace:
    test = SimpleNamespace(frame=frame, step_s=3600.0)
    return SimpleNamespace(residual_test=residual, split=SimpleNamespace(test=test))


def test_rows_count_only_once_the_heater_has_been_off_long_enough():
    heating = np.where(np.arange(24) <= 5, 2000.0, 0.0)
    off = off_rows(_frame(24, heating, np.ones(24)))
    # On through 05:00; the first row with OFF_FOR_H hours free of its heat is 05:00 + 3 h.
    assert OFF_FOR_H == 3.0
    assert not off[:8].any()
    assert off[8:].all()


def test_a_gain_that_warms_the_free_floating_hours_forecasts_them_better():
    hours = 48
    schedule = np.tile(np.where((np.arange(24) >= 8) & (np.arange(24) < 18), 1.0, 0.0), 2)
    heating = np.tile(np.where(np.arange(24) < 7, 3000.0, 0.0), 2)  # morning recovery only
    frame = _frame(hours, heating, schedule)
    cold = np.where(schedule > 0, 0.8, 0.1)  # measured − simulated [K]: the model runs cold
    fixed = np.where(schedule > 0, 0.1, 0.1)
    change = heater_off_change([_block(frame, cold)], [_block(frame, fixed)], SIGNAL)
    assert change is not None
    # Heating through 06:00; the occupied rows 3 h free of its heat are 09:00–17:00, 9 a day.
    assert change["hours"] == pytest.approx(18.0)
    assert change["rmse_before"] == pytest.approx(0.8)
    assert change["rmse_after"] == pytest.approx(0.1)


def test_too_few_heater_off_hours_on_the_schedule_judge_nothing():
    hours = 24
    schedule = np.where((np.arange(24) >= 8) & (np.arange(24) < 18), 1.0, 0.0)
    heating = np.where(np.arange(24) < 16, 3000.0, 0.0)  # heats through the working day
    frame = _frame(hours, heating, schedule)
    residual = np.full(hours, 0.5)
    assert MIN_OFF_HOURS > 0
    assert heater_off_change([_block(frame, residual)], [_block(frame, residual)], SIGNAL) is None


def test_only_a_gain_that_holds_with_the_heater_off_goes_over_the_season(monkeypatch):
    """Of two gains the rolling folds rejected, the one that forecasts the free-floating
    occupied hours better is judged on the held-out blocks, its reason keeping the rolling
    folds' verdict; the other keeps that verdict as it was."""
    from rcengine.diagnose import selection
    from rcengine.diagnose.report import HEATER_OFF
    from rcengine.diagnose.settings import DiagnoseSettings

    schedule = np.tile(np.where((np.arange(24) >= 8) & (np.arange(24) < 18), 1.0, 0.0), 2)
    heating = np.tile(np.where(np.arange(24) < 7, 3000.0, 0.0), 2)
    frame = _frame(48, heating, schedule)
    current = _block(frame, np.where(schedule > 0, 0.8, 0.1))
    helps, stands_in = (
        _block(frame, np.full(48, 0.1)),
        _block(frame, np.where(schedule > 0, 0.9, 0.1)),
    )
    judged = []
    monkeypatch.setattr(selection, "_block_fits", lambda *_: ([], [[helps], [stands_in]]))
    monkeypatch.setattr(
        selection, "_judge_on_blocks", lambda p, s, finding, *_: judged.append(finding.effect)
    )
    problem = SimpleNamespace(settings=DiagnoseSettings(), say=lambda _: None)
    state = SimpleNamespace(current_blocks=[current])
    ext = SimpleNamespace(effect="unmetered_gains", inputs=((SIGNAL, "t_air"),))
    rolling = "rejected across folds: helps in 2 of 5 folds"
    plug_load = SimpleNamespace(effect="plug_load", accepted=False, reason=rolling, detail={})
    stand_in = SimpleNamespace(effect="stand_in", accepted=False, reason=rolling, detail={})
    split = "accepted: test RMSE 1.000 → 0.500 K (-50%)"
    selection._gains_over_the_season(
        problem, state, [(ext, plug_load, split), (ext, stand_in, split)]
    )
    assert judged == ["plug_load"]
    assert plug_load.detail[HEATER_OFF]["rmse_after"] == pytest.approx(0.1)
    assert plug_load.reason.endswith("(the rolling folds: helps in 2 of 5 folds)")
    assert HEATER_OFF not in stand_in.detail and stand_in.reason == rolling
    assert not stand_in.accepted
