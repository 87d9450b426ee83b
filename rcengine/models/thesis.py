"""The thesis's 3R3C models (§2.4.2–2.4.3): "Basic" (horizontal irradiance) and "Sun" (geometric
solar module).

Network (thesis Fig. 2.9): three capacitors — external walls, indoor air, internal mass — and
three resistors in a chain  t_out —R_we— wall —R_wi— air —R_i— internal mass.  Resistances and the
wall and mass capacities are per unit area (Table 2.2): R_we = r_wall_ext / A_wall,
R_wi = r_wall_int / A_wall, R_i = r_int / A_floor, C_wall = c_wall · A_wall, C_int = c_int · A_mass.
"""

from __future__ import annotations

from collections.abc import Collection

from rcengine.building import Building
from rcengine.columns import GHI, SOLAR_OPAQUE, SOLAR_WINDOW, T_OUT
from rcengine.exceptions import BuildingError
from rcengine.models.common import (
    THESIS_FLOOR_AREA_M2,
    THESIS_VOLUME_M3,
    THESIS_WALL_AREA_M2,
    add_internal_gains,
)
from rcengine.network import Parameter, RCNetwork


def _mass_area(building: Building) -> float:
    # A building JSON without internal_mass_area: the floor is the internal mass (thesis §2.4.2).
    return building.internal_mass_area or building.floor_area


def _three_r_three_c(name: str, building: Building, description: str) -> RCNetwork:
    """The common 3R3C skeleton with the bounds of thesis Table 2.3."""
    v = building.volume / THESIS_VOLUME_M3
    net = RCNetwork(name, description=description)
    for p in (
        Parameter(
            "r_wall_ext",
            "m²K/W",
            0.1,
            8.0,
            "resistance between outdoor air and the external-wall node, per wall area",
        ),
        Parameter(
            "r_wall_int",
            "m²K/W",
            0.1,
            8.0,
            "resistance between the external-wall node and the indoor air, per wall area",
        ),
        Parameter(
            "r_int",
            "m²K/W",
            0.01,
            3.0,
            "resistance between the indoor air and the internal mass, per floor area",
        ),
        Parameter(
            "c_wall", "J/(K·m²)", 1e4, 1e6, "heat capacity of the external walls per wall area"
        ),
        Parameter(
            "c_air",
            "J/K",
            1e5 * v,
            1e7 * v,
            "heat capacity of the indoor air and fast furniture (Table 2.3 scaled by volume)",
        ),
        Parameter(
            "c_int",
            "J/(K·m²)",
            1e4,
            1e6,
            "heat capacity of the internal mass per internal-mass area",
        ),
    ):
        net.add_parameter(p)
    wall_area, floor_area = building.wall_area, building.floor_area
    net.add_capacitor("wall", "c_wall", factor=wall_area)
    net.add_capacitor("air", "c_air")
    net.add_capacitor("int", "c_int", factor=_mass_area(building))
    net.add_resistor(T_OUT, "wall", "r_wall_ext", factor=1.0 / wall_area)
    net.add_resistor("wall", "air", "r_wall_int", factor=1.0 / wall_area)
    net.add_resistor("air", "int", "r_int", factor=1.0 / floor_area)
    net.set_output("air")
    return net


def basic(building: Building, inputs: Collection[str] | None = None) -> RCNetwork:
    """3R3C "Basic" model of the thesis: global horizontal irradiance split by two absorption areas.

    Inputs: t_out [°C], ghi [W/m²] → wall (alpha_wall [m²]) and internal mass (alpha_int [m²]),
    q_hvac and q_occ [W] → air, q_light [W] → internal mass. Output: indoor air temperature.
    """
    net = _three_r_three_c(
        "basic", building, "thesis 3R3C Basic model (§2.4.2): ghi split by absorption areas"
    )
    net.add_parameter(
        Parameter(
            "alpha_wall",
            "m²",
            0.0,
            60.0 * building.wall_area / THESIS_WALL_AREA_M2,
            "equivalent area absorbing ghi on the external walls (Table 2.3 scaled by wall area)",
        )
    )
    net.add_parameter(
        Parameter(
            "alpha_int",
            "m²",
            0.0,
            40.0 * building.floor_area / THESIS_FLOOR_AREA_M2,
            "equivalent area passing ghi to the internal mass (Table 2.3 scaled by floor area)",
        )
    )
    net.add_heat_input(GHI, "wall", "alpha_wall")
    net.add_heat_input(GHI, "int", "alpha_int")
    return add_internal_gains(net, inputs, air="air", radiant="int")


def sun(building: Building, inputs: Collection[str] | None = None) -> RCNetwork:
    """3R3C "Sun" model of the thesis: solar heat on opaque walls and through windows by geometry.

    Inputs as ``basic`` but the irradiance comes from the solar module: solar_opaque [W] (Σ wall
    area × plane-of-array irradiance) → wall with absorbed fraction alpha_wall [-], and
    solar_window [W] (Σ window area × transmitted irradiance) → internal mass with alpha_int [-].
    Bounds from thesis Table 2.4.
    """
    if not building.windows or not building.walls:
        raise BuildingError(
            "model 'sun' needs 'windows' and 'walls' (azimuth, tilt, area) in the building JSON"
        )
    net = _three_r_three_c(
        "sun", building, "thesis 3R3C Sun model (§2.4.3): solar heat resolved by surface"
    )
    net.add_parameter(
        Parameter(
            "alpha_wall",
            "-",
            0.0,
            0.25,
            "fraction of opaque-wall irradiance reaching the wall node",
        )
    )
    net.add_parameter(
        Parameter(
            "alpha_int",
            "-",
            0.0,
            0.95,
            "fraction of window irradiance absorbed by the internal mass",
        )
    )
    net.add_heat_input(SOLAR_OPAQUE, "wall", "alpha_wall")
    net.add_heat_input(SOLAR_WINDOW, "int", "alpha_int")
    return add_internal_gains(net, inputs, air="air", radiant="int")
