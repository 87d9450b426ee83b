"""POST /buildings/{id}/plan: the reference MPC on the served model."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from .conftest import DAY, wait_for_job

START = "2017-01-12T01:00:00+01:00"


@pytest.fixture
def calibrated(client, measured):
    """Days 1–3 measured, day 4 future inputs only, a current set fitted on day 2."""
    building_id, headers = measured
    job = client.post(f"/buildings/{building_id}/calibrations", json={"days": 1}, headers=headers)
    assert wait_for_job(client, job.json()["id"], headers)["outcome"] == "promoted"
    return building_id, headers


def post_plan(client, building_id, headers, **body):
    return client.post(f"/buildings/{building_id}/plan", json=body, headers=headers)


def office_band(free_end: np.ndarray, times: list[str]) -> list[float | None]:
    """1.5 K above the free-running temperature at the end of steps in weekday office hours
    (08–18 local), no edge otherwise: a band that needs heat. [°C]"""
    ends = pd.DatetimeIndex([pd.Timestamp(t) for t in times]) + pd.Timedelta(minutes=15)
    occupied = [t.day_of_week < 5 and 8 <= t.hour < 18 for t in ends]
    return [round(t + 1.5, 2) if o else None for t, o in zip(free_end, occupied, strict=True)]


def test_plan_meets_the_band_and_the_served_model_agrees(client, calibrated):
    building_id, headers = calibrated
    free = post_plan(client, building_id, headers, start=START, t_min=-30.0, q_max=60_000.0)
    assert free.status_code == 200, free.text
    assert free.json()["energy_kwh"] == 0.0
    free_end = np.append(free.json()["t_in_pred"][1:], free.json()["t_in_end"])
    t_min = office_band(free_end, free.json()["times"])
    response = post_plan(client, building_id, headers, start=START, t_min=t_min, q_max=60_000.0)
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["feasible"] and body["violation_kh"] == pytest.approx(0.0, abs=1e-3)
    assert len(body["times"]) == len(body["q_hvac"]) == len(body["t_in_pred"]) == DAY
    q = np.array(body["q_hvac"])
    assert (q >= 0.0).all() and (q <= 60_000.0 + 1e-6).all() and q.sum() > 0.0
    predicted_end = np.append(body["t_in_pred"][1:], body["t_in_end"])
    occupied = np.array([v is not None for v in t_min])
    edge = np.array([np.nan if v is None else v for v in t_min])
    assert (predicted_end[occupied] >= edge[occupied] - 1e-3).all()
    # The served simulator, given the plan, predicts the same temperatures.
    simulated = client.post(
        f"/buildings/{building_id}/simulate",
        json={"start": START, "q_hvac": q.tolist()},
        headers=headers,
    )
    assert simulated.status_code == 200, simulated.text
    np.testing.assert_allclose(simulated.json()["t_in"][0], body["t_in_pred"], atol=1e-6)
    assert body["energy_kwh"] == pytest.approx(q.sum() * 0.25 / 1000.0)


def test_unreachable_band_answers_with_the_least_violation_plan(client, calibrated):
    building_id, headers = calibrated
    response = post_plan(client, building_id, headers, start=START, t_min=50.0, q_max=500.0)
    assert response.status_code == 200, response.text
    body = response.json()
    assert not body["feasible"] and body["violation_kh"] > 1.0
    assert "capacity of 0.5 kW" in body["message"]
    assert (
        "first missed at the end of the step starting 2017-01-12T01:00:00+01:00"
        in (body["message"])
    )
    np.testing.assert_allclose(body["q_hvac"], 500.0, rtol=1e-6)


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({"hours": 0.0}, "hours"),
        ({"hours": 49.0}, "hours"),
        ({"t_min": [21.0] * 10}, "t_min has 10 values; the horizon has 96 steps"),
        ({"t_min": 100.0}, "t_min"),
        ({"q_max": -1.0}, "q_max"),
        ({"q_max": None}, "q_max"),
        ({"t_min": 22.0, "t_max": 20.0}, "empty comfort band"),
        ({"price": [0.1, 0.2]}, "price has 2 values"),
        ({"margin": -0.5}, "margin"),
        ({"start": "yesterday"}, "start"),
        ({"start": "2017-01-20T00:00:00+01:00"}, "stored row(s)"),
        ({"colour": "red"}, "colour"),
    ],
)
def test_bad_requests_are_422_naming_the_field(client, calibrated, body, words):
    building_id, headers = calibrated
    request = {"start": START, "t_min": 21.0, "q_max": 60_000.0} | body
    response = post_plan(client, building_id, headers, **request)
    assert response.status_code == 422, response.text
    assert words in response.text


def test_plan_without_a_parameter_set_is_409(client, measured):
    building_id, headers = measured
    response = post_plan(client, building_id, headers, t_min=21.0, q_max=60_000.0)
    assert response.status_code == 409, response.text


def test_missing_future_weather_is_named(client, calibrated):
    building_id, headers = calibrated
    response = post_plan(
        client, building_id, headers, start="2017-01-12T12:00:00+01:00", t_min=21.0, q_max=1e4
    )
    assert response.status_code == 422, response.text
    assert "t_out" in response.text and "missing" in response.text
