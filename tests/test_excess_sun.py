"""Sun the declared glazing cannot pass is the evidence for the opaque envelope's (issue 11).

The small office declares its windows; its dark facades' sun is concealed. Fitted without it,
the base model lets the windows admit more sun than glass can; held to glass, the opaque sun
carries the rest, with the declared glazing's g-value and the walls' α·U recovered. Where the
windows stay within glass, the opaque sun is not taken. In the rounds, where glazing is declared,
it is named only against another effect that passes.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.diagnose.candidates import CANDIDATES, Context
from rcengine.diagnose.declared import with_declared_glazing
from rcengine.diagnose.excess_sun import RIVAL_ONLY, capped_bounds, declared_g, held_to_glass
from rcengine.diagnose.fitting import Fit
from rcengine.diagnose.selection import _unrivalled
from rcengine.models import get_model
from rcengine.models.bounds import G_GLAZING_MAX
from rcengine.signals import SignalOptions, prepare
from rcengine.simulate import simulate
from tests.synthetic import TRUTH_BASIC, weather_and_gains
from tests.test_plausibility import SMALL

GLAZING = {"g_window": 0.45, "g_window_air": 0.05, "r_window": 0.3}
TRUTH = {**TRUTH_BASIC, "alpha_wall": 1.0, "alpha_int": 0.0, **GLAZING}
QUICK = DiagnoseSettings(
    evidence="split", baseline_starts=2, max_rounds=1, effects=("opaque_solar_gains",)
)


def _declared(frame: pd.DataFrame):
    return with_declared_glazing(get_model("basic", SMALL, frame.columns), SMALL, "int")


def glazed_winter(truth: dict[str, float]) -> tuple[pd.DataFrame, Context]:
    """Eight winter weeks of the small office (a twentieth of the synthetic heater, its gains
    scaled to its floor area) and what a candidate is built from on its base model with the
    declared glazing at ``truth``: the record an extended network is then simulated on."""
    frame = weather_and_gains(56, start="2017-01-02")
    frame = frame.assign(q_hvac=0.05 * frame["q_hvac"])
    for gain in ("q_occ", "q_light"):
        frame[gain] *= SMALL.floor_area / 1050.0
    base = _declared(frame)
    data = prepare(frame.assign(t_in=20.0), SMALL, base.compile().input_names)
    return frame, Context(base, SMALL, data, SignalOptions(), truth, np.zeros(len(data)))


def _record(au_walls: float) -> pd.DataFrame:
    """Eight winter weeks of the small office whose walls pass α·U = ``au_walls`` W/(m²K) of
    their sun (sol-air), simulated by the extended network."""
    frame, ctx = glazed_winter(TRUTH)
    ext = CANDIDATES["opaque_solar_gains"](ctx)
    compiled = ext.network.compile()
    params = {**TRUTH, "au_opaque_walls": au_walls, "au_opaque_roof": 0.0}
    rc = compiled.rc_matrices(compiled.as_theta(params)[:1])
    data = prepare(frame.assign(t_in=20.0), SMALL, compiled.input_names)
    u = data.inputs(compiled.input_names)
    return frame.assign(t_in=simulate(rc, u, np.full((1, 3), 19.0), data.step_s)[0])


def test_the_glazing_is_held_to_glass_in_its_own_split_between_mass_and_air():
    frame = weather_and_gains(7)
    net = _declared(frame)
    params = {**TRUTH, "g_window": 0.9, "g_window_air": 0.3}
    g = declared_g(net, params)
    assert g == pytest.approx(1.2)  # the basic model's mass passes all its heat to the air
    bounds = capped_bounds(net, params, g)
    assert bounds["g_window"][1] == pytest.approx(0.9 * G_GLAZING_MAX / 1.2)
    assert bounds["g_window_air"][1] == pytest.approx(0.3 * G_GLAZING_MAX / 1.2)
    others = {n: (p.lower, p.upper) for n, p in net.parameters.items() if not n.startswith("g_")}
    assert {n: b for n, b in bounds.items() if not n.startswith("g_")} == others
    # The model that goes on keeps the cap as its own bounds; the network given is untouched.
    held = held_to_glass(net, params, g)
    assert {n: (p.lower, p.upper) for n, p in held.parameters.items()} == bounds
    assert net.parameters["g_window"].upper == G_GLAZING_MAX
    assert declared_g(get_model("basic", SMALL, frame.columns), TRUTH_BASIC) is None


@pytest.fixture(scope="module")
def dark_walls():
    return diagnose(_record(2.0), SMALL, "basic", QUICK).to_dict()


def test_sun_beyond_glass_is_found_on_the_opaque_walls(dark_walls):
    (finding,) = [f for f in dark_walls["findings"] if f["accepted"]]
    assert finding["effect"] == "opaque_solar_gains"
    excess = finding["detail"]["excess_sun"]
    assert excess["declared_g_before"] > G_GLAZING_MAX
    assert excess["declared_g_after"] == pytest.approx(0.5, abs=0.05)
    assert finding["parameters"]["au_opaque_walls"] == pytest.approx(2.0, rel=0.25)
    assert finding["reason"].startswith("accepted: the declared glazing admitted g = ")
    assert dark_walls["verdict"].endswith("missing: opaque_solar_gains")
    assert "opaque_solar_gains" not in dark_walls["skipped"]
    # The round's verdict on it (a rival with nothing else passing) gives way to the finding.
    assert [f["effect"] for f in dark_walls["findings"]] == ["opaque_solar_gains"]


def test_windows_within_glass_leave_the_walls_alone():
    report = diagnose(_record(0.0), SMALL, "basic", QUICK).to_dict()
    assert report["baseline"]["parameters"]["g_window"] < G_GLAZING_MAX
    assert not any(f["accepted"] for f in report["findings"])
    assert "opaque_solar_gains" not in report["skipped"]  # judged in the round as a rival


def _verdict(effect: str, accepted: bool) -> SimpleNamespace:
    reason = "accepted: test RMSE 0.50 → 0.40 K (-20%)" if accepted else "rejected: ΔBIC +3.0"
    return SimpleNamespace(effect=effect, accepted=accepted, reason=reason)


def test_the_opaque_sun_is_named_in_a_round_only_against_another_effect_that_passes():
    alone = [_verdict("opaque_solar_gains", True), _verdict("wind_infiltration", False)]
    _unrivalled(alone, {"opaque_solar_gains"})
    assert not alone[0].accepted
    assert alone[0].reason.startswith("passed its own margins (test RMSE 0.50 → 0.40 K (-20%))")
    assert alone[0].reason.endswith(RIVAL_ONLY)
    assert alone[1].reason == "rejected: ΔBIC +3.0"
    # Beside a passing effect it stays in the round's head to head, which may name it.
    beside = [_verdict("opaque_solar_gains", True), _verdict("wind_infiltration", True)]
    _unrivalled(beside, {"opaque_solar_gains"})
    assert all(f.accepted for f in beside)
    # Without declared glazing it is no rival: it stands on its own margins.
    own = [_verdict("opaque_solar_gains", True)]
    _unrivalled(own, set())
    assert own[0].accepted


def test_the_opaque_sun_must_be_preferred_by_the_bic_over_the_glazing_held_to_glass(
    dark_walls, monkeypatch
):
    (finding,) = [f for f in dark_walls["findings"] if f["accepted"]]
    assert finding["detail"]["excess_sun"]["delta_bic_capped_base"] < 0.0
    assert "against them" in finding["reason"]
    # The same record, had the opaque sun's fit been no better than its two parameters cost.
    monkeypatch.setattr(Fit, "criteria_change", lambda self, simpler: {"aic": 1.0, "bic": 1.0})
    report = diagnose(_record(2.0), SMALL, "basic", QUICK).to_dict()
    (judged,) = [f for f in report["findings"] if f["effect"] == "opaque_solar_gains"]
    assert not judged["accepted"]
    assert "ΔBIC +1.0 against them" in judged["reason"]
    assert report["verdict"].endswith("nothing missing")
