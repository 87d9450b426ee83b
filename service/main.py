"""The app factory: ``create_app(settings)`` builds an app whose lifespan owns the database
engine, the job executor and the scheduler; nothing is created at import time."""

from __future__ import annotations

import logging
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI

from rcengine import __version__

from .api import api_router
from .api.errors import install_error_handlers
from .api.middleware import BodyLimitMiddleware, RequestLogMiddleware
from .context import ServiceContext
from .core.config import Settings
from .core.db import Database
from .forecasting import Forecaster
from .jobs import JobRunner, announce_mode, fail_interrupted
from .scheduler import start_scheduler
from .tokens import TokenIndex, admin_token_hash
from .ui import install_ui

log = logging.getLogger(__name__)

DESCRIPTION = """
Calibrated grey-box RC thermal models of buildings for Model Predictive Control.

1. `POST /buildings` with the admin token and the building description → id and the
   building's own token (use it for everything below).
2. `POST /buildings/{id}/measurements`: measured rows, and future rows (`t_in` empty) with the
   weather forecast and planned `q_hvac`.
3. `POST /buildings/{id}/calibrations`, poll `GET /jobs/{job_id}`; a nightly job re-fits every
   building with new data.
4. `GET /buildings/{id}/forecast`, `POST /buildings/{id}/simulate`, `GET /buildings/{id}/model`.
5. `POST /buildings/{id}/diagnoses`, then `GET /buildings/{id}/diagnosis` (JSON or HTML): where
   the model misses the measurements and which physics it lacks; `POST
   /buildings/{id}/diagnoses/{diagnosis_id}/adopt` makes that model the building's (calibrated at
   once, served only if it wins the held-out day), `POST /buildings/{id}/model/revert` undoes it.

Every call but `/health` needs `Authorization: Bearer <token>`.
"""

TAGS = [
    {"name": "buildings", "description": "Register buildings and read their state."},
    {"name": "measurements", "description": "Upload and read time series (CONTRACT.md §1)."},
    {"name": "calibrations", "description": "Re-estimate parameters."},
    {"name": "diagnoses", "description": "Mismatch diagnosis: the physics the model lacks."},
    {"name": "jobs", "description": "Poll calibration and diagnosis jobs."},
    {"name": "parameters", "description": "Parameter sets with their fit metrics."},
    {"name": "forecast", "description": "Forecasts, trajectories and the model for an MPC."},
    {"name": "health", "description": "Liveness."},
]


def create_app(settings: Settings | None = None) -> FastAPI:
    """A new app; ``settings`` default to the environment (``RCSERVICE_*``)."""
    settings = settings or Settings()
    app = FastAPI(
        title="rcservice",
        version=__version__,
        summary="Calibration service for grey-box RC building models",
        description=DESCRIPTION,
        openapi_tags=TAGS,
        lifespan=lifespan,
    )
    app.state.settings = settings
    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes)
    app.add_middleware(RequestLogMiddleware)
    install_error_handlers(app)
    app.include_router(api_router)
    install_ui(app)
    return app


@asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    settings: Settings = app.state.settings
    folder = settings.sqlite_path.parent if settings.sqlite_path is not None else None
    if folder is not None and not folder.exists():
        # The embedded default lives in a folder of its own; say so when it is made, so a
        # mistyped RCSERVICE_DATABASE_URL shows in the log instead of an empty service.
        folder.mkdir(parents=True)
        log.warning("created the database folder", extra={"folder": str(folder)})
    db = Database(settings.database_url)
    db.migrate()
    admin_hash = admin_token_hash(settings, db)
    fail_interrupted(db)
    runner = JobRunner(settings, db)
    announce_mode(settings, db, runner.terms.owner)
    if settings.several_processes:  # jobs a dead replica queued are claimed, not failed
        runner.resume_queued()
    scheduler = start_scheduler(settings, db, runner) if settings.scheduler_enabled else None
    app.state.context = ServiceContext(
        settings=settings,
        db=db,
        admin_token_hash=admin_hash,
        tokens=TokenIndex(db),
        runner=runner,
        forecaster=Forecaster(db, settings.forecast_cache_size),
    )
    log.info("service started", extra={"database": _safe_url(db)})
    try:
        yield
    finally:
        if scheduler is not None:
            scheduler.shutdown(wait=False)
        runner.shutdown()
        db.dispose()
        log.info("service stopped")


def _safe_url(db: Database) -> str:
    return db.engine.url.render_as_string(hide_password=True)
