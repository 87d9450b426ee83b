"""Job leases: the owner, fencing token, heartbeat and expiry of the run holding a job.

Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from service.models import UTCDateTime

revision: str = "0003"
down_revision: str | None = "0002"


def upgrade() -> None:
    op.add_column("jobs", sa.Column("lease_owner", sa.String(64), nullable=True))
    op.add_column(
        "jobs", sa.Column("lease_token", sa.Integer(), nullable=False, server_default="0")
    )
    op.add_column("jobs", sa.Column("heartbeat_at", UTCDateTime(), nullable=True))
    op.add_column("jobs", sa.Column("lease_expires_at", UTCDateTime(), nullable=True))


def downgrade() -> None:
    # Plain DROP COLUMN (SQLite >= 3.35): a batch copy would fire parameter_sets' ON DELETE.
    for name in ("lease_expires_at", "heartbeat_at", "lease_token", "lease_owner"):
        op.drop_column("jobs", name)
