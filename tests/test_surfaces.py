"""The interior surfaces: radiant heat lands on them, and part of it reaches the air before the
mass stores it (``rcengine.diagnose.surfaces``)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rcengine.diagnose import diagnose
from rcengine.diagnose.candidates import radiant_node
from rcengine.diagnose.surfaces import (
    R_MASS_SURF,
    SURFACE_NODE,
    released_share,
    with_surface_node,
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


def test_the_surfaces_stand_between_the_air_and_the_mass():
    frame = weather_and_gains(2)
    base = get_model("basic", BUILDING, frame.columns)
    assert radiant_node(base) == "int"
    net = with_surface_node(base)
    assert SURFACE_NODE in net.massless and radiant_node(net) == SURFACE_NODE
    # The radiant gains (the lights, the mass's sun) now enter the surfaces, and r_int is the
    # film from the air to them.
    assert {h.node for h in net.heat_inputs if h.signal in ("q_light", "ghi")} >= {SURFACE_NODE}
    assert not any(h.node == "int" for h in net.heat_inputs)
    params = {**TRUTH_BASIC, R_MASS_SURF: 0.45}
    heat = heat_per_watt(net, params, "q_light")
    # r_mass_surf / (r_int + r_mass_surf) of a watt on the surfaces reaches the air at once.
    assert released_share(params) == pytest.approx(0.75)
    assert heat["air"] == pytest.approx(0.75) and heat["int"] == pytest.approx(0.25)
    assert with_surface_node(net) is None
    assert with_surface_node(get_model("1r1c", BUILDING, frame.columns)) is None


def test_surfaces_at_the_mass_temperature_are_the_thesis_routing():
    frame = weather_and_gains(3)
    base = get_model("basic", BUILDING, frame.columns)
    net = with_surface_node(base)
    nested = {**TRUTH_BASIC, R_MASS_SURF: net.parameters[R_MASS_SURF].lower}
    heat, thesis = (
        heat_per_watt(net, nested, "q_light"),
        heat_per_watt(base, TRUTH_BASIC, "q_light"),
    )
    assert heat["int"] == pytest.approx(thesis["int"], abs=0.01)
    assert heat["air"] == pytest.approx(thesis["air"], abs=0.01)


def test_surfaces_that_give_radiant_heat_back_to_the_air_are_read_and_name_nothing():
    """Three weeks from the hand-written 3R3C with a heavy interior mass behind surfaces that
    give 0.6 of the radiant heat (the mass's sun, 10 kW of lights) straight back to the air: the
    thesis's routing leaves the sunny and occupied hours short of heat in the air, which an
    unmetered gain in step with the use would fill; the base model takes the surfaces and reads
    the share, and nothing is named."""
    inputs = lit_office(21)
    params = {**TRUTH_BASIC, "c_int": 1.0e6, "r_int": 0.2, R_MASS_SURF: 0.3}
    record = inputs.assign(t_in=basic_reference(inputs, params, (15.0, 19.0, 19.0)))
    d = json.loads(diagnose(record, BUILDING, "basic", UNMETERED_GAIN_ONLY).to_json())
    fitted = d["baseline"]["parameters"]
    assert released_share(fitted) == pytest.approx(0.6, abs=0.05)
    assert d["baseline"]["rmse_test"] < 0.02
    assert not any(f["accepted"] for f in d["findings"])
    assert np.isfinite(d["baseline"]["rmse_train"])
