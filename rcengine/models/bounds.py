"""Parameter bounds derived from the building description, for every model of the library.

The thesis's Table 2.3 fixes per-area bounds for one office; on other buildings a fit can end on
them although the building is ordinary. Here every bound is what the building's own areas allow
between the lightest, best-insulated construction and the heaviest, worst one:

- capacities: areal heat capacity κ [J/(m²K)] of the element a node stands for, times its area;
- the air node: ρ·c_p·V times a furniture factor;
- resistances: the envelope's heat-loss coefficient UA [W/K] between its extremes,
  UA = Σ U_e·A_e + ρ·c_p·V·n/3600, and the surface films bounding each side of a wall node;
- solar apertures [m²]: glazing area × g plus opaque area × α·R_se·U, the share of absorbed
  sun that ISO 13790 Eq. 44 lets through an opaque element.

Areas the description leaves open are ranges: glazing not described may be anything from none to
a curtain wall; a zone's roof and ground floor each from nothing (a middle storey) to the whole
floor area (a single storey). ``building_bounds(model, building)`` gives ``{parameter: (lower,
upper)}`` in the parameter's own unit (per-area where the model's parameter is per area).

References
----------
ISO 13790:2008 §12.3.1.2 Table 12 (C_m/A_f 80–370 kJ/(m²K)), Eq. 44 (opaque solar share);
ISO 6946:2017 Table 7 (surface resistances R_si 0.10–0.17, R_se 0.04 m²K/W);
ISO 13370:2017 (ground floor U); EN ISO 10456 (dense concrete ρ = 2400 kg/m³, c = 1000 J/(kg·K));
EN 410 (single clear glass g ≈ 0.85–0.87); literature values of EnergyPlus's zone temperature
capacitance multiplier from model validations, 3.6–15 (NREL/resstock issue #1161).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

from rcengine.building import Building
from rcengine.exceptions import ModelError
from rcengine.network import RCNetwork

Range = tuple[float, float]

# Indoor air: ρ = 1.2 kg/m³, c_p = 1005 J/(kg·K) (dry air near 20 °C). [J/(m³K)]
RHO_CP_AIR = 1.2 * 1005.0
# Air-node capacity multiplier for furniture and light contents: 1 is air alone; validations of
# EnergyPlus's capacitance multiplier found 3.6–15. [-]
FURNITURE_FACTOR: Range = (1.0, 15.0)
# Areal heat capacity of an envelope element (walls, roof), whole layer as thesis Eq. 14 counts
# it: from the 12.5 mm plasterboard lining of a light steel or timber frame (≈ 10 kJ, halved for
# a thinner or partly decoupled lining) to 300 mm of dense concrete (0.3 · 2400 · 1000). [J/(m²K)]
KAPPA_ENVELOPE: Range = (5e3, 7.5e5)
# Internal mass (slabs, partitions, contents) per m² of floor: ISO 13790's classes span 80–370
# kJ/(m²K) of effective (10 cm deep) capacity for the whole building; the internal part alone of
# a timber-floor, plasterboard building is a few times lighter, and whole-layer slabs of 250 mm
# concrete on both faces with masonry partitions reach ≈ 1 MJ. [J/(m²K)]
KAPPA_INTERNAL: Range = (1e4, 1e6)
# Thermal transmittance, opaque elements: passive-house walls to a bare single skin (1/(R_si +
# R_se) ≈ 6); glazing: the best triple glazing to single glazing. [W/(m²K)]
U_OPAQUE: Range = (0.1, 6.0)
U_GLAZING: Range = (0.5, 5.8)
# Ground floor: an uninsulated slab of a small building (ISO 13370, λ = 2 W/(mK), B' = 2 m).
# [W/(m²K)]
U_GROUND_MAX = 2.0
# Air changes per hour, infiltration plus ventilation: a very airtight building to a leaky or
# strongly ventilated one. [1/h]
AIR_CHANGES: Range = (0.05, 3.0)
# Surface resistances (ISO 6946 Table 7): outside R_se; inside R_si from upward flow (0.10) to
# downward flow (0.17). [m²K/W]
R_SE = 0.04
R_SI: Range = (0.10, 0.17)
# The outside film of a sheltered facade, at 1 m/s of wind (ISO 6946 Annex C: h_c = 4 + 4·v,
# h_r ≈ 4.1 W/(m²K)): the most of an absorbed flux the film can send into the wall, so the least
# α·U a fitted sol-air share α·U·R_se can mean. R_SE (4 m/s) is the design value for heat loss;
# sunny hours are often calmer. [m²K/W]
R_SE_SHELTERED = 0.08
# A covering between the indoor air and the internal mass: carpet with underlay, raised-floor or
# suspended-ceiling void; with margin for mass reached through other rooms' air. [m²K/W]
R_COVERING_MAX = 0.8
# Solar absorptance of an opaque surface, dark paint or roofing. [-]
ABSORPTANCE_MAX = 0.95
# Total solar energy transmittance at normal incidence of single clear glass (EN 410). [-]
G_GLAZING_MAX = 0.87
# Share of a fully glazed facade that is still frames, mullions and spandrels; and the least
# glazed-or-light share (doors, frames) of any facade, for the 5R1C window path. [-]
FRAME_SHARE_MIN = 0.1
LIGHT_SHARE_MIN = 0.01
# The sun is no lower than this at noon for the bounds (below it, the air mass removes most of
# the beam). [°]
SUN_ALTITUDE_MIN_DEG = 10.0
EARTH_TILT_DEG = 23.44


@dataclass(frozen=True)
class Envelope:
    """The areas of a building as ranges, where its description leaves them open.

    facade: gross external wall area, glazing included [m²]; opaque_facade: opaque wall area
    [m²]; glazing: window area [m²]; floor_area [m²] (the roof and the ground floor are each 0
    to floor_area); mass_area: the internal-mass area the models scale by [m²]; volume [m³];
    latitude [°].
    """

    facade: float
    opaque_facade: Range
    glazing: Range
    floor_area: float
    mass_area: float
    volume: float
    latitude: float


def envelope(building: Building) -> Envelope:
    """The envelope of ``building`` as the models need it.

    ``wall_area`` is gross (glazing included) in some descriptions and opaque in others; the
    facade is the larger of it and Σ walls + Σ windows. Without ``windows`` the glazing is
    anything from none to all of the facade but its frames; without ``walls`` the opaque area
    is the facade less the glazing.
    """
    windows = sum(s.area for s in building.windows)
    walls = sum(s.area for s in building.walls)
    facade = max(building.wall_area, walls + windows)
    glazing = (windows, windows) if building.windows else (0.0, (1 - FRAME_SHARE_MIN) * facade)
    frames = FRAME_SHARE_MIN * facade
    opaque = (
        (walls, walls)
        if building.walls
        else (max(facade - glazing[1], frames), max(facade - glazing[0], frames))
    )
    return Envelope(
        facade=facade,
        opaque_facade=opaque,
        glazing=glazing,
        floor_area=building.floor_area,
        mass_area=building.internal_mass_area or building.floor_area,
        volume=building.volume,
        latitude=building.location.latitude,
    )


def air_capacity(env: Envelope) -> Range:
    """Indoor air and furniture, C_air = f · ρ·c_p·V with f in ``FURNITURE_FACTOR``. [J/K]"""
    air = RHO_CP_AIR * env.volume
    return FURNITURE_FACTOR[0] * air, FURNITURE_FACTOR[1] * air


def envelope_capacity(env: Envelope) -> Range:
    """Walls and roof, C_env = κ · (A_opaque + A_roof), κ in ``KAPPA_ENVELOPE``; the roof is 0
    to the floor area. The ground slab counts as internal mass. [J/K]"""
    low, high = env.opaque_facade
    return KAPPA_ENVELOPE[0] * low, KAPPA_ENVELOPE[1] * (high + env.floor_area)


def internal_capacity(env: Envelope) -> Range:
    """Slabs, partitions and contents, C_int = κ_int·A_floor, κ_int in ``KAPPA_INTERNAL``. [J/K]"""
    return KAPPA_INTERNAL[0] * env.floor_area, KAPPA_INTERNAL[1] * env.floor_area


def zone_capacity(env: Envelope) -> Range:
    """Everything a single-capacity model lumps: air, internal mass and envelope. [J/K]"""
    parts = (air_capacity(env), internal_capacity(env), envelope_capacity(env))
    return sum(p[0] for p in parts), sum(p[1] for p in parts)


def ventilation_conductance(env: Envelope) -> Range:
    """Air exchange, H_ve = ρ·c_p·V·n/3600 with n in ``AIR_CHANGES`` [1/h]. [W/K]"""
    per_ach = RHO_CP_AIR * env.volume / 3600.0
    return AIR_CHANGES[0] * per_ach, AIR_CHANGES[1] * per_ach


def facade_conductance(env: Envelope) -> Range:
    """Opaque walls and glazing, H = U_op·A_op + U_gl·A_gl with A_op = A_facade − A_gl (kept
    within its own range), at the glazing area and U-values that make it least and most. [W/K]"""

    def conduction(u_opaque: float, u_glazing: float, glazing: float) -> float:
        opaque = min(max(env.facade - glazing, env.opaque_facade[0]), env.opaque_facade[1])
        return u_opaque * opaque + u_glazing * glazing

    low = min(conduction(U_OPAQUE[0], U_GLAZING[0], g) for g in env.glazing)
    high = max(conduction(U_OPAQUE[1], U_GLAZING[1], g) for g in env.glazing)
    return low, high


def heat_loss_coefficient(env: Envelope) -> Range:
    """The whole envelope's UA = H_facade + U_roof·A_roof + U_ground·A_ground + H_ve, with roof
    and ground floor absent at the low end and as large as the floor at the high end. [W/K]"""
    facade, vent = facade_conductance(env), ventilation_conductance(env)
    roof_and_ground = (U_OPAQUE[1] + U_GROUND_MAX) * env.floor_area
    return facade[0] + vent[0], facade[1] + roof_and_ground + vent[1]


def envelope_surface_max(env: Envelope) -> float:
    """The largest envelope surface a wall node can exchange heat through: facade, roof and
    ground floor. [m²]"""
    return env.facade + 2.0 * env.floor_area


def vertical_gain_max(latitude: float) -> float:
    """Largest ratio of irradiance on a sun-facing vertical plane to the horizontal, for the
    beam at winter-solstice noon: cot(h) with h = 90° − |φ| − 23.44°, h ≥ 10°. [-]"""
    altitude = max(90.0 - abs(latitude) - EARTH_TILT_DEG, SUN_ALTITUDE_MIN_DEG)
    return max(1.0, 1.0 / math.tan(math.radians(altitude)))


def opaque_solar_share_max() -> float:
    """Largest share of the irradiance on an opaque element that reaches inside, α·R_se·U
    (ISO 13790 Eq. 44) at the darkest surface and the poorest U. [-]"""
    return ABSORPTANCE_MAX * R_SE * U_OPAQUE[1]


def glazing_aperture_max(env: Envelope) -> float:
    """Window aperture per unit global horizontal irradiance, A_gl · g_max · k_vertical. [m²]"""
    return env.glazing[1] * G_GLAZING_MAX * vertical_gain_max(env.latitude)


def opaque_aperture_max(env: Envelope) -> float:
    """Opaque aperture per unit global horizontal irradiance: α·R_se·U · (A_opaque · k_vertical
    + A_roof), the roof as large as the floor. [m²]"""
    walls = env.opaque_facade[1] * vertical_gain_max(env.latitude)
    return opaque_solar_share_max() * (walls + env.floor_area)


def _per(value: Range, area: float) -> Range:
    return value[0] / area, value[1] / area


def _resistance_per(conductance: Range, area: float) -> Range:
    """Conductance range [W/K] → resistance range × ``area`` [m²K/W]."""
    return area / conductance[1], area / conductance[0]


def wall_resistances(env: Envelope, wall_area: float) -> dict[str, Range]:
    """r_wall_ext and r_wall_int of the chain t_out — wall — air, per wall area [m²K/W].

    Each side holds at least its surface film over the largest envelope surface (R_se outside,
    R_si inside) and at most all the envelope's resistance, A_wall/UA_min: where the capacity
    sits within the construction (behind or in front of the insulation) decides the split,
    and the description does not say.
    """
    surface = envelope_surface_max(env)
    total_max = wall_area / heat_loss_coefficient(env)[0]
    return {
        "r_wall_ext": (wall_area * R_SE / surface, total_max),
        "r_wall_int": (wall_area * R_SI[0] / surface, total_max),
    }


def internal_resistance(env: Envelope) -> Range:
    """r_int between the indoor air and the internal mass, per floor area [m²K/W]: R_si over
    both faces of floor and internal mass at the low end, R_si + a covering over the smaller
    of the two at the high end."""
    most = 2.0 * (env.floor_area + env.mass_area)
    least = min(env.floor_area, env.mass_area)
    low = env.floor_area * R_SI[0] / most
    return low, env.floor_area * (R_SI[1] + R_COVERING_MAX) / least


def wall_capacity(env: Envelope) -> Range:
    """The wall node of a lumped model [J/K]: at least the lightest envelope, at most the
    heaviest envelope with the heaviest internal mass, since slabs touching both the envelope and
    the indoor air may be lumped with either node."""
    outer, internal = envelope_capacity(env), internal_capacity(env)
    return outer[0], outer[1] + internal[1]


def _three_r_three_c(env: Envelope, wall_area: float) -> dict[str, Range]:
    return {
        **wall_resistances(env, wall_area),
        "r_int": internal_resistance(env),
        "c_wall": _per(wall_capacity(env), wall_area),
        "c_air": air_capacity(env),
        "c_int": _per(internal_capacity(env), env.mass_area),
    }


def solar_aperture_max(env: Envelope) -> float:
    """Glazing and opaque apertures together, for a node that may host either gain. [m²]"""
    return glazing_aperture_max(env) + opaque_aperture_max(env)


def _basic(env: Envelope, building: Building) -> dict[str, Range]:
    # The wall node may host mass that absorbs transmitted sun, as it may host its capacity.
    return {
        **_three_r_three_c(env, building.wall_area),
        "alpha_wall": (0.0, solar_aperture_max(env)),
        "alpha_int": (0.0, glazing_aperture_max(env)),
    }


def _sun(env: Envelope, building: Building) -> dict[str, Range]:
    # The solar module's inputs are already plane-of-array irradiance × area: the factors are
    # the shares that reach the node.
    return {
        **_three_r_three_c(env, building.wall_area),
        "alpha_wall": (0.0, opaque_solar_share_max()),
        "alpha_int": (0.0, G_GLAZING_MAX),
    }


def _r1c1(env: Envelope, building: Building) -> dict[str, Range]:
    return {
        "r_env": _resistance_per(heat_loss_coefficient(env), building.wall_area),
        "c_zone": _per(zone_capacity(env), env.floor_area),
        "alpha_sol": (0.0, solar_aperture_max(env)),
    }


def _r2c2(env: Envelope, building: Building) -> dict[str, Range]:
    # Without an internal-mass node, that mass may sit with either capacity.
    air, internal = air_capacity(env), internal_capacity(env)
    return {
        **wall_resistances(env, building.wall_area),
        "c_wall": _per(wall_capacity(env), building.wall_area),
        "c_air": (air[0], air[1] + internal[1]),
        "alpha_wall": (0.0, solar_aperture_max(env)),
        "alpha_air": (0.0, glazing_aperture_max(env)),
    }


def _r5c1(env: Envelope, building: Building) -> dict[str, Range]:
    """ISO 13790 5R1C: H_ve the air exchange, H_tr,w the glazing (at least doors and frames),
    H_tr,em the opaque walls, roof and ground (the series surface-mass conductance, fixed and
    several times larger, is neglected); all resistances per floor area."""
    af = env.floor_area
    opaque = env.opaque_facade
    light = LIGHT_SHARE_MIN * env.facade
    windows = (U_GLAZING[0] * max(env.glazing[0], light), U_GLAZING[1] * max(env.glazing[1], light))
    walls = (U_OPAQUE[0] * opaque[0], U_OPAQUE[1] * (opaque[1] + af) + U_GROUND_MAX * af)
    return {
        "r_ve": _resistance_per(ventilation_conductance(env), af),
        "r_win": _resistance_per(windows, af),
        "r_em": _resistance_per(walls, af),
        "c_m": _per(zone_capacity(env), af),
        "alpha_sol": (0.0, solar_aperture_max(env)),
    }


_BOUNDS: dict[str, Callable[[Envelope, Building], dict[str, Range]]] = {
    "basic": _basic,
    "sun": _sun,
    "1r1c": _r1c1,
    "2r2c": _r2c2,
    "5r1c": _r5c1,
}


def building_bounds(model: str, building: Building) -> dict[str, Range]:
    """Bounds of every parameter of library ``model`` from the description of ``building``,
    ``{name: (lower, upper)}`` in each parameter's unit (see the module docstring)."""
    try:
        derive = _BOUNDS[model]
    except KeyError:
        raise ModelError(f"invalid model {model!r}; choose from {sorted(_BOUNDS)}") from None
    return derive(envelope(building), building)


def with_bounds(network: RCNetwork, bounds: Mapping[str, Range]) -> RCNetwork:
    """``network`` with the bounds of the named parameters replaced (in place; returned)."""
    for name, (lower, upper) in bounds.items():
        network.parameters[name] = replace(network.parameters[name], lower=lower, upper=upper)
    return network
