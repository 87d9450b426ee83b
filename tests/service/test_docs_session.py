"""The curl session of docs/service.md, run as written against a live server (issue 13, defect 9:
the documented forecast call failed because the session never uploaded the future rows)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import LiveServer

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "service.md"


def session_block() -> str:
    """The first bash block after "A session with `curl`"."""
    text = DOCS.read_text()
    after = text[text.index("A session with `curl`") :]
    return re.search(r"```bash\n(.*?)```", after, re.DOTALL).group(1)


@pytest.mark.slow
def test_the_documented_curl_session_runs_against_a_live_server(tmp_path):
    (tmp_path / "data").symlink_to(ROOT / "data")
    # No admin token given: the server generates one into rcservice-admin-token beside its
    # database, as for `make run`; the session reads it from there.
    env = {"RCSERVICE_DIAGNOSIS_PRESET": "modestpy", "RCSERVICE_DIAGNOSIS_DAYS": "56"}
    server = LiveServer(tmp_path, **env)
    server.env.pop("RCSERVICE_ADMIN_TOKEN")
    server.start()
    try:
        script = "set -euo pipefail\n" + session_block().replace("localhost:8000", server.url)
        run = subprocess.run(
            ["bash", "-c", script],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=600,
            env={**os.environ, "PATH": f"{Path(sys.executable).parent}:{os.environ['PATH']}"},
        )
    finally:
        server.stop()
    assert run.returncode == 0, f"{run.stdout[-2000:]}\n{run.stderr[-2000:]}\n{server.log()}"
    assert '"status":"succeeded"' in run.stdout and '"t_in_pred":[' in run.stdout
    assert (tmp_path / "diagnosis.html").read_text().lstrip().lower().startswith("<!doctype html")
