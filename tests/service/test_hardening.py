"""Defects found by probing a running server (issue 13, defects 1–4, 8, 9): none answers 500,
every refusal names the field and stores nothing, and answers say what was done."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from rcengine.diagnose.html import local_day
from rcengine.exceptions import DataValidationError, ModelError
from rcengine.io.timeseries import parse_rows
from rcengine.parameter_set import ParameterSet
from service import diagnosis

from .conftest import ADMIN, DAY, SYNTHETIC_BUILDING, assert_refused, json_rows, wait_for_job

# API tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True
BEYOND_INT64 = "9223372036854775808"
BEYOND_INT32 = "2147483648"
ANCIENT = "0001-01-01T00:00:00+00:00"


def summary(client, building_id, headers) -> dict:
    return client.get(f"/buildings/{building_id}", headers=headers).json()


# --- 1: ids beyond the database's integers ---------------------------------------------------
@pytest.mark.parametrize("big", [BEYOND_INT64, BEYOND_INT32])
def test_ids_beyond_the_database_integers_are_422_naming_the_id(client, measured, big):
    building_id, headers = measured
    assert_refused(client.get(f"/jobs/{big}", headers=ADMIN), "job_id")
    assert_refused(client.get(f"/buildings/{big}", headers=ADMIN), "building_id")
    one_set = client.get(f"/buildings/{building_id}/parameters/{big}", headers=headers)
    assert_refused(one_set, "set_id")
    assert_refused(client.post(f"/buildings/{big}/token", headers=ADMIN), "building_id")
    largest = client.get("/jobs/2147483647", headers=ADMIN)
    assert largest.status_code == 404


# --- 2: candidate trajectories ----------------------------------------------------------------
@pytest.mark.parametrize(
    ("q_hvac", "words"),
    [
        ([[0, 0], [0]], "equal, non-zero length"),
        ([[]], "equal, non-zero length"),
        ([1e308, 0.0], "within [-1e+08, 1e+08] W; candidate 0, step 0 is 1e+308 W"),
        ([[0.0, 0.0], [0.0, -2e8]], "candidate 1, step 1"),
    ],
)
def test_simulate_refuses_ragged_or_absurd_candidates(client, measured, q_hvac, words):
    building_id, headers = measured
    response = client.post(
        f"/buildings/{building_id}/simulate", json={"q_hvac": q_hvac}, headers=headers
    )
    assert_refused(response, "q_hvac")
    assert words in response.json()["detail"]


# --- 3: deeply nested JSON --------------------------------------------------------------------
def test_deeply_nested_upload_is_422_and_stores_nothing(client, measured):
    building_id, headers = measured
    before = summary(client, building_id, headers)
    body = '{"rows": ' + "[" * 1000 + "]" * 1000 + "}"
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=body,
        headers={**headers, "Content-Type": "application/json"},
    )
    assert response.status_code == 422, response.text
    assert "nested too deeply" in response.json()["detail"]
    assert summary(client, building_id, headers) == before


# --- 4: times outside pandas' range -----------------------------------------------------------
@pytest.mark.parametrize("when", [ANCIENT, "2262-04-12T00:00:00+00:00", "9999-12-31T23:45:00Z"])
def test_uploads_with_times_outside_the_range_are_422_and_store_nothing(client, measured, when):
    building_id, headers = measured
    before = summary(client, building_id, headers)
    row = {"time": when, "t_in": 20.0, "t_out": 1.0, "ghi": 0.0, "q_hvac": 0.0}
    as_json = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": [row]}, headers=headers
    )
    as_csv = client.post(
        f"/buildings/{building_id}/measurements",
        content=f"time,t_in,t_out,ghi,q_hvac\n{when},20,1,0,0\n",
        headers={**headers, "Content-Type": "text/csv"},
    )
    for response in (as_json, as_csv):
        assert_refused(response, "time")
        assert "outside the supported range" in response.json()["detail"]
    assert summary(client, building_id, headers) == before


def test_queries_with_times_outside_the_range_are_422(client, measured):
    building_id, headers = measured
    url = f"/buildings/{building_id}"
    for path, field in (
        (f"{url}/forecast?start={ANCIENT}", "start"),
        (f"{url}/model?at={ANCIENT}", "at"),
        (f"{url}/measurements?start={ANCIENT}", "start"),
        (f"{url}/measurements?end=9999-01-01T00:00:00Z", "end"),
    ):
        assert_refused(client.get(path.replace("+", "%2B"), headers=headers), field)
    simulate = client.post(
        f"{url}/simulate", json={"start": ANCIENT, "q_hvac": [0]}, headers=headers
    )
    assert_refused(simulate, "start")
    diagnose = client.post(f"{url}/diagnoses", json={"start": ANCIENT}, headers=headers)
    assert diagnose.status_code == 422 and "start" in diagnose.text


# --- 8: the documented shape of every 422, JSON literals --------------------------------------
def test_framework_422_has_the_documented_shape_without_echoing_the_body(client, measured):
    building_id, headers = measured
    response = client.post(
        f"/buildings/{building_id}/calibrations",
        json={"days": "x", "secret": "do not echo"},
        headers=headers,
    )
    assert response.status_code == 422
    body = response.json()
    assert isinstance(body["detail"], str) and "do not echo" not in response.text
    assert {p["column"] for p in body["problems"]} == {"days", "secret"}
    unparseable = client.post(
        f"/buildings/{building_id}/calibrations",
        content="{",
        headers={**headers, "Content-Type": "application/json"},
    )
    assert_refused(unparseable, "body")


def test_json_nan_is_refused_not_taken_as_empty(client, measured):
    building_id, headers = measured
    before = summary(client, building_id, headers)
    row = '{"time": "2017-01-01T00:00:00+00:00", "t_in": NaN, "t_out": 1, "ghi": 0, "q_hvac": 0}'
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content='{"rows": [' + row + "]}",
        headers={**headers, "Content-Type": "application/json"},
    )
    assert response.status_code == 422
    assert "NaN is not a JSON value" in response.json()["detail"]
    assert summary(client, building_id, headers) == before


def test_a_boolean_reading_is_named_as_written(client, measured, synthetic):
    building_id, headers = measured
    rows = json_rows(synthetic.iloc[:2])
    for row in rows:  # a column of booleans only: numpy's bool type, shown as written
        row["t_in"] = True
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": rows}, headers=headers
    )
    assert response.status_code == 422
    assert "not a number: True" in response.json()["detail"]
    assert "np." not in response.text


def test_405_allow_lists_every_method_of_the_path(client, measured):
    building_id, headers = measured
    response = client.delete(f"/buildings/{building_id}/calibrations", headers=headers)
    assert response.status_code == 405
    assert set(response.headers["allow"].split(", ")) == {"GET", "POST"}


# --- 9: what a new user met -------------------------------------------------------------------
def test_forecast_rows_without_a_t_in_key_are_accepted(client, measured, synthetic):
    building_id, headers = measured
    future = json_rows(synthetic.iloc[3 * DAY :])
    for row in future:
        del row["t_in"]
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": future}, headers=headers
    )
    assert response.status_code == 200, response.text
    assert response.json()["rows"] == len(future)


def test_forecast_rows_without_a_t_in_column_are_accepted_as_csv(client, measured, synthetic):
    building_id, headers = measured
    future = synthetic.iloc[3 * DAY :].drop(columns="t_in")
    body = future.rename_axis("time").reset_index()
    body["time"] = body["time"].map(lambda t: t.isoformat())
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=body.to_csv(index=False, lineterminator="\r\n"),
        headers={**headers, "Content-Type": "text/csv"},
    )
    assert response.status_code == 200, response.text
    assert response.json()["updated"] == DAY
    stored = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert stored["last_measured_time"] < response.json()["first_time"]


def test_calibration_of_more_days_than_stored_says_the_days_fitted(client, measured):
    building_id, headers = measured  # 3 measured days: 2 to fit, 1 held out
    response = client.post(
        f"/buildings/{building_id}/calibrations", json={"days": 30}, headers=headers
    )
    assert response.status_code == 202
    job = response.json()
    assert job["days"] == 2 and job["options"] == {"days_requested": 30}


def test_empty_diagnosis_window_names_the_window_asked_in_order():
    spec = diagnosis.DiagnosisSpec(end=pd.Timestamp("2017-01-01", tz="UTC"), days=2)
    with pytest.raises(DataValidationError) as caught:
        diagnosis.plan(
            spec,
            pd.Timestamp("2017-02-01", tz="UTC"),
            pd.Timestamp("2017-02-10", tz="UTC"),
            900.0,
            7,
        )
    assert "2016-12-30T00:00:00+00:00 to 2017-01-01T00:00:00+00:00" in str(caught.value)


def test_diagnosis_job_keeps_the_days_asked_beside_the_days_used(client, measured):
    building_id, headers = measured
    response = client.post(
        f"/buildings/{building_id}/diagnoses", json={"days": 56}, headers=headers
    )
    assert response.status_code == 202, response.text
    job = response.json()
    assert job["days"] == 3 and job["options"]["days_requested"] == 56
    # Let it end here, not in a pool the interpreter is shutting down.
    wait_for_job(client, job["id"], headers, timeout_s=300.0)


def test_a_building_file_given_as_parameters_says_what_it_is():
    with pytest.raises(ModelError) as caught:
        ParameterSet.from_dict(json.loads(json.dumps(SYNTHETIC_BUILDING)))
    assert "looks like a building description" in str(caught.value)
    assert "'network'" in str(caught.value) and "a parameter file has" in str(caught.value)


def test_times_without_offset_are_one_problem_with_the_count():
    rows = [
        {"time": f"2017-01-09T00:{m:02d}:00", "t_in": 20, "t_out": 1, "ghi": 0, "q_hvac": 0}
        for m in (0, 15, 30, 45)
    ]
    with pytest.raises(DataValidationError) as caught:
        parse_rows(rows)
    (problem,) = caught.value.problems
    assert (problem.row, problem.column) == (0, "time")
    assert "nor have 3 later rows" in problem.message


def test_kelvin_message_names_the_column_once():
    rows = [
        {"time": f"2017-01-09T00:{m:02d}:00Z", "t_in": 293.0, "t_out": 1, "ghi": 0, "q_hvac": 0}
        for m in (0, 15, 30)
    ]
    with pytest.raises(DataValidationError) as caught:
        parse_rows(rows)
    assert str(caught.value).count("'t_in'") == 1


def test_report_dates_are_the_buildings_local_dates():
    assert local_day("2017-01-08T23:00:00+00:00", "Europe/Rome") == "2017-01-09"
    assert local_day("2017-01-09T05:00:00+00:00", "America/New_York") == "2017-01-09"
