"""The diagnosis's verdict, its evidence across rolling folds, the head to head between candidates
that both pass, and the base model's health in the report (issue 11, items 2, 4 and 5)."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.diagnose.folds import FoldEvidence, rolling_folds
from rcengine.diagnose.health import Health
from rcengine.diagnose.html import _fold_tables, _residual_before, render
from rcengine.diagnose.report import (
    SHORT_OF_BIC,
    SHORT_OF_TEST,
    Finding,
    _across,
    confirm_on_folds,
    confirm_over_the_season,
    reject_implausible,
    verdict,
)
from rcengine.diagnose.selection import (
    MIN_HVAC_SHARE,
    _informative,
    _not_the_excess_sun,
    _winner,
)
from tests.synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains
from tests.test_diagnose import _hidden_gain

HEALTHY = Health(reasons=(), on_bounds=())
CRIPPLED = Health(
    reasons=(
        "c_wall ended on its upper bound 7.5e+05 J/(K·m²): stores more heat than any "
        "construction of this building could",
    ),
    on_bounds=("c_wall",),
)


def _finding(effect: str, accepted: bool, **fields) -> Finding:
    """A made-up refitted finding: test RMSE 1.0 → 0.5 K."""
    defaults = dict(
        round=1,
        screen_explained=0.5,
        screen_method="projection",
        rmse_test_before=1.0,
        rmse_train_before=1.0,
        rmse_test_after=0.5,
        rmse_train_after=0.5,
        reason="accepted: test RMSE 1.000 → 0.500 K (-50%); ΔBIC -40.0",
    )
    return Finding(effect, accepted, **{**defaults, **fields})


def _evidence(before: list[float], after: list[float]) -> FoldEvidence:
    """Fold evidence whose test residuals are constant: each fold's RMSE is the value given."""
    return FoldEvidence(tuple(np.full(48, b) for b in before), tuple(np.full(48, a) for a in after))


def test_verdict_names_what_is_missing_or_that_nothing_is():
    wind = _finding("wind_infiltration", True)
    mass = _finding("thermal_mass", False)
    gains = _finding("unmetered_gains", True, round=2)
    assert verdict([], HEALTHY) == "nothing missing"
    assert verdict([mass], None) == "nothing missing"
    assert verdict([wind, mass], HEALTHY) == "missing: wind_infiltration"
    assert verdict([wind, gains, mass], HEALTHY) == "missing: wind_infiltration, unmetered_gains"


def test_verdict_says_the_base_model_is_inadequate_and_what_was_found_against_it():
    wind = _finding("wind_infiltration", True)
    text = verdict([wind], CRIPPLED)
    assert text.startswith("base model inadequate: c_wall ended on its upper bound")
    assert text.endswith("judged against it anyway: missing: wind_infiltration")
    # Repaired by the structural step: the verdict says so and names only what was found after.
    repair = _finding("thermal_mass", True, round=0, baseline_repair=True)
    text = verdict([repair, wind], CRIPPLED)
    assert text.endswith("— healthy with thermal_mass, then missing: wind_infiltration"), text
    assert verdict([repair], CRIPPLED).endswith("healthy with thermal_mass, then nothing missing")
    # Dropped after the selection, the later findings having healed the base model.
    repair.accepted = False
    text = verdict([wind, repair], CRIPPLED)
    healed = "healthy once what it left out is in (thermal_mass not needed)"
    assert text.endswith(f"— {healed}: missing: wind_infiltration"), text


def test_a_base_model_resting_on_a_bound_is_healthy_but_still_offered_the_repair_step():
    """A bound the data do not press on is no reason against the base model (the verdict does not
    call it inadequate), but the model is not settled: the structural step is still tried, and
    where it is taken the verdict names it beside what was found."""
    resting = (
        "r_int ended on its upper bound 0.97 m²K/W, but a fit past it gains 0.2% of the training "
        "RMSE: the data do not press on it (the model does without that element)"
    )
    health = Health(reasons=(), on_bounds=("r_int",), notes=(resting,), resting=(resting,))
    assert health.healthy and health.verdict == "healthy" and not health.settled
    assert health.summary() == (
        f"the base model represents this building, resting on bounds the data do not press on: "
        f"{resting}"
    )
    assert HEALTHY.settled and not CRIPPLED.settled
    wind = _finding("wind_infiltration", True)
    assert verdict([wind], health) == "missing: wind_infiltration"
    repair = _finding("thermal_mass", True, round=0, baseline_repair=True)
    assert verdict([repair, wind], health) == (
        "missing: wind_infiltration (against the base model with thermal_mass: without it, "
        "parameters rested on bounds the data do not press on)"
    )


def test_a_single_split_winner_that_helps_in_few_folds_is_rejected():
    folds = rolling_folds(
        pd.date_range("2017-01-01", "2017-03-01", freq="1h", tz="UTC"), "Europe/Rome", 14, 7, 3
    )
    lucky = _finding("opaque_solar_gains", True)
    confirm_on_folds(
        lucky, _evidence([1, 1, 1], [0.5, 1.2, 1.3]), folds, DiagnoseSettings(), "Europe/Rome"
    )
    assert not lucky.accepted
    assert lucky.reason.startswith("rejected across folds: helps in 1 of 3 folds")
    assert [f["rmse_test_after"] for f in lucky.folds["folds"]] == [0.5, 1.2, 1.3]
    assert lucky.folds["folds"][0]["test"] == folds[0].label("Europe/Rome")
    steady = _finding("window_solar_gains", True)
    confirm_on_folds(
        steady, _evidence([1, 1, 1], [0.6, 0.7, 0.8]), folds, DiagnoseSettings(), "Europe/Rome"
    )
    assert steady.accepted and "across folds: helps in 3 of 3 folds" in steady.reason
    assert steady.folds["helped"] == 3 and steady.folds["pooled_rmse_test_before"] == 1.0


def test_a_finding_short_of_the_bic_alone_is_judged_by_the_bic_over_the_season():
    """The training half's three months may not pay for a facade's g-values; the folds' fits,
    each over the season around its window, may. Only the BIC may be short: a candidate whose
    test gain is too small never reaches the folds."""
    folds = rolling_folds(
        pd.date_range("2017-01-01", "2017-03-01", freq="1h", tz="UTC"), "Europe/Rome", 14, 7, 3
    )
    helps = _evidence([1, 1, 1], [0.6, 0.7, 0.8])

    def short(season_bic: float) -> Finding:
        finding = _finding(
            "window_solar_gains", False, reason="rejected: ΔBIC +9.1", short_of=SHORT_OF_BIC
        )
        finding.delta_bic = 9.1
        confirm_over_the_season(
            finding, helps, folds, DiagnoseSettings(), "Europe/Rome", season_bic
        )
        return finding

    paid = short(-21.8)
    assert paid.accepted and paid.detail["season_delta_bic"] == -21.8
    assert paid.reason.startswith(
        "accepted: test RMSE 1.000 → 0.500 K (-50%); ΔBIC +9.1 on the training half, -21.8 over "
        "the season"
    )
    assert "across held-out blocks: helps in 3 of 3 folds" in paid.reason
    assert paid.folds["training"] == "held-out blocks"
    assert _across(paid).startswith("; across 3 held-out blocks it helps in 3")
    table = _fold_tables({"effect": "window_solar_gains", "folds": paid.folds})
    assert "window_solar_gains across held-out blocks: helps in 3" in table
    unpaid = short(-4.0)
    assert not unpaid.accepted and unpaid.reason == (
        "rejected: ΔBIC +9.1, -4.0 over the season (median of the folds' fits)"
    )
    assert unpaid.folds["helped"] == 3  # the evidence is reported either way
    implausible = _finding("window_solar_gains", False, short_of=SHORT_OF_BIC)
    reject_implausible(implausible, {}, ["g-value of the glazing facing 210°: 1.2 exceeds any"])
    assert implausible.short_of is None  # an implausible fit goes no further


def _slow_ground(season_bic: float, accepted: bool = True, **fields) -> Finding:
    """A made-up ground (ΔBIC −40 on the training half; ``fields`` its single split's verdict)
    whose soil is too slow for the rolling folds, judged on three held-out blocks it helps."""
    folds = rolling_folds(
        pd.date_range("2017-01-01", "2017-03-01", freq="1h", tz="UTC"), "Europe/Rome", 14, 7, 3
    )
    finding = _finding("ground_coupling", accepted, **{"delta_bic": -40.0, **fields})
    finding.detail["slow_input"] = {"signal": "t_ground", "within_fold_share": 0.16}
    helps = _evidence([1, 1, 1], [0.6, 0.7, 0.8])
    confirm_over_the_season(finding, helps, folds, DiagnoseSettings(), "Europe/Rome", season_bic)
    return finding


def test_a_finding_whose_input_is_too_slow_for_the_rolling_folds_is_judged_over_the_season():
    """A ground that passed the single split is judged on held-out blocks, whose fits carry its
    parameters through autumn and spring: accepted where the season's BIC pays for it and the
    blocks agree, rejected where the season's BIC does not; the reason says why."""
    paid = _slow_ground(-30.0)
    assert paid.accepted and paid.folds["training"] == "held-out blocks"
    assert paid.detail["slow_input"] == {"signal": "t_ground", "within_fold_share": 0.16}
    assert (
        "judged over the season: its input t_ground varies within a fold's training weeks by "
        "16% of its variation over the record" in paid.reason
    )
    assert "across held-out blocks: helps in 3 of 3 folds" in paid.reason
    unpaid = _slow_ground(-4.0)
    assert not unpaid.accepted and unpaid.reason.startswith(
        "rejected: ΔBIC -4.0 over the season (median of the folds' fits); judged over the season"
    )
    assert unpaid.reason.endswith("(single split: test RMSE 1.000 → 0.500 K (-50%); ΔBIC -40.0)")


def test_a_slow_input_short_of_the_single_split_s_test_alone_is_judged_over_the_season():
    """The single split tests a ground fitted on autumn against the spring: its soil's slow
    course is confounded there with every seasonal trend (the sun's rise), so a ground short of
    that test alone — its BIC paid, its magnitudes plausible — is judged on held-out blocks, whose
    fits span the season; the reason keeps the single split's figure and says why it is not
    asked."""

    def short(season_bic: float) -> Finding:
        return _slow_ground(
            season_bic,
            False,
            rmse_test_after=1.1,
            reason="rejected: test RMSE 1.000 → 1.100 K (+10%)",
            short_of=SHORT_OF_TEST,
        )

    paid = short(-30.0)
    assert paid.accepted and paid.folds["training"] == "held-out blocks"
    assert paid.reason.startswith(
        "accepted: test RMSE 1.000 → 1.100 K (+10%) on a test half that is the season's other "
        "half; ΔBIC -40.0 on the training half, -30.0 over the season"
    )
    assert "across held-out blocks: helps in 3 of 3 folds" in paid.reason
    unpaid = short(-4.0)
    assert not unpaid.accepted and unpaid.reason.startswith(
        "rejected: test RMSE 1.000 → 1.100 K (+10%); ΔBIC -40.0 on the training half, -4.0 over "
        "the season (median of the folds' fits); judged over the season: its input t_ground"
    )
    implausible = _finding("ground_coupling", False, short_of=SHORT_OF_TEST)
    reject_implausible(implausible, {}, ["mean ground temperature: -20 °C is below any soil"])
    assert implausible.short_of is None  # an implausible fit goes no further


def test_a_gain_the_rolling_folds_rejected_is_judged_over_the_season_with_the_heater_off():
    """A plug load that passed the single split but not the rolling folds, while the heater held
    the set point, is judged on held-out blocks once it forecasts the hours with the heater off
    better; the reason names those hours' figures and keeps the single split's."""
    folds = rolling_folds(
        pd.date_range("2017-01-01", "2017-03-01", freq="1h", tz="UTC"), "Europe/Rome", 14, 7, 3
    )

    def judged(season_bic: float) -> Finding:
        finding = _finding("unmetered_gains", True, delta_bic=-100.7)
        off = {"signal": "sched_gains", "hours": 558.0, "rmse_before": 0.433, "rmse_after": 0.219}
        finding.detail["heater_off"] = off
        helps = _evidence([1, 1, 1], [0.6, 0.7, 0.8])
        confirm_over_the_season(
            finding, helps, folds, DiagnoseSettings(), "Europe/Rome", season_bic
        )
        return finding

    paid = judged(-137.6)
    assert paid.accepted and paid.folds["training"] == "held-out blocks"
    assert (
        "judged over the season: over the 558 h of its schedule with the heater off, it "
        "forecasts 0.433 → 0.219 K" in paid.reason
    )
    unpaid = judged(-4.0)
    assert not unpaid.accepted and unpaid.reason.startswith("rejected: ΔBIC -4.0 over the season")


def test_findings_judged_on_unlike_folds_are_compared_on_the_single_split():
    """A ground judged on held-out blocks and a gain judged on rolling folds, both paid for by
    the training half: the blocks' fits span the season and err less, so the two are compared on
    the single split's test, not on their folds' errors."""
    ground = _finding("ground_coupling", True, rmse_test_after=0.6)
    ground.evidence = _evidence([1, 1, 1], [0.3, 0.3, 0.3])
    ground.folds = {"training": "held-out blocks"}
    gain = _finding("unmetered_gains", True, rmse_test_after=0.4)
    gain.evidence = _evidence([1, 1, 1], [0.8, 0.8, 0.8])
    gain.folds = {"helped": 3}
    assert _winner([ground, gain], 1) is gain
    assert ground.lost_to["reason"] == "test RMSE 0.600 K against the winner's 0.400 K"


def test_the_season_does_not_pick_the_way_of_sun_beyond_glass():
    """Where the model already lets in more sun than glass could, which way the excess comes in
    is the excess-sun step's to judge after the selection, not the season's BIC before it."""

    def short() -> list:
        return [
            (None, _finding(e, False, reason="rejected: ΔBIC +9.1", short_of=SHORT_OF_BIC))
            for e in ("window_solar_gains", "opaque_solar_gains", "sky_radiation")
        ]

    within = short()
    assert _not_the_excess_sun(within, 0.6) == within  # within glass: all go to the season
    assert _not_the_excess_sun(within, None) == within  # no declared glazing
    beyond = short()
    kept = _not_the_excess_sun(beyond, 1.4)
    assert [f.effect for _, f in kept] == ["sky_radiation"]
    window = beyond[0][1]
    assert not window.accepted and window.short_of is None
    assert window.reason == (
        "rejected: ΔBIC +9.1; the model's sun is already beyond glass (as g = 1.40): the "
        "excess-sun step judges which way it comes in"
    )


def test_a_fold_trained_without_heating_but_tested_with_it_is_left_out():
    times = pd.date_range("2016-10-01", "2017-01-01", freq="1h", tz="UTC")
    folds = rolling_folds(times, "Europe/Rome", 28, 14, 3)
    # Free-floating until 1 November, then heated: the first fold trains on October alone.
    heating = np.where(times < pd.Timestamp("2016-11-01", tz="UTC"), 0.0, 2000.0)
    frame = pd.DataFrame({"q_hvac": heating}, index=times)
    kept, left_out = _informative(frame, folds)
    assert left_out == [folds[0]] and kept == folds[1:]
    # A trickle of heating in training is still too little to identify its effect.
    trickle = frame.assign(q_hvac=np.maximum(heating, 0.5 * MIN_HVAC_SHARE * 2000.0))
    assert _informative(trickle, folds)[1] == [folds[0]]
    assert _informative(frame.assign(q_hvac=0.0), folds) == (folds, [])
    assert _informative(frame.drop(columns="q_hvac"), folds) == (folds, [])


def test_of_two_passing_candidates_the_head_to_head_winner_is_taken_and_the_other_reported():
    window = _finding("window_solar_gains", True, evidence=_evidence([1, 1, 1], [0.6, 0.7, 0.5]))
    opaque = _finding(
        "opaque_solar_gains",
        True,
        rmse_test_after=0.4,  # better on the single split
        evidence=_evidence([1, 1, 1], [0.8, 0.6, 0.9]),
    )
    best = _winner([opaque, window], 1)
    assert best is window and window.accepted
    assert not opaque.accepted and opaque.lost_to["effect"] == "window_solar_gains"
    assert "better in 1 of 3 folds" in opaque.lost_to["reason"]
    assert opaque.reason.startswith("not taken in round 1: lost to window_solar_gains")
    assert window.runner_up == {"effect": "opaque_solar_gains", "reason": opaque.lost_to["reason"]}


def test_a_finding_the_training_half_pays_for_beats_one_the_season_pays_for():
    """Held-out blocks fit more data than a rolling fold: the two findings' fold evidence is
    unlike, and the one the training half's BIC pays for is taken first; the other is judged
    again in a later round, from the model that has it."""
    season = _finding("sky_radiation", True, short_of=SHORT_OF_BIC)
    season.evidence = _evidence([1, 1, 1], [0.3, 0.3, 0.3])  # far better on its own folds
    paid = _finding("wind_infiltration", True, evidence=_evidence([1, 1, 1], [0.8, 0.8, 0.8]))
    assert _winner([season, paid], 2) is paid
    assert not season.accepted and season.lost_to == {
        "effect": "wind_infiltration",
        "reason": "the training half pays for the winner, not for it",
    }


def test_a_finding_the_single_split_s_test_pays_for_beats_one_only_the_season_pays_for():
    season = _finding("ground_coupling", True, short_of=SHORT_OF_TEST)
    season.evidence = _evidence([1, 1, 1], [0.3, 0.3, 0.3])
    paid = _finding("thermal_mass", True, evidence=_evidence([1, 1, 1], [0.8, 0.8, 0.8]))
    assert _winner([season, paid], 1) is paid
    assert season.lost_to == {
        "effect": "thermal_mass",
        "reason": "the test half pays for the winner, not for it",
    }


def test_an_implausible_magnitude_rejects_the_finding_with_its_reason():
    gains = _finding("unmetered_gains", True)
    magnitudes = {"q_unmetered": {"value": 180.0, "unit": "W/m²"}}
    reject_implausible(gains, magnitudes, ["180 W/m² of floor is more than any occupancy"])
    assert not gains.accepted and gains.magnitudes == magnitudes
    assert gains.reason == "rejected as implausible: 180 W/m² of floor is more than any occupancy"
    assert gains.to_dict()["magnitudes"] == magnitudes


@pytest.fixture(scope="module")
def gain_report():
    """The three-week synthetic building with a hidden weekday gain, judged on six folds of a
    week's training and three days' test."""
    inputs = weather_and_gains(21)
    truth_inputs = inputs.assign(q_occ=inputs["q_occ"] + _hidden_gain(inputs.index))
    frame = inputs.assign(t_in=basic_reference(truth_inputs, TRUTH_BASIC, (15.0, 19.0, 19.0)))
    settings = DiagnoseSettings(train_fraction=0.6, fold_train_days=7, fold_test_days=3)
    return diagnose(frame, BUILDING, "basic", settings)


def test_the_hidden_gain_is_confirmed_across_the_folds(gain_report):
    d = json.loads(gain_report.to_json())
    assert d["evidence"]["method"] == "folds" and len(d["evidence"]["folds"]) == 6
    first = next(f for f in d["findings"] if f["accepted"])
    assert first["effect"] == "unmetered_gains"
    folds = first["folds"]
    assert len(folds["folds"]) == 6 and folds["helped"] > 3
    assert folds["pooled_rmse_test_after"] <= 0.5 * folds["pooled_rmse_test_before"]
    assert "across folds: helps in" in first["reason"]
    assert {f["outcome"] for f in folds["folds"]} <= {"helped", "tied", "did not"}
    assert folds["helped"] == sum(f["outcome"] == "helped" for f in folds["folds"])
    assert folds["tied"] == sum(f["outcome"] == "tied" for f in folds["folds"])
    page = render(gain_report)
    assert "across rolling folds: helps in" in page
    assert page.count("<td class=ok>helped</td>") >= folds["helped"]


def test_a_baseline_no_better_than_a_constant_gives_the_inadequate_verdict(gain_report):
    # Without the 15 kW weekday gain the base model's test error exceeds the spread of the
    # measured temperature: it is inadequate, and the gain is found against it anyway.
    d = json.loads(gain_report.to_json())
    health = d["baseline"]["health"]
    assert health["verdict"] == "inadequate"
    assert health["rmse_test"] > health["naive_rmse_test"]["constant"]
    assert d["verdict"].startswith("base model inadequate: test RMSE")
    assert "missing: unmetered_gains" in d["verdict"]


def test_a_findings_figure_shows_the_residual_of_the_round_it_was_judged_in():
    """The accepted findings are listed by strength of evidence, not by round: a finding's
    screening figure is drawn against the fit of the one accepted in the latest earlier round
    (the base model's before round one; a repair is round 0)."""
    baseline = SimpleNamespace(residual_train="base model")
    repair = _finding("thermal_mass", True, round=0, baseline_repair=True)
    first, second = _finding("sky_radiation", True, round=1), _finding("wind", True, round=2)
    for f in (repair, first, second):
        f.fit = SimpleNamespace(residual_train=f"after {f.effect}")
    report = SimpleNamespace(baseline=baseline, accepted=[second, first, repair])
    assert _residual_before(report, second) == "after sky_radiation"
    assert _residual_before(report, first) == "after thermal_mass"
    assert _residual_before(report, repair) == "base model"
    late = _finding("ground_coupling", False, round=3)
    assert _residual_before(report, late) == "after wind"
