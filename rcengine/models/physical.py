"""Plausibility readers: a fitted parameter set in the physical terms a building is checked by.

A fitted RC network is read through its steady state and its modes, whatever its topology:

- steady-state gains G_k = c·K⁻¹·F_k + d_k: the indoor temperature rise per unit of input k
  once everything has settled [K per W, or K per W/m² for an irradiance];
- heat-loss coefficient UA = 1/G_q_hvac: the heat [W] that holds the indoor air 1 K above
  outdoors; its mean U-value UA/A_facade [W/(m²K)] lumps roof, ground floor and air exchange in,
  so it is high beside a wall's own U;
- time constants τ_i = 1/λ_i of K·x = λ·C·x (the generalised symmetric eigenproblem of
  C dT/dt = −K T) [h];
- capacity per floor area ΣC_i/A_floor [kJ/(m²K)], beside ISO 13790's 80–370 classes;
- solar aperture A_k = G_k/G_q_hvac: the heat input through signal k equal in its effect on
  the indoor air to one watt of heating [m² for an irradiance, – for a signal already in W];
  for ``ghi`` divided by the glazing area it is an implied g-value referred to the horizontal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from rcengine.building import Building
from rcengine.columns import GHI, Q_HVAC, SOLAR_OPAQUE, SOLAR_WINDOW
from rcengine.exceptions import ModelError
from rcengine.models.bounds import envelope
from rcengine.network import CompiledNetwork, RCNetwork

SOLAR_SIGNALS = (GHI, SOLAR_WINDOW, SOLAR_OPAQUE)


def _compiled(network: RCNetwork | CompiledNetwork) -> CompiledNetwork:
    return network.compile() if isinstance(network, RCNetwork) else network


def steady_state_gains(
    network: RCNetwork | CompiledNetwork, params: dict[str, float]
) -> dict[str, float]:
    """Settled indoor temperature rise per unit of each input, G = c·K⁻¹·F + d. [K per unit]"""
    net = _compiled(network)
    rc = net.rc_matrices(params)
    gains = rc.c[0] @ np.linalg.solve(rc.K[0], rc.F[0]) + rc.d[0]
    return dict(zip(net.input_names, gains.tolist(), strict=True))


def steady_share(network: RCNetwork, params: dict[str, float], node: str) -> float:
    """Settled indoor temperature rise per W held at ``node`` over that per W held in the indoor
    air: the share of a heat flow at ``node`` that warms the room rather than leaving through the
    node's own paths outdoors. [-]"""
    probe = network.copy("probe")
    probe.add_heat_input("probe_node", node)
    probe.add_heat_input("probe_air", network.output)
    gains = steady_state_gains(probe, params)
    return gains["probe_node"] / gains["probe_air"]


def ua(network: RCNetwork | CompiledNetwork, params: dict[str, float]) -> float:
    """Heat-loss coefficient: heat holding the indoor air 1 K above its boundaries. [W/K]"""
    gains = steady_state_gains(network, params)
    if Q_HVAC not in gains:
        raise ModelError(f"{_compiled(network).name} has no '{Q_HVAC}' input to read its UA by")
    return 1.0 / gains[Q_HVAC]


def time_constants_h(network: RCNetwork | CompiledNetwork, params: dict[str, float]) -> list[float]:
    """Time constants of the network's modes, slowest first. [h]"""
    rc = _compiled(network).rc_matrices(params)
    rates = scipy.linalg.eigh(rc.K[0], np.diag(rc.capacity[0]), eigvals_only=True)
    return sorted((1.0 / rates / 3600.0).tolist(), reverse=True)


def capacity_per_floor_area(
    network: RCNetwork | CompiledNetwork, params: dict[str, float], building: Building
) -> float:
    """Total heat capacity of the network's nodes per floor area. [kJ/(m²K)]"""
    capacity = _compiled(network).rc_matrices(params).capacity[0]
    return float(capacity.sum()) / building.floor_area / 1e3


def solar_apertures(
    network: RCNetwork | CompiledNetwork, params: dict[str, float]
) -> dict[str, float]:
    """Effective aperture of each solar input, G_k/G_q_hvac. [m² for ghi, – for W signals]"""
    gains = steady_state_gains(network, params)
    heating = gains[Q_HVAC]
    return {k: g / heating for k, g in gains.items() if k.startswith(SOLAR_SIGNALS)}


@dataclass(frozen=True)
class Reading:
    """A fitted model in physical terms (see the module docstring for each quantity)."""

    ua: float  # [W/K]
    mean_u: float  # UA over the gross facade [W/(m²K)]
    time_constants_h: list[float]  # [h], slowest first
    capacity_per_floor_area: float  # [kJ/(m²K)]
    solar_apertures: dict[str, float]  # [m² for ghi, – for W signals]
    implied_g: float | None  # [-]: window aperture over glazing area; None without glazing


def read(
    network: RCNetwork | CompiledNetwork, params: dict[str, float], building: Building
) -> Reading:
    """Every plausibility reading of ``params`` for ``network`` of ``building``."""
    net = _compiled(network)
    env = envelope(building)
    apertures = solar_apertures(net, params)
    loss = ua(net, params)
    return Reading(
        ua=loss,
        mean_u=loss / env.facade,
        time_constants_h=time_constants_h(net, params),
        capacity_per_floor_area=capacity_per_floor_area(net, params, building),
        solar_apertures=apertures,
        implied_g=_implied_g(apertures, building),
    )


def _implied_g(apertures: dict[str, float], building: Building) -> float | None:
    """The window aperture as a g-value: solar_window's is one already; ghi's (which also carries
    any opaque share) is divided by the glazing area."""
    if SOLAR_WINDOW in apertures:
        return apertures[SOLAR_WINDOW]
    glazing = sum(s.area for s in building.windows)
    if GHI in apertures and glazing > 0:
        return apertures[GHI] / glazing
    return None
