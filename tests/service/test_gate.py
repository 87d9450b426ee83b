"""The promotion gate (issue 13, defect 6): degenerate fits are never promoted, whatever the
held-out comparison says, and the job names the checks that refused them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import pytest

from rcengine.network import Parameter, RCNetwork
from service.promotion import judge

from .conftest import DAY, json_rows, register
from .test_calibration import calibrate, parameter_sets


def upload(client, frame) -> tuple[int, dict]:
    building_id, headers = register(client)
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(frame)}, headers=headers
    )
    assert response.status_code == 200, response.text
    return building_id, headers


def refused(job: dict) -> list[str]:
    assert job["status"] == "succeeded", job["error"]
    assert job["outcome"] == "rejected"
    assert job["details"]["reason"].startswith("refused by the promotion gate")
    return job["details"]["gate"]["refused_by"]


@pytest.mark.parametrize(
    ("stuck", "checks"),
    [
        ({"t_in": 21.0}, {"t_in_varies"}),
        ({"q_hvac": 0.0}, {"heating_excites"}),
        ({"t_in": 21.0, "q_hvac": 0.0}, {"t_in_varies", "heating_excites"}),
    ],
)
def test_a_degenerate_series_is_never_promoted_on_a_new_building(
    client, three_days_measured, stuck, checks
):
    frame = three_days_measured.copy()
    for column, value in stuck.items():
        frame[column] = np.where(frame["t_in"].isna() & (column == "t_in"), np.nan, value)
    building_id, headers = upload(client, frame)
    job = calibrate(client, building_id, headers)
    assert checks <= set(refused(job))
    sets = parameter_sets(client, building_id, headers)
    assert sets["current_id"] is None and sets["items"][0]["status"] == "rejected"


def test_an_honest_fit_passes_every_check(client, measured):
    building_id, headers = measured
    job = calibrate(client, building_id, headers)
    assert job["outcome"] == "promoted"
    gate = job["details"]["gate"]
    assert gate["passed"] and gate["refused_by"] == []
    assert {c["name"] for c in gate["checks"]} == {
        "t_in_varies",
        "heating_excites",
        "parameters_inside_bounds",
        "predictions_plausible",
        "beats_persistence",
    }


@dataclass
class FittedSet:
    """What the gate reads of a parameter set."""

    values: dict = field(default_factory=lambda: dict.fromkeys("abcdefgh", 1.0))
    fit: dict = field(default_factory=lambda: {"at_bounds": []})
    network: RCNetwork = field(default_factory=lambda: RCNetwork("made up"))


@pytest.fixture
def days() -> tuple[pd.DataFrame, pd.DataFrame]:
    times = pd.date_range("2017-01-09", periods=2 * DAY, freq="15min", tz="UTC")
    hours = np.arange(times.size) / 4.0
    frame = pd.DataFrame(
        {"t_in": 20.0 + np.sin(hours / 24.0 * 2 * np.pi), "q_hvac": 1000.0 * (hours % 24 < 8)},
        index=times,
    )
    return frame.iloc[:DAY], frame.iloc[DAY:]


def test_most_parameters_on_bounds_are_refused(days):
    training, holdout = days
    pinned = FittedSet(fit={"at_bounds": list("abcdef")})
    verdict = judge(pinned, training, holdout, holdout["t_in"].to_numpy())
    assert verdict.refused_by == ["parameters_inside_bounds"]
    assert "6 of 8 parameters ended on a bound" in verdict.reason()


def test_gains_resting_at_zero_do_not_count_as_pinned(days):
    """Six of eight parameters on a bound, four of them non-negative gains at zero (their
    effect idle over the training days): two are pinned, within the gate's half."""
    training, holdout = days
    network = RCNetwork("with gains")
    for name in "abcd":
        network.add_parameter(Parameter(name, "W/m²", 0.0, 20.0, "a gain that cannot be negative"))
    network.add_parameter(Parameter("e", "m²K/W", 0.05, 5.0, "a resistance"))
    values = {**dict.fromkeys("abcdefgh", 1.0), **dict.fromkeys("abcd", 0.0), "e": 0.05}
    fitted = FittedSet(values, {"at_bounds": list("abcdef")}, network)
    verdict = judge(fitted, training, holdout, holdout["t_in"].to_numpy())
    assert verdict.passed
    check = next(c for c in verdict.checks if c.name == "parameters_inside_bounds")
    assert check.message.startswith("2 of 8 parameters ended on a bound (e, f;")
    assert check.message.endswith("resting at zero, not counted: a, b, c, d")
    # The same gains away from zero but on their upper bound are pinned.
    pinned = FittedSet({**values, **dict.fromkeys("abcd", 20.0)}, fitted.fit, network)
    verdict = judge(pinned, training, holdout, holdout["t_in"].to_numpy())
    assert verdict.refused_by == ["parameters_inside_bounds"]


@pytest.mark.parametrize("bad", [np.nan, np.inf, 7e304, -40.0])
def test_non_finite_or_absurd_predictions_are_refused(days, bad):
    training, holdout = days
    predicted = holdout["t_in"].to_numpy().copy()
    predicted[5] = bad
    verdict = judge(FittedSet(), training, holdout, predicted)
    assert "predictions_plausible" in verdict.refused_by


def test_worse_than_persistence_on_the_held_out_day_is_refused(days):
    training, holdout = days
    persistence = np.full(len(holdout), training["t_in"].iloc[-1])
    verdict = judge(FittedSet(), training, holdout, persistence + 3.0)
    assert verdict.refused_by == ["beats_persistence"]
    assert judge(FittedSet(), training, holdout, holdout["t_in"].to_numpy()).passed
