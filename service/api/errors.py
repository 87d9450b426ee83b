"""Errors of the engine and of the service's logic as HTTP answers."""

from __future__ import annotations

import re

from fastapi import FastAPI, Request, status
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException

from rcengine.exceptions import BuildingError, DataValidationError, ModelError

from ..errors import CalibrationError, ConflictError, DiagnosisError, NotFoundError


def _data_error(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, DataValidationError)
    problems = [{"row": p.row, "column": p.column, "message": p.message} for p in exc.problems]
    return JSONResponse(
        {"detail": str(exc), "problems": problems}, status.HTTP_422_UNPROCESSABLE_CONTENT
    )


def _request_error(_request: Request, exc: Exception) -> JSONResponse:
    """FastAPI's validation errors in the documented shape (detail text plus problems), naming
    each field without echoing the body back."""
    assert isinstance(exc, RequestValidationError)
    problems = [_problem(error) for error in exc.errors()]
    detail = "invalid request: " + "; ".join(f"{p['column']}: {p['message']}" for p in problems)
    return JSONResponse(
        {"detail": detail, "problems": problems}, status.HTTP_422_UNPROCESSABLE_CONTENT
    )


def _problem(error: dict) -> dict:
    if error["type"] == "json_invalid":  # loc: ("body", character position)
        why = error.get("ctx", {}).get("error", "")
        message = f"the body is not valid JSON ({why}) at character {error['loc'][-1]}"
        return {"row": None, "column": "body", "message": message}
    return {"row": None, "column": _field(error["loc"]), "message": error["msg"]}


def _field(location: tuple | list) -> str:
    """``("body", "q_hvac", 1)`` → ``"q_hvac[1]"``; ``("query", "hours")`` → ``"hours"``."""
    text = ""
    for part in location[1:] or location:
        text += f"[{part}]" if isinstance(part, int) else f".{part}" if text else str(part)
    return text or str(location[0])


def _answer(code: int):
    def handler(_request: Request, exc: Exception) -> JSONResponse:
        if code == status.HTTP_422_UNPROCESSABLE_CONTENT:  # documented with its problems
            # A building description's field at fault is its "column" (docs/service.md).
            problem = {"row": None, "column": getattr(exc, "field", None), "message": str(exc)}
            return JSONResponse({"detail": str(exc), "problems": [problem]}, code)
        return JSONResponse({"detail": str(exc)}, code)

    return handler


async def _http_error(request: Request, exc: Exception) -> Response:
    """Starlette's answer, but a 405 allows every method the OpenAPI document gives the path
    (Starlette lists only those of the first route that matched it)."""
    assert isinstance(exc, StarletteHTTPException)
    if exc.status_code == status.HTTP_405_METHOD_NOT_ALLOWED:
        allowed = {
            method.upper()
            for template, operations in request.app.openapi()["paths"].items()
            if re.fullmatch(re.sub(r"\{[^/]+\}", "[^/]+", template), request.url.path)
            for method in operations
        }
        exc.headers = {**(exc.headers or {}), "Allow": ", ".join(sorted(allowed))}
    return await http_exception_handler(request, exc)


def install_error_handlers(app: FastAPI) -> None:
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(DataValidationError, _data_error)
    app.add_exception_handler(RequestValidationError, _request_error)
    for error, code in (
        (BuildingError, status.HTTP_422_UNPROCESSABLE_CONTENT),
        (ModelError, status.HTTP_422_UNPROCESSABLE_CONTENT),
        (NotFoundError, status.HTTP_404_NOT_FOUND),
        (ConflictError, status.HTTP_409_CONFLICT),
        # The stored data do not allow the job asked for (too little, no step yet).
        (CalibrationError, status.HTTP_409_CONFLICT),
        (DiagnosisError, status.HTTP_409_CONFLICT),
    ):
        app.add_exception_handler(error, _answer(code))
