"""What the building description declares, given to the base model before anything is judged.

A diagnosis asks which physics the model leaves out that the building has. Glazing listed in the
building JSON is not left out by the building's owner: its area and orientation are known, only
its g-value is not. A base model that cannot carry declared windows (the thesis's "Basic" model
sees the sun only as ghi on two lumped apertures) would have every building with ordinary windows
"missing window solar gains"; so the base model is given the declared glazing — one g-value for
all of it, fitted within what glazing can transmit — and the window candidate looks for sun
beyond it (``candidates.window_solar_gains``).

The declared glazing enters as ISO 52016-1 and ISO 13790 §11.3 put it: the transmitted sun is
absorbed by the interior surfaces (the mass node) with a share heating the air directly, and the
glazing is a massless conductance from the air to outdoors (U_w·A_w) when the model has none.
"""

from __future__ import annotations

from rcengine.building import Building
from rcengine.columns import SOLAR_WINDOW, T_OUT
from rcengine.models.bounds import G_GLAZING_MAX, RHO_CP_AIR, U_GLAZING
from rcengine.network import Parameter, RCNetwork

# The declared glazing's g-values: into the interior mass, and into the air directly.
G_WINDOW, G_WINDOW_AIR = "g_window", "g_window_air"
# The share of it absorbed by a storage a diagnosis added (``sun_on_added_mass``).
G_WINDOW_ADDED_MASS = "g_window_mass_extra"
# Steady air leakage the glazing conductance may also carry where the model has no other direct
# path from the air to outdoors: a leaky building's infiltration (EN 12831-1 Table B.5). [1/h]
LEAKAGE_ACH = 1.0


def glazing_area(building: Building) -> float:
    """Σ declared window area. [m²]"""
    return sum(w.area for w in building.windows)


def has_declared_glazing(network: RCNetwork) -> bool:
    """Whether the network already takes the sun through the declared glazing."""
    return SOLAR_WINDOW in network.signals


def has_glazing_g(network: RCNetwork) -> bool:
    """Whether the network takes the sun through declared glazing with a fitted g-value (the
    base model given the description's windows, ``with_declared_glazing``)."""
    return has_declared_glazing(network) and G_WINDOW in network.parameters


def with_declared_glazing(network: RCNetwork, building: Building, mass: str) -> RCNetwork:
    """``network`` with the building's declared windows (a copy; the network itself when it has
    them already or none are declared).

    Adds g_window × solar_window into ``mass`` (the interior surfaces), g_window_air ×
    solar_window into the air, and, where the air has no resistance to outdoors, r_window per m²
    of glazing between them. solar_window = Σ A_w · transmitted irradiance [W].
    """
    if not building.windows or has_declared_glazing(network):
        return network
    area, air = glazing_area(building), network.output
    net = network.copy(network.name)
    net.add_parameter(
        Parameter(
            G_WINDOW,
            "-",
            0.0,
            G_GLAZING_MAX,
            f"g-value of the declared glazing ({area:g} m²): transmitted sun absorbed indoors",
        )
    )
    net.add_heat_input(SOLAR_WINDOW, mass, G_WINDOW)
    if mass != air:
        net.add_parameter(
            Parameter(
                G_WINDOW_AIR,
                "-",
                0.0,
                G_GLAZING_MAX,
                "part of the declared glazing's g-value heating the indoor air directly",
            )
        )
        net.add_heat_input(SOLAR_WINDOW, air, G_WINDOW_AIR)
    if T_OUT not in network.neighbours(air):
        leakage = LEAKAGE_ACH * RHO_CP_AIR * building.volume / 3600.0 / area  # [W/(m²K)]
        net.add_parameter(
            Parameter(
                "r_window",
                "m²K/W",
                1.0 / (U_GLAZING[1] + leakage),
                1.0 / U_GLAZING[0],
                f"thermal resistance of the declared glazing ({area:g} m²), films included",
            )
        )
        net.add_resistor(T_OUT, air, "r_window", factor=1.0 / area)
    return net


def sun_on_added_mass(network: RCNetwork, node: str) -> RCNetwork | None:
    """``network`` with the declared glazing's sun falling on the storage ``node`` too, None
    where the network takes no declared sun: exposed mass in a glazed room is one of the
    surfaces the transmitted sun lands on (EnergyPlus spreads the transmitted diffuse sun over
    the interior surfaces by area, ISO 52016-1 §6.5.13 likewise), so a storage added to the
    network takes its own g-value of the glazing's sun, g_window_mass_extra × solar_window."""
    if not has_glazing_g(network):
        return None
    net = network.copy(network.name)
    net.add_parameter(
        Parameter(
            G_WINDOW_ADDED_MASS,
            "-",
            0.0,
            G_GLAZING_MAX,
            "part of the declared glazing's g-value absorbed by the added storage",
        )
    )
    net.add_heat_input(SOLAR_WINDOW, node, G_WINDOW_ADDED_MASS)
    return net
