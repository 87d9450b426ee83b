"""Mismatch diagnosis from the service: token rules, the job and its report (JSON and HTML), the
window a job diagnoses, failures that keep the earlier report, one active diagnosis per building,
and the migration that adds them.

Data: the first two weeks of the project's EnergyPlus variant with unmetered internal gains
(data/energyplus/variants/unmetered_gains). One real diagnosis runs (fast preset, one candidate
effect, both chosen through the service's settings and the request body); the other jobs replace
the engine call with a fake so that they test the service, not the engine.
"""

from __future__ import annotations

import json
import threading
from pathlib import Path

import pandas as pd
import pytest
from alembic import command
from fastapi.testclient import TestClient
from sqlalchemy import inspect, text

from rcengine.io.timeseries import format_times, read_timeseries
from service import diagnosis
from service.core.db import Database

from .conftest import (
    ADMIN,
    bearer,
    json_rows,
    migrate,
    module_client,
    register,
    schema_revision,
    wait_for_job,
)

DAYS = 14
STEP = pd.Timedelta(minutes=15)
EFFECTS = ["unmetered_gains"]
JOB_TIMEOUT_S = 300.0


@pytest.fixture(scope="module")
def variant(project_data: Path) -> tuple[dict, pd.DataFrame]:
    folder = project_data / "energyplus" / "variants" / "unmetered_gains"
    building = json.loads((folder / "building.json").read_text())
    frame = read_timeseries(folder / "data.csv").iloc[: DAYS * 96]
    return building, frame


# One app for the module; diagnoses with the fast "modestpy" preset and 14 days.
client = module_client(
    "diagnosis", preset="modestpy", diagnosis_preset="modestpy", diagnosis_days=DAYS
)


def measured_building(client: TestClient, variant) -> tuple[int, dict]:
    description, frame = variant
    building_id, headers = register(client, description)
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(frame)}, headers=headers
    )
    assert response.status_code == 200, response.text
    return building_id, headers


def start(client: TestClient, building_id: int, headers: dict, **body) -> dict:
    response = client.post(f"/buildings/{building_id}/diagnoses", json=body, headers=headers)
    assert response.status_code == 202, response.text
    assert response.headers["location"] == f"/jobs/{response.json()['id']}"
    return response.json()


def diagnose(client: TestClient, building_id: int, headers: dict, **body) -> dict:
    job = start(client, building_id, headers, **body)
    return wait_for_job(client, job["id"], headers, timeout_s=JOB_TIMEOUT_S)


@pytest.fixture(scope="module")
def diagnosed(client, variant) -> tuple[int, dict, dict]:
    """A building with one real diagnosis: its id, headers and finished job."""
    building_id, headers = measured_building(client, variant)
    job = diagnose(client, building_id, headers, effects=EFFECTS)
    assert job["status"] == "succeeded", job["error"]
    return building_id, headers, job


def report(client, building_id, headers, **params):
    return client.get(f"/buildings/{building_id}/diagnosis", params=params, headers=headers)


def fake_report() -> dict:
    """The contract's fields and a few more, as an engine could add them."""
    return {
        "baseline": {
            "model": "basic",
            "rmse_train": 0.25,
            "rmse_test": 0.3,
            "parameters": {"c_air": 1.0e6},
        },
        "mismatch": {"summary": "under-predicts on weekday afternoons", "test": {"bias": -0.1}},
        "findings": [
            {
                "effect": "unmetered_gains",
                "accepted": True,
                "explanation": "internal gains on a weekly schedule",
                "rmse_test_before": 0.3,
                "rmse_test_after": 0.2,
                "delta_bic": -40.0,
            }
        ],
        "final": {"model": "basic+unmetered_gains", "rmse_train": 0.2, "rmse_test": 0.2},
        "verdict": "missing physics found: unmetered_gains",
    }


# --- the real diagnosis -----------------------------------------------------------------------
def test_job_produces_a_report_with_the_contract_fields(client, variant, diagnosed):
    building_id, headers, job = diagnosed
    response = report(client, building_id, headers)
    assert response.status_code == 200
    body = response.json()
    assert (body["id"], body["job_id"]) == (job["diagnosis_id"], job["id"])
    assert body["baseline"]["model"] == "basic"
    before, after = body["baseline"]["rmse_test"], body["final"]["rmse_test"]
    assert 0.0 < body["baseline"]["rmse_train"] < 5.0 and 0.0 < before < 5.0
    assert isinstance(body["mismatch"]["summary"], str) and body["mismatch"]["summary"]
    # Only the effects asked for are tested; an extension is kept only if it helps the test.
    assert [f["effect"] for f in body["findings"]] == EFFECTS
    accepted = [f["effect"] for f in body["findings"] if f["accepted"]]
    assert after <= before
    assert body["final"]["model"] == "+".join(["basic", *accepted])
    assert job["details"]["accepted"] == accepted
    assert job["details"]["rmse_test"] == {"baseline": before, "final": after}
    # The window is the whole upload: diagnosis_days covers it exactly.
    description, frame = variant
    tz = description["location"]["timezone"]
    first, end = format_times(pd.DatetimeIndex([frame.index[0], frame.index[-1] + STEP]), tz)
    assert body["window"] == {"start": first, "end": end, "train_fraction": 0.5}
    assert body["settings"]["preset"] == "modestpy" and body["settings"]["effects"] == EFFECTS
    assert (job["kind"], job["model"], job["days"]) == ("diagnosis", "basic", DAYS)


def test_html_report_by_format_or_accept(client, diagnosed):
    building_id, headers, _ = diagnosed
    page = report(client, building_id, headers, format="html")
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    assert page.text.lstrip().lower().startswith("<!doctype html")
    assert "unmetered_gains" in page.text
    by_accept = client.get(
        f"/buildings/{building_id}/diagnosis", headers={**headers, "Accept": "text/html"}
    )
    assert by_accept.text == page.text
    forced_json = client.get(
        f"/buildings/{building_id}/diagnosis",
        params={"format": "json"},
        headers={**headers, "Accept": "text/html"},
    )
    assert forced_json.headers["content-type"] == "application/json"
    assert forced_json.json()["baseline"]["model"] == "basic"


def test_failed_diagnosis_is_recorded_and_keeps_the_earlier_report(client, diagnosed, monkeypatch):
    building_id, headers, first = diagnosed
    earlier = report(client, building_id, headers).json()

    def broken(*args, **kwargs):
        raise RuntimeError("injected failure")

    monkeypatch.setattr(diagnosis, "diagnose_frame", broken)
    job = diagnose(client, building_id, headers, effects=EFFECTS)
    assert (job["status"], job["error"]) == ("failed", "RuntimeError: injected failure")
    assert job["diagnosis_id"] is None
    assert report(client, building_id, headers).json() == earlier
    jobs = client.get(f"/buildings/{building_id}/diagnoses", headers=headers).json()["items"]
    assert [(j["id"], j["status"]) for j in jobs[:2]] == [
        (job["id"], "failed"),
        (first["id"], "succeeded"),
    ]


def test_a_stuck_sensor_fails_the_diagnosis_with_its_reason(client, variant):
    description, frame = variant
    building_id, headers = measured_building(client, (description, frame.assign(t_in=21.0)))
    job = diagnose(client, building_id, headers, effects=EFFECTS)
    assert job["status"] == "failed"
    assert "column 't_in'" in job["error"] and "stuck sensor" in job["error"]
    assert job["diagnosis_id"] is None
    assert report(client, building_id, headers).status_code == 404


# --- the service around the engine -------------------------------------------------------------
def test_no_report_before_a_diagnosis_is_404_with_what_to_do(client, variant):
    building_id, headers = register(client, variant[0])
    response = report(client, building_id, headers)
    assert response.status_code == 404
    assert response.json()["detail"] == (
        f"building {building_id} has no diagnosis report yet; start one with "
        f"POST /buildings/{building_id}/diagnoses"
    )
    assert report(client, building_id, headers, format="html").status_code == 404
    response = client.post(f"/buildings/{building_id}/diagnoses", headers=headers)
    assert response.status_code == 409
    assert "upload measurements first" in response.json()["detail"]


def test_a_token_reaches_only_its_own_building(client, variant, diagnosed):
    building_id, _, job = diagnosed
    _, other = register(client, variant[0])
    calls = [
        ("post", f"/buildings/{building_id}/diagnoses"),
        ("get", f"/buildings/{building_id}/diagnoses"),
        ("get", f"/buildings/{building_id}/diagnosis"),
        ("get", f"/jobs/{job['id']}"),
    ]
    for method, url in calls:
        assert client.request(method, url, headers=other).status_code == 404, url
        assert client.request(method, url).status_code == 401, url
        assert client.request(method, url, headers=bearer("not-a-token")).status_code == 401, url
    assert report(client, building_id, ADMIN).status_code == 200


def test_window_of_days_or_start_end_clipped_to_the_measured_rows(client, variant, monkeypatch):
    _, frame = variant
    building_id, headers = measured_building(client, variant)
    seen = {}

    def fake(frame, building, model, settings, progress):
        seen.update(frame=frame, model=model, settings=settings)
        return fake_report(), "<!DOCTYPE html><p>fake</p>"

    monkeypatch.setattr(diagnosis, "diagnose_frame", fake)
    job = diagnose(client, building_id, headers, days=3, train_fraction=0.6, model="sun")
    assert job["status"] == "succeeded", job["error"]
    last = frame.index[-1]
    assert seen["frame"].index[0] == last + STEP - pd.Timedelta(days=3)
    assert seen["frame"].index[-1] == last
    assert seen["model"] == "sun" and job["days"] == 3
    assert (seen["settings"].train_fraction, seen["settings"].preset) == (0.6, "modestpy")

    # An explicit window: the end beyond the last measured row is clipped to it.
    window_start = frame.index[96]
    job = diagnose(
        client,
        building_id,
        headers,
        start=window_start.isoformat(),
        end=(last + pd.Timedelta(days=30)).isoformat(),
        effects=["unmetered_gains", "window_solar_gains"],
    )
    assert seen["frame"].index[0] == window_start and seen["frame"].index[-1] == last
    assert seen["settings"].effects == ("unmetered_gains", "window_solar_gains")
    assert pd.Timestamp(job["options"]["end"]) == last + STEP
    assert job["days"] == DAYS - 1
    body = report(client, building_id, headers).json()
    assert body["id"] == job["diagnosis_id"]
    # Every field of the engine's report reaches the client, the ones it adds too.
    assert {k: body[k] for k in fake_report()} == fake_report()
    page = report(client, building_id, headers, format="html")
    assert page.text == "<!DOCTYPE html><p>fake</p>"


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({"days": 7, "start": "2016-10-01T00:00:00+01:00"}, "either days or start"),
        ({"effects": ["moon_tides"]}, "unknown effect(s) ['moon_tides']"),
        ({"effects": []}, "at least one effect"),
        ({"model": "7r7c"}, "invalid model '7r7c'"),
        ({"train_fraction": 1.5}, "less than or equal to 0.9"),
        ({"train_fraction": 0.05}, "greater than or equal to 0.1"),
        ({"days": 1}, "greater than or equal to 2"),
        ({"start": "2016-10-01T00:00:00"}, "not an ISO 8601 time with a UTC offset"),
        ({"start": "2030-01-01T00:00:00+01:00"}, "holds no measured data"),
    ],
)
def test_invalid_diagnosis_request_is_422(client, diagnosed, body, words):
    building_id, headers, _ = diagnosed
    response = client.post(f"/buildings/{building_id}/diagnoses", json=body, headers=headers)
    assert response.status_code == 422
    assert words in response.text


def test_one_active_diagnosis_per_building_and_a_calibration_beside_it(
    client, variant, monkeypatch
):
    building_id, headers = measured_building(client, variant)
    started, release = threading.Event(), threading.Event()

    def held(*args, **kwargs):
        started.set()
        release.wait(30)
        return fake_report(), "<p>held</p>"

    monkeypatch.setattr(diagnosis, "diagnose_frame", held)
    first = start(client, building_id, headers)
    assert started.wait(30)
    second = client.post(f"/buildings/{building_id}/diagnoses", headers=headers)
    assert second.status_code == 409
    assert f"diagnosis job {first['id']} running" in second.json()["detail"]
    running = report(client, building_id, headers)
    assert running.status_code == 404
    assert f"diagnosis job {first['id']} is running" in running.json()["detail"]
    calibration = client.post(
        f"/buildings/{building_id}/calibrations", json={"days": 1}, headers=headers
    )
    assert calibration.status_code == 202
    release.set()
    assert wait_for_job(client, first["id"], headers)["status"] == "succeeded"
    assert wait_for_job(client, calibration.json()["id"], headers)["status"] == "succeeded"
    # Each list holds its own kind only.
    diagnoses = client.get(f"/buildings/{building_id}/diagnoses", headers=headers).json()
    calibrations = client.get(f"/buildings/{building_id}/calibrations", headers=headers).json()
    assert [j["id"] for j in diagnoses["items"]] == [first["id"]]
    assert [j["id"] for j in calibrations["items"]] == [calibration.json()["id"]]


# --- the migration ----------------------------------------------------------------------------
def test_migration_applies_on_a_fresh_sqlite_file(tmp_path):
    db = Database(f"sqlite:///{tmp_path / 'fresh.db'}")
    db.migrate()
    tables = inspect(db.engine)
    assert "diagnoses" in tables.get_table_names()
    assert {"kind", "options"} <= {c["name"] for c in tables.get_columns("jobs")}
    assert schema_revision(db) == "0006"
    db.dispose()


def test_migration_keeps_existing_jobs_as_calibrations_and_downgrades(tmp_path):
    db = Database(f"sqlite:///{tmp_path / 'old.db'}")
    migrate(db, command.upgrade, "0001")
    now = "2017-01-30 00:00:00"
    with db.engine.begin() as connection:
        connection.execute(
            text(
                "INSERT INTO buildings (id, name, description, timezone, token_hash, "
                "data_revision, created_at) VALUES (1, 'b', '{}', 'UTC', 'h', 1, :now)"
            ),
            {"now": now},
        )
        connection.execute(
            text(
                "INSERT INTO jobs (id, building_id, status, trigger, model, days, "
                "data_revision, created_at) VALUES (1, 1, 'succeeded', 'api', 'basic', 7, 1, :now)"
            ),
            {"now": now},
        )
        connection.execute(
            text(
                "INSERT INTO parameter_sets (building_id, job_id, model, status, is_current, "
                "train_start, train_end, metrics, engine_version, document, created_at) "
                "VALUES (1, 1, 'basic', 'current', 1, :now, :now, '{}', '0', '{}', :now)"
            ),
            {"now": now},
        )
    migrate(db, command.upgrade, "head")
    with db.session() as session:
        assert session.execute(text("SELECT kind FROM jobs")).scalars().all() == ["calibration"]
    migrate(db, command.downgrade, "0001")
    tables = inspect(db.engine)
    assert "diagnoses" not in tables.get_table_names()
    assert "kind" not in {c["name"] for c in tables.get_columns("jobs")}
    with db.session() as session:
        # Dropping the columns in place keeps the parameter set's link to its job.
        assert session.execute(text("SELECT job_id FROM parameter_sets")).scalar() == 1
    db.dispose()
