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

import time
from collections.abc import Callable
from dataclasses import dataclass

import pandas as pd

from ..building import Building
from ..models import get_model
from ..signals import SignalOptions
from .candidates import CANDIDATES, Context, Extension, Skipped
from .fitting import Fit, fit_model, split_data
from .locate import summarize
from .report import Finding, Report, explain, judge, screened_only
from .screen import screen
from .whiteness import ljung_box

__all__ = ["DiagnoseSettings", "Report", "diagnose"]


@dataclass(frozen=True)
class DiagnoseSettings:
    """train_fraction: share of the record (whole days) used for fitting, the rest is the test;
    preset: estimator preset for every refit; confirm: candidates refitted per round;
    min_improvement: relative test-RMSE cut an extension must bring, and min_improvement_k in
    kelvin; bic_margin: how much the effective-n BIC must drop; max_rounds: forward-selection
    rounds; effects: the candidate ids to consider (default: the whole vocabulary)."""

    train_fraction: float = 0.5
    preset: str = "default"
    confirm: int = 3
    min_improvement: float = 0.10
    min_improvement_k: float = 0.03
    bic_margin: float = 10.0
    max_rounds: int = 3
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
    settings = settings or DiagnoseSettings()
    say = progress or (lambda message: None)
    started = time.perf_counter()
    boundary = split_time(frame, settings.train_fraction, building.location.timezone)
    network = get_model(model, building, frame.columns)
    options = SignalOptions()
    say(f"fitting {model} on the training period (until {boundary.date()})")
    baseline = fit_model(
        network,
        options,
        split_data(frame, building, network, options, boundary),
        settings.preset,
        settings.random_state,
    )
    locate = {
        "train": summarize(baseline.residual_train, baseline.split.train.frame, building),
        "test": summarize(baseline.residual_test, baseline.split.test.frame, building),
    }
    current, skipped = baseline, {}
    verdicts: dict[str, Finding] = {}
    accepted: list[Finding] = []
    for round_no in range(1, settings.max_rounds + 1):
        extensions = _extensions(current, building, settings, skipped)
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
    current: Fit, building: Building, settings: DiagnoseSettings, skipped: dict[str, str]
) -> list[Extension]:
    ctx = Context(
        current.network,
        building,
        current.split.train.frame,
        current.options,
        current.innovations_train,
        current.split.train.step_s,
    )
    out = []
    for effect in settings.effects:
        built = CANDIDATES[effect](ctx)
        if isinstance(built, Skipped):
            skipped.setdefault(effect, built.reason)
        else:
            skipped.pop(effect, None)
            out.append(built)
    return out


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
    ranked = sorted(extensions, key=lambda e: screens[e.effect].explained, reverse=True)
    confirmed = []
    for ext in ranked[: settings.confirm]:
        say(f"  refitting {ext.network.name} (screening: {screens[ext.effect].explained:.0%})")
        fit = fit_model(
            ext.network,
            ext.signals,
            splits[ext.effect],
            settings.preset,
            settings.random_state,
            warm_start=[dict(current.params)],
        )
        confirmed.append(judge(ext, current, fit, screens[ext.effect], round_no, settings))
    for ext in ranked[settings.confirm :]:
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
