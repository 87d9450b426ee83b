"""The dashboard's pages and forms under ``/ui``.

Pages are rendered on the server (Jinja2, autoescaped); the charts are drawn in the browser by
plotly.js, served from the ``plotly`` package, with the series embedded as JSON. Forms post to
the server with the session's CSRF token; the cookie is ``SameSite=Strict`` besides.
"""

from __future__ import annotations

import secrets
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, Form, Request, status
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from fastapi.templating import Jinja2Templates

from .. import repository
from ..core.security import same_hash
from ..diagnosis import DiagnosisSpec
from ..errors import ConflictError, NotFoundError
from ..models import CALIBRATION, DIAGNOSIS, JOB_COLLECTIONS
from ..schemas.common import id_in_path
from . import views
from .auth import ContextDep, SessionDep, reachable, store, who
from .sessions import COOKIE, SESSION_TTL_S, SIGNIN_COOKIE, Session

TEMPLATES = Jinja2Templates(directory=Path(__file__).parent / "templates")
PREFIX = "/ui"
TRIGGER = "dashboard"
# Only our own files: no inline script, no other origin (plotly adds inline styles).
CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
    "img-src 'self' data:; frame-ancestors 'none'; form-action 'self'; base-uri 'none'"
)
SECURITY_HEADERS = {
    "Content-Security-Policy": CSP,
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}
# The engine's report: inline styles and data: images, nothing to run.
REPORT_HEADERS = {
    "Content-Security-Policy": "sandbox; default-src 'none'; img-src data:; "
    "style-src 'unsafe-inline'",
    "X-Content-Type-Options": "nosniff",
    "Cache-Control": "no-store",
}
IdPath = Annotated[int, id_in_path("Building", 1)]

router = APIRouter(prefix=PREFIX, include_in_schema=False)


def render(
    request: Request, template: str, code: int = 200, session: Session | None = None, **values
) -> HTMLResponse:
    if session is not None:
        values.update(session=session, flash=session.flash)
        session.flash = None
    response = TEMPLATES.TemplateResponse(request, template, values, status_code=code)
    response.headers.update(SECURITY_HEADERS)
    return response


def redirect(path: str) -> RedirectResponse:
    return RedirectResponse(path, status.HTTP_303_SEE_OTHER)


def not_found(request: Request, session: Session, exc: Exception) -> HTMLResponse:
    return render(request, "error.html", 404, session, message=str(exc))


def _cookie(response: Response, request: Request, name: str, value: str, max_age: int) -> None:
    response.set_cookie(
        name,
        value,
        max_age=max_age,
        path=PREFIX,
        httponly=True,
        samesite="strict",
        secure=request.url.scheme == "https",
    )


# --- sign-in ----------------------------------------------------------------------------------
@router.get("/login")
def login_page(request: Request, error: str | None = None) -> HTMLResponse:
    form_token = secrets.token_urlsafe(32)
    response = render(request, "login.html", 200, csrf=form_token, error=error)
    _cookie(response, request, SIGNIN_COOKIE, form_token, 3600)
    return response


@router.post("/login")
def login(
    request: Request,
    ctx: ContextDep,
    token: Annotated[str, Form(max_length=200)] = "",
    csrf: Annotated[str, Form(max_length=100)] = "",
) -> Response:
    expected = request.cookies.get(SIGNIN_COOKIE, "")
    if not expected or not same_hash(expected, csrf):
        return render(request, "login.html", 403, csrf="", error="the form expired; reload it")
    found = who(ctx, token) if token.strip() else None
    if found is None:
        return render(request, "login.html", 401, csrf=csrf, error="unknown token")
    session_id, _ = store(request).open(*found)
    response = redirect(PREFIX)
    _cookie(response, request, COOKIE, session_id, int(SESSION_TTL_S))
    response.delete_cookie(SIGNIN_COOKIE, path=PREFIX)
    return response


@router.post("/logout")
def logout(request: Request, session: SessionDep, csrf: Annotated[str, Form()] = "") -> Response:
    if not session.csrf_ok(csrf):
        return render(request, "error.html", 403, session, message="invalid form token")
    store(request).close(request.cookies.get(COOKIE))
    response = redirect(f"{PREFIX}/login")
    response.delete_cookie(COOKIE, path=PREFIX)
    return response


# --- pages ------------------------------------------------------------------------------------
@router.get("")
def home(session: SessionDep) -> Response:
    if session.building_id is None:
        return redirect(f"{PREFIX}/fleet")
    return redirect(f"{PREFIX}/buildings/{session.building_id}")


@router.get("/fleet")
async def fleet_page(request: Request, session: SessionDep, ctx: ContextDep) -> Response:
    if session.building_id is not None:  # a building token sees only its building
        return redirect(f"{PREFIX}/buildings/{session.building_id}")
    rows = await run_in_threadpool(views.fleet, ctx)
    return render(request, "fleet.html", 200, session, rows=rows)


@router.get("/buildings/{building_id}")
async def building_page(
    request: Request, building_id: IdPath, session: SessionDep, ctx: ContextDep
) -> Response:
    try:
        reachable(ctx, session, building_id)
    except NotFoundError as exc:
        return not_found(request, session, exc)
    page = await run_in_threadpool(views.building_page, ctx, building_id)
    return render(request, "building.html", 200, session, **page)


@router.get("/buildings/{building_id}/jobs")
def active_jobs(building_id: IdPath, session: SessionDep, ctx: ContextDep) -> JSONResponse:
    """Whether the building has a queued or running job: the page polls it to refresh."""
    reachable(ctx, session, building_id)
    with ctx.db.session() as db_session:
        active = [
            job.id
            for kind in (CALIBRATION, DIAGNOSIS)
            if (job := repository.active_job(db_session, building_id, kind)) is not None
        ]
    return JSONResponse({"active": active}, headers={"Cache-Control": "no-store"})


@router.get("/buildings/{building_id}/diagnosis")
def diagnosis_report(
    request: Request, building_id: IdPath, session: SessionDep, ctx: ContextDep
) -> Response:
    """The latest diagnosis report, the page the API serves with ``format=html``."""
    try:
        reachable(ctx, session, building_id)
        with ctx.db.session() as db_session:
            record = repository.latest_diagnosis(db_session, building_id)
            if record is None:
                raise NotFoundError(f"building {building_id} has no diagnosis report yet")
            return HTMLResponse(record.html, headers=REPORT_HEADERS)
    except NotFoundError as exc:
        return not_found(request, session, exc)


# --- actions ----------------------------------------------------------------------------------
def _route_start(kind: str, collection: str) -> None:
    """Route the building page's button that queues a job of ``kind``."""

    @router.post(f"/buildings/{{building_id}}/{collection}", name=f"start_{kind}")
    def start(
        request: Request,
        building_id: IdPath,
        session: SessionDep,
        ctx: ContextDep,
        csrf: Annotated[str, Form()] = "",
    ) -> Response:
        if not session.csrf_ok(csrf):
            return render(request, "error.html", 403, session, message="invalid form token")
        try:
            reachable(ctx, session, building_id)
        except NotFoundError as exc:
            return not_found(request, session, exc)
        model = ctx.settings.model
        try:
            if kind == DIAGNOSIS:
                job = ctx.runner.create_diagnosis(building_id, model, DiagnosisSpec(), TRIGGER)
            else:
                days = ctx.settings.training_days
                job = ctx.runner.create_calibration(building_id, model, days, TRIGGER)
            session.flash = f"{kind} job {job.id} queued"
        except ConflictError as exc:
            session.flash = f"not started: {exc}"
        return redirect(f"{PREFIX}/buildings/{building_id}#jobs")


for kind, collection in JOB_COLLECTIONS.items():
    _route_start(kind, collection)
