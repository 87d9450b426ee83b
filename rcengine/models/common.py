"""Pieces shared by the model builders: the thesis's reference sizes and gain inputs."""

from __future__ import annotations

from collections.abc import Collection

from rcengine.columns import Q_HVAC, Q_LIGHT, Q_OCC
from rcengine.network import RCNetwork

# The thesis office (§2.4.1) the default bounds of Table 2.3 were set for; bounds on whole-building
# quantities (c_air [J/K], absorption areas [m²]) scale from it to other buildings.
THESIS_VOLUME_M3 = 3150.0
THESIS_WALL_AREA_M2 = 455.0
THESIS_FLOOR_AREA_M2 = 1050.0


def has(inputs: Collection[str] | None, column: str) -> bool:
    """Whether the data provide ``column`` (None means: assume every column is there)."""
    return inputs is None or column in inputs


def add_internal_gains(
    net: RCNetwork, inputs: Collection[str] | None, air: str, radiant: str
) -> RCNetwork:
    """HVAC and occupants heat the air node; lights the radiant (mass) node — thesis Fig. 2.9.

    Occupant heat is taken as convective to air and lighting as radiant to the internal mass,
    as the thesis models them. Absent optional gain columns are left out (unknown physics).
    """
    net.add_heat_input(Q_HVAC, air)
    if has(inputs, Q_OCC):
        net.add_heat_input(Q_OCC, air)
    if has(inputs, Q_LIGHT):
        net.add_heat_input(Q_LIGHT, radiant)
    return net
