"""Findings, their plain-words explanations, and the diagnose report (CONTRACT.md §3)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.diagnose.candidates import Extension
from rcengine.diagnose.fitting import Fit
from rcengine.diagnose.locate import summarize
from rcengine.diagnose.screen import Screen

# What each effect means, in the words of the report.
MISSING = {
    "window_solar_gains": "solar heat entering through the glazing, which depends on each façade's "
    "orientation and the sun's position",
    "opaque_solar_gains": "solar heat absorbed by the opaque walls and roof, by orientation",
    "wind_infiltration": "air leakage that grows with wind speed",
    "ventilation_schedule": "outdoor-air ventilation during scheduled hours",
    "ground_coupling": "heat exchange through the floor with the slowly varying ground",
    "sky_radiation": "long-wave radiation from the envelope to the cold night sky",
    "unmetered_gains": "internal heat gains that are not in the data, on a weekly schedule",
    "thermal_mass": "a heat-storage element the model lacks (its order is too low)",
    "emitter_dynamics": "the inertia of the heat emitter between the HVAC meter and the air",
}


@dataclass
class Finding:
    """One candidate's verdict. ``rmse_test_after`` is None when it was only screened."""

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
    screen: Screen | None = None
    fit: Fit | None = None

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
        }


def judge(
    ext: Extension,
    current: Fit,
    fit: Fit,
    screened: Screen,
    round_no: int,
    settings,
    building: Building,
) -> Finding:
    """Accept an extension only for a meaningful test improvement that the BIC confirms."""
    before, after = current.rmse_test, fit.rmse_test
    n_eff = current.n_eff
    ic_before, ic_after = current.information_criteria(n_eff), fit.information_criteria(n_eff)
    delta_bic = ic_after["bic"] - ic_before["bic"]
    new = {p: fit.params[p] for p in ext.new_parameters}
    bounds = [p for p in fit.at_bounds if p in ext.new_parameters]
    # Idle: every new parameter whose neutral value is its lower bound (a gain, a capacity) sits
    # there, so whatever the refit improved came from re-fitting the old parameters.
    lower = {p: ext.network.parameters[p].lower for p in ext.neutral}
    gains = [p for p, v in ext.neutral.items() if v == lower[p]]
    idle = bool(gains) and all(
        np.isclose(fit.params[p], lower[p], rtol=1e-3, atol=1e-9) for p in gains
    )
    gain = before - after
    checks = [
        (
            gain >= settings.min_improvement * before and gain >= settings.min_improvement_k,
            f"test RMSE {before:.3f} → {after:.3f} K ({-gain / before:+.0%})",
        ),
        (delta_bic <= -settings.bic_margin, f"ΔBIC {delta_bic:+.1f}"),
        (not idle, "fitted gain is zero" if idle else "fitted gain is non-zero"),
    ]
    accepted = all(ok for ok, _ in checks)
    failed = [text for ok, text in checks if not ok]
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
    return Finding(
        effect=ext.effect,
        accepted=accepted,
        round=round_no,
        screen_explained=screened.explained,
        screen_method=screened.method,
        rmse_test_before=before,
        rmse_train_before=current.rmse_train,
        rmse_test_after=after,
        rmse_train_after=fit.rmse_train,
        delta_bic=delta_bic,
        delta_aic=ic_after["aic"] - ic_before["aic"],
        parameters=new,
        at_bounds=bounds,
        reason=reason,
        detail=detail,
        screen=screened,
        fit=fit,
    )


def screened_only(ext: Extension, current: Fit, screened: Screen, round_no: int) -> Finding:
    return Finding(
        effect=ext.effect,
        accepted=False,
        round=round_no,
        screen_explained=screened.explained,
        screen_method=screened.method,
        rmse_test_before=current.rmse_test,
        rmse_train_before=current.rmse_train,
        parameters=screened.coefficients,
        reason="not refitted: weaker screening evidence than the refitted candidates",
        detail=dict(ext.detail),
        screen=screened,
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
        return (
            f"The model left out {what}. Where and when: {pattern}; {correction}{facts}. "
            f"Adding it ({_values(finding)}) removes {max(removed, 0.0):.0%} of the training "
            f"error and cuts the test RMSE from {finding.rmse_test_before:.2f} to "
            f"{finding.rmse_test_after:.2f} °C."
        )
    return (
        f"Not confirmed — {what}{facts}: adding it ({_values(finding)}) changes the test RMSE "
        f"from {finding.rmse_test_before:.2f} to {finding.rmse_test_after:.2f} °C "
        f"({finding.reason})."
    )


def _facts(finding: Finding) -> str:
    d = finding.detail
    if "orientations" in d:
        peaks = d.get("peak_input", {})
        faces = ", ".join(
            f"{v['facade']} {v['area_m2']:g} m²"
            + (
                f" receiving up to {peaks[s] / v['area_m2']:.0f} W/m²"
                if (s := _signal_of(finding, k)) in peaks
                else ""
            )
            for k, v in d["orientations"].items()
        )
        return f" ({faces})"
    if "schedule" in d:
        return f" (schedule learnt from the residuals: {d['schedule']})"
    return ""


def _signal_of(finding: Finding, orientation: str) -> str:
    kind = "window" if finding.effect == "window_solar_gains" else "opaque"
    return f"solar_{kind}_{orientation}"


@dataclass
class Report:
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

    @property
    def accepted(self) -> list[Finding]:
        return [f for f in self.findings if f.accepted]

    def to_dict(self) -> dict:
        split = self.baseline.split
        verdict = (
            "missing physics found: " + ", ".join(f.effect for f in self.accepted)
            if self.accepted
            else "nothing missing: no candidate physics improved the later period enough"
        )
        return {
            "baseline": {
                "model": self.model,
                "rmse_train": self.baseline.rmse_train,
                "rmse_test": self.baseline.rmse_test,
                "parameters": self.baseline.params,
            },
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
            },
            "verdict": verdict,
            "skipped": self.skipped,
            "whiteness": self.whiteness,
            "periods": {
                "train": [split.train.times[0].isoformat(), self.boundary.isoformat()],
                "test": [
                    self.boundary.isoformat(),
                    (split.test.times[-1] + pd.Timedelta(seconds=split.test.step_s)).isoformat(),
                ],
            },
            "wall_time_s": self.wall_time_s,
        }

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(_plain(self.to_dict()), indent=indent, allow_nan=False)


def _plain(value: object) -> object:
    """JSON-safe copy: numpy scalars and arrays to Python, NaN and ±inf to null."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value) if np.isfinite(value) else None
    return value
