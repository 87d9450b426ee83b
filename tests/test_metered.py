"""The lights' convective share: heat the model places on the mass that belongs to the air is not
an unmetered gain (``rcengine.diagnose.metered``)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from rcengine.diagnose import diagnose
from rcengine.diagnose.metered import (
    F_LIGHT_AIR,
    LIGHT_CONVECTIVE_SHARE,
    lights_node,
    with_lights_in_air,
)
from rcengine.models import get_model
from tests.synthetic import (
    BUILDING,
    TRUTH_BASIC,
    UNMETERED_GAIN_ONLY,
    basic_reference,
    heat_per_watt,
    lit_office,
    weather_and_gains,
)
from tests.test_diagnose import _hidden_gain


def test_the_lights_share_moves_heat_from_the_mass_to_the_air_and_keeps_it_whole():
    frame = weather_and_gains(2)
    base = get_model("basic", BUILDING, frame.columns)
    assert lights_node(base) == "int"
    split = with_lights_in_air(base)
    assert split.parameters[F_LIGHT_AIR].lower == LIGHT_CONVECTIVE_SHARE[0]
    assert split.parameters[F_LIGHT_AIR].upper == LIGHT_CONVECTIVE_SHARE[1]
    heat = heat_per_watt(split, {**TRUTH_BASIC, F_LIGHT_AIR: 0.4}, "q_light")
    assert heat["air"] == pytest.approx(0.4)
    assert heat["int"] == pytest.approx(0.6)
    assert sum(heat.values()) == pytest.approx(1.0)
    # Once split, or where the lights heat the air already, there is nothing to move.
    assert lights_node(split) is None and with_lights_in_air(split) is None
    assert lights_node(get_model("1r1c", BUILDING, frame.columns)) is None
    without_lights = get_model("basic", BUILDING, frame.drop(columns="q_light").columns)
    assert with_lights_in_air(without_lights) is None


def test_lights_that_convect_part_of_their_heat_are_not_an_unmetered_gain():
    """Three weeks from the hand-written 3R3C with a heavy, loosely coupled interior mass whose
    lights (10 kW beside 2 kW of occupants) put 0.6 of their heat into the air: the model's
    all-radiant lights leave the occupied hours short of heat in the air, which an unmetered
    gain in step with the use would fill; the base model takes the lights' share, fitted at the
    0.6, and nothing is named."""
    inputs = lit_office(21)
    convected = 0.6 * inputs["q_light"]
    truth = inputs.assign(q_occ=inputs["q_occ"] + convected, q_light=inputs["q_light"] - convected)
    params = {**TRUTH_BASIC, "c_int": 1.0e6, "r_int": 0.3}
    record = inputs.assign(t_in=basic_reference(truth, params, (15.0, 19.0, 19.0)))
    d = json.loads(diagnose(record, BUILDING, "basic", UNMETERED_GAIN_ONLY).to_json())
    assert d["baseline"]["parameters"][F_LIGHT_AIR] == pytest.approx(0.6, abs=0.03)
    assert d["baseline"]["rmse_test"] < 0.01
    assert not any(f["accepted"] for f in d["findings"])


def test_heat_truly_missing_is_still_named(hidden_gain_record_small):
    """A hidden kitchen gain on weekday mornings: the lights' share, pressed to the most a
    luminaire convects, cannot take it; the base model keeps its routing and the gain is found
    (``test_diagnose`` runs it in full)."""
    d = json.loads(
        diagnose(hidden_gain_record_small, BUILDING, "basic", UNMETERED_GAIN_ONLY).to_json()
    )
    (gain,) = [f for f in d["findings"] if f["effect"] == "unmetered_gains"]
    assert gain["accepted"], gain["reason"]
    assert F_LIGHT_AIR not in d["baseline"]["parameters"]


@pytest.fixture(scope="module")
def hidden_gain_record_small() -> pd.DataFrame:
    """``test_diagnose``'s record: its kitchen gain (``_hidden_gain``) added to the air."""
    inputs = weather_and_gains(21)
    truth = inputs.assign(q_occ=inputs["q_occ"] + _hidden_gain(inputs.index))
    return inputs.assign(t_in=basic_reference(truth, TRUTH_BASIC, (15.0, 19.0, 19.0)))
