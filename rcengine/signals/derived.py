"""Derived input signals: model inputs computed from the contract columns and the building.

A network's inputs are contract columns (``t_out``, ``ghi``, ``q_hvac`` …) or derived signals
named here. ``prepare`` is the one bridge from a validated frame to the dataset a network
simulates, used by the CLI, the study and the service alike.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import (
    CLOUD_COVER,
    NUMERIC_COLUMNS,
    SKY_DELTA,
    SOLAR_OPAQUE,
    T_GROUND,
    T_IN,
    T_OUT,
    UNIT,
    VENT_LOSS,
    VENT_SCHEDULE,
    WIND_LOSS,
    WIND_SPEED,
    is_orientation_signal,
    schedule_signal_name,
)
from rcengine.dataset import Dataset
from rcengine.exceptions import ModelError
from rcengine.signals.film import EXTERIOR_FILMS, film_factor
from rcengine.signals.ground import (
    GROUND_DEPTH_M,
    AnnualCycle,
    seasonal_ground_temperature,
)
from rcengine.signals.schedules import CLOCKS, Zone, clock_zone, closed_weekdays, schedule_signal
from rcengine.signals.sky import CLOUD_SOURCES, SKY_EMISSIVITY, sky_delta
from rcengine.signals.solar import (
    DECOMPOSITION_MODELS,
    IAM_MODELS,
    SKY_MODELS,
    solar_gains,
    solar_signal_names,
)
from rcengine.statespace import HOLDS

# Indoor temperature of the air-exchange losses where none was measured before (and none after):
# a heated building's usual setpoint. [°C]
T_REF_C = 20.0


def _is_real(value: object) -> bool:
    """Whether ``value`` is a real number (a bool is not)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class SignalOptions:
    """How derived signals are computed (stored with a parameter set so forecasts match fits).

    sky_model: "isotropic" (thesis Eq. 16–17), "perez" or "haydavies"; albedo: ground reflectance
    or None to neglect reflection; iam_model: glazing incidence-angle modifier; decomposition:
    ghi → dni/dhi model when those columns are absent; schedules: weekly 0/1 or level profiles
    (168 hourly values) by name; schedule_clock: "local" (civil time, daylight saving) or
    "standard" (standard time all year) for playing them back; ground_cycle: the outdoor annual
    cycle under ``t_ground`` (``AnnualCycle.to_dict``), fixed once fitted, else fitted to the
    frame at hand (``signals.ground``); input_hold: "zoh" (the contract's rows, means over their
    step) or "foh" (inputs recorded as samples, linear in between), ``Dataset.hold``;
    sky_emissivity: the clear sky's emissivity model of ``sky_delta`` (``signals.sky``:
    "clark_allen" or "swinbank", which parameter sets stored before it existed keep,
    ``from_stored``); cloud_cover: where ``sky_delta``'s cloud cover comes from, "estimated"
    (from ``ghi``) or "column" (the data's ``cloud_cover``, which a forecast's future rows then
    need too; ``for_columns`` chooses it when the fitted data have the column); ground_depth_m:
    how deep into the soil ``t_ground`` reads the annual cycle (``signals.ground``; a month's
    lag, which parameter sets stored before it existed were fitted with) [m]; exterior_film:
    the outer surface film under each orientation's opaque sun (``solar_opaque_<k>``), "fixed"
    (a sheltered facade's, which parameter sets stored before it existed were fitted with) or
    "wind" (``signals.film``: varying with the data's ``wind_speed``, which a forecast's future
    rows then need too).
    """

    sky_model: str = "isotropic"
    albedo: float | None = None
    iam_model: str = "physical"
    decomposition: str = "erbs"
    schedules: dict[str, list[float]] = field(default_factory=dict)
    schedule_clock: str = "local"
    ground_cycle: dict[str, float | str] | None = None
    input_hold: str = "zoh"
    sky_emissivity: str = "clark_allen"
    cloud_cover: str = "estimated"
    ground_depth_m: float = GROUND_DEPTH_M
    exterior_film: str = "fixed"

    def __post_init__(self) -> None:
        # A stored model file is read back through here: a setting no signal knows is refused
        # when the file is read, naming it, not when a forecast first derives the signal.
        for name, allowed in _CHOICES.items():
            value = getattr(self, name)
            if not isinstance(value, str) or value not in allowed:
                raise ValueError(f"signal setting {name!r} must be one of {allowed}, not {value!r}")
        if self.albedo is not None and not (_is_real(self.albedo) and 0.0 <= self.albedo <= 1.0):
            raise ValueError(
                f"signal setting 'albedo' must be in [0, 1] or null, not {self.albedo!r}"
            )
        depth = self.ground_depth_m
        if not (_is_real(depth) and 0.0 <= depth < 1e3):
            raise ValueError(
                f"signal setting 'ground_depth_m' must be metres in [0, 1000), not {depth!r}"
            )

    @classmethod
    def for_columns(cls, columns: Iterable[str], **options: Any) -> SignalOptions:
        """Options for data with ``columns``: the measured cloud cover where there is one."""
        cloud = "column" if CLOUD_COVER in columns else "estimated"
        return cls(**{"cloud_cover": cloud, **options})

    @classmethod
    def from_stored(cls, data: dict) -> SignalOptions:
        """The options of a stored document. One written before ``sky_emissivity`` existed was
        fitted to Swinbank's sky, and keeps it so its model forecasts as it was fitted."""
        return cls(**{"sky_emissivity": "swinbank", **data})

    def schedule_zone(self, building: Building) -> Zone:
        return clock_zone(building.location.timezone, self.schedule_clock)

    def to_dict(self) -> dict:
        return asdict(self)


# The named settings and the values each may take.
_CHOICES = {
    "sky_model": SKY_MODELS,
    "iam_model": IAM_MODELS,
    "decomposition": DECOMPOSITION_MODELS,
    "schedule_clock": CLOCKS,
    "input_hold": HOLDS,
    "sky_emissivity": SKY_EMISSIVITY,
    "cloud_cover": CLOUD_SOURCES,
    "exterior_film": EXTERIOR_FILMS,
}

Deriver = Callable[[pd.DataFrame, Building, SignalOptions, Sequence[str]], pd.DataFrame]
"""A deriver's arguments: the validated frame, the building, the options and the names asked of
it (one deriver computes a family of signals, once for all; some need a column only for some
names). It returns at least the names asked."""


def _solar(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """The solar signals (``signals.solar``), computed once for all of them. Each orientation's
    opaque sun ``solar_opaque_<k>`` [W] passes the outer film of ``options.exterior_film``: one
    that follows the wind needs the data's ``wind_speed``, and only a model taking these signals
    does (the thesis's summed ``solar_opaque`` keeps the sheltered film)."""
    out = solar_gains(
        frame,
        building,
        sky_model=options.sky_model,
        albedo=options.albedo,
        iam_model=options.iam_model,
        decomposition=options.decomposition,
    )
    opaque = [c for c in wanted if is_orientation_signal(c, SOLAR_OPAQUE)]
    if options.exterior_film == "wind" and opaque:
        film = film_factor(_require(frame, WIND_SPEED, opaque[0]))
        out[opaque] = out[opaque].mul(film, axis=0)
    return out


def _require(frame: pd.DataFrame, column: str, signal: str) -> np.ndarray:
    if column not in frame.columns or not frame[column].notna().any():
        raise ModelError(f"signal '{signal}' needs the column '{column}', absent from the data")
    return frame[column].to_numpy(dtype=float)


def indoor_operating_point(frame: pd.DataFrame) -> np.ndarray:
    """The indoor temperature an air-exchange loss n·ρc_pV/3600·(t_in − t_out) is linearised at:
    the measured ``t_in``, carried forward over gaps and past the last measurement (a forecast's
    horizon, which must hold none: ``mask_measured``), ``T_REF_C`` before the first. [°C]

    The loss is bilinear (rate × indoor temperature). A fixed reference instead of t_in
    overstates it wherever the room runs cold — a heater at its capacity, a setback — and makes
    a scheduled loss almost a constant plus a t_out term, which other physics can mimic.
    """
    if T_IN not in frame.columns:
        return np.full(len(frame), T_REF_C)
    return frame[T_IN].astype(float).ffill().fillna(T_REF_C).to_numpy()


def mask_measured(frame: pd.DataFrame, start: pd.Timestamp) -> pd.DataFrame:
    """A copy of ``frame`` without the ``t_in`` measured from ``start`` on: what a forecast from
    ``start`` may not see, even through a derived input (``indoor_operating_point``)."""
    masked = frame.copy()
    if T_IN in masked.columns:
        masked.loc[masked.index >= start, T_IN] = np.nan
    return masked


def _wind_loss(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """wind_loss = wind_speed · (t_out − t_in) (``indoor_operating_point``). [m/s·K]"""
    t_out = frame[T_OUT].to_numpy(dtype=float)
    wind = _require(frame, WIND_SPEED, WIND_LOSS)
    loss = wind * (t_out - indoor_operating_point(frame))
    return pd.DataFrame({WIND_LOSS: loss}, index=frame.index)


def _vent_loss(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """vent_loss = vent schedule · (t_out − t_in) (``indoor_operating_point``). [K]"""
    if VENT_SCHEDULE not in options.schedules:
        raise ModelError(f"signal '{VENT_LOSS}' needs a '{VENT_SCHEDULE}' schedule")
    t_out = frame[T_OUT].to_numpy(dtype=float)
    zone = options.schedule_zone(building)
    schedule = schedule_signal(
        options.schedules[VENT_SCHEDULE], frame.index, zone, closed_weekdays(frame, zone)
    )
    loss = schedule * (t_out - indoor_operating_point(frame))
    return pd.DataFrame({VENT_LOSS: loss}, index=frame.index)


def _schedules(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """sched_<name>: a stored weekly schedule played back on its clock. [-]"""
    tz = options.schedule_zone(building)
    closed = closed_weekdays(frame, tz)
    return pd.DataFrame(
        {
            schedule_signal_name(name): schedule_signal(p, frame.index, tz, closed)
            for name, p in options.schedules.items()
        },
        index=frame.index,
    )


def _ground(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """t_ground: the outdoor annual cycle damped and lagged into the soil [°C] (its mean is
    fitted on top, through a constant heat input on ``unit``)."""
    t_out = frame[T_OUT].to_numpy(dtype=float)
    latitude = building.location.latitude
    cycle = None if options.ground_cycle is None else AnnualCycle.from_dict(options.ground_cycle)
    return pd.DataFrame(
        {
            T_GROUND: seasonal_ground_temperature(
                frame.index, t_out, latitude, options.ground_depth_m, cycle
            )
        },
        index=frame.index,
    )


def _unit(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """unit = 1 [-]: the signal of a constant heat input."""
    return pd.DataFrame({UNIT: np.ones(len(frame))}, index=frame.index)


def _sky(
    frame: pd.DataFrame, building: Building, options: SignalOptions, wanted: Sequence[str]
) -> pd.DataFrame:
    """sky_delta = T_sky − t_out [K]: the long-wave driving temperature difference to the sky."""
    if options.cloud_cover == "column":
        _require(frame, CLOUD_COVER, SKY_DELTA)
    delta = sky_delta(frame, building.location, options.sky_emissivity, options.cloud_cover)
    return pd.DataFrame({SKY_DELTA: delta}, index=frame.index)


def derivers(building: Building, options: SignalOptions) -> dict[str, Deriver]:
    """Every signal derivable for ``building`` with ``options`` → the function computing it
    (one function may compute several signals: it then runs once for all of them)."""
    return {
        **dict.fromkeys(solar_signal_names(building), _solar),
        WIND_LOSS: _wind_loss,
        VENT_LOSS: _vent_loss,
        **{schedule_signal_name(name): _schedules for name in options.schedules},
        T_GROUND: _ground,
        UNIT: _unit,
        SKY_DELTA: _sky,
    }


def derive(
    frame: pd.DataFrame, building: Building, names: Iterable[str], options: SignalOptions
) -> pd.DataFrame:
    """Compute the requested derived signals (columns already in ``frame`` are left alone)."""
    wanted = [n for n in dict.fromkeys(names) if n not in frame.columns]
    by_name = derivers(building, options)
    out = pd.DataFrame(index=frame.index)
    for deriver in dict.fromkeys(by_name.values()):
        family = [n for n in wanted if by_name.get(n) is deriver]
        if family:
            out = out.join(deriver(frame, building, options, family)[family])
    unknown = [n for n in wanted if n not in out.columns]
    if unknown:
        absent = [n for n in unknown if n in NUMERIC_COLUMNS]
        why = (
            f"column(s) {absent} are absent from the data"
            if absent
            else f"signal(s) {unknown} are neither data columns nor derivable"
        )
        raise ModelError(f"the model needs inputs the data cannot give: {why}")
    return out


def prepare(
    frame: pd.DataFrame,
    building: Building,
    inputs: Iterable[str],
    options: SignalOptions | None = None,
    step_s: float | None = None,
) -> Dataset:
    """Dataset holding the contract columns plus every derived signal in ``inputs``."""
    options = options or SignalOptions()
    extra = derive(frame, building, inputs, options)
    data = Dataset.from_frame(frame, step_s, options.input_hold)
    return data.with_columns(extra) if len(extra.columns) else data
