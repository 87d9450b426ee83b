"""The dashboard in process (TestClient): sign-in, session cookie, CSRF, who sees what, and the
pages' content. The browser tests are in ``test_dashboard_browser.py``."""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from fastapi.testclient import TestClient

from service.ui.sessions import COOKIE, SIGNIN_COOKIE
from service.ui.views import gaps

from .conftest import ADMIN, ADMIN_TOKEN, SYNTHETIC_BUILDING, register, wait_for_job

CSRF = re.compile(r'name="csrf" value="([^"]*)"')


def form_token(html: str) -> str:
    return CSRF.search(html).group(1)


def sign_in(client: TestClient, token: str):
    page = client.get("/ui/login")
    assert page.status_code == 200
    return client.post(
        "/ui/login", data={"token": token, "csrf": form_token(page.text)}, follow_redirects=False
    )


@pytest.fixture
def token_of(client):
    """Registers a building: its id and its token (the token itself, to sign in with)."""

    def register_with_token() -> tuple[int, str]:
        response = client.post("/buildings", json=SYNTHETIC_BUILDING, headers=ADMIN)
        return response.json()["id"], response.json()["token"]

    return register_with_token


def test_pages_need_a_session(client):
    for path in ("/ui", "/ui/fleet", "/ui/buildings/1", "/ui/buildings/1/diagnosis"):
        response = client.get(path, follow_redirects=False)
        assert (response.status_code, response.headers["location"]) == (303, "/ui/login"), path
    assert client.post("/ui/buildings/1/calibrations", follow_redirects=False).status_code == 303


def test_sign_in_sets_a_strict_http_only_cookie_and_keeps_the_token_out_of_urls(client):
    response = sign_in(client, ADMIN_TOKEN)
    assert (response.status_code, response.headers["location"]) == (303, "/ui")
    cookie = next(c for c in response.headers.get_list("set-cookie") if c.startswith(COOKIE))
    assert "HttpOnly" in cookie and "SameSite=strict" in cookie and "Path=/ui" in cookie
    assert ADMIN_TOKEN not in "".join(response.headers.values())
    fleet = client.get("/ui", follow_redirects=True)
    assert fleet.status_code == 200 and str(fleet.url).endswith("/ui/fleet")
    assert ADMIN_TOKEN not in fleet.text and ADMIN_TOKEN not in str(fleet.url)
    assert "script-src 'self'" in fleet.headers["content-security-policy"]


def test_sign_in_refuses_a_wrong_token_and_a_form_without_its_csrf_token(client):
    assert sign_in(client, "not-a-token-" * 3).status_code == 401
    client.get("/ui/login")
    forged = client.post("/ui/login", data={"token": ADMIN_TOKEN, "csrf": "forged"})
    assert forged.status_code == 403
    # Not ASCII: a str compare_digest raised TypeError (a 500) before the texts went as bytes.
    assert client.post("/ui/login", data={"token": ADMIN_TOKEN, "csrf": "é"}).status_code == 403
    client.cookies.delete(SIGNIN_COOKIE, path="/ui")
    assert client.post("/ui/login", data={"token": ADMIN_TOKEN, "csrf": ""}).status_code == 403
    assert client.get("/ui/fleet", follow_redirects=False).status_code == 303


def test_a_building_token_sees_only_its_building(client, token_of):
    own, token = token_of()
    other, _ = token_of()
    assert sign_in(client, token).status_code == 303
    assert client.get("/ui", follow_redirects=False).headers["location"] == f"/ui/buildings/{own}"
    assert client.get("/ui/fleet", follow_redirects=False).headers["location"] == (
        f"/ui/buildings/{own}"
    )
    assert client.get(f"/ui/buildings/{own}").status_code == 200
    denied = client.get(f"/ui/buildings/{other}")
    assert denied.status_code == 404 and "not found" in denied.text
    assert client.get(f"/ui/buildings/{other}/diagnosis").status_code == 404
    page = client.get(f"/ui/buildings/{own}")
    started = client.post(
        f"/ui/buildings/{other}/calibrations", data={"csrf": form_token(page.text)}
    )
    assert started.status_code == 404
    assert client.get(f"/buildings/{other}/calibrations", headers=ADMIN).json()["items"] == []


def test_forms_need_the_session_csrf_token(client, measured):
    building_id, _ = measured
    sign_in(client, ADMIN_TOKEN)
    refused = client.post(f"/ui/buildings/{building_id}/calibrations", data={"csrf": "x"})
    assert refused.status_code == 403
    jobs = client.get(f"/buildings/{building_id}/calibrations", headers=ADMIN).json()
    assert jobs["items"] == []
    assert client.post("/ui/logout", data={"csrf": "x"}).status_code == 403
    assert client.post("/ui/logout", data={"csrf": "é"}).status_code == 403


def test_building_page_shows_data_model_jobs_and_starts_a_calibration(client, measured):
    building_id, headers = measured
    sign_in(client, ADMIN_TOKEN)
    page = client.get(f"/ui/buildings/{building_id}")
    assert page.status_code == 200
    assert "no parameter set yet" in page.text and 'id="chart-json"' in page.text
    started = client.post(
        f"/ui/buildings/{building_id}/calibrations",
        data={"csrf": form_token(page.text)},
        follow_redirects=False,
    )
    assert started.headers["location"] == f"/ui/buildings/{building_id}#jobs"
    job = client.get(f"/buildings/{building_id}/calibrations", headers=headers).json()["items"][0]
    assert job["trigger"] == "dashboard"
    assert wait_for_job(client, job["id"], headers)["outcome"] == "promoted"
    assert client.get(f"/ui/buildings/{building_id}/jobs").json() == {"active": []}
    page = client.get(f"/ui/buildings/{building_id}")
    assert f"calibration job {job['id']} queued" in page.text  # the flash, shown once
    assert "queued" not in client.get(f"/ui/buildings/{building_id}").text.split("<h1>")[0]
    charts = re.search(r'id="chart-json">(.*?)</script>', page.text, re.S).group(1)
    assert re.search(r'"predicted": \{"x": \[\d+', charts) and '"std": [' in charts
    fleet = client.get("/ui/fleet").text
    assert "promoted" in fleet and "stale data" in fleet
    assert f'data-building="{building_id}"' in fleet


def test_rotating_a_building_token_ends_its_sessions(client, token_of):
    building_id, token = token_of()
    sign_in(client, token)
    assert client.get(f"/ui/buildings/{building_id}").status_code == 200
    client.post(f"/buildings/{building_id}/token", headers=ADMIN)
    assert client.get(f"/ui/buildings/{building_id}", follow_redirects=False).status_code == 303


def test_a_diagnosis_without_data_is_refused_with_a_message(client):
    building_id, _ = register(client)
    sign_in(client, ADMIN_TOKEN)
    page = client.get(f"/ui/buildings/{building_id}")
    assert "no measured t_in stored yet" in page.text
    answer = client.post(
        f"/ui/buildings/{building_id}/diagnoses", data={"csrf": form_token(page.text)}
    )
    assert answer.status_code == 200 and "not started:" in answer.text


def test_static_files_and_plotly_come_from_the_service(client):
    assert client.get("/ui/static/dashboard.js").status_code == 200
    plotly = client.get("/ui/vendor/plotly.min.js")
    assert plotly.status_code == 200 and "plotly" in plotly.text[:2000].lower()


def test_gaps_are_missing_rows_and_unmeasured_rows_before_the_last_measured_one():
    times = pd.date_range("2017-01-09", periods=96, freq="15min", tz="UTC")
    t_in = np.full(96, 20.0)
    t_in[10:14] = np.nan  # an hour without t_in
    t_in[90:] = np.nan  # future rows: inputs only, not a gap
    kept = np.r_[0:40, 48:96]  # two hours without rows
    row = SimpleNamespace(step_s=900.0, last_measured_time=times[89], timezone="UTC")
    found = gaps(times[kept], t_in[kept], row)
    assert [(g["kind"], g["steps"], g["start"]) for g in found] == [
        ("no rows", 8, "2017-01-09 10:00 +0000"),
        ("no t_in", 4, "2017-01-09 02:30 +0000"),
    ]


def test_the_diagnosis_button_queues_a_diagnosis_of_the_building(client, measured, monkeypatch):
    building_id, headers = measured
    runner = client.app.state.context.runner
    monkeypatch.setattr(runner, "submit", lambda *args: None)  # queued, not run: the form's job
    sign_in(client, ADMIN_TOKEN)
    page = client.get(f"/ui/buildings/{building_id}")
    answer = client.post(
        f"/ui/buildings/{building_id}/diagnoses", data={"csrf": form_token(page.text)}
    )
    jobs = client.get(f"/buildings/{building_id}/diagnoses", headers=headers).json()["items"]
    assert [(j["status"], j["trigger"]) for j in jobs] == [("queued", "dashboard")]
    assert f"diagnosis job {jobs[0]['id']} queued" in answer.text
    assert 'data-active="true"' in answer.text  # the page polls until the job ends
