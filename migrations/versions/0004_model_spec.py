"""Adopted models: the building's model specification and the audit of adopt / revert calls.

Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from service.models import UTCDateTime, reference

revision: str = "0004"
down_revision: str | None = "0003"


def upgrade() -> None:
    op.add_column("buildings", sa.Column("model_spec", sa.JSON(), nullable=True))
    op.create_table(
        "model_changes",
        sa.Column("id", sa.Integer(), primary_key=True),
        reference("building_id", "buildings.id", "CASCADE"),
        sa.Column("action", sa.String(16), nullable=False),
        reference("diagnosis_id", "diagnoses.id", "SET NULL"),
        sa.Column("model", sa.String(200), nullable=True),
        sa.Column("actor", sa.String(32), nullable=False),
        sa.Column("changed", sa.Boolean(), nullable=False),
        reference("calibration_job_id", "jobs.id", "SET NULL"),
        sa.Column("detail", sa.JSON(), nullable=True),
        sa.Column("created_at", UTCDateTime(), nullable=False),
    )
    op.create_index("ix_model_changes_building", "model_changes", ["building_id", "id"])


def downgrade() -> None:
    op.drop_index("ix_model_changes_building", table_name="model_changes")
    op.drop_table("model_changes")
    # Plain DROP COLUMN (SQLite >= 3.35): a batch copy would fire the ON DELETE of the tables
    # that reference buildings.
    op.drop_column("buildings", "model_spec")
