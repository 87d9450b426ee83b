"""Dependencies of the routes: the service context and who the bearer token lets in.

A building's token reaches only that building: any other building id answers 404, exactly as if
it did not exist, so ids cannot be probed. The admin token registers buildings and may read any.

The dependencies are ``async``: FastAPI runs a plain ``def`` dependency on a worker thread, and
these only hash a token and read a cache (a database query only on a cache miss), far cheaper
than a thread hop per dependency per request.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, HTTPException, Request, Security, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from .. import repository
from ..context import ServiceContext
from ..core.security import hash_token, same_hash
from ..schemas.common import error_responses, id_in_path

bearer = HTTPBearer(
    auto_error=False,
    description="The admin token (registers buildings) or a building's own token.",
)
Credentials = Annotated[HTTPAuthorizationCredentials | None, Security(bearer)]


async def get_context(request: Request) -> ServiceContext:
    return request.app.state.context


ContextDep = Annotated[ServiceContext, Depends(get_context)]


def _unauthorized(message: str) -> HTTPException:
    return HTTPException(
        status.HTTP_401_UNAUTHORIZED, message, headers={"WWW-Authenticate": "Bearer"}
    )


def _token_hash(credentials: HTTPAuthorizationCredentials | None) -> str:
    if credentials is None or not credentials.credentials:
        raise _unauthorized("missing bearer token: send the header 'Authorization: Bearer <token>'")
    return hash_token(credentials.credentials)


def _is_admin(ctx: ServiceContext, token_hash: str) -> bool:
    return same_hash(token_hash, ctx.admin_token_hash)


async def require_admin(ctx: ContextDep, credentials: Credentials) -> None:
    token_hash = _token_hash(credentials)
    if _is_admin(ctx, token_hash):
        return
    if ctx.tokens.building_for(token_hash) is not None:
        raise HTTPException(status.HTTP_403_FORBIDDEN, "this call needs the admin token")
    raise _unauthorized("invalid token")


async def token_building(ctx: ContextDep, credentials: Credentials) -> int | None:
    """The building a token belongs to; None for the admin token."""
    token_hash = _token_hash(credentials)
    if _is_admin(ctx, token_hash):
        return None
    owner = ctx.tokens.building_for(token_hash)
    if owner is None:
        raise _unauthorized("invalid token")
    return owner


async def building_access(
    building_id: Annotated[int, id_in_path("Building", 1)],
    ctx: ContextDep,
    credentials: Credentials,
) -> int:
    """The path's building id, if the token may reach it."""
    owner = await token_building(ctx, credentials)
    if owner is None:  # the admin token: any building that exists
        with ctx.db.session() as session:
            repository.get_building(session, building_id)  # NotFoundError: 404
    elif owner != building_id:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"building {building_id} not found")
    return building_id


BuildingDep = Annotated[int, Depends(building_access)]
TokenBuildingDep = Annotated[int | None, Depends(token_building)]
# In a route's ``dependencies``: the call needs the admin token (and nothing from it).
ADMIN_ONLY = Depends(require_admin)
# What any call may answer about a resource it names: no valid token (401), or a resource the
# token cannot reach (404); a router whose every call answers only these declares them once.
ACCESS_ERRORS = error_responses(401, 404)
