"""Zone-level IDF objects: the zone, its gains, air exchange and ideal-loads heating."""

from __future__ import annotations

from .idf import constant_schedule, idf_object

# Sensible + latent heat of a seated office worker, as thesis §2.4.1. [W/person]
ACTIVITY_W = 100.0


def zone(name: str) -> str:
    """A zone whose volume, ceiling height and floor area EnergyPlus takes from its surfaces."""
    return idf_object("Zone", name, 0.0, 0.0, 0.0, 0.0, 1, 1, "autocalculate", "autocalculate")


def people(zone_name: str, count: float, schedule: str, activity_schedule: str) -> str:
    """Occupants; EnergyPlus splits the activity into sensible and latent by air temperature."""
    return idf_object(
        "People",
        f"{zone_name} People",
        zone_name,
        schedule,
        "People",
        count,
        None,
        None,
        0.3,
        "autocalculate",
        activity_schedule,
    )


def activity_schedule(name: str = "Activity") -> str:
    return constant_schedule(name, ACTIVITY_W)


def lights(zone_name: str, watts_per_m2: float, schedule: str) -> str:
    """Lighting; radiant / visible fractions of suspended fluorescent luminaires
    (EnergyPlus Input Output Reference, Lights, table of heat gain fractions)."""
    # Fractions: return air 0, radiant 0.42, visible 0.18; replaceable 1.
    return _gain_per_area(
        "Lights", "Lights", zone_name, watts_per_m2, schedule, 0.0, 0.42, 0.18, 1.0
    )


def electric_equipment(zone_name: str, watts_per_m2: float, schedule: str) -> str:
    """Plug loads (office equipment): half radiant."""
    # Fractions: latent 0, radiant 0.5, lost 0.
    return _gain_per_area(
        "ElectricEquipment", "Equipment", zone_name, watts_per_m2, schedule, 0.0, 0.5, 0.0
    )


def _gain_per_area(
    kind: str, tag: str, zone_name: str, watts_per_m2: float, schedule: str, *fractions: float
) -> str:
    """A ``kind`` gain of ``watts_per_m2`` of floor on ``schedule``, split by the object's own
    heat ``fractions``. [W/m²]"""
    return idf_object(
        kind,
        f"{zone_name} {tag}",
        zone_name,
        schedule,
        "Watts/Area",
        None,
        watts_per_m2,
        None,
        *fractions,
        "General",
    )


def infiltration(
    zone_name: str,
    ach: float,
    constant: float = 1.0,
    per_wind: float = 0.0,
    schedule: str = "AlwaysOn",
) -> str:
    """Infiltration ``ach · (constant + per_wind · v_wind)``; v_wind is EnergyPlus's local
    wind speed at the zone centroid height. [1/h], [-], [s/m]"""
    # Coefficients: constant, temperature 0, velocity, velocity squared 0.
    return _design_flow_rate("Infiltration", zone_name, ach, schedule, constant, 0.0, per_wind, 0.0)


def ventilation(zone_name: str, ach: float, schedule: str) -> str:
    """Outdoor-air ventilation (balanced, no fan heat) at ``ach`` while ``schedule`` is on. [1/h]"""
    # No fan pressure rise, fan efficiency 1; coefficients: constant 1, the others 0.
    return _design_flow_rate(
        "Ventilation", zone_name, ach, schedule, "Balanced", 0.0, 1.0, 1.0, 0.0, 0.0, 0.0
    )


def _design_flow_rate(kind: str, zone_name: str, ach: float, schedule: str, *rest: object) -> str:
    """``Zone<kind>:DesignFlowRate``: ``ach`` air changes of outdoor air while ``schedule`` is
    on; ``rest``: the object's own fields after the rate. [1/h]"""
    return idf_object(
        f"Zone{kind}:DesignFlowRate",
        f"{zone_name} {kind}",
        zone_name,
        schedule,
        "AirChanges/Hour",
        None,
        None,
        None,
        ach,
        *rest,
    )


def internal_mass(zone_name: str, construction: str, area: float, tag: str = "Mass") -> str:
    """Exposed internal mass of ``area`` (one face; the other face is adiabatic). [m²]"""
    return idf_object("InternalMass", f"{zone_name} {tag}", construction, zone_name, None, area)


def ideal_loads_heating(
    zone_name: str, setpoint_schedule: str, availability_schedule: str, capacity_w: float
) -> str:
    """Heating-only ideal loads air system, limited to ``capacity_w`` of sensible heat. [W]

    A single-heating thermostat, so no cooling is ever asked for; when ``availability_schedule``
    is 0 the zone floats freely.
    """
    z = zone_name
    return "".join(
        [
            _equipment(
                z,
                "ZoneHVAC:IdealLoadsAirSystem",
                f"{z} Ideal Loads",
                f"{z} Supply Inlet",
                f"{z} Return Outlet",
            ),
            idf_object(
                "ZoneHVAC:IdealLoadsAirSystem",
                f"{z} Ideal Loads",
                availability_schedule,
                f"{z} Supply Inlet",
                None,
                None,
                50.0,
                13.0,
                0.0156,
                0.0077,
                "LimitCapacity",
                None,
                capacity_w,
                "NoLimit",
                None,
                None,
                None,
                "AlwaysOff",
                "None",
                0.7,
                "None",
            ),
            idf_object(
                "ZoneControl:Thermostat",
                f"{z} Thermostat",
                z,
                "SingleHeatingControl",
                "ThermostatSetpoint:SingleHeating",
                f"{z} Heating Setpoint",
            ),
            idf_object(
                "ThermostatSetpoint:SingleHeating", f"{z} Heating Setpoint", setpoint_schedule
            ),
        ]
    )


def _equipment(
    zone_name: str, kind: str, name: str, inlet: str | None = None, outlet: str | None = None
) -> str:
    """The zone's equipment connections and its list of one piece of equipment, ``kind``
    ``name``; ``inlet`` / ``outlet``: the air nodes of equipment that moves air."""
    return idf_object(
        "ZoneHVAC:EquipmentConnections",
        zone_name,
        f"{zone_name} Equipment",
        inlet,
        None,
        f"{zone_name} Air Node",
        outlet,
    ) + idf_object(
        "ZoneHVAC:EquipmentList",
        f"{zone_name} Equipment",
        "SequentialLoad",
        kind,
        name,
        1,
        1,
        None,
        None,
    )


def single_heating_control_schedule() -> str:
    """Control-type schedule of ``ZoneControl:Thermostat``: 1 = single heating setpoint."""
    return constant_schedule("SingleHeatingControl", 1)


def radiant_floor_heating(
    zone_name: str,
    surface: str,
    construction: str,
    source_after_layer: int,
    capacity_w: float,
    setpoint_schedule: str,
    availability_schedule: str,
    name: str = "Radiant Floor",
    with_source: bool = True,
) -> str:
    """Electric radiant floor heating ``surface`` (whose ``construction`` holds the mat after
    layer ``source_after_layer``), at most ``capacity_w``, proportional on the air temperature
    over 2 K around the setpoint (full power 1 K below it, none 1 K above). [W]

    ``with_source``: whether to declare the construction's heat source; EnergyPlus takes one
    declaration per construction, so the radiant floors of further zones sharing it leave it
    out."""
    source = idf_object(
        "ConstructionProperty:InternalHeatSource",
        f"{name} Source",
        construction,
        source_after_layer,
        source_after_layer,
        1,
        0.15,
        0.0,
    )
    return "".join(
        [
            source if with_source else "",
            _equipment(zone_name, "ZoneHVAC:LowTemperatureRadiant:Electric", name),
            idf_object(
                "ZoneHVAC:LowTemperatureRadiant:Electric",
                name,
                availability_schedule,
                zone_name,
                surface,
                "HeatingDesignCapacity",
                capacity_w,
                None,
                None,
                "MeanAirTemperature",
                "HalfFlowPower",
                2.0,
                setpoint_schedule,
            ),
        ]
    )


def heat_into_air(zone_name: str, schedule: str, name: str | None = None) -> str:
    """Heat put straight into the zone air, ``schedule`` giving the power. [W]"""
    return idf_object(
        "OtherEquipment",
        name or schedule,
        "None",
        zone_name,
        schedule,
        "EquipmentLevel",
        1.0,
        None,
        None,
        0.0,
        0.0,
        0.0,
        0.0,
        "General",
    )
