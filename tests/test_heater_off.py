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


def test_a_block_s_first_hours_are_read_with_the_heat_given_before_it():
    """A held-out block that begins an hour after the heater stopped (on through 05:00, the
    block from 06:00): its 07:00 is not yet three hours free of that heat, though the block's own
    rows show none. Read against the whole record it is left out, and the hours counted are
    08:00 on; read from the block alone, 07:00 would count, with the error the heat left."""
    schedule = np.ones(24)
    heating = np.where(np.arange(24) <= 5, 2000.0, 0.0)
    record = _frame(24, heating, schedule)
    block = record.iloc[6:]
    cold, fixed = np.full(len(block), 0.5), np.full(len(block), 0.1)
    fixed[:2] = 2.0  # wrong only in the hours the heater's heat still shows
    blocks = [_block(block, cold)], [_block(block, fixed)]
    change = heater_off_change(*blocks, SIGNAL, off_rows(record))
    assert change is not None
    assert change["hours"] == pytest.approx(16.0)  # 08:00–23:00
    assert change["rmse_after"] == pytest.approx(0.1)
    alone = heater_off_change(*blocks, SIGNAL, off_rows(block))
    assert alone is not None and alone["hours"] == pytest.approx(17.0)
    assert alone["rmse_after"] == pytest.approx(np.sqrt((2.0**2 + 16 * 0.1**2) / 17))


def test_rows_count_only_once_the_heater_has_been_off_long_enough():
    heating = np.where(np.arange(24) <= 5, 2000.0, 0.0)
    off = off_rows(_frame(24, heating, np.ones(24)))
    # On through 05:00; the first row with OFF_FOR_H hours free of its heat is 05:00 + 3 h.
    assert OFF_FOR_H == 3.0
    assert not off.iloc[:8].any()
    assert off.iloc[8:].all()


def test_a_gain_that_warms_the_free_floating_hours_forecasts_them_better():
    hours = 48
    schedule = np.tile(np.where((np.arange(24) >= 8) & (np.arange(24) < 18), 1.0, 0.0), 2)
    heating = np.tile(np.where(np.arange(24) < 7, 3000.0, 0.0), 2)  # morning recovery only
    frame = _frame(hours, heating, schedule)
    cold = np.where(schedule > 0, 0.8, 0.1)  # measured − simulated [K]: the model runs cold
    fixed = np.where(schedule > 0, 0.1, 0.1)
    blocks = [_block(frame, cold)], [_block(frame, fixed)]
    change = heater_off_change(*blocks, SIGNAL, off_rows(frame))
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
    blocks = [_block(frame, residual)], [_block(frame, residual)]
    assert heater_off_change(*blocks, SIGNAL, off_rows(frame)) is None


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
    problem = SimpleNamespace(settings=DiagnoseSettings(), say=lambda _: None, frame=frame)
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


@pytest.mark.parametrize("folds_pass", [(True, False), (False, False)])
def test_no_version_goes_over_the_season_where_the_rolling_folds_pass_one(monkeypatch, folds_pass):
    """Two versions of a gain (a learnt schedule and its refinement) pass the single split. Where
    the rolling folds pass either, neither is sent to the held-out blocks: the blocks' errors,
    fitted on more of the record, are no measure against the folds' in choosing between
    versions. Where the folds reject both, both go, each with the single split's reason."""
    from rcengine.diagnose import selection
    from rcengine.diagnose.settings import DiagnoseSettings

    split_reason = "accepted: test RMSE 1.000 → 0.500 K (-50%)"
    versions = [
        SimpleNamespace(effect="unmetered_gains", network=None, signals=None) for _ in range(2)
    ]
    findings = [
        SimpleNamespace(
            effect="unmetered_gains",
            accepted=True,
            reason=split_reason,
            short_of=None,
            detail={},
            fit=SimpleNamespace(params={}),
        )
        for _ in range(2)
    ]
    verdicts = dict(zip(map(id, findings), folds_pass, strict=True))

    def rolling(finding, *_):
        finding.accepted = verdicts[id(finding)]
        finding.reason = "accepted across folds" if finding.accepted else "rejected across folds"

    sent = []
    monkeypatch.setattr(selection, "_slow_input", lambda *_: None)
    monkeypatch.setattr(selection, "_confirm_over_the_season", lambda *_: None)
    monkeypatch.setattr(selection, "_fold_fits_beside_current", lambda p, s, m: [[]] * len(m))
    monkeypatch.setattr(selection, "confirm_on_folds", rolling)
    monkeypatch.setattr(selection, "_gains_over_the_season", lambda p, s, gains: sent.extend(gains))
    problem = SimpleNamespace(
        settings=DiagnoseSettings(),
        folds=[object()] * 5,
        building=SimpleNamespace(location=SimpleNamespace(timezone="UTC")),
        say=lambda _: None,
    )
    state = SimpleNamespace(current_folds=[])
    selection._confirm_on_folds(problem, state, versions, findings)
    if any(folds_pass):
        assert sent == []
    else:
        assert [(e, f) for e, f, _ in sent] == list(zip(versions, findings, strict=True))
        assert all(reason == split_reason for _, _, reason in sent)
