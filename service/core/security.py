"""Bearer tokens: random, shown once, stored only as SHA-256 hashes.

A token has 32 random bytes (256 bits), so a fast unsalted hash is enough: there is no
dictionary to attack, and a stolen hash cannot be turned back into the token.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
from pathlib import Path

TOKEN_BYTES = 32


def new_token() -> str:
    """A random URL-safe token (43 characters)."""
    return secrets.token_urlsafe(TOKEN_BYTES)


def hash_token(token: str) -> str:
    """SHA-256 hex digest of a token: what the database keeps."""
    return hashlib.sha256(token.encode()).hexdigest()


def same_hash(a: str, b: str) -> bool:
    """Constant-time equality of two texts. As bytes: ``compare_digest`` refuses str with
    non-ASCII characters (a TypeError, a 500, for a form field sent as "é")."""
    return hmac.compare_digest(a.encode(), b.encode())


def write_secret(path: Path, secret: str) -> None:
    """Write ``secret`` to a file only its owner can read."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as handle:
        handle.write(secret + "\n")
    os.chmod(path, 0o600)
