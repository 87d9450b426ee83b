"""The diagnosis as a forward selection over the candidate physics.

1. fit the model on the training period (the first part of the record), simulate the later test
   period, and locate the errors (``locate``);
2. build every candidate extension of the vocabulary that the data and building allow
   (``candidates``) and screen them cheaply against the training residual (``screen``);
3. refit the best few for real; a candidate passes if it cuts the test RMSE by a meaningful
   margin, an information criterion with an effective sample size agrees and its fitted
   magnitudes are plausible for the building; with fold evidence (the default) it must also help
   in most rolling folds across the record and on their pooled test. Of those that pass, a head
   to head on the folds picks the one accepted (the runner-up is reported with why it lost);
   where glazing is declared the opaque sun takes part only as a rival, named when it beats an
   effect that passes, never alone (``excess_sun``); repeat from the extended model until
   nothing more is accepted — or, where the model then still forecasts no better than a naive
   forecast, until a pair of effects that mask each other is not found either (``_masked_pair``);
4. check every accepted finding backward: left out of the final model, does it still help across
   the folds? One that no longer does is dropped; the rest are ordered by what they are worth.

Before any of this the base model (fitted within bounds derived from the building) is given the
interior surfaces between its air and its mass (``surfaces``) and then the lights' convective
share (``metered``), each where it settles inside its range, and checked for health
(``health``): against a crippled base model any flexible extension "wins".
A base model that is inadequate, or rests a parameter on a bound the data do not press on
(healthy, but perhaps of too low an order), is given the structural ``thermal_mass`` step, taken
when it leaves no parameter on a bound; otherwise the candidates are still judged against the
base model, and the verdict says whether it is inadequate.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import Q_HVAC, T_IN
from rcengine.dataset import aggregated, bridge_short_gaps
from rcengine.diagnose.candidates import CANDIDATES, Context, Extension, Skipped, mass_node
from rcengine.diagnose.clock import check_clock, realigned
from rcengine.diagnose.day_ahead import day_ahead_block
from rcengine.diagnose.declared import (
    G_WINDOW_ADDED_MASS,
    has_glazing_g,
    sun_on_added_mass,
    with_declared_glazing,
)
from rcengine.diagnose.excess_sun import EFFECT as EXCESS_SUN_EFFECT
from rcengine.diagnose.excess_sun import (
    EXCESS_EFFECTS,
    RIVAL_ONLY,
    attribute_excess_sun,
    sun_as_glazing_g,
)
from rcengine.diagnose.fitting import (
    Fit,
    FitJob,
    Split,
    fit_many,
    fold_splits,
    residual_at,
    split_data,
    trust_region,
)
from rcengine.diagnose.folds import (
    SLOW_INPUT_SHARE,
    Fold,
    FoldEvidence,
    head_to_head,
    held_out_blocks,
    judge_folds,
    rolling_folds,
    within_fold_share,
)
from rcengine.diagnose.health import (
    FitQuality,
    Health,
    check_health,
    fit_quality,
    on_bounds,
    relaxed_bounds,
)
from rcengine.diagnose.heater_off import heater_off_change, off_rows
from rcengine.diagnose.locate import summarize
from rcengine.diagnose.metered import (
    F_LIGHT_AIR,
    LIGHT_CONVECTIVE_SHARE,
    MIN_SHARE_TAKEN,
    with_lights_in_air,
)
from rcengine.diagnose.plausibility import assess
from rcengine.diagnose.report import (
    HEATER_OFF,
    SHORT_OF_BIC,
    SHORT_OF_TEST,
    SLOW_INPUT,
    Finding,
    Report,
    confirm_on_folds,
    confirm_over_the_season,
    explain,
    judge,
    reject_implausible,
    screened_only,
)
from rcengine.diagnose.screen import Screen, screen, screen_all
from rcengine.diagnose.settings import DiagnoseSettings, split_time
from rcengine.diagnose.surfaces import R_MASS_SURF, released_share, with_surface_node
from rcengine.diagnose.whiteness import ljung_box
from rcengine.estimation.presets import EstimatorSettings
from rcengine.models import get_model
from rcengine.models.bounds import G_GLAZING_MAX
from rcengine.network import RCNetwork
from rcengine.parallel import one_blas_thread
from rcengine.record import check_diagnosable
from rcengine.signals import SignalOptions

# A fold whose training window barely heats (or cools) cannot identify the model's response to
# the HVAC; when its test window does heat, its test error measures that extrapolation, not the
# candidate (a season's first fold, free-floating until the heating starts, is the usual case).
# Such a fold — mean |q_hvac| in training below this share of the test window's — is left out. [-]
MIN_HVAC_SHARE = 0.1


@dataclass(frozen=True)
class Problem:
    """What the whole selection works on: the record (UTC index), the building, the train/test
    boundary (a local midnight, UTC), the settings, the progress callback and the rolling folds
    an extension must help across (none: the single split decides)."""

    frame: pd.DataFrame
    building: Building
    boundary: pd.Timestamp
    settings: DiagnoseSettings
    say: Callable[[str], None]
    folds: list[Fold] = field(default_factory=list)

    def split(self, network: RCNetwork, options: SignalOptions) -> Split:
        """The record prepared for ``network`` and cut at the boundary."""
        return split_data(self.frame, self.building, network, options, self.boundary)


@dataclass
class Selection:
    """The state of the forward selection: the model reached so far, the round, the extensions
    accepted in order, the latest verdict on every other candidate, the candidates that cannot
    be built (with the reason), the current model's refits on the folds (once needed), and the
    outcome of an attempt to repair an inadequate base model."""

    current: Fit
    round_no: int = 0
    accepted: list[Finding] = field(default_factory=list)
    verdicts: dict[str, Finding] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    current_folds: list[Fit] | None = None
    current_blocks: list[Fit] | None = None
    repair: dict | None = None

    def trial(self) -> Selection:
        """A copy to try a step on, whose containers can change without changing this one's."""
        return replace(
            self,
            accepted=list(self.accepted),
            verdicts=dict(self.verdicts),
            skipped=dict(self.skipped),
        )

    def take(self, finding: Finding) -> None:
        """Accept ``finding`` and continue from its model (an earlier verdict on its effect goes:
        it is accepted, not a verdict)."""
        self.verdicts.pop(finding.effect, None)
        self.accepted.append(finding)
        self.go_on_from(finding.fit)

    def go_on_from(self, fit: Fit, fold_fits: list[Fit] | None = None) -> None:
        """Continue from ``fit`` (and its rolling folds' fits where known); the fits judged
        against the model before it are no longer its own."""
        self.current, self.current_folds, self.current_blocks = fit, fold_fits, None

    def findings(self, pattern: str) -> list[Finding]:
        """Accepted first, then the rest with the refitted and most helpful ahead, each with its
        plain-words explanation against the baseline's error ``pattern``."""
        findings = self.accepted + sorted(
            (v for v in self.verdicts.values() if not v.accepted),
            key=lambda v: (v.rmse_test_after is not None, v.improvement_k, v.screen_explained),
            reverse=True,
        )
        for f in findings:
            f.explanation = explain(f, pattern)
        return findings


def diagnose(
    frame: pd.DataFrame,
    building: Building,
    model: str = "basic",
    settings: DiagnoseSettings | None = None,
    progress: Callable[[str], None] | None = None,
) -> Report:
    """Run the whole diagnosis on a validated contract frame (UTC index)."""
    with one_blas_thread():
        return _diagnose(frame, building, model, settings or DiagnoseSettings(), progress)


def _diagnose(
    frame: pd.DataFrame,
    building: Building,
    model: str,
    settings: DiagnoseSettings,
    progress: Callable[[str], None] | None,
) -> Report:
    started = time.perf_counter()
    frame = aggregated(bridge_short_gaps(frame), settings.min_step_s)
    timezone = building.location.timezone
    say = progress or (lambda message: None)
    problem, left_out = _problem(frame, building, settings, say)
    problem.say(f"fitting {model} on the training period (until {problem.boundary.date()})")
    baseline = _baseline(problem, model)
    clock = check_clock(problem, baseline) if settings.clock_check else None
    if clock is not None and clock.offset_h:
        problem.say(f"  {clock.words()}; fitting {model} again")
        frame = realigned(frame, clock.offset_h, timezone)
        problem, left_out = _problem(frame, building, settings, say)
        baseline = _baseline(problem, model)
    baseline = _lights_placed(problem, _surfaces_placed(problem, baseline))
    quality, health = _health(problem, baseline, weigh_bounds=True)
    locate = _locate(baseline, building)
    state = Selection(baseline)
    if not health.settled:
        problem.say(f"  {health.summary()}")
        _repair(problem, state)
    _select(problem, state)
    _backward(problem, state)
    if problem.settings.excess_sun and attribute_excess_sun(
        problem, state, _context(problem, state.current)
    ):
        _backward(problem, state)
    _recheck_repair(problem, state)
    findings = state.findings(locate["train"]["summary"])
    whiteness = {
        "baseline": ljung_box(baseline.innovations_test, baseline.split.test.times),
        "final": ljung_box(state.current.innovations_test, state.current.split.test.times),
    }
    problem.say("forecasting the test half day by day")
    day_ahead = day_ahead_block(baseline, state.current, timezone)
    return Report(
        building,
        model,
        problem.boundary,
        baseline,
        state.current,
        locate,
        findings,
        state.skipped,
        whiteness,
        time.perf_counter() - started,
        health,
        quality,
        state.repair,
        problem.folds,
        left_out,
        day_ahead,
        clock,
    )


def _problem(
    frame: pd.DataFrame, building: Building, settings: DiagnoseSettings, say: Callable[[str], None]
) -> tuple[Problem, list[Fold]]:
    """The record cut at its train/test boundary with its informative rolling folds, and the
    folds left out."""
    timezone = building.location.timezone
    boundary = split_time(frame, settings.train_fraction, timezone)
    check_diagnosable(frame, boundary)
    folds, left_out = [], []
    if settings.evidence == "folds":
        days = (settings.fold_train_days, settings.fold_test_days, settings.max_folds)
        folds, left_out = _informative(frame, rolling_folds(frame.index, timezone, *days))
    return Problem(frame, building, boundary, settings, say, folds), left_out


def _informative(frame: pd.DataFrame, folds: list[Fold]) -> tuple[list[Fold], list[Fold]]:
    """The folds whose training window runs the HVAC enough to identify its effect on what the
    test window asks (``MIN_HVAC_SHARE``), and the folds left out."""
    if Q_HVAC not in frame.columns:
        return folds, []
    q = frame[Q_HVAC].abs()
    kept, left_out = [], []
    for fold in folds:
        train = q[fold.in_training(q.index)].mean()
        test = q[(q.index >= fold.test_start) & (q.index < fold.test_end)].mean()
        (left_out if train < MIN_HVAC_SHARE * test else kept).append(fold)
    return kept, left_out


def _baseline(problem: Problem, model: str) -> Fit:
    """The best of ``baseline_starts`` independent fits of the model as given.

    RC models often have two basins that swap the roles of two capacitors; one genetic search
    falls into the worse one often enough that every extension would get the credit a better
    optimum brings. Bounds derived from the building span every construction from the lightest
    to the heaviest, a box so wide that short searches can all settle in a basin far from the
    typical one (a wall node taking the sun on a near-zero resistance); so one of the searches
    runs in the narrower box of the thesis's typical per-area values (Table 2.3), and a refit
    within the building's bounds started from its optimum competes with the others.
    """
    settings, options = problem.settings, SignalOptions.for_columns(problem.frame.columns)
    network = _base_model(problem, model, settings.bounds)
    split = problem.split(network, options)
    starts = [
        FitJob(network, options, split, settings.preset, settings.random_state + k)
        for k in range(settings.baseline_starts)
    ]
    widened = settings.bounds != "thesis"
    if widened:
        typical = _base_model(problem, model, "thesis")
        typical_split = problem.split(typical, options)
        starts[-1] = FitJob(typical, options, typical_split, settings.preset, settings.random_state)
    fits = fit_many(starts, settings.workers)
    if widened:
        # The typical box's optimum is a start, not a result: its bounds are not this building's.
        fits[-1] = FitJob(
            network, options, split, settings.preset, settings.random_state, [fits[-1].params]
        ).run()
    return min(fits, key=lambda f: f.sse_train)


def _surfaces_placed(problem: Problem, baseline: Fit) -> Fit:
    """The base model with its interior surfaces between the air and the mass (``surfaces``),
    where r_mass_surf settles inside its range, fits the training period better and forecasts
    the test period no worse; otherwise the base model as fitted (r_mass_surf at its least is the
    thesis's routing)."""
    network = with_surface_node(baseline.network)
    if network is None:
        return baseline
    r_mass_surf = network.parameters[R_MASS_SURF]
    low, high = r_mass_surf.lower, r_mass_surf.upper
    placed = _refined_base(problem, baseline, network, R_MASS_SURF, (low, (low + high) / 2))
    if placed is None or R_MASS_SURF in placed.at_bounds:
        return baseline
    problem.say(
        f"  the interior surfaces give {released_share(placed.params):.2f} of the radiant heat "
        f"to the air: test RMSE {baseline.rmse_test:.3f} → {placed.rmse_test:.3f} K"
    )
    return placed


def _lights_placed(problem: Problem, baseline: Fit) -> Fit:
    """The base model with the lights' heat let into the air in the share a luminaire convects
    (``metered``), where the fitted share settles inside its range at ``MIN_SHARE_TAKEN`` or
    more, fits the training period better and forecasts the test period no worse; otherwise the
    base model as fitted.

    A share pressed to the most a luminaire convects says the occupied hours want more heat in
    the air than the lights can give: heat missing, which the unmetered gain is there to judge,
    so the base model is left as it was; a share of none is the model's own routing."""
    network = with_lights_in_air(baseline.network)
    if network is None:
        return baseline
    low, high = LIGHT_CONVECTIVE_SHARE
    placed = _refined_base(problem, baseline, network, F_LIGHT_AIR, (low, (low + high) / 2))
    if placed is None:
        return baseline
    share = placed.params[F_LIGHT_AIR]
    if share < MIN_SHARE_TAKEN or F_LIGHT_AIR in placed.at_bounds:
        return baseline
    problem.say(
        f"  the lights convect {share:.2f} of their heat into the air: "
        f"test RMSE {baseline.rmse_test:.3f} → {placed.rmse_test:.3f} K"
    )
    return placed


def _refined_base(
    problem: Problem,
    baseline: Fit,
    network: RCNetwork,
    parameter: str,
    starts: tuple[float, ...],
) -> Fit | None:
    """``network`` (the base model with one more ``parameter``) fitted from the base model's
    optimum with ``parameter`` at each of ``starts``; the fit where it fits the training period
    better and forecasts the test period no worse, else None."""
    settings, options = problem.settings, baseline.options
    begin = [{**baseline.params, parameter: value} for value in starts]
    split = problem.split(network, options)
    job = FitJob(network, options, split, settings.preset, settings.random_state, begin)
    (placed,) = fit_many([job], settings.workers)
    better = placed.sse_train < baseline.sse_train and placed.rmse_test <= baseline.rmse_test
    return placed if better else None


def _base_model(problem: Problem, model: str, bounds: str) -> RCNetwork:
    """The model as given, with the glazing the building declares (``declared``)."""
    network = get_model(model, problem.building, problem.frame.columns, bounds=bounds)
    return with_declared_glazing(network, problem.building, mass_node(network))


def _health(problem: Problem, fit: Fit, weigh_bounds: bool = False) -> tuple[FitQuality, Health]:
    """The fitted model's test error against naive forecasts, and its health verdict; with
    ``weigh_bounds``, a bound counts against it only where the data press on it (the base
    model's verdict), else every bound does (whether a repair step has settled it)."""
    quality = _quality(problem, fit)
    health = check_health(
        fit.network,
        fit.params,
        quality,
        building=problem.building,
        pressure=_pressure_on_bounds(problem, fit) if weigh_bounds else None,
    )
    return quality, health


def _quality(problem: Problem, fit: Fit) -> FitQuality:
    """The fitted model's test error against naive forecasts (``health.fit_quality``)."""
    return fit_quality(
        problem.frame[T_IN],
        fit.split.test.times,
        fit.simulated_test,
        problem.building.location.timezone,
    )


def _pressure_on_bounds(problem: Problem, fit: Fit) -> dict[str, float]:
    """Per parameter on a bound (not at a physical zero), the share of the training RMSE a refit
    with that bound a decade further out gains (``health.relaxed_bounds``; least squares from
    the fit, one batch): whether the data press on the bound or the fit merely rests there."""
    settings = problem.settings
    pressed = [b for b in on_bounds(fit.network, fit.params) if not b.physical_none]
    jobs = [
        FitJob(
            fit.network,
            fit.options,
            fit.split,
            settings.fold_preset,
            settings.random_state,
            [fit.params],
            relaxed_bounds(fit.network, b),
        )
        for b in pressed
    ]
    refits = fit_many(jobs, settings.workers)
    rmse_train = max(fit.rmse_train, 1e-12)  # an exact fit gains nothing anywhere
    return {b.name: 1.0 - r.rmse_train / rmse_train for b, r in zip(pressed, refits, strict=True)}


def _repair(problem: Problem, state: Selection) -> None:
    """Add the structural ``thermal_mass`` step to a base model that is inadequate or rests a
    parameter on a bound, and continue from it if that leaves no parameter on any bound (the
    every-bound health) with a plausible added capacity (a base model too low in
    order ends its capacities on their bounds); otherwise leave the base model as it is."""
    effect = "thermal_mass"
    if effect not in problem.settings.effects:
        return
    ext = CANDIDATES[effect](_context(problem, state.current))
    if isinstance(ext, Skipped):
        return
    problem.say(f"  trying {effect} to make the base model healthy")
    current, settings = state.current, problem.settings
    split = problem.split(ext.network, ext.signals)
    fit = _refits(problem, current, [ext], {effect: split})[0]
    _, health = _health(problem, fit)
    problems = assess(ext, fit.params).problems
    state.repair = {
        "effect": effect,
        "verdict": "healthy" if health.healthy and not problems else "inadequate",
        "reasons": [*health.reasons, *problems],
        "rmse_test": fit.rmse_test,
    }
    if state.repair["reasons"]:
        problem.say(f"  still inadequate with {effect}: {'; '.join(state.repair['reasons'])}")
        return
    screened = screen(ext, current, split, settings.random_state)
    finding = _judge(problem, ext, current, fit, screened, 0)
    finding.accepted, finding.baseline_repair = True, True
    finding.reason = f"taken to make the base model healthy ({finding.reason})"
    state.take(finding)
    _settle_sun(problem, state, finding)


def _judge(
    problem: Problem, ext: Extension, current: Fit, fit: Fit, screened: Screen, round_no: int
) -> Finding:
    """The single split's verdict on a refitted extension, with its fitted magnitudes in
    physical units; an implausible magnitude rejects it, an evident one asks a smaller cut."""
    assessment = assess(ext, fit.params)
    finding = judge(
        ext,
        current,
        fit,
        screened,
        round_no,
        problem.settings,
        problem.building,
        assessment.evident,
    )
    reject_implausible(finding, assessment.magnitudes, assessment.problems)
    return finding


def _refits(
    problem: Problem, current: Fit, extensions: list[Extension], splits: dict[str, Split]
) -> list[Fit]:
    """Each extension refitted on the training period (``_fit_from_current``)."""
    return _fit_from_current(problem, current, extensions, [splits[e.effect] for e in extensions])


def _fit_from_current(
    problem: Problem, current: Fit, extensions: list[Extension], splits: list[Split]
) -> list[Fit]:
    """Each extension fitted on its split's training period, started from the current
    parameters with the extension neutral and as they are."""
    settings = problem.settings
    return fit_many(
        [
            FitJob(
                e.network,
                e.signals,
                split,
                refit_preset(settings, e, current.network),
                settings.random_state,
                [{**current.params, **e.neutral}, dict(current.params)],
            )
            for e, split in zip(extensions, splits, strict=True)
        ],
        settings.workers,
    )


def refit_preset(
    settings: DiagnoseSettings, ext: Extension, current: RCNetwork
) -> str | EstimatorSettings:
    """The estimator preset of ``ext``'s refit from the ``current`` model: ``structural_preset``
    where it changes the dynamics — a new state (the thermal mass, the emitter, the ground through
    its layer of soil) or a re-routing — whose longer genetic search explores the basins a new
    capacitor brings; ``preset`` where it only adds inputs.

    The soil's capacity under a slab trades against the base model's own stores: on the
    thirty-seventh sealed set's bare open-plan slab in Golden, the short search read the ground
    at 12.5 °C, U 1.9 W/(m²K), and forecast the test half 18 % worse; the longer one read 7.9 °C
    at U 1.2 (the soil 9.1 °C over those months, the floor 1.08) and 23 % better."""
    adds_state = len(ext.network.capacitors) > len(current.capacitors)
    return settings.structural_preset if ext.structural or adds_state else settings.preset


def _locate(baseline: Fit, building: Building) -> dict:
    """Where and when the baseline misses, on both periods (open loop and one step ahead)."""
    train_frame, test_frame = baseline.split.train.frame, baseline.split.test.frame
    return {
        "train": summarize(baseline.residual_train, train_frame, building),
        "test": summarize(baseline.residual_test, test_frame, building),
        # One-step-ahead errors show fast, local misses the open-loop drift can hide.
        "innovations": {
            "train": summarize(baseline.innovations_train, train_frame, building),
            "test": summarize(baseline.innovations_test, test_frame, building),
        },
    }


def _select(problem: Problem, state: Selection) -> None:
    """Extend the model by one accepted effect a round, until a round accepts none (nor a pair
    masked in it, ``_masked_pair``), no candidate is left to build, or ``max_rounds`` is
    reached."""
    round_no = 1
    while round_no <= problem.settings.max_rounds:
        state.round_no = round_no
        extensions = _extensions(problem, state)
        if not extensions:
            break
        problem.say(
            f"round {round_no}: screening {len(extensions)} candidate(s) on "
            f"{state.current.network.name}"
        )
        best = _round(problem, state, extensions)
        if best is not None:
            state.take(best)
            _settle_sun(problem, state, best)
        elif round_no == problem.settings.max_rounds or not _masked_pair(problem, state):
            break
        round_no = state.round_no + 1


# Two effects can mask each other in a forward selection: each alone is judged against a model
# whose parameters bend to take part of the other, and neither passes, while together they do
# (the suppressor effect of regression, Conger 1974). In the test bed's open-plan Chicago ground +
# wind pairs (sets 27 and 32) the wind alone cut the test half by 6 % and 4 %, the ground alone
# worsened it by 38 % and 45 %, and the two together cut it by 48 % and 55 %. The pair is looked
# for only where the model, nothing more passing, forecasts the test half no better than a naive
# forecast (``health.fit_quality``: the temperature a day or a week earlier, or its mean): what two
# large effects leave out shows there, and a trial round costs a round's refits (tried after every
# round that accepted nothing, it took the main bed's light Torino null from 23 to 37 s).


def _masked_pair(problem: Problem, state: Selection) -> bool:
    """After a round that accepts nothing: its near miss the training half pays for most
    (``_near_miss``) is taken on trial and the next round run on it. The pair is kept when that
    round accepts an effect, the near miss passes the single split's checks on top of that effect
    alone (its margins, its ΔBIC, its magnitudes plausible in the joint fit), and each of the
    two, added last to the other, helps across the folds (the rule they would enter by). Returns
    whether it was kept; ``state`` then continues from the pair."""
    near = _near_miss(problem, state) if _quality(problem, state.current).poor else None
    if near is None:
        return False
    problem.say(f"  nothing passed alone; trying {near.effect} with the next round's candidates")
    alone_verdict = near
    near = replace(near, detail=dict(near.detail), absent=dict(near.absent))
    trial = state.trial()
    trial.take(near)
    _settle_sun(problem, trial, near)
    trial.round_no += 1
    extensions = _extensions(problem, trial)
    partner = _round(problem, trial, extensions) if extensions else None
    if partner is None:
        return _refused(alone_verdict, None, "no other candidate passed on top of it")
    alone = state.verdicts.get(partner.effect)
    if alone is None or alone.fit is None:
        why = f"{partner.effect} has no fit of its own, alone, to judge the pair against"
        return _refused(alone_verdict, partner.effect, why)
    on_top = _judge(problem, near.extension, alone.fit, partner.fit, near.screen, near.round)
    if not on_top.accepted:
        problem.say(f"  {near.effect} on top of {partner.effect} alone: {on_top.reason}")
        why = f"on top of {partner.effect} alone, {on_top.reason}"
        return _refused(alone_verdict, partner.effect, why)
    trial.take(partner)
    _settle_sun(problem, trial, partner)
    failed = _fails_added_last(problem, trial, [near, partner])
    if failed:
        return _refused(alone_verdict, partner.effect, failed)
    near.accepted = True
    near.reason = (
        f"accepted with {partner.effect}, which masked it ({near.reason}); on top of "
        f"{partner.effect} alone: {on_top.reason.removeprefix('accepted: ')}"
    )
    near.detail["taken_with"] = partner.effect
    partner.detail["taken_with"] = near.effect
    vars(state).update(vars(trial))
    return True


def _near_miss(problem: Problem, state: Selection) -> Finding | None:
    """Of the round's refitted candidates, the one the training half's ΔBIC pays for most among
    those that are plausible, improve the test half too and may be named on their own (not a
    rival, ``_rivals``); None where there is none."""
    rivals, margin = _rivals(problem, state), problem.settings.bic_margin
    near = [
        f
        for f in state.verdicts.values()
        if f.round == state.round_no
        and f.fit is not None
        and f.plausible
        and f.effect not in rivals
        and f.improvement_k > 0.0
        and f.delta_bic is not None
        and f.delta_bic <= -margin
    ]
    return min(near, key=lambda f: f.delta_bic, default=None)


def _fails_added_last(problem: Problem, state: Selection, pair: list[Finding]) -> str:
    """What the folds say (``judge_folds``) of each finding of ``pair`` that, left out of
    ``state``'s model and added last again, does not help across them: "" where both help (and
    without folds). The first keeps that evidence as its own (it was judged against the model
    before the pair)."""
    if not problem.folds:
        return ""
    _, evidence = _without_each(problem, state, pair)
    verdicts = [judge_folds(ev, problem.settings.fold_rule) for ev in evidence]
    for finding, (_, text) in zip(pair, verdicts, strict=True):
        problem.say(f"  {finding.effect} added last to the pair: {text}")
    pair[0].evidence = evidence[0]
    pair[0].folds = evidence[0].to_dict(problem.folds, problem.building.location.timezone)
    return "; ".join(
        f"{finding.effect} added last to the pair: {text}"
        for finding, (ok, text) in zip(pair, verdicts, strict=True)
        if not ok
    )


def _refused(near: Finding, partner: str | None, why: str) -> bool:
    """Record on the near miss's own verdict that it was tried as a masked pair (with
    ``partner``, the effect the trial round accepted on top of it) and why the pair was not
    kept, so the report shows the step was taken. Returns False: nothing was kept."""
    near.detail["pair_trial"] = {"with": partner, "outcome": why}
    tried = f"with {partner}" if partner else "with the next round's candidates"
    near.reason += f"; tried as a masked pair {tried}, not kept: {why}"
    return False


def _settle_sun(problem: Problem, state: Selection, finding: Finding) -> None:
    """Once a storage (``thermal_mass``) is accepted, let the declared glazing's sun fall on it too
    (``declared.sun_on_added_mass``), refitted from the accepted fit; kept where it fits the
    training period better without forecasting the test period worse. The candidate itself
    takes no sun: judged with it, a null's base model took a storage that re-timed its sun."""
    if finding.effect != "thermal_mass":
        return
    network = sun_on_added_mass(state.current.network, finding.detail["node"])
    if network is None:
        return
    current, settings = state.current, problem.settings
    job = FitJob(
        network,
        current.options,
        problem.split(network, current.options),
        settings.preset,
        settings.random_state,
        [{**current.params, G_WINDOW_ADDED_MASS: 0.0}],
    )
    (fit,) = fit_many([job], settings.workers)
    if fit.sse_train < current.sse_train and fit.rmse_test <= current.rmse_test:
        problem.say(
            f"  the added storage takes g = {fit.params[G_WINDOW_ADDED_MASS]:.2f} of the "
            f"glazing's sun: test RMSE {current.rmse_test:.3f} → {fit.rmse_test:.3f} K"
        )
        finding.absent = {**finding.absent, G_WINDOW_ADDED_MASS: 0.0}
        finding.detail["glazing_g_on_storage"] = fit.params[G_WINDOW_ADDED_MASS]
        state.go_on_from(fit)


def _extensions(problem: Problem, state: Selection) -> list[Extension]:
    """Every candidate not yet accepted that can be built on the current model; the others are
    recorded in ``state.skipped`` with the reason (and taken out again once they can be built)."""
    ctx = _context(problem, state.current)
    taken = {f.effect for f in state.accepted}
    out = []
    for effect in (e for e in problem.settings.effects if e not in taken):
        built = CANDIDATES[effect](ctx)
        if isinstance(built, Skipped):
            state.skipped.setdefault(effect, built.reason)
        else:
            state.skipped.pop(effect, None)
            out.append(built)
    return out


def _rivals(problem: Problem, state: Selection) -> set[str]:
    """The candidates a round may name only against another that passes: the opaque sun where
    glazing is declared, whose evidence on its own is the model's sun beyond glass after the
    selection (``excess_sun``), not a margin of test error."""
    judged_after = problem.settings.excess_sun and has_glazing_g(state.current.network)
    return {EXCESS_SUN_EFFECT} if judged_after else set()


def _unrivalled(findings: list[Finding], rivals: set[str]) -> None:
    """Where no finding but a rival passes, each passing rival is rejected with why."""
    if any(f.accepted and f.effect not in rivals for f in findings):
        return
    for f in findings:
        if f.accepted and f.effect in rivals:
            f.accepted = False
            f.reason = (
                f"passed its own margins ({f.reason.removeprefix('accepted: ')}) but nothing else "
                f"did: {RIVAL_ONLY}"
            )


def _context(problem: Problem, current: Fit) -> Context:
    """What a candidate is built from: the current model, its training data and residual."""
    return Context(
        current.network,
        problem.building,
        current.split.train,
        current.options,
        current.params,
        current.residual_train,
    )


def _refine(
    problem: Problem, current: Fit, extensions: list[Extension], fits: list[Fit]
) -> list[tuple[int, Extension, Fit]]:
    """Re-learn the shape of learnt inputs (schedules) from each refit and refit once more;
    returns the refined versions as (index of the first version, extension, fit).

    The first schedule is learnt from the current model's residual, whose parameters had bent to
    absorb part of the missing effect; after a refit the model is closer to the truth and the
    residual shows the effect's shape more fully. A better training fit does not make it the
    better version: the refit's new basin can fit the training weeks more closely and forecast
    worse (``_versions`` chooses).
    """
    settings = problem.settings
    jobs, where = [], []
    for i, (ext, fit) in enumerate(zip(extensions, fits, strict=True)):
        if not ext.learnt:
            continue
        params = {name: fit.params[name] for name in current.params}
        train = current.split.train
        ctx = Context(
            current.network,
            problem.building,
            train,
            current.options,
            params,
            residual_at(current.network, params, train),
        )
        refined = CANDIDATES[ext.effect](ctx)
        if isinstance(refined, Skipped) or refined.signals == ext.signals:
            continue
        split = problem.split(refined.network, refined.signals)
        jobs.append(
            FitJob(
                refined.network,
                refined.signals,
                split,
                settings.preset,
                settings.random_state,
                [dict(fit.params)],
            )
        )
        where.append((i, refined))
    if jobs:
        problem.say(f"  refining the learnt shape of {', '.join(r.effect for _, r in where)}")
    refits = fit_many(jobs, settings.workers)
    return [(i, refined, fit) for (i, refined), fit in zip(where, refits, strict=True)]


def _alternatives(
    problem: Problem, current: Fit, extensions: list[Extension]
) -> list[tuple[int, Extension, Fit]]:
    """Each extension's alternatives (``Extension.alternatives``: the same parameters, another
    reading of its input), refitted from the same starts as the first version (``_refits``), so
    that each version is the fit it would be alone; as (index of the first version, alternative,
    fit). A ``folds_only`` alternative only where the folds judge."""
    where = [
        (i, alt)
        for i, ext in enumerate(extensions)
        for alt in ext.alternatives
        if problem.folds or not alt.folds_only
    ]
    alternatives = [alt for _, alt in where]
    splits = [problem.split(alt.network, alt.signals) for alt in alternatives]
    refits = _fit_from_current(problem, current, alternatives, splits) if where else []
    return [(i, alt, fit) for (i, alt), fit in zip(where, refits, strict=True)]


def _versions(
    extensions: list[Extension], fits: list[Fit], others: list[tuple]
) -> list[tuple[Extension, Fit]]:
    """The versions of each extension to judge: the first, and the refined or alternative ones
    (``_one_version_each`` chooses among them once they are judged)."""
    return list(zip(extensions, fits, strict=True)) + [(ext, fit) for _, ext, fit in others]


# The detail keys that name a version of an effect not taken (``_one_version_each``).
NOT_TAKEN = "_not_taken"


def _one_version_each(findings: list[Finding]) -> list[Finding]:
    """Per effect, the version the evidence favours: accepted before rejected, then the larger
    relative cut of the pooled test RMSE across its folds (where they judge), then the better
    training fit; the other is named in its detail.

    The cut is relative because two versions can be judged on unlike folds — one on the rolling
    folds' four weeks of training, another on the held-out blocks fitted on the rest of the
    record — whose errors are no measure of one another; on the same folds it orders them as
    their pooled test RMSEs do."""

    def rank(f: Finding) -> tuple[bool, float, float]:
        e = f.evidence
        judged = e is not None and e.pooled_before > 0.0
        kept = e.pooled_after / e.pooled_before if judged else float("inf")
        return (not f.accepted, kept, f.fit.sse_train)

    chosen: dict[str, Finding] = {}
    for f in findings:
        other = chosen.get(f.effect)
        if other is None:
            chosen[f.effect] = f
            continue
        best, worse = sorted((other, f), key=rank)
        _carry_not_taken(best, worse)
        if worse.detail.get("base_load", False) != best.detail.get("base_load", False):
            _name_base_load_not_taken(best, worse)
        else:
            if worse.evidence is not None and "schedule" in worse.detail:
                words = f"{worse.detail['schedule']}: {_version_words(worse)}"
                _add_not_taken(best, "schedule_not_taken", words)
            if "follows" in worse.detail and "follows" not in best.detail:
                _add_not_taken(best, "use_not_taken", _version_words(worse))
        if "ground_lag_months" in worse.detail:
            words = f"{_ground_words(worse)} ({_version_words(worse)})"
            _add_not_taken(best, "ground_lag_not_taken", words)
        if "radiant_to" in worse.detail:
            _add_not_taken(best, "radiant_not_taken", _version_words(worse))
        elif "radiant_to" in best.detail:
            _add_not_taken(best, "convective_not_taken", _version_words(worse))
        chosen[f.effect] = best
    return list(chosen.values())


def _name_base_load_not_taken(best: Finding, worse: Finding) -> None:
    """An unmetered gain's version with a base load at every hour against one without: the
    other named, with its shape, in ``base_load_not_taken`` or ``no_base_load_not_taken``
    (each version not taken in turn)."""
    key = "base_load_not_taken" if worse.detail.get("base_load") else "no_base_load_not_taken"
    shape = worse.detail.get("schedule", f"in step with {worse.detail.get('follows')}")
    _add_not_taken(best, key, f"{shape}: {_version_words(worse)}")


def _carry_not_taken(best: Finding, worse: Finding) -> None:
    """The versions ``worse`` had beaten before it lost to ``best`` stay named: each of its
    ``*_not_taken`` entries is added to ``best``'s."""
    for key, words in worse.detail.items():
        if key.endswith(NOT_TAKEN) and words:
            _add_not_taken(best, key, words)


def _add_not_taken(best: Finding, key: str, words: str) -> None:
    """``best.detail[key]`` lists every version not taken, in the order they lost."""
    named = (best.detail.get(key), words)
    best.detail[key] = "; ".join(w for w in named if w)


def _ground_words(f: Finding) -> str:
    """A ground version's reading: its lag, and the layer of soil where it has one."""
    words = f"{f.detail['ground_lag_months']:.1f} months"
    if not f.detail.get("soil_layer"):
        return words
    return f"{words} through {f.fit.params['d_soil']:.1f} m of soil"


def _version_words(f: Finding) -> str:
    """How a version not taken fared: its pooled test RMSE on its own folds, before → after and
    the relative cut the versions are ranked by (``_one_version_each``), else its verdict."""
    if f.evidence is not None:
        return f"{f.evidence.pooled_words()} on its folds"
    return "accepted" if f.accepted else (f.reason or "rejected")


def _round(problem: Problem, state: Selection, extensions: list[Extension]) -> Finding | None:
    """Screen every extension, refit the most promising, and return the accepted one (or None);
    every verdict of the round is recorded in ``state.verdicts``."""
    settings, current, round_no = problem.settings, state.current, state.round_no
    splits = {e.effect: problem.split(e.network, e.signals) for e in extensions}
    screens = screen_all(extensions, current, splits, settings.random_state, settings.workers)

    # Screening is a linearisation; the first round refits every candidate for real, later
    # rounds the ``confirm`` most promising (all by default: a screen on a residual the fit has
    # bent to take part of an effect underrates it, and left pairs' second effects unrefitted).
    def promise(e: Extension) -> tuple[float, float]:
        earlier = state.verdicts.get(e.effect)
        return (earlier.improvement_k if earlier else 0.0, screens[e.effect].explained)

    ranked = sorted(extensions, key=promise, reverse=True)
    n_refit = len(ranked) if round_no == 1 else settings.confirm
    refit = ranked[:n_refit]
    problem.say(f"  refitting {', '.join(e.effect for e in refit)}")
    fits = _refits(problem, current, refit, splits)
    others = _refine(problem, current, refit, fits) + _alternatives(problem, current, refit)
    versions = _versions(refit, fits, others)
    confirmed = [
        _judge(problem, e, current, fit, screens[e.effect], round_no) for e, fit in versions
    ]
    # A rival alone is rejected before the folds, so it costs no fold refits, and again after
    # them, since the effect it stood beside may fail there.
    rivals = _rivals(problem, state)
    _unrivalled(confirmed, rivals)
    if problem.folds:
        _confirm_on_folds(problem, state, [e for e, _ in versions], confirmed)
        _unrivalled(confirmed, rivals)
    confirmed = _one_version_each(confirmed)
    for ext in ranked[n_refit:]:
        state.verdicts[ext.effect] = screened_only(ext, current, screens[ext.effect], round_no)
    for finding in confirmed:
        state.verdicts[finding.effect] = finding
    return _winner(confirmed, round_no)


def _confirm_on_folds(
    problem: Problem, state: Selection, extensions: list[Extension], findings: list[Finding]
) -> None:
    """Refit the current model and every extension that passed the single split on each fold
    (warm-started from their fits on the whole training period, in one parallel batch) and keep
    only those that help across the folds (``confirm_on_folds``). Under "hybrid" fold training,
    those short of the training half's BIC alone and those whose input is too slow for the
    rolling folds (``_slow_input``) are judged over the season instead — a slow input also where
    it fell short of the single split's test alone: fitted on autumn and tested on the spring,
    the soil's slow course is confounded with every seasonal trend the base model carries (the
    sun's rise), which the test half then judges rather than the soil."""
    pairs = list(zip(extensions, findings, strict=True))
    if problem.settings.fold_training == "hybrid":
        for e, f in pairs:
            slow = _slow_input(problem, e, f) if f.accepted or f.short_of == SHORT_OF_TEST else None
            if slow is not None:
                f.detail[SLOW_INPUT] = slow
        _confirm_over_the_season(problem, state, [p for p in pairs if _over_the_season(p[1])])
    # Those judged over the season keep that evidence: the rolling folds are not asked again.
    passing = [(e, f) for e, f in pairs if f.accepted and not _over_the_season(f)]
    if not passing:
        return
    models = [(e.network, e.signals, f.fit.params) for e, f in passing]
    # A learnt schedule and its refinement are two versions of one effect.
    counts = Counter(e.effect for e, _ in passing)
    names = [f"{e} ({n} versions)" if n > 1 else e for e, n in counts.items()]
    problem.say(f"  confirming {', '.join(names)} on {len(problem.folds)} rolling folds")
    fits = _fold_fits_beside_current(problem, state, models)
    before = tuple(f.residual_test for f in state.current_folds)
    single = {id(f): f.reason for _, f in passing}
    for (_, finding), fold_fits in zip(passing, fits, strict=True):
        after = tuple(f.residual_test for f in fold_fits)
        confirm_on_folds(
            finding,
            FoldEvidence(before, after),
            problem.folds,
            problem.settings,
            problem.building.location.timezone,
        )
    gains = [(e, f, single[id(f)]) for e, f in passing if e.effect == "unmetered_gains"]
    if problem.settings.fold_training == "hybrid" and not any(f.accepted for _, f, _ in gains):
        _gains_over_the_season(problem, state, gains)


def _over_the_season(finding: Finding) -> bool:
    """Whether ``finding`` is judged on the held-out blocks rather than the rolling folds: short
    of the training half's BIC alone, or with an input too slow for the rolling folds (having
    passed the single split, or fallen short of its test alone)."""
    return finding.short_of == SHORT_OF_BIC or SLOW_INPUT in finding.detail


def _season_judged(finding: Finding) -> bool:
    """Whether ``finding`` was accepted on the held-out blocks for what the rolling folds cannot
    judge: an input too slow for them, or a gain they rejected that holds with the heater off."""
    return SLOW_INPUT in finding.detail or HEATER_OFF in finding.detail


def _slow_input(problem: Problem, ext: Extension, finding: Finding) -> dict | None:
    """The extension's input that varies most within the rolling folds' training weeks, with
    that share of its variation over the record (``folds.within_fold_share``), as the finding's
    ``detail[SLOW_INPUT]``, when even it varies less than ``SLOW_INPUT_SHARE``; None for a
    structural extension or a fast input."""
    split = finding.fit.split
    shares = {}
    for signal, _ in ext.inputs:
        record = pd.concat([split.train.frame[signal], split.test.frame[signal]])
        share = within_fold_share(record, problem.folds)
        if np.isfinite(share):
            shares[signal] = share
    if not shares or max(shares.values()) >= SLOW_INPUT_SHARE:
        return None
    fastest = max(shares, key=shares.__getitem__)
    return {"signal": fastest, "within_fold_share": shares[fastest]}


def _confirm_over_the_season(
    problem: Problem,
    state: Selection,
    season: list[tuple[Extension, Finding]],
) -> None:
    """Findings judged on held-out blocks: short of the training half's BIC alone, or passing
    the single split with an input too slow for the rolling folds (``detail[SLOW_INPUT]``)."""
    judged = _not_the_excess_sun(season, sun_as_glazing_g(state.current))
    if not judged:
        return
    blocks, fits = _block_fits(problem, state, judged)
    for (_, finding), fold_fits in zip(judged, fits, strict=True):
        _judge_on_blocks(problem, state, finding, blocks, fold_fits)


def _judge_on_blocks(
    problem: Problem, state: Selection, finding: Finding, blocks: list[Fold], fits: list[Fit]
) -> None:
    """``confirm_over_the_season`` of ``finding`` by its ``fits`` on the held-out ``blocks``
    against the current model's (``state.current_blocks``)."""
    confirm_over_the_season(
        finding,
        FoldEvidence(
            tuple(f.residual_test for f in state.current_blocks),
            tuple(f.residual_test for f in fits),
        ),
        blocks,
        problem.settings,
        problem.building.location.timezone,
        _season_bic(state.current_blocks, fits),
    )


def _block_fits(
    problem: Problem, state: Selection, pairs: list[tuple[Extension, Finding]]
) -> tuple[list[Fold], list[list[Fit]]]:
    """The held-out blocks and each extension's fits on them (``_fold_fits``); the current
    model's too, once, kept in ``state.current_blocks``."""
    blocks = held_out_blocks(problem.folds, problem.frame.index)
    seasonal = replace(problem, folds=blocks)
    if state.current_blocks is None:
        current = state.current
        (state.current_blocks,) = _fold_fits(
            seasonal, [(current.network, current.options, current.params)]
        )
    return blocks, _fold_fits(seasonal, [(e.network, e.signals, f.fit.params) for e, f in pairs])


def _gains_over_the_season(
    problem: Problem, state: Selection, rejected: list[tuple[Extension, Finding, str]]
) -> None:
    """Unmetered gains that passed the single split (``rejected``: each version with that
    verdict's reason) but not the rolling folds, none of their versions, judged again on the
    held-out blocks (``confirm_over_the_season``) where they forecast the blocks' hours with the
    heater off better, by the relative margin (``heater_off``). A version the rolling folds
    passed is the effect's: the blocks' errors, fitted on more of the record, are no measure
    against the folds' in choosing between versions (``_one_version_each``).

    While the heater holds the set point, a missing gain shows only in the heat it no longer
    gives, which a lower envelope conductance asks as well over a fold's four weeks; the two part
    as the indoor–outdoor difference moves over the season. The hours with the heater off keep
    out what stands in for the heater's own timing (an emitter's lag), which the season alone
    would take."""
    if not rejected:
        return
    blocks, fits = _block_fits(problem, state, [(e, f) for e, f, _ in rejected])
    margin = 1.0 - problem.settings.min_improvement
    heater_off = off_rows(problem.frame)
    for (ext, finding, split_reason), fold_fits in zip(rejected, fits, strict=True):
        off = heater_off_change(state.current_blocks, fold_fits, ext.inputs[0][0], heater_off)
        if off is None or off["rmse_after"] > margin * off["rmse_before"]:
            continue
        finding.detail[HEATER_OFF] = off
        problem.say(
            f"  judging {ext.effect} over the season: with the heater off it forecasts "
            f"{off['rmse_before']:.3f} → {off['rmse_after']:.3f} K over {off['hours']:.0f} h"
        )
        finding.accepted, rolling, finding.reason = True, finding.reason, split_reason
        _judge_on_blocks(problem, state, finding, blocks, fold_fits)
        finding.reason += f" (the rolling folds: {rolling.removeprefix('rejected across folds: ')})"


def _not_the_excess_sun(
    short: list[tuple[Extension, Finding]], g: float | None
) -> list[tuple[Extension, Finding]]:
    """``short`` but the ways the sun comes in that fell short of the BIC, where the model
    already lets in more than glass could (``g``, its sun as the declared glazing's g-value):
    which way carries that excess is the excess-sun step's to judge, with the sun held to glass,
    after the selection; the season's evidence is no ground to pick one before it. Those left
    out are rejected with why."""
    if g is None or g <= G_GLAZING_MAX:
        return short
    kept = []
    for ext, finding in short:
        if not (finding.short_of == SHORT_OF_BIC and finding.effect in EXCESS_EFFECTS):
            kept.append((ext, finding))
            continue
        finding.short_of = None
        finding.reason += (
            f"; the model's sun is already beyond glass (as g = {g:.2f}): the excess-sun step "
            "judges which way it comes in"
        )
    return kept


def _season_bic(current: list[Fit], extended: list[Fit]) -> float:
    """The median over the folds of the extension's ΔBIC on its fold's training rows.

    A held-out block's fit spans the season around its window: the autumn's low sun and the
    spring's high, the cold months and the mild, where the training half has three months of
    one. Effects that only the sun's course or the weather's range identify — a facade's own
    g-value, a sky the heat-loss coefficient stands in for while it is cold — pay for their
    parameters there or nowhere."""
    return float(
        np.median([e.criteria_change(c)["bic"] for c, e in zip(current, extended, strict=True)])
    )


def _fold_fits_beside_current(
    problem: Problem,
    state: Selection,
    models: list[tuple[RCNetwork, SignalOptions, dict[str, float]]],
) -> list[list[Fit]]:
    """``_fold_fits`` of the models; the current model's too, in the same batch, when it has
    none yet (kept in ``state.current_folds``)."""
    current = state.current
    if state.current_folds is not None:
        return _fold_fits(problem, models)
    state.current_folds, *fits = _fold_fits(
        problem, [(current.network, current.options, current.params), *models]
    )
    return fits


def _fold_fits(
    problem: Problem, models: list[tuple[RCNetwork, SignalOptions, dict[str, float]]]
) -> list[list[Fit]]:
    """Each model (network, signals, its fit on the training period) refitted on every fold,
    warm-started from that fit and within its ``trust_region``, in one parallel batch."""
    settings, n = problem.settings, len(problem.folds)
    jobs = [
        FitJob(
            network,
            options,
            split,
            settings.fold_preset,
            settings.random_state,
            [params],
            trust_region(network, params),
        )
        for network, options, params in models
        for split in fold_splits(problem.frame, problem.building, network, options, problem.folds)
    ]
    fits = fit_many(jobs, settings.workers)
    return [fits[k * n : (k + 1) * n] for k in range(len(models))]


def _backward(problem: Problem, state: Selection) -> None:
    """The backward step of a stepwise selection (Efroymson 1960): every accepted finding is
    left out of the final model again, the rest refitted from the final model's parameters, and
    judged on the folds by what it is still worth there.

    A forward selection can take a flexible candidate first (a learnt gain schedule) that stands
    in for part of an effect it cannot express; once the effect itself is in, the stand-in may
    explain nothing more. And a finding is credited with whatever its refit gained, including
    a better optimum of the parameters it did not add: the last finding too is checked, since the
    model without it, refitted from the final parameters, need not be the one it was judged
    against. The finding that no longer helps across the folds (``FoldRule``, the rule it
    entered by) and is worth least is dropped and the check repeated on the model without it;
    the findings kept are ordered by what leaving each out costs on the folds' pooled test, the
    one that matters most first. Steps taken to make the base model healthy are not candidates
    and stay first. A finding accepted on other evidence than the rolling folds (the opaque sun,
    from what the declared glazing admits beyond glass, ``excess_sun``; an input too slow for
    them, judged over the season, ``_slow_input``; a gain they rejected that holds with the
    heater off, ``_gains_over_the_season``) is ordered with the others but not dropped by them;
    the opaque sun is checked after it too, since a finding taken before it may have stood in
    for its sun.
    """
    rule = problem.settings.fold_rule
    while problem.folds:
        judged = [f for f in state.accepted if not f.baseline_repair]
        if len(judged) < 2:
            return
        problem.say(f"  checking {', '.join(f.effect for f in judged)} backward")
        reduced, evidence = _without_each(problem, state, judged)
        worth: dict[str, float] = {}
        failing = []
        for finding, ev in zip(judged, evidence, strict=True):
            ok, text = judge_folds(ev, rule)
            worth[finding.effect] = ev.pooled_before - ev.pooled_after
            finding.backward = _added_last(problem, ev, text, still_needed=ok)
            if not ok and finding.evidence is not None and not _season_judged(finding):
                failing.append(finding)
        state.accepted.sort(key=lambda f: (not f.baseline_repair, -worth.get(f.effect, 0.0)))
        if not failing:
            return
        dropped = min(failing, key=lambda f: worth[f.effect])
        dropped.accepted = False
        dropped.reason = f"dropped by the backward check: {dropped.backward['reason']}"
        state.accepted.remove(dropped)
        state.verdicts[dropped.effect] = dropped
        state.go_on_from(*reduced[judged.index(dropped)])


def _recheck_repair(problem: Problem, state: Selection) -> None:
    """The step taken to make the base model healthy, checked once the selection is over, like
    the findings in ``_backward``: a missing effect bends the base model's parameters too, and a
    storage may then heal the bounds without being the physics left out. A step that does not
    help across the folds of the final model (the rule findings enter by) is not what the data
    show missing. Without it the final model, refitted from the final parameters, is either
    healthy — the step stood in for what the later findings explain and is dropped — or still
    inadequate: the step then stays in the model as the structure its bounds need, listed after
    the later findings (``findings`` are ordered by strength of evidence, CONTRACT §3), and
    where no finding came after it, it is dropped as well, since the first accepted finding is
    the report's answer to what was left out and the data do not show the storage missing. A
    step that helps stays first."""
    repair = next((f for f in state.accepted if f.baseline_repair), None)
    if repair is None or not problem.folds:
        return
    problem.say(f"  checking whether the final model still needs {repair.effect}")
    ((fit, fold_fits),), (evidence,) = _without_each(problem, state, [repair])
    _, health = _health(problem, fit)
    helps, text = judge_folds(evidence, problem.settings.fold_rule)
    later = len(state.accepted) > 1
    kept_for_bounds = later and not health.healthy
    repair.backward = _added_last(
        problem,
        evidence,
        text,
        still_needed=helps or kept_for_bounds,
        helps_on_folds=helps,
        healthy_without=health.healthy,
    )
    if helps:
        return
    state.accepted.remove(repair)
    if kept_for_bounds:
        repair.reason += (
            f"; added last to the final model it fails the folds ({text}): kept for the base "
            "model's bounds, listed after the findings the data show missing"
        )
        state.accepted.append(repair)
        return
    repair.accepted = False
    if health.healthy and later:
        repair.reason = (
            f"dropped once the later findings were in: without it the model is healthy; {text}"
        )
    else:
        without = (
            "is healthy, refitted"
            if health.healthy
            else "rests on its bounds again, but the data do not show the storage missing"
        )
        repair.reason = (
            f"dropped: added last to the model it fails the folds ({text}); without it the "
            f"base model {without}"
        )
    state.verdicts[repair.effect] = repair
    state.go_on_from(fit, fold_fits)


def _added_last(problem: Problem, evidence: FoldEvidence, text: str, **verdict: bool) -> dict:
    """A finding's ``backward`` record: the folds' evidence of it added last to the others, what
    the fold rule said (``text``) and the check's verdict."""
    record = evidence.to_dict(problem.folds, problem.building.location.timezone)
    return {**record, **verdict, "reason": f"added last, to the other findings: {text}"}


def _without_each(
    problem: Problem, state: Selection, judged: list[Finding]
) -> tuple[list[tuple[Fit, list[Fit]]], list[FoldEvidence]]:
    """The final model without each finding in ``judged`` (its new parameters fixed where it does
    nothing): fitted on the training period and on every fold; and per finding the folds' test
    errors without it (``before``) and with it (``after``, the final model's)."""
    settings, final = problem.settings, state.current
    networks = [
        final.network.fixed(f.absent, final.network.name.replace(f"+{f.effect}", ""))
        for f in judged
    ]
    jobs = [
        FitJob(
            network,
            final.options,
            problem.split(network, final.options),
            settings.preset,
            settings.random_state,
            [dict(final.params)],
        )
        for network in networks
    ]
    fits = fit_many(jobs, settings.workers)
    models = [(f.network, f.options, f.params) for f in fits]
    fold_fits = _fold_fits_beside_current(problem, state, models)
    after = tuple(f.residual_test for f in state.current_folds)
    evidence = [FoldEvidence(tuple(f.residual_test for f in ff), after) for ff in fold_fits]
    return list(zip(fits, fold_fits, strict=True)), evidence


def _winner(confirmed: list[Finding], round_no: int) -> Finding | None:
    """Of the round's accepted findings, the one that wins every head to head (on the folds when
    they were judged on folds, ``folds.head_to_head``, else on the single split's test); the others
    are marked not taken with why they lost, the closest as the winner's runner-up."""
    winners = [f for f in confirmed if f.accepted]
    if not winners:
        return None
    best = winners[0]
    for f in winners[1:]:
        best = (best, f)[_duel(best, f)[0]]
    # Closest first: on the folds' pooled test, else on the single split's test.
    losers = sorted(
        (f for f in winners if f is not best),
        key=lambda f: f.evidence.pooled_after if f.evidence else -f.improvement_k,
    )
    for f in losers:
        why = _duel(best, f)[1]
        f.accepted = False
        f.lost_to = {"effect": best.effect, "reason": why}
        f.reason = f"not taken in round {round_no}: lost to {best.effect} — {why}"
    if losers:
        best.runner_up = {"effect": losers[0].effect, "reason": losers[0].lost_to["reason"]}
    return best


def _duel(first: Finding, second: Finding) -> tuple[int, str]:
    """Which of two passing findings explains more (0 or 1), and why the other lost."""
    short = [f.short_of is not None for f in (first, second)]
    if short[0] != short[1]:
        # Judged on unlike folds (held-out blocks fit more data): the one the single split
        # pays for comes first, the season's on its own evidence in a later round.
        loser = first if short[0] else second
        half = "training" if loser.short_of == SHORT_OF_BIC else "test"
        return int(short[0]), f"the {half} half pays for the winner, not for it"
    if first.evidence is not None and second.evidence is not None and _alike(first, second):
        return head_to_head(first.evidence, second.evidence)
    winner = 0 if first.improvement_k >= second.improvement_k else 1
    lo, hi = sorted((first.rmse_test_after, second.rmse_test_after))
    return winner, f"test RMSE {hi:.3f} K against the winner's {lo:.3f} K"


def _alike(first: Finding, second: Finding) -> bool:
    """Whether two findings were judged on folds fitted alike (both on the rolling folds, or both
    on the held-out blocks, ``Finding.folds["training"]``): the blocks' fits span the season and
    err less, so their test errors are no match for the rolling folds'."""
    return (first.folds or {}).get("training") == (second.folds or {}).get("training")
