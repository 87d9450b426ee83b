"""One building of the test bed: an archetype (``archetypes``) turned in plan, with its ordinary
glazing and the switches of its concealed effects, as EnergyPlus zones and surfaces.

Plan coordinates (x east, y north) are turned clockwise seen from above by
``Variant.rotation_deg``: a facade facing south at 0° faces 180° + rotation. Zones are the boxes
of the archetype's grid; walls between rows and floors between storeys are interzone surfaces.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from . import zones
from .archetypes import Archetype, Calendar, radiant_floor
from .geometry import SIDES, Box, Point2, Point3, VerticalRect
from .idf import (
    RunPeriod,
    SiteInfo,
    building_ground_temperatures,
    building_surface,
    header,
    materials_and_constructions,
    output_variables,
    sky_at_air_temperature,
    week_schedule,
    window_surface,
)
from .library import (
    Construction,
    Material,
    SimpleGlazing,
    WeekSchedule,
)
from .shoebox import (
    HEAVY_MASS,
    OFFICE_EQUIPMENT,
    OUTPUTS,
    VENTILATION_HOURS,
    local_wind_factor,
    replay_schedule,
)

# ISO 6946 surface resistances: outside, inside horizontal / upward / downward flow. [m²·K/W]
R_SE, R_SI_WALL, R_SI_UP, R_SI_DOWN = 0.04, 0.13, 0.10, 0.17
RHO_CP_AIR = 1.2 * 1005.0  # [J/(m³·K)]
# Wind speed at which a wind-driven leak is sized into the heater (a windy design day). [m/s]
DESIGN_WIND = 4.0
STOREY_NAMES = ("Ground", "First")
ROW_NAMES = ("South", "North")
OPPOSITE = {"north": "south", "south": "north", "east": "west", "west": "east"}
IDEAL_HEATING = "Zone Ideal Loads Zone Sensible Heating Rate"
RADIANT_HEATING = "Zone Radiant HVAC Heating Rate"


@dataclass(frozen=True)
class Zone:
    """One box zone of the grid: storey (0 = ground) and row (0 = south)."""

    name: str
    box: Box
    storey: int
    row: int


def turn(point: Point2, degrees: float) -> Point2:
    """``point`` turned clockwise (seen from above) about the origin. [m]"""
    a = math.radians(degrees)
    x, y = point
    return (x * math.cos(a) + y * math.sin(a), -x * math.sin(a) + y * math.cos(a))


def turn_rect(rect: VerticalRect, degrees: float) -> VerticalRect:
    return replace(rect, left=turn(rect.left, degrees), right=turn(rect.right, degrees))


def turn_points(points: list[Point3], degrees: float) -> list[Point3]:
    return [(*turn((x, y), degrees), z) for x, y, z in points]


def u_value(c: Construction, r_si: float, r_se: float = R_SE) -> float:
    """Thermal transmittance with surface films. [W/(m²·K)]"""
    return 1.0 / (r_se + 1.0 / c.conductance + r_si)


def reversed_construction(c: Construction) -> Construction:
    """The same layers seen from the other side (the partner of an interzone surface)."""
    return Construction(f"{c.name} reversed", c.layers[::-1])


def window_construction(glazing: SimpleGlazing) -> Construction:
    return Construction(f"Window {glazing.name}", (glazing,))


# Large windows: nearly storey-high, 0.3 m above the floor to 0.3 m below the ceiling. [m]
LARGE_SILL, LARGE_HEAD_GAP = 0.3, 0.3


@dataclass(frozen=True)
class Variant:
    """One building of the test bed: an archetype, its orientation and ordinary glazing, and
    the switches of the concealed effects (all off by default).

    rotation_deg: plan rotation, clockwise [°]; wwr: glazed share of every facade [-];
    large_glazing: sides (before rotation) whose facades have large windows of glazed share
    ``large_share`` [-] and solar heat gain coefficient ``large_g`` (None: the archetype's
    glazing; the reference admits only the sun of ordinary windows); dark_walls: facade construction
    instead of the archetype's; wall_sun: facades absorb sun (False: solar absorptance 0);
    ach_per_wind: extra infiltration per m/s of weather-station wind [1/h per m/s];
    ventilation_ach: outdoor air on weekdays 08:00–18:00 [1/h]; unmetered_w_m2: plug loads in
    no column, peak [W/m²]; ground_slab: ground floor on the soil instead of the archetype's;
    roof: roof construction instead of the archetype's; sky_at_air_temperature: the sky
    radiates at the outdoor air temperature; extra_mass_area: exposed 200 mm concrete [m²];
    radiant_screed_mm: electric radiant floor under this screed instead of ideal loads [mm];
    replayed_heat: zone → heat put straight into its air instead of any heating, per local
    standard-time interval start on EnergyPlus's schedule clock (``schedule_clock``) [W].
    """

    archetype: Archetype
    rotation_deg: float = 0.0
    wwr: float = 0.2
    large_glazing: tuple[str, ...] = ()
    large_share: float = 0.6
    large_g: float | None = None
    dark_walls: Construction | None = None
    wall_sun: bool = True
    ach_per_wind: float = 0.0
    ventilation_ach: float = 0.0
    unmetered_w_m2: float = 0.0
    ground_slab: Construction | None = None
    roof: Construction | None = None
    sky_at_air_temperature: bool = False
    extra_mass_area: float = 0.0
    radiant_screed_mm: int = 0
    replayed_heat: Mapping[str, pd.Series] | None = field(default=None, compare=False)

    # --- geometry ---------------------------------------------------------------------------
    def zones(self) -> list[Zone]:
        a = self.archetype
        if a.rows not in (1, 2) or a.storeys not in (1, 2):
            raise ValueError(f"{a.name}: one or two rows and storeys are supported")
        row_depth = a.depth / a.rows
        out = []
        for storey in range(a.storeys):
            for row in range(a.rows):
                parts = ([STOREY_NAMES[storey]] if a.storeys > 1 else []) + (
                    [ROW_NAMES[row]] if a.rows > 1 else []
                )
                box = Box(
                    0.0,
                    a.width,
                    row * row_depth,
                    (row + 1) * row_depth,
                    a.storey_height,
                    storey * a.storey_height,
                )
                out.append(Zone(" ".join(parts) or a.zone_name, box, storey, row))
        return out

    def zone_areas(self) -> dict[str, float]:
        """Floor area of each zone, the weights of the mean air temperature. [m²]"""
        return {z.name: z.box.floor_area for z in self.zones()}

    def exterior_walls(self) -> list[VerticalRect]:
        """Gross exterior walls (windows included), turned."""
        return [
            turn_rect(z.box.wall(side), self.rotation_deg)
            for z in self.zones()
            for side in SIDES
            if self._neighbour(z, side) is None
        ]

    def windows(self) -> list[VerticalRect]:
        out = []
        for z in self.zones():
            for side in SIDES:
                window = self._window(z, side) if self._neighbour(z, side) is None else None
                if window is not None:
                    out.append(turn_rect(window[0], self.rotation_deg))
        return out

    @property
    def roof_area(self) -> float:
        return self.archetype.width * self.archetype.depth

    @property
    def internal_mass_area(self) -> float:
        """Internal mass, partitions between zones and floors between storeys (both faces). [m²]"""
        a = self.archetype
        between_rows = (a.rows - 1) * a.width * a.storey_height * a.storeys
        between_storeys = (a.storeys - 1) * a.width * a.depth
        return (
            a.mass_per_floor * a.floor_area
            + self.extra_mass_area
            + 2.0 * (between_rows + between_storeys)
        )

    def _neighbour(self, z: Zone, side: str) -> Zone | None:
        row = z.row + {"north": 1, "south": -1}.get(side, 0)
        if side in ("east", "west") or not 0 <= row < self.archetype.rows:
            return None
        return self._at(z.storey, row)

    def _at(self, storey: int, row: int) -> Zone:
        return next(z for z in self.zones() if z.storey == storey and z.row == row)

    def _window(self, z: Zone, side: str) -> tuple[VerticalRect, SimpleGlazing] | None:
        """The window of an exterior wall (before turning) and its glazing."""
        a = self.archetype
        large = side in self.large_glazing
        share = self.large_share if large else self.wwr
        if share <= 0.0:
            return None
        wall = z.box.wall(side)
        sill, head = (LARGE_SILL, a.storey_height - LARGE_HEAD_GAP) if large else (a.sill, a.head)
        width = share * wall.area / (head - sill)
        rect = wall.window(width, wall.z_bottom + sill, wall.z_bottom + head)
        glazing = a.glazing
        if large and self.large_g is not None:
            glazing = SimpleGlazing(
                f"{glazing.name} g{self.large_g:.3f}",
                glazing.u_factor,
                self.large_g,
                glazing.visible_transmittance,
            )
        return rect, glazing

    # --- constructions ----------------------------------------------------------------------
    def _wall(self) -> Construction:
        c = self.dark_walls or self.archetype.wall
        if self.wall_sun:
            return c
        outer = c.layers[0]
        if not isinstance(outer, Material):
            raise TypeError(f"{c.name}: the outer layer must be a material")
        dull = outer.surface(f"{outer.name} no sun", outer.thermal_absorptance, 0.0)
        return Construction(f"{c.name} no sun", (dull, *c.layers[1:]))

    def _roof(self) -> Construction:
        return self.roof or self.archetype.roof

    def _ground_floor(self) -> tuple[Construction, str]:
        """Construction and outside boundary condition of the ground floor."""
        a = self.archetype
        if self.radiant_screed_mm:
            if self.ground_slab is not None or a.storeys > 1:
                raise ValueError("a radiant floor needs a single storey off the ground")
            return radiant_floor(a.floor, self.radiant_screed_mm), a.floor_boundary
        if self.ground_slab is not None:
            return self.ground_slab, "Ground"
        return a.floor, a.floor_boundary

    def _constructions(self) -> list[Construction]:
        a = self.archetype
        used = [self._wall(), self._roof(), self._ground_floor()[0], a.internal_mass]
        if a.intermediate_floor is not None:
            used += [a.intermediate_floor, reversed_construction(a.intermediate_floor)]
        if a.partition is not None:
            used.append(a.partition)
        if self.extra_mass_area > 0.0:
            used.append(HEAVY_MASS)
        glazings = {
            w[1].name: w[1]
            for z in self.zones()
            for side in SIDES
            if (w := self._window(z, side)) is not None
        }
        used += [window_construction(g) for g in glazings.values()]
        return list({c.name: c for c in used}.values())

    # --- IDF --------------------------------------------------------------------------------
    def idf(
        self,
        site: SiteInfo,
        period: RunPeriod,
        calendar: Calendar,
        capacities: Mapping[str, float],
    ) -> str:
        """The whole model; ``capacities``: heater size of each zone (``heating_capacities``,
        of the case's own building, so that its references heat alike). [W]"""
        parts = [
            header(self.archetype.name, site, period, timesteps_per_hour=4),
            calendar.objects(),
            materials_and_constructions(self._constructions()),
            week_schedule("Occupancy", self.archetype.occupancy),
            week_schedule("Lighting", self.archetype.lighting),
            week_schedule("Heating Setpoint", self._setpoints(), "Any"),
            zones.activity_schedule(),
            zones.single_heating_control_schedule(),
            *self._shared_effects(site),
            *(self._zone(z, capacities[z.name]) for z in self.zones()),
            output_variables(OUTPUTS + self._heating_outputs()),
        ]
        return "".join(parts)

    def _setpoints(self) -> WeekSchedule:
        a = self.archetype
        on, off = a.heated_hours
        setback = (("24:00", a.setback),)
        weekday = ((f"{on:02d}:00", a.setback), (f"{off:02d}:00", a.occupied_setpoint))
        return WeekSchedule(weekday + setback, setback, setback)

    def _shared_effects(self, site: SiteInfo) -> list[str]:
        out = []
        if self.ventilation_ach > 0.0:
            out.append(week_schedule("Ventilation Hours", VENTILATION_HOURS, "OnOff"))
        if self.unmetered_w_m2 > 0.0:
            out.append(week_schedule("Equipment", OFFICE_EQUIPMENT))
        if self.ground_slab is not None:
            out.append(building_ground_temperatures(site))
        if self.sky_at_air_temperature:
            out.append(sky_at_air_temperature())
        if self.replayed_heat is not None:
            out += [
                replay_schedule(f"{zone} Replayed Heat", heat)
                for zone, heat in self.replayed_heat.items()
            ]
        return out

    def _zone(self, z: Zone, capacity_w: float) -> str:
        a = self.archetype
        area = z.box.floor_area
        out = [zones.zone(z.name), *self._surfaces(z)]
        out.append(
            zones.internal_mass(z.name, a.internal_mass.name, a.mass_per_floor * area, "Mass")
        )
        if self.extra_mass_area > 0.0:
            share = self.extra_mass_area * area / a.floor_area
            out.append(zones.internal_mass(z.name, HEAVY_MASS.name, share, "Concrete"))
        out += [
            zones.people(z.name, area / a.m2_per_person, "Occupancy", "Activity"),
            zones.lights(z.name, a.lights_w_m2, "Lighting"),
            self._infiltration(z),
        ]
        if self.ventilation_ach > 0.0:
            out.append(zones.ventilation(z.name, self.ventilation_ach, "Ventilation Hours"))
        if self.unmetered_w_m2 > 0.0:
            out.append(zones.electric_equipment(z.name, self.unmetered_w_m2, "Equipment"))
        out.append(self._heating(z, capacity_w))
        return "".join(out)

    def _infiltration(self, z: Zone) -> str:
        a = self.archetype
        if self.ach_per_wind == 0.0:
            return zones.infiltration(z.name, a.infiltration_ach)
        # Design level 1 ACH: constant term = base rate, velocity term per local m/s.
        per_local = self.ach_per_wind / local_wind_factor(z.box.z0 + z.box.height / 2.0)
        return zones.infiltration(z.name, 1.0, constant=a.infiltration_ach, per_wind=per_local)

    def _surfaces(self, z: Zone) -> list[str]:
        a, deg = self.archetype, self.rotation_deg
        wall_construction = self._wall().name
        out = []
        for side in SIDES:
            name = f"{z.name} {side.capitalize()} Wall"
            vertices = turn_rect(z.box.wall(side), deg).vertices()
            other = self._neighbour(z, side)
            if other is not None and a.partition is not None:
                partner = f"{other.name} {OPPOSITE[side].capitalize()} Wall"
                out.append(
                    building_surface(
                        name, "Wall", a.partition.name, z.name, vertices, "Surface", partner
                    )
                )
                continue
            out.append(building_surface(name, "Wall", wall_construction, z.name, vertices))
            window = self._window(z, side)
            if window is not None:
                rect, glazing = window
                construction = window_construction(glazing).name
                out.append(
                    window_surface(f"{name} Window", construction, name, turn_rect(rect, deg))
                )
        return [*out, self._top(z), self._bottom(z)]

    def _top(self, z: Zone) -> str:
        a, roof = self.archetype, turn_points(z.box.roof(), self.rotation_deg)
        if z.storey == a.storeys - 1 or a.intermediate_floor is None:
            return building_surface(f"{z.name} Roof", "Roof", self._roof().name, z.name, roof)
        above = self._at(z.storey + 1, z.row).name
        ceiling = reversed_construction(a.intermediate_floor).name
        return building_surface(
            f"{z.name} Ceiling", "Ceiling", ceiling, z.name, roof, "Surface", f"{above} Floor"
        )

    def _bottom(self, z: Zone) -> str:
        a, floor = self.archetype, turn_points(z.box.floor(), self.rotation_deg)
        if z.storey > 0 and a.intermediate_floor is not None:
            below = self._at(z.storey - 1, z.row).name
            return building_surface(
                f"{z.name} Floor",
                "Floor",
                a.intermediate_floor.name,
                z.name,
                floor,
                "Surface",
                f"{below} Ceiling",
            )
        construction, boundary = self._ground_floor()
        return building_surface(
            f"{z.name} Floor",
            "Floor",
            construction.name,
            z.name,
            floor,
            boundary,
            sun=False,
            wind=False,
        )

    def _heating(self, z: Zone, capacity_w: float) -> str:
        if self.replayed_heat is not None:
            return zones.heat_into_air(z.name, f"{z.name} Replayed Heat")
        if self.radiant_screed_mm:
            return zones.radiant_floor_heating(
                z.name,
                f"{z.name} Floor",
                self._ground_floor()[0].name,
                len(self.archetype.floor.layers),
                capacity_w,
                "Heating Setpoint",
                "Heating Availability",
                name=f"{z.name} Radiant Floor",
                with_source=z == self.zones()[0],
            )
        return zones.ideal_loads_heating(
            z.name, "Heating Setpoint", "Heating Availability", capacity_w
        )

    def _heating_outputs(self) -> tuple[str, ...]:
        if self.replayed_heat is not None:
            return ()
        if self.radiant_screed_mm:
            return (RADIANT_HEATING,)
        return (IDEAL_HEATING, "Zone Ideal Loads Zone Sensible Cooling Rate")

    def heater_keys(self) -> tuple[str, dict[str, str]]:
        """The EnergyPlus variable reporting the heating, and each zone's key in it."""
        variable, suffix = (IDEAL_HEATING, "Ideal Loads")
        if self.radiant_screed_mm:
            variable, suffix = (RADIANT_HEATING, "Radiant Floor")
        return variable, {z.name: f"{z.name} {suffix}".upper() for z in self.zones()}

    # --- heater sizing ----------------------------------------------------------------------
    def heating_capacities(self, t_design: float, t_ground: float) -> dict[str, float]:
        """Heater size of each zone: ``capacity_factor`` × its design heat loss at the occupied
        setpoint and the outdoor design temperature ``t_design`` (a slab loses to the coldest
        monthly ground temperature ``t_ground``). [W]"""
        a = self.archetype
        delta = a.occupied_setpoint - t_design
        ground_share = (a.occupied_setpoint - t_ground) / delta
        return {
            z.name: a.capacity_factor * self._design_conductance(z, ground_share) * delta
            for z in self.zones()
        }

    def _design_conductance(self, z: Zone, ground_share: float) -> float:
        """Heat loss of zone ``z`` per kelvin between setpoint and outdoor air, windy design
        day; slabs count with ``ground_share`` of their conductance. [W/K]"""
        a = self.archetype
        ua = 0.0
        for side in SIDES:
            if self._neighbour(z, side) is not None:
                continue
            window = self._window(z, side)
            glazed = 0.0 if window is None else window[0].area
            ua += glazed * a.glazing.u_factor
            ua += (z.box.wall(side).area - glazed) * u_value(self._wall(), R_SI_WALL)
        if z.storey == a.storeys - 1:
            ua += z.box.floor_area * u_value(self._roof(), R_SI_UP)
        if z.storey == 0:
            floor, boundary = self._ground_floor()
            if boundary == "Outdoors":
                ua += z.box.floor_area * u_value(floor, R_SI_DOWN)
            elif boundary == "Ground":
                ua += z.box.floor_area * u_value(floor, R_SI_DOWN, r_se=0.0) * ground_share
        ach = a.infiltration_ach + self.ach_per_wind * DESIGN_WIND + self.ventilation_ach
        return ua + ach * z.box.volume * RHO_CP_AIR / 3600.0


def schedule_clock(heat: pd.Series, tz_offset_h: float, timezone: str) -> pd.Series:
    """``heat`` (indexed by local standard-time interval starts, ``tz_offset_h`` east of UTC)
    re-indexed on the clock of EnergyPlus's schedules, for ``replay_schedule`` in a run with the
    daylight saving of the IANA ``timezone``.

    EnergyPlus reads a schedule one hour ahead on its daylight-saving days — whole standard-time
    days, the change days included (daylight saving holds at the day's start or its end) — and
    the last hour of such a day in the next day's first. Where two intervals land on one
    schedule time (the first hour after the autumn change) the later one is kept.
    """
    standard = pd.Timedelta(hours=tz_offset_h)

    def daylight_saving(utc: pd.DatetimeIndex) -> np.ndarray:
        civil = utc.tz_convert(timezone).tz_localize(None)
        return np.asarray(civil - utc.tz_localize(None) != standard)

    day_start = (heat.index.normalize() - standard).tz_localize("UTC")
    shifted = daylight_saving(day_start) | daylight_saving(day_start + pd.Timedelta(days=1))
    clock = pd.Series(heat.to_numpy(), index=heat.index + pd.to_timedelta(shifted.astype(int), "h"))
    return clock[~clock.index.duplicated(keep="last")]
