"""Diagnoses: the request that starts one, and the stored report (CONTRACT.md §3 fields plus
the service's own)."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, model_validator

from rcengine.diagnose import DiagnoseSettings
from rcengine.diagnose.settings import TRAIN_FRACTION

from .common import LocalTime, ModelName, with_examples

# The effect ids of CONTRACT.md §3 that the engine can test (its default: all of them).
EFFECTS = DiagnoseSettings().effects

REQUEST_EXAMPLE = {
    "model": "basic",
    "days": 28,
    "effects": ["window_solar_gains", "unmetered_gains"],
}

FINDING_EXAMPLE = {
    "effect": "unmetered_gains",
    "accepted": True,
    "explanation": "The model misses internal heat gains that are not in the data, on a weekly "
    "schedule. It under-predicts on weekdays 08:00-18:00; adding them cuts the test RMSE from "
    "0.30 to 0.20 K.",
    "rmse_test_before": 0.303,
    "rmse_test_after": 0.199,
    "round": 1,
    "delta_bic": -412.0,
}

DIAGNOSIS_EXAMPLE = {
    "id": 3,
    "building_id": 1,
    "job_id": 14,
    "created_at": "2016-10-22T02:01:10+02:00",
    "window": {
        "start": "2016-10-01T00:00:00+02:00",
        "end": "2016-10-22T00:00:00+02:00",
        "train_fraction": 0.5,
    },
    "settings": {
        "preset": "study",
        "random_state": 0,
        "train_fraction": 0.5,
        "effects": ["unmetered_gains"],
    },
    "engine_version": "0.1.0",
    "baseline": {"model": "basic", "rmse_train": 0.205, "rmse_test": 0.303},
    "mismatch": {"summary": "under-predicts on weekdays 08:00-18:00 ..."},
    "findings": [FINDING_EXAMPLE],
    "final": {"model": "basic+unmetered_gains", "rmse_train": 0.147, "rmse_test": 0.199},
    "verdict": "missing physics found: unmetered_gains",
}


def _known_effects(effects: list[str] | None) -> list[str] | None:
    if effects is None:
        return None
    unknown = [e for e in effects if e not in EFFECTS]
    if unknown:
        raise ValueError(f"unknown effect(s) {unknown}; choose from {list(EFFECTS)}")
    if not effects or len(set(effects)) != len(effects):
        raise ValueError("effects must name at least one effect, each once")
    return effects


class DiagnosisRequest(BaseModel):
    """The window is ``days`` before ``end``, or ``start`` to ``end``; ``end`` defaults to one
    step after the last measured t_in. The window is clipped to the stored measured rows."""

    model_config = with_examples(REQUEST_EXAMPLE, extra="forbid")

    model: ModelName = None
    days: int | None = Field(
        None,
        ge=2,
        le=3660,
        description="Days diagnosed, ending at `end` (default RCSERVICE_DIAGNOSIS_DAYS, 182)",
    )
    start: str | None = Field(
        None,
        description="Window start, ISO 8601 with UTC offset (instead of `days`)",
        examples=["2016-10-01T00:00:00+02:00"],
    )
    end: str | None = Field(
        None,
        description="Window end (exclusive), ISO 8601 with UTC offset; default one step after "
        "the last measured t_in",
        examples=["2016-10-22T00:00:00+02:00"],
    )
    train_fraction: float | None = Field(
        None,
        ge=TRAIN_FRACTION[0],
        le=TRAIN_FRACTION[1],
        description="Share of the window fitted (whole days); the rest tests the fit "
        "(default: the engine's, 0.5)",
    )
    effects: Annotated[list[str] | None, AfterValidator(_known_effects)] = Field(
        None, description=f"Effect ids to test (default: all): {', '.join(EFFECTS)}"
    )

    @model_validator(mode="after")
    def _one_window(self) -> DiagnosisRequest:
        if self.days is not None and self.start is not None:
            raise ValueError("give either days or start, not both")
        return self


class ReportPart(BaseModel):
    """A part of the engine's report: the fields it adds beyond these reach the client too."""

    model_config = ConfigDict(extra="allow")


class BaselineRead(ReportPart):
    """The model as given, fitted on the training part."""

    model: str
    rmse_train: float | None = Field(description="[K]")
    rmse_test: float | None = Field(description="On the later test period. [K]")


class FindingRead(ReportPart):
    """One candidate effect's verdict; the first accepted one is the tool's answer."""

    effect: str
    accepted: bool
    explanation: str
    rmse_test_before: float | None = Field(description="[K]")
    rmse_test_after: float | None = Field(description="None when only screened. [K]")


class MismatchRead(ReportPart):
    """Where and when the baseline's errors concentrate."""

    summary: str


class DiagnosisWindow(BaseModel):
    start: LocalTime = Field(description="First row diagnosed")
    end: LocalTime = Field(description="One step after the last row diagnosed")
    train_fraction: float


class DiagnosisRead(BaseModel):
    """The report of ``rcengine diagnose`` (CONTRACT.md §3: every field of the engine's JSON,
    at the top level) plus the service's: id, job, creation time, window, engine settings."""

    model_config = with_examples(DIAGNOSIS_EXAMPLE, extra="allow")

    id: int
    building_id: int
    job_id: int | None
    created_at: LocalTime
    window: DiagnosisWindow
    settings: dict[str, Any] = Field(description="preset, random_state, train_fraction, effects")
    engine_version: str
    baseline: BaselineRead
    mismatch: MismatchRead
    findings: list[FindingRead]
    final: BaselineRead = Field(description="The model with every accepted extension")
