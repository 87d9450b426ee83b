"""The interior surfaces: where radiant heat lands before the mass stores it.

The thesis's models put the radiant gains — the sun through the glazing, the lights' heat, the
``ghi`` aperture of the internal mass — on the interior mass node itself, as if the surfaces that
absorb them were at the mass's mean temperature (thesis Fig. 2.9). They are not: an absorbing
surface warms within minutes, gives part of the heat back to the room air by convection and
conducts the rest into the slab or partition behind it, which stores it for hours. ISO 13790's
hourly model (§C.2, the 5R1C network) has a massless surface node for that reason, between the
air (H_tr,is = 3.45 W/(m²K) over every interior surface) and the mass (H_tr,ms = 9.1 W/(m²K) over
the effective mass area), with the solar and radiant internal gains entering the surface and the
mass nodes. A model without it releases radiant heat to the air only at the mass's pace: the
occupied and sunny hours get too little heat in the air, and every candidate that puts heat back
on them is credited with it. On the test bed's open-plan Chicago and Golden nulls the lights'
convective share (``metered``) pressed its upper end and was not taken, while a surface node cut
the base model's training error by 24 % and 22 % and its test error by 8 % and 21 %.

``with_surface_node`` inserts it: the air–mass resistance r_int becomes the film between the air
and the surfaces (its meaning and bounds unchanged: inside films and coverings), a new r_mass_surf
conducts from the surfaces into the mass, and the gains that entered the mass enter the surfaces.
Of the radiant heat, the share r_mass_surf / (r_int + r_mass_surf) reaches the air without the
mass's delay. r_mass_surf → 0 is the thesis's routing; the base model takes the node
(``selection._surfaces_placed``) only where the fit settles inside its range.
"""

from __future__ import annotations

from rcengine.network import HeatInput, Parameter, RCNetwork, Resistor

SURFACE_NODE = "surface"
R_MASS_SURF = "r_mass_surf"
R_INT = "r_int"
# How far below r_int's least value r_mass_surf may go: the surfaces at the mass's temperature to
# within a hundredth of the films' resistance, the thesis's routing as a limit. [-]
NESTED_SHARE = 0.01


def mass_coupling(network: RCNetwork) -> tuple[str, Resistor] | None:
    """The interior mass node that takes radiant gains and the one resistor r_int joining it to
    the air (the thesis 3R3C's ``int``), where the network has exactly that; else None (no such
    node, or a surface node already)."""
    if SURFACE_NODE in network.nodes or R_INT not in network.parameters:
        return None
    air = network.output
    joins = [r for r in network.resistors if r.resistance == R_INT and air in (r.a, r.b)]
    if len(joins) != 1:
        return None
    (resistor,) = joins
    mass = resistor.b if resistor.a == air else resistor.a
    if mass not in network.nodes or not any(h.node == mass for h in network.heat_inputs):
        return None
    return mass, resistor


def with_surface_node(network: RCNetwork) -> RCNetwork | None:
    """A copy of ``network`` with the interior surfaces between its air and its mass (module
    docstring): r_int [m²K/W per m² of floor] from the air to the surfaces, r_mass_surf (same
    units, same factor) from the surfaces to the mass, and every heat input of the mass moved to
    the surfaces. None where ``mass_coupling`` finds no mass to put them in front of."""
    found = mass_coupling(network)
    if found is None:
        return None
    mass, resistor = found
    film = network.parameters[R_INT]
    net = network.copy(network.name)
    net.add_parameter(
        Parameter(
            R_MASS_SURF,
            film.unit,
            film.lower * NESTED_SHARE,
            film.upper,
            "resistance from the interior surfaces into the internal mass, per floor area",
        )
    )
    net.add_node(SURFACE_NODE)
    net.resistors = [
        Resistor(net.output, SURFACE_NODE, r.resistance, r.factor) if r == resistor else r
        for r in net.resistors
    ]
    net.add_resistor(SURFACE_NODE, mass, R_MASS_SURF, factor=resistor.factor)
    net.heat_inputs = [
        HeatInput(h.signal, SURFACE_NODE, h.gain, h.factor) if h.node == mass else h
        for h in net.heat_inputs
    ]
    return net


def released_share(params: dict[str, float]) -> float:
    """The share of the radiant heat on the surfaces that reaches the air without the mass's
    delay, r_mass_surf / (r_int + r_mass_surf) (steady state, mass held). [-]"""
    return params[R_MASS_SURF] / (params[R_INT] + params[R_MASS_SURF])
