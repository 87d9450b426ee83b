"""Every database query of the service, on a caller's session (SQLite and PostgreSQL alike).

Functions take a :class:`~sqlalchemy.orm.Session` and neither commit nor open transactions:
callers choose ``Database.session()`` (reads) or ``Database.write()`` (one write transaction);
the Core-only query of the forecast hot path also runs on ``Database.connect()``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any

from sqlalchemy import (
    Connection,
    Insert,
    Row,
    Select,
    String,
    and_,
    cast,
    delete,
    func,
    select,
    update,
)
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from rcengine.columns import T_IN, TIME

from .errors import ConflictError, LeaseLostError, NotFoundError
from .models import (
    ACTIVE_JOB_STATUSES,
    CALIBRATION,
    CURRENT,
    FAILED,
    QUEUED,
    REJECTED,
    RUNNING,
    SUPERSEDED,
    AdminTokenRecord,
    BuildingRecord,
    DiagnosisRecord,
    JobRecord,
    ParameterSetRecord,
    measurements,
    utc_now,
)

_INSERT = {"sqlite": sqlite.insert, "postgresql": postgresql.insert}


@dataclass(frozen=True)
class Lease:
    """A run's hold on a job: the job, who runs it, and the fencing token of the run."""

    job_id: int
    owner: str
    token: int

    def __str__(self) -> str:
        return f"{self.token} of {self.owner!r}"


# --- buildings --------------------------------------------------------------------------------
def add_building(
    session: Session, name: str, description: dict[str, Any], timezone: str, token_hash: str
) -> BuildingRecord:
    record = BuildingRecord(
        name=name,
        description=description,
        timezone=timezone,
        token_hash=token_hash,
        data_revision=0,
    )
    session.add(record)
    session.flush()
    return record


def get_building(session: Session, building_id: int) -> BuildingRecord:
    record = session.get(BuildingRecord, building_id)
    if record is None:
        raise NotFoundError(f"building {building_id} not found")
    return record


def lock_building(session: Session, building_id: int) -> BuildingRecord:
    """The building, its row locked until the transaction ends (``SELECT … FOR UPDATE`` on
    PostgreSQL; SQLite's write transactions hold the database's write lock already): writers of
    one building's data run one after another."""
    record = session.scalar(
        select(BuildingRecord).where(BuildingRecord.id == building_id).with_for_update()
    )
    if record is None:
        raise NotFoundError(f"building {building_id} not found")
    return record


def next_data_revision(session: Session, building_id: int) -> int:
    """Increment the building's ``data_revision`` in the database (one atomic statement, no
    read-then-write) and return the new value."""
    return session.scalar(
        update(BuildingRecord)
        .where(BuildingRecord.id == building_id)
        .values(data_revision=BuildingRecord.data_revision + 1)
        .returning(BuildingRecord.data_revision)
    )


def building_summary(session: Session, building_id: int) -> Row:
    """A building's columns and what it stores (see :func:`building_summaries`)."""
    row = session.execute(_summaries().where(BuildingRecord.id == building_id)).first()
    if row is None:
        raise NotFoundError(f"building {building_id} not found")
    return row


def building_summaries(session: Session) -> Sequence[Row]:
    """Every building by id: id, name, timezone, description, created_at, step_s,
    last_measured_time, data_revision, and its stored rows (count, first_time, last_time) and
    current_parameter_set_id, in one query."""
    return session.execute(_summaries().order_by(BuildingRecord.id)).all()


def _summaries() -> Select:
    time = measurements.c[TIME]

    def stored(aggregate: Any) -> Any:  # over the building's rows (index range of its key)
        return select(aggregate).where(measurements.c.building_id == BuildingRecord.id)

    return select(
        BuildingRecord.id,
        BuildingRecord.name,
        BuildingRecord.timezone,
        BuildingRecord.description,
        BuildingRecord.created_at,
        BuildingRecord.step_s,
        BuildingRecord.last_measured_at.label("last_measured_time"),
        BuildingRecord.data_revision,
        stored(func.count()).scalar_subquery().label("rows"),
        stored(func.min(time)).scalar_subquery().label("first_time"),
        stored(func.max(time)).scalar_subquery().label("last_time"),
        ParameterSetRecord.id.label("current_parameter_set_id"),
    ).outerjoin(
        ParameterSetRecord,
        and_(ParameterSetRecord.building_id == BuildingRecord.id, ParameterSetRecord.is_current),
    )


def building_id_for_token(session: Session, token_hash: str) -> int | None:
    return session.scalar(select(BuildingRecord.id).where(BuildingRecord.token_hash == token_hash))


def set_token_hash(session: Session, building_id: int, token_hash: str) -> None:
    get_building(session, building_id).token_hash = token_hash


# --- measurements -----------------------------------------------------------------------------
def existing_times(
    session: Session, building_id: int, start: datetime, end: datetime
) -> set[datetime]:
    """Stored times of a building in [start, end]."""
    time = measurements.c[TIME]
    query = select(time).where(
        measurements.c.building_id == building_id, time >= start, time <= end
    )
    return set(session.scalars(query))


def stored_times(session: Session, building_id: int) -> list[datetime]:
    """Every stored time of a building, in order (for a series whose step is not known yet)."""
    time = measurements.c[TIME]
    query = select(time).where(measurements.c.building_id == building_id).order_by(time)
    return list(session.scalars(query))


def delete_measurements(session: Session, building_id: int, start: datetime, end: datetime) -> int:
    """Remove a building's rows with start ≤ time < end; returns how many."""
    time = measurements.c[TIME]
    query = delete(measurements).where(
        measurements.c.building_id == building_id, time >= start, time < end
    )
    return session.execute(query).rowcount


def has_measurements(session: Session, building_id: int) -> bool:
    """Whether the building stores any row at all (measured or weather only)."""
    query = select(measurements.c.building_id).where(measurements.c.building_id == building_id)
    return session.scalar(select(query.exists())) is True


def last_measured_time(session: Session, building_id: int) -> datetime | None:
    """The latest stored time with a measured t_in."""
    query = select(func.max(measurements.c[TIME])).where(
        measurements.c.building_id == building_id, measurements.c[T_IN].is_not(None)
    )
    return session.scalar(query)


def upsert_measurements(
    session: Session, building_id: int, columns: Sequence[str], rows: list[dict[str, Any]]
) -> None:
    """Insert rows, or update the stored row at the same time (see :func:`upsert_statement`)."""
    statement = upsert_statement(session.get_bind().dialect.name, columns)
    # A list of parameters runs as the driver's executemany: one statement compiled, rows bound
    # in C (a multi-row VALUES clause would compile one bound parameter per cell).
    session.execute(statement, [{"building_id": building_id, **row} for row in rows])


def upsert_statement(dialect: str, columns: Sequence[str]) -> Insert:
    """``INSERT … ON CONFLICT (building_id, time) DO UPDATE`` writing only ``columns``; on
    update an empty value (NULL) keeps the stored one, so a re-uploaded forecast row never
    erases a measured ``t_in``."""
    statement = _INSERT[dialect](measurements)
    return statement.on_conflict_do_update(
        index_elements=["building_id", TIME],
        set_={c: func.coalesce(statement.excluded[c], measurements.c[c]) for c in columns},
    )


def read_measurements(
    session: Session,
    building_id: int,
    columns: Sequence[str],
    start: datetime | None = None,
    end: datetime | None = None,
) -> Sequence[Row]:
    """(time, *columns) rows of a building with start ≤ time < end, in time order."""
    time = measurements.c[TIME]
    query = select(time, *(measurements.c[c] for c in columns)).where(
        measurements.c.building_id == building_id
    )
    if start is not None:
        query = query.where(time >= start)
    if end is not None:
        query = query.where(time < end)
    return session.execute(query.order_by(time)).all()


def read_series(
    session: Session, building_id: int, columns: Sequence[str], start: datetime
) -> Sequence[Row]:
    """(time as text, *columns) rows of a building from ``start`` on, in time order: a long
    series for display, whose times ``pandas.to_datetime(..., utc=True)`` parses at once (the
    per-row datetime conversion of :func:`read_measurements` costs ~20 µs a row). The text is
    UTC on SQLite (stored naive) and carries its offset on PostgreSQL."""
    time = measurements.c[TIME]
    query = select(cast(time, String), *(measurements.c[c] for c in columns)).where(
        measurements.c.building_id == building_id, time >= start
    )
    return session.execute(query.order_by(time)).all()


# --- jobs -------------------------------------------------------------------------------------
def add_job(
    session: Session,
    building_id: int,
    trigger: str,
    model: str,
    days: int,
    kind: str = CALIBRATION,
    options: dict[str, Any] | None = None,
) -> JobRecord:
    """A queued job; ConflictError when the building already has one of this kind queued or
    running."""
    _refuse_a_second(session, building_id, kind)
    building = get_building(session, building_id)
    job = JobRecord(
        building_id=building_id,
        kind=kind,
        status=QUEUED,
        trigger=trigger,
        model=model,
        days=days,
        data_revision=building.data_revision,
        options=options,
    )
    try:
        with session.begin_nested():
            session.add(job)
    except IntegrityError as exc:  # another process queued one between the check and now
        _refuse_a_second(session, building_id, kind)
        raise ConflictError(f"building {building_id} already has an active {kind}") from exc
    return job


def _refuse_a_second(session: Session, building_id: int, kind: str) -> None:
    """ConflictError naming the building's active job of ``kind`` (queued or running), if any."""
    active = active_job(session, building_id, kind)
    if active is not None:
        raise ConflictError(
            f"building {building_id} already has {kind} job {active.id} {active.status}; "
            f"poll GET /jobs/{active.id}"
        )


def active_job(session: Session, building_id: int, kind: str = CALIBRATION) -> JobRecord | None:
    query = select(JobRecord).where(
        JobRecord.building_id == building_id,
        JobRecord.kind == kind,
        JobRecord.status.in_(ACTIVE_JOB_STATUSES),
    )
    return session.scalars(query).first()


def get_job(session: Session, job_id: int) -> JobRecord:
    job = session.get(JobRecord, job_id)
    if job is None:
        raise NotFoundError(f"job {job_id} not found")
    return job


def list_jobs(
    session: Session, building_id: int, limit: int, kind: str = CALIBRATION
) -> Sequence[JobRecord]:
    query = (
        select(JobRecord)
        .where(JobRecord.building_id == building_id, JobRecord.kind == kind)
        .order_by(JobRecord.id.desc())
        .limit(limit)
    )
    return session.scalars(query).all()


def start_job(session: Session, job_id: int, owner: str = "", lease_s: float = 0.0) -> Lease:
    """Mark a queued job running under a new lease of ``owner`` for ``lease_s``; ConflictError
    if it is not queued. The job's fencing token is incremented: every later write of this run
    must present it (:func:`renew_lease`, :func:`finish_job`)."""
    now = utc_now()
    token = session.scalar(
        update(JobRecord)
        .where(JobRecord.id == job_id, JobRecord.status == QUEUED)
        .values(
            status=RUNNING,
            started_at=now,
            lease_owner=owner,
            lease_token=JobRecord.lease_token + 1,
            heartbeat_at=now,
            lease_expires_at=now + timedelta(seconds=lease_s),
        )
        .returning(JobRecord.lease_token)
    )
    if token is None:
        raise ConflictError(f"job {job_id} is {get_job(session, job_id).status}, not queued")
    return Lease(job_id, owner, token)


def claim_next_job(
    session: Session, kind: str, owner: str, lease_s: float, building_ids: Sequence[int] = ()
) -> Lease | None:
    """Start the oldest queued job of ``kind`` (of ``building_ids`` if given) under a lease of
    ``owner``; None when none is left. Several processes claim from one queue: PostgreSQL skips
    the rows another transaction is claiming (``FOR UPDATE SKIP LOCKED``) instead of waiting for
    them; SQLite's write transaction holds the database's write lock already."""
    query = select(JobRecord.id).where(JobRecord.status == QUEUED, JobRecord.kind == kind)
    if building_ids:
        query = query.where(JobRecord.building_id.in_(building_ids))
    job_id = session.scalar(query.order_by(JobRecord.id).limit(1).with_for_update(skip_locked=True))
    return None if job_id is None else start_job(session, job_id, owner, lease_s)


def renew_lease(session: Session, lease: Lease, lease_s: float) -> bool:
    """Heartbeat: extend the lease by ``lease_s`` from now; False if it was taken over."""
    now = utc_now()
    renewed = session.execute(
        _held(update(JobRecord), lease).values(
            heartbeat_at=now, lease_expires_at=now + timedelta(seconds=lease_s)
        )
    )
    return renewed.rowcount == 1


def finish_job(
    session: Session,
    job_id: int,
    status: str,
    *,
    outcome: str | None = None,
    error: str | None = None,
    details: dict[str, Any] | None = None,
    lease: Lease | None = None,
    model: str | None = None,
) -> None:
    """End a job; with ``lease``, only if that lease still holds it (LeaseLostError, and the
    caller's transaction must roll back, if not); without, only if it is still active. The
    fencing token is incremented, so that no earlier lease can write again. ``model``: the
    model the job ended up fitting, where it differs from the one it was queued with (a
    diagnosis adopted while it waited)."""
    query = update(JobRecord).where(JobRecord.id == job_id)
    query = _held(query, lease) if lease else query.where(JobRecord.status.in_(ACTIVE_JOB_STATUSES))
    values: dict[str, Any] = {
        "status": status,
        "outcome": outcome,
        "error": error,
        "details": details,
        "finished_at": utc_now(),
        "lease_token": JobRecord.lease_token + 1,
        "lease_expires_at": None,
    }
    if model is not None:
        values["model"] = model
    ended = session.execute(query.values(**values))
    if ended.rowcount != 1:
        job = get_job(session, job_id)
        raise LeaseLostError(
            f"job {job_id} is {job.status} under lease {job.lease_token} of "
            f"{job.lease_owner!r}; this run's lease ({lease}) no longer holds it"
        )


def _held(query: Any, lease: Lease) -> Any:
    return query.where(
        JobRecord.id == lease.job_id,
        JobRecord.status == RUNNING,
        JobRecord.lease_token == lease.token,
    )


def fail_abandoned_jobs(session: Session, reason: str, queued_too: bool = False) -> list[int]:
    """Fail running jobs whose lease expired (their process is gone), and queued ones too when
    ``queued_too`` (at start-up: the process that queued them is gone); ids of the jobs failed.
    Their fencing token moves on, so a late write of the dead run is refused."""
    abandoned = (JobRecord.status == RUNNING) & (JobRecord.lease_expires_at < utc_now())
    if queued_too:
        abandoned = abandoned | (JobRecord.status == QUEUED)
    ids = list(
        session.scalars(
            update(JobRecord)
            .where(abandoned)
            .values(
                status=FAILED,
                error=reason,
                finished_at=utc_now(),
                lease_token=JobRecord.lease_token + 1,
                lease_expires_at=None,
            )
            .returning(JobRecord.id)
        )
    )
    return sorted(ids)


def buildings_with_new_data(
    session: Session, unless_error: str | None = None, among: Sequence[int] = ()
) -> list[int]:
    """Buildings (``among`` these if given) whose data changed since their last calibration job
    (or that never had one); a job that failed with ``unless_error`` (interrupted: its process
    died) does not count."""
    fitted = select(JobRecord.building_id, func.max(JobRecord.data_revision).label("revision"))
    fitted = fitted.where(JobRecord.kind == CALIBRATION)
    if among:
        fitted = fitted.where(JobRecord.building_id.in_(among))
    if unless_error is not None:
        fitted = fitted.where((JobRecord.error.is_(None)) | (JobRecord.error != unless_error))
    last_job = fitted.group_by(JobRecord.building_id).subquery()
    query = (
        select(BuildingRecord.id)
        .outerjoin(last_job, last_job.c.building_id == BuildingRecord.id)
        .where(
            BuildingRecord.data_revision > 0,
            (last_job.c.revision.is_(None)) | (BuildingRecord.data_revision > last_job.c.revision),
        )
        .order_by(BuildingRecord.id)
    )
    if among:
        query = query.where(BuildingRecord.id.in_(among))
    return list(session.scalars(query))


# --- parameter sets ---------------------------------------------------------------------------
def current_parameter_set(session: Session, building_id: int) -> ParameterSetRecord | None:
    query = select(ParameterSetRecord).where(
        ParameterSetRecord.building_id == building_id, ParameterSetRecord.is_current
    )
    return session.scalars(query).first()


def get_parameter_set(session: Session, building_id: int, set_id: int) -> ParameterSetRecord:
    record = session.get(ParameterSetRecord, set_id)
    if record is None or record.building_id != building_id:
        raise NotFoundError(f"parameter set {set_id} not found for building {building_id}")
    return record


def list_parameter_sets(session: Session, building_id: int) -> Sequence[ParameterSetRecord]:
    query = (
        select(ParameterSetRecord)
        .where(ParameterSetRecord.building_id == building_id)
        .order_by(ParameterSetRecord.id.desc())
    )
    return session.scalars(query).all()


def add_parameter_set(
    session: Session, record: ParameterSetRecord, promote: bool
) -> ParameterSetRecord:
    """Store a fitted set; when promoted it becomes current and the previous one superseded."""
    if promote:
        session.execute(
            update(ParameterSetRecord)
            .where(
                ParameterSetRecord.building_id == record.building_id,
                ParameterSetRecord.is_current,
            )
            .values(is_current=False, status=SUPERSEDED)
        )
    record.is_current, record.status = promote, CURRENT if promote else REJECTED
    session.add(record)
    session.flush()
    return record


def forecast_key(session: Session | Connection, building_id: int) -> Row:
    """(data_revision, set_id, timezone, step_s, last_measured_at) of a building in one query;
    ``set_id`` is the current parameter set's, or None."""
    query = (
        select(
            BuildingRecord.data_revision,
            ParameterSetRecord.id.label("set_id"),
            BuildingRecord.timezone,
            BuildingRecord.step_s,
            BuildingRecord.last_measured_at,
        )
        .outerjoin(
            ParameterSetRecord,
            and_(
                ParameterSetRecord.building_id == BuildingRecord.id,
                ParameterSetRecord.is_current,
            ),
        )
        .where(BuildingRecord.id == building_id)
    )
    row = session.execute(query).first()
    if row is None:
        raise NotFoundError(f"building {building_id} not found")
    return row


# --- diagnoses --------------------------------------------------------------------------------
def add_diagnosis(session: Session, record: DiagnosisRecord) -> DiagnosisRecord:
    session.add(record)
    session.flush()
    return record


def latest_diagnosis(session: Session, building_id: int) -> DiagnosisRecord | None:
    query = (
        select(DiagnosisRecord)
        .where(DiagnosisRecord.building_id == building_id)
        .order_by(DiagnosisRecord.id.desc())
    )
    return session.scalars(query).first()


# --- admin token ------------------------------------------------------------------------------
def stored_admin_token_hash(session: Session) -> str | None:
    query = select(AdminTokenRecord.token_hash).order_by(AdminTokenRecord.id.desc())
    return session.scalars(query).first()


def replace_admin_token_hash(session: Session, token_hash: str) -> None:
    for record in session.scalars(select(AdminTokenRecord)):
        session.delete(record)
    session.add(AdminTokenRecord(token_hash=token_hash))
