"""Column names, units and physical limits of the time-series contract (CONTRACT.md §1).

Defined once here; every reader, model and service schema refers to these names.
"""

from __future__ import annotations

from dataclasses import dataclass

TIME = "time"
T_IN = "t_in"
T_OUT = "t_out"
GHI = "ghi"
Q_HVAC = "q_hvac"
DNI = "dni"
DHI = "dhi"
Q_OCC = "q_occ"
Q_LIGHT = "q_light"
WIND_SPEED = "wind_speed"


@dataclass(frozen=True)
class Column:
    """One numeric column of the contract CSV.

    ``lower``/``upper`` are the physically possible range; values outside are rejected.
    """

    name: str
    unit: str
    required: bool
    meaning: str
    lower: float
    upper: float


# Irradiance may dip a little below zero from sensor offset at night; beyond this it is an error.
IRRADIANCE_NOISE_W_M2 = -10.0

COLUMNS: dict[str, Column] = {
    c.name: c
    for c in (
        Column(T_IN, "°C", True, "indoor air temperature", -30.0, 60.0),
        Column(T_OUT, "°C", True, "outdoor dry-bulb temperature", -60.0, 60.0),
        Column(GHI, "W/m²", True, "global horizontal irradiance", IRRADIANCE_NOISE_W_M2, 1500.0),
        Column(Q_HVAC, "W", True, "heat delivered by the HVAC system (heating +)", -1e8, 1e8),
        Column(DNI, "W/m²", False, "direct normal irradiance", IRRADIANCE_NOISE_W_M2, 1500.0),
        Column(DHI, "W/m²", False, "diffuse horizontal irradiance", IRRADIANCE_NOISE_W_M2, 1000.0),
        Column(Q_OCC, "W", False, "sensible heat from occupants", 0.0, 1e7),
        Column(Q_LIGHT, "W", False, "metered lighting and plug-load heat", 0.0, 1e8),
        Column(WIND_SPEED, "m/s", False, "wind speed at weather-station height", 0.0, 80.0),
    )
}

NUMERIC_COLUMNS: tuple[str, ...] = tuple(COLUMNS)
REQUIRED_COLUMNS: tuple[str, ...] = (
    TIME,
    *(c.name for c in COLUMNS.values() if c.required),
)
TEMPERATURE_COLUMNS: tuple[str, ...] = (T_IN, T_OUT)

# Allowed timestep of the CSV [s].
MIN_STEP_S = 60
MAX_STEP_S = 3600
