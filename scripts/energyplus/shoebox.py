"""The single-zone "shoebox" family: one base building, one switch per concealed effect.

Base ("plain"): 10 m (E–W) × 20 m (N–S) × 3 m, one zone of 200 m². Walls of light-painted
brick (solar absorptance 0.25), 50 mm insulation, 200 mm concrete block and gypsum (U = 0.44
W/(m²·K) with films); roof and floor adiabatic (the thesis's roof and floor constructions as
mass), so roof solar and the roof's sky radiation do not exist; 150 m² of gypsum partitions; no
windows; constant infiltration 0.3 ACH. UA ≈ 140 W/K (walls 79, infiltration 60). Metered
people (12 at 100 W) and lights (6 W/m²) on the office profiles; ideal-loads heating to 21 °C,
50 W/m², available 06:00–20:00 on weekdays and off at weekends, free-floating otherwise.
Torino IWEC weather, 1 Oct 2016 – 31 Mar 2017, 15 minutes.

Each variant switches one thing on (``CASES``). The effect never appears as a CSV column; its
strength is measured against a reference run of the same building without it, and recorded in
``data/energyplus/variants/manifest.json``:

* window_solar_gains — 24 m² of east glazing; reference: the same glazing with a pane that
  reflects the sun (same conduction), so only the solar gain differs.
* wind_infiltration — 0.3 ACH + 0.4 ACH per m/s of weather-station wind (EnergyPlus applies
  the velocity term to the local wind at the zone's mid-height, 0.47 × the station's).
* ventilation_schedule — 2.5 ACH of outdoor air, weekdays 08:00–18:00.
* unmetered_gains — 10 W/m² of plug loads on a weekly schedule (15–20 W/m² overheats this
  tight, windowless box past 30 °C in winter).
* ground_coupling — the floor becomes an uninsulated slab on 1 m of soil over
  ``Site:GroundTemperature:BuildingSurface`` = the EPW header's 4 m monthly temperatures
  (16.0 °C in October to 7.3 °C in February); the soil layer smooths the monthly steps.
* thermal_mass — 400 m² of exposed 200 mm heavyweight concrete (164 MJ/K); the 3R3C model
  already has an internal-mass node, so this one is diagnosed with 1R1C.
* emitter_dynamics — electric radiant floor (50 W/m², mat under 100 mm of screed) on a 2 K
  proportional band around 21 °C; q_hvac is its power. Reference: the same q_hvac series put
  straight into the air (``OtherEquipment``) over the same floor.
* sky_radiation — white (solar absorptance 0.1), high-emissivity (0.95) 200 mm concrete roof
  with only 25 mm of insulation (U = 0.89 W/(m²·K)); reference: the same roof under a sky at
  the outdoor air temperature (``WeatherProperty:SkyTemperature``). A fully uninsulated roof
  (U ≈ 4) made the box unheatable with 50 W/m².
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import pandas as pd

from . import zones
from .geometry import SIDES, Box, VerticalRect
from .idf import (
    RunPeriod,
    SiteInfo,
    building_ground_temperatures,
    building_surface,
    constant_schedule,
    header,
    idf_object,
    materials_and_constructions,
    output_variables,
    sky_at_air_temperature,
    week_schedule,
    window_surface,
)
from .library import (
    AIR_13MM,
    BRICK_100,
    CLEAR_3MM,
    CONCRETE_BLOCK_200,
    FLOOR,
    GYPSUM_19,
    HEAVY_CONCRETE_100,
    HEAVY_CONCRETE_200,
    INSULATION_25,
    INSULATION_50,
    OFFICE_LIGHTING,
    OFFICE_OCCUPANCY,
    PARTITION,
    ROOF,
    WINDOW_DOUBLE_CLEAR,
    Construction,
    Glazing,
    Material,
    WeekSchedule,
    day_profile,
    heating_availability,
)

ZONE = "Shoebox"
BOX = Box(0.0, 10.0, 0.0, 20.0, 3.0)
PEOPLE = 12
LIGHTS_W_M2 = 6.0
PARTITION_AREA = 150.0
INFILTRATION_ACH = 0.3
SETPOINT = 21.0
HEATING_CAPACITY_W_M2 = 50.0
WINDOW_SILL, WINDOW_HEAD = 0.5, 2.5

# --- constructions of the family (outside → inside) -------------------------------------------
PAINTED_BRICK = BRICK_100.surface("M01 100mm brick light paint", thermal=0.9, solar=0.25)
WALL = Construction("Shoebox wall", (PAINTED_BRICK, INSULATION_50, CONCRETE_BLOCK_200, GYPSUM_19))
# Soil below the slab: Site:GroundDomain:Slab's default soil (k 1.5, ρ 2800, c 850).
SOIL_1000 = Material("Soil 1000mm", 1.0, 1.5, 2800.0, 850.0, "Rough")
GROUND_SLAB = Construction("Uninsulated slab on ground", (SOIL_1000, HEAVY_CONCRETE_100))
# Radiant floor: the electric mat sits after layer 2, under 100 mm of concrete screed.
RADIANT_FLOOR = Construction(
    "Radiant floor", (INSULATION_50, HEAVY_CONCRETE_100, HEAVY_CONCRETE_100)
)
RADIANT_SOURCE_AFTER_LAYER = 2
HEAVY_MASS = Construction("Exposed concrete", (HEAVY_CONCRETE_200,))
# White, high-emissivity, uninsulated concrete roof: weak solar, strong long-wave exchange.
WHITE_CONCRETE = HEAVY_CONCRETE_200.surface("M15 200mm heavyweight concrete white", 0.95, 0.1)
EXPOSED_ROOF = Construction("Exposed roof", (WHITE_CONCRETE, INSULATION_25))
# The reference of window_solar_gains: the same unit with a pane that reflects the sun away.
SUN_BLOCKING_PANE = Glazing("Sun-blocking 3MM", 0.003, 0.0, 0.92, 0.0, 0.92, 0.84, 0.9)
WINDOW_NO_SUN = Construction("Double 3mm/13mm air no sun", (SUN_BLOCKING_PANE, AIR_13MM, CLEAR_3MM))

OFFICE_EQUIPMENT = WeekSchedule(
    weekday=day_profile(
        ("07:00", "08:00", "12:00", "13:00", "17:00", "19:00", "24:00"),
        (0.2, 0.5, 0.9, 0.7, 0.9, 0.5, 0.2),
    ),
    saturday=(("24:00", 0.2),),
    sunday=(("24:00", 0.2),),
)
VENTILATION_HOURS = WeekSchedule(
    weekday=(("08:00", 0.0), ("18:00", 1.0), ("24:00", 0.0)),
    saturday=(("24:00", 0.0),),
    sunday=(("24:00", 0.0),),
)

OUTPUTS = (
    "Zone Mean Air Temperature",
    "Zone People Sensible Heating Rate",
    "Zone Lights Total Heating Rate",
    "Site Outdoor Air Drybulb Temperature",
    "Site Direct Solar Radiation Rate per Area",
    "Site Diffuse Solar Radiation Rate per Area",
    "Site Solar Altitude Angle",
    "Site Wind Speed",
)


def local_wind_factor(
    height: float, terrain_exponent: float = 0.22, boundary_layer: float = 370.0
) -> float:
    """EnergyPlus's local / weather-station wind speed at ``height`` (Suburbs terrain).

    V_z = V_met (δ_met / z_met)^a_met (z / δ)^a with a_met = 0.14, δ_met = 270 m, z_met = 10 m
    (EnergyPlus Engineering Reference, "Local Wind Speed Calculations").
    """
    return (270.0 / 10.0) ** 0.14 * (height / boundary_layer) ** terrain_exponent


@dataclass(frozen=True)
class Shoebox:
    """The switches; all defaults give the plain building.

    east_glazing: glazed fraction of the east facade [-]; sun_blocking_glass: that glazing
    admits no sun; ach_per_wind: extra infiltration per m/s of weather-station wind [1/h per
    m/s]; ventilation_ach: outdoor air in office hours [1/h]; unmetered_w_m2: plug loads
    [W/m²]; ground_floor: uninsulated slab on the ground; heavy_mass_area: exposed 200 mm
    concrete [m²]; radiant_floor: electric radiant floor heating instead of ideal loads;
    replayed_heat: heat put straight into the air instead of any heating system, per local
    standard-time interval start [W]; exposed_roof: uninsulated white roof under the sky;
    sky_at_air_temperature: the sky radiates at the outdoor air temperature.
    """

    east_glazing: float = 0.0
    sun_blocking_glass: bool = False
    ach_per_wind: float = 0.0
    ventilation_ach: float = 0.0
    unmetered_w_m2: float = 0.0
    ground_floor: bool = False
    heavy_mass_area: float = 0.0
    radiant_floor: bool = False
    replayed_heat: pd.Series | None = field(default=None, compare=False)
    exposed_roof: bool = False
    sky_at_air_temperature: bool = False

    # --- geometry ---------------------------------------------------------------------------
    def walls(self) -> list[VerticalRect]:
        return [BOX.wall(side) for side in SIDES]

    def window(self) -> VerticalRect | None:
        if self.east_glazing <= 0.0:
            return None
        wall = BOX.wall("east")
        height = WINDOW_HEAD - WINDOW_SILL
        return wall.window(self.east_glazing * wall.area / height, WINDOW_SILL, WINDOW_HEAD)

    @property
    def internal_mass_area(self) -> float:
        return PARTITION_AREA + self.heavy_mass_area

    # --- IDF --------------------------------------------------------------------------------
    def idf(self, site: SiteInfo, period: RunPeriod) -> str:
        parts = [
            header("Shoebox", site, period, timesteps_per_hour=4),
            materials_and_constructions(self._constructions()),
            week_schedule("Occupancy", OFFICE_OCCUPANCY),
            week_schedule("Lighting", OFFICE_LIGHTING),
            week_schedule("Heating Availability", heating_availability((6, 20), None), "OnOff"),
            constant_schedule("Heating Setpoint", SETPOINT),
            zones.activity_schedule(),
            zones.single_heating_control_schedule(),
            zones.zone(ZONE),
            *self._envelope(),
            zones.internal_mass(ZONE, PARTITION.name, PARTITION_AREA, "Partitions"),
            zones.people(ZONE, PEOPLE, "Occupancy", "Activity"),
            zones.lights(ZONE, LIGHTS_W_M2, "Lighting"),
            self._infiltration(),
            *self._effects(site),
            self._heating(),
            output_variables(OUTPUTS + self._heating_outputs()),
        ]
        return "".join(parts)

    def _glazing(self) -> Construction | None:
        if self.east_glazing <= 0.0:
            return None
        return WINDOW_NO_SUN if self.sun_blocking_glass else WINDOW_DOUBLE_CLEAR

    def _roof(self) -> tuple[Construction, str]:
        """Roof construction and outside boundary condition."""
        return (EXPOSED_ROOF, "Outdoors") if self.exposed_roof else (ROOF, "Adiabatic")

    def _floor(self) -> tuple[Construction, str]:
        """Floor construction and outside boundary condition."""
        if self.ground_floor:
            return GROUND_SLAB, "Ground"
        if self.radiant_floor or self.replayed_heat is not None:
            return RADIANT_FLOOR, "Adiabatic"
        return FLOOR, "Adiabatic"

    def _constructions(self) -> list[Construction]:
        out = [WALL, self._roof()[0], self._floor()[0], PARTITION]
        glazing = self._glazing()
        if glazing is not None:
            out.append(glazing)
        if self.heavy_mass_area > 0.0:
            out.append(HEAVY_MASS)
        return out

    def _envelope(self) -> list[str]:
        out = []
        window, glazing = self.window(), self._glazing()
        for side, wall in zip(SIDES, self.walls(), strict=True):
            name = f"{side.capitalize()} Wall"
            out.append(building_surface(name, "Wall", WALL.name, ZONE, wall.vertices()))
            if side == "east" and window is not None and glazing is not None:
                out.append(window_surface("East Window", glazing.name, name, window))
        roof, roof_boundary = self._roof()
        floor, floor_boundary = self._floor()
        return [
            *out,
            building_surface("Roof", "Roof", roof.name, ZONE, BOX.roof(), boundary=roof_boundary),
            building_surface(
                "Floor", "Floor", floor.name, ZONE, BOX.floor(), boundary=floor_boundary
            ),
        ]

    def _infiltration(self) -> str:
        if self.ach_per_wind == 0.0:
            return zones.infiltration(ZONE, INFILTRATION_ACH)
        # Design level 1 ACH: constant term = base rate, velocity term per local m/s.
        per_local = self.ach_per_wind / local_wind_factor(BOX.height / 2.0)
        return zones.infiltration(ZONE, 1.0, constant=INFILTRATION_ACH, per_wind=per_local)

    def _effects(self, site: SiteInfo) -> list[str]:
        out = []
        if self.ventilation_ach > 0.0:
            out += [
                week_schedule("Ventilation Hours", VENTILATION_HOURS, "OnOff"),
                zones.ventilation(ZONE, self.ventilation_ach, "Ventilation Hours"),
            ]
        if self.unmetered_w_m2 > 0.0:
            out += [
                week_schedule("Equipment", OFFICE_EQUIPMENT),
                zones.electric_equipment(ZONE, self.unmetered_w_m2, "Equipment"),
            ]
        if self.ground_floor:
            out.append(building_ground_temperatures(site))
        if self.heavy_mass_area > 0.0:
            out.append(zones.internal_mass(ZONE, HEAVY_MASS.name, self.heavy_mass_area, "Concrete"))
        if self.sky_at_air_temperature:
            out.append(sky_at_air_temperature())
        return out

    def _heating_outputs(self) -> tuple[str, ...]:
        if self.replayed_heat is not None:
            return ()
        if self.radiant_floor:
            return ("Zone Radiant HVAC Heating Rate",)
        return (
            "Zone Ideal Loads Zone Sensible Heating Rate",
            "Zone Ideal Loads Zone Sensible Cooling Rate",
        )

    def _heating(self) -> str:
        if self.replayed_heat is not None:
            return replay_schedule("Replayed Heat", self.replayed_heat) + zones.heat_into_air(
                ZONE, "Replayed Heat"
            )
        if self.radiant_floor:
            return radiant_floor_heating()
        return zones.ideal_loads_heating(
            ZONE, "Heating Setpoint", "Heating Availability", HEATING_CAPACITY_W_M2 * BOX.floor_area
        )


def radiant_floor_heating() -> str:
    """Electric radiant floor, 50 W/m², proportional on the air temperature over 2 K around
    the setpoint (full power at 20 °C, none at 22 °C), in office hours."""
    return zones.radiant_floor_heating(
        ZONE,
        "Floor",
        RADIANT_FLOOR.name,
        RADIANT_SOURCE_AFTER_LAYER,
        HEATING_CAPACITY_W_M2 * BOX.floor_area,
        "Heating Setpoint",
        "Heating Availability",
    )


def replay_schedule(name: str, heat: pd.Series) -> str:
    """Schedule:Compact reproducing a 15-minute heat series day by day. [W]

    ``heat`` is indexed by local standard-time interval starts; EnergyPlus's ``Until: hh:mm``
    value holds for the timestep that ends at hh:mm. Days outside the series are 0. The run
    must not hold 29 February (the calendar below is that of a common year).
    """
    by_day = {(d.month, d.day): s for d, s in heat.groupby(heat.index.normalize())}
    if (2, 29) in by_day:
        raise ValueError("replay_schedule: runs holding 29 February are not supported")
    fields: list[object] = [name, "Any"]
    for day in pd.date_range("2017-01-01", "2017-12-31", freq="D"):
        series = by_day.get((day.month, day.day))
        fields += [f"Through: {day.month:02d}/{day.day:02d}", "For: AllDays"]
        if series is None:
            fields += ["Until: 24:00", 0.0]
            continue
        ends = series.index + pd.Timedelta(minutes=15) - series.index.normalize()
        values = series.to_numpy()
        for k, (end, value) in enumerate(zip(ends, values, strict=True)):
            last = k == len(values) - 1
            if last or values[k + 1] != value:
                minutes = int(end.total_seconds() // 60)
                fields += [f"Until: {minutes // 60:02d}:{minutes % 60:02d}", round(value, 1)]
    return idf_object("Schedule:Compact", *fields)


@dataclass(frozen=True)
class Case:
    """One committed variant: the building with its effect and the reference without it."""

    name: str
    effect: str | None
    description: str
    building: Shoebox
    reference: Shoebox | None
    reference_description: str = ""
    model: str = "basic"


PLAIN = Shoebox()
CASES = (
    Case(
        "plain",
        None,
        "The base building; a 3R3C model with t_out, ghi, q_occ, q_light and "
        "q_hvac is well specified.",
        PLAIN,
        None,
    ),
    Case(
        "window_solar_gains",
        "window_solar_gains",
        "40 % of the east facade glazed (24 m² double clear): morning solar gains.",
        Shoebox(east_glazing=0.4),
        Shoebox(east_glazing=0.4, sun_blocking_glass=True),
        "same glazing with a pane that reflects all sun (same conduction)",
    ),
    Case(
        "wind_infiltration",
        "wind_infiltration",
        "Infiltration 0.3 ACH + 0.4 ACH per m/s of weather-station wind.",
        Shoebox(ach_per_wind=0.4),
        PLAIN,
        "plain: constant 0.3 ACH",
    ),
    Case(
        "ventilation_schedule",
        "ventilation_schedule",
        "2.5 ACH of outdoor air on weekdays 08:00-18:00 (no heat recovery).",
        Shoebox(ventilation_ach=2.5),
        PLAIN,
        "plain: no ventilation",
    ),
    Case(
        "unmetered_gains",
        "unmetered_gains",
        "10 W/m² of plug loads on an office weekly schedule, in no column.",
        Shoebox(unmetered_w_m2=10.0),
        PLAIN,
        "plain: no plug loads",
    ),
    Case(
        "ground_coupling",
        "ground_coupling",
        "Uninsulated slab on 1 m of soil over the ground at the EPW's 4 m monthly temperatures.",
        Shoebox(ground_floor=True),
        PLAIN,
        "plain: adiabatic floor",
    ),
    Case(
        "thermal_mass",
        "thermal_mass",
        "400 m² of exposed 200 mm heavyweight concrete inside; diagnose with 1R1C.",
        Shoebox(heavy_mass_area=400.0),
        PLAIN,
        "plain: partitions only",
        model="1r1c",
    ),
    Case(
        "emitter_dynamics",
        "emitter_dynamics",
        "Electric radiant floor under 100 mm of screed, proportional control on the air "
        "temperature; q_hvac is its electric power.",
        Shoebox(radiant_floor=True),
        None,
        "the same q_hvac series put straight into the air (same floor, no emitter)",
    ),
    Case(
        "sky_radiation",
        "sky_radiation",
        "Exposed white concrete roof with 25 mm of insulation (solar absorptance 0.1, "
        "emissivity 0.95, U = 0.89 W/(m²·K)).",
        Shoebox(exposed_roof=True),
        Shoebox(exposed_roof=True, sky_at_air_temperature=True),
        "same roof under a sky at the outdoor air temperature",
    ),
)


def with_replay(box: Shoebox, heat: pd.Series) -> Shoebox:
    """The reference of emitter_dynamics: same building, ``heat`` straight into the air."""
    return replace(box, radiant_floor=False, replayed_heat=heat)
