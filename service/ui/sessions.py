"""Dashboard sessions: a random session id in an ``HttpOnly``, ``SameSite=Strict`` cookie, the
signed-in token's hash and a CSRF token kept server-side.

The bearer token is sent once, in the sign-in form's body, and never stored: the session keeps
its SHA-256 hash, which is checked again on every request, so a rotated building token or a new
admin token ends the sessions it opened. Sessions live in the server process (one process
serves the dashboard); a restart signs everyone out, which is the safe failure.
"""

from __future__ import annotations

import secrets
import threading
import time
from dataclasses import dataclass, field

from ..core.security import same_hash

COOKIE = "rc_session"
# Double-submit cookie of the sign-in form, before any session exists.
SIGNIN_COOKIE = "rc_signin"
# Sessions end this long after sign-in. [s]
SESSION_TTL_S = 8 * 3600.0
MAX_SESSIONS = 10_000


@dataclass
class Session:
    """Who signed in (``building_id`` None: the admin) and the CSRF token of their forms."""

    token_hash: str
    building_id: int | None
    expires: float
    csrf: str = field(default_factory=lambda: secrets.token_urlsafe(32))
    flash: str | None = None

    def csrf_ok(self, submitted: str | None) -> bool:
        return submitted is not None and same_hash(submitted, self.csrf)


class SessionStore:
    """Sessions by id; expired ones are dropped when met or when the store is full."""

    def __init__(self, ttl_s: float = SESSION_TTL_S):
        self._ttl_s = ttl_s
        self._sessions: dict[str, Session] = {}
        self._lock = threading.Lock()

    def open(self, token_hash: str, building_id: int | None) -> tuple[str, Session]:
        session_id = secrets.token_urlsafe(32)
        session = Session(token_hash, building_id, time.monotonic() + self._ttl_s)
        with self._lock:
            if len(self._sessions) >= MAX_SESSIONS:
                self._drop_expired()
            self._sessions[session_id] = session
        return session_id, session

    def get(self, session_id: str | None) -> Session | None:
        if not session_id:
            return None
        session = self._sessions.get(session_id)
        if session is not None and session.expires < time.monotonic():
            self.close(session_id)
            return None
        return session

    def close(self, session_id: str | None) -> None:
        with self._lock:
            self._sessions.pop(session_id or "", None)

    def _drop_expired(self) -> None:
        now = time.monotonic()
        for key in [k for k, s in self._sessions.items() if s.expires < now]:
            del self._sessions[key]
