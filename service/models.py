"""Database tables (SQLAlchemy 2). Alembic owns the schema: a change here needs a migration.

Measurements are one row per (building, time) with the contract columns of
:mod:`rcengine.columns`, clustered on that key so that a forecast reads one short range.
Times are stored in UTC (:class:`UTCDateTime`), whatever the database.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any, ClassVar

from sqlalchemy import (
    JSON,
    Column,
    DateTime,
    Float,
    ForeignKey,
    Index,
    Integer,
    String,
    Table,
    Text,
    text,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column
from sqlalchemy.sql.elements import TextClause
from sqlalchemy.types import TypeDecorator

from rcengine.columns import NUMERIC_COLUMNS, TIME

# Job life cycle (CONTRACT.md §4) and what a finished calibration did with its result.
QUEUED, RUNNING, SUCCEEDED, FAILED = "queued", "running", "succeeded", "failed"
ACTIVE_JOB_STATUSES = (QUEUED, RUNNING)
PROMOTED, REJECTED = "promoted", "rejected"
# What a job does: re-estimate the parameters, or diagnose the model-data mismatch.
CALIBRATION, DIAGNOSIS = "calibration", "diagnosis"
# Where a building's jobs of each kind are started and listed: /buildings/{id}/<collection>.
JOB_COLLECTIONS = {CALIBRATION: "calibrations", DIAGNOSIS: "diagnoses"}
# Parameter-set status: the one in use, one it replaced, or one that lost on the held-out day.
CURRENT, SUPERSEDED = "current", "superseded"


def utc_now() -> datetime:
    return datetime.now(UTC)


class UTCDateTime(TypeDecorator):
    """Timezone-aware datetimes in, UTC datetimes out, on SQLite (naive text) and PostgreSQL."""

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_bind_param(self, value: datetime | None, dialect: Any) -> datetime | None:
        if value is None:
            return None
        if value.tzinfo is None:
            raise ValueError(f"naive datetime {value!r}: the service stores UTC instants only")
        return value.astimezone(UTC)

    def process_result_value(self, value: datetime | None, dialect: Any) -> datetime | None:
        if value is None:
            return None
        return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


# --- shared with the migrations: what they create depends on these, so they stay as they are --
def partial(where: str) -> dict[str, TextClause]:
    """The keywords of an index over the rows where ``where`` holds, on SQLite and PostgreSQL."""
    condition = text(where)
    return {"sqlite_where": condition, "postgresql_where": condition}


def reference(name: str, target: str, ondelete: str) -> Column:
    """An integer foreign key to ``target``; nullable exactly when the row outlives its target
    (SET NULL), required when it is deleted with it (CASCADE)."""
    return Column(
        name, Integer(), ForeignKey(target, ondelete=ondelete), nullable=ondelete == "SET NULL"
    )


def unique_where(name: str, *columns: str, where: str) -> Index:
    """A unique index over the rows where ``where`` holds."""
    return Index(name, *columns, unique=True, **partial(where))


class Base(DeclarativeBase):
    type_annotation_map: ClassVar[dict[Any, Any]] = {
        datetime: UTCDateTime,
        float: Float,
        dict[str, Any]: JSON,
    }


class BuildingRecord(Base):
    """A registered building: its §2 description, token hash and time grid."""

    __tablename__ = "buildings"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    description: Mapped[dict[str, Any]]
    timezone: Mapped[str] = mapped_column(String(64))
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    # Step and one time of the stored series: later uploads must lie on the same grid. [s]
    step_s: Mapped[float | None]
    grid_origin: Mapped[datetime | None]
    # Latest time with a measured t_in: a forecast starts one step after it by default.
    last_measured_at: Mapped[datetime | None]
    # Incremented by every upload; forecasts are cached per revision, jobs record the one fitted.
    data_revision: Mapped[int] = mapped_column(Integer, default=0)
    created_at: Mapped[datetime] = mapped_column(default=utc_now)
    # The adopted model (rcengine.models.spec.ModelSpec document) every calibration fits; None:
    # the base model of the service's settings or of the calibration request.
    model_spec: Mapped[dict[str, Any] | None] = mapped_column(JSON)


measurements = Table(
    "measurements",
    Base.metadata,
    Column(
        "building_id",
        Integer,
        ForeignKey("buildings.id", ondelete="CASCADE"),
        primary_key=True,
    ),
    Column(TIME, UTCDateTime, primary_key=True),
    *(Column(name, Float, nullable=True) for name in NUMERIC_COLUMNS),
    sqlite_with_rowid=False,
)


class JobRecord(Base):
    """A calibration or a diagnosis: queued → running → succeeded | failed; a calibration's
    ``outcome`` says whether its set was promoted. ``days``: days fitted (calibration) or days
    diagnosed; ``options``: what a diagnosis was asked (window, train fraction, effects)."""

    __tablename__ = "jobs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    building_id: Mapped[int] = mapped_column(ForeignKey("buildings.id", ondelete="CASCADE"))
    kind: Mapped[str] = mapped_column(String(16), default=CALIBRATION, server_default=CALIBRATION)
    status: Mapped[str] = mapped_column(String(16), default=QUEUED)
    outcome: Mapped[str | None] = mapped_column(String(16))
    trigger: Mapped[str] = mapped_column(String(16))
    model: Mapped[str] = mapped_column(Text)
    days: Mapped[int] = mapped_column(Integer)
    data_revision: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(default=utc_now)
    started_at: Mapped[datetime | None]
    finished_at: Mapped[datetime | None]
    error: Mapped[str | None] = mapped_column(Text)
    details: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    options: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    # The lease of the run that holds the job (see service.jobs): who runs it, the fencing
    # token every write of that run must still match, its last heartbeat and expiry.
    lease_owner: Mapped[str | None] = mapped_column(String(64))
    lease_token: Mapped[int] = mapped_column(Integer, default=0, server_default="0")
    heartbeat_at: Mapped[datetime | None]
    lease_expires_at: Mapped[datetime | None]

    @property
    def parameter_set_id(self) -> int | None:
        """The set a succeeded calibration stored."""
        return (self.details or {}).get("parameter_set_id")

    @property
    def diagnosis_id(self) -> int | None:
        """The report a succeeded diagnosis stored."""
        return (self.details or {}).get("diagnosis_id")

    __table_args__ = (
        # At most one queued or running job of each kind per building, enforced by the database.
        unique_where(
            "uq_jobs_active_building_kind",
            "building_id",
            "kind",
            where="status IN ('queued', 'running')",
        ),
        Index("ix_jobs_building_created", "building_id", "created_at"),
    )


class JobProduct:
    """Columns of what a job stores for a building: a parameter set, a diagnosis report."""

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    building_id: Mapped[int] = mapped_column(ForeignKey("buildings.id", ondelete="CASCADE"))
    job_id: Mapped[int | None] = mapped_column(ForeignKey("jobs.id", ondelete="SET NULL"))
    model: Mapped[str] = mapped_column(Text)
    engine_version: Mapped[str] = mapped_column(String(32))
    created_at: Mapped[datetime] = mapped_column(default=utc_now)


class ParameterSetRecord(JobProduct, Base):
    """A fitted parameter set: the full ``params.json`` document plus searchable summaries."""

    __tablename__ = "parameter_sets"

    status: Mapped[str] = mapped_column(String(16))
    is_current: Mapped[bool] = mapped_column(default=False)
    reason: Mapped[str | None] = mapped_column(Text)
    train_start: Mapped[datetime]
    train_end: Mapped[datetime]
    rmse_train: Mapped[float | None]
    rmse_holdout: Mapped[float | None]
    metrics: Mapped[dict[str, Any]]
    document: Mapped[dict[str, Any]]

    @property
    def parameters(self) -> dict[str, Any]:
        """Value, unit, bounds and description of each parameter (from the document)."""
        return self.document["parameters"]

    __table_args__ = (
        unique_where("uq_parameter_sets_current_building", "building_id", where="is_current"),
        Index("ix_parameter_sets_building_created", "building_id", "created_at"),
    )


class DiagnosisRecord(JobProduct, Base):
    """A finished diagnosis: the CONTRACT.md §3 report, its HTML page and what was diagnosed."""

    __tablename__ = "diagnoses"

    # First and one-past-last time of the rows diagnosed.
    window_start: Mapped[datetime]
    window_end: Mapped[datetime]
    # The engine settings of the run: preset, random_state, train_fraction, effects.
    settings: Mapped[dict[str, Any]]
    report: Mapped[dict[str, Any]]
    # Hundreds of kB: loaded only when the HTML page is asked for.
    html: Mapped[str] = mapped_column(Text, deferred=True)

    __table_args__ = (Index("ix_diagnoses_building_created", "building_id", "created_at"),)


class ModelChangeRecord(Base):
    """One adopt or revert call (audit): who made it (admin, building token or the automatic
    adoption), when, which diagnosis, the model in use after it, whether it changed anything,
    and the calibration it started."""

    __tablename__ = "model_changes"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    building_id: Mapped[int] = mapped_column(ForeignKey("buildings.id", ondelete="CASCADE"))
    action: Mapped[str] = mapped_column(String(16))
    diagnosis_id: Mapped[int | None] = mapped_column(
        ForeignKey("diagnoses.id", ondelete="SET NULL")
    )
    model: Mapped[str | None] = mapped_column(Text)
    actor: Mapped[str] = mapped_column(String(32))
    changed: Mapped[bool] = mapped_column(default=False)
    calibration_job_id: Mapped[int | None] = mapped_column(
        ForeignKey("jobs.id", ondelete="SET NULL")
    )
    detail: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    created_at: Mapped[datetime] = mapped_column(default=utc_now)

    __table_args__ = (Index("ix_model_changes_building", "building_id", "id"),)


class AdminTokenRecord(Base):
    """Hash of the generated admin token (one row); unused when RCSERVICE_ADMIN_TOKEN is set."""

    __tablename__ = "admin_tokens"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    token_hash: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[datetime] = mapped_column(default=utc_now)
