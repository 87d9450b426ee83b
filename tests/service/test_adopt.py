"""Adopting a diagnosed model (issue 17): the calibration it starts, what is served, the audit.

Data: five synthetic days whose indoor temperature comes from the Basic 3R3C model plus wind
infiltration (air changes growing with wind speed) — four measured, the fifth future weather only.
The diagnosis is replaced by a fake that reports the extended network, as the engine's report
holds it (``final.network``, ``final.signals``), so that these tests exercise the service: the
engine's diagnosis of the same physics is tested in tests/test_diagnose.py and, end to end
through the service on the EnergyPlus variants, in tests/service/test_adopt_variants.py.
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
import pytest
from alembic import command
from fastapi.testclient import TestClient
from sqlalchemy import inspect

from rcengine.columns import WIND_LOSS
from rcengine.models import get_model
from rcengine.models.spec import ModelSpec
from rcengine.network import Parameter
from rcengine.parameter_set import ParameterSet
from rcengine.signals import SignalOptions, prepare
from rcengine.simulate import simulate
from service import diagnosis
from service.core.db import Database
from service.main import create_app
from service.models import BuildingRecord

from ..synthetic import BUILDING, TRUTH_BASIC, weather_and_gains
from .conftest import (
    ADMIN,
    DAY,
    app_settings,
    json_rows,
    migrate,
    module_client,
    register,
    rmse,
    run_docs_session,
    schema_revision,
    wait_for_job,
)

ACH_WIND = 0.1  # air changes per hour per m/s of wind of the truth [1/h per m/s]
START = "2017-01-13T01:00:00+01:00"  # the first future row (day 5)


def wind_network(lowest: float = 0.0):
    """Basic plus wind infiltration, shaped as the diagnosis's candidate builds it, with at
    least ``lowest`` air changes per hour per m/s."""
    net = get_model("basic", BUILDING).copy("basic+wind_infiltration")
    net.add_parameter(Parameter("ach_wind", "1/h per m/s", lowest, 1.0, "wind air changes"))
    net.add_heat_input(WIND_LOSS, net.output, "ach_wind", factor=1.2 * 1005.0 * 3150.0 / 3600.0)
    return net


@pytest.fixture(scope="module")
def truth() -> pd.DataFrame:
    frame = weather_and_gains(days=5, seed=5)
    rng = np.random.default_rng(4)
    frame["wind_speed"] = np.repeat(rng.uniform(0.0, 9.0, 5 * 8), 12)  # 3-hourly gusts [m/s]
    compiled = wind_network().compile()
    rc = compiled.rc_matrices({**TRUTH_BASIC, "ach_wind": ACH_WIND})
    # The leakage loss is bilinear, wind·(t_in − t_out): iterated to its fixed point, each pass
    # linearised at the previous pass's indoor temperature (the signal reads the frame's t_in).
    for _ in range(8):
        data = prepare(frame, BUILDING, compiled.input_names)
        u = data.inputs(compiled.input_names)
        frame["t_in"] = simulate(rc, u, np.full((1, 3), 19.0), data.step_s)[0]
    return frame


client = module_client("adopt", preset="modestpy", training_days=3)


def fake_report(accepted: bool = True, lowest: float = 0.0) -> dict:
    net = wind_network(lowest)
    return {
        "baseline": {"model": "basic", "rmse_train": 1.0, "rmse_test": 1.2, "parameters": {}},
        "mismatch": {"summary": "under-predicts on windy days"},
        "findings": [
            {
                "effect": "wind_infiltration",
                "accepted": accepted,
                "explanation": "air leakage that grows with wind speed",
                "rmse_test_before": 1.2,
                "rmse_test_after": 0.1,
                "detail": {"volume_m3": 3150.0},
                "model": {"network": net.to_dict(), "signals": SignalOptions().to_dict()},
            }
        ],
        "final": {
            "model": net.name if accepted else "basic",
            "rmse_train": 0.1,
            "rmse_test": 0.1,
            "parameters": {},
            "network": (net if accepted else get_model("basic", BUILDING)).to_dict(),
            "signals": SignalOptions().to_dict(),
        },
        "verdict": "missing: wind_infiltration" if accepted else "nothing missing",
    }


def diagnosed(client, building_id, headers, monkeypatch, accepted=True, lowest=0.0) -> int:
    """A stored (fake) diagnosis; its id."""
    report = fake_report(accepted, lowest)
    monkeypatch.setattr(diagnosis, "diagnose_frame", lambda *a, **k: (report, "<html></html>"))
    job = client.post(f"/buildings/{building_id}/diagnoses", json={}, headers=headers).json()
    job = wait_for_job(client, job["id"], headers)
    assert job["status"] == "succeeded", job["error"]
    return job["diagnosis_id"]


def calibrate(client, building_id, headers, **body) -> dict:
    response = client.post(f"/buildings/{building_id}/calibrations", json=body, headers=headers)
    assert response.status_code == 202, response.text
    return wait_for_job(client, response.json()["id"], headers)


@pytest.fixture(scope="module")
def building(client, truth) -> tuple[int, dict]:
    """Four measured days and the fifth's weather; the base model calibrated and served."""
    building_id, headers = register(client)
    upload = truth.copy()
    upload.iloc[4 * DAY :, upload.columns.get_loc("t_in")] = np.nan
    # The future wind is known for the first 12 h only.
    upload.iloc[4 * DAY + 48 :, upload.columns.get_loc("wind_speed")] = np.nan
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(upload)}, headers=headers
    )
    assert response.status_code == 200, response.text
    assert calibrate(client, building_id, headers)["outcome"] == "promoted"
    return building_id, headers


@pytest.fixture(scope="module")
def adopted(client, building) -> tuple[int, dict, int, dict]:
    """The fake diagnosis adopted with the building's token: ids, headers and the answer."""
    building_id, headers = building
    with pytest.MonkeyPatch.context() as monkeypatch:
        diagnosis_id = diagnosed(client, building_id, headers, monkeypatch)
    response = client.post(
        f"/buildings/{building_id}/diagnoses/{diagnosis_id}/adopt", headers=headers
    )
    assert response.status_code == 200, response.text
    return building_id, headers, diagnosis_id, response.json()


def forecast(client, building_id, headers, hours=12.0):
    return client.get(
        f"/buildings/{building_id}/forecast",
        params={"start": START, "hours": hours},
        headers=headers,
    )


def test_adoption_calibrates_at_once_and_is_served_through_the_held_out_rule(
    client, adopted, truth
):
    building_id, headers, diagnosis_id, answer = adopted
    assert answer["changed"] and answer["action"] == "adopt" and answer["actor"] == "building"
    assert answer["diagnosis_id"] == diagnosis_id and answer["model"] == "basic+wind_infiltration"
    job = wait_for_job(client, answer["calibration_job_id"], headers)
    assert job["status"] == "succeeded", job["error"]
    assert job["trigger"] == "adopt" and job["model"] == "basic+wind_infiltration"
    # Promoted only because it beats the base set on the held-out day.
    holdout = job["details"]["holdout"]
    assert job["outcome"] == "promoted"
    assert holdout["new"]["rmse"] <= holdout["current"]["rmse"]
    assert job["details"]["model"] == "basic+wind_infiltration"
    body = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert body["current_parameter_set_id"] == job["parameter_set_id"]
    model = body["model"]
    assert model["name"] == "basic+wind_infiltration" and model["source"] == "diagnosis"
    assert model["effects"] == ["wind_infiltration"] and model["diagnosis_id"] == diagnosis_id
    assert model["by"] == "building" and model["since"].endswith("+01:00")
    assert "wind_speed" in model["required_columns"]
    # The served forecast uses the wind and is close to the truth the base model misses.
    served = forecast(client, building_id, headers).json()
    assert served["parameter_set"]["model"] == "basic+wind_infiltration"
    future = truth["t_in"].iloc[4 * DAY : 4 * DAY + 48]
    assert rmse(served["t_in_pred"], future) < 0.1


def test_model_and_simulate_of_an_adopted_model_match_the_forecast(client, adopted, truth):
    building_id, headers, _, _ = adopted
    served = forecast(client, building_id, headers).json()
    m = client.get(f"/buildings/{building_id}/model", params={"at": START}, headers=headers)
    assert m.status_code == 200, m.text
    m = m.json()
    assert WIND_LOSS in m["input_names"]
    # The derived inputs an MPC feeds the matrices: the stored set's own signals (rcengine).
    set_id = served["parameter_set"]["id"]
    document = client.get(f"/buildings/{building_id}/parameters/{set_id}/document", headers=headers)
    pset = ParameterSet.from_dict(document.json())
    # The leakage is linearised at the forecast's own indoor temperature (forecast_frame).
    future = truth.iloc[4 * DAY : 4 * DAY + 48].assign(t_in=served["t_in_pred"])
    u = pset.prepare(future).inputs(tuple(m["input_names"]))
    A, B, C, D = (np.array(m[k]) for k in ("A", "B", "C", "D"))
    x, outputs = np.array(m["state"]["x"]), []
    for row in u:
        outputs.append(C @ x + D @ row)
        x = A @ x + B @ row
    np.testing.assert_allclose(outputs, served["t_in_pred"], rtol=0, atol=1e-9)
    planned = truth["q_hvac"].iloc[4 * DAY : 4 * DAY + 48].tolist()
    simulated = client.post(
        f"/buildings/{building_id}/simulate",
        json={"start": START, "q_hvac": [planned, [0.0] * 48]},
        headers=headers,
    )
    assert simulated.status_code == 200, simulated.text
    np.testing.assert_allclose(simulated.json()["t_in"][0], served["t_in_pred"], atol=1e-9)


def test_a_forecast_beyond_the_uploaded_wind_names_the_column(client, adopted):
    building_id, headers, _, _ = adopted
    response = forecast(client, building_id, headers, hours=24.0)
    assert response.status_code == 422
    problems = response.json()["problems"]
    assert [p["column"] for p in problems] == ["wind_speed"]
    assert "missing at 48 of 96 future row(s)" in problems[0]["message"]


def test_adopt_revert_readopt_are_idempotent_and_audited(client, adopted):
    building_id, headers, diagnosis_id, first = adopted
    wait_for_job(client, first["calibration_job_id"], headers)
    url = f"/buildings/{building_id}/diagnoses/{diagnosis_id}/adopt"
    again = client.post(url, headers=ADMIN).json()
    assert not again["changed"] and again["calibration_job_id"] is None
    assert again["actor"] == "admin" and again["model_in_use"]["by"] == "building"
    served = client.get(f"/buildings/{building_id}", headers=headers).json()
    adopted_set = served["current_parameter_set_id"]
    # Revert: the base model's set is served again at once, and the base model recalibrated.
    revert = client.post(f"/buildings/{building_id}/model/revert", headers=ADMIN).json()
    assert revert["changed"] and revert["model"] is None and revert["actor"] == "admin"
    restored = revert["detail"]["restored_parameter_set_id"]
    assert restored is not None and restored != adopted_set
    job = wait_for_job(client, revert["calibration_job_id"], headers)
    assert job["status"] == "succeeded" and job["model"] == "basic" and job["trigger"] == "revert"
    body = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert body["model"]["source"] == "base" and body["model"]["name"] is None
    assert body["model"]["by"] == "admin"
    assert forecast(client, building_id, headers).json()["parameter_set"]["model"] == "basic"
    twice = client.post(f"/buildings/{building_id}/model/revert", headers=headers).json()
    assert not twice["changed"] and twice["calibration_job_id"] is None
    # Re-adopting after a revert is a change again, with its own calibration.
    readopt = client.post(url, headers=headers).json()
    assert readopt["changed"] and readopt["calibration_job_id"] is not None
    wait_for_job(client, readopt["calibration_job_id"], headers)
    changes = client.get(f"/buildings/{building_id}/model/changes", headers=headers).json()
    audit = [(c["action"], c["actor"], c["changed"], c["diagnosis_id"]) for c in changes["items"]]
    assert audit == [
        ("adopt", "building", True, diagnosis_id),
        ("adopt", "admin", False, diagnosis_id),
        ("revert", "admin", True, None),
        ("revert", "building", False, None),
        ("adopt", "building", True, diagnosis_id),
    ]
    assert all(c["created_at"].endswith("+01:00") for c in changes["items"])


def test_adopting_a_model_that_forecasts_worse_changes_nothing_served(client, truth, monkeypatch):
    building_id, headers = register(client)
    upload = truth.iloc[: 4 * DAY]
    url = f"/buildings/{building_id}/measurements"
    assert client.post(url, json={"rows": json_rows(upload)}, headers=headers).status_code == 200
    base = calibrate(client, building_id, headers)
    # Wind leakage forced to at least six times the truth's: a worse model.
    diagnosis_id = diagnosed(client, building_id, headers, monkeypatch, lowest=6 * ACH_WIND)
    answer = client.post(
        f"/buildings/{building_id}/diagnoses/{diagnosis_id}/adopt", headers=headers
    ).json()
    job = wait_for_job(client, answer["calibration_job_id"], headers)
    assert job["outcome"] == "rejected", job["details"]
    assert job["details"]["holdout"]["new"]["rmse"] > job["details"]["holdout"]["current"]["rmse"]
    body = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert body["current_parameter_set_id"] == base["parameter_set_id"]
    assert body["model"]["name"] == "basic+wind_infiltration"  # adopted for the next fits


def test_what_cannot_be_adopted_is_said(client, building, adopted, monkeypatch):
    building_id, headers, diagnosis_id, _ = adopted
    missing = client.post(f"/buildings/{building_id}/diagnoses/999/adopt", headers=headers)
    assert missing.status_code == 404 and "diagnosis 999 not found" in missing.json()["detail"]
    other_id, other_headers = register(client)
    foreign = client.post(
        f"/buildings/{other_id}/diagnoses/{diagnosis_id}/adopt", headers=other_headers
    )
    assert foreign.status_code == 404
    # While a model is adopted, a calibration of another model is refused with what to do.
    refused = client.post(
        f"/buildings/{building_id}/calibrations", json={"model": "1r1c"}, headers=headers
    )
    assert refused.status_code == 409 and "model/revert" in refused.json()["detail"]
    nothing = diagnosed(client, building_id, headers, monkeypatch, accepted=False)
    response = client.post(f"/buildings/{building_id}/diagnoses/{nothing}/adopt", headers=headers)
    assert response.status_code == 422 and "nothing to adopt" in response.json()["detail"]


def test_a_finding_the_diagnosis_rejected_is_adopted_by_name(client, truth, monkeypatch):
    """An engineer adopts the refitted wind the diagnosis did not accept: its model becomes the
    building's, audited with the finding and the diagnosis's verdict, calibrated at once."""
    building_id, headers = register(client)
    upload = truth.iloc[: 4 * DAY]
    url = f"/buildings/{building_id}/measurements"
    assert client.post(url, json={"rows": json_rows(upload)}, headers=headers).status_code == 200
    diagnosis_id = diagnosed(client, building_id, headers, monkeypatch, accepted=False)
    adopt = f"/buildings/{building_id}/diagnoses/{diagnosis_id}/adopt"
    final = client.post(adopt, headers=headers)
    assert final.status_code == 422 and "nothing to adopt" in final.json()["detail"]
    unjudged = client.post(adopt, params={"finding": "sky_radiation"}, headers=headers)
    assert unjudged.status_code == 422
    assert "judged no 'sky_radiation' (it judged: wind_infiltration)" in unjudged.json()["detail"]
    answer = client.post(adopt, params={"finding": "wind_infiltration"}, headers=headers)
    assert answer.status_code == 200, answer.text
    body = answer.json()
    assert body["changed"] and body["model"] == "basic+wind_infiltration"
    assert body["detail"] == {"finding": "wind_infiltration", "accepted_by_the_diagnosis": False}
    assert body["model_in_use"]["effects"] == ["wind_infiltration"]
    job = wait_for_job(client, body["calibration_job_id"], headers)
    assert job["status"] == "succeeded" and job["model"] == "basic+wind_infiltration"
    again = client.post(adopt, params={"finding": "wind_infiltration"}, headers=headers).json()
    assert not again["changed"] and again["detail"] == {"finding": "wind_infiltration"}
    # The refused calls left no audit row.
    changes = client.get(f"/buildings/{building_id}/model/changes", headers=headers).json()
    assert [c["changed"] for c in changes["items"]] == [True, False]


def test_migration_0004_adds_and_removes_the_adoption_tables(tmp_path):
    db = Database(f"sqlite:///{tmp_path / 'm.db'}")
    db.migrate()
    tables = inspect(db.engine)
    assert "model_changes" in tables.get_table_names()
    assert "model_spec" in {c["name"] for c in tables.get_columns("buildings")}
    migrate(db, command.downgrade, "0003")
    tables = inspect(db.engine)
    assert "model_changes" not in tables.get_table_names()
    assert "model_spec" not in {c["name"] for c in tables.get_columns("buildings")}
    assert schema_revision(db) == "0003"
    db.dispose()


def test_migration_0005_adds_and_removes_the_cloud_cover_column(tmp_path):
    db = Database(f"sqlite:///{tmp_path / 'm.db'}")
    db.migrate()
    assert "cloud_cover" in {c["name"] for c in inspect(db.engine).get_columns("measurements")}
    migrate(db, command.downgrade, "0004")
    assert "cloud_cover" not in {c["name"] for c in inspect(db.engine).get_columns("measurements")}
    assert schema_revision(db) == "0004"
    db.dispose()


def test_auto_adopt_adopts_a_diagnosis_with_findings_and_calibrates(tmp_path, truth, monkeypatch):
    settings = app_settings(
        f"sqlite:///{tmp_path / 'auto.db'}", preset="modestpy", training_days=3, auto_adopt=True
    )
    with TestClient(create_app(settings)) as client:
        building_id, headers = register(client)
        upload = truth.iloc[: 4 * DAY]
        client.post(
            f"/buildings/{building_id}/measurements",
            json={"rows": json_rows(upload)},
            headers=headers,
        )
        diagnosis_id = diagnosed(client, building_id, headers, monkeypatch)
        changes = []
        for _ in range(200):  # the adoption follows the diagnosis's run, on its thread
            url = f"/buildings/{building_id}/model/changes"
            changes = client.get(url, headers=headers).json()["items"]
            if changes and changes[0]["calibration_job_id"] is not None:
                break
            time.sleep(0.05)
        assert [(c["action"], c["actor"], c["diagnosis_id"]) for c in changes] == [
            ("adopt", "auto", diagnosis_id)
        ]
        job = wait_for_job(client, changes[0]["calibration_job_id"], headers)
        assert job["status"] == "succeeded" and job["model"] == "basic+wind_infiltration"
        model = client.get(f"/buildings/{building_id}", headers=headers).json()["model"]
        assert model["by"] == "auto" and model["name"] == "basic+wind_infiltration"


@pytest.mark.slow
def test_the_documented_adopt_session_runs_against_a_live_server(tmp_path):
    """docs/service.md's adopt flow, run as written (the docs' first session: test_docs_session)."""
    out = run_docs_session(tmp_path, "The adopt flow with `curl`", RCSERVICE_PRESET="modestpy")
    assert "missing" in out and "wind_infiltration" in out, out
    assert '"changed":true' in out and "'name': 'basic+wind_infiltration'" in out, out
    assert '"parameter_set":{"id":2,' in out and '"model":"basic+wind_infiltration"' in out, out
    assert "False\n" in out and '"action":"revert"' in out and '"actor":"admin"' in out, out


def test_a_stored_model_this_engine_cannot_read_is_said_not_a_server_error(client, truth):
    """A specification written by a newer engine: GET /buildings/{id} says why, a calibration is
    refused with the reason (422; a nightly one fails with it), revert still works."""
    building_id, headers = register(client)
    upload = truth.iloc[: 4 * DAY]
    url = f"/buildings/{building_id}/measurements"
    assert client.post(url, json={"rows": json_rows(upload)}, headers=headers).status_code == 200
    spec = ModelSpec.base(wind_network(), "basic", BUILDING).to_dict()
    with client.app.state.context.db.write() as session:
        session.get(BuildingRecord, building_id).model_spec = {**spec, "spec_version": 99}
    model = client.get(f"/buildings/{building_id}", headers=headers).json()["model"]
    assert model["name"] == "basic+wind_infiltration"
    assert "version 99 is newer than this engine" in model["error"]
    refused = client.post(f"/buildings/{building_id}/calibrations", json={}, headers=headers)
    assert refused.status_code == 422 and "newer than this engine" in refused.json()["detail"]
    revert = client.post(f"/buildings/{building_id}/model/revert", headers=headers).json()
    assert revert["changed"] and revert["model_in_use"]["source"] == "base"


def test_a_calibration_that_waited_through_a_revert_fails_saying_so(client, adopted):
    """Queued for the adopted model, run after a revert: it said "invalid model
    'basic+wind_infiltration'"; it now says the model was reverted and fits nothing."""
    from types import SimpleNamespace

    from service import calibration, repository
    from service.errors import CalibrationError

    building_id, headers, _, first = adopted
    wait_for_job(client, first["calibration_job_id"], headers)
    revert = client.post(f"/buildings/{building_id}/model/revert", headers=headers).json()
    wait_for_job(client, revert["calibration_job_id"], headers)
    db = client.app.state.context.db
    waited = SimpleNamespace(building_id=building_id, model="basic+wind_infiltration", days=3)
    with pytest.raises(CalibrationError, match="was reverted while this calibration waited"):
        calibration.load(db, waited, calibration.CalibrationOptions())
    # And a job records the model it fitted, whatever it was queued with.
    job = client.post(f"/buildings/{building_id}/calibrations", json={}, headers=headers).json()
    wait_for_job(client, job["id"], headers)
    with db.write() as session:
        repository.get_job(session, job["id"]).model = "queued-as"
    with db.write() as session:
        record = repository.get_job(session, job["id"])
        record.status = "running"
        record.lease_token = 0
    with db.write() as session:
        repository.finish_job(session, job["id"], "succeeded", details={}, model="basic")
    assert client.get(f"/jobs/{job['id']}", headers=headers).json()["model"] == "basic"


def test_a_set_of_a_model_reverted_while_it_was_fitted_is_not_served(client, adopted):
    """Reverted while the adopted model's calibration ran: that set was promoted, the reverted
    model was served on, and every later base-model fit lost the held-out day to it."""
    from types import SimpleNamespace

    from service import calibration

    building_id, headers, diagnosis_id, first = adopted
    wait_for_job(client, first["calibration_job_id"], headers)
    # The module's building may have been reverted by an earlier test: adopt (again).
    url = f"/buildings/{building_id}/diagnoses/{diagnosis_id}/adopt"
    again = client.post(url, headers=headers).json()
    if again["calibration_job_id"] is not None:
        wait_for_job(client, again["calibration_job_id"], headers)
    done = wait_for_job(client, first["calibration_job_id"], headers)
    db = client.app.state.context.db
    options = calibration.CalibrationOptions(preset="modestpy")
    running = SimpleNamespace(id=done["id"], building_id=building_id, days=3, model=done["model"])
    product = calibration.compute(calibration.load(db, running, options), options)
    revert = client.post(f"/buildings/{building_id}/model/revert", headers=headers).json()
    wait_for_job(client, revert["calibration_job_id"], headers)
    served = client.get(f"/buildings/{building_id}", headers=headers).json()
    with db.write() as session:
        details = product.save(session, running)
    assert product.outcome == "rejected"
    assert details["reason"] == (
        "the building's model changed to the base model while this calibration ran"
    )
    after = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert after["current_parameter_set_id"] == served["current_parameter_set_id"]
    assert forecast(client, building_id, headers).json()["parameter_set"]["model"] == "basic"


def test_an_adoption_during_a_calibration_calibrates_the_adopted_model_after_it(
    client, truth, monkeypatch
):
    """Adopted while the base model's calibration ran: that calibration's set is stored
    rejected, and the adopted model's first calibration, which the adoption could not start,
    starts as soon as it ends (it used to wait for the next night)."""
    import threading

    from service import calibration

    building_id, headers = register(client)
    upload = truth.iloc[: 4 * DAY]
    client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(upload)}, headers=headers
    )
    diagnosis_id = diagnosed(client, building_id, headers, monkeypatch)
    entered, release, compute = threading.Event(), threading.Event(), calibration.compute

    def held(inputs, options):
        entered.set()
        release.wait(timeout=60.0)
        return compute(inputs, options)

    monkeypatch.setattr(calibration, "compute", held)
    running = client.post(f"/buildings/{building_id}/calibrations", json={}, headers=headers)
    # Adopted once the calibration has read the model to fit (a job that has not started yet
    # fits the adopted model, and needs no follow-up).
    assert entered.wait(timeout=60.0)
    url = f"/buildings/{building_id}/diagnoses/{diagnosis_id}/adopt"
    adopt = client.post(url, headers=headers).json()
    assert adopt["changed"] and adopt["calibration_job_id"] is None
    assert "already has calibration job" in adopt["detail"]["calibration"]
    release.set()
    first = wait_for_job(client, running.json()["id"], headers)
    assert first["outcome"] == "rejected" and first["details"]["model_changed"]
    url = f"/buildings/{building_id}/model/changes"
    change = {}
    for _ in range(200):  # the follow-up starts in the finished calibration's callback
        change = client.get(url, headers=headers).json()["items"][-1]
        if change["calibration_job_id"] is not None:
            break
        time.sleep(0.05)
    follow_up = wait_for_job(client, change["calibration_job_id"], headers)
    assert follow_up["status"] == "succeeded" and follow_up["model"] == wind_network().name
    assert change["detail"]["calibration"].startswith("started when the calibration running")
