"""Materials, constructions and weekly schedules, as values.

Opaque materials carry the values of EnergyPlus's ``DataSets/ASHRAE_2005_HOF_Materials.idf``
(ASHRAE Handbook of Fundamentals 2005, ch. 30, table 19) under their dataset names; glazing and
gas those of ``WindowGlassMaterials.idf`` / ``WindowGasMaterials.idf``. The office schedules
follow the ASHRAE 90.1-1989 §13 office profiles of ``DataSets/Schedules.idf``, with Sundays
empty as thesis §3.1 describes (no HVAC, people or lights on Sundays).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

DayProfile = tuple[tuple[str, float], ...]  # ("HH:MM" until, value) pairs ending at 24:00


@dataclass(frozen=True)
class Material:
    """A massive layer. thickness [m], conductivity [W/(m·K)], density [kg/m³],
    specific_heat [J/(kg·K)], absorptances [-] (thermal = long-wave emissivity)."""

    name: str
    thickness: float
    conductivity: float
    density: float
    specific_heat: float
    roughness: str = "MediumRough"
    thermal_absorptance: float = 0.9
    solar_absorptance: float = 0.7
    visible_absorptance: float = 0.7

    def surface(self, name: str, thermal: float, solar: float) -> Material:
        """The same layer with other surface absorptances (a paint)."""
        return replace(
            self,
            name=name,
            thermal_absorptance=thermal,
            solar_absorptance=solar,
            visible_absorptance=solar,
        )


@dataclass(frozen=True)
class Glazing:
    """A glass pane, spectral averages. thickness [m], conductivity [W/(m·K)]."""

    name: str
    thickness: float
    solar_transmittance: float
    solar_reflectance: float
    visible_transmittance: float
    visible_reflectance: float
    emissivity: float
    conductivity: float


@dataclass(frozen=True)
class SimpleGlazing:
    """A whole glazing unit by its centre-of-glass figures (EnergyPlus's simple glazing model,
    ``WindowMaterial:SimpleGlazingSystem``, whose fields these are, in its order).

    u_factor: with films [W/(m²·K)]; shgc: solar heat gain coefficient at normal incidence [-];
    visible_transmittance [-].
    """

    name: str
    u_factor: float
    shgc: float
    visible_transmittance: float


@dataclass(frozen=True)
class Gas:
    """A gas gap of a glazing unit. thickness [m]"""

    name: str
    thickness: float
    gas: str = "Air"


@dataclass(frozen=True)
class AirGap:
    """A resistance-only layer. resistance [m²·K/W]"""

    name: str
    resistance: float


Layer = Material | AirGap | Glazing | SimpleGlazing | Gas


@dataclass(frozen=True)
class Construction:
    """Layers from outside to inside."""

    name: str
    layers: tuple[Layer, ...]

    @property
    def conductance(self) -> float:
        """Surface-to-surface conductance of the layers, films excluded. [W/(m²·K)]"""
        r = sum(
            m.thickness / m.conductivity if isinstance(m, Material) else m.resistance
            for m in self.layers
            if isinstance(m, Material | AirGap)
        )
        return 1.0 / r


# --- ASHRAE 2005 HOF materials (values of EnergyPlus's dataset) -----------------------------
BRICK_100 = Material("M01 100mm brick", 0.1016, 0.89, 1920.0, 790.0)
INSULATION_25 = Material("I01 25mm insulation board", 0.0254, 0.03, 43.0, 1210.0)
INSULATION_50 = Material("I02 50mm insulation board", 0.0508, 0.03, 43.0, 1210.0)
WALL_AIR_SPACE = AirGap("F04 Wall air space resistance", 0.15)
GYPSUM_19 = Material("G01a 19mm gypsum board", 0.019, 0.16, 800.0, 1090.0, "MediumSmooth")
CONCRETE_BLOCK_200 = Material("M05 200mm concrete block", 0.2032, 1.11, 800.0, 920.0)
ACOUSTIC_TILE = Material("F16 Acoustic tile", 0.0191, 0.06, 368.0, 590.0, "MediumSmooth")
HEAVY_CONCRETE_100 = Material("M14a 100mm heavyweight concrete", 0.1016, 1.95, 2240.0, 900.0)
HEAVY_CONCRETE_200 = Material("M15 200mm heavyweight concrete", 0.2032, 1.95, 2240.0, 900.0)
WOOD_25 = Material("G05 25mm wood", 0.0254, 0.15, 608.0, 1630.0, "MediumSmooth")

# --- WindowGlassMaterials.idf / WindowGasMaterials.idf --------------------------------------
CLEAR_3MM = Glazing("CLEAR 3MM", 0.003, 0.837, 0.075, 0.898, 0.081, 0.84, 0.9)
AIR_13MM = Gas("AIR 13MM", 0.0127)

# --- thesis Table 2.1 (outside → inside) -----------------------------------------------------
WINDOW_DOUBLE_CLEAR = Construction("Double clear 3mm/13mm air", (CLEAR_3MM, AIR_13MM, CLEAR_3MM))
EXTERIOR_WALL = Construction("Exterior wall", (BRICK_100, INSULATION_50, WALL_AIR_SPACE, GYPSUM_19))
FLOOR = Construction(
    "Floor", (CONCRETE_BLOCK_200, ACOUSTIC_TILE, WALL_AIR_SPACE, HEAVY_CONCRETE_100, WOOD_25)
)
ROOF = Construction("Roof", (HEAVY_CONCRETE_100, WALL_AIR_SPACE, INSULATION_50, ACOUSTIC_TILE))
PARTITION = Construction("Partition", (GYPSUM_19, WALL_AIR_SPACE, GYPSUM_19))


# --- weekly schedules ------------------------------------------------------------------------
@dataclass(frozen=True)
class WeekSchedule:
    """Profiles of a weekday, a Saturday and a Sunday."""

    weekday: DayProfile
    saturday: DayProfile
    sunday: DayProfile


OFF_DAY: DayProfile = (("24:00", 0.0),)


def day_profile(until: tuple[str, ...], values: tuple[float, ...]) -> DayProfile:
    """A day as its "HH:MM" ends of periods (the last 24:00) and each period's value."""
    return tuple(zip(until, values, strict=True))


OFFICE_OCCUPANCY = WeekSchedule(
    weekday=day_profile(
        ("06:00", "07:00", "08:00", "12:00", "13:00", "17:00", "18:00", "22:00", "24:00"),
        (0.0, 0.1, 0.2, 0.95, 0.5, 0.95, 0.3, 0.1, 0.05),
    ),
    saturday=day_profile(
        ("06:00", "08:00", "12:00", "17:00", "19:00", "24:00"), (0.0, 0.1, 0.3, 0.1, 0.05, 0.0)
    ),
    sunday=OFF_DAY,
)
OFFICE_LIGHTING = WeekSchedule(
    weekday=day_profile(
        ("05:00", "07:00", "08:00", "17:00", "18:00", "20:00", "22:00", "23:00", "24:00"),
        (0.05, 0.1, 0.3, 0.9, 0.5, 0.3, 0.2, 0.1, 0.05),
    ),
    saturday=(("06:00", 0.05), ("08:00", 0.1), ("12:00", 0.3), ("17:00", 0.15), ("24:00", 0.05)),
    sunday=OFF_DAY,
)


def heating_availability(
    weekday_hours: tuple[int, int], saturday_hours: tuple[int, int] | None
) -> WeekSchedule:
    """On/off availability: on from the first to the second hour; Sundays off."""

    def day(hours: tuple[int, int] | None) -> DayProfile:
        if hours is None:
            return OFF_DAY
        on, off = hours
        return ((f"{on:02d}:00", 0.0), (f"{off:02d}:00", 1.0), ("24:00", 0.0))

    return WeekSchedule(day(weekday_hours), day(saturday_hours), OFF_DAY)


NEVER = WeekSchedule(OFF_DAY, OFF_DAY, OFF_DAY)
