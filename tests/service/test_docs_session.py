"""The curl session of docs/service.md, run as written against a live server (issue 13, defect 9:
the documented forecast call failed because the session never uploaded the future rows)."""

from __future__ import annotations

import pytest

from .conftest import run_docs_session


@pytest.mark.slow
def test_the_documented_curl_session_runs_against_a_live_server(tmp_path):
    run, log = run_docs_session(
        tmp_path,
        "A session with `curl`",
        RCSERVICE_DIAGNOSIS_PRESET="modestpy",
        RCSERVICE_DIAGNOSIS_DAYS="56",
    )
    assert run.returncode == 0, f"{run.stdout[-2000:]}\n{run.stderr[-2000:]}\n{log}"
    assert '"status":"succeeded"' in run.stdout and '"t_in_pred":[' in run.stdout
    assert (tmp_path / "diagnosis.html").read_text().lstrip().lower().startswith("<!doctype html")
