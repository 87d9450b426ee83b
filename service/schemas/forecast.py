"""Forecasts, candidate trajectories and the state-space model for an MPC."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from .common import LocalTime, with_examples

MAX_HORIZON_H = 7 * 24.0
MAX_CANDIDATES = 1000

SET_REF_EXAMPLE = {
    "id": 4,
    "model": "basic",
    "created_at": "2017-01-31T02:00:03+01:00",
    "train_start": "2017-01-23T00:00:00+01:00",
    "train_end": "2017-01-30T00:00:00+01:00",
    "rmse_train": 0.37,
    "rmse_holdout": 0.41,
    "engine_version": "0.1.0",
}
TIMES_EXAMPLE = ["2017-01-31T00:00:00+01:00", "2017-01-31T00:15:00+01:00"]


class ParameterSetRef(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    model: str
    created_at: LocalTime
    train_start: LocalTime
    train_end: LocalTime
    rmse_train: float | None = Field(description="[K]")
    rmse_holdout: float | None = Field(description="[K]")
    engine_version: str


class ForecastRead(BaseModel):
    """Indoor temperature at each row start; times in the building's time zone."""

    model_config = with_examples(
        {
            "times": TIMES_EXAMPLE,
            "t_in_pred": [20.61, 20.55],
            "t_in_std": [0.12, 0.15],
            "parameter_set": SET_REF_EXAMPLE,
            "step_s": 900.0,
            "unit": "°C",
        }
    )

    times: list[str]
    t_in_pred: list[float] = Field(description="[°C]")
    t_in_std: list[float] = Field(
        description="Standard deviation of the measured t_in about t_in_pred, per row [K]: the "
        "set's fitted noise model when it has one (likelihood criterion), else the Kalman "
        "filter's fixed defaults (nominal only); parameter uncertainty not included"
    )
    parameter_set: ParameterSetRef
    step_s: float = Field(description="[s]")
    unit: str = "°C"


class SimulateRequest(BaseModel):
    """Candidate HVAC heat trajectories from ``start``; the other inputs (weather, gains) are
    the stored future rows. One candidate (a list) or many (a list of lists), each H steps."""

    model_config = with_examples(
        {
            "start": "2017-01-31T00:00:00+01:00",
            "q_hvac": [[0.0, 0.0, 30000.0, 30000.0], [20000.0, 20000.0, 20000.0, 0.0]],
        },
        extra="forbid",
    )

    start: str | None = Field(
        None, description="ISO 8601 with offset; default one step after the last measured t_in"
    )
    q_hvac: list[list[float]] | list[float] = Field(
        description="[W], heating +; N candidates × H steps"
    )


class SimulateRead(BaseModel):
    model_config = with_examples(
        {
            "times": TIMES_EXAMPLE,
            "t_in": [[20.61, 20.55], [20.72, 20.80]],
            "parameter_set": SET_REF_EXAMPLE,
            "step_s": 900.0,
            "unit": "°C",
        }
    )

    times: list[str]
    t_in: list[list[float]] = Field(description="One trajectory per candidate [°C]")
    parameter_set: ParameterSetRef
    step_s: float
    unit: str = "°C"


class StateEstimate(BaseModel):
    time: LocalTime = Field(description="The state is at the start of this step")
    x: list[float] = Field(description="Node temperatures, in state_names order [°C]")
    std: list[float] = Field(description="Their standard deviation from the Kalman filter [K]")
    t_in: float = Field(description="C·x: the indoor temperature the state implies [°C]")


class ModelRead(BaseModel):
    """x[k+1] = A x[k] + B u[k],  t_in[k] = C x[k] + D u[k]  (zero-order hold, step dt)."""

    model_config = with_examples(
        {
            "A": [[0.98, 0.01, 0.0], [0.02, 0.95, 0.03], [0.0, 0.04, 0.96]],
            "B": [
                [0.01, 1e-5, 0.0, 0.0, 0.0],
                [0.0, 0.0, 1.7e-4, 1.7e-4, 0.0],
                [0.0, 1e-5, 0.0, 0.0, 2e-6],
            ],
            "C": [0.0, 1.0, 0.0],
            "D": [0.0, 0.0, 0.0, 0.0, 0.0],
            "dt": 900.0,
            "state_names": ["wall", "air", "int"],
            "input_names": ["t_out", "ghi", "q_hvac", "q_occ", "q_light"],
            "input_units": ["°C", "W/m²", "W", "W", "W"],
            "output": "t_in",
            "state": {
                "time": "2017-01-31T00:00:00+01:00",
                "x": [12.1, 20.6, 20.1],
                "std": [0.4, 0.09, 0.3],
                "t_in": 20.6,
            },
            "parameter_set": SET_REF_EXAMPLE,
        }
    )

    A: list[list[float]]
    B: list[list[float]]
    C: list[float]
    D: list[float]
    dt: float = Field(description="[s]")
    state_names: list[str]
    input_names: list[str] = Field(description="Column order of B and D")
    input_units: list[str | None] = Field(description="None for derived signals")
    output: str = "t_in"
    state: StateEstimate
    parameter_set: ParameterSetRef
