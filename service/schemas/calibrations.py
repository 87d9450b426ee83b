"""Calibrations: the request that starts one (the job is answered as ``schemas.jobs.JobRead``)."""

from __future__ import annotations

from pydantic import BaseModel, Field

from .common import ModelName, with_examples


class CalibrationRequest(BaseModel):
    model_config = with_examples({"days": 7, "model": "basic"}, extra="forbid")

    days: int | None = Field(
        None, ge=1, le=365, description="Days fitted before the held-out day (default 7)"
    )
    model: ModelName = None
