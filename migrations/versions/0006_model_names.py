"""Model names of any length: an extended model's name grows with each effect it adopts.

The jobs, parameter sets, diagnoses and audit rows held it in VARCHAR(100) or (200); PostgreSQL
refuses a longer value, so a calibration of a model with several long effects fitted its set
and then failed to store it. SQLite does not enforce a VARCHAR length, and altering a column
there means copying the table (which would fire the ON DELETE of the tables referencing it), so
only other databases are altered.

Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0006"
down_revision: str | None = "0005"

COLUMNS = {"jobs": 100, "parameter_sets": 100, "diagnoses": 100, "model_changes": 200}


def upgrade() -> None:
    if op.get_bind().dialect.name == "sqlite":
        return
    for table, length in COLUMNS.items():
        op.alter_column(table, "model", type_=sa.Text(), existing_type=sa.String(length))


def downgrade() -> None:
    if op.get_bind().dialect.name == "sqlite":
        return
    for table, length in COLUMNS.items():
        op.alter_column(table, "model", type_=sa.String(length), existing_type=sa.Text())
