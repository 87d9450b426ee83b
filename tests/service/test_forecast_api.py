"""Forecast, simulate and model endpoints against the engine and against each other."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from fastapi.testclient import TestClient

from rcengine.forecast import forecast
from rcengine.parameter_set import ParameterSet
from service.main import create_app

from .conftest import DAY, json_rows, register, rmse, wait_for_job

# Storage, API and job tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True


def get_forecast(client, building_id, headers, **params):
    return client.get(f"/buildings/{building_id}/forecast", params=params, headers=headers)


def test_forecast_matches_the_engine_and_the_truth(
    client, calibrated, synthetic, three_days_measured
):
    building_id, headers = calibrated
    start = synthetic.index[3 * DAY]
    response = get_forecast(client, building_id, headers, start="2017-01-12T01:00:00+01:00")
    assert response.status_code == 200
    body = response.json()
    set_id = body["parameter_set"]["id"]
    document = client.get(f"/buildings/{building_id}/parameters/{set_id}/document", headers=headers)
    pset = ParameterSet.from_dict(document.json())
    data = pset.prepare(three_days_measured)
    expected = forecast(pset.compiled, pset.values, data, start, hours=24)
    np.testing.assert_allclose(body["t_in_pred"], expected.t_in_pred, rtol=0, atol=1e-9)
    assert rmse(body["t_in_pred"], synthetic["t_in"].iloc[3 * DAY :]) < 0.01
    assert body["times"][0] == "2017-01-12T01:00:00+01:00"
    assert body["times"][-1] == "2017-01-13T00:45:00+01:00" and len(body["times"]) == DAY
    assert body["step_s"] == 900.0 and body["unit"] == "°C"


def test_forecast_carries_its_standard_deviation(client, calibrated, three_days_measured):
    """t_in_std beside t_in_pred (CONTRACT.md §4 extended): one per row, positive, finite,
    growing over the horizon, and the engine's own figure for the stored set's noise model."""
    building_id, headers = calibrated
    body = get_forecast(client, building_id, headers, start="2017-01-12T01:00:00+01:00").json()
    std = np.asarray(body["t_in_std"])
    assert len(std) == len(body["t_in_pred"]) == len(body["times"])
    assert np.isfinite(std).all() and (std > 0).all()
    assert np.mean(np.diff(std)) >= 0 and std[-1] > std[0]
    set_id = body["parameter_set"]["id"]
    document = client.get(f"/buildings/{building_id}/parameters/{set_id}/document", headers=headers)
    pset = ParameterSet.from_dict(document.json())
    data = pset.prepare(three_days_measured)
    start = pd.Timestamp("2017-01-12T00:00:00Z")
    expected = forecast(pset.compiled, pset.values, data, start, hours=24, noise=pset.noise)
    np.testing.assert_allclose(std, expected.t_in_std, rtol=1e-12, atol=0)


def test_default_start_is_one_step_after_the_last_measurement(client, calibrated):
    building_id, headers = calibrated
    default = get_forecast(client, building_id, headers, hours=6).json()
    explicit = get_forecast(client, building_id, headers, start="2017-01-12T00:00:00Z", hours=6)
    assert default["times"][0] == "2017-01-12T01:00:00+01:00"
    assert default == explicit.json()


def test_unescaped_plus_in_start_is_understood(client, calibrated):
    building_id, headers = calibrated
    # A client that forgets to escape '+' sends a space after URL decoding.
    url = f"/buildings/{building_id}/forecast?start=2017-01-12T01:00:00 01:00&hours=2"
    assert client.get(url, headers=headers).json()["times"][0] == "2017-01-12T01:00:00+01:00"


@pytest.mark.parametrize("start", ["tomorrow", "2017-01-12T01:00:00"])
def test_bad_start_is_422_naming_it(client, calibrated, start):
    building_id, headers = calibrated
    response = get_forecast(client, building_id, headers, start=start)
    assert response.status_code == 422
    assert response.json()["problems"][0]["column"] == "start"


def test_missing_future_inputs_are_named(client, calibrated):
    building_id, headers = calibrated
    # Day 4 has inputs up to 2017-01-13 00:45 local; 30 h from day 4's start runs 6 h past them.
    response = get_forecast(
        client, building_id, headers, start="2017-01-12T01:00:00+01:00", hours=30
    )
    assert response.status_code == 422
    problems = {p["column"]: p["message"] for p in response.json()["problems"]}
    assert set(problems) == {"t_out", "ghi", "q_hvac", "q_occ", "q_light"}
    assert problems["t_out"] == "missing at 24 forecast time(s), first 2017-01-13T00:00:00+00:00"


def test_forecast_without_history_is_422(client, calibrated):
    building_id, headers = calibrated
    response = get_forecast(client, building_id, headers, start="2017-01-09T01:00:00+01:00")
    assert response.status_code == 422
    assert "no measurements in the step before" in response.json()["detail"]


def test_forecast_without_parameter_set_is_409(client, synthetic):
    building_id, headers = register(client)
    client.post(
        f"/buildings/{building_id}/measurements",
        json={"rows": json_rows(synthetic)},
        headers=headers,
    )
    response = get_forecast(client, building_id, headers)
    assert response.status_code == 409
    assert "no calibrated parameter set" in response.json()["detail"]


def test_new_upload_changes_the_next_forecast(client, calibrated, synthetic):
    """Forecasts are cached per data revision: an upload must never leave a stale answer."""
    building_id, headers = calibrated
    start = "2017-01-12T01:00:00+01:00"
    before = get_forecast(client, building_id, headers, start=start).json()
    hotter = synthetic.iloc[3 * DAY :].copy()
    hotter["t_in"] = np.nan
    hotter["q_hvac"] += 20_000.0
    client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(hotter)}, headers=headers
    )
    after = get_forecast(client, building_id, headers, start=start).json()
    assert after["times"] == before["times"]
    assert all(a > b for a, b in zip(after["t_in_pred"][1:], before["t_in_pred"][1:], strict=True))


def test_simulate_candidates_by_linearity(client, calibrated, synthetic):
    building_id, headers = calibrated
    start = "2017-01-12T01:00:00+01:00"
    planned = synthetic["q_hvac"].iloc[3 * DAY :].to_numpy()
    zero, step = np.zeros(DAY), np.where(np.arange(DAY) >= 40, 30_000.0, 0.0)
    candidates = [planned.tolist(), zero.tolist(), step.tolist(), (zero + 10_000.0).tolist()]
    response = client.post(
        f"/buildings/{building_id}/simulate",
        json={"start": start, "q_hvac": candidates},
        headers=headers,
    )
    assert response.status_code == 200
    planned_y, zero_y, step_y, constant_y = np.array(response.json()["t_in"])
    # The planned q_hvac reproduces the forecast.
    reference = get_forecast(client, building_id, headers, start=start).json()["t_in_pred"]
    np.testing.assert_allclose(planned_y, reference, atol=1e-9)
    # Heat added from step 40 on changes nothing before it (causality), warms after it.
    np.testing.assert_allclose(step_y[:41], zero_y[:41], atol=1e-12)
    assert (step_y[41:] > zero_y[41:]).all()
    # A constant 10 kW warms every step after the first and more as time goes on.
    gain = constant_y - zero_y
    assert gain[0] == pytest.approx(0.0, abs=1e-12) and (np.diff(gain) > 0).all()


def test_single_candidate_as_a_flat_list(client, calibrated):
    building_id, headers = calibrated
    response = client.post(
        f"/buildings/{building_id}/simulate",
        json={"start": "2017-01-12T01:00:00+01:00", "q_hvac": [0.0] * 8},
        headers=headers,
    )
    assert response.status_code == 200
    assert len(response.json()["t_in"]) == 1 and len(response.json()["times"]) == 8


def test_model_matrices_and_state_reproduce_the_forecast(client, calibrated, synthetic):
    building_id, headers = calibrated
    start = "2017-01-12T01:00:00+01:00"
    model = client.get(f"/buildings/{building_id}/model", params={"at": start}, headers=headers)
    assert model.status_code == 200
    m = model.json()
    A, B, C, D = (np.array(m[k]) for k in ("A", "B", "C", "D"))
    assert m["input_names"] == ["t_out", "ghi", "q_hvac", "q_occ", "q_light"]
    assert m["input_units"] == ["°C", "W/m²", "W", "W", "W"]
    assert m["state"]["time"] == start and m["dt"] == 900.0
    # An MPC embedding the model: x[k+1] = A x + B u from the state estimate, inputs as stored.
    u = synthetic[m["input_names"]].iloc[3 * DAY :].to_numpy()
    x = np.array(m["state"]["x"])
    outputs = []
    for row in u:
        outputs.append(C @ x + D @ row)
        x = A @ x + B @ row
    reference = get_forecast(client, building_id, headers, start=start).json()["t_in_pred"]
    np.testing.assert_allclose(outputs, reference, atol=1e-9)
    # The state's air node is the measured indoor temperature within the filter's spread.
    assert m["state"]["t_in"] == pytest.approx(synthetic["t_in"].iloc[3 * DAY], abs=0.05)


def test_measurements_read_back_as_uploaded_and_upsert_keeps_measured_t_in(client, synthetic):
    building_id, headers = register(client)
    rows = json_rows(synthetic.iloc[:10])
    first = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": rows}, headers=headers
    )
    assert (first.json()["inserted"], first.json()["updated"]) == (10, 0)
    # Re-send rows 5–14 as a forecast would: t_in empty, other values changed.
    later = synthetic.iloc[5:15].copy()
    later["t_in"] = np.nan
    later["t_out"] += 1.0
    second = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(later)}, headers=headers
    )
    assert (second.json()["inserted"], second.json()["updated"]) == (5, 5)
    stored = client.get(f"/buildings/{building_id}/measurements", headers=headers).json()["rows"]
    assert len(stored) == 15
    stored_frame = pd.DataFrame(stored).set_index("time")
    np.testing.assert_allclose(stored_frame["t_in"].iloc[:10], synthetic["t_in"].iloc[:10], atol=0)
    assert stored_frame["t_in"].iloc[10:].isna().all()
    np.testing.assert_allclose(stored_frame["t_out"].iloc[5:], later["t_out"], atol=0)
    csv = client.get(
        f"/buildings/{building_id}/measurements",
        params={
            "format": "csv",
            "start": "2017-01-09T01:00:00+01:00",
            "end": "2017-01-09T02:00:00+01:00",
        },
        headers=headers,
    )
    assert csv.headers["content-type"].startswith("text/csv")
    lines = csv.text.strip().splitlines()
    assert lines[0].startswith("time,t_in,t_out,ghi,q_hvac") and len(lines) == 1 + 4
    assert lines[1].startswith("2017-01-09T01:00:00+01:00,")


def test_building_summary_reports_grid_and_last_measurement(client, calibrated):
    building_id, headers = calibrated
    summary = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert summary["step_s"] == 900.0 and summary["rows"] == 4 * DAY
    assert summary["first_time"] == "2017-01-09T01:00:00+01:00"
    assert summary["last_measured_time"] == "2017-01-12T00:45:00+01:00"
    assert summary["current_parameter_set_id"] is not None


def test_likelihood_criterion_stores_and_serves_the_fitted_noise(settings, three_days_measured):
    """RCSERVICE_CRITERION=likelihood: the calibration fits by maximum likelihood, the set keeps
    its noise model, and the forecast's t_in_std is the engine's figure for that model."""
    chosen = settings.model_copy(update={"criterion": "likelihood"})
    with TestClient(create_app(chosen)) as client:
        building_id, headers = register(client)
        rows = {"rows": json_rows(three_days_measured)}
        client.post(f"/buildings/{building_id}/measurements", json=rows, headers=headers)
        job = client.post(
            f"/buildings/{building_id}/calibrations", json={"days": 1}, headers=headers
        )
        finished = wait_for_job(client, job.json()["id"], headers)
        assert finished["outcome"] == "promoted", finished["error"]
        start = "2017-01-12T01:00:00+01:00"
        body = get_forecast(client, building_id, headers, start=start, hours=12).json()
        set_id = body["parameter_set"]["id"]
        document = client.get(
            f"/buildings/{building_id}/parameters/{set_id}/document", headers=headers
        ).json()
    pset = ParameterSet.from_dict(document)
    assert pset.fit["criterion"] == "likelihood" and pset.noise is not None
    data = pset.prepare(three_days_measured)
    expected = forecast(pset.compiled, pset.values, data, start, hours=12, noise=pset.noise)
    np.testing.assert_allclose(body["t_in_std"], expected.t_in_std, rtol=1e-12, atol=0)
    np.testing.assert_allclose(body["t_in_pred"], expected.t_in_pred, rtol=0, atol=1e-9)
    assert np.isfinite(body["t_in_std"]).all() and min(body["t_in_std"]) > 0
