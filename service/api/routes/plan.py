"""The reference MPC on the served model: a heat plan that keeps a comfort band."""

from __future__ import annotations

import numpy as np
from fastapi import APIRouter

from rcengine.columns import Q_HVAC
from rcengine.control.mpc import BAND_TOLERANCE_K
from rcengine.control.mpc import plan as mpc_plan
from rcengine.exceptions import DataValidationError, Problem
from rcengine.io.instants import parse_instant
from rcengine.io.timeseries import format_times

from ...schemas.common import error_responses, in_zone
from ...schemas.forecast import ParameterSetRef
from ...schemas.plan import PlanRead, PlanRequest
from ..deps import BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["forecast"])


@router.post(
    "/{building_id}/plan",
    summary="Heat plan of least energy (or cost) that keeps t_in in a comfort band",
    description=(
        "A linear MPC (HiGHS) over the current parameter set's discrete model, from the Kalman "
        "state at `start` (as for `/model`), with the stored future rows of the weather and "
        "gains as their forecast; q_hvac need not be stored, it is what the plan decides. The "
        "band is soft: when the heater cannot keep it, the answer is the plan of least "
        "violation with `feasible` false and a message saying where and by how much. "
        "Per-step lists must have one value per step of the horizon. Missing future inputs: "
        "422 naming the columns and times. No current parameter set: 409."
    ),
    responses=error_responses(401, 404, 409, 422),
)
def plan(building_id: BuildingDep, body: PlanRequest, ctx: ContextDep) -> PlanRead:
    start = None if body.start is None else parse_instant(body.start, "start")
    state = ctx.forecaster.model_state(building_id, start, body.hours)
    steps = round(body.hours * 3600.0 / state.model.dt)
    if steps < 1:
        raise _bad("hours", f"hours {body.hours:g} is shorter than one step of the model")
    times, u = state.inputs_from_state(steps, Q_HVAC)
    result = mpc_plan(
        state.model,
        state.state,
        u,
        _per_step("t_min", body.t_min, steps),
        _per_step("t_max", body.t_max, steps),
        body.q_max,
        None if body.price is None else _per_step("price", body.price, steps),
        body.margin,
    )
    local = format_times(times, state.timezone)
    message = result.message()
    if not result.feasible:
        missed = np.flatnonzero(np.maximum(result.below, result.above) > BAND_TOLERANCE_K)[0]
        message += f" (first missed at the end of the step starting {local[missed]})"
    return PlanRead(
        times=local,
        q_hvac=result.q_hvac.tolist(),
        setpoint=[None if np.isnan(v) else v for v in result.setpoint.tolist()],
        t_in_pred=result.t_in[:-1].tolist(),
        t_in_end=float(result.t_in[-1]),
        feasible=result.feasible,
        message=message,
        violation_kh=result.violation_kh,
        energy_kwh=result.energy_kwh,
        cost=result.cost,
        solve_s=result.solve_s,
        parameter_set=ParameterSetRef.model_validate(
            state.parameter_set, context=in_zone(state.timezone)
        ),
        step_s=state.model.dt,
    )


def _per_step(name: str, value: float | list | None, steps: int) -> np.ndarray:
    """One value per step (NaN for none); 422 naming the field if a list has another length."""
    if value is None or not isinstance(value, list):
        return np.full(steps, np.nan if value is None else float(value))
    if len(value) != steps:
        raise _bad(name, f"{name} has {len(value)} values; the horizon has {steps} steps")
    return np.array([np.nan if v is None else v for v in value], dtype=float)


def _bad(column: str, message: str) -> DataValidationError:
    return DataValidationError([Problem(None, column, message)])
