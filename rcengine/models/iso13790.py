"""The 5R1C network of ISO 13790:2008 (Annex C, simple hourly method), as a grey box.

Nodes: air θ_air and surface θ_s (both massless, as in the standard) and mass θ_m with C_m.
Conductances (standard symbols):
  H_ve     t_out — air       ventilation               estimated: R_ve = r_ve / A_f
  H_tr,w   t_out — surface   windows                   estimated: R_w = r_win / A_f
  H_tr,is  surface — air     3.45 W/(m²K) · A_t        fixed, A_t = 4.5 A_f (Eq. C.1/7.2.2.2)
  H_tr,ms  surface — mass    9.1 W/(m²K) · A_m         fixed, A_m = 2.5 A_f (medium class, Table 12)
  H_tr,em  t_out — mass      opaque elements           estimated: R_em = r_em / A_f
Heat flows (Eq. C.1–C.3): half the internal gains to the air, q_hvac to the air, the rest of the
internal gains plus solar split between mass (A_m/A_t) and surface (1 − A_m/A_t); the standard's
small window correction H_tr,w/(9.1 A_t) of the surface share is neglected.
"""

from __future__ import annotations

from collections.abc import Collection

from rcengine.building import Building
from rcengine.columns import GHI, Q_HVAC, Q_LIGHT, Q_OCC, T_OUT
from rcengine.models.common import has
from rcengine.network import Parameter, RCNetwork

H_IS_W_M2K = 3.45
H_MS_W_M2K = 9.1
AT_PER_AF = 4.5
AM_PER_AF = 2.5  # "medium" construction class
MASS_SHARE = AM_PER_AF / AT_PER_AF


def iso13790_5r1c(building: Building, inputs: Collection[str] | None = None) -> RCNetwork:
    """ISO 13790 5R1C: one mass capacity, massless air and surface nodes, five conductances."""
    af = building.floor_area
    net = RCNetwork("5r1c", description="ISO 13790:2008 Annex C 5R1C network (grey box)")
    for p in (
        Parameter("r_ve", "m²K/W", 0.1, 50.0, "ventilation/infiltration resistance × floor area"),
        Parameter("r_win", "m²K/W", 0.1, 100.0, "window transmission resistance × floor area"),
        Parameter("r_em", "m²K/W", 0.1, 50.0, "opaque envelope resistance × floor area"),
        Parameter("c_m", "J/(K·m²)", 3e4, 1e6, "internal heat capacity per floor area"),
        Parameter("alpha_sol", "m²", 0.0, 0.2 * af, "equivalent area absorbing ghi"),
    ):
        net.add_parameter(p)
    net.add_node("air")
    net.add_node("surface")
    net.add_capacitor("mass", "c_m", factor=af)
    net.add_resistor(T_OUT, "air", "r_ve", factor=1.0 / af)
    net.add_resistor(T_OUT, "surface", "r_win", factor=1.0 / af)
    net.add_resistor("surface", "air", 1.0 / (H_IS_W_M2K * AT_PER_AF * af))
    net.add_resistor("surface", "mass", 1.0 / (H_MS_W_M2K * AM_PER_AF * af))
    net.add_resistor(T_OUT, "mass", "r_em", factor=1.0 / af)
    net.add_heat_input(Q_HVAC, "air")
    for gain in (Q_OCC, Q_LIGHT):
        if has(inputs, gain):
            net.add_heat_input(gain, "air", factor=0.5)
            net.add_heat_input(gain, "mass", factor=0.5 * MASS_SHARE)
            net.add_heat_input(gain, "surface", factor=0.5 * (1.0 - MASS_SHARE))
    net.add_heat_input(GHI, "mass", "alpha_sol", factor=MASS_SHARE)
    net.add_heat_input(GHI, "surface", "alpha_sol", factor=1.0 - MASS_SHARE)
    net.set_output("air")
    return net
