"""For an MPC: forecasts, candidate trajectories in one call, the state-space model."""

from __future__ import annotations

from functools import lru_cache
from typing import Annotated, TypeVar

import numpy as np
from fastapi import APIRouter, Query
from fastapi.concurrency import run_in_threadpool

from rcengine.columns import COLUMNS, Q_HVAC
from rcengine.exceptions import DataValidationError, Problem
from rcengine.io.instants import parse_instant

from ...forecasting import Prediction, SetInfo
from ...schemas.common import error_responses, in_zone
from ...schemas.forecast import (
    MAX_CANDIDATES,
    MAX_HORIZON_H,
    ForecastRead,
    ModelRead,
    ParameterSetRef,
    SimulateRead,
    SimulateRequest,
)
from ..deps import BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["forecast"])
Trajectories = TypeVar("Trajectories", ForecastRead, SimulateRead)

StartQuery = Annotated[
    str | None,
    Query(
        description="ISO 8601 with UTC offset ('+' as %2B in a URL); default one step after "
        "the last measured t_in",
        examples=["2017-01-31T00:00:00+01:00"],
    ),
]


@router.get(
    "/{building_id}/forecast",
    summary="Indoor temperature forecast with the current parameter set",
    description=(
        "The unmeasured states at `start` come from a Kalman filter over the measurements "
        "before it; the inputs over the horizon are the rows already uploaded for it (weather "
        "forecast, planned q_hvac). `t_in_std`: the standard deviation of the measured t_in "
        "about `t_in_pred` [K], from the set's fitted noise model (likelihood criterion), else "
        "the filter's fixed defaults (then only nominal); parameter uncertainty is not included. "
        "Missing future inputs: 422 naming the columns and times. "
        "No current parameter set: 409."
    ),
    responses=error_responses(401, 404, 409, 422),
)
async def forecast(
    building_id: BuildingDep,
    ctx: ContextDep,
    start: StartQuery = None,
    hours: Annotated[
        float, Query(gt=0, le=MAX_HORIZON_H, description="Horizon [h]", examples=[24.0])
    ] = 24.0,
) -> ForecastRead:
    first = None if start is None else parse_instant(start, "start")
    # A cached forecast is served on the event loop; computing one goes to a worker thread.
    prediction = ctx.forecaster.cached(building_id, first, hours)
    if prediction is None:
        prediction = await run_in_threadpool(ctx.forecaster.forecast, building_id, first, hours)
    return _trajectories(
        ForecastRead,
        prediction,
        t_in_pred=prediction.t_in_pred.tolist(),
        t_in_std=prediction.t_in_std.tolist(),
    )


@router.post(
    "/{building_id}/simulate",
    summary="Indoor temperature for many candidate q_hvac trajectories in one call",
    description=(
        "For an MPC optimiser: the start state as for a forecast, the stored future rows for "
        "every other input, and each candidate HVAC heat trajectory (one value per step) "
        "in place of the planned q_hvac. Computed by linearity in one matrix product."
    ),
    responses=error_responses(401, 404, 409, 422),
)
def simulate(building_id: BuildingDep, body: SimulateRequest, ctx: ContextDep) -> SimulateRead:
    candidates = _candidates(body.q_hvac)
    first = None if body.start is None else parse_instant(body.start, "start")
    prediction, outputs = ctx.forecaster.simulate(building_id, first, candidates)
    return _trajectories(SimulateRead, prediction, t_in=outputs.tolist())


@router.get(
    "/{building_id}/model",
    summary="Discrete state-space matrices of the current set and the current state estimate",
    description=(
        "x[k+1] = A x[k] + B u[k], t_in[k] = C x[k] + D u[k], exact zero-order hold at step "
        "dt, inputs in `input_names` order; the state is the Kalman estimate at `at` from the "
        "measurements before it, ready for an MPC to embed."
    ),
    responses=error_responses(401, 404, 409, 422),
)
def model(
    building_id: BuildingDep,
    ctx: ContextDep,
    at: Annotated[
        str | None,
        Query(
            description="State time, ISO 8601 with offset; default one step after the last "
            "measured t_in",
            examples=["2017-01-31T00:00:00+01:00"],
        ),
    ] = None,
) -> ModelRead:
    when = None if at is None else parse_instant(at, "at")
    result = ctx.forecaster.model_state(building_id, when)
    m = result.model
    return ModelRead.model_validate(
        {
            "A": m.A.tolist(),
            "B": m.B.tolist(),
            "C": m.C.tolist(),
            "D": m.D.tolist(),
            "dt": m.dt,
            "state_names": list(m.state_names),
            "input_names": list(m.input_names),
            "input_units": [COLUMNS[n].unit if n in COLUMNS else None for n in m.input_names],
            "state": {
                "time": result.at,
                "x": result.state.tolist(),
                "std": np.sqrt(np.clip(np.diag(result.covariance), 0.0, None)).tolist(),
                "t_in": float(m.C @ result.state),
            },
            "parameter_set": result.parameter_set,
        },
        context=in_zone(result.timezone),
    )


def _candidates(q_hvac: list[list[float]] | list[float]) -> np.ndarray:
    """The candidates as an N × H array; 422 naming q_hvac unless 1 … MAX_CANDIDATES
    trajectories of one non-zero length with every value within the contract's range of q_hvac.
    """
    rows = [q_hvac] if not q_hvac or not isinstance(q_hvac[0], list) else q_hvac
    lengths = {len(row) for row in rows}
    if not 1 <= len(rows) <= MAX_CANDIDATES or len(lengths) != 1 or 0 in lengths:
        raise _bad_q_hvac(
            f"1 to {MAX_CANDIDATES} candidates of equal, non-zero length (got {len(rows)} "
            f"of length(s) {sorted(lengths)[:5]})"
        )
    candidates = np.asarray(rows, dtype=float)
    low, high = COLUMNS[Q_HVAC].lower, COLUMNS[Q_HVAC].upper
    with np.errstate(invalid="ignore"):
        inside = (candidates >= low) & (candidates <= high)
    if not inside.all():
        n, k = np.argwhere(~inside)[0]
        raise _bad_q_hvac(
            f"finite values within [{low:g}, {high:g}] W; candidate {n}, step {k} is "
            f"{candidates[n, k]:g} W"
        )
    return candidates


def _bad_q_hvac(needed: str) -> DataValidationError:
    return DataValidationError([Problem(None, Q_HVAC, f"q_hvac must be {needed}")])


def _trajectories(schema: type[Trajectories], prediction: Prediction, **t_in: list) -> Trajectories:
    """Indoor temperature ``t_in`` over the prediction's times, with the set it came from."""
    return schema(
        times=prediction.local_times,
        parameter_set=_ref(prediction.parameter_set, prediction.timezone),
        step_s=prediction.model.dt,
        **t_in,
    )


@lru_cache(maxsize=256)
def _ref(info: SetInfo, tz: str) -> ParameterSetRef:
    """The set's summary with local times (cached: formatting times costs more than a forecast
    served from the cache)."""
    return ParameterSetRef.model_validate(info, context=in_zone(tz))
