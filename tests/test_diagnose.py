"""Mismatch diagnosis: its building blocks against independent calculations, a synthetic building
with a hidden weekly gain, and the concealed-effect EnergyPlus variants (the issue's evidence)."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose import DiagnoseSettings, diagnose, selection, split_time
from rcengine.diagnose.candidates import CANDIDATES, Context, Skipped
from rcengine.diagnose.fitting import residual_at, split_data
from rcengine.diagnose.html import render
from rcengine.diagnose.response import explain_residual, node_responses, on_off_explainer
from rcengine.estimation import Estimator
from rcengine.io.timeseries import read_timeseries
from rcengine.models import get_model
from rcengine.models.spec import ModelSpec
from rcengine.signals import SignalOptions
from rcengine.signals.schedules import CLOCKS, clock_zone
from rcengine.simulate import simulate
from tests.synthetic import (
    BUILDING,
    TRUTH_BASIC,
    basic_reference,
    fitted_context,
    weather_and_gains,
)

# The hidden gain: a kitchen on weekday mornings, on a schedule no column carries. [W]
HIDDEN_GAIN_W = 15_000.0


def _hidden_gain(times: pd.DatetimeIndex, zone: str | dt.tzinfo | None = None) -> np.ndarray:
    local = times.tz_convert(zone or BUILDING.location.timezone)
    return HIDDEN_GAIN_W * ((local.day_of_week < 5) & (local.hour >= 7) & (local.hour < 13))


def _learnt_gain_schedule(frame: pd.DataFrame) -> dict:
    """The unmetered-gain candidate learnt from the residual of a baseline fit on 70 % of frame."""
    ctx = fitted_context(frame, "basic", 0.7)
    return CANDIDATES["unmetered_gains"](ctx).detail


@pytest.fixture(scope="module")
def hidden_gain_record() -> pd.DataFrame:
    """Three weeks from the hand-written 3R3C with the hidden gain added to the air node."""
    inputs = weather_and_gains(21)
    truth_inputs = inputs.assign(q_occ=inputs["q_occ"] + _hidden_gain(inputs.index))
    t_in = basic_reference(truth_inputs, TRUTH_BASIC, (15.0, 19.0, 19.0))
    return inputs.assign(t_in=t_in)


def test_node_responses_match_a_simulation_of_the_same_input():
    frame = weather_and_gains(3)
    network = get_model("basic", BUILDING, frame.columns)
    data = split_data(
        frame.assign(t_in=20.0), BUILDING, network, SignalOptions(), frame.index[-1]
    ).train
    heat = np.sin(np.arange(len(data)) / 7.0) * 1000.0
    got = node_responses(network, TRUTH_BASIC, data, "int", heat)[:, 0]
    probe = network.copy("probe")
    probe.add_heat_input("extra", "int")
    compiled = probe.compile()
    u = np.zeros((len(data), compiled.n_inputs))
    u[:, compiled.input_names.index("extra")] = heat
    expected = simulate(
        compiled.rc_matrices(TRUTH_BASIC), u, np.zeros((1, compiled.n_states)), data.step_s
    )[0]
    np.testing.assert_allclose(got, expected, atol=1e-9 * np.abs(expected).max())


def test_explain_residual_separates_candidate_from_nuisance():
    rng = np.random.default_rng(0)
    candidate, nuisance = rng.normal(size=(500, 2)), rng.normal(size=(500, 1))
    residual = 2.0 * candidate[:, 0] - 3.0 * nuisance[:, 0]
    theta, explained = explain_residual(residual, candidate, nuisance)
    np.testing.assert_allclose(theta, [2.0, 0.0], atol=1e-8)
    assert explained == pytest.approx(1.0)


def test_unmetered_gain_schedule_is_learnt_from_the_residual(hidden_gain_record):
    # From the baseline's residual alone: the right days and onset (diagnose refines the end), on
    # the civil clock (three weeks in January: both clocks agree, and the civil one is kept).
    detail = _learnt_gain_schedule(hidden_gain_record)
    assert detail["schedule"].startswith("Mon–Fri 07:00–")
    assert detail["clock"] == "local"


@pytest.mark.parametrize("clock", CLOCKS)
def test_learnt_schedule_finds_the_clock_the_building_keeps(clock):
    """Three weeks across the end of daylight saving (29 Oct 2017): a controller on civil time
    and one on standard time all year put the same gain an hour apart in October. Seen through
    the true model (the residual is the hidden gain's response alone), the schedule and its
    clock come out exactly."""
    inputs = weather_and_gains(21, start="2017-10-16")
    zone = clock_zone(BUILDING.location.timezone, clock)
    truth_inputs = inputs.assign(q_occ=inputs["q_occ"] + _hidden_gain(inputs.index, zone))
    frame = inputs.assign(t_in=basic_reference(truth_inputs, TRUTH_BASIC, (15.0, 19.0, 19.0)))
    network = get_model("basic", BUILDING, frame.columns)
    data = split_data(frame, BUILDING, network, SignalOptions(), frame.index[-1]).train
    residual = residual_at(network, TRUTH_BASIC, data)
    ctx = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, residual)
    detail = CANDIDATES["unmetered_gains"](ctx).detail
    assert detail["clock"] == clock
    assert detail["schedule"].startswith("Mon–Fri 07:00–13:00")


def test_a_day_seen_once_is_an_episode_not_a_schedule():
    """Nine days from a Monday hold one Saturday: heat on that Saturday alone is an episode the
    weekly schedule must not absorb, while the weekday gain (seen on seven dates) is learnt."""
    inputs = weather_and_gains(9)
    local = inputs.index.tz_convert(BUILDING.location.timezone)
    episode = HIDDEN_GAIN_W * (local.normalize() == pd.Timestamp("2017-01-14", tz=local.tz))
    truth_inputs = inputs.assign(q_occ=inputs["q_occ"] + _hidden_gain(inputs.index) + episode)
    frame = inputs.assign(t_in=basic_reference(truth_inputs, TRUTH_BASIC, (15.0, 19.0, 19.0)))
    network = get_model("basic", BUILDING, frame.columns)
    data = split_data(frame, BUILDING, network, SignalOptions(), frame.index[-1]).train
    residual = residual_at(network, TRUTH_BASIC, data)
    ctx = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, residual)
    schedule = CANDIDATES["unmetered_gains"](ctx).detail["schedule"]
    # (Friday evenings stretch to soak up some of the unexplained Saturday warmth.)
    assert schedule.startswith("Mon–Fri 07:00–") and "Sat" not in schedule, schedule


def test_unmetered_gains_in_step_with_the_metered_use():
    """Equipment switched on with the people and lights: 40 % of q_occ + q_light more, into the
    air. The candidate's alternative that follows the metered use reproduces the record at
    q_unmetered = 0.4 × the metered gains' mean over the occupied hours, per m² of floor."""
    inputs = weather_and_gains(14)
    metered = inputs["q_occ"] + inputs["q_light"]
    truth_inputs = inputs.assign(q_occ=inputs["q_occ"] + 0.4 * metered)
    frame = inputs.assign(t_in=basic_reference(truth_inputs, TRUTH_BASIC, (15.0, 19.0, 19.0)))
    network = get_model("basic", BUILDING, frame.columns)
    data = split_data(frame, BUILDING, network, SignalOptions(), frame.index[-1]).train
    residual = residual_at(network, TRUTH_BASIC, data)
    ctx = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, residual)
    found = CANDIDATES["unmetered_gains"](ctx)
    use = next(e for e in (found, *found.alternatives) if "follows" in e.detail)
    occupied = inputs["q_occ"].loc[data.times] > 0
    mean_w_m2 = metered.loc[data.times][occupied].mean() / BUILDING.floor_area
    assert use.detail["metered_w_m2"] == pytest.approx(mean_w_m2)
    assert use.detail["occupied_share"] == 1.0
    params = {**TRUTH_BASIC, "q_unmetered": 0.4 * mean_w_m2}
    # (to the first hours' unmeasured wall and mass temperatures, which the reference starts apart)
    assert np.abs(residual_at(use.network, params, data)).max() < 1e-3
    assert np.abs(residual).max() > 0.5  # without it the record is not explained


def test_plug_loads_that_never_fall_to_zero_are_recovered():
    """Equipment in step with the metered use (0.4 × q_occ + q_light) plus a base load of
    1.5 W/m² at every hour (servers, standby), with 0.05 K of sensor noise: the candidate's
    version with a base load, fitted with the rest of the model known, recovers both within
    10 %, while the version without it cannot carry the nights and weekends (its training RMSE
    ten times the noise)."""
    inputs = weather_and_gains(21)
    metered = inputs["q_occ"] + inputs["q_light"]
    base_w_m2 = 1.5
    unmetered = 0.4 * metered + base_w_m2 * BUILDING.floor_area
    truth_inputs = inputs.assign(q_occ=inputs["q_occ"] + unmetered)
    t_in = basic_reference(truth_inputs, TRUTH_BASIC, (15.0, 19.0, 19.0))
    noise = np.random.default_rng(5).normal(0.0, 0.05, len(t_in))
    frame = inputs.assign(t_in=t_in + noise)
    network = get_model("basic", BUILDING, frame.columns)
    data = split_data(frame, BUILDING, network, SignalOptions(), frame.index[-1]).train
    residual = residual_at(network, TRUTH_BASIC, data)
    ctx = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, residual)
    found = CANDIDATES["unmetered_gains"](ctx)
    versions = [found, *found.alternatives]
    use = next(e for e in versions if "follows" in e.detail and "base_load" not in e.detail)
    with_base = next(e for e in versions if "follows" in e.detail and "base_load" in e.detail)
    assert with_base.folds_only and with_base.neutral["q_base_load"] == 0.0

    data = split_data(frame, BUILDING, with_base.network, SignalOptions(), frame.index[-1]).train

    def fitted(ext):
        return Estimator(
            ext.network,
            random_state=0,
            known=TRUTH_BASIC,
            warm_start=[ext.neutral],
            warn_bounds=False,
        ).fit(data)

    est = fitted(with_base)
    mean_w_m2 = use.detail["metered_w_m2"]
    assert est.params_["q_unmetered"] == pytest.approx(0.4 * mean_w_m2, rel=0.1)
    assert est.params_["q_base_load"] == pytest.approx(base_w_m2, rel=0.1)
    without = fitted(use)
    rmse = np.sqrt(np.nanmean((data.measured - without.trajectory_.y) ** 2))
    assert rmse > 10 * 0.05


def test_on_off_explainer_equals_the_bounded_least_squares_it_shortcuts():
    rng = np.random.default_rng(1)
    responses, nuisance = rng.normal(size=(400, 6)), rng.normal(size=(400, 3))
    weights = np.array([1.0, 0.0, 1.0, 1.0, 0.0, 0.0])
    residual = 0.7 * responses @ weights + nuisance @ [1.0, -2.0, 0.5] + rng.normal(size=400)
    explained = on_off_explainer(residual, responses, nuisance)
    for trial in (weights, 1.0 - weights):
        expected = explain_residual(residual, (responses @ trial)[:, None], nuisance)[1]
        assert explained(trial) == pytest.approx(expected, rel=1e-9, abs=1e-12)
    # θ ≥ 0: a column pointing against the residual explains nothing.
    assert on_off_explainer(-residual, responses, nuisance)(weights) == 0.0


def test_candidates_without_their_inputs_are_skipped_with_the_reason(hidden_gain_record):
    frame = hidden_gain_record
    network = get_model("basic", BUILDING, frame.columns)
    data = split_data(frame, BUILDING, network, SignalOptions(), frame.index[-1]).train
    ctx = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, np.zeros(len(data)))
    assert CANDIDATES["wind_infiltration"](ctx) == Skipped(
        "wind_infiltration", "no wind_speed column in the data"
    )
    assert CANDIDATES["window_solar_gains"](ctx) == Skipped(
        "window_solar_gains", "no windows or facades ('windows', 'walls') in the building JSON"
    )
    no_heating = Context(
        network,
        BUILDING,
        split_data(
            frame.assign(q_hvac=0.0), BUILDING, network, SignalOptions(), frame.index[-1]
        ).train,
        SignalOptions(),
        TRUTH_BASIC,
        np.zeros(len(data)),
    )
    assert "q_hvac is zero" in CANDIDATES["emitter_dynamics"](no_heating).reason


def test_split_rejects_a_fraction_outside_the_sane_range(hidden_gain_record):
    with pytest.raises(ValueError, match="train_fraction must be within"):
        split_time(hidden_gain_record, 0.97, "Europe/Rome")


def test_hidden_weekly_gain_is_found_named_and_fixed(hidden_gain_record):
    report = diagnose(hidden_gain_record, BUILDING, "basic", DiagnoseSettings(train_fraction=0.6))
    d = json.loads(report.to_json())
    accepted = [f for f in d["findings"] if f["accepted"]]
    assert accepted[0]["effect"] == "unmetered_gains"
    assert "Mon–Fri 07:00–13:00" in accepted[0]["explanation"]
    assert d["final"]["rmse_test"] <= 0.5 * d["baseline"]["rmse_test"]
    assert d["skipped"]["wind_infiltration"] == "no wind_speed column in the data"
    innovations = np.array(d["mismatch"]["innovations"]["train"]["hour_weekday_mean_K"], float)
    assert innovations.shape == (7, 24)
    # The hidden gain switches on at 07:00 on weekdays: the one-step errors are largest then.
    assert np.nanargmax(np.nanmean(innovations[:5], axis=0)) in (7, 8)
    assert d["final"]["model"].startswith("basic+unmetered_gains")
    # Every refitted finding carries its model, so an engineer may adopt one by name.
    for f in d["findings"]:
        if f["rmse_test_after"] is not None:
            assert f["model"]["network"]["name"].endswith(f"+{f['effect']}")
            spec = ModelSpec.from_report(d, BUILDING, finding=f["effect"])
            assert spec.effects[-1] == f["effect"] and spec.source["accepted"] == f["accepted"]
    # What the MPC would have been served over the test half's days: the gain helps there too.
    ahead = d["day_ahead"]
    assert ahead["days"] >= 7 and ahead["horizon_h"] == 24.0
    assert ahead["rmse_final"] < 0.7 * ahead["rmse_baseline"]
    html = render(report)
    assert "unmetered_gains" in html and "<img" in html
    assert "as the service forecasts for an MPC" in html


@pytest.mark.parametrize("evidence", ["split", "folds"])
def test_only_the_folds_choose_the_gain_in_step_with_the_use(
    hidden_gain_record, monkeypatch, evidence
):
    """The unmetered gain in step with the metered use is a version only the folds choose
    (``folds_only``): a diagnosis on a single split never refits it; one on folds does."""
    refitted = []
    fit_from_current = selection._fit_from_current

    def spy(problem, current, extensions, splits):
        refitted.extend(extensions)
        return fit_from_current(problem, current, extensions, splits)

    monkeypatch.setattr(selection, "_fit_from_current", spy)
    settings = DiagnoseSettings(
        train_fraction=0.6,
        evidence=evidence,
        baseline_starts=1,
        max_rounds=1,
        effects=("unmetered_gains",),
        fold_train_days=6,
        fold_test_days=3,
    )
    diagnose(hidden_gain_record, BUILDING, "basic", settings)
    assert any(e.folds_only for e in refitted) == (evidence == "folds")


def test_a_five_minute_record_is_judged_at_a_quarter_hour(hidden_gain_record):
    """The same building logged every 5 minutes (inputs held, t_in interpolated): averaged into
    15-minute means before it is judged, and the hidden gain is still what is found."""
    fine_times = pd.date_range(
        hidden_gain_record.index[0], hidden_gain_record.index[-1], freq="5min"
    )
    fine = hidden_gain_record.reindex(fine_times).ffill()
    fine["t_in"] = hidden_gain_record["t_in"].reindex(fine_times).interpolate()
    report = diagnose(fine, BUILDING, "basic", DiagnoseSettings(train_fraction=0.6))
    d = report.to_dict()
    assert d["periods"]["step_s"] == 900.0
    assert next(f["effect"] for f in d["findings"] if f["accepted"]) == "unmetered_gains"


VARIANTS = Path(__file__).resolve().parents[1] / "data" / "energyplus" / "variants"
MANIFEST = {c["case"]: c for c in json.loads((VARIANTS / "manifest.json").read_text())}


# The window variant's glazing is in no description (its JSON lists the facade as opaque wall):
# found first, on the east facade, until the forty-eighth session, but at 0.80 × the baseline's
# test RMSE, short of the variants' 0.7 (−20 % on the single split, −14 % on the folds' pooled
# test); since the base model takes the interior surfaces, −22 % on the single split and −8 %
# pooled, under the folds' margin, so it is not found (docs/diagnosis.md).
# The sky variant, found first with 6 of 6 folds, reaches 0.69 × (−25 % pooled over the folds)
# since its share is read over a sheltered surface's film, whose wider search box the fit uses;
# it was 0.71 × before: a margin of a hundredth either way.
SHORT_OF_RATIO = {"window_solar_gains"}


@pytest.mark.slow
@pytest.mark.parametrize(
    "name",
    [
        pytest.param(
            n,
            marks=pytest.mark.xfail(
                n in SHORT_OF_RATIO, reason="not found, or by less than 0.7×", strict=True
            ),
        )
        for n in sorted(MANIFEST)
    ],
)
def test_concealed_effect_is_the_first_finding(name):
    case = MANIFEST[name]
    folder = VARIANTS / name
    building = type(BUILDING).from_json(folder / "building.json")
    frame = read_timeseries(folder / "data.csv")
    assert case["effect"] not in frame.columns
    d = json.loads(diagnose(frame, building, case["model"]).to_json())
    accepted = [f["effect"] for f in d["findings"] if f["accepted"]]
    # The final model holds exactly the accepted extensions (one dropped by the backward check
    # is no longer in it).
    assert sorted(d["final"]["network"]["name"].split("+")[1:]) == sorted(accepted)
    if case["effect"] is None:
        assert accepted == [], d["verdict"]
        return
    assert accepted and accepted[0] == case["effect"], [
        (f["effect"], f["reason"]) for f in d["findings"]
    ]
    assert d["final"]["rmse_test"] <= 0.7 * d["baseline"]["rmse_test"]
