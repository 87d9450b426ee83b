"""Initial schema: buildings, measurements, jobs, parameter sets, admin token.

Create Date: 2026-11-22
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from rcengine.columns import DHI, DNI, GHI, Q_HVAC, Q_LIGHT, Q_OCC, T_IN, T_OUT, TIME, WIND_SPEED
from service.models import UTCDateTime, partial, reference

revision: str = "0001"
down_revision: str | None = None

# The contract columns as of this revision (a later contract column needs a new migration).
_MEASURED = (T_IN, T_OUT, GHI, Q_HVAC, DNI, DHI, Q_OCC, Q_LIGHT, WIND_SPEED)
_ACTIVE = "status IN ('queued', 'running')"


def upgrade() -> None:
    op.create_table(
        "buildings",
        sa.Column("id", sa.Integer(), primary_key=True),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("description", sa.JSON(), nullable=False),
        sa.Column("timezone", sa.String(64), nullable=False),
        sa.Column("token_hash", sa.String(64), nullable=False, unique=True),
        sa.Column("step_s", sa.Float(), nullable=True),
        sa.Column("grid_origin", UTCDateTime(), nullable=True),
        sa.Column("last_measured_at", UTCDateTime(), nullable=True),
        sa.Column("data_revision", sa.Integer(), nullable=False),
        sa.Column("created_at", UTCDateTime(), nullable=False),
    )
    op.create_table(
        "measurements",
        sa.Column(
            "building_id",
            sa.Integer(),
            sa.ForeignKey("buildings.id", ondelete="CASCADE"),
            primary_key=True,
        ),
        sa.Column(TIME, UTCDateTime(), primary_key=True),
        *(sa.Column(name, sa.Float(), nullable=True) for name in _MEASURED),
        sqlite_with_rowid=False,
    )
    op.create_table(
        "jobs",
        sa.Column("id", sa.Integer(), primary_key=True),
        reference("building_id", "buildings.id", "CASCADE"),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("outcome", sa.String(16), nullable=True),
        sa.Column("trigger", sa.String(16), nullable=False),
        sa.Column("model", sa.String(100), nullable=False),
        sa.Column("days", sa.Integer(), nullable=False),
        sa.Column("data_revision", sa.Integer(), nullable=False),
        sa.Column("created_at", UTCDateTime(), nullable=False),
        sa.Column("started_at", UTCDateTime(), nullable=True),
        sa.Column("finished_at", UTCDateTime(), nullable=True),
        sa.Column("error", sa.Text(), nullable=True),
        sa.Column("details", sa.JSON(), nullable=True),
    )
    op.create_index(
        "uq_jobs_active_building", "jobs", ["building_id"], unique=True, **partial(_ACTIVE)
    )
    op.create_index("ix_jobs_building_created", "jobs", ["building_id", "created_at"])
    op.create_table(
        "parameter_sets",
        sa.Column("id", sa.Integer(), primary_key=True),
        reference("building_id", "buildings.id", "CASCADE"),
        reference("job_id", "jobs.id", "SET NULL"),
        sa.Column("model", sa.String(100), nullable=False),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("is_current", sa.Boolean(), nullable=False),
        sa.Column("reason", sa.Text(), nullable=True),
        sa.Column("train_start", UTCDateTime(), nullable=False),
        sa.Column("train_end", UTCDateTime(), nullable=False),
        sa.Column("rmse_train", sa.Float(), nullable=True),
        sa.Column("rmse_holdout", sa.Float(), nullable=True),
        sa.Column("metrics", sa.JSON(), nullable=False),
        sa.Column("engine_version", sa.String(32), nullable=False),
        sa.Column("document", sa.JSON(), nullable=False),
        sa.Column("created_at", UTCDateTime(), nullable=False),
    )
    op.create_index(
        "uq_parameter_sets_current_building",
        "parameter_sets",
        ["building_id"],
        unique=True,
        **partial("is_current"),
    )
    op.create_index(
        "ix_parameter_sets_building_created", "parameter_sets", ["building_id", "created_at"]
    )
    op.create_table(
        "admin_tokens",
        sa.Column("id", sa.Integer(), primary_key=True),
        sa.Column("token_hash", sa.String(64), nullable=False),
        sa.Column("created_at", UTCDateTime(), nullable=False),
    )


def downgrade() -> None:
    op.drop_table("admin_tokens")
    op.drop_index("ix_parameter_sets_building_created", table_name="parameter_sets")
    op.drop_index("uq_parameter_sets_current_building", table_name="parameter_sets")
    op.drop_table("parameter_sets")
    op.drop_index("ix_jobs_building_created", table_name="jobs")
    op.drop_index("uq_jobs_active_building", table_name="jobs")
    op.drop_table("jobs")
    op.drop_table("measurements")
    op.drop_table("buildings")
