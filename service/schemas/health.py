"""Liveness."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class HealthRead(BaseModel):
    model_config = ConfigDict(
        json_schema_extra={"examples": [{"status": "ok", "database": "ok", "version": "0.1.0"}]}
    )

    status: str
    database: str
    version: str
