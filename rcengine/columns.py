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
CLOUD_COVER = "cloud_cover"


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
        Column(CLOUD_COVER, "%", False, "share of the sky covered by cloud", 0.0, 100.0),
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

# --- derived signals --------------------------------------------------------------------------
# Model inputs computed from the columns above and the building (rcengine.signals.derived).
SOLAR_WINDOW = "solar_window"  # Σ window area × irradiance reaching the glazing [W]
SOLAR_OPAQUE = "solar_opaque"  # Σ opaque area × plane-of-array irradiance [W]
WIND_LOSS = "wind_loss"  # wind_speed · (t_out − T_REF) [m/s·K]
VENT_LOSS = "vent_loss"  # ventilation schedule · (t_out − T_REF) [K]
T_GROUND = "t_ground"  # ground temperature under the floor [°C]
UNIT = "unit"  # 1 at every row: the signal of a constant heat input [-]
SKY_DELTA = "sky_delta"  # T_sky − t_out [K]
# Weekly schedules stored in the signal options, by name; each plays back as sched_<name> [-].
VENT_SCHEDULE = "vent"
GAINS_SCHEDULE = "gains"
# The contract columns each derived signal above is computed from: what a forecast's future rows
# must hold for a model's inputs (the solar signals need GHI; a schedule, the clock alone).
DERIVED_FROM: dict[str, tuple[str, ...]] = {
    WIND_LOSS: (T_OUT, WIND_SPEED),
    VENT_LOSS: (T_OUT,),
    T_GROUND: (T_OUT,),
    UNIT: (),
    SKY_DELTA: (T_OUT, GHI),
}


def schedule_signal_name(schedule: str) -> str:
    """The signal playing back the stored weekly schedule ``schedule``, e.g. ``sched_gains``."""
    return f"sched_{schedule}"


SCHED_GAINS = schedule_signal_name(GAINS_SCHEDULE)


def orientation_key(azimuth: float, tilt: float) -> str:
    """Suffix naming a surface orientation in signal columns, e.g. ``90_90`` (east, vertical).

    Parameters
    ----------
    azimuth : clockwise from north. [°]
    tilt : from horizontal. [°]
    """
    return f"{azimuth:g}_{tilt:g}"


def solar_orientation_signal(total: str, orientation: str) -> str:
    """The share of ``total`` (``SOLAR_WINDOW`` or ``SOLAR_OPAQUE``) falling on the surfaces of
    one orientation (``orientation_key``), e.g. ``solar_window_180_90``. [W]"""
    return f"{total}_{orientation}"


def is_orientation_signal(name: str, total: str) -> bool:
    """Whether ``name`` is one orientation's share of ``total`` (``solar_orientation_signal``)."""
    return name.startswith(f"{total}_")
