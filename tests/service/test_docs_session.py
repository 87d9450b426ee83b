"""The curl session of docs/service.md, run as written against a live server (issue 13, defect 9:
the documented forecast call failed because the session never uploaded the future rows)."""

from __future__ import annotations

import pytest

from .conftest import run_docs_session


@pytest.mark.slow
def test_the_documented_curl_session_runs_against_a_live_server(tmp_path):
    out = run_docs_session(tmp_path, "A session with `curl`", RCSERVICE_DIAGNOSIS_DAYS="56")
    assert '"status":"succeeded"' in out and '"t_in_pred":[' in out
    assert (tmp_path / "diagnosis.html").read_text().lstrip().lower().startswith("<!doctype html")
