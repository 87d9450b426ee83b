"""The envelope's outside surface film under the wind (ISO 6946:2017 Annex C).

Sun absorbed on an opaque facade splits between the outer film, back to the outdoor air, and the
construction behind it: the sol-air excess over the air temperature is α·I·R_se, R_se = 1/h_se
the film's resistance, and U·R_se of the absorbed flux reaches the room in the steady state (ISO
13790 Eq. 44). The film's coefficient is h_se = h_ce + h_re, with h_ce = 4 + 4·v the convection
at wind speed v and h_re = ε·h_r0 the radiation (Annex C, Eq. C.2 and C.4): a calm day's film
has twice a windy one's resistance, so the wind sets how much of a dark, weakly insulated
facade's sun reaches the room. Read through a fixed film, the difference is what a wind-driven
air leak would make on sunny days.

The wind in the data (``wind_speed``) is a weather station's, at 10 m in open country; the
facade's own is less, by its height and the terrain around it. It is carried there by the power
law of ASHRAE Fundamentals (2017, ch. 24, Eq. 4 and Table 1): V = V_met·(δ_met/H_met)^a_met ·
(H/δ)^a, from the station (a 0.14, δ 270 m) to a suburban site (a 0.22, δ 370 m) at 5 m, a low
building's facade: 0.62 of the station's wind. R_se at 1 m/s, a sheltered facade's
(``models.bounds.R_SE_SHELTERED``, at which a fitted share is read), stays the reference.

The sky's long-wave pull on a roof is left at the fixed film: on the clear, calm nights it is
strongest, a surface colder than the air above it loses little by convection whatever the
formula's 4 W/(m²K) says, and on the test bed's light Chicago roof the sky read through this
film lost what the fixed one found.
"""

from __future__ import annotations

import numpy as np

# The outer film taken as fixed at R_SE_SHELTERED, or varying with the data's wind.
EXTERIOR_FILMS = ("fixed", "wind")
STEFAN_BOLTZMANN = 5.670e-8  # [W/(m²K⁴)]


def radiative_coefficient(emissivity: float, t_k: float) -> float:
    """ε·h_r, h_r = 4σT³: a surface's linearised long-wave exchange at ``t_k`` [K]. [W/(m²K)]"""
    return emissivity * 4 * STEFAN_BOLTZMANN * t_k**3


# ε·h_r0 of a painted, brick or roofing surface (ε = 0.9) at 0 °C. [W/(m²K)]
H_RE = radiative_coefficient(0.9, 273.15)
# Convection h_ce = H_CE_CALM + H_CE_PER_WIND·v (ISO 6946 Eq. C.4). [W/(m²K)], [W/(m²K) per m/s]
H_CE_CALM, H_CE_PER_WIND = 4.0, 4.0
# The wind of the sheltered film the fixed readings use (``R_SE_SHELTERED``). [m/s]
REFERENCE_WIND_M_S = 1.0
# ASHRAE's wind profile: exponent and boundary-layer depth [m] of the weather station's open
# country and of a suburban site, the station's height and a low facade's [m].
STATION_PROFILE, SITE_PROFILE = (0.14, 270.0), (0.22, 370.0)
STATION_HEIGHT_M, FACADE_HEIGHT_M = 10.0, 5.0


def facade_wind(station_wind_m_s: np.ndarray | float) -> np.ndarray:
    """The wind at a low suburban facade for the weather station's ``station_wind_m_s``, by
    ASHRAE's power law (module docstring). [m/s]"""
    (a_met, depth_met), (a, depth) = STATION_PROFILE, SITE_PROFILE
    ratio = (depth_met / STATION_HEIGHT_M) ** a_met * (FACADE_HEIGHT_M / depth) ** a
    return ratio * np.asarray(station_wind_m_s, dtype=float)


def film_resistance(wind_m_s: np.ndarray | float) -> np.ndarray:
    """R_se = 1/(h_ce + h_re) at wind speed ``wind_m_s`` [m/s]. [m²K/W]"""
    wind = np.maximum(np.asarray(wind_m_s, dtype=float), 0.0)
    return 1.0 / (H_CE_CALM + H_CE_PER_WIND * wind + H_RE)


def film_factor(station_wind_m_s: np.ndarray | float) -> np.ndarray:
    """R_se at the facade's wind (``facade_wind``) over R_se at REFERENCE_WIND_M_S: the share of
    an outer surface's absorbed flux the film passes on, relative to a sheltered facade's. [-]"""
    return film_resistance(facade_wind(station_wind_m_s)) / film_resistance(REFERENCE_WIND_M_S)
