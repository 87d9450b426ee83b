"""Tokens in the database: the admin token's hash (from the settings, stored, or generated at
first start) and the building each token hash reaches, remembered for a while."""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

from . import repository
from .core.config import Settings
from .core.db import Database
from .core.security import hash_token, new_token, write_secret

log = logging.getLogger(__name__)


def admin_token_hash(settings: Settings, db: Database) -> str:
    """Hash of the admin token: from the settings, else the stored one, else a new one.

    A new token is printed once and written to ``settings.token_file()`` (mode 0600); only its
    hash is stored.
    """
    if settings.admin_token is not None:
        log.info("admin token: taken from RCSERVICE_ADMIN_TOKEN")
        return hash_token(settings.admin_token.get_secret_value())
    with db.write() as session:
        stored = repository.stored_admin_token_hash(session)
        if stored is not None:
            _log_where(settings.token_file())
            return stored
        token = new_token()
        # The file first, the hash then, in the same transaction: stored before a write that
        # failed, the hash left a token nobody had (the next start found it and printed none).
        path = settings.token_file()
        write_secret(path, token)
        repository.replace_admin_token_hash(session, hash_token(token))
    print(f"rcservice: generated admin token {token}\n  (also written to {path})", flush=True)
    log.info("admin token generated", extra={"token_file": str(path)})
    return hash_token(token)


def reset_admin_token(settings: Settings, db: Database) -> tuple[str, Path]:
    """Replace the stored admin token by a new one; returns it and the file it was written to."""
    token = new_token()
    path = settings.token_file()
    # Written before the hash is replaced: a file that cannot be written leaves the old token
    # working, not a new one nobody has.
    write_secret(path, token)
    with db.write() as session:
        repository.replace_admin_token_hash(session, hash_token(token))
    return token, path


def _log_where(path: Path) -> None:
    if path.exists():
        log.info(
            "admin token: in %s (written at first start)", path, extra={"token_file": str(path)}
        )
    else:
        log.info(
            "admin token: printed at first start; `rcservice reset-admin-token` makes a new one"
        )


class TokenIndex:
    """Building of each token hash, remembered for ``ttl_s`` after a database lookup.

    Saves a query on every request; a rotated token stops working here at once and, in other
    server processes sharing the database, within ``ttl_s``.
    """

    def __init__(self, db: Database, ttl_s: float = 60.0):
        self._db = db
        self._ttl_s = ttl_s
        self._known: dict[str, tuple[int, float]] = {}
        self._lock = threading.Lock()

    def building_for(self, token_hash: str) -> int | None:
        now = time.monotonic()
        found = self._known.get(token_hash)
        if found is not None and found[1] > now:
            return found[0]
        with self._db.session() as session:
            building_id = repository.building_id_for_token(session, token_hash)
        with self._lock:
            if building_id is None:
                self._known.pop(token_hash, None)
            else:
                self._known[token_hash] = (building_id, now + self._ttl_s)
        return building_id

    def forget(self, building_id: int) -> None:
        with self._lock:
            for key in [k for k, (b, _) in self._known.items() if b == building_id]:
                del self._known[key]
