"""Errors of the service's own logic; the API layer turns them into HTTP statuses.

Data problems reuse the engine's :class:`~rcengine.exceptions.DataValidationError` (with its list
of row/column problems), so the service rejects exactly what the engine rejects.
"""

from __future__ import annotations


class ServiceError(Exception):
    """Base class of the service's deliberate errors."""


class NotFoundError(ServiceError):
    """No such resource for this caller (another building's resources are "not found" too)."""


class ConflictError(ServiceError):
    """The request clashes with the current state (a job already active, no parameter set)."""


class NoParameterSetError(ConflictError):
    """The building has no current parameter set yet."""

    def __init__(self, building_id: int):
        super().__init__(
            f"building {building_id} has no calibrated parameter set yet; start one with "
            f"POST /buildings/{building_id}/calibrations and wait for it to succeed"
        )


class LeaseLostError(ServiceError):
    """A job run's lease was taken over (its job failed as abandoned): its writes are refused."""


class CalibrationError(ServiceError):
    """A calibration cannot run on the stored data (too little data, gaps, ...)."""


class DiagnosisError(ServiceError):
    """A diagnosis cannot run on the stored data (too little measured data in its window)."""
