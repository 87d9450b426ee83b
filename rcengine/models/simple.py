"""Low-order networks to move down in model order: 1R1C and 2R2C."""

from __future__ import annotations

from collections.abc import Collection

from rcengine.building import Building
from rcengine.columns import GHI, T_OUT
from rcengine.models.common import THESIS_VOLUME_M3, add_internal_gains
from rcengine.network import Parameter, RCNetwork


def r1c1(building: Building, inputs: Collection[str] | None = None) -> RCNetwork:
    """1R1C: one lumped zone capacity behind one envelope resistance.

    C_zone dT/dt = (t_out − T)/R_env + alpha_sol·ghi + q_hvac + q_occ + q_light, with
    C_zone = c_zone · A_floor [J/K] and R_env = r_env / A_wall [K/W].
    """
    net = RCNetwork("1r1c", description="one lumped capacity behind one envelope resistance")
    net.add_parameter(
        Parameter(
            "r_env",
            "m²K/W",
            0.02,
            10.0,
            "envelope resistance (conduction, air exchange), per wall area",
        )
    )
    net.add_parameter(
        Parameter("c_zone", "J/(K·m²)", 1e3, 2e6, "heat capacity of the whole zone per floor area")
    )
    net.add_parameter(
        Parameter(
            "alpha_sol", "m²", 0.0, 0.1 * building.floor_area, "equivalent area absorbing ghi"
        )
    )
    net.add_capacitor("air", "c_zone", factor=building.floor_area)
    net.add_resistor(T_OUT, "air", "r_env", factor=1.0 / building.wall_area)
    net.add_heat_input(GHI, "air", "alpha_sol")
    net.set_output("air")
    return add_internal_gains(net, inputs, air="air", radiant="air")


def r2c2(building: Building, inputs: Collection[str] | None = None) -> RCNetwork:
    """2R2C: envelope capacity and indoor-air capacity in a chain (t_out — wall — air).

    C_wall = c_wall · A_wall, R_we = r_wall_ext / A_wall, R_wi = r_wall_int / A_wall; ghi is split
    into the wall (alpha_wall [m²]) and the air node (alpha_air [m²]); every gain heats the air.
    """
    v = building.volume / THESIS_VOLUME_M3
    net = RCNetwork("2r2c", description="envelope and indoor-air capacities in a chain")
    for p in (
        Parameter("r_wall_ext", "m²K/W", 0.02, 8.0, "outdoor air to envelope node, per wall area"),
        Parameter("r_wall_int", "m²K/W", 0.02, 8.0, "envelope node to indoor air, per wall area"),
        Parameter("c_wall", "J/(K·m²)", 1e4, 2e6, "envelope heat capacity per wall area"),
        Parameter("c_air", "J/K", 1e5 * v, 1e8 * v, "indoor air, furniture and light mass"),
        Parameter(
            "alpha_wall", "m²", 0.0, 0.15 * building.wall_area, "ghi absorbed by the envelope"
        ),
        Parameter("alpha_air", "m²", 0.0, 0.1 * building.floor_area, "ghi reaching the indoor air"),
    ):
        net.add_parameter(p)
    net.add_capacitor("wall", "c_wall", factor=building.wall_area)
    net.add_capacitor("air", "c_air")
    net.add_resistor(T_OUT, "wall", "r_wall_ext", factor=1.0 / building.wall_area)
    net.add_resistor("wall", "air", "r_wall_int", factor=1.0 / building.wall_area)
    net.add_heat_input(GHI, "wall", "alpha_wall")
    net.add_heat_input(GHI, "air", "alpha_air")
    net.set_output("air")
    return add_internal_gains(net, inputs, air="air", radiant="air")
