"""Candidate physics: one physically shaped extension of the RC network per effect id.

Each candidate builds, from the data and the building JSON, what the model would need to represent
one missing effect — a new input with a bounded gain, a new node, or a new resistance to a new
boundary temperature — or says why it cannot be built (its inputs are missing). The effect ids are
the contract's vocabulary (CONTRACT.md §3).

Each enters where the physics puts it and is parameterised in physical units (g-value,
absorptance, air changes per hour, W/m² of floor, floor U-value, capacity per m²), searched
``plausibility.SEARCH_MARGIN`` past the range a real building allows, so that
``plausibility.assess`` can tell a fit that needs an impossible magnitude.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import (
    GAINS_SCHEDULE,
    Q_HVAC,
    Q_LIGHT,
    Q_OCC,
    SCHED_GAINS,
    SKY_DELTA,
    SOLAR_OPAQUE,
    SOLAR_WINDOW,
    T_GROUND,
    T_OUT,
    UNIT,
    VENT_LOSS,
    VENT_SCHEDULE,
    WIND_LOSS,
    WIND_SPEED,
    orientation_key,
    solar_orientation_signal,
)
from rcengine.dataset import Dataset
from rcengine.diagnose.plausibility import (
    ABSORPTANCE,
    EXTRA_CAPACITY_J_M2K,
    G_VALUE,
    SEARCH_MARGIN,
    SKY_COUPLING,
    SKY_H_R_TYPICAL,
    U_FLOOR,
    UNMETERED_W_M2,
    VENTILATION_ACH,
    WIND_ACH_PER_M_S,
)
from rcengine.diagnose.response import (
    explain_residual,
    node_responses,
    on_off_explainer,
    parameter_sensitivities,
)
from rcengine.diagnose.surfaces import SURFACE_NODE
from rcengine.models.bounds import (
    R_SE_SHELTERED,
    RHO_CP_AIR,
    U_OPAQUE,
    envelope,
    internal_resistance,
)
from rcengine.models.physical import steady_share
from rcengine.network import Parameter, RCNetwork
from rcengine.signals import SignalOptions
from rcengine.signals.derived import indoor_operating_point
from rcengine.signals.ground import (
    GROUND_LAGS_S,
    SOIL_CONDUCTIVITY,
    SOIL_HEAT_CAPACITY,
    YEAR_S,
    annual_cycle,
    annual_mean_uncertainty,
    ground_depth,
    ground_lag,
    seasonal_ground_temperature,
)
from rcengine.signals.schedules import (
    CLOCKS,
    N_DAY_TYPES,
    clock_zone,
    closed_weekdays,
    day_type_hour,
    describe,
    hour_of_week,
    on_hours,
    weekly_from_day_types,
)

# Shares of the learnt profile's peak tried as the on/off threshold of a schedule.
ON_SHARES = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
# Dates of a day type the training period must hold before a schedule may switch on in it.
MIN_REPEATS = 2
# A heater delivering at least this share of its largest output is at its capacity. [-]
SATURATION_SHARE = 0.97
# A heater at its largest output in more than this share of its heating rows is switched on/off
# at one stage: its output then says nothing about capacity. [-]
ON_OFF_SHARE = 0.5
# Share of an hour's rows with the heater at capacity beyond which no schedule may switch on in
# that hour (of a day type): most of its dates hold the heater's recovery. [-]
SATURATED_HOUR_SHARE = 0.5


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
    # Values at which it is absent altogether (the backward check's model without it), where
    # they lie outside its search box: a conduction path open (r = ∞), a node without capacity
    # joined to its neighbour (C = 0, r = 0); ``RCNetwork.fixed`` removes them. Default
    # ``neutral``.
    absent: dict[str, float] | None = None
    # Facts an explanation quotes and ``plausibility.assess`` reads (areas, volume, temperatures).
    detail: dict = field(default_factory=dict)
    # Other versions of the same physics with the same parameters (the soil read at another lag),
    # each refitted beside it and judged as a version of one effect (``selection._versions``).
    alternatives: tuple[Extension, ...] = ()
    # An alternative only the folds can choose (a shape that may fit one split and forecast
    # worse): left out of a diagnosis judged on a single split.
    folds_only: bool = False


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


def radiant_node(net: RCNetwork) -> str:
    """Where radiant heat lands: the interior surfaces where the model has them (``surfaces``),
    else the interior mass (``mass_node``)."""
    return SURFACE_NODE if SURFACE_NODE in net.nodes else mass_node(net)


def _has_wind(ctx: Context) -> bool:
    return WIND_SPEED in ctx.train.columns and bool(ctx.train[WIND_SPEED].notna().any())


def _through_the_film(ctx: Context) -> Context:
    """``ctx`` with the envelope's outer film varying with the wind where the data have a wind
    speed (``signals.film``): the film sets the share of an outer surface's sun that reaches
    the room, and a fixed film leaves the wind's part of it to a wind-driven leak."""
    if not _has_wind(ctx):
        return ctx
    return replace(ctx, signals=replace(ctx.signals, exterior_film="wind"))


def _has_signal(net: RCNetwork, prefix: str) -> bool:
    return any(s.startswith(prefix) for s in net.signals)


def _areas_by_orientation(surfaces: list) -> dict[str, float]:
    areas: dict[str, float] = {}
    for s in surfaces:
        key = orientation_key(s.azimuth, s.tilt)
        areas[key] = areas.get(key, 0.0) + s.area
    return areas


def _facade_tilt(key: str) -> float:
    return float(key.split("_")[1])


def _facade(key: str) -> str:
    """The facade an orientation key (``orientation_key``) names: a compass point, or "roof"."""
    azimuth, tilt = (float(v) for v in key.split("_"))
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


def facade_areas(building: Building) -> dict[str, float]:
    """Gross area of each orientation's surfaces, glazing and opaque: the most glazing an
    orientation could have. [m²]"""
    glazed, opaque = (_areas_by_orientation(s) for s in (building.windows, building.walls))
    return {k: glazed.get(k, 0.0) + opaque.get(k, 0.0) for k in {*glazed, *opaque}}


def window_solar_gains(ctx: Context) -> Extension | Skipped:
    """Solar heat through glazing beyond what the declared windows admit at one g-value, per
    orientation, absorbed where the radiant heat lands (``radiant_node``):

    - where windows are declared, an extra g-value g_k × the irradiance transmitted to them
      (``solar_window_<k>``: declared area × transmitted irradiance, incidence-angle modifier
      included), the implied g-value being the declared glazing's plus g_k;
    - on a facade with no declared window, the share s_k of the irradiance on its opaque
      surfaces (``solar_opaque_<k>``: area × plane-of-array irradiance) that glazing the
      description leaves out lets in, s_k = g × glazed share.

    The base model carries the declared glazing (``declared``); no orientation may admit more
    than clear glass over its whole facade (``plausibility``). Roofs take part only through
    declared roof windows: an undeclared skylight's sun cannot be told from the roof's own
    sol-air heat in a lumped model.
    """
    effect = "window_solar_gains"
    if _has_signal(ctx.network, f"{SOLAR_WINDOW}_"):
        return Skipped(effect, "the model already has window solar gains by orientation")
    glazed = _areas_by_orientation(ctx.building.windows)
    opaque = _areas_by_orientation(ctx.building.walls)
    undeclared = [k for k in opaque if k not in glazed and _facade_tilt(k) >= 30]
    if not glazed and not undeclared:
        return Skipped(effect, "no windows or facades ('windows', 'walls') in the building JSON")
    facades = facade_areas(ctx.building)
    target = radiant_node(ctx.network)
    net = ctx.network.copy(_name(ctx.network, effect))
    orientations, inputs = {}, []
    for key in [*glazed, *undeclared]:
        facade, declared = _facade(key), glazed.get(key, 0.0)
        if declared:
            signal, upper = SOLAR_WINDOW, facades[key] / declared
            meaning = (
                f"g-value the {facade} glazing ({declared:g} m²) adds to the declared glazing's"
            )
        else:
            signal, upper = SOLAR_OPAQUE, 1.0
            meaning = (
                f"share of the sun on the {facade} facade ({facades[key]:g} m², no window "
                "declared) let in by glazing the description leaves out: g × glazed share"
            )
        name = f"g_window_{key}"
        net.add_parameter(Parameter(name, "-", 0.0, SEARCH_MARGIN * G_VALUE[1] * upper, meaning))
        net.add_heat_input(solar_orientation_signal(signal, key), target, name)
        inputs.append((solar_orientation_signal(signal, key), target))
        orientations[key] = {
            "area_m2": declared,
            "facade": facade,
            "facade_m2": facades[key],
            "signal": solar_orientation_signal(signal, key),
            "signal_area_m2": declared or facades[key],
        }
    params = tuple(f"g_window_{k}" for k in orientations)
    return Extension(
        effect,
        net,
        ctx.signals,
        params,
        tuple(inputs),
        neutral=dict.fromkeys(params, 0.0),
        detail={"orientations": orientations, "node": target},
    )


def opaque_solar_gains(ctx: Context) -> Extension | Skipped:
    """Solar absorbed on the opaque walls and roof as sol-air (ISO 13790 Eq. 44): of the
    irradiance I_k on the A_k m² of an orientation's opaque surfaces, α·R_se·U·A_k·I_k reaches
    the indoor air in the steady state.

    The quantity fitted is the product α·U [W/(m²K)], once for the walls and once for the roof
    (surfaces tilted less than 30°): the description gives neither the surfaces' colour nor their
    U-value, and the lumped wall node's conductance is the envelope's average, not the sunlit
    part's (a dark, uninsulated cladding over a well insulated roof). The facades of one
    envelope part share one construction and one colour, so one α·U drives each orientation's
    own irradiance: the sun on four facades is one signal seen at four angles, and a product per
    orientation let a fit put the sun wherever the base model's errors lie (on the test bed's
    null buildings 1–8 W/(m²K) on one or two sunny facades, none on the others, and 6–16 % off
    their test error), which one envelope's sun cannot do. The sun ``solar_opaque_<k>``
    (A_k × plane-of-array irradiance [W]) enters the envelope node, scaled by R_se over the share
    of that node's heat that warms the room under the current fit (``steady_share``), so that
    its steady share is α·U·R_se. The data identify that share, not α·U: R_se is a sheltered
    facade's film (``R_SE_SHELTERED``, the most an outside film passes in), so the α·U fitted is
    the least the share can mean, and the plausibility checks reject only what no envelope could
    pass. Where the data have a wind speed the film follows it (``signals.film``, relative to
    that sheltered film): a windy day's film passes half a calm one's sun.
    """
    effect = "opaque_solar_gains"
    ctx = _through_the_film(ctx)
    if not ctx.building.walls:
        return Skipped(effect, "no opaque walls ('walls') in the building JSON")
    if _has_signal(ctx.network, SOLAR_OPAQUE):
        return Skipped(effect, "the model already has opaque solar gains")
    node = envelope_node(ctx.network)
    share = steady_share(ctx.network, ctx.params, node)
    if share <= 0.0:
        return Skipped(effect, f"no heat at '{node}' reaches the indoor air for sol-air to act on")
    net = ctx.network.copy(_name(ctx.network, effect))
    groups = {k: (_facade(k), a) for k, a in _areas_by_orientation(ctx.building.walls).items()}
    upper = SEARCH_MARGIN * ABSORPTANCE[1] * U_OPAQUE[1]
    params, inputs, part_of = [], [], {}
    for key, (facade, _) in groups.items():
        part = "roof" if facade == "roof" else "walls"
        name = f"au_opaque_{part}"
        part_of[key] = {"part": part, "parameter": name}
        meaning = f"solar absorptance × U-value of the opaque {part}"
        if name not in params:
            net.add_parameter(Parameter(name, "W/(m²K)", 0.0, upper, meaning))
            params.append(name)
        signal = solar_orientation_signal(SOLAR_OPAQUE, key)
        net.add_heat_input(signal, node, name, factor=R_SE_SHELTERED / share)
        inputs.append((signal, node))
    detail = {
        "orientations": {
            k: {"area_m2": a, "facade": f, **part_of[k]} for k, (f, a) in groups.items()
        },
        "node": node,
        "node_share": share,
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


def _with_gain(
    ctx: Context,
    effect: str,
    gain: Parameter,
    heat: tuple[str, str],
    detail: dict,
    factor: float = 1.0,
) -> Extension:
    """The current network plus one heat input, ``factor`` × ``gain`` × signal into node
    (``heat`` = (signal, node)) [W]. The gain's lower bound, zero, is where the extension does
    nothing."""
    signal, node = heat
    net = ctx.network.copy(_name(ctx.network, effect))
    net.add_parameter(gain)
    net.add_heat_input(signal, node, gain.name, factor=factor)
    return Extension(
        effect,
        net,
        ctx.signals,
        (gain.name,),
        (heat,),
        neutral={gain.name: gain.lower},
        detail=detail,
    )


def _air_change_loss(
    ctx: Context, effect: str, rate: str, unit: str, highest: float, meaning: str, loss: str
) -> Extension:
    """The current network plus an air-change rate ``rate`` [``unit``], searched from none up to
    SEARCH_MARGIN × the ``highest`` plausible rate, times the ``loss`` signal into the output
    node, each air change per hour through the zone a conductance of ρ·c_p·V/3600 [W/K]."""
    parameter = Parameter(rate, unit, 0.0, SEARCH_MARGIN * highest, meaning)
    heat = (loss, ctx.network.output)
    detail = {"volume_m3": ctx.building.volume}
    per_air_change = RHO_CP_AIR * ctx.building.volume / 3600.0  # [W/K per 1/h]
    return _with_gain(ctx, effect, parameter, heat, detail, per_air_change)


def wind_infiltration(ctx: Context) -> Extension | Skipped:
    """Air leakage growing with wind speed, in air changes per hour per m/s through the volume:
    loss = n_wind · ρc_pV/3600 · wind · (t_in − t_out), t_in the measured indoor temperature
    (``signals.derived.indoor_operating_point``)."""
    effect = "wind_infiltration"
    if not _has_wind(ctx):
        return Skipped(effect, "no wind_speed column in the data")
    return _air_change_loss(
        ctx,
        effect,
        "ach_wind",
        "1/h per m/s",
        WIND_ACH_PER_M_S[1],
        "air changes per hour per m/s of wind: loss = n·ρc_pV/3600·wind·(t_in − t_out)",
        WIND_LOSS,
    )


@dataclass(frozen=True)
class LearntSchedule:
    """A 0/1 weekly schedule (168,), the clock it runs on and the residual share it explains."""

    schedule: np.ndarray
    clock: str
    explained: float
    closed_days: int = 0  # weekdays of the training period without occupants, on Sunday's hours

    @property
    def words(self) -> str:
        clock = "" if self.clock == "local" else ", standard time all year (no daylight saving)"
        closed = (
            f"; {self.closed_days} weekdays without occupants on Sunday's hours"
            if self.closed_days
            else ""
        )
        return f"{describe(self.schedule)}{clock}{closed}"


def _learnt_schedule(
    ctx: Context, node: str, per_unit: np.ndarray, saturated: np.ndarray
) -> LearntSchedule:
    """0/1 weekly schedule of a missing input ``θ · schedule(t) · per_unit(t)`` at ``node``,
    learnt outside the rows where the heater is ``saturated`` (see ``_schedule_on_clock``).

    Learnt on both clocks a building may keep (civil time or standard time all year) unless the
    model already plays a schedule on one; the clock whose schedule explains more is kept.
    """
    learnt = [_schedule_on_clock(ctx, saturated, node, per_unit, clock) for clock in _clocks(ctx)]
    return max(learnt, key=lambda s: s.explained)


def heater_saturated(frame: pd.DataFrame) -> np.ndarray:
    """Rows where ``q_hvac`` sits at the heater's capacity: within ``SATURATION_SHARE`` of its
    largest output, unless that is how the heater always runs (``ON_OFF_SHARE``).

    A heater at capacity leaves the room under its setpoint in a pattern that repeats every cold
    morning; its recovery is metered physics, not a schedule, and learning a schedule of missing
    heat from those rows would name it a missing gain.
    """
    if Q_HVAC not in frame.columns:
        return np.zeros(len(frame), dtype=bool)
    q = np.nan_to_num(frame[Q_HVAC].to_numpy(dtype=float))
    peak = q.max(initial=0.0)
    at_peak = q >= SATURATION_SHARE * peak
    heating = q > (1.0 - SATURATION_SHARE) * peak
    if peak <= 0.0 or at_peak.sum() > ON_OFF_SHARE * heating.sum():
        return np.zeros(len(frame), dtype=bool)
    return at_peak


def _clocks(ctx: Context) -> tuple[str, ...]:
    """The clocks worth learning on: the model's own if it plays a schedule already, only the
    civil one when the training period has no daylight saving (both read the same hours)."""
    if ctx.signals.schedules:
        return (ctx.signals.schedule_clock,)
    tz = ctx.building.location.timezone
    zones = [clock_zone(tz, clock) for clock in CLOCKS]
    local, standard = (
        day_type_hour(ctx.data.times, z, closed_weekdays(ctx.train, z)) for z in zones
    )
    return ("local",) if np.array_equal(local, standard) else CLOCKS


def _schedule_on_clock(
    ctx: Context, saturated: np.ndarray, node: str, per_unit: np.ndarray, clock: str
) -> LearntSchedule:
    """The schedule on one clock, in three steps, learnt from the training residual outside the
    rows where the heater is ``saturated`` (``heater_saturated``) and never switching on in an
    hour of a day type where the heater is at capacity on most dates.

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
    closed = closed_weekdays(data.frame, zone)
    hour = day_type_hour(data.times, zone, closed)
    heat = np.zeros((len(data), N_DAY_TYPES * 24))
    heat[np.arange(len(data)), hour] = per_unit
    # A weekly schedule is a pattern that repeats: a day type seen on one date only (the single
    # Saturday of a short record) would let the "schedule" absorb that day's episode.
    dates = data.times.tz_convert(zone).normalize()
    repeated = np.repeat(
        [dates[hour // 24 == k].nunique() >= MIN_REPEATS for k in range(N_DAY_TYPES)], 24
    )
    # A heater at capacity leaves the same deficit every cold morning; an hour that holds that
    # recovery on most of its dates cannot be told apart from it.
    rows = np.bincount(hour, minlength=N_DAY_TYPES * 24)
    at_capacity = np.bincount(hour, weights=saturated, minlength=N_DAY_TYPES * 24)
    allowed = repeated & (at_capacity < SATURATED_HOUR_SHARE * rows)
    heat[:, ~allowed] = 0.0
    residual = np.where(saturated, np.nan, ctx.residual)
    responses = node_responses(ctx.network, ctx.params, data, node, heat)
    theta = np.zeros(N_DAY_TYPES * 24)
    if allowed.any():
        theta[allowed] = explain_residual(residual, responses[:, allowed], ctx.sensitivities)[0]
    # Neighbouring hours share a schedule; the mean over three damps least squares' spiky
    # solutions, which would otherwise set the peak (each day type wraps around midnight).
    days = theta.reshape(N_DAY_TYPES, 24)
    profile = ((np.roll(days, 1, axis=1) + days + np.roll(days, -1, axis=1)) / 3.0).ravel()
    explained = on_off_explainer(residual, responses, ctx.sensitivities)
    start = max((on_hours(profile, share) * allowed for share in ON_SHARES), key=explained)
    best = _move_edges(start, explained) * allowed
    closed_days = data.times[closed].tz_convert(zone).normalize().nunique()
    return LearntSchedule(weekly_from_day_types(best), clock, explained(best), closed_days)


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


def _on_schedule(ext: Extension, name: str, learnt: LearntSchedule) -> Extension:
    """``ext`` with its input played on the weekly schedule ``name``, learnt from the residual
    (and learnt again after each refit)."""
    signals = replace(
        ext.signals,
        schedules={**ext.signals.schedules, name: learnt.schedule.tolist()},
        schedule_clock=learnt.clock,
    )
    detail = {"schedule": learnt.words, "clock": learnt.clock, **ext.detail}
    return replace(ext, signals=signals, learnt=True, detail=detail)


def ventilation_schedule(ctx: Context) -> Extension | Skipped:
    """Outdoor-air ventilation in the hours the residuals show an extra loss that grows with
    the indoor–outdoor difference: loss = h · schedule · (T_in − t_out)."""
    effect = "ventilation_schedule"
    if VENT_LOSS in ctx.network.signals:
        return Skipped(effect, "the model already has a ventilation schedule")
    outdoor_excess = ctx.train[T_OUT].to_numpy(dtype=float) - indoor_operating_point(ctx.train)
    # A missing loss may itself drive the heater to its capacity: those rows are evidence.
    saturated = np.zeros(len(ctx.data), dtype=bool)
    learnt = _learnt_schedule(ctx, ctx.network.output, outdoor_excess, saturated)
    if not learnt.schedule.any():
        return Skipped(effect, "the residuals show no weekly pattern of extra heat loss")
    meaning = "air changes per hour in the scheduled hours (loss = n·ρc_pV/3600·(t_in − t_out))"
    ext = _air_change_loss(ctx, effect, "ach_vent", "1/h", VENTILATION_ACH[1], meaning, VENT_LOSS)
    return _on_schedule(ext, VENT_SCHEDULE, learnt)


# The unmetered gain's parameter, in either version (learnt schedule, metered use).
Q_UNMETERED = "q_unmetered"


def _unmetered_per_floor(name: str, meaning: str) -> Parameter:
    """An unmetered heat per m² of floor [W/m²], searched from none to past a dense floor's."""
    return Parameter(name, "W/m²", 0.0, SEARCH_MARGIN * UNMETERED_W_M2[1], meaning)


def _q_unmetered(hours: str) -> Parameter:
    meaning = f"unmetered internal heat (equipment, people) in the {hours} hours, per m² of floor"
    return _unmetered_per_floor(Q_UNMETERED, meaning)


def unmetered_gains(ctx: Context) -> Extension | Skipped:
    """Internal gains missing from the data, on the weekly schedule the residuals reveal, and,
    as its alternative, in step with the metered use of the building (``_gains_with_use``;
    where the residuals show no schedule, that version alone)."""
    effect = "unmetered_gains"
    if any(h.gain == Q_UNMETERED for h in ctx.network.heat_inputs):
        return Skipped(effect, "the model already has unmetered gains")
    # A missing gain would lighten the heater's load; a heater at capacity is evidence of the
    # opposite, and its recovery (metered) must not be learnt as a gain.
    saturated = heater_saturated(ctx.train)
    learnt = _learnt_schedule(ctx, ctx.network.output, np.ones(len(ctx.data)), saturated)
    with_use = _gains_with_use(ctx)
    uses = () if with_use is None else (with_use, _with_base_load(ctx, with_use))
    if not learnt.schedule.any():
        if not uses:
            return Skipped(effect, "the residuals show no weekly pattern of missing heat")
        return replace(uses[0], alternatives=uses[1:])
    floor = ctx.building.floor_area
    heat = (SCHED_GAINS, ctx.network.output)
    on = _on_learnt_hours(ctx, learnt)
    detail = {
        "floor_area_m2": floor,
        **occupied_shares(ctx, on),
        **metered_gains_on_schedule(ctx, on),
    }
    ext = _with_gain(ctx, effect, _q_unmetered("scheduled"), heat, detail, floor)
    ext = _on_schedule(ext, GAINS_SCHEDULE, learnt)
    return replace(ext, alternatives=(_with_base_load(ctx, ext), *uses))


# The unmetered gain's load at every hour, beside its scheduled or metered-use part.
Q_BASE_LOAD = "q_base_load"


def _with_base_load(ctx: Context, ext: Extension) -> Extension:
    """``ext`` plus the unmetered equipment's base load: q_base_load·A_floor into the air at
    every hour [W], a version of the same effect that only the folds choose.

    Plug loads never fall to zero (servers, network, refrigeration, standby): the reference
    office's equipment schedule keeps 0.4 of its 0.9 occupied level through nights and weekends
    (DOE commercial reference buildings, ASHRAE 90.1 User's Manual). A gain played on the
    occupied hours alone is gone over the nights and closures that still carry it, and the
    model's other parameters answer for it there: a heavy Torino office's two weeks of
    Christmas closure were forecast 0.33 K off with the gain in step with the use, against
    0.07 K without it, and the effect failed the folds. A base load free beside the scheduled
    part is a second way to spread the same weekly heat, which a lumped model tells apart
    poorly: on a single split it can trade the one for the other and forecast worse (an open
    plan's learnt office hours, 8.4 W/m², read as 1.9 W/m² on the use plus 1.7 at every hour,
    test RMSE 0.50 K against 0.37), so only the folds may prefer it (``folds_only``)."""
    floor = ctx.building.floor_area
    net = ext.network.copy(ext.network.name)
    meaning = "unmetered internal heat at every hour (equipment left on), per m² of floor"
    net.add_parameter(_unmetered_per_floor(Q_BASE_LOAD, meaning))
    net.add_heat_input(UNIT, net.output, Q_BASE_LOAD, factor=floor)
    return replace(
        ext,
        network=net,
        new_parameters=(*ext.new_parameters, Q_BASE_LOAD),
        inputs=(*ext.inputs, (UNIT, net.output)),
        neutral={**ext.neutral, Q_BASE_LOAD: 0.0},
        detail={**ext.detail, "base_load": True},
        alternatives=(),
        folds_only=True,
    )


def _gains_with_use(ctx: Context) -> Extension | None:
    """Unmetered gains that follow the building's metered use (equipment switched on with the
    people and lights, the usual plug loads): q(t) = q_unmetered·A_floor·m(t)/m̄ into the air,
    m = q_occ + q_light [W] and m̄ its mean over the training rows with occupants metered
    (q_occ > 0), so that q_unmetered is the gain's mean over the occupied hours [W/m²]. A
    schedule learnt from the residuals can take the hours the base model errs in rather than
    the gain's (a heavy building's residual holds little of a daytime gain's shape); the metered
    use gives the shape without learning it. None without occupants metered.

    Only the folds choose it over the learnt schedule (``folds_only``): on a single split the
    unmetered variant's record before February took it by both the split's test and the
    training fit, and its adopted model served the first week of February a day-ahead forecast
    0.395 K off, against 0.342 K with the learnt schedule."""
    occupied = _occupied(ctx)
    if occupied is None:
        return None
    metered = metered_gains_on_schedule(ctx, occupied)  # m̄ / A_floor, where m̄ > 0
    if not metered:
        return None
    columns = _metered_columns(ctx)
    net = ctx.network.copy(_name(ctx.network, "unmetered_gains"))
    gain = _q_unmetered("occupied")
    net.add_parameter(gain)
    for column in columns:
        net.add_heat_input(column, net.output, gain.name, factor=1.0 / metered["metered_w_m2"])
    detail = {
        "floor_area_m2": ctx.building.floor_area,
        "follows": " + ".join(columns),
        **occupied_shares(ctx, occupied),
        **metered,
    }
    return Extension(
        "unmetered_gains",
        net,
        ctx.signals,
        (gain.name,),
        tuple((c, net.output) for c in columns),
        neutral={gain.name: 0.0},
        detail=detail,
        folds_only=True,
    )


def _on_learnt_hours(ctx: Context, learnt: LearntSchedule) -> np.ndarray:
    """The training rows the ``learnt`` schedule is on."""
    zone = clock_zone(ctx.building.location.timezone, learnt.clock)
    closed = closed_weekdays(ctx.train, zone)
    return learnt.schedule[hour_of_week(ctx.data.times, zone, closed)] > 0.0


def _occupied(ctx: Context) -> np.ndarray | None:
    """The training rows in which occupants are metered (``q_occ`` > 0); None without a
    ``q_occ`` column."""
    if Q_OCC not in ctx.train.columns:
        return None
    return np.nan_to_num(ctx.train[Q_OCC].to_numpy(dtype=float)) > 0.0


def _metered_columns(ctx: Context) -> list[str]:
    """The metered internal gains the record has: ``q_occ`` and ``q_light``, where given."""
    return [c for c in (Q_OCC, Q_LIGHT) if c in ctx.train.columns]


def occupied_shares(ctx: Context, on: np.ndarray) -> dict[str, float]:
    """Shares of the training rows in which occupants are metered (``q_occ`` > 0): of those a
    learnt schedule is ``on`` (``occupied_share``) and of all (``occupied_share_all``) [-]; empty
    without a ``q_occ`` column, or when it meters no occupant."""
    occupied = _occupied(ctx)
    if occupied is None or not occupied.any() or not on.any():
        return {}
    share, share_all = float(occupied[on].mean()), float(occupied.mean())
    return {"occupied_share": share, "occupied_share_all": share_all}


def metered_gains_on_schedule(ctx: Context, on: np.ndarray) -> dict[str, float]:
    """The metered internal gains (``q_occ`` + ``q_light``) per m² of floor, averaged over the
    training rows a learnt schedule is ``on`` (``metered_w_m2``) [W/m²]; empty without either
    column or when they meter nothing there."""
    columns = _metered_columns(ctx)
    if not columns or not on.any():
        return {}
    metered = sum(np.nan_to_num(ctx.train[c].to_numpy(dtype=float)) for c in columns)
    level = float(np.mean(metered[on])) / ctx.building.floor_area
    return {"metered_w_m2": level} if level > 0.0 else {}


# The layer of soil between a floor on the ground and the soil read, whose storage a heated slab
# charges over days and gets back through a holiday or a cold snap: ISO 52016-1 takes a virtual
# layer of 0.5 m (the warm start); its depth is fitted from a bed of fill (0.1 m) to 2 m, about
# where the annual wave is read (1.66 m at a month's lag, 2.49 m at a month and a half). The soil
# is ISO 13370's sand or gravel (``SOIL_CONDUCTIVITY``, ``SOIL_HEAT_CAPACITY``): the periodic
# penetration depth of a month's swing in it, √(λ·P/(π·ρc)), is 0.9 m, so the weeks of a heating
# season reach about a metre down. [m]
SOIL_LAYER_DEPTH = (0.1, 2.0)
SOIL_LAYER_DEPTH_ISO = 0.5


def ground_coupling(ctx: Context) -> Extension | Skipped:
    """Heat exchange through the floor with the soil under it, into the interior mass.

    q = U_floor·A_floor·(T_base(t) + ΔT − T_mass), with U_floor = 1/r_floor, A_floor the
    footprint (``Building.footprint_area``: the storeys above stand on the ground floor) and
    T_base the outdoor annual cycle damped and lagged into the soil (``signals.ground``, signal
    t_ground); the soil's warming by the building, ΔT, is fitted as the constant heat q_ground =
    U_floor·ΔT per m² of ground floor on the ``unit`` signal, so the fitted ground temperature is
    T_base + q·r.
    The lag depends on the floor's insulation, which the building description does not give:
    the soil is read at the model's lag (a month by default), and at ISO 13370's other lags
    (``GROUND_LAGS_S``) as alternatives. Each lag is also offered through a layer of soil between
    the floor and the soil read, its depth fitted (``SOIL_LAYER_DEPTH``; ISO 52016-1 fixes 0.5 m):
    a heated slab warms the soil under it over days and gets that heat back when the heating
    stops (a holiday, a cold snap), which a floor straight onto its boundary temperature
    answers at once; without the layer, a storage added to the air (``thermal_mass``) took that
    part first and the ground was read at a soil colder than any. With ISO 52016-1's 0.5 m, a
    test bed's bare Chicago slab on 1 m of soil (``testbed_sealed_29``) was still read at 3.9 °C,
    colder than any soil; through its fitted 1.1 m it reads 12.0 °C, U 0.94 W/(m²K).
    """
    effect = "ground_coupling"
    if T_GROUND in ctx.network.signals:
        return Skipped(effect, "the model already has ground coupling")
    own = ctx.signals.ground_depth_m
    depths = [ground_depth(lag) for lag in GROUND_LAGS_S]
    depths = [own, *(z for z in depths if not np.isclose(z, own))]
    readings = list(zip(depths, _ground_temperatures(ctx, depths), strict=True))
    first, *others = (
        _ground_at(ctx, replace(ctx.signals, ground_depth_m=z), soil, layer)
        for layer in (False, True)
        for z, soil in readings
    )
    return replace(first, alternatives=tuple(others))


def _ground_at(
    ctx: Context, signals: SignalOptions, soil: dict[str, float], layer: bool
) -> Extension:
    """``ground_coupling`` with the soil read at ``signals.ground_depth_m``, judged against
    ``soil`` (``_ground_temperatures`` at that depth); with ``layer``, through a layer of soil
    d_soil deep under the floor (R = d/λ, C = ρc·d per m² of footprint), whose own storage a slab
    on the ground charges over days and gives back through a holiday."""
    effect = "ground_coupling"
    net = ctx.network.copy(_name(ctx.network, effect))
    footprint = ctx.building.footprint_area
    target = mass_node(net)
    # The node the floor reaches the soil at: the soil read, or the layer's own.
    soil_side = "soil" if layer else T_GROUND
    if layer:
        meaning = "depth of the layer of soil under the floor"
        net.add_parameter(Parameter("d_soil", "m", *SOIL_LAYER_DEPTH, meaning))
        net.add_capacitor(soil_side, "d_soil", factor=SOIL_HEAT_CAPACITY * footprint)
        lambda_area = SOIL_CONDUCTIVITY * footprint  # R = d/(λ·A) [W/(m·K)·m²]
        net.add_resistor(T_GROUND, soil_side, "d_soil", factor=1.0 / lambda_area)
    net.add_parameter(
        Parameter(
            "r_floor",
            "m²K/W",
            1.0 / (SEARCH_MARGIN * U_FLOOR[1]),
            SEARCH_MARGIN / U_FLOOR[0],
            "resistance between the floor/interior mass and the soil, per m² of ground floor (1/U)",
        )
    )
    net.add_parameter(
        Parameter(
            "q_ground",
            "W/m²",
            -20.0,
            60.0,
            "constant heat from the soil's warming by the building, ΔT over the resistance the "
            "ground is seen through (the floor's, or the layer of soil's), per m² of ground floor",
        )
    )
    net.add_resistor(soil_side, target, "r_floor", factor=1.0 / footprint)
    # The soil's warming by the building, ΔT on the ground temperature, is the constant heat
    # ΔT/R of its Norton equivalent, on the node the ground temperature is seen from.
    heated = soil_side if layer else target
    iso_depth = {"d_soil": SOIL_LAYER_DEPTH_ISO} if layer else {}
    net.add_heat_input(UNIT, heated, "q_ground", factor=footprint)
    return Extension(
        effect,
        net,
        signals,
        ("r_floor", "q_ground", *iso_depth),
        ((T_GROUND, heated), (UNIT, heated)),
        neutral={"r_floor": SEARCH_MARGIN / U_FLOOR[0], "q_ground": 0.0, **iso_depth},
        absent={"r_floor": np.inf, "q_ground": 0.0, **iso_depth},
        detail={
            "node": target,
            "ground_floor_area_m2": footprint,
            "ground_depth_m": signals.ground_depth_m,
            "ground_lag_months": 12.0 * ground_lag(signals.ground_depth_m) / YEAR_S,
            "soil_layer": layer,
            **soil,
        },
    )


def _ground_temperatures(ctx: Context, depths_m: list[float]) -> list[dict[str, float]]:
    """What the fitted ground temperature is judged against, over the training period [°C], per
    depth: the mean of T_base read that deep, the outdoor annual mean (with its standard error
    [K]) and the mean indoor temperature (the annual cycle read once for all depths)."""
    times, t_out = ctx.data.times, ctx.train[T_OUT].to_numpy(dtype=float)
    latitude = ctx.building.location.latitude
    cycle = annual_cycle(times, t_out, latitude)
    common = {
        "outdoor_mean_c": float(cycle.mean),
        "outdoor_mean_se_k": annual_mean_uncertainty(times, t_out, cycle),
        "indoor_mean_c": float(np.nanmean(ctx.data.measured)),
    }
    return [
        {
            "ground_base_c": float(
                np.mean(seasonal_ground_temperature(times, t_out, latitude, z, cycle))
            ),
            **common,
        }
        for z in depths_m
    ]


def sky_view_area(building: Building) -> float:
    """Σ A·(1 + cos β)/2 over the opaque surfaces (tilt β): the sky view factor weights a roof
    by 1 and a wall by ½. Without ``walls``, a roof as large as the floor and ``wall_area``. [m²]"""
    if not building.walls:
        return building.floor_area + 0.5 * building.wall_area
    return sum(s.area * (1.0 + np.cos(np.radians(s.tilt))) / 2.0 for s in building.walls)


def sky_radiation(ctx: Context) -> Extension | Skipped:
    """Long-wave loss of the envelope to the (cold, clear, night) sky, as sol-air in the
    long-wave: the sky lowers the temperature the outer surfaces see by ε·h_r·R_se·(T_sky −
    t_out), and U·R_se·ε·h_r·A·(T_sky − t_out) of it reaches the room in the steady state (A:
    the sky-viewing area, ``sky_view_area``).

    The quantity fitted is u_sky, the U-value of the sky-viewing envelope, at ε·h_r =
    ``SKY_H_R_TYPICAL`` (the lumped wall's conductance is the envelope's average, not the roof's:
    an uninsulated roof over insulated walls). ``sky_delta`` enters the envelope node, scaled
    by R_se over the share of that node's heat that warms the room under the current fit
    (``steady_share``). R_se is a sheltered surface's film (``R_SE_SHELTERED``), as for the
    opaque sun: the data identify the share U·R_se, and the clear, calm nights that cool a roof
    most are those of the least wind, so the U read is the least the share can mean."""
    effect = "sky_radiation"
    if SKY_DELTA in ctx.network.signals:
        return Skipped(effect, "the model already has sky radiation")
    target = envelope_node(ctx.network)
    view = sky_view_area(ctx.building)
    share = steady_share(ctx.network, ctx.params, target)
    if share <= 0.0:
        return Skipped(effect, f"no heat at '{target}' reaches the indoor air for the sky to cool")
    u_sky = Parameter(
        "u_sky",
        "W/(m²K)",
        0.0,
        SEARCH_MARGIN * U_OPAQUE[1] * SKY_COUPLING[1] / SKY_H_R_TYPICAL,
        f"U-value of the sky-viewing envelope, roof + ½ wall ({view:g} m²), at ε·h_r = "
        f"{SKY_H_R_TYPICAL:.2g} W/(m²K)",
    )
    detail = {"node": target, "sky_view_area_m2": view, "node_share": share}
    factor = SKY_H_R_TYPICAL * R_SE_SHELTERED * view / share
    return _with_gain(ctx, effect, u_sky, (SKY_DELTA, target), detail, factor)


def thermal_mass(ctx: Context) -> Extension | Skipped:
    """A heat-storage state the model lacks, coupled to the indoor air; capacity and coupling
    resistance per m² of floor."""
    effect = "thermal_mass"
    net = ctx.network.copy(_name(ctx.network, effect))
    floor = ctx.building.floor_area
    node = "mass_extra"
    net.add_parameter(
        Parameter(
            "c_mass_extra",
            "J/(K·m²)",
            1e3,
            SEARCH_MARGIN * EXTRA_CAPACITY_J_M2K[1],
            "heat capacity of the added storage, per floor area",
        )
    )
    net.add_parameter(
        Parameter(
            "r_mass_extra",
            "m²K/W",
            1e-3,
            5.0,
            "resistance between the indoor air and the added storage, per floor area",
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
        absent={"c_mass_extra": 0.0, "r_mass_extra": np.inf},
        detail={
            "node": node,
            "floor_area_m2": floor,
            "coupling_range_m2k_w": internal_resistance(envelope(ctx.building)),
        },
    )


def emitter_dynamics(ctx: Context) -> Extension | Skipped:
    """HVAC heat reaching the room through an emitter (radiator, radiant floor, slab) with its
    own inertia: all of it to the air (a convector), and, where the model has an interior mass,
    a radiant surface's, part of it to that mass (the alternative, ``_radiant_emitter``)."""
    effect = "emitter_dynamics"
    q = ctx.train[Q_HVAC].to_numpy(dtype=float) if Q_HVAC in ctx.train.columns else np.zeros(1)
    if not np.any(np.abs(q) > 0):
        return Skipped(effect, "q_hvac is zero throughout the training period")
    direct = [
        h for h in ctx.network.heat_inputs if h.signal == Q_HVAC and h.node == ctx.network.output
    ]
    if not direct:
        return Skipped(effect, "q_hvac does not enter the air node directly in this model")
    convective, mass = _emitter(ctx), mass_node(ctx.network)
    if mass == ctx.network.output:
        return convective
    return replace(convective, alternatives=(_radiant_emitter(ctx, convective, mass),))


def _emitter(ctx: Context) -> Extension:
    """``emitter_dynamics`` giving all its heat to the air."""
    effect = "emitter_dynamics"
    net = ctx.network.copy(_name(ctx.network, effect))
    floor = ctx.building.floor_area
    net.add_parameter(
        Parameter(
            "c_emitter",
            "J/(K·m²)",
            1e2,
            1e6,  # past any emitter's (plausibility.EMITTER_CAPACITY_J_M2K)
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
        absent={"c_emitter": 0.0, "r_emitter": 0.0},
        detail={"node": "emitter", "floor_area_m2": floor},
    )


def _radiant_emitter(ctx: Context, convective: Extension, mass: str) -> Extension:
    """The emitter as a radiant surface (floor, ceiling, slab): besides its convection to the air
    (r_emitter), long-wave exchange with the room's other surfaces, the interior mass
    (r_emitter_mass). A radiator or fan coil gives nearly all its heat to the air; a heated floor
    about half by radiation (EN 1264-2: 10.8 W/(m²K) at its surface, ε·4σT³ ≈ 5.1 of it), which
    warms the mass before the air (``mass``, the model's interior mass node). Absent, the
    radiant path is open (r_emitter_mass = ∞)."""
    net = convective.network.copy(convective.network.name)
    floor = ctx.building.floor_area
    net.add_parameter(
        Parameter(
            "r_emitter_mass",
            "m²K/W",
            1e-3,
            1e3,  # a path that passes almost nothing: the convector
            "resistance between the emitter and the interior mass (long-wave), per floor area",
        )
    )
    net.add_resistor("emitter", mass, "r_emitter_mass", factor=1.0 / floor)
    return replace(
        convective,
        network=net,
        new_parameters=(*convective.new_parameters, "r_emitter_mass"),
        neutral={**convective.neutral, "r_emitter_mass": 1e3},
        absent={**(convective.absent or {}), "r_emitter_mass": np.inf},
        detail={**convective.detail, "radiant_to": mass},
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
