"""The layer of soil under a slab on the ground is fitted in depth, not fixed at ISO 52016-1's
0.5 m: a heated slab stores heat in the metre of soil a heating season reaches and gives it back
through a holiday, and a layer too thin reads that storage as a ground of another temperature
(here 4 K warmer than the truth; on the test bed's bare Chicago slab, 9 K colder)."""

from __future__ import annotations

import numpy as np
import pytest

from rcengine.diagnose.candidates import SOIL_LAYER_DEPTH_ISO, Context, Extension
from rcengine.diagnose.plausibility import assess
from rcengine.diagnose.selection import refit_preset
from rcengine.diagnose.settings import DiagnoseSettings
from rcengine.estimation import Estimator
from rcengine.models import get_model
from rcengine.signals import SignalOptions, prepare
from rcengine.simulate import simulate
from tests.synthetic import BUILDING, TRUTH_BASIC, ground_version, weather_and_gains

# A floor on 1.2 m of soil, 0.8 W/(m²K) from the slab to the soil's top, the soil 3 K warmer
# than the undisturbed ground below it (q_ground = ΔT·λ/d). [m], [m²K/W], [W/m²]
TRUTH_FLOOR = {"d_soil": 1.2, "r_floor": 1.25, "q_ground": 3.0 * 2.0 / 1.2}
# Days simulated before the record starts, so the soil starts charged as a season leaves it. [d]
WARM_UP_DAYS = 30
RECORD_DAYS = 60
# The sensor's noise. [K]
NOISE_K = 0.05


@pytest.fixture(scope="module")
def slab_record():
    """The office on the basic model with the layered floor at ``TRUTH_FLOOR``: 90 days from
    November at 15 min, heating off for a week (days 50–57 of the simulation), the record its
    last 60 days, measured with ``NOISE_K`` of white noise."""
    frame = weather_and_gains(WARM_UP_DAYS + RECORD_DAYS, start="2016-11-01")
    day = np.arange(len(frame)) // 96
    frame.loc[(day >= 50) & (day < 57), "q_hvac"] = 0.0
    network = get_model("basic", BUILDING, frame.columns)
    data = prepare(frame.assign(t_in=20.0), BUILDING, network.compile().input_names)
    zero = np.zeros(len(data))
    context = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, zero)
    layered = ground_version(context, layer=True)
    compiled = layered.network.compile()
    data = prepare(frame.assign(t_in=20.0), BUILDING, compiled.input_names, layered.signals)
    truth = {**TRUTH_BASIC, **TRUTH_FLOOR}
    x0 = np.full((1, compiled.n_states), 18.0)
    t_in = simulate(compiled.rc_matrices(truth), data.inputs(compiled.input_names), x0, 900.0)
    noise = np.random.default_rng(11).normal(0.0, NOISE_K, len(frame))
    frame = frame.assign(t_in=t_in[0] + noise)
    record = frame.iloc[WARM_UP_DAYS * 96 :]
    return layered, prepare(record, BUILDING, compiled.input_names, layered.signals)


def _fit(layered: Extension, data, **pinned: float) -> Estimator:
    return Estimator(
        layered.network,
        random_state=0,
        known={**TRUTH_BASIC, **pinned},
        warm_start=[layered.neutral],
        warn_bounds=False,
    ).fit(data)


def test_the_depth_of_soil_under_a_slab_is_recovered(slab_record):
    """Fitted with the rest of the model known, the floor's three parameters come back: the
    depth of soil within 15 %, the floor's U-value and the ground temperature read as the truth
    within 15 % and 0.5 K, and the reading is plausible."""
    layered, data = slab_record
    est = _fit(layered, data)
    assert est.params_["d_soil"] == pytest.approx(TRUTH_FLOOR["d_soil"], rel=0.15)
    truth = assess(layered, {**TRUTH_BASIC, **TRUTH_FLOOR}).magnitudes
    fitted = assess(layered, est.params_)
    assert not fitted.problems, fitted.problems
    u, t_ground = (fitted.magnitudes[k]["value"] for k in ("u_floor", "t_ground"))
    assert u == pytest.approx(truth["u_floor"]["value"], rel=0.15)
    assert t_ground == pytest.approx(truth["t_ground"]["value"], abs=0.5)


def test_iso_52016_s_fixed_half_metre_cannot_carry_a_deeper_soil(slab_record):
    """Held at 0.5 m, the layer cannot store what 1.2 m of soil does: the training fit is at
    least three times worse than with the depth free (which is down to the sensor's noise)."""
    layered, data = slab_record
    free = _fit(layered, data)
    fixed = _fit(layered, data, d_soil=SOIL_LAYER_DEPTH_ISO)
    assert free.rmse_ < 1.2 * NOISE_K
    assert fixed.rmse_ > 3.0 * free.rmse_, (fixed.rmse_, free.rmse_)


def test_a_refit_that_adds_a_state_takes_the_longer_search():
    """The layer of soil is a capacitor the model did not have: its refit takes the structural
    preset's longer genetic search, as the thermal mass and the emitter do; the floor straight
    onto the soil adds only inputs and takes the short one."""
    frame = weather_and_gains(10, start="2016-11-01")
    network = get_model("basic", BUILDING, frame.columns)
    data = prepare(frame.assign(t_in=20.0), BUILDING, network.compile().input_names)
    context = Context(network, BUILDING, data, SignalOptions(), TRUTH_BASIC, np.zeros(len(data)))
    settings = DiagnoseSettings()
    assert settings.structural_preset != settings.preset
    layered, bare = (ground_version(context, layer) for layer in (True, False))
    assert refit_preset(settings, layered, network) == settings.structural_preset
    assert refit_preset(settings, bare, network) == settings.preset
