"""A real PostgreSQL server for the tests: the ``pgserver`` wheel (PostgreSQL binaries inside a
pip package, in the ``dev`` extra), started once per test session in a temporary folder and
reached on its Unix socket only (it listens on no TCP address); one fresh database per test.
"""

from __future__ import annotations

import itertools
import os
import shutil
import tempfile
from pathlib import Path

import psycopg

_names = itertools.count(1)


def _ensure_runtime_dir() -> None:
    """pgserver keeps its lock in the user's runtime directory; a shell without a login session
    (CI, containers) has no XDG_RUNTIME_DIR, and platformdirs then warns and falls back to
    /tmp/runtime-<uid>. That same folder is named here, private to the user as the spec asks."""
    if os.environ.get("XDG_RUNTIME_DIR"):
        return
    folder = Path(tempfile.gettempdir()) / f"runtime-{os.getuid()}"
    folder.mkdir(mode=0o700, exist_ok=True)
    folder.chmod(0o700)  # the fallback may have made it earlier with the default mode
    os.environ["XDG_RUNTIME_DIR"] = str(folder)


class PostgresServer:
    """The session's server; ``create()`` a new empty database, ``drop()`` it again."""

    def __init__(self) -> None:
        _ensure_runtime_dir()
        import pgserver  # imported here: only the tests that ask for PostgreSQL pay for it

        self.folder = Path(tempfile.mkdtemp(prefix="rcservice-pg-"))
        self._server = pgserver.get_server(self.folder / "data", cleanup_mode="delete")
        self.socket_dir = self._server.get_postmaster_info().socket_dir
        self.pid = self._server.get_pid()

    def url(self, database: str) -> str:
        """SQLAlchemy URL (driver psycopg 3) of ``database`` on the server's socket."""
        return f"postgresql+psycopg://postgres@/{database}?host={self.socket_dir}"

    def create(self) -> str:
        name = f"rc_test_{next(_names)}"
        self._admin(f'CREATE DATABASE "{name}"')
        return name

    def drop(self, name: str) -> None:
        self._admin(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')

    def _admin(self, statement: str) -> None:
        with psycopg.connect(
            dbname="postgres", user="postgres", host=str(self.socket_dir), autocommit=True
        ) as connection:
            connection.execute(statement)

    def stop(self) -> None:
        self._server.cleanup()
        # cleanup() deletes the data folder, not the temporary folder made for it.
        shutil.rmtree(self.folder, ignore_errors=True)
