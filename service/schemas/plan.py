"""The reference MPC's heat plan: request and answer of ``POST /buildings/{id}/plan``."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rcengine.columns import COLUMNS, Q_HVAC, T_IN

from .common import with_examples
from .forecast import SET_REF_EXAMPLE, TIMES_EXAMPLE, ParameterSetRef

# The range of MPC horizons is 24–48 h; shorter ones are allowed for tests and tools.
MAX_PLAN_HORIZON_H = 48.0
MAX_MARGIN_K = 5.0

Temperature = Annotated[float, Field(ge=COLUMNS[T_IN].lower, le=COLUMNS[T_IN].upper)]
Price = Annotated[float, Field(ge=-1e6, le=1e6)]


class PlanRequest(BaseModel):
    """Comfort band, horizon, heater and price of a plan; the weather and gains over the
    horizon are the stored future rows (as for a forecast), q_hvac is what the plan decides."""

    model_config = with_examples(
        {
            "start": "2017-01-31T00:00:00+01:00",
            "hours": 24.0,
            "t_min": 21.0,
            "t_max": 24.0,
            "q_max": 63000.0,
            "price": [0.1, 0.1, 0.3, 0.3],
            "margin": 0.1,
        },
        extra="forbid",
    )

    start: str | None = Field(
        None, description="ISO 8601 with offset; default one step after the last measured t_in"
    )
    hours: float = Field(24.0, gt=0, le=MAX_PLAN_HORIZON_H, description="Horizon [h]")
    t_min: Temperature | list[Temperature | None] = Field(
        description="Lower edge of the comfort band for t_in at the end of each step: one value "
        "for the whole horizon or one per step, null for none [°C]"
    )
    t_max: Temperature | list[Temperature | None] | None = Field(
        None, description="Upper edge, as t_min; null: none [°C]"
    )
    q_max: float = Field(
        gt=0, le=COLUMNS[Q_HVAC].upper, description="Heating capacity of the HVAC system [W]"
    )
    price: Price | list[Price] | None = Field(
        None,
        description="Energy price per step, one value or one per step [price unit/kWh]; null: "
        "minimise energy",
    )
    margin: float = Field(
        0.0, ge=0, le=MAX_MARGIN_K, description="The plan aims this far inside the band [K]"
    )


class PlanRead(BaseModel):
    """The plan: heat per step and the indoor temperature it gives, times in the building's
    zone. ``feasible`` false: the band cannot be met (``message`` says why and where); the plan
    is then the one of least violation."""

    model_config = with_examples(
        {
            "times": TIMES_EXAMPLE,
            "q_hvac": [42000.0, 0.0],
            "setpoint": [20.9, 21.0],
            "t_in_pred": [19.8, 20.9],
            "t_in_end": 21.0,
            "feasible": True,
            "message": "the comfort band is met at every step",
            "violation_kh": 0.0,
            "energy_kwh": 10.5,
            "cost": 1.05,
            "solve_s": 0.004,
            "parameter_set": SET_REF_EXAMPLE,
            "step_s": 900.0,
        }
    )

    times: list[str] = Field(description="Start of each step")
    q_hvac: list[float] = Field(description="Planned heat of each step [W]")
    setpoint: list[float | None] = Field(
        description="Thermostat setpoint giving the same heat: the predicted t_in at the end of "
        "each heated step, the band's lower edge (null: none) where the plan does not heat [°C]"
    )
    t_in_pred: list[float] = Field(description="Predicted t_in at the start of each step [°C]")
    t_in_end: float = Field(description="Predicted t_in at the end of the horizon [°C]")
    feasible: bool
    message: str
    violation_kh: float = Field(description="Time-integrated distance outside the band [K·h]")
    energy_kwh: float = Field(description="Planned heat over the horizon [kWh]")
    cost: float = Field(description="Under the price; equals energy_kwh without one")
    solve_s: float = Field(description="Time the linear programme took [s]")
    parameter_set: ParameterSetRef
    step_s: float = Field(description="[s]")
