"""Two effects that mask each other: neither passes alone, the pair does (issue 11, item 4)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from rcengine.building import Building
from rcengine.diagnose import DiagnoseSettings, diagnose, selection
from rcengine.diagnose.report import Finding
from rcengine.diagnose.selection import Selection, _masked_pair, _near_miss
from rcengine.io.timeseries import read_timeseries
from tests.test_diagnose_evidence import _finding


def _verdict(effect: str, delta_bic: float, after: float | None, **fields) -> Finding:
    """A made-up verdict of round 1, refitted, not accepted: test RMSE 1.0 K → ``after``."""
    fields = {"rmse_test_after": after, "delta_bic": delta_bic, "fit": object(), **fields}
    return _finding(effect, False, **fields)


def _state(*verdicts: Finding) -> tuple[SimpleNamespace, Selection]:
    problem = SimpleNamespace(settings=DiagnoseSettings(excess_sun=False))
    state = Selection(current=None, round_no=1, verdicts={v.effect: v for v in verdicts})
    return problem, state


def test_the_near_miss_tried_is_the_one_the_training_half_pays_for_most():
    problem, state = _state(
        _verdict("wind_infiltration", -60.0, 0.95),
        _verdict("unmetered_gains", -90.0, 0.96),
        _verdict("sky_radiation", -120.0, 1.05),  # worse on the test half
        _verdict("ground_coupling", -150.0, 0.9, plausible=False),
        _verdict("window_solar_gains", -5.0, 0.8),  # the training half does not pay for it
        _verdict("thermal_mass", -200.0, 0.9, round=0),  # judged in an earlier round
        _verdict("emitter_dynamics", -300.0, None, fit=None),  # only screened
    )
    assert _near_miss(problem, state).effect == "unmetered_gains"


def test_no_near_miss_where_nothing_helps_both_halves():
    problem, state = _state(
        _verdict("wind_infiltration", 3.0, 0.9), _verdict("sky_radiation", -40.0, 1.2)
    )
    assert _near_miss(problem, state) is None


def test_a_refused_trial_is_written_on_the_near_miss(monkeypatch):
    """Where the trial round accepts nothing on top of the near miss, the state is left as it
    was and the near miss's own verdict says it was tried and why it was not kept."""
    near = _verdict("ground_coupling", -60.0, 0.95, detail={})
    problem, state = _state(near, _verdict("wind_infiltration", -20.0, 0.97))
    problem.say = lambda message: None
    monkeypatch.setattr(selection, "_quality", lambda problem, fit: SimpleNamespace(poor=True))
    monkeypatch.setattr(Selection, "go_on_from", lambda self, fit, fold_fits=None: None)
    monkeypatch.setattr(selection, "_extensions", lambda problem, state: ["a candidate"])
    monkeypatch.setattr(selection, "_round", lambda problem, state, extensions: None)
    assert not _masked_pair(problem, state)
    assert state.accepted == [] and state.verdicts["ground_coupling"] is near
    assert near.reason.endswith(
        "; tried as a masked pair with the next round's candidates, not kept: no other "
        "candidate passed on top of it"
    )
    assert near.detail["pair_trial"] == {
        "with": None,
        "outcome": "no other candidate passed on top of it",
    }


@pytest.mark.slow
def test_a_ground_and_a_wind_that_mask_each_other_are_found_together(project_data):
    """The thirty-second sealed set's open-plan Chicago slab on the ground with a wind-driven
    leak. Alone the wind cut the test half by 4 % and the ground worsened it by 45 %, and the
    forward selection found nothing; taken with the ground, the wind passes on top of the ground
    alone, each helps added last to the other across the folds, and the test half's error falls
    below a kelvin from 3.4 K."""
    case = (
        project_data
        / "testbed_sealed_32"
        / "open_plan-chicago-ground_coupling+wind_infiltration-drawn"
    )
    building = Building.from_json(case / "building.json")
    report = diagnose(read_timeseries(case / "data.csv"), building, "basic", DiagnoseSettings())
    accepted = {f.effect: f for f in report.findings if f.accepted}
    assert set(accepted) == {"ground_coupling", "wind_infiltration"}
    wind = accepted["wind_infiltration"]
    assert wind.reason.startswith("accepted with ground_coupling, which masked it (rejected:")
    assert wind.detail["taken_with"] == "ground_coupling"
    assert accepted["ground_coupling"].detail["taken_with"] == "wind_infiltration"
    assert all(f.backward["still_needed"] for f in accepted.values())
    assert report.baseline.rmse_test > 3.0 and report.final.rmse_test < 1.0
