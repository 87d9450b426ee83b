"""Adopting a diagnosed model, and reverting to the base model.

Adopting stores the diagnosis's final model as the building's model specification
(:class:`~rcengine.models.spec.ModelSpec`: the network, its signal settings and provenance), which
every later calibration fits (``service.calibration``). The served parameter set changes only
through the usual promotion: the calibration started with the adoption must beat the current set
on the held-out day, so adopting a model that does not forecast better changes nothing served.

Reverting clears the specification: the base model is calibrated from then on, and the set the
building served before the adoption — the latest base-model set that was once current — is
served again at once (an undo must not wait for the base model to win a held-out day against
the model it undoes).

Every call is audited (``ModelChangeRecord``: who, when, which diagnosis, whether it changed
anything); adopting the adopted diagnosis again or reverting a base model changes nothing.
"""

from __future__ import annotations

import json
import logging
from concurrent.futures import Future
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import pandas as pd
from sqlalchemy import select, update
from sqlalchemy.orm import Session

from rcengine.exceptions import RCEngineError
from rcengine.io.jsonable import jsonable
from rcengine.models import MODELS
from rcengine.models.spec import ModelSpec

from . import bridge, repository
from .errors import ConflictError, NotFoundError, ServiceError
from .models import (
    CURRENT,
    SUCCEEDED,
    SUPERSEDED,
    BuildingRecord,
    DiagnosisRecord,
    ModelChangeRecord,
    ParameterSetRecord,
)

if TYPE_CHECKING:  # the runner owns the jobs; adoption only asks it for a calibration
    from .jobs import JobRunner

log = logging.getLogger(__name__)
ADOPT, REVERT = "adopt", "revert"
# Who made a change: the admin token, the building's own token, or the automatic adoption of a
# diagnosis's findings (RCSERVICE_AUTO_ADOPT).
ADMIN, BUILDING, AUTO = "admin", "building", "auto"


@dataclass(frozen=True)
class Change:
    """An adopt or revert call's audit row, and the model the building uses after it."""

    record: ModelChangeRecord
    spec: ModelSpec | None


def spec_of(building: BuildingRecord) -> ModelSpec | None:
    """The building's adopted model, None for the base model."""
    return None if building.model_spec is None else ModelSpec.from_dict(building.model_spec)


def _adopted_from(spec: ModelSpec | None) -> tuple[int | None, str | None]:
    """The diagnosis and the finding (None: its final model) a model was adopted from."""
    source = {} if spec is None else spec.source
    return source.get("diagnosis_id"), source.get("finding")


def job_model(spec: ModelSpec | None, default: str) -> str:
    """What a calibration job is labelled with: the adopted model's name, else ``default``."""
    return default if spec is None else spec.name


def adopt(
    session: Session, building_id: int, diagnosis_id: int, actor: str, finding: str | None = None
) -> Change:
    """Make diagnosis ``diagnosis_id``'s final model the building's — or, with ``finding``, the
    model it refitted with that effect, accepted or not (an engineer who knows the building has
    it; the held-out day still decides what is served); NotFoundError for another building's or
    an unknown diagnosis, ModelError when it has nothing to adopt. The building's row is locked:
    two adoptions at once on PostgreSQL both read "not adopted" and both said they changed the
    model."""
    building = repository.lock_building(session, building_id)
    diagnosis = session.get(DiagnosisRecord, diagnosis_id)
    if diagnosis is None or diagnosis.building_id != building_id:
        raise NotFoundError(f"diagnosis {diagnosis_id} not found for building {building_id}")
    current = spec_of(building)
    detail = None if finding is None else {"finding": finding}
    if _adopted_from(current) == (diagnosis_id, finding):
        record = _audit(session, building_id, ADOPT, actor, current, diagnosis_id, detail=detail)
        return Change(record, current)
    description = bridge.building_of(building.description)
    spec = ModelSpec.from_report(
        diagnosis.report, description, diagnosis_id=diagnosis_id, finding=finding
    )
    if spec.needs_record:  # the ground's annual cycle, fitted once to the diagnosed record
        frame = bridge.load_frame(
            session,
            building_id,
            pd.Timestamp(diagnosis.window_start),
            pd.Timestamp(diagnosis.window_end),
        )
        spec = spec.with_fixed_signals(frame, description)
    building.model_spec = _document(spec)
    if finding is not None:
        detail = {"finding": finding, "accepted_by_the_diagnosis": spec.source["accepted"]}
    record = _audit(session, building_id, ADOPT, actor, spec, diagnosis_id, True, detail)
    return Change(record, spec)


def revert(session: Session, building_id: int, actor: str) -> Change:
    """Back to the base model; the last base-model set served before is served again (the
    building's row locked, as for ``adopt``)."""
    building = repository.lock_building(session, building_id)
    if building.model_spec is None:
        return Change(_audit(session, building_id, REVERT, actor, None), None)
    building.model_spec = None
    restored = _restore_base_set(session, building_id)
    detail = {"restored_parameter_set_id": restored}
    record = _audit(session, building_id, REVERT, actor, None, changed=True, detail=detail)
    return Change(record, None)


def calibrate_now(
    runner: JobRunner, building_id: int, change: Change, follow_up: bool = False
) -> None:
    """The first calibration of the model a change put in use, started at once, and recorded
    with the change (or why none could start: one is already running, no measured data).
    ``follow_up``: started after a calibration that fitted the model before the change."""
    if not change.record.changed:
        return
    settings = runner.settings
    model = job_model(change.spec, settings.model)
    job_id, note = None, None
    try:
        job = runner.create_calibration(
            building_id, model, settings.training_days, change.record.action
        )
        job_id = job.id
    except ConflictError as exc:
        note = f"not started: {exc}; the next calibration fits the new model"
    with runner.db.write() as session:
        record = session.get(ModelChangeRecord, change.record.id)
        if record is None:
            return
        record.calibration_job_id = job_id
        if note is None and follow_up:
            note = "started when the calibration running at the change had ended"
        if note is not None:
            record.detail = {**(record.detail or {}), "calibration": note}


def after_diagnosis(runner: JobRunner, job_id: int, done: Future) -> None:
    """RCSERVICE_AUTO_ADOPT: adopt a diagnosis that accepted findings as soon as it succeeds,
    and calibrate (a done-callback of the diagnosis's run: it never raises)."""
    if done.cancelled() or done.exception() is not None:
        return
    try:
        with runner.db.session() as session:
            job = repository.get_job(session, job_id)
        if job.status != SUCCEEDED or not (job.details or {}).get("accepted"):
            return
        with runner.db.write() as session:
            change = adopt(session, job.building_id, job.diagnosis_id, AUTO)
        calibrate_now(runner, job.building_id, change)
    except (RCEngineError, ServiceError) as exc:
        log.warning("automatic adoption failed", extra={"job_id": job_id, "error": str(exc)})
    except Exception:  # a callback's error would vanish; the diagnosis itself succeeded
        log.exception("automatic adoption failed", extra={"job_id": job_id})


def after_calibrations(runner: JobRunner, job_ids: list[int]) -> None:
    """Calibrations that fitted a model the building no longer uses — adopted or reverted while
    they ran, when the change could not start its own calibration (one was running) — are
    followed at once by the first calibration of the model in use; else the change waited for
    the next night. Called when the calibrations have ended; it never raises."""
    try:
        for job_id in job_ids:
            with runner.db.session() as session:
                job = repository.get_job(session, job_id)
                if job.status != SUCCEEDED or not (job.details or {}).get("model_changed"):
                    continue
                change = latest_change(session, job.building_id)
                spec = spec_of(repository.get_building(session, job.building_id))
            if change is not None:
                calibrate_now(runner, job.building_id, Change(change, spec), follow_up=True)
    except (RCEngineError, ServiceError) as exc:
        log.warning("no follow-up calibration", extra={"job_ids": job_ids, "error": str(exc)})
    except Exception:  # a callback's error would vanish; the calibrations themselves ended
        log.exception("no follow-up calibration", extra={"job_ids": job_ids})


def history(session: Session, building_id: int) -> list[ModelChangeRecord]:
    """Every adopt and revert call of a building, oldest first."""
    query = (
        select(ModelChangeRecord)
        .where(ModelChangeRecord.building_id == building_id)
        .order_by(ModelChangeRecord.id)
    )
    return list(session.scalars(query))


def latest_change(session: Session, building_id: int) -> ModelChangeRecord | None:
    """The last call that changed the model."""
    query = (
        select(ModelChangeRecord)
        .where(ModelChangeRecord.building_id == building_id, ModelChangeRecord.changed)
        .order_by(ModelChangeRecord.id.desc())
    )
    return session.scalars(query).first()


def in_use(session: Session, building: BuildingRecord) -> dict:
    """What ``GET /buildings/{id}`` says of the model the building's calibrations fit, and of
    the last call that changed it."""
    spec_document, change = building.model_spec, latest_change(session, building.id)
    since = {"since": None, "by": None}
    if change is not None:
        since = {"since": change.created_at, "by": change.actor}
    if spec_document is None:
        return {"name": None, "source": "base", "effects": [], "diagnosis_id": None, **since}
    try:
        spec = ModelSpec.from_dict(spec_document)
    except RCEngineError as exc:  # written by another engine: said, and the building still read
        source = spec_document.get("source") or {}
        return {
            "name": spec_document.get("name"),
            "source": source.get("kind", "diagnosis"),
            "effects": list(spec_document.get("effects") or []),
            "diagnosis_id": source.get("diagnosis_id"),
            "error": f"{exc}; revert, or adopt the diagnosis again",
            **since,
        }
    return {
        "name": spec.name,
        "source": spec.source.get("kind", "diagnosis"),
        "base_model": spec.base_model,
        "effects": list(spec.effects),
        "diagnosis_id": spec.source.get("diagnosis_id"),
        "required_columns": spec.required_columns,
        **since,
    }


def _document(spec: ModelSpec) -> dict[str, Any]:
    # Strict JSON, as parameter documents are stored: PostgreSQL refuses NaN.
    return json.loads(json.dumps(jsonable(spec.to_dict()), allow_nan=False))


def _audit(
    session: Session,
    building_id: int,
    action: str,
    actor: str,
    spec: ModelSpec | None,
    diagnosis_id: int | None = None,
    changed: bool = False,
    detail: dict[str, Any] | None = None,
) -> ModelChangeRecord:
    record = ModelChangeRecord(
        building_id=building_id,
        action=action,
        diagnosis_id=diagnosis_id,
        model=None if spec is None else spec.name[:200],
        actor=actor,
        changed=changed,
        detail=detail,
    )
    session.add(record)
    session.flush()
    return record


def _restore_base_set(session: Session, building_id: int) -> int | None:
    """Serve again the latest base-model set that was once current, if the current set was
    fitted with an adopted model; returns the id now current by this, else None."""
    current = repository.current_parameter_set(session, building_id)
    if current is None or current.model in MODELS:
        return None
    query = (
        select(ParameterSetRecord)
        .where(
            ParameterSetRecord.building_id == building_id,
            ParameterSetRecord.status == SUPERSEDED,
            ParameterSetRecord.model.in_(list(MODELS)),
        )
        .order_by(ParameterSetRecord.id.desc())
    )
    previous = session.scalars(query).first()
    if previous is None:
        return None
    session.execute(
        update(ParameterSetRecord)
        .where(ParameterSetRecord.id == current.id)
        .values(is_current=False, status=SUPERSEDED)
    )
    session.flush()
    previous.is_current, previous.status = True, CURRENT
    session.flush()
    return previous.id
