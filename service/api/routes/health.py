"""Liveness: the only call without a token."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, status
from sqlalchemy import text

from rcengine import __version__

from ...schemas.health import HealthRead
from ..deps import ContextDep

router = APIRouter(tags=["health"])


@router.get(
    "/health",
    summary="Liveness and database check",
    responses={503: {"description": "The database does not answer"}},
)
def health(ctx: ContextDep) -> HealthRead:
    try:
        with ctx.db.session() as session:
            session.execute(text("SELECT 1"))
    except Exception as exc:  # any database failure means "not healthy"
        raise HTTPException(status.HTTP_503_SERVICE_UNAVAILABLE, f"database: {exc}") from exc
    return HealthRead(status="ok", database="ok", version=__version__)
