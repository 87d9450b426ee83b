"""Errors of the engine and of the service's logic as HTTP answers."""

from __future__ import annotations

from fastapi import FastAPI, Request, status
from fastapi.responses import JSONResponse

from rcengine.exceptions import BuildingError, DataValidationError, ModelError

from ..errors import ConflictError, NotFoundError


def _data_error(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, DataValidationError)
    problems = [{"row": p.row, "column": p.column, "message": p.message} for p in exc.problems]
    return JSONResponse(
        {"detail": str(exc), "problems": problems}, status.HTTP_422_UNPROCESSABLE_CONTENT
    )


def _answer(code: int):
    def handler(_request: Request, exc: Exception) -> JSONResponse:
        return JSONResponse({"detail": str(exc)}, code)

    return handler


def install_error_handlers(app: FastAPI) -> None:
    app.add_exception_handler(DataValidationError, _data_error)
    for error, code in (
        (BuildingError, status.HTTP_422_UNPROCESSABLE_CONTENT),
        (ModelError, status.HTTP_422_UNPROCESSABLE_CONTENT),
        (NotFoundError, status.HTTP_404_NOT_FOUND),
        (ConflictError, status.HTTP_409_CONFLICT),
    ):
        app.add_exception_handler(error, _answer(code))
