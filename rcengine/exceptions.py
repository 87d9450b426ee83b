"""Errors and warnings of the engine, distinct classes so callers can catch them apart."""

from __future__ import annotations

from dataclasses import dataclass


class RCEngineError(Exception):
    """Base class of every error the engine raises on purpose."""


@dataclass(frozen=True)
class Problem:
    """One problem in a data set: which row (0-based data row, ``None`` for the whole file),
    which column, and what is wrong."""

    row: int | None
    column: str | None
    message: str

    def __str__(self) -> str:
        where = []
        if self.row is not None:
            where.append(f"row {self.row}")
        if self.column is not None:
            where.append(f"column '{self.column}'")
        prefix = ", ".join(where)
        return f"{prefix}: {self.message}" if prefix else self.message


class DataValidationError(RCEngineError, ValueError):
    """The time-series data break a rule of the contract; ``problems`` lists each one."""

    def __init__(self, problems: list[Problem], max_listed: int = 20):
        self.problems = list(problems)
        self.max_listed = max_listed
        shown = "; ".join(str(p) for p in self.problems[:max_listed])
        more = len(self.problems) - max_listed
        if more > 0:
            shown += f"; ... and {more} more"
        super().__init__(f"invalid data: {shown}")

    def __reduce__(self) -> tuple:
        # Rebuilt from its problems, not its message: a job's error crosses to the service
        # from a worker process, and the default (the message as ``problems``) listed each
        # character of it as a problem.
        return (type(self), (self.problems, self.max_listed))


class BuildingError(RCEngineError, ValueError):
    """The building description is invalid or lacks what a model needs; ``field``: the
    description's field at fault (``location.timezone``, ``windows[0].tilt``), where one is."""

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.field = field

    def __reduce__(self) -> tuple:
        return (type(self), (str(self), self.field))


class ModelError(RCEngineError, ValueError):
    """A network or model is ill-formed, unknown, or lacks an input."""


class NotFittedError(RCEngineError, AttributeError):
    """An estimator was used before ``fit``."""


class ConvergenceWarning(UserWarning):
    """The optimiser stopped on its iteration limit or a parameter sits on a bound."""
