"""Alembic environment.

The service runs ``upgrade head`` at start-up with its own connection
(``service.core.db.Database.migrate``). From the command line (``alembic upgrade head``,
``alembic revision --autogenerate -m ...``, using ``alembic.ini``) the URL comes from
``RCSERVICE_DATABASE_URL`` like the service's.
"""

from __future__ import annotations

from logging.config import fileConfig

from alembic import context
from sqlalchemy import Connection, create_engine

from service.core.config import Settings
from service.models import Base

config = context.config
if config.config_file_name is not None:  # the command line; the service keeps its own logging
    fileConfig(config.config_file_name)
target_metadata = Base.metadata


def _url() -> str:
    return config.get_main_option("sqlalchemy.url") or Settings().database_url


def _run(connection: Connection) -> None:
    # SQLite cannot ALTER most things in place; batch mode rebuilds tables when needed.
    context.configure(
        connection=connection,
        target_metadata=target_metadata,
        render_as_batch=connection.dialect.name == "sqlite",
    )
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_offline() -> None:
    context.configure(url=_url(), target_metadata=target_metadata, literal_binds=True)
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    connection = config.attributes.get("connection")
    if connection is not None:
        _run(connection)
        return
    engine = create_engine(_url())
    with engine.begin() as own:
        _run(own)
    engine.dispose()


if context.is_offline_mode():
    run_migrations_offline()
else:
    run_migrations_online()
