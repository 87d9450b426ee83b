"""Who may see what on the dashboard: the session behind the cookie, checked against the tokens
on every request, and the building it reaches (a building token: only its own; any other id is
'not found', as in the API)."""

from __future__ import annotations

import secrets
from typing import Annotated

from fastapi import Depends, Request

from .. import repository
from ..context import ServiceContext
from ..core.security import hash_token, same_hash
from ..errors import NotFoundError
from .sessions import COOKIE, Session, SessionStore


class SignInRequiredError(Exception):
    """No valid session: the dashboard answers with the sign-in page."""


def context(request: Request) -> ServiceContext:
    return request.app.state.context


def store(request: Request) -> SessionStore:
    return request.app.state.ui_sessions


def who(ctx: ServiceContext, token: str) -> tuple[str, int | None] | None:
    """(token hash, building id or None for the admin) of a valid token, else None."""
    token_hash = hash_token(token.strip())
    if same_hash(token_hash, ctx.admin_token_hash):
        return token_hash, None
    building_id = ctx.tokens.building_for(token_hash)
    return None if building_id is None else (token_hash, building_id)


def _still_valid(ctx: ServiceContext, session: Session) -> bool:
    if session.building_id is None:
        return same_hash(session.token_hash, ctx.admin_token_hash)
    return ctx.tokens.building_for(session.token_hash) == session.building_id


async def signed_in(request: Request) -> Session:
    ctx = context(request)
    sessions = store(request)
    session_id = request.cookies.get(COOKIE)
    session = sessions.get(session_id)
    if session is None or not _still_valid(ctx, session):
        sessions.close(session_id)
        raise SignInRequiredError
    return session


SessionDep = Annotated[Session, Depends(signed_in)]
ContextDep = Annotated[ServiceContext, Depends(context)]


def reachable(ctx: ServiceContext, session: Session, building_id: int) -> int:
    """``building_id`` if the session may see it; NotFoundError (404) otherwise."""
    if session.building_id is None:
        with ctx.db.session() as db_session:
            repository.get_building(db_session, building_id)
        return building_id
    if session.building_id != building_id:
        raise NotFoundError(f"building {building_id} not found")
    return building_id


def new_form_token() -> str:
    return secrets.token_urlsafe(32)
