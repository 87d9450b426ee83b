"""A floor on a soil layer that stores heat is found and read back in physical units (issue 11).

The small office's floor lies on a metre of soil (2 MJ/(m²K)) over soil at 10 °C, its U-value
0.8 W/(m²K); the record is simulated by the ground candidate's own network and the floor is
concealed. The diagnosis finds the ground coupling and reads its U-value, the soil's capacity and
the ground temperature back within what eight winter weeks can tell.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.diagnose.candidates import CANDIDATES, Context
from rcengine.models import get_model
from rcengine.signals import SignalOptions, prepare
from rcengine.simulate import simulate
from tests.synthetic import TRUTH_BASIC, weather_and_gains
from tests.test_plausibility import SMALL

U_FLOOR = 0.8  # [W/(m²K)]
C_SOIL = 2.0e6  # a metre of soil at 2 MJ/(m³K) [J/(m²K)]
T_GROUND = 10.0  # [°C]
QUICK = DiagnoseSettings(
    evidence="split", baseline_starts=2, max_rounds=1, effects=("ground_coupling",)
)


def _record() -> pd.DataFrame:
    """Eight winter weeks of the small office on its soil layer (the resistance split evenly
    about the layer), simulated by the extended network."""
    frame = weather_and_gains(56, start="2017-01-02")
    frame = frame.assign(q_hvac=0.05 * frame["q_hvac"])
    for gain in ("q_occ", "q_light"):
        frame[gain] *= SMALL.floor_area / 1050.0
    base = get_model("basic", SMALL, frame.columns)
    data = prepare(frame.assign(t_in=20.0), SMALL, base.compile().input_names)
    ctx = Context(base, SMALL, data, SignalOptions(), TRUTH_BASIC, np.zeros(len(data)))
    ext = CANDIDATES["ground_coupling"](ctx)
    r_half = 0.5 / U_FLOOR
    soil = {
        "r_floor": r_half,
        "r_soil": r_half,
        "c_soil": C_SOIL,
        "q_ground": (T_GROUND - ext.detail["ground_base_c"]) / r_half,
    }
    compiled = ext.network.compile()
    rc = compiled.rc_matrices(compiled.as_theta({**TRUTH_BASIC, **soil})[:1])
    data = prepare(frame.assign(t_in=20.0), SMALL, compiled.input_names)
    x0 = np.full((1, len(compiled.state_names)), 19.0)
    x0[0, compiled.state_names.index("soil")] = 14.0
    t_in = simulate(rc, data.inputs(compiled.input_names), x0, data.step_s)[0]
    return frame.assign(t_in=t_in)


@pytest.fixture(scope="module")
def on_soil():
    return diagnose(_record(), SMALL, "basic", QUICK).to_dict()


def test_the_floor_on_its_soil_is_found_and_read_back(on_soil):
    (finding,) = [f for f in on_soil["findings"] if f["accepted"]]
    assert finding["effect"] == "ground_coupling"
    magnitudes = {k: v["value"] for k, v in finding["magnitudes"].items()}
    assert magnitudes["u_floor"] == pytest.approx(U_FLOOR, rel=0.15)
    assert magnitudes["t_ground"] == pytest.approx(T_GROUND, abs=2.0)
    assert magnitudes["c_soil"] == pytest.approx(C_SOIL, rel=0.25)
    assert on_soil["verdict"].endswith("missing: ground_coupling")
