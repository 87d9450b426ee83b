"""Findings, their plain-words explanations, and the diagnose report (CONTRACT.md §3)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import SOLAR_OPAQUE, SOLAR_WINDOW, solar_orientation_signal
from rcengine.diagnose.candidates import Extension
from rcengine.diagnose.clock import ClockCheck
from rcengine.diagnose.fitting import Fit
from rcengine.diagnose.folds import Fold, FoldEvidence, judge_folds, rmse_change
from rcengine.diagnose.health import FitQuality, Health
from rcengine.diagnose.locate import summarize
from rcengine.diagnose.screen import Screen
from rcengine.diagnose.settings import DiagnoseSettings
from rcengine.io.jsonable import jsonable

# What each effect means, in the words of the report.
MISSING = {
    "window_solar_gains": "solar heat entering through the glazing, which depends on each façade's "
    "orientation and the sun's position",
    "opaque_solar_gains": "solar heat absorbed by the opaque walls and roof, each facade by the "
    "sun on its own orientation",
    "wind_infiltration": "air leakage that grows with wind speed",
    "ventilation_schedule": "outdoor-air ventilation during scheduled hours",
    "ground_coupling": "heat exchange through the floor with the slowly varying ground",
    "sky_radiation": "long-wave radiation from the envelope to the cold night sky",
    "unmetered_gains": "internal heat gains that are not in the data, on a weekly schedule",
    "thermal_mass": "a heat-storage element the model lacks (its order is too low)",
    "emitter_dynamics": "the inertia of the heat emitter between the HVAC meter and the air",
}


# The single split's checks a finding can fall short of alone (``Finding.short_of``).
ShortOf = Literal["bic", "test"]
SHORT_OF_BIC: ShortOf = "bic"
SHORT_OF_TEST: ShortOf = "test"


@dataclass
class Finding:
    """One candidate's verdict. ``rmse_test_after`` is None when it was only screened.

    magnitudes: the fitted effect in physical units (plausibility check); folds: its evidence
    across the rolling folds (``FoldEvidence.to_dict``), ``evidence`` the residuals behind it;
    runner_up / lost_to: {"effect", "reason"} of the head-to-head between candidates that both
    passed; baseline_repair: taken to make an inadequate base model healthy, not judged as a
    candidate; backward: what leaving it out of the final model costs across the folds (the
    backward check of an accepted finding); absent: the values of its new parameters at which it
    is left out (``Extension.absent``); extension: the candidate this verdict is on;
    plausible: False where a fitted magnitude is implausible for the building; short_of: the one
    check of the single split a plausible fit fell short of, where it was the only one —
    ``SHORT_OF_BIC`` (the training half's BIC) or ``SHORT_OF_TEST`` (the test improvement) — which
    may send it to be judged over the season (``selection._over_the_season``), else None.
    """

    effect: str
    accepted: bool
    round: int
    screen_explained: float
    screen_method: str
    rmse_test_before: float
    rmse_train_before: float
    rmse_test_after: float | None = None
    rmse_train_after: float | None = None
    delta_bic: float | None = None
    delta_aic: float | None = None
    parameters: dict[str, float] = field(default_factory=dict)
    at_bounds: list[str] = field(default_factory=list)
    reason: str = ""
    explanation: str = ""
    detail: dict = field(default_factory=dict)
    magnitudes: dict[str, dict] = field(default_factory=dict)
    folds: dict | None = None
    runner_up: dict[str, str] | None = None
    lost_to: dict[str, str] | None = None
    baseline_repair: bool = False
    backward: dict | None = None
    absent: dict[str, float] = field(default_factory=dict)
    screen: Screen | None = None
    fit: Fit | None = None
    evidence: FoldEvidence | None = None
    short_of: ShortOf | None = None
    extension: Extension | None = None
    plausible: bool = True

    @property
    def improvement_k(self) -> float:
        if self.rmse_test_after is None:
            return 0.0
        return self.rmse_test_before - self.rmse_test_after

    def to_dict(self) -> dict:
        return {
            "effect": self.effect,
            "accepted": self.accepted,
            "explanation": self.explanation,
            "rmse_test_before": self.rmse_test_before,
            "rmse_test_after": self.rmse_test_after,
            "rmse_train_before": self.rmse_train_before,
            "rmse_train_after": self.rmse_train_after,
            "round": self.round,
            "screening": {"explained_share": self.screen_explained, "method": self.screen_method},
            "delta_bic": self.delta_bic,
            "delta_aic": self.delta_aic,
            "parameters": self.parameters,
            "parameters_at_bounds": self.at_bounds,
            "reason": self.reason,
            "detail": self.detail,
            "magnitudes": self.magnitudes,
            "folds": self.folds,
            "runner_up": self.runner_up,
            "lost_to": self.lost_to,
            "baseline_repair": self.baseline_repair,
            "backward": self.backward,
            # The refitted model with this finding, accepted or not, so that it can be adopted
            # by name (``ModelSpec.from_report(..., finding=...)``); None where only screened.
            "model": None if self.fit is None else self.fit.model_document(),
        }


# How a finding judged over the season was refitted, in its report's ``folds`` (``training``):
# each fold on the whole record but its test window and guard days (``folds.held_out_blocks``).
HELD_OUT_BLOCKS = "held-out blocks"
# A finding's ``detail`` key for the input too slow for the rolling folds that sent it to the
# held-out blocks (``selection._slow_input``): {"signal", "within_fold_share"}.
SLOW_INPUT = "slow_input"
# A gain the rolling folds rejected, judged on the held-out blocks for what it forecasts with
# the heater off (``selection._gains_over_the_season``): ``heater_off.heater_off_change``.
HEATER_OFF = "heater_off"


def improvement_check(
    before: float, after: float, settings: DiagnoseSettings, evident: bool = False
) -> tuple[bool, str]:
    """Whether the test RMSE [K] fell from ``before`` to ``after`` by the relative cut and the
    kelvin margin of ``settings``, or, for a fit whose magnitude is ``evident``, by the smaller
    relative cut alone; with the change in words."""
    gain, text = before - after, rmse_change(before, after)
    if evident:
        cut = settings.min_improvement_evident
        return gain >= cut * before, f"{text}, its magnitude evident (a {cut:.0%} cut asked)"
    return (
        gain >= settings.min_improvement * before and gain >= settings.min_improvement_k,
        text,
    )


def judge(
    ext: Extension,
    current: Fit,
    fit: Fit,
    screened: Screen,
    round_no: int,
    settings: DiagnoseSettings,
    building: Building,
    evident: bool = False,
) -> Finding:
    """Accept an extension only for a meaningful test improvement that the BIC confirms: a
    relative cut of the test RMSE and one in kelvin, or, for a fit whose magnitude is ``evident``
    (``plausibility.Assessment``), the smaller relative cut such a fit asks alone."""
    before, after = current.rmse_test, fit.rmse_test
    change = fit.criteria_change(current)
    delta_bic = change["bic"]
    new = {p: fit.params[p] for p in ext.new_parameters}
    bounds = [p for p in fit.at_bounds if p in ext.new_parameters]
    idle = is_idle(ext, fit.params)
    checks = [
        improvement_check(before, after, settings, evident),
        (delta_bic <= -settings.bic_margin, f"ΔBIC {delta_bic:+.1f}"),
        (not idle, "fitted gain is zero" if idle else "fitted gain is non-zero"),
    ]
    accepted = all(ok for ok, _ in checks)
    failed = [text for ok, text in checks if not ok]
    alone: dict[str, ShortOf] = {checks[0][1]: SHORT_OF_TEST, checks[1][1]: SHORT_OF_BIC}
    short_of = alone.get(failed[0]) if not accepted and len(failed) == 1 else None
    reason = (
        "accepted: " + "; ".join(text for _, text in checks)
        if accepted
        else "rejected: " + "; ".join(failed)
    )
    detail = dict(ext.detail)
    detail["correction"] = summarize(
        fit.simulated_train - current.simulated_train,
        fit.split.train.frame,
        building,
        ("adding it", "raises the prediction", "lowers the prediction"),
    )["summary"]
    detail["peak_input"] = {
        signal: float(np.nanmax(np.abs(fit.split.train.frame[signal].to_numpy(dtype=float))))
        for signal, _ in ext.inputs
    }
    return _finding(
        ext,
        current,
        screened,
        round_no,
        accepted=accepted,
        rmse_test_after=after,
        rmse_train_after=fit.rmse_train,
        delta_bic=delta_bic,
        delta_aic=change["aic"],
        parameters=new,
        at_bounds=bounds,
        reason=reason,
        detail=detail,
        fit=fit,
        short_of=short_of,
    )


def is_idle(ext: Extension, params: dict[str, float]) -> bool:
    """Whether every new parameter whose neutral value is its lower bound (a gain, a capacity)
    sits there: whatever the refit improved then came from re-fitting the old parameters."""
    lower = {p: ext.network.parameters[p].lower for p in ext.neutral}
    gains = [p for p, v in ext.neutral.items() if v == lower[p]]
    return bool(gains) and all(np.isclose(params[p], lower[p], rtol=1e-3, atol=1e-9) for p in gains)


def confirm_on_folds(
    finding: Finding,
    evidence: FoldEvidence,
    folds: list[Fold],
    settings: DiagnoseSettings,
    timezone: str,
    training: str | None = None,
) -> None:
    """Keep a finding that passed the single split accepted only if it also helps in most folds
    and on their pooled test; the fold evidence goes into the finding either way (``training``:
    how the folds were fitted, where not the rolling folds')."""
    _record(finding, evidence, folds, timezone, training)
    ok, text = judge_folds(evidence, settings.fold_rule)
    single = finding.reason.removeprefix("accepted: ")
    across = training or "folds"
    finding.accepted = ok
    finding.reason = (
        f"accepted: {single}; across {across}: {text}"
        if ok
        else f"rejected across {across}: {text} (single split: {single})"
    )


def confirm_over_the_season(
    finding: Finding,
    evidence: FoldEvidence,
    blocks: list[Fold],
    settings: DiagnoseSettings,
    timezone: str,
    season_bic: float,
) -> None:
    """A finding judged on held-out blocks: one short of the training half's BIC alone
    (``short_of`` ``SHORT_OF_BIC``), or one that passed the single split, or fell short of its
    test alone (``SHORT_OF_TEST``), but whose input is too slow for the rolling folds
    (``detail[SLOW_INPUT]``: the input and its ``folds.within_fold_share``). It
    passes the BIC where ``season_bic``, its ΔBIC on the blocks' fits over the season around each
    test window, is within the margin, and is then judged as ``confirm_on_folds``."""
    finding.detail["season_delta_bic"] = season_bic
    season = f"{season_bic:+.1f} over the season (median of the folds' fits)"
    slow = finding.detail.get(SLOW_INPUT)
    off = finding.detail.get(HEATER_OFF)
    if off is not None:
        season += (
            f"; judged over the season: over the {off['hours']:.0f} h of its schedule with the "
            f"heater off, it forecasts {off['rmse_before']:.3f} → {off['rmse_after']:.3f} K"
        )
    if slow is not None:
        season += (
            f"; judged over the season: its input {slow['signal']} varies within a fold's "
            f"training weeks by {slow['within_fold_share']:.0%} of its variation over the "
            "record, too slowly for a refit on them to tell it from the base model"
        )
    if season_bic > -settings.bic_margin:
        _record(finding, evidence, blocks, timezone, HELD_OUT_BLOCKS)
        if finding.accepted:
            single = finding.reason.removeprefix("accepted: ")
            finding.reason = f"rejected: ΔBIC {season} (single split: {single})"
        elif finding.short_of == SHORT_OF_TEST:
            finding.reason += f"; ΔBIC {finding.delta_bic:+.1f} on the training half, {season}"
        else:
            finding.reason += f", {season}"
        finding.accepted = False
        return
    single = rmse_change(finding.rmse_test_before, finding.rmse_test_after)
    if finding.short_of == SHORT_OF_TEST:
        single += " on a test half that is the season's other half"
    finding.reason = (
        f"accepted: {single}; "
        f"ΔBIC {finding.delta_bic:+.1f} on the training half, {season}; fitted gain is non-zero"
    )
    confirm_on_folds(finding, evidence, blocks, settings, timezone, HELD_OUT_BLOCKS)


def _record(
    finding: Finding,
    evidence: FoldEvidence,
    folds: list[Fold],
    timezone: str,
    training: str | None,
) -> None:
    finding.evidence = evidence
    finding.folds = evidence.to_dict(folds, timezone)
    if training is not None:
        finding.folds["training"] = training


def reject_implausible(finding: Finding, magnitudes: dict[str, dict], problems: list[str]) -> None:
    """Record the fitted magnitudes in physical units; an implausible one rejects the finding."""
    finding.magnitudes = magnitudes
    if not problems:
        return
    text = "implausible: " + "; ".join(problems)
    finding.short_of = None
    finding.plausible = False
    finding.reason = f"rejected as {text}" if finding.accepted else f"{finding.reason}; {text}"
    finding.accepted = False


def screened_only(ext: Extension, current: Fit, screened: Screen, round_no: int) -> Finding:
    return _finding(
        ext,
        current,
        screened,
        round_no,
        accepted=False,
        parameters=screened.coefficients,
        reason="not refitted: weaker screening evidence than the refitted candidates",
        detail=dict(ext.detail),
    )


def _finding(
    ext: Extension, current: Fit, screened: Screen, round_no: int, **verdict: Any
) -> Finding:
    """A finding on ``ext`` in round ``round_no``: its screening and the current model's errors
    [K], with the ``verdict`` fields (accepted, refit results, reason, detail)."""
    return Finding(
        effect=ext.effect,
        round=round_no,
        screen_explained=screened.explained,
        screen_method=screened.method,
        rmse_test_before=current.rmse_test,
        rmse_train_before=current.rmse_train,
        absent=dict(ext.neutral if ext.absent is None else ext.absent),
        screen=screened,
        extension=ext,
        **verdict,
    )


def _values(finding: Finding) -> str:
    parts = []
    for name, value in finding.parameters.items():
        parts.append(f"{name} = {value:.3g}")
    return ", ".join(parts)


def explain(finding: Finding, pattern: str) -> str:
    """Plain words: what physics was left out, where and when, the evidence, what adding it did."""
    what = MISSING.get(finding.effect, finding.effect)
    facts = _facts(finding)
    if finding.rmse_test_after is None:
        evidence = (
            f"its own input, passed through the model's dynamics, explains "
            f"{max(finding.screen_explained, 0.0):.0%} of the training error"
            if finding.screen_method == "projection"
            else f"a short refit with it removes {max(finding.screen_explained, 0.0):.0%} of the "
            "training error"
        )
        return f"Candidate: {what}. Screening only: {evidence}{facts}."
    removed = 1.0 - (finding.rmse_train_after / finding.rmse_train_before) ** 2
    correction = finding.detail.get("correction", "")
    if finding.accepted:
        lead = f"The model left out {what}"
        if finding.baseline_repair and not (finding.backward or {}).get("helps_on_folds", True):
            lead = (
                "The base model cannot represent this building without it, but once the "
                f"findings above are in the data do not show it missing. It adds {what}"
            )
        elif finding.baseline_repair:
            lead = f"The base model cannot represent this building without it. {lead}"
        return (
            f"{lead}. Where and when: {pattern}; {correction}{facts}. "
            f"Adding it ({_values(finding)}) removes {max(removed, 0.0):.0%} of the training "
            f"error and cuts the test RMSE from {finding.rmse_test_before:.2f} to "
            f"{finding.rmse_test_after:.2f} K{_across(finding)}."
        )
    return (
        f"Not confirmed — {what}{facts}: adding it ({_values(finding)}) changes the test RMSE "
        f"from {finding.rmse_test_before:.2f} to {finding.rmse_test_after:.2f} K "
        f"({finding.reason})."
    )


def _across(finding: Finding) -> str:
    if finding.folds is None:
        return ""
    n, ties = len(finding.folds["folds"]), finding.folds["tied"]
    tied = f", {ties} tied" if ties else ""
    folds = finding.folds.get("training", "rolling folds")
    return (
        f"; across {n} {folds} it helps in {finding.folds['helped']}{tied} "
        f"(pooled test RMSE {finding.folds['pooled_rmse_test_before']:.2f} → "
        f"{finding.folds['pooled_rmse_test_after']:.2f} K)"
    )


def verdict(findings: list[Finding], health: Health | None) -> str:
    """The verdict: "nothing missing", "missing: <effect>[, <effect>]", or, when the base model
    cannot represent the building, "base model inadequate: <reasons>" and what was found against
    the healthy model reached by a repair step, or against the inadequate one when none was."""
    missing = [f.effect for f in findings if f.accepted and not f.baseline_repair]
    found = "missing: " + ", ".join(missing) if missing else "nothing missing"
    repairs = [f.effect for f in findings if f.accepted and f.baseline_repair]
    if health is None or health.healthy:
        if not repairs:
            return found
        return (
            f"{found} (against the base model with {', '.join(repairs)}: without it, parameters "
            "rested on bounds the data do not press on)"
        )
    dropped = [f for f in findings if not f.accepted and f.baseline_repair]
    names = ", ".join(f.effect for f in dropped)
    if repairs:
        against = f"healthy with {', '.join(repairs)}, then {found}"
    elif dropped and all((f.backward or {}).get("healthy_without", True) for f in dropped):
        against = (
            f"healthy once what it left out is in ({names} not needed): {found}"
            if missing
            else f"healthy without {names} once refitted (not needed): {found}"
        )
    elif dropped:
        against = (
            f"{names} would heal its bounds but the data do not show it missing (dropped): {found}"
        )
    else:
        against = f"judged against it anyway: {found}"
    return f"base model inadequate: {'; '.join(health.reasons)} — {against}"


def health_dict(health: Health, quality: FitQuality) -> dict:
    """The base model's health for the report: verdict, reasons, notes, parameters on bounds
    and what a fit past each gains (``bound_pressure``, a share of the training RMSE), and its
    test RMSE against the naive forecasts' [K]."""
    return {
        "verdict": health.verdict,
        "reasons": list(health.reasons),
        "notes": list(health.notes),
        "parameters_on_bounds": list(health.on_bounds),
        "bound_pressure": dict(health.pressure),
        "rmse_test": quality.rmse,
        "naive_rmse_test": quality.naive,
    }


def _facts(finding: Finding) -> str:
    d = finding.detail
    if "orientations" in d:
        peaks = d.get("peak_input", {})
        faces = ", ".join(_face(finding, k, v, peaks) for k, v in d["orientations"].items())
        return f" ({faces})"
    if "schedule" in d:
        return f" (schedule learnt from the residuals: {d['schedule']})"
    if "follows" in d:
        return f" (in step with the metered use, {d['follows']})"
    if "glazing_g_on_storage" in d:
        return f" (the declared glazing's sun falls on it too: g = {d['glazing_g_on_storage']:.2f})"
    return ""


def _face(finding: Finding, key: str, orientation: dict, peaks: dict[str, float]) -> str:
    """One orientation's surfaces in words, with the highest irradiance they received."""
    area, facade = orientation["area_m2"], orientation["facade"]
    words = (
        f"{facade} {area:g} m²"
        if area
        else f"{facade} facade of {orientation['facade_m2']:g} m² with no window declared"
    )
    total = SOLAR_WINDOW if finding.effect == "window_solar_gains" else SOLAR_OPAQUE
    signal = orientation.get("signal", solar_orientation_signal(total, key))
    if signal not in peaks:
        return words
    per_m2 = peaks[signal] / orientation.get("signal_area_m2", area)
    return f"{words}, receiving up to {per_m2:.0f} W/m²"


@dataclass
class Report:
    """The diagnosis: ``health`` and ``quality`` of the base model as given, ``repair`` the
    outcome of the structural step tried on an inadequate one; ``folds`` the rolling folds an
    extension had to help across (none: judged on the single split), ``folds_left_out`` those
    whose training window barely ran the HVAC its test window ran; ``day_ahead`` the base and
    final models' day-ahead forecasts over the test half (``diagnose.day_ahead``); ``clock``
    how the building's readings were aligned with the weather (``diagnose.clock``; None:
    unchecked)."""

    building: Building
    model: str
    boundary: pd.Timestamp
    baseline: Fit
    final: Fit
    locate: dict
    findings: list[Finding]
    skipped: dict[str, str]
    whiteness: dict
    wall_time_s: float
    health: Health | None = None
    quality: FitQuality | None = None
    repair: dict | None = None
    folds: list[Fold] = field(default_factory=list)
    folds_left_out: list[Fold] = field(default_factory=list)
    day_ahead: dict | None = None
    clock: ClockCheck | None = None

    @property
    def accepted(self) -> list[Finding]:
        return [f for f in self.findings if f.accepted]

    def to_dict(self) -> dict:
        split = self.baseline.split
        baseline = {
            "model": self.model,
            "rmse_train": self.baseline.rmse_train,
            "rmse_test": self.baseline.rmse_test,
            "parameters": self.baseline.params,
        }
        if self.health is not None and self.quality is not None:
            baseline["health"] = health_dict(self.health, self.quality) | {"repair": self.repair}
        tz = self.building.location.timezone
        return {
            "baseline": baseline,
            "mismatch": {
                "summary": self.locate["test"]["summary"],
                "train": self.locate["train"],
                "test": self.locate["test"],
                "innovations": self.locate["innovations"],
            },
            "findings": [f.to_dict() for f in self.findings],
            "final": {
                "model": self.final.network.name,
                "rmse_train": self.final.rmse_train,
                "rmse_test": self.final.rmse_test,
                "parameters": self.final.params,
                # What rebuilds the final model exactly (rcengine.models.spec.ModelSpec).
                **self.final.model_document(),
            },
            "verdict": verdict(self.findings, self.health),
            "evidence": {
                "method": "folds" if self.folds else "split",
                "folds": [
                    {"train_start": f.train_start.tz_convert(tz).isoformat(), "test": f.label(tz)}
                    for f in self.folds
                ],
                "left_out": [
                    {
                        "test": f.label(tz),
                        "reason": "its training window barely ran the HVAC its test window ran",
                    }
                    for f in self.folds_left_out
                ],
            },
            "skipped": self.skipped,
            "whiteness": self.whiteness,
            "day_ahead": self.day_ahead,
            "clock": None if self.clock is None else self.clock.to_dict(),
            "periods": {
                "step_s": split.train.step_s,
                "train": [split.train.times[0].isoformat(), self.boundary.isoformat()],
                "test": [
                    self.boundary.isoformat(),
                    (split.test.times[-1] + pd.Timedelta(seconds=split.test.step_s)).isoformat(),
                ],
            },
            "wall_time_s": self.wall_time_s,
        }

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(jsonable(self.to_dict()), indent=indent, allow_nan=False)
