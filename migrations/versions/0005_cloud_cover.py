"""The contract's optional cloud_cover column (the sky's long-wave from measured cloudiness).

Create Date: 2026-11-27
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from rcengine.columns import CLOUD_COVER

revision: str = "0005"
down_revision: str | None = "0004"


def upgrade() -> None:
    op.add_column("measurements", sa.Column(CLOUD_COVER, sa.Float(), nullable=True))


def downgrade() -> None:
    op.drop_column("measurements", CLOUD_COVER)
