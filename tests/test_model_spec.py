"""Model specifications (rcengine.models.spec): the network a building uses, stored as JSON.

A specification rebuilt from its JSON simulates exactly as the one written (every element,
parameter bound and derived-signal setting survives); the ground's annual cycle is fixed when the
specification is made, so a one-day frame derives the same ground temperature as the record;
versions and documents it cannot read are clear errors; the columns a model needs are named.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rcengine.columns import (
    SKY_DELTA,
    SOLAR_WINDOW,
    T_GROUND,
    UNIT,
    VENT_LOSS,
    VENT_SCHEDULE,
    WIND_LOSS,
    solar_orientation_signal,
)
from rcengine.exceptions import DataValidationError, ModelError
from rcengine.models import get_model
from rcengine.models.spec import (
    SPEC_VERSION,
    ModelSpec,
    building_key,
    check_future_columns,
    columns_needed,
)
from rcengine.network import Parameter, RCNetwork
from rcengine.signals import SignalOptions, prepare
from rcengine.simulate import simulate

from .synthetic import BUILDING, TRUTH_BASIC, office, weather_and_gains

EXTRA = {"ach_wind": 0.3, "ach_vent": 2.0, "r_floor": 3.0, "q_ground": 5.0}


@pytest.fixture(scope="module")
def frame():
    data = weather_and_gains(days=21, seed=11)
    rng = np.random.default_rng(2)
    data["wind_speed"] = rng.uniform(0.0, 8.0, len(data))
    return data


def extended_network():
    """Basic plus the shapes the diagnosis gives wind, ventilation and ground coupling."""
    net = get_model("basic", BUILDING).copy("basic+wind_infiltration+ventilation_schedule")
    per_ach = 1.2 * 1005.0 * BUILDING.volume / 3600.0
    net.add_parameter(Parameter("ach_wind", "1/h per m/s", 0.0, 2.0, "wind air changes"))
    net.add_parameter(Parameter("ach_vent", "1/h", 0.0, 10.0, "scheduled air changes"))
    net.add_parameter(Parameter("r_floor", "m²K/W", 0.1, 20.0, "floor resistance"))
    net.add_parameter(Parameter("q_ground", "W/m²", -20.0, 60.0, "soil warming"))
    net.add_heat_input(WIND_LOSS, net.output, "ach_wind", factor=per_ach)
    net.add_heat_input(VENT_LOSS, net.output, "ach_vent", factor=per_ach)
    mass = net.states[-1]
    net.add_resistor(T_GROUND, mass, "r_floor", factor=1.0 / BUILDING.floor_area)
    net.add_heat_input(UNIT, mass, "q_ground", factor=BUILDING.floor_area)
    return net


def schedule() -> list[float]:
    weekday = [1.0 if 8 <= h < 18 else 0.0 for h in range(24)]
    return weekday * 5 + [0.0] * 48


def report(net) -> dict:
    """The parts of a diagnosis report (Report.to_dict) a specification is made from."""
    signals = SignalOptions(schedules={VENT_SCHEDULE: schedule()}, schedule_clock="standard")
    return {
        "baseline": {"model": "basic"},
        "findings": [
            {"effect": "wind_infiltration", "accepted": True, "detail": {"volume_m3": 3150.0}},
            {"effect": "sky_radiation", "accepted": False, "detail": {}},
            {"effect": "ventilation_schedule", "accepted": True, "detail": {"clock": "standard"}},
        ],
        "final": {"model": net.name, "network": net.to_dict(), "signals": signals.to_dict()},
    }


def run(spec: ModelSpec, frame) -> np.ndarray:
    """The specification's network simulated over ``frame`` with the true parameters."""
    compiled = spec.network(BUILDING).compile()
    data = prepare(frame, BUILDING, compiled.input_names, spec.signals)
    rc = compiled.rc_matrices({**TRUTH_BASIC, **EXTRA})
    x0 = np.full((1, compiled.n_states), 20.0)
    return simulate(rc, data.inputs(compiled.input_names), x0, data.step_s)[0]


def test_a_rebuilt_specification_simulates_identically(frame):
    spec = ModelSpec.from_report(report(extended_network()), BUILDING, frame, diagnosis_id=7)
    again = ModelSpec.from_json(spec.to_json())
    assert again == spec
    assert again.to_dict() == spec.to_dict()
    assert np.array_equal(run(again, frame), run(spec, frame))
    assert again.effects == ("wind_infiltration", "ventilation_schedule")
    assert again.source["diagnosis_id"] == 7 and again.base_model == "basic"
    assert again.signals.schedule_clock == "standard"
    assert again.rc.parameters["ach_wind"] == spec.rc.parameters["ach_wind"]  # unit and bounds
    assert json.loads(spec.to_json())["spec_version"] == SPEC_VERSION


def test_the_ground_cycle_is_fixed_when_the_specification_is_made(frame):
    spec = ModelSpec.from_report(report(extended_network()), BUILDING, frame)
    assert spec.signals.ground_cycle is not None and not spec.needs_record
    assert ModelSpec.from_report(report(extended_network()), BUILDING).needs_record
    inputs = spec.inputs
    whole = prepare(frame, BUILDING, inputs, spec.signals).frame[T_GROUND]
    day = frame.iloc[-96:]
    alone = prepare(day, BUILDING, inputs, spec.signals).frame[T_GROUND]
    assert np.allclose(alone.to_numpy(), whole.iloc[-96:].to_numpy(), atol=1e-12, rtol=0.0)
    # Without the fixed cycle a single day would fit its own (what a forecast must not do).
    loose = prepare(day, BUILDING, inputs, SignalOptions(schedules=spec.signals.schedules))
    assert not np.allclose(loose.frame[T_GROUND].to_numpy(), alone.to_numpy(), atol=1e-3)


def test_a_specification_belongs_to_its_building(frame):
    spec = ModelSpec.from_report(report(extended_network()), BUILDING, frame)
    assert spec.network(office(name="renamed")).name == spec.name  # the name is not physics
    with pytest.raises(ModelError, match="another building description"):
        spec.network(office(floor_area=900.0))
    assert building_key(BUILDING) == building_key(office(name="x"))


def test_a_report_without_a_final_network_or_findings_cannot_be_adopted(frame):
    old = report(extended_network())
    del old["final"]["network"]
    with pytest.raises(ModelError, match="older engine"):
        ModelSpec.from_report(old, BUILDING, frame)
    nothing = report(extended_network())
    nothing["findings"] = [{"effect": "sky_radiation", "accepted": False}]
    with pytest.raises(ModelError, match="nothing to adopt"):
        ModelSpec.from_report(nothing, BUILDING, frame)


def sky_network():
    """Basic with the wind the round before accepted and a sky the diagnosis rejected."""
    net = get_model("basic", BUILDING).copy("basic+wind_infiltration+sky_radiation")
    per_ach = 1.2 * 1005.0 * BUILDING.volume / 3600.0
    net.add_parameter(Parameter("ach_wind", "1/h per m/s", 0.0, 2.0, "wind air changes"))
    net.add_parameter(Parameter("u_sky", "W/(m²K)", 0.0, 5.0, "sky exchange"))
    net.add_heat_input(WIND_LOSS, net.output, "ach_wind", factor=per_ach)
    net.add_heat_input(SKY_DELTA, net.states[0], "u_sky", factor=100.0)
    return net


def test_a_finding_the_diagnosis_rejected_can_be_adopted_by_name(frame):
    """An engineer may adopt a refitted finding the diagnosis did not accept: the model of its
    round with the effect added; one only screened, or never judged, is a clear error."""
    diagnosed = report(extended_network())
    sky = sky_network()
    options = SignalOptions(cloud_cover="estimated")
    diagnosed["findings"][1]["model"] = {"network": sky.to_dict(), "signals": options.to_dict()}
    spec = ModelSpec.from_report(
        diagnosed, BUILDING, frame, diagnosis_id=3, finding="sky_radiation"
    )
    assert spec.name == "basic+wind_infiltration+sky_radiation"
    assert spec.effects == ("wind_infiltration", "sky_radiation")
    assert spec.source["finding"] == "sky_radiation" and spec.source["accepted"] is False
    assert set(spec.source["details"]) == {"wind_infiltration", "sky_radiation"}
    assert SKY_DELTA in spec.inputs and "u_sky" in spec.rc.parameters
    assert ModelSpec.from_json(spec.to_json()) == spec
    with pytest.raises(ModelError, match="screened, not refitted"):
        ModelSpec.from_report(diagnosed, BUILDING, finding="wind_infiltration")
    with pytest.raises(ModelError, match="judged no 'ground_coupling'"):
        ModelSpec.from_report(diagnosed, BUILDING, finding="ground_coupling")


def window_report(g: dict[str, float]) -> dict:
    """Basic with the window candidate's extra g-value per orientation, accepted at ``g``."""
    net = get_model("basic", BUILDING).copy("basic+window_solar_gains")
    for key in g:
        net.add_parameter(Parameter(f"g_window_{key}", "-", 0.0, 1.5, f"extra g {key}"))
        net.add_heat_input(solar_orientation_signal(SOLAR_WINDOW, key), "int", f"g_window_{key}")
    new = {f"g_window_{k}": v for k, v in g.items()}
    model = {"network": net.to_dict(), "signals": SignalOptions().to_dict()}
    finding = {
        "effect": "window_solar_gains",
        "accepted": True,
        "detail": {"orientations": {key: {} for key in g}},
        "parameters": new,
        "model": model,
    }
    final = {**model, "parameters": {**TRUTH_BASIC, **new}}
    return {"baseline": {"model": "basic"}, "findings": [finding], "final": final}


def test_the_diagnosed_split_across_facades_is_kept_and_one_scale_fitted():
    """A fortnight's calibration cannot tell which facade has the extra glass, as the months of
    the diagnosis did: the specification keeps the diagnosed shares and fits one scale, and at
    the diagnosed value it is the diagnosis's model."""
    diagnosed = window_report({"90_90": 0.4, "270_90": 0.1, "0_90": 0.0})
    spec = ModelSpec.from_report(diagnosed, BUILDING)
    scale = spec.rc.parameters["g_window_scale"]
    assert (scale.lower, scale.upper) == (0.0, 1.5)
    assert "(90_90 1.00, 270_90 0.25, 0_90 0.00)" in scale.description
    assert not [p for p in spec.rc.parameters if p.startswith("g_window_") and p[9].isdigit()]
    east, west, north = (solar_orientation_signal(SOLAR_WINDOW, k) for k in ("90", "270", "0"))
    assert {east + "_90", west + "_90"} <= set(spec.inputs)
    assert north + "_90" not in spec.inputs  # the facade fitted at zero drops out
    original = RCNetwork.from_dict(diagnosed["final"]["network"]).compile()
    kept = spec.rc.compile()
    at_diagnosis = kept.rc_matrices({**TRUTH_BASIC, "g_window_scale": 0.4})
    fitted = original.rc_matrices(diagnosed["final"]["parameters"])
    columns = [original.input_names.index(name) for name in kept.input_names]
    assert np.allclose(at_diagnosis.F, fitted.F[..., columns], rtol=1e-12, atol=0.0)
    assert ModelSpec.from_json(spec.to_json()) == spec
    named = ModelSpec.from_report(diagnosed, BUILDING, finding="window_solar_gains")
    assert named.rc.parameters["g_window_scale"] == scale
    # Nothing fitted above zero: the orientations are left as they are.
    nothing = ModelSpec.from_report(window_report({"90_90": 0.0, "270_90": 0.0}), BUILDING)
    assert {"g_window_90_90", "g_window_270_90"} <= set(nothing.rc.parameters)


def test_older_documents_load_and_unreadable_ones_say_why(frame):
    spec = ModelSpec.from_report(report(extended_network()), BUILDING, frame)
    document = spec.to_dict()
    # Written before ground_cycle existed: loads, the cycle then fitted to each frame as before.
    older = json.loads(json.dumps(document))
    del older["signals"]["ground_cycle"]
    assert ModelSpec.from_dict(older).signals.ground_cycle is None
    for version, words in ((SPEC_VERSION + 1, "newer than this engine"), (0, "not one")):
        with pytest.raises(ModelError, match=words):
            ModelSpec.from_dict({**document, "spec_version": version})
    with pytest.raises(ModelError, match="no 'spec_version'"):
        ModelSpec.from_dict({k: v for k, v in document.items() if k != "spec_version"})
    with pytest.raises(ModelError, match="parameter file"):
        ModelSpec.from_dict({"network": {}, "parameters": {}})
    future = json.loads(json.dumps(document))
    future["signals"]["moon_phase"] = 0.5
    with pytest.raises(ModelError, match=r"\['moon_phase'\] are unknown"):
        ModelSpec.from_dict(future)
    with pytest.raises(ModelError, match="no 'network'"):
        ModelSpec.from_dict({k: v for k, v in document.items() if k != "network"})
    deep = json.loads(json.dumps(document))
    deep["signals"]["ground_depth_m"] = "deep"
    with pytest.raises(ModelError, match="'ground_depth_m' must be metres"):
        ModelSpec.from_dict(deep)
    for name, value in [("sky_model", "cubist"), ("input_hold", 1), ("albedo", 1.5)]:
        odd = json.loads(json.dumps(document))
        odd["signals"][name] = value
        with pytest.raises(ModelError, match=f"signal setting '{name}' must be"):
            ModelSpec.from_dict(odd)
    with pytest.raises(ModelError, match="must be JSON"):
        ModelSpec.from_json("{not json")


def test_the_columns_a_model_needs_are_named(frame):
    spec = ModelSpec.from_report(report(extended_network()), BUILDING, frame)
    needed = {"t_out", "ghi", "q_hvac", "q_occ", "q_light", "wind_speed"}
    assert set(spec.required_columns) == needed
    assert columns_needed(["sched_gains", "sky_delta", "solar_window_90_90"]) == ["t_out", "ghi"]
    measured_sky = SignalOptions(cloud_cover="column")
    assert columns_needed(["sky_delta"], measured_sky) == ["cloud_cover", "t_out", "ghi"]
    assert columns_needed(["wind_loss"], measured_sky) == ["t_out", "wind_speed"]
    # An outer film that follows the wind needs it under each orientation's opaque sun only.
    windy = SignalOptions(exterior_film="wind")
    assert columns_needed(["solar_opaque_90_90"], windy) == ["wind_speed", "ghi"]
    assert columns_needed(["solar_window_90_90", "solar_opaque", "sky_delta"], windy) == [
        "ghi",
        "t_out",
    ]
    start, end = frame.index[10], frame.index[20]
    check_future_columns(frame, ["sky_delta"], start, end)
    with pytest.raises(DataValidationError, match="needs 'cloud_cover' over the forecast"):
        check_future_columns(frame, ["sky_delta"], start, end, measured_sky)
    base = ModelSpec.base(get_model("basic", BUILDING), "basic", BUILDING)
    assert base.name == "basic" and base.effects == () and base.source == {"kind": "base"}


# --- the command line: diagnose --save-model, fit --model-file ----------------------------------
def wind_report() -> dict:
    net = get_model("basic", BUILDING).copy("basic+wind_infiltration")
    net.add_parameter(Parameter("ach_wind", "1/h per m/s", 0.0, 1.0, "wind air changes"))
    net.add_heat_input(WIND_LOSS, net.output, "ach_wind", factor=1.2 * 1005.0 * 3150.0 / 3600.0)
    finding = {"effect": "wind_infiltration", "accepted": True, "explanation": "wind", "detail": {}}
    return {
        "baseline": {"model": "basic", "rmse_test": 1.0},
        "mismatch": {"summary": "windy days"},
        "findings": [finding],
        "final": {
            "model": net.name,
            "rmse_test": 0.1,
            "network": net.to_dict(),
            "signals": SignalOptions().to_dict(),
        },
    }


def test_diagnose_saves_the_model_that_fit_then_calibrates(tmp_path, monkeypatch):
    from types import SimpleNamespace

    from typer.testing import CliRunner

    from rcengine import cli
    from rcengine.diagnose import selection

    monkeypatch.chdir(tmp_path)
    frame = weather_and_gains(days=4, seed=5)
    frame["wind_speed"] = np.repeat(np.random.default_rng(4).uniform(0.0, 9.0, 32), 12)
    spec = ModelSpec.from_report(wind_report(), BUILDING)
    compiled = spec.network(BUILDING).compile()
    data = prepare(frame, BUILDING, compiled.input_names)
    rc = compiled.rc_matrices({**TRUTH_BASIC, "ach_wind": 0.1})
    frame["t_in"] = simulate(rc, data.inputs(compiled.input_names), np.full((1, 3), 19.0), 900.0)[0]
    table = frame.rename_axis("time").reset_index()
    table["time"] = [t.isoformat() for t in frame.index]
    table.to_csv("data.csv", index=False)
    Path("b.json").write_text(json.dumps(BUILDING.to_dict()))
    findings = [SimpleNamespace(accepted=True, effect="wind_infiltration", explanation="wind")]
    fake = SimpleNamespace(to_dict=wind_report, findings=findings, wall_time_s=0.1)
    monkeypatch.setattr(selection, "diagnose", lambda *a, **k: fake)
    runner = CliRunner()
    save = ["diagnose", "data.csv", "-b", "b.json", "--save-model", "m.json"]
    saved = runner.invoke(cli.app, save)
    assert saved.exit_code == 0, saved.output
    assert "model basic+wind_infiltration; effects: wind_infiltration" in saved.output
    assert ModelSpec.load("m.json") == spec
    fit = runner.invoke(
        cli.app,
        ["fit", "data.csv", "-b", "b.json", "--model-file", "m.json", "-o", "p.json",
         "--preset", "modestpy"],
    )  # fmt: skip
    assert fit.exit_code == 0, fit.output
    params = json.loads(Path("p.json").read_text())
    assert params["model"] == "basic+wind_infiltration"
    assert params["parameters"]["ach_wind"]["value"] == pytest.approx(0.1, rel=0.2)
    both = runner.invoke(
        cli.app, ["fit", "data.csv", "-b", "b.json", "-m", "basic", "--model-file", "m.json",
                  "-o", "p.json"],
    )  # fmt: skip
    assert both.exit_code == 2 and "either --model or --model-file" in both.output
    wrong = runner.invoke(
        cli.app, ["fit", "data.csv", "-b", "b.json", "--model-file", "p.json", "-o", "q.json"]
    )
    assert wrong.exit_code == 2 and "not a model specification" in wrong.output
    # A finding the diagnosis refitted but did not accept, saved by name.
    rejected = wind_report()
    rejected["findings"][0] |= {"accepted": False, "model": dict(rejected.pop("final"))}
    rejected["final"] = {
        **rejected["findings"][0]["model"],
        "network": get_model("basic", BUILDING).to_dict(),
    }
    fake = SimpleNamespace(to_dict=lambda: rejected, findings=[], wall_time_s=0.1)
    monkeypatch.setattr(selection, "diagnose", lambda *a, **k: fake)
    named = runner.invoke(cli.app, [*save[:-1], "n.json", "--finding", "wind_infiltration"])
    assert named.exit_code == 0, named.output
    assert ModelSpec.load("n.json").effects == ("wind_infiltration",)
    assert ModelSpec.load("n.json").source["accepted"] is False
    alone = runner.invoke(cli.app, [*save[:-2], "--finding", "wind_infiltration"])
    assert alone.exit_code == 2 and "needs --save-model" in alone.output
    unknown = runner.invoke(cli.app, [*save[:-1], "u.json", "--finding", "windows"])
    assert unknown.exit_code == 2 and "--finding names an effect of" in unknown.output
