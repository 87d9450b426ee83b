"""Writing result files whole or not at all, and saying in one line why a file could not be."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all: into a temporary file beside it, then
    renamed over it. Written in place, a full disk or a killed process left half a file where
    the previous good one had been."""
    target = Path(path)
    fd, temporary = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def file_error(exc: OSError) -> str:
    """An operating-system error in one line: the file and the reason (a full disk, a missing
    folder, no permission), for a command line to print instead of a traceback."""
    return f"{exc.filename or 'a file'}: {exc.strerror or exc}"
