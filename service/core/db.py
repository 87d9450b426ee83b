"""Database engine, sessions and migrations.

SQLite is tuned for a web service: write-ahead log (readers never wait for the writer), foreign
keys on, a busy timeout, and write transactions that take the write lock when they begin
(``BEGIN IMMEDIATE``). Without the last, a transaction that reads and then writes can fail at
once with "database is locked" when another writer committed in between, instead of waiting.
PostgreSQL gets plain READ COMMITTED transactions: there, writers that read then write lock
the rows they change first (``repository.lock_building``: ``SELECT … FOR UPDATE``, ignored by
SQLite, whose write lock covers the database) and counters move in one statement
(``UPDATE … SET n = n + 1 RETURNING n``), so both databases give the same results.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from alembic import command
from alembic.config import Config
from sqlalchemy import Connection, Engine, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session, sessionmaker

MIGRATIONS_DIR = Path(__file__).resolve().parents[2] / "migrations"
BUSY_TIMEOUT_MS = 30_000
# Option on the write engine read by the SQLite "begin" hook.
_BEGIN_OPTION = "sqlite_begin"


class Database:
    """One engine and its session factories: ``session()`` for reads, ``write()`` for writes."""

    def __init__(self, url: str):
        self.url = url
        self.engine = create_db_engine(url)
        self._reads = sessionmaker(self.engine, expire_on_commit=False)
        self._writes = sessionmaker(
            self.engine.execution_options(**{_BEGIN_OPTION: "IMMEDIATE"}),
            expire_on_commit=False,
        )

    @contextmanager
    def session(self) -> Iterator[Session]:
        """A session for reads (a deferred transaction on SQLite)."""
        with self._reads() as session:
            yield session

    @contextmanager
    def connect(self) -> Iterator[Connection]:
        """A plain connection for one light query on a hot path (no ORM session to set up)."""
        with self.engine.connect() as connection:
            yield connection

    @contextmanager
    def write(self) -> Iterator[Session]:
        """A session whose transaction holds the write lock from its start; commits on exit."""
        with self._writes() as session, session.begin():
            yield session

    def migrate(self) -> None:
        """``alembic upgrade head`` on this database."""
        with self.engine.begin() as connection:
            config = alembic_config(self.url)
            config.attributes["connection"] = connection
            command.upgrade(config, "head")

    def dispose(self) -> None:
        self.engine.dispose()


def alembic_config(url: str) -> Config:
    """Alembic configured from code: the service does not read ``alembic.ini``."""
    config = Config()
    config.set_main_option("script_location", str(MIGRATIONS_DIR))
    config.set_main_option("sqlalchemy.url", url.replace("%", "%%"))
    return config


def create_db_engine(url: str) -> Engine:
    backend = make_url(url).get_backend_name()
    if backend != "sqlite":
        return create_engine(url, pool_size=10, max_overflow=20, pool_pre_ping=True)
    # More connections than request threads (40) plus the event loop: a checkout never waits.
    engine = create_engine(url, pool_size=10, max_overflow=50)
    event.listen(engine, "connect", _sqlite_on_connect)
    event.listen(engine, "begin", _sqlite_begin)
    return engine


def _sqlite_on_connect(dbapi_connection: Any, _record: Any) -> None:
    # The driver's own implicit BEGIN would defeat BEGIN IMMEDIATE; SQLAlchemy's "begin" hook
    # below issues every BEGIN instead (SQLAlchemy docs, "Serializable isolation / Savepoints").
    dbapi_connection.isolation_level = None
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")
    cursor.close()


def _sqlite_begin(connection: Any) -> None:
    mode = connection.get_execution_options().get(_BEGIN_OPTION, "DEFERRED")
    connection.exec_driver_sql(f"BEGIN {mode}")
