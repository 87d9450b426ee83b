"""For an MPC: forecasts, candidate trajectories in one call, the state-space model."""

from __future__ import annotations

from functools import lru_cache
from typing import Annotated, TypeVar

import numpy as np
from fastapi import APIRouter, HTTPException, Query, status
from fastapi.concurrency import run_in_threadpool

from rcengine.columns import COLUMNS
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
    response_model=ForecastRead,
    summary="Indoor temperature forecast with the current parameter set",
    description=(
        "The unmeasured states at `start` come from a Kalman filter over the measurements "
        "before it; the inputs over the horizon are the rows already uploaded for it (weather "
        "forecast, planned q_hvac). Missing future inputs: 422 naming the columns and times. "
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
    return _trajectories(ForecastRead, prediction, t_in_pred=prediction.t_in_pred.tolist())


@router.post(
    "/{building_id}/simulate",
    response_model=SimulateRead,
    summary="Indoor temperature for many candidate q_hvac trajectories in one call",
    description=(
        "For an MPC optimiser: the start state as for a forecast, the stored future rows for "
        "every other input, and each candidate HVAC heat trajectory (one value per step) "
        "in place of the planned q_hvac. Computed by linearity in one matrix product."
    ),
    responses=error_responses(401, 404, 409, 422),
)
def simulate(building_id: BuildingDep, body: SimulateRequest, ctx: ContextDep) -> SimulateRead:
    candidates = np.atleast_2d(np.asarray(body.q_hvac, dtype=float))
    if candidates.ndim != 2 or candidates.shape[1] == 0 or len(candidates) > MAX_CANDIDATES:
        raise HTTPException(
            status.HTTP_422_UNPROCESSABLE_CONTENT,
            f"q_hvac must be 1 to {MAX_CANDIDATES} candidates of equal, non-zero length",
        )
    if not np.isfinite(candidates).all():
        raise HTTPException(status.HTTP_422_UNPROCESSABLE_CONTENT, "q_hvac must be finite")
    first = None if body.start is None else parse_instant(body.start, "start")
    prediction, outputs = ctx.forecaster.simulate(building_id, first, candidates)
    return _trajectories(SimulateRead, prediction, t_in=outputs.tolist())


@router.get(
    "/{building_id}/model",
    response_model=ModelRead,
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
