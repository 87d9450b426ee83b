"""Diagnoses: job kinds (one active job per building and kind), the diagnosis reports table.

Existing jobs become calibrations. Downgrading deletes the diagnosis jobs and reports.

Create Date: 2026-11-29
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from service.models import UTCDateTime, partial, reference

revision: str = "0002"
down_revision: str | None = "0001"

_ACTIVE = "status IN ('queued', 'running')"


def upgrade() -> None:
    op.add_column(
        "jobs",
        sa.Column("kind", sa.String(16), nullable=False, server_default="calibration"),
    )
    op.add_column("jobs", sa.Column("options", sa.JSON(), nullable=True))
    op.drop_index("uq_jobs_active_building", table_name="jobs")
    op.create_index(
        "uq_jobs_active_building_kind",
        "jobs",
        ["building_id", "kind"],
        unique=True,
        **partial(_ACTIVE),
    )
    op.create_table(
        "diagnoses",
        sa.Column("id", sa.Integer(), primary_key=True),
        reference("building_id", "buildings.id", "CASCADE"),
        reference("job_id", "jobs.id", "SET NULL"),
        sa.Column("model", sa.String(100), nullable=False),
        sa.Column("window_start", UTCDateTime(), nullable=False),
        sa.Column("window_end", UTCDateTime(), nullable=False),
        sa.Column("settings", sa.JSON(), nullable=False),
        sa.Column("report", sa.JSON(), nullable=False),
        sa.Column("html", sa.Text(), nullable=False),
        sa.Column("engine_version", sa.String(32), nullable=False),
        sa.Column("created_at", UTCDateTime(), nullable=False),
    )
    op.create_index("ix_diagnoses_building_created", "diagnoses", ["building_id", "created_at"])


def downgrade() -> None:
    op.drop_index("ix_diagnoses_building_created", table_name="diagnoses")
    op.drop_table("diagnoses")
    op.execute(sa.text("DELETE FROM jobs WHERE kind = 'diagnosis'"))
    op.drop_index("uq_jobs_active_building_kind", table_name="jobs")
    op.create_index(
        "uq_jobs_active_building", "jobs", ["building_id"], unique=True, **partial(_ACTIVE)
    )
    # Plain ALTER TABLE … DROP COLUMN (SQLite ≥ 3.35): a batch copy of the table would fire
    # the ON DELETE SET NULL of parameter_sets.job_id when the old table is dropped.
    op.drop_column("jobs", "options")
    op.drop_column("jobs", "kind")
