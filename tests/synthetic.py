"""Synthetic measurements from an independently written reference: the thesis 3R3C equations typed
out by hand and integrated with scipy's solve_ivp (not the engine's network or discretisation)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from rcengine.building import Building
from rcengine.diagnose.candidates import CANDIDATES, Context, Extension
from rcengine.diagnose.fitting import fit_model, split_data
from rcengine.diagnose.settings import DiagnoseSettings, split_time
from rcengine.models import get_model
from rcengine.signals import SignalOptions

STEP_S = 900.0


def office(**changes: object) -> Building:
    """The synthetic office in Turin (the thesis's sizes), with ``changes`` to its description."""
    description = {
        "name": "synthetic-office",
        "location": {"latitude": 45.07, "longitude": 7.69, "timezone": "Europe/Rome"},
        "floor_area": 1050.0,
        "volume": 3150.0,
        "wall_area": 455.0,
        "internal_mass_area": 560.0,
    }
    return Building.from_dict({**description, **changes})


BUILDING = office()

TRUTH_BASIC = {
    "r_wall_ext": 1.2,
    "r_wall_int": 0.4,
    "r_int": 0.15,
    "c_wall": 2.0e5,
    "c_air": 5.0e6,
    "c_int": 1.2e5,
    "alpha_wall": 20.0,
    "alpha_int": 12.0,
}


def weather_and_gains(days: int, seed: int = 3, start: str = "2017-01-09") -> pd.DataFrame:
    """Winter-like inputs at 15 min from ``start`` (UTC): daily outdoor cycle, clear-sky-shaped
    irradiance with random cloudiness, office gains on weekdays and a pseudo-random heating
    sequence (rich excitation)."""
    rng = np.random.default_rng(seed)
    times = pd.date_range(start, periods=days * 96, freq="15min", tz="UTC")
    hours = np.asarray(times.hour + times.minute / 60.0)
    day = np.arange(len(times)) // 96
    t_out = 4.0 + 4.0 * np.sin((hours - 9.0) / 24.0 * 2 * np.pi) + rng.normal(0, 1.5, days)[day]
    sun_up = np.clip(np.sin((hours - 7.5) / 9.0 * np.pi), 0.0, None) * (
        (hours > 7.5) & (hours < 16.5)
    )
    ghi = 450.0 * sun_up * rng.uniform(0.2, 1.0, days)[day]
    weekday = np.asarray(times.day_of_week < 5)
    occupied = weekday & (hours >= 8) & (hours < 18)
    blocks = np.repeat(rng.integers(0, 2, len(times) // 8 + 1), 8)[: len(times)]
    q_hvac = 40_000.0 * blocks * ((hours >= 5) & (hours < 20))
    return pd.DataFrame(
        {
            "t_out": t_out,
            "ghi": ghi,
            "q_hvac": q_hvac,
            "q_occ": 4000.0 * occupied,
            "q_light": 3000.0 * occupied,
        },
        index=times,
    )


def basic_reference(
    frame: pd.DataFrame,
    p: dict,
    x0: tuple[float, float, float],
    solar: tuple[str, str] = ("ghi", "ghi"),
) -> np.ndarray:
    """Indoor temperature at each row start from the hand-written 3R3C ODEs (thesis Fig. 2.9).

    ``solar`` names the columns heating the wall and the internal mass (ghi for Basic; the solar
    module's opaque and window signals for Sun). Inputs are held over each step (zero-order hold).
    With ``r_mass_surf`` in ``p``, the radiant gains land on massless interior surfaces between
    the air (through r_int) and the mass (through r_mass_surf), ISO 13790's surface node.
    """
    a_wall, a_floor, a_mass = 455.0, 1050.0, 560.0
    r_we, r_wi, r_i = p["r_wall_ext"] / a_wall, p["r_wall_int"] / a_wall, p["r_int"] / a_floor
    r_ms = p.get("r_mass_surf", 0.0) / a_floor
    c_w, c_a, c_i = p["c_wall"] * a_wall, p["c_air"], p["c_int"] * a_mass
    cols = frame[["t_out", solar[0], solar[1], "q_hvac", "q_occ", "q_light"]].to_numpy()

    def rhs(_t: float, x: np.ndarray, row: np.ndarray) -> list[float]:
        t_w, t_a, t_i = x
        t_out, sol_w, sol_i, q_hvac, q_occ, q_light = row
        radiant = p["alpha_int"] * sol_i + q_light
        # The surfaces' balance: (t_a − t_s)/r_i + (t_i − t_s)/r_ms + radiant = 0.
        t_s = (t_a / r_i + t_i / r_ms + radiant) / (1 / r_i + 1 / r_ms) if r_ms else t_i
        into_mass = (t_s - t_i) / r_ms if r_ms else (t_a - t_i) / r_i + radiant
        d_w = ((t_out - t_w) / r_we + (t_a - t_w) / r_wi + p["alpha_wall"] * sol_w) / c_w
        d_a = ((t_w - t_a) / r_wi + (t_s - t_a) / r_i + q_hvac + q_occ) / c_a
        return [d_w, d_a, into_mass / c_i]

    x = np.array(x0, dtype=float)
    out = np.empty(len(frame))
    for k, row in enumerate(cols):
        out[k] = x[1]
        sol = solve_ivp(rhs, (0.0, STEP_S), x, args=(row,), rtol=1e-10, atol=1e-10)
        x = sol.y[:, -1]
    return out


def lit_office(days: int) -> pd.DataFrame:
    """``weather_and_gains`` with 2 kW of occupants and 10 kW of lights over the lit hours: the
    lights dominate the metered gains, so where their heat goes shows."""
    inputs = weather_and_gains(days)
    occupied = inputs["q_light"] > 0
    return inputs.assign(q_occ=2_000.0 * occupied, q_light=10_000.0 * occupied)


# One round judging the unmetered gain alone on a single 60/40 split, from one base-model search:
# what the base-model steps' tests ask of a short synthetic record.
UNMETERED_GAIN_ONLY = DiagnoseSettings(
    train_fraction=0.6, evidence="split", baseline_starts=1, max_rounds=1,
    effects=("unmetered_gains",),
)  # fmt: skip


def heat_per_watt(network, params: dict[str, float], signal: str) -> dict[str, float]:
    """The heat [W] one watt of ``signal`` puts on each state of ``network`` at ``params`` (its
    massless nodes solved)."""
    compiled = network.compile()
    rc = compiled.rc_matrices(compiled.as_theta(params)[:1])
    column = rc.F[0, :, compiled.input_names.index(signal)]
    return dict(zip(compiled.state_names, column, strict=True))


# --- Sun model: real weather, geometric solar inputs ---------------------------------------------

TRUTH_SUN = {**TRUTH_BASIC, "alpha_wall": 0.12, "alpha_int": 0.55}
WEATHER_COLUMNS = ("t_out", "ghi", "dni", "dhi")


def with_recorded_weather(frame: pd.DataFrame, csv_path: str | Path) -> pd.DataFrame:
    """``frame`` with t_out, ghi, dni, dhi taken from a contract CSV at the same UTC times.

    Read with pandas, not the engine's reader, so the reference stays independent of it.
    """
    recorded = pd.read_csv(csv_path, usecols=["time", *WEATHER_COLUMNS])
    recorded.index = pd.to_datetime(recorded.pop("time"), utc=True)
    weather = recorded.reindex(frame.index)
    if weather.isna().any().any():
        raise ValueError(f"{csv_path} does not cover {frame.index[0]} … {frame.index[-1]}")
    return frame.assign(**{c: weather[c].to_numpy() for c in WEATHER_COLUMNS})


def fitted_context(frame: pd.DataFrame, model: str, fraction: float) -> Context:
    """What a candidate sees after a baseline fit of ``model`` (BUILDING, "default" preset) on
    the first ``fraction`` of ``frame``: the training data, parameters and residual."""
    network = get_model(model, BUILDING, frame.columns)
    boundary = split_time(frame, fraction, BUILDING.location.timezone)
    split = split_data(frame, BUILDING, network, SignalOptions(), boundary)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_model(network, SignalOptions(), split, "default", 0)
    return Context(
        network, BUILDING, fit.split.train, SignalOptions(), fit.params, fit.residual_train
    )


def ground_version(ctx: Context, layer: bool) -> Extension:
    """The ground candidate's version read at a month's lag, with or without its layer of soil."""
    ground = CANDIDATES["ground_coupling"](ctx)
    (version,) = [
        v
        for v in (ground, *ground.alternatives)
        if v.detail["soil_layer"] == layer and np.isclose(v.detail["ground_lag_months"], 1.0)
    ]
    return version
