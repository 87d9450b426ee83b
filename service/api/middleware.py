"""ASGI middleware: a log line per request, and the request-size limit."""

from __future__ import annotations

import logging
import re
import time
import uuid

from fastapi import HTTPException, status
from fastapi.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

log = logging.getLogger("service.request")


# A caller's request id is echoed and logged only if it looks like one (a UUID, a trace id): an
# 8 kB header was sent back whole and written to every log line.
_REQUEST_ID = re.compile(r"[A-Za-z0-9._:-]{1,128}")


class RequestLogMiddleware:
    """One JSON log line per request (id, method, path, status, duration); the id is echoed in
    the ``X-Request-ID`` response header (taken from the request's when it has a plausible one)."""

    def __init__(self, app: ASGIApp):
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        given = _header(scope, b"x-request-id")
        request_id = given if given and _REQUEST_ID.fullmatch(given) else uuid.uuid4().hex[:16]
        started = time.perf_counter()
        status_code = 500

        async def send_with_id(message: Message) -> None:
            nonlocal status_code
            if message["type"] == "http.response.start":
                status_code = message["status"]
                message["headers"] = [
                    *message.get("headers", []),
                    (b"x-request-id", request_id.encode()),
                ]
            await send(message)

        try:
            await self.app(scope, receive, send_with_id)
        finally:
            extra = {
                "request_id": request_id,
                "method": scope["method"],
                "path": scope["path"],
                "status": status_code,
                "duration_ms": round((time.perf_counter() - started) * 1000.0, 2),
            }
            building_id = str(scope.get("path_params", {}).get("building_id", ""))
            # An id the database can hold (a 5,000-digit one exceeds int()'s digit limit).
            if building_id.isdigit() and len(building_id) <= 18:
                extra["building_id"] = int(building_id)
            log.info("request", extra=extra)


class BodyLimitMiddleware:
    """413 for a body over ``max_bytes``: at once from ``Content-Length``, else while the body
    streams in (chunked uploads have no length)."""

    def __init__(self, app: ASGIApp, max_bytes: int):
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        declared = _header(scope, b"content-length")
        if declared is not None and (not declared.isdigit() or int(declared) > self.max_bytes):
            code = status.HTTP_413_CONTENT_TOO_LARGE if declared.isdigit() else 400
            message = self._too_large(int(declared)) if declared.isdigit() else "bad Content-Length"
            await JSONResponse({"detail": message}, code)(scope, receive, send)
            return
        received = 0

        async def limited_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.max_bytes:
                    raise HTTPException(
                        status.HTTP_413_CONTENT_TOO_LARGE, self._too_large(received)
                    )
            return message

        await self.app(scope, limited_receive, send)

    def _too_large(self, size: int) -> str:
        return (
            f"request body of {size} bytes or more exceeds the limit of {self.max_bytes} bytes "
            "(RCSERVICE_MAX_BODY_BYTES); split the upload into several requests"
        )


def _header(scope: Scope, name: bytes) -> str | None:
    for key, value in scope.get("headers", []):
        if key == name:
            return value.decode("latin-1")
    return None
