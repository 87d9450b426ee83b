"""Building archetypes of the diagnosis test bed, the constructions of its concealed effects and
the civil calendar of a site — values; ``variant`` builds the EnergyPlus model from them.

Each archetype is a grid of box zones — one or two rows (south, north) per storey, one or two
storeys — in plan coordinates (x east, y north), turned by ``Variant.rotation_deg``.
Constructions are listed outside → inside; U-values include ISO 6946 films.

* ``light`` — timber-frame pavilion on piers, 12 m × 18 m × 3 m, one zone (216 m²). Painted
  timber cladding on 154 mm batt (U 0.26), membrane roof on 200 mm board (U 0.16), insulated
  timber floor over a ventilated crawl space (outdoor air, no sun, U 0.24), gypsum partitions
  (1 m² per m² of floor). Older double glazing (U 2.7, g 0.70). 0.4 ACH; 1 person per 12 m²,
  lights 8 W/m². Heating to 21 °C on weekdays 06:00–19:00, 15 °C otherwise.
* ``heavy`` — two-storey masonry office, 24 m × 12 m, storeys of 3.3 m, south and north zones
  on each storey (576 m², 4 zones): rendered 240 mm solid brick with 80 mm external insulation
  (U 0.35), 200 mm concrete roof slab under 140 mm insulation (U 0.23), 200 mm concrete
  floor slabs between storeys, brick partitions between zones and 0.6 m² of internal brick
  walls per m² of floor; ground floor over a heated basement (adiabatic). Low-e double glazing
  (U 1.4, g 0.55). 0.3 ACH; 1 person per 10 m², lights 7 W/m². Heating to 20 °C on weekdays
  05:00–19:00, 16 °C otherwise.
* ``open_plan`` — steel-frame open-plan floor, 35 m × 20 m × 4 m, one zone (700 m²): insulated
  metal panels (100 mm PUR, U 0.24), metal-deck roof under 180 mm board (U 0.18), an exposed
  200 mm concrete floor slab over a heated ground floor (adiabatic), light partitions (0.3 m²
  per m²). Ribbon windows of double low-e glazing (U 1.8, g 0.60). 0.3 ACH; 1 person per
  12 m², lights 9 W/m². Heating to 21 °C on weekdays 06:00–19:00, 16 °C otherwise.

* ``school`` (``UNSEEN_ARCHETYPES``: never drawn into the main bed or a sealed set, kept for
  sets of its own, ``testbed.UNSEEN_SETS``) — single-storey school, 36 m × 16 m × 3.2 m, a row of
  classrooms to the south and one to the north (576 m², 2 zones): red-brick cavity wall with
  100 mm mineral wool and a concrete-block inner leaf (U 0.30), dark membrane roof on 180 mm
  board and timber deck (U 0.18), a concrete floor over a heated basement (adiabatic), a
  block corridor wall between the rows and 0.8 m² of light partitions and furniture per m².
  Solar-control double glazing (U 1.6, g 0.45) from 0.9 to 2.8 m. 0.6 ACH; 1 person per 8 m²
  of gross floor on school hours (08:00–15:00, lunch at half), lights 10 W/m². Heating to
  20 °C on weekdays 06:00–16:00, 15 °C otherwise. Its schedules, shape and constructions were
  chosen after the diagnosis was built, to judge it on a building type it was never tuned on.

Every variant has windows on every facade (``Variant.wwr``), constant infiltration, metered
people and lights on its archetype's profiles (the office's; the school's own), a heater of
limited capacity (``Variant.heating_capacities``: ``capacity_factor`` × the design heat loss at
the EPW's 99.6 % heating design temperature) and a holiday closure with the heating off
(``Calendar``).
Schedules run on civil time: EnergyPlus shifts them by an hour on its daylight-saving days
(whole days, the change days included) while its clock and outputs stay on standard time.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date, timedelta
from typing import Any

from .idf import idf_object
from .library import (
    BRICK_100,
    CONCRETE_BLOCK_200,
    GYPSUM_19,
    HEAVY_CONCRETE_100,
    HEAVY_CONCRETE_200,
    OFF_DAY,
    OFFICE_LIGHTING,
    OFFICE_OCCUPANCY,
    PARTITION,
    WALL_AIR_SPACE,
    WOOD_25,
    Construction,
    Material,
    SimpleGlazing,
    WeekSchedule,
    day_profile,
)
from .shoebox import SOIL_1000

# --- materials (ASHRAE 2005 HOF values where the dataset has them) ----------------------------
METAL = Material("F08 Metal surface", 0.0008, 45.28, 7824.0, 500.0, "Smooth")
BATT_154 = Material("I05 154mm batt insulation", 0.1524, 0.045, 19.0, 960.0)
BOARD_200 = Material("Insulation board 200mm", 0.2, 0.035, 30.0, 1210.0)
BOARD_180 = Material("Insulation board 180mm", 0.18, 0.035, 30.0, 1210.0)
BOARD_140 = Material("Insulation board 140mm", 0.14, 0.035, 30.0, 1210.0)
EPS_80 = Material("EPS 80mm", 0.08, 0.035, 20.0, 1450.0)
XPS_100 = Material("XPS 100mm", 0.1, 0.035, 35.0, 1450.0)
PUR_100 = Material("PUR 100mm", 0.1, 0.025, 35.0, 1400.0)
PUR_20 = Material("PUR 20mm", 0.02, 0.025, 35.0, 1400.0)
MEMBRANE = Material("F13 Built-up roofing", 0.0095, 0.16, 1120.0, 1460.0, "Rough")
SOLID_BRICK_240 = Material("Solid brick 240mm", 0.24, 0.72, 1800.0, 840.0, "Rough")
RENDER = Material("Render 15mm", 0.015, 0.87, 1800.0, 840.0, "Rough")
PLASTER = Material("Gypsum plaster 15mm", 0.015, 0.4, 1000.0, 1000.0, "Smooth")
SCREED_50 = Material("Cement screed 50mm", 0.05, 1.4, 2000.0, 1000.0)
MINERAL_WOOL_100 = Material("Mineral wool 100mm", 0.1, 0.036, 30.0, 840.0)

# --- constructions (outside → inside) -------------------------------------------------------
CLADDING = WOOD_25.surface("Timber cladding painted", 0.9, 0.45)
TIMBER_WALL = Construction("Timber frame wall", (CLADDING, BATT_154, GYPSUM_19))
LIGHT_ROOF = Construction(
    "Light membrane roof", (MEMBRANE.surface("Membrane grey", 0.9, 0.6), BOARD_200, WOOD_25)
)
CRAWL_FLOOR = Construction("Timber floor over crawl space", (BATT_154, WOOD_25, WOOD_25))
MASONRY_WALL = Construction(
    "Insulated masonry wall",
    (RENDER.surface("Render light", 0.9, 0.4), EPS_80, SOLID_BRICK_240, PLASTER),
)
CONCRETE_ROOF = Construction(
    "Concrete roof",
    (MEMBRANE.surface("Membrane grey", 0.9, 0.6), BOARD_140, HEAVY_CONCRETE_200, PLASTER),
)
CONCRETE_FLOOR = Construction("Concrete floor slab", (PLASTER, HEAVY_CONCRETE_200, SCREED_50))
BRICK_PARTITION = Construction("Brick partition", (PLASTER, BRICK_100, PLASTER))
PANEL_WALL = Construction(
    "Insulated metal panel", (METAL.surface("Metal grey", 0.9, 0.5), PUR_100, METAL)
)
DECK_ROOF = Construction(
    "Metal deck roof", (MEMBRANE.surface("Membrane grey", 0.9, 0.6), BOARD_180, METAL)
)
EXPOSED_SLAB = Construction("Exposed concrete slab", (HEAVY_CONCRETE_200, SCREED_50))
CAVITY_WALL = Construction(
    "Brick cavity wall",
    (BRICK_100.surface("Brick red", 0.9, 0.65), MINERAL_WOOL_100, CONCRETE_BLOCK_200, PLASTER),
)
TIMBER_DECK_ROOF = Construction(
    "Timber deck roof",
    (MEMBRANE.surface("Membrane dark", 0.9, 0.75), BOARD_180, WOOD_25, GYPSUM_19),
)
BLOCK_PARTITION = Construction("Block partition", (PLASTER, CONCRETE_BLOCK_200, PLASTER))

# --- constructions of the concealed effects -------------------------------------------------
# Dark facades of little insulation: the sun they absorb reaches the room (sol-air).
DARK_PANEL = Construction(
    "Dark metal panel 20mm", (METAL.surface("Metal dark", 0.9, 0.9), PUR_20, METAL)
)
DARK_CLADDING = Construction(
    "Dark metal cladding uninsulated",
    (METAL.surface("Metal dark", 0.9, 0.92), WALL_AIR_SPACE, GYPSUM_19),
)
# High-emissivity, pale, uninsulated roofs: long-wave loss to the sky, little sun.
BARE_ROOF = Construction(
    "Pale metal roof uninsulated",
    (METAL.surface("Metal pale", 0.9, 0.3), WALL_AIR_SPACE, GYPSUM_19),
)
SINGLE_SKIN_ROOF = Construction(
    "Pale single-skin metal roof", (METAL.surface("Metal pale", 0.9, 0.3),)
)
# Slabs on the ground: the soil below carries the ground's slow temperature.
INSULATED_SLAB = Construction(
    "Insulated slab on ground", (SOIL_1000, XPS_100, HEAVY_CONCRETE_100, SCREED_50)
)
BARE_SLAB = Construction("Uninsulated slab on ground", (SOIL_1000, HEAVY_CONCRETE_100, SCREED_50))


def radiant_floor(below: Construction, screed_mm: int) -> Construction:
    """The floor ``below`` with an electric mat under ``screed_mm`` of screed (the mat sits
    after the layers of ``below``). [mm]"""
    screed = Material(f"Cement screed {screed_mm}mm", screed_mm / 1000.0, 1.4, 2000.0, 1000.0)
    return Construction(f"{below.name} radiant {screed_mm}mm", (*below.layers, screed))


@dataclass(frozen=True)
class Archetype:
    """One building type. summary: plain words; sizes [m]; rows: zones per storey (south,
    north); ``mass_per_floor``: internal-mass area per floor area [m²/m²]; sill / head: window
    heights above the storey floor [m]; ``m2_per_person`` [m²]; lights [W/m²]; infiltration
    [1/h]; setpoints [°C]; heated_hours: weekday hours of the occupied setpoint (civil time);
    capacity_factor: heater size / design heat loss [-]; occupancy, lighting: the metered
    people's and lights' profiles (shares of their peak)."""

    name: str
    summary: str
    zone_name: str
    width: float
    depth: float
    storey_height: float
    storeys: int
    rows: int
    wall: Construction
    roof: Construction
    floor: Construction
    floor_boundary: str
    intermediate_floor: Construction | None
    partition: Construction | None
    internal_mass: Construction
    mass_per_floor: float
    glazing: SimpleGlazing
    sill: float
    head: float
    m2_per_person: float
    lights_w_m2: float
    infiltration_ach: float
    occupied_setpoint: float
    setback: float
    heated_hours: tuple[int, int]
    capacity_factor: float
    occupancy: WeekSchedule = OFFICE_OCCUPANCY
    lighting: WeekSchedule = OFFICE_LIGHTING

    @property
    def floor_area(self) -> float:
        return self.width * self.depth * self.storeys

    @property
    def volume(self) -> float:
        return self.floor_area * self.storey_height


# One row per field, one column per archetype (light, heavy, open_plan), to read side by side.
_TABLE: dict[str, tuple[Any, Any, Any]] = {
    "name": ("light", "heavy", "open_plan"),
    "summary": (
        "Light timber-frame pavilion, 216 m², one zone",
        "Heavy two-storey masonry office, 576 m² in four zones",
        "Steel-frame open-plan floor over an exposed concrete slab, 700 m², one zone",
    ),
    "zone_name": ("Pavilion", "Office", "Open plan"),
    "width": (12.0, 24.0, 35.0),
    "depth": (18.0, 12.0, 20.0),
    "storey_height": (3.0, 3.3, 4.0),
    "storeys": (1, 2, 1),
    "rows": (1, 2, 1),
    "wall": (TIMBER_WALL, MASONRY_WALL, PANEL_WALL),
    "roof": (LIGHT_ROOF, CONCRETE_ROOF, DECK_ROOF),
    "floor": (CRAWL_FLOOR, CONCRETE_FLOOR, EXPOSED_SLAB),
    "floor_boundary": ("Outdoors", "Adiabatic", "Adiabatic"),
    "intermediate_floor": (None, CONCRETE_FLOOR, None),
    "partition": (None, BRICK_PARTITION, None),
    "internal_mass": (PARTITION, BRICK_PARTITION, PARTITION),
    "mass_per_floor": (1.0, 0.6, 0.3),
    "glazing": (
        SimpleGlazing("Double clear U2.7", 2.7, 0.70, 0.78),
        SimpleGlazing("Double low-e U1.4", 1.4, 0.55, 0.70),
        SimpleGlazing("Double low-e U1.8", 1.8, 0.60, 0.70),
    ),
    "sill": (0.8, 0.9, 1.0),
    "head": (2.4, 2.5, 3.2),
    "m2_per_person": (12.0, 10.0, 12.0),
    "lights_w_m2": (8.0, 7.0, 9.0),
    "infiltration_ach": (0.4, 0.3, 0.3),
    "occupied_setpoint": (21.0, 20.0, 21.0),
    "setback": (15.0, 16.0, 16.0),
    "heated_hours": ((6, 19), (5, 19), (6, 19)),
    "capacity_factor": (1.3, 1.1, 1.2),
}
LIGHT, HEAVY, OPEN_PLAN = (
    Archetype(**{field: column[i] for field, column in _TABLE.items()}) for i in range(3)
)
ARCHETYPES = {a.name: a for a in (LIGHT, HEAVY, OPEN_PLAN)}

SCHOOL_OCCUPANCY = WeekSchedule(
    weekday=day_profile(
        ("07:30", "08:00", "12:00", "13:00", "15:00", "17:00", "24:00"),
        (0.0, 0.3, 0.95, 0.5, 0.95, 0.1, 0.0),
    ),
    saturday=OFF_DAY,
    sunday=OFF_DAY,
)
SCHOOL_LIGHTING = WeekSchedule(
    weekday=day_profile(("07:00", "08:00", "15:00", "17:00", "24:00"), (0.02, 0.5, 0.9, 0.3, 0.02)),
    saturday=(("24:00", 0.02),),
    sunday=(("24:00", 0.02),),
)
SCHOOL = Archetype(
    name="school",
    summary="Single-storey brick school, 576 m² in two rows of classrooms",
    zone_name="Classrooms",
    width=36.0,
    depth=16.0,
    storey_height=3.2,
    storeys=1,
    rows=2,
    wall=CAVITY_WALL,
    roof=TIMBER_DECK_ROOF,
    floor=CONCRETE_FLOOR,
    floor_boundary="Adiabatic",
    intermediate_floor=None,
    partition=BLOCK_PARTITION,
    internal_mass=PARTITION,
    mass_per_floor=0.8,
    glazing=SimpleGlazing("Double solar-control U1.6", 1.6, 0.45, 0.6),
    sill=0.9,
    head=2.8,
    m2_per_person=8.0,
    lights_w_m2=10.0,
    infiltration_ach=0.6,
    occupied_setpoint=20.0,
    setback=15.0,
    heated_hours=(6, 16),
    capacity_factor=1.4,
    occupancy=SCHOOL_OCCUPANCY,
    lighting=SCHOOL_LIGHTING,
)
# Archetypes kept out of every draw of the main bed and the sealed sets (``ARCHETYPES``).
UNSEEN_ARCHETYPES = {SCHOOL.name: SCHOOL}
_EVERY_ARCHETYPE = {**ARCHETYPES, **UNSEEN_ARCHETYPES}


def archetype_named(name: str) -> Archetype:
    """The archetype called ``name``, drawn or unseen."""
    return _EVERY_ARCHETYPE[name]


@dataclass(frozen=True)
class Calendar:
    """Civil calendar of a site: IANA ``timezone``, EnergyPlus's daylight-saving rule
    (``dst_start`` / ``dst_end``, e.g. "Last Sunday in March") and the holiday closure
    (first day as (month, day), length in days) when the heating is off and nobody comes."""

    timezone: str
    dst_start: str
    dst_end: str
    holiday_start: tuple[int, int]
    holiday_days: int

    def objects(self) -> str:
        """Daylight saving, the closure as holidays, the heating availability schedule."""
        month, day = self.holiday_start
        first = date(2017, month, day)
        last = first + timedelta(days=self.holiday_days - 1)
        if last.year == first.year:
            spans = [(first - timedelta(days=1), 1), (last, 0), (date(2017, 12, 31), 1)]
        else:
            spans = [(last.replace(year=2017), 0), (first - timedelta(days=1), 1)]
            spans.append((date(2017, 12, 31), 0))
        fields: list[object] = ["Heating Availability", "OnOff"]
        for until, on in spans:
            fields += [f"Through: {until.month:02d}/{until.day:02d}", "For: AllDays"]
            fields += ["Until: 24:00", on]
        return "".join(
            [
                idf_object("RunPeriodControl:DaylightSavingTime", self.dst_start, self.dst_end),
                idf_object(
                    "RunPeriodControl:SpecialDays",
                    "Holiday closure",
                    f"{month}/{day}",
                    self.holiday_days,
                    "Holiday",
                ),
                idf_object("Schedule:Compact", *fields),
            ]
        )
