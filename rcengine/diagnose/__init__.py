"""Mismatch diagnosis: locate where model and recordings differ, name the missing physics, add it,
refit, and show the fit improve on a later period.

    report = diagnose(frame, building, model="basic")
    report.to_json()   # CONTRACT.md §3 diagnose report

Procedure (forward selection):
1. fit the model on the training period (the first part of the record), simulate the later test
   period, and locate the errors (``locate``);
2. build every candidate extension of the vocabulary that the data and building allow
   (``candidates``) and screen them cheaply against the training residual (``screen``);
3. refit the best few for real and accept the one with the largest test improvement if it cuts
   the test RMSE by a meaningful margin and an information criterion with an effective sample size
   agrees; repeat from the extended model until nothing more is accepted.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import pandas as pd

from rcengine.building import Building
from rcengine.diagnose.candidates import CANDIDATES, Context, Extension, Skipped
from rcengine.diagnose.fitting import Fit, FitJob, fit_many, residual_at, split_data
from rcengine.diagnose.locate import summarize
from rcengine.diagnose.report import Finding, Report, explain, judge, screened_only
from rcengine.diagnose.screen import screen
from rcengine.diagnose.whiteness import ljung_box
from rcengine.models import get_model
from rcengine.parallel import one_blas_thread
from rcengine.signals import SignalOptions

__all__ = ["DiagnoseSettings", "Report", "diagnose"]


@dataclass(frozen=True)
class DiagnoseSettings:
    """train_fraction: share of the record (whole days) used for fitting, the rest is the test;
    preset: estimator preset of the baseline and of every refit that adds inputs;
    structural_preset: of refits that add a state (a new capacitor brings new basins, which the
    longer GA of "default" explores); confirm: candidates refitted per round after the first
    (which refits them all); min_improvement: relative test-RMSE cut an extension must bring,
    and min_improvement_k in kelvin (0.1 K, a room sensor's accuracy: smaller gains are no
    evidence of physics); bic_margin: how much the effective-n BIC must drop; max_rounds:
    forward-selection rounds; baseline_starts: independent searches for the baseline fit (best
    kept); workers: processes for the refits of a round (default: every core); effects: the
    candidate ids to consider (default: the whole vocabulary)."""

    train_fraction: float = 0.5
    preset: str = "study"
    structural_preset: str = "default"
    confirm: int = 3
    min_improvement: float = 0.10
    min_improvement_k: float = 0.1
    bic_margin: float = 10.0
    max_rounds: int = 3
    baseline_starts: int = 4
    workers: int = field(default_factory=lambda: os.cpu_count() or 1)
    random_state: int = 0
    effects: tuple[str, ...] = tuple(CANDIDATES)


def split_time(frame: pd.DataFrame, fraction: float, timezone: str) -> pd.Timestamp:
    """Local midnight closest to ``fraction`` of the record, so train and test are whole days."""
    if not 0.1 <= fraction <= 0.9:
        raise ValueError(f"train_fraction must be within [0.1, 0.9], got {fraction}")
    t = frame.index[int(len(frame) * fraction)].tz_convert(timezone)
    midnight = t.normalize()
    if t - midnight > pd.Timedelta(hours=12):
        midnight += pd.Timedelta(days=1)
    return midnight.tz_convert("UTC")


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
    say = progress or (lambda message: None)
    started = time.perf_counter()
    boundary = split_time(frame, settings.train_fraction, building.location.timezone)
    network = get_model(model, building, frame.columns)
    options = SignalOptions()
    say(f"fitting {model} on the training period (until {boundary.date()})")
    split = split_data(frame, building, network, options, boundary)
    # RC models often have two basins that swap the roles of two capacitors; one genetic search
    # falls into the worse one often enough that every extension would get the credit a better
    # optimum brings. The best of several independent searches is the baseline.
    baseline = min(
        fit_many(
            [
                FitJob(network, options, split, settings.preset, settings.random_state + k)
                for k in range(settings.baseline_starts)
            ],
            settings.workers,
        ),
        key=lambda f: f.sse_train,
    )
    train_frame, test_frame = baseline.split.train.frame, baseline.split.test.frame
    locate = {
        "train": summarize(baseline.residual_train, train_frame, building),
        "test": summarize(baseline.residual_test, test_frame, building),
        # One-step-ahead errors show fast, local misses the open-loop drift can hide.
        "innovations": {
            "train": summarize(baseline.innovations_train, train_frame, building),
            "test": summarize(baseline.innovations_test, test_frame, building),
        },
    }
    current, skipped = baseline, {}
    verdicts: dict[str, Finding] = {}
    accepted: list[Finding] = []
    for round_no in range(1, settings.max_rounds + 1):
        taken = {f.effect for f in accepted}
        extensions = _extensions(current, building, settings, skipped, taken)
        if not extensions:
            break
        say(f"round {round_no}: screening {len(extensions)} candidate(s) on {current.network.name}")
        best = _round(
            frame, building, boundary, current, extensions, round_no, settings, verdicts, say
        )
        if best is None:
            break
        accepted.append(best)
        current = best.fit
    pattern = locate["train"]["summary"]
    findings = accepted + sorted(
        (v for v in verdicts.values() if not v.accepted),
        key=lambda v: (v.rmse_test_after is not None, v.improvement_k, v.screen_explained),
        reverse=True,
    )
    for f in findings:
        f.explanation = explain(f, pattern)
    whiteness = {
        "baseline": ljung_box(baseline.innovations_test, baseline.split.test.times),
        "final": ljung_box(current.innovations_test, current.split.test.times),
    }
    return Report(
        building,
        model,
        boundary,
        baseline,
        current,
        locate,
        findings,
        skipped,
        whiteness,
        time.perf_counter() - started,
    )


def _extensions(
    current: Fit,
    building: Building,
    settings: DiagnoseSettings,
    skipped: dict[str, str],
    taken: set[str],
) -> list[Extension]:
    ctx = Context(
        current.network,
        building,
        current.split.train,
        current.options,
        current.params,
        current.residual_train,
    )
    out = []
    for effect in (e for e in settings.effects if e not in taken):
        built = CANDIDATES[effect](ctx)
        if isinstance(built, Skipped):
            skipped.setdefault(effect, built.reason)
        else:
            skipped.pop(effect, None)
            out.append(built)
    return out


def _refine(
    frame: pd.DataFrame,
    building: Building,
    boundary: pd.Timestamp,
    current: Fit,
    extensions: list[Extension],
    fits: list[Fit],
    settings: DiagnoseSettings,
    say: Callable[[str], None],
) -> tuple[list[Extension], list[Fit]]:
    """Re-learn the shape of learnt inputs (schedules) from each refit and refit once more.

    The first schedule is learnt from the current model's residual, whose parameters had bent to
    absorb part of the missing effect; after a refit the model is closer to the truth and the
    residual shows the effect's shape more fully. The refined version is kept if it fits better.
    """
    extensions, fits = list(extensions), list(fits)
    jobs, where = [], []
    for i, (ext, fit) in enumerate(zip(extensions, fits, strict=True)):
        if not ext.learnt:
            continue
        params = {name: fit.params[name] for name in current.params}
        train = current.split.train
        ctx = Context(
            current.network,
            building,
            train,
            current.options,
            params,
            residual_at(current.network, params, train),
        )
        refined = CANDIDATES[ext.effect](ctx)
        if isinstance(refined, Skipped) or refined.signals == ext.signals:
            continue
        split = split_data(frame, building, refined.network, refined.signals, boundary)
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
        say(f"  refining the learnt shape of {', '.join(r.effect for _, r in where)}")
    for (i, refined), fit in zip(where, fit_many(jobs, settings.workers), strict=True):
        if fit.sse_train < fits[i].sse_train:
            extensions[i], fits[i] = refined, fit
    return extensions, fits


def _round(
    frame: pd.DataFrame,
    building: Building,
    boundary: pd.Timestamp,
    current: Fit,
    extensions: list[Extension],
    round_no: int,
    settings: DiagnoseSettings,
    verdicts: dict[str, Finding],
    say: Callable[[str], None],
) -> Finding | None:
    """Screen every extension, refit the most promising, and return the accepted one (or None)."""
    splits = {
        e.effect: split_data(frame, building, e.network, e.signals, boundary) for e in extensions
    }
    screens = {
        e.effect: screen(e, current, splits[e.effect], settings.random_state) for e in extensions
    }
    # Screening is a linearisation; the first round refits every candidate for real, later
    # rounds the ones whose earlier refit helped most.
    def promise(e: Extension) -> tuple[float, float]:
        earlier = verdicts.get(e.effect)
        return (earlier.improvement_k if earlier else 0.0, screens[e.effect].explained)

    ranked = sorted(extensions, key=promise, reverse=True)
    n_refit = len(ranked) if round_no == 1 else settings.confirm
    refit = ranked[:n_refit]
    say(f"  refitting {', '.join(e.effect for e in refit)}")
    fits = fit_many(
        [
            FitJob(
                e.network,
                e.signals,
                splits[e.effect],
                settings.structural_preset if e.structural else settings.preset,
                settings.random_state,
                [{**current.params, **e.neutral}, dict(current.params)],
            )
            for e in refit
        ],
        settings.workers,
    )
    refit, fits = _refine(frame, building, boundary, current, refit, fits, settings, say)
    confirmed = [
        judge(e, current, fit, screens[e.effect], round_no, settings, building)
        for e, fit in zip(refit, fits, strict=True)
    ]
    for ext in ranked[n_refit:]:
        verdicts[ext.effect] = screened_only(ext, current, screens[ext.effect], round_no)
    for finding in confirmed:
        verdicts[finding.effect] = finding
    winners = [f for f in confirmed if f.accepted]
    best = max(winners, key=lambda f: f.improvement_k, default=None)
    for f in winners:
        if f is not best:
            f.accepted = False
            f.reason = f"not taken in round {round_no}: {best.effect} improved the test more"
    if best is not None:
        del verdicts[best.effect]
    return best
