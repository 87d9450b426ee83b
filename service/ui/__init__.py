"""The dashboard: the service's buildings, models, forecasts and diagnoses in the browser, under
``/ui``. Everything it loads is served by the service itself (no CDN): its own CSS and script,
and plotly.js from the ``plotly`` package."""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles

from .auth import SignInRequiredError
from .routes import PREFIX, router
from .sessions import SessionStore

STATIC = Path(__file__).parent / "static"
# A week: the files change only with the installed version.
STATIC_CACHE = "public, max-age=604800"


def plotly_js() -> Path:
    """plotly.min.js as the ``plotly`` package ships it."""
    return Path(str(files("plotly") / "package_data" / "plotly.min.js"))


def install_ui(app: FastAPI) -> None:
    """Add the dashboard's routes, static files and sessions to ``app``."""
    app.state.ui_sessions = SessionStore()
    app.include_router(router)
    app.mount(f"{PREFIX}/static", StaticFiles(directory=STATIC), name="ui-static")

    @app.get(f"{PREFIX}/vendor/plotly.min.js", include_in_schema=False)
    def plotly() -> FileResponse:
        return FileResponse(
            plotly_js(), media_type="text/javascript", headers={"Cache-Control": STATIC_CACHE}
        )

    @app.exception_handler(SignInRequiredError)
    def sign_in(_request: Request, _exc: Exception) -> RedirectResponse:
        return RedirectResponse(f"{PREFIX}/login", status_code=303)
