"""A storage the diagnosis adds takes its share of the declared glazing's sun (issue 11).

Exposed mass in a glazed room is a surface the transmitted sun lands on. The ``thermal_mass``
candidate adds a storage without sun (judged with sun, a null's base model took a storage that
re-timed its glazing's sun); once it is accepted, the glazing's sun may fall on it too, refitted
from the accepted fit. Without that, every glazed thermal-mass case of the dev pool went on to a
false window or unmetered gain: the sun reached the wrong mass and any extra sun path repaired it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.diagnose.candidates import CANDIDATES
from rcengine.diagnose.declared import G_WINDOW_ADDED_MASS, sun_on_added_mass
from rcengine.models import get_model
from rcengine.simulate import simulate
from tests.synthetic import TRUTH_BASIC, weather_and_gains
from tests.test_excess_sun import glazed_winter
from tests.test_plausibility import SMALL

# 800 kJ/(m²K) of floor behind 0.02 m²K/W: more storage than the basic model's own can stand for.
STORAGE = {"c_mass_extra": 8e5, "r_mass_extra": 0.02}
# The glazing's sun on the storage alone, none on the interior mass (a sunlit concrete floor).
SUN = {"g_window": 0.0, "g_window_air": 0.05, "r_window": 0.3, G_WINDOW_ADDED_MASS: 0.5}
TRUTH = {**TRUTH_BASIC, "alpha_wall": 1.0, "alpha_int": 0.0, **STORAGE, **SUN}


def _record() -> pd.DataFrame:
    """Eight winter weeks of the small office with an exposed concrete storage taking the
    glazing's sun, simulated by the extended network."""
    frame, ctx = glazed_winter(TRUTH)
    ext = CANDIDATES["thermal_mass"](ctx)
    network = sun_on_added_mass(ext.network, ext.detail["node"])
    compiled = network.compile()
    rc = compiled.rc_matrices(compiled.as_theta(TRUTH)[:1])
    u = ctx.data.inputs(compiled.input_names)
    states = np.full((1, len(compiled.state_names)), 19.0)
    return frame.assign(t_in=simulate(rc, u, states, ctx.data.step_s)[0])


def test_the_sun_falls_on_the_added_storage_only_where_glazing_is_declared():
    frame = weather_and_gains(7)
    bare = get_model("basic", SMALL, frame.columns)
    assert sun_on_added_mass(bare, "int") is None
    glazed = sun_on_added_mass(glazed_winter(TRUTH)[1].network, "int")
    assert G_WINDOW_ADDED_MASS in glazed.parameters
    (sun,) = [h for h in glazed.heat_inputs if h.gain == G_WINDOW_ADDED_MASS]
    assert (sun.signal, sun.node) == ("solar_window", "int")


@pytest.mark.slow
def test_the_glazing_sun_on_an_added_storage_is_read_back():
    """The base model cannot hold the storage (it is repaired with it); the repaired model then
    lets the glazing's sun fall on the storage and reads back the g-value it was simulated with."""
    settings = DiagnoseSettings(
        evidence="split",
        baseline_starts=2,
        max_rounds=2,
        effects=("thermal_mass", "window_solar_gains"),
    )
    report = diagnose(_record(), SMALL, settings=settings).to_dict()
    accepted = [f for f in report["findings"] if f["accepted"]]
    assert [f["effect"] for f in accepted] == ["thermal_mass"], report["verdict"]
    g_storage = accepted[0]["detail"]["glazing_g_on_storage"]
    assert g_storage == pytest.approx(SUN[G_WINDOW_ADDED_MASS], abs=0.15)
    assert report["final"]["parameters"][G_WINDOW_ADDED_MASS] == g_storage
    assert (
        f"the declared glazing's sun falls on it too: g = {g_storage:.2f}"
        in (accepted[0]["explanation"])
    )
