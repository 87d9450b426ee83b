"""Candidate physics: one physically shaped extension of the RC network per effect id.

Each candidate builds, from the data and the building JSON, what the model would need to represent
one missing effect — a new input with a bounded gain, a new node, or a new resistance to a new
boundary temperature — or says why it cannot be built (its inputs are missing). The effect ids are
the contract's vocabulary (CONTRACT.md §3).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import Q_HVAC, T_OUT, WIND_SPEED
from rcengine.dataset import Dataset
from rcengine.diagnose.response import (
    explain_residual,
    node_responses,
    on_off_explainer,
    parameter_sensitivities,
)
from rcengine.network import Parameter, RCNetwork
from rcengine.signals import SignalOptions
from rcengine.signals.derived import T_REF_C
from rcengine.signals.schedules import (
    CLOCKS,
    N_DAY_TYPES,
    clock_zone,
    day_type_hour,
    describe,
    on_hours,
    weekly_from_day_types,
)
from rcengine.signals.solar import orientation_key

AIR_HEAT_CAPACITY_J_M3K = 1.2 * 1005.0
# Shares of the learnt profile's peak tried as the on/off threshold of a schedule.
ON_SHARES = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
# Dates of a day type the training period must hold before a schedule may switch on in it.
MIN_REPEATS = 2


@dataclass(frozen=True)
class Extension:
    """The extended network, the signal options it needs, its new parameters and the facts an
    explanation quotes (orientations, areas, schedules ...)."""

    effect: str
    network: RCNetwork
    signals: SignalOptions
    new_parameters: tuple[str, ...]
    inputs: tuple[tuple[str, str], ...] = ()  # (signal, node) of new heat inputs, for screening
    structural: bool = False  # changes the dynamics (new node / re-routing), screened by a refit
    learnt: bool = False  # its input's shape is learnt from the residual (refined after a refit)
    # Values of the new parameters at which the extension does nothing: the refit's warm start
    # then contains the current model itself, so it can only improve on it.
    neutral: dict[str, float] = field(default_factory=dict)
    detail: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Skipped:
    effect: str
    reason: str


@dataclass(frozen=True)
class Context:
    """What a candidate may look at: the current model and the training data and errors."""

    network: RCNetwork
    building: Building
    data: Dataset  # training period with the current model's signals
    signals: SignalOptions
    params: dict[str, float]  # the current model's fitted parameters
    residual: np.ndarray  # open-loop simulation error on ``data`` (measured − simulated) [K]

    @property
    def train(self) -> pd.DataFrame:
        return self.data.frame

    @cached_property
    def sensitivities(self) -> np.ndarray:
        """∂y/∂ln p of the current model on the training period (T, n_params). [K]"""
        return parameter_sensitivities(self.network, self.params, self.data)


def _name(net: RCNetwork, effect: str) -> str:
    return f"{net.name}+{effect}"


def envelope_node(net: RCNetwork) -> str:
    """The state exchanging directly with outdoors (wall), else the output node."""
    outside = [n for n in net.states if n != net.output and T_OUT in net.neighbours(n)]
    return outside[0] if outside else net.output


def mass_node(net: RCNetwork) -> str:
    """An interior state not touching outdoors (internal mass, floor), else the output node."""
    inside = [n for n in net.states if n != net.output and T_OUT not in net.neighbours(n)]
    return inside[0] if inside else net.output


def _has_signal(net: RCNetwork, prefix: str) -> bool:
    return any(s.startswith(prefix) for s in net.signals)


def _facade(azimuth: float, tilt: float) -> str:
    if tilt < 30:
        return "roof"
    names = [
        "north",
        "north-east",
        "east",
        "south-east",
        "south",
        "south-west",
        "west",
        "north-west",
    ]
    return names[int(((azimuth % 360) + 22.5) // 45) % 8]


def _solar_by_orientation(
    ctx: Context,
    effect: str,
    kind: str,
    target: str,
    upper: float,
    meaning: Callable[[str, float], str],
) -> Extension:
    """One gain per orientation of the building's ``kind`` surfaces ("window" or "opaque"),
    feeding ``solar_<kind>_<orientation>`` (irradiance × area [W]) into ``target``."""
    surfaces = ctx.building.windows if kind == "window" else ctx.building.walls
    net = ctx.network.copy(_name(ctx.network, effect))
    groups: dict[str, tuple[str, float]] = {}
    for s in surfaces:
        key = orientation_key(s.azimuth, s.tilt)
        area = groups.get(key, ("", 0.0))[1] + s.area
        groups[key] = (_facade(s.azimuth, s.tilt), area)
    params, inputs = [], []
    for key, (facade, area) in groups.items():
        name = f"{'g' if kind == 'window' else 'a'}_{kind}_{key}"
        net.add_parameter(Parameter(name, "-", 0.0, upper, meaning(facade, area)))
        signal = f"solar_{kind}_{key}"
        net.add_heat_input(signal, target, name)
        params.append(name)
        inputs.append((signal, target))
    detail = {
        "orientations": {k: {"area_m2": a, "facade": f} for k, (f, a) in groups.items()},
        "node": target,
    }
    return Extension(
        effect,
        net,
        ctx.signals,
        tuple(params),
        tuple(inputs),
        neutral=dict.fromkeys(params, 0.0),
        detail=detail,
    )


def window_solar_gains(ctx: Context) -> Extension | Skipped:
    """Solar heat through the glazing, one gain per façade orientation, into the interior mass."""
    effect = "window_solar_gains"
    if not ctx.building.windows:
        return Skipped(effect, "no windows in the building JSON")
    if _has_signal(ctx.network, "solar_window"):
        return Skipped(effect, "the model already has window solar gains")
    ext = _solar_by_orientation(
        ctx,
        effect,
        "window",
        mass_node(ctx.network),
        0.9,
        lambda facade, area: (
            f"share of the irradiance on the {facade} glazing ({area:g} m²) "
            "that heats the zone (solar heat gain coefficient)"
        ),
    )
    if T_OUT in ctx.network.neighbours(ctx.network.output):
        return ext
    # Glazing is also a massless conductance between the air and outdoors; a model whose only
    # path outdoors runs through the wall capacity cannot take the windows in without it.
    glazing = sum(w.area for w in ctx.building.windows)
    ext.network.add_parameter(
        Parameter(
            "r_window",
            "m²K/W",
            0.1,
            100.0,
            f"thermal resistance of the glazing ({glazing:g} m²), surface films included",
        )
    )
    ext.network.add_resistor(T_OUT, ctx.network.output, "r_window", factor=1.0 / glazing)
    return replace(
        ext,
        new_parameters=(*ext.new_parameters, "r_window"),
        neutral={**ext.neutral, "r_window": 100.0},
        detail={**ext.detail, "glazing_area_m2": glazing},
    )


def opaque_solar_gains(ctx: Context) -> Extension | Skipped:
    """Solar absorbed on the opaque walls and roof by orientation (sol-air), into the envelope."""
    effect = "opaque_solar_gains"
    if not ctx.building.walls:
        return Skipped(effect, "no opaque walls ('walls') in the building JSON")
    if _has_signal(ctx.network, "solar_opaque"):
        return Skipped(effect, "the model already has opaque solar gains")
    return _solar_by_orientation(
        ctx,
        effect,
        "opaque",
        envelope_node(ctx.network),
        0.3,
        lambda facade, area: (
            f"share of the irradiance on the {facade} opaque surfaces "
            f"({area:g} m²) reaching the envelope node (absorptance × inward fraction)"
        ),
    )


def wind_infiltration(ctx: Context) -> Extension | Skipped:
    """Air leakage growing with wind speed: loss = k · wind · (T_in − t_out)."""
    effect = "wind_infiltration"
    if WIND_SPEED not in ctx.train.columns or not ctx.train[WIND_SPEED].notna().any():
        return Skipped(effect, "no wind_speed column in the data")
    net = ctx.network.copy(_name(ctx.network, effect))
    upper = AIR_HEAT_CAPACITY_J_M3K * ctx.building.volume / 3600.0  # 1 air change/h per m/s
    net.add_parameter(
        Parameter(
            "k_wind",
            "W/(K·m/s)",
            0.0,
            upper,
            f"infiltration conductance per m/s of wind: loss = k·wind·({T_REF_C:g} °C − t_out)",
        )
    )
    net.add_heat_input("wind_loss", net.output, "k_wind")
    detail = {"volume_m3": ctx.building.volume}
    return Extension(
        effect,
        net,
        ctx.signals,
        ("k_wind",),
        (("wind_loss", net.output),),
        neutral={"k_wind": 0.0},
        detail=detail,
    )


@dataclass(frozen=True)
class LearntSchedule:
    """A 0/1 weekly schedule (168,), the clock it runs on and the residual share it explains."""

    schedule: np.ndarray
    clock: str
    explained: float

    @property
    def words(self) -> str:
        clock = "" if self.clock == "local" else ", standard time all year (no daylight saving)"
        return f"{describe(self.schedule)}{clock}"


def _learnt_schedule(ctx: Context, node: str, per_unit: np.ndarray) -> LearntSchedule:
    """0/1 weekly schedule of a missing input ``θ · schedule(t) · per_unit(t)`` at ``node``.

    Learnt on both clocks a building may keep (civil time or standard time all year) unless the
    model already plays a schedule on one; the clock whose schedule explains more is kept.
    """
    learnt = [_schedule_on_clock(ctx, node, per_unit, clock) for clock in _clocks(ctx)]
    return max(learnt, key=lambda s: s.explained)


def _clocks(ctx: Context) -> tuple[str, ...]:
    """The clocks worth learning on: the model's own if it plays a schedule already, only the
    civil one when the training period has no daylight saving (both read the same hours)."""
    if ctx.signals.schedules:
        return (ctx.signals.schedule_clock,)
    tz = ctx.building.location.timezone
    standard = day_type_hour(ctx.data.times, clock_zone(tz, "standard"))
    return ("local",) if np.array_equal(day_type_hour(ctx.data.times, tz), standard) else CLOCKS


def _schedule_on_clock(ctx: Context, node: str, per_unit: np.ndarray, clock: str) -> LearntSchedule:
    """The schedule on one clock, in three steps.

    1. θ_h ≥ 0 for every hour of the three day types of building schedules (weekdays, Saturday,
       Sunday; a day type seen on fewer than two dates stays off) is the value that, passed
       through the fitted model's dynamics, best explains the training residual (a
       deconvolution: the raw residual is the missing heat smeared and delayed by the
       building's inertia), while the model's own parameters may move to undo what they had
       absorbed.
    2. The schedule is on where the smoothed θ exceeds a share of its peak, the share (0.2–0.8)
       whose on/off schedule explains the residual best.
    3. Its switching hours then move one hour at a time while that explains the residual better:
       smoothing blurs the edges, and an edge an hour off leaves a daily error twice a day.
    """
    data = ctx.data
    zone = clock_zone(ctx.building.location.timezone, clock)
    hour = day_type_hour(data.times, zone)
    heat = np.zeros((len(data), N_DAY_TYPES * 24))
    heat[np.arange(len(data)), hour] = per_unit
    # A weekly schedule is a pattern that repeats: a day type seen on one date only (the single
    # Saturday of a short record) would let the "schedule" absorb that day's episode.
    dates = data.times.tz_convert(zone).normalize()
    repeated = np.repeat(
        [dates[hour // 24 == k].nunique() >= MIN_REPEATS for k in range(N_DAY_TYPES)], 24
    )
    heat[:, ~repeated] = 0.0
    responses = node_responses(ctx.network, ctx.params, data, node, heat)
    theta = np.zeros(N_DAY_TYPES * 24)
    if repeated.any():
        theta[repeated] = explain_residual(
            ctx.residual, responses[:, repeated], ctx.sensitivities
        )[0]
    # Neighbouring hours share a schedule; the mean over three damps least squares' spiky
    # solutions, which would otherwise set the peak (each day type wraps around midnight).
    days = theta.reshape(N_DAY_TYPES, 24)
    profile = ((np.roll(days, 1, axis=1) + days + np.roll(days, -1, axis=1)) / 3.0).ravel()
    explained = on_off_explainer(ctx.residual, responses, ctx.sensitivities)
    start = max((on_hours(profile, share) for share in ON_SHARES), key=explained)
    best = _move_edges(start, explained)
    return LearntSchedule(weekly_from_day_types(best), clock, explained(best))


def _move_edges(
    schedule: np.ndarray, explained: Callable[[np.ndarray], float], min_gain: float = 0.005
) -> np.ndarray:
    """Flip the switching hour (of the (72,) day-type schedule) that most raises ``explained``,
    repeatedly, while it raises it by more than ``min_gain`` of its value."""
    schedule, value = schedule.copy(), explained(schedule)
    while True:
        days = schedule.reshape(N_DAY_TYPES, 24)
        edge = (days != np.roll(days, 1, axis=1)) | (days != np.roll(days, -1, axis=1))
        trials = []
        for h in np.flatnonzero(edge.ravel()):
            flipped = schedule.copy()
            flipped[h] = 1.0 - flipped[h]
            trials.append((explained(flipped), h))
        best, h = max(trials, default=(0.0, -1))
        if best <= value * (1.0 + min_gain):
            return schedule
        schedule[h], value = 1.0 - schedule[h], best


def ventilation_schedule(ctx: Context) -> Extension | Skipped:
    """Outdoor-air ventilation in the hours the residuals show an extra loss that grows with
    the indoor–outdoor difference: loss = h · schedule · (T_in − t_out)."""
    effect = "ventilation_schedule"
    if "vent_loss" in ctx.network.signals:
        return Skipped(effect, "the model already has a ventilation schedule")
    outdoor_excess = ctx.train[T_OUT].to_numpy(dtype=float) - T_REF_C
    learnt = _learnt_schedule(ctx, ctx.network.output, outdoor_excess)
    if not learnt.schedule.any():
        return Skipped(effect, "the residuals show no weekly pattern of extra heat loss")
    signals = replace(
        ctx.signals,
        schedules={**ctx.signals.schedules, "vent": learnt.schedule.tolist()},
        schedule_clock=learnt.clock,
    )
    net = ctx.network.copy(_name(ctx.network, effect))
    upper = AIR_HEAT_CAPACITY_J_M3K * ctx.building.volume * 10.0 / 3600.0  # 10 air changes/h
    net.add_parameter(
        Parameter(
            "h_vent",
            "W/K",
            0.0,
            upper,
            f"ventilation conductance in the scheduled hours (loss = h · ({T_REF_C:g} °C − t_out))",
        )
    )
    net.add_heat_input("vent_loss", net.output, "h_vent")
    detail = {"schedule": learnt.words, "clock": learnt.clock, "volume_m3": ctx.building.volume}
    return Extension(
        effect,
        net,
        signals,
        ("h_vent",),
        (("vent_loss", net.output),),
        learnt=True,
        neutral={"h_vent": 0.0},
        detail=detail,
    )


def unmetered_gains(ctx: Context) -> Extension | Skipped:
    """Internal gains missing from the data, on the weekly schedule the residuals reveal."""
    effect = "unmetered_gains"
    if "sched_gains" in ctx.network.signals:
        return Skipped(effect, "the model already has an unmetered-gain schedule")
    learnt = _learnt_schedule(ctx, ctx.network.output, np.ones(len(ctx.data)))
    if not learnt.schedule.any():
        return Skipped(effect, "the residuals show no weekly pattern of missing heat")
    signals = replace(
        ctx.signals,
        schedules={**ctx.signals.schedules, "gains": learnt.schedule.tolist()},
        schedule_clock=learnt.clock,
    )
    net = ctx.network.copy(_name(ctx.network, effect))
    net.add_parameter(
        Parameter(
            "q_unmetered",
            "W",
            0.0,
            60.0 * ctx.building.floor_area,
            "unmetered internal heat (equipment, people) in the scheduled hours",
        )
    )
    net.add_heat_input("sched_gains", net.output, "q_unmetered")
    detail = {
        "schedule": learnt.words,
        "clock": learnt.clock,
        "floor_area_m2": ctx.building.floor_area,
    }
    return Extension(
        effect,
        net,
        signals,
        ("q_unmetered",),
        (("sched_gains", net.output),),
        learnt=True,
        neutral={"q_unmetered": 0.0},
        detail=detail,
    )


def ground_coupling(ctx: Context) -> Extension | Skipped:
    """Heat exchange through the floor with the slowly varying ground temperature."""
    effect = "ground_coupling"
    if "t_ground" in ctx.network.signals:
        return Skipped(effect, "the model already has ground coupling")
    net = ctx.network.copy(_name(ctx.network, effect))
    floor = ctx.building.floor_area
    target = mass_node(net)
    net.add_parameter(
        Parameter(
            "r_ground",
            "m²K/W",
            0.05,
            50.0,
            "resistance between the floor/interior mass and the ground, per floor area",
        )
    )
    net.add_resistor("t_ground", target, "r_ground", factor=1.0 / floor)
    detail = {"node": target, "floor_area_m2": floor}
    return Extension(
        effect,
        net,
        ctx.signals,
        ("r_ground",),
        (("t_ground", target),),
        neutral={"r_ground": 50.0},
        detail=detail,
    )


def sky_radiation(ctx: Context) -> Extension | Skipped:
    """Long-wave loss of the envelope to the (cold, clear, night) sky: q = h · (T_sky − t_out)."""
    effect = "sky_radiation"
    if "sky_delta" in ctx.network.signals:
        return Skipped(effect, "the model already has sky radiation")
    net = ctx.network.copy(_name(ctx.network, effect))
    target = envelope_node(net)
    area = ctx.building.floor_area + ctx.building.wall_area  # roof + walls seeing the sky
    net.add_parameter(
        Parameter(
            "h_sky",
            "W/K",
            0.0,
            3.0 * area,
            "long-wave coupling of the envelope to the sky (≈ ε·h_r·F_sky·A)",
        )
    )
    net.add_heat_input("sky_delta", target, "h_sky")
    detail = {"node": target}
    return Extension(
        effect,
        net,
        ctx.signals,
        ("h_sky",),
        (("sky_delta", target),),
        neutral={"h_sky": 0.0},
        detail=detail,
    )


def thermal_mass(ctx: Context) -> Extension | Skipped:
    """A heat-storage state the model lacks, coupled to the indoor air."""
    effect = "thermal_mass"
    net = ctx.network.copy(_name(ctx.network, effect))
    floor = ctx.building.floor_area
    node = "mass_extra"
    net.add_parameter(
        Parameter(
            "c_mass_extra",
            "J/(K·m²)",
            1e3,
            1e6,
            "heat capacity of the added storage, per floor area",
        )
    )
    net.add_parameter(
        Parameter(
            "r_mass_extra",
            "m²K/W",
            1e-3,
            5.0,
            "resistance between the indoor air and the added storage",
        )
    )
    net.add_capacitor(node, "c_mass_extra", factor=floor)
    net.add_resistor(net.output, node, "r_mass_extra", factor=1.0 / floor)
    return Extension(
        effect,
        net,
        ctx.signals,
        ("c_mass_extra", "r_mass_extra"),
        structural=True,
        neutral={"c_mass_extra": 1e3, "r_mass_extra": 5.0},
        detail={"node": node},
    )


def emitter_dynamics(ctx: Context) -> Extension | Skipped:
    """HVAC heat reaching the air through an emitter (radiator, slab) with its own inertia."""
    effect = "emitter_dynamics"
    q = ctx.train[Q_HVAC].to_numpy(dtype=float) if Q_HVAC in ctx.train.columns else np.zeros(1)
    if not np.any(np.abs(q) > 0):
        return Skipped(effect, "q_hvac is zero throughout the training period")
    direct = [
        h for h in ctx.network.heat_inputs if h.signal == Q_HVAC and h.node == ctx.network.output
    ]
    if not direct:
        return Skipped(effect, "q_hvac does not enter the air node directly in this model")
    net = ctx.network.copy(_name(ctx.network, effect))
    floor = ctx.building.floor_area
    net.add_parameter(
        Parameter(
            "c_emitter",
            "J/(K·m²)",
            1e2,
            5e5,
            "heat capacity of the emitter (water, metal, screed), per floor area",
        )
    )
    net.add_parameter(
        Parameter(
            "r_emitter",
            "m²K/W",
            1e-3,
            1.0,
            "resistance between the emitter and the indoor air, per floor area",
        )
    )
    net.add_capacitor("emitter", "c_emitter", factor=floor)
    net.add_resistor("emitter", net.output, "r_emitter", factor=1.0 / floor)
    net.move_heat_input(Q_HVAC, net.output, "emitter")
    return Extension(
        effect,
        net,
        ctx.signals,
        ("c_emitter", "r_emitter"),
        structural=True,
        neutral={"c_emitter": 1e2, "r_emitter": 1e-3},
        detail={"node": "emitter"},
    )


CANDIDATES: dict[str, Callable[[Context], Extension | Skipped]] = {
    "window_solar_gains": window_solar_gains,
    "opaque_solar_gains": opaque_solar_gains,
    "wind_infiltration": wind_infiltration,
    "ventilation_schedule": ventilation_schedule,
    "ground_coupling": ground_coupling,
    "sky_radiation": sky_radiation,
    "unmetered_gains": unmetered_gains,
    "thermal_mass": thermal_mass,
    "emitter_dynamics": emitter_dynamics,
}
