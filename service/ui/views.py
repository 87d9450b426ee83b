"""What the dashboard shows, read through the repository and the forecaster the API uses.

Fleet: one row per building (last measured time, coverage, current set, last calibration, last day's
forecast error, diagnosis verdict, badges). Building: the same summary, the series of the last
days measured beside the day-ahead predictions, the next 24 h forecast with its interval, the
last 30 days of data with their gaps, the parameter-set history, the jobs and the latest
diagnosis. Forecasts go through :class:`~service.forecasting.Forecaster`, cached per data
revision, so a page seen twice is not recomputed.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy import Row
from sqlalchemy.orm import Session

from rcengine.columns import Q_HVAC, T_IN, T_OUT
from rcengine.exceptions import RCEngineError

from .. import repository
from ..context import ServiceContext
from ..errors import ConflictError
from ..forecasting import Prediction
from ..models import CALIBRATION, DIAGNOSIS, FAILED, REJECTED, JobRecord, ParameterSetRecord

# Data older than this at page time is flagged stale.
STALE_AFTER = timedelta(hours=48)
# Days of measured vs day-ahead predicted shown, and days of data in the overview.
DAYS_SHOWN = 3
OVERVIEW_DAYS = 30
FORECAST_H = 24.0
JOBS_SHOWN = 20
GAPS_SHOWN = 20
# Time the fleet page may spend computing last days' errors not yet cached. [s]
FLEET_FORECAST_BUDGET_S = 1.0
DAY = pd.Timedelta(hours=24)
EPOCH = pd.Timestamp("1970-01-01")


@dataclass(frozen=True)
class Overview:
    """A building's state at a glance: one fleet row, the head of its page."""

    id: int
    name: str
    timezone: str
    rows: int
    last_measured: str | None
    last_measured_utc: str | None  # sorts across time zones
    coverage: float | None
    set_id: int | None
    set_model: str | None
    set_age_days: float | None
    rmse_holdout: float | None
    calibration: str | None
    calibration_why: str | None
    day_error: float | None
    verdict: str | None
    badges: tuple[str, ...]


# --- fleet and overview -----------------------------------------------------------------------
def fleet(ctx: ServiceContext) -> list[Overview]:
    """Every building's overview. A last day's error not in the forecast cache is computed
    only while the page's FLEET_FORECAST_BUDGET_S lasts (tens of ms each): a large fleet after
    a round of uploads still answers at once, the rest shown when next computed."""
    deadline = time.monotonic() + FLEET_FORECAST_BUDGET_S
    with ctx.db.session() as session:
        rows = repository.building_summaries(session)
        return [_overview(ctx, session, row, time.monotonic() < deadline) for row in rows]


def _overview(ctx: ServiceContext, session: Session, row: Row, compute: bool = True) -> Overview:
    current = repository.current_parameter_set(session, row.id)
    jobs = repository.list_jobs(session, row.id, 1, CALIBRATION)
    diagnosis = repository.latest_diagnosis(session, row.id)
    last_job = jobs[0] if jobs else None
    day_error = None if current is None else last_day_error(ctx, row, compute)
    now = datetime.now(UTC)
    return Overview(
        id=row.id,
        name=row.name,
        timezone=row.timezone,
        rows=row.rows,
        last_measured=local(row.last_measured_time, row.timezone),
        last_measured_utc=local(row.last_measured_time, "UTC"),
        coverage=coverage(row),
        set_id=None if current is None else current.id,
        set_model=None if current is None else current.model,
        set_age_days=None if current is None else (now - current.created_at) / timedelta(days=1),
        rmse_holdout=None if current is None else current.rmse_holdout,
        calibration=None if last_job is None else job_outcome(last_job),
        calibration_why=None if last_job is None else job_reason(last_job),
        day_error=day_error,
        verdict=None if diagnosis is None else diagnosis.report.get("verdict"),
        badges=badges(row, current, last_job, now),
    )


def badges(
    row: Row, current: ParameterSetRecord | None, last_job: JobRecord | None, now: datetime
) -> tuple[str, ...]:
    """'stale data' (no measured t_in for STALE_AFTER), 'no data', 'no model', 'fit failing'
    (the last calibration failed or its set was refused)."""
    found = []
    if row.last_measured_time is None:
        found.append("no data")
    elif now - row.last_measured_time > STALE_AFTER:
        found.append("stale data")
    if current is None:
        found.append("no model")
    if last_job is not None and (last_job.status == FAILED or last_job.outcome == REJECTED):
        found.append("fit failing")
    return tuple(found)


def coverage(row: Row) -> float | None:
    """Share of the time grid from the first to the last stored row that holds a row."""
    if not row.rows or row.step_s is None or row.first_time is None:
        return None
    expected = (row.last_time - row.first_time).total_seconds() / row.step_s + 1
    return min(1.0, row.rows / expected)


def job_outcome(job: JobRecord) -> str:
    """'promoted' / 'rejected' for a finished calibration, else the job's status."""
    return job.outcome or job.status


def job_reason(job: JobRecord) -> str | None:
    return job.error or (job.details or {}).get("reason")


# --- forecasts --------------------------------------------------------------------------------
def _end(row: Row) -> pd.Timestamp | None:
    """One step after the last measured t_in: where the next forecast starts."""
    if row.last_measured_time is None or row.step_s is None:
        return None
    return pd.Timestamp(row.last_measured_time) + pd.Timedelta(seconds=row.step_s)


def _predict(
    ctx: ServiceContext, building_id: int, start: pd.Timestamp | None, hours: float = FORECAST_H
) -> Prediction:
    return ctx.forecaster.forecast(building_id, start, hours)


def last_day_error(ctx: ServiceContext, row: Row, compute: bool = True) -> float | None:
    """RMSE [K] of the current set's day-ahead forecast of the last measured day; None when it
    cannot be made, or is not cached and ``compute`` is False."""
    end = _end(row)
    if end is None:
        return None
    try:
        if compute:
            prediction = _predict(ctx, row.id, end - DAY)
        else:
            prediction = ctx.forecaster.cached(row.id, end - DAY, FORECAST_H)
    except (RCEngineError, ConflictError):
        return None
    if prediction is None:
        return None
    measured = _measured(prediction)
    both = ~np.isnan(measured)
    if not both.any():
        return None
    return float(np.sqrt(np.mean((measured[both] - prediction.t_in_pred[both]) ** 2)))


def _measured(prediction: Prediction) -> np.ndarray:
    frame = prediction.data.frame
    if T_IN not in frame:
        return np.full(len(prediction.times), np.nan)
    return frame[T_IN].reindex(prediction.times).to_numpy(dtype=float)


def forecast_chart(ctx: ServiceContext, row: Row) -> dict[str, Any]:
    """Series of the main chart: the model run open loop over the last DAYS_SHOWN days (its
    state filtered from the measurements before) beside the measured t_in, then the next 24 h
    forecast and its ±2σ band; ``note`` says what could not be drawn and why.

    One forecast call covers the past days: the page recomputes its forecasts after every
    upload (they are cached per data revision), and each call costs tens of milliseconds.
    """
    chart: dict[str, Any] = {"measured": _series(), "predicted": _series(), "forecast": None}
    end = _end(row)
    if end is None:
        return {**chart, "note": "no measured t_in stored yet"}
    notes = []
    for days in range(DAYS_SHOWN, 0, -1):  # fewer days when the record is short
        try:
            past = _predict(ctx, row.id, end - days * DAY, days * 24.0)
        except (RCEngineError, ConflictError) as exc:
            failure = exc
            continue
        _extend(chart["measured"], past.times, _measured(past), row.timezone)
        _extend(chart["predicted"], past.times, past.t_in_pred, row.timezone)
        chart["days"] = days
        break
    else:
        notes.append(f"model over the last days: {failure}")
    try:
        ahead = _predict(ctx, row.id, None)
        chart["forecast"] = {
            "x": wall_clock(ahead.times, row.timezone),
            "y": _rounded(ahead.t_in_pred),
            "std": _rounded(ahead.t_in_std),
        }
    except (RCEngineError, ConflictError) as exc:
        notes.append(f"next {FORECAST_H:g} h: {exc}")
    return {**chart, "note": "; ".join(notes) or None}


def _series() -> dict[str, list]:
    return {"x": [], "y": []}


def _extend(series: dict[str, list], times: pd.DatetimeIndex, values: np.ndarray, tz: str):
    series["x"].extend(wall_clock(times, tz))
    series["y"].extend(_rounded(values))


# --- data -------------------------------------------------------------------------------------
def data_overview(session: Session, row: Row) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The last OVERVIEW_DAYS days of t_in, t_out and q_hvac up to the last stored row, and the
    gaps in them (missing rows, or rows without t_in before the last measured one)."""
    if row.last_time is None:
        return {"x": [], T_IN: [], T_OUT: [], Q_HVAC: []}, []
    start = row.last_time - timedelta(days=OVERVIEW_DAYS)
    stored = repository.read_series(session, row.id, [T_IN, T_OUT, Q_HVAC], start)
    times = pd.DatetimeIndex(pd.to_datetime([r[0] for r in stored], utc=True, format="ISO8601"))
    values = np.array([r[1:] for r in stored], dtype=float).reshape(len(stored), 3)
    series = {"x": wall_clock(times, row.timezone)}
    for k, name in enumerate((T_IN, T_OUT, Q_HVAC)):
        series[name] = _rounded(values[:, k])
    return series, gaps(times, values[:, 0], row)


def gaps(times: pd.DatetimeIndex, t_in: np.ndarray, row: Row) -> list[dict[str, Any]]:
    """Missing stretches, longest first: steps with no row at all, and runs of rows without a
    measured t_in up to the last measured time (later rows are the forecast's inputs)."""
    if len(times) < 2 or row.step_s is None:
        return []
    step = pd.Timedelta(seconds=row.step_s)
    found = []
    jumps = np.flatnonzero(np.asarray((times[1:] - times[:-1]) > step))
    for k in jumps:
        found.append(_gap(times[k] + step, times[k + 1], step, "no rows", row.timezone))
    measured_until = times <= pd.Timestamp(row.last_measured_time or times[0])
    missing = np.isnan(t_in) & measured_until
    edges = np.diff(np.concatenate(([0], missing.astype(np.int8), [0])))
    for first, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        found.append(_gap(times[first], times[stop - 1] + step, step, "no t_in", row.timezone))
    found.sort(key=lambda gap: -gap["steps"])
    return found[:GAPS_SHOWN]


def _gap(start: pd.Timestamp, end: pd.Timestamp, step: pd.Timedelta, kind: str, tz: str):
    return {
        "start": local(start, tz),
        "end": local(end, tz),
        "steps": int((end - start) / step),
        "hours": (end - start) / pd.Timedelta(hours=1),
        "kind": kind,
    }


# --- history ----------------------------------------------------------------------------------
def parameter_history(session: Session, building_id: int, tz: str) -> list[dict[str, Any]]:
    history = []
    for record in repository.list_parameter_sets(session, building_id):
        holdout = (record.metrics or {}).get("holdout") or {}
        history.append(
            {
                "id": record.id,
                "model": record.model,
                "status": record.status,
                "created": local(record.created_at, tz),
                "train": f"{local(record.train_start, tz)} → {local(record.train_end, tz)}",
                "rmse_train": record.rmse_train,
                "rmse_holdout": record.rmse_holdout,
                "ashrae": holdout.get("ashrae14_pass"),
                "reason": record.reason,
                "values": {k: (v["value"], v["unit"]) for k, v in record.parameters.items()},
            }
        )
    return history


def jobs(session: Session, building_id: int, tz: str) -> list[dict[str, Any]]:
    """Calibrations and diagnoses, newest first."""
    records = [
        *repository.list_jobs(session, building_id, JOBS_SHOWN, CALIBRATION),
        *repository.list_jobs(session, building_id, JOBS_SHOWN, DIAGNOSIS),
    ]
    records.sort(key=lambda job: job.id, reverse=True)
    return [
        {
            "id": job.id,
            "kind": job.kind,
            "status": job.status,
            "outcome": job.outcome,
            "trigger": job.trigger,
            "model": job.model,
            "days": job.days,
            "created": local(job.created_at, tz),
            "finished": local(job.finished_at, tz),
            "why": job_reason(job),
        }
        for job in records[:JOBS_SHOWN]
    ]


def prefetch_forecasts(ctx: ServiceContext, row: Row) -> None:
    """Compute the page's three forecasts side by side, into the forecaster's cache: each
    spends much of its time in SQLite and numpy, which release the GIL, so together they take
    little more than the slowest. Failures are left for :func:`forecast_chart` to report."""
    end = _end(row)
    if end is None:
        return
    calls = (
        (end - DAYS_SHOWN * DAY, DAYS_SHOWN * 24.0),
        (end - DAY, FORECAST_H),
        (None, FORECAST_H),
    )
    with ThreadPoolExecutor(len(calls)) as pool:
        for future in [pool.submit(_predict, ctx, row.id, *call) for call in calls]:
            future.exception()  # waits


def building_page(ctx: ServiceContext, building_id: int) -> dict[str, Any]:
    """Everything the building page shows."""
    with ctx.db.session() as session:
        row = repository.building_summary(session, building_id)
    prefetch_forecasts(ctx, row)
    with ctx.db.session() as session:
        head = _overview(ctx, session, row)
        data, found_gaps = data_overview(session, row)
        history = parameter_history(session, building_id, row.timezone)
        job_rows = jobs(session, building_id, row.timezone)
        diagnosis = repository.latest_diagnosis(session, building_id)
        report = None if diagnosis is None else _diagnosis(diagnosis.report, diagnosis, row)
    return {
        "b": head,
        "charts": {"forecast": forecast_chart(ctx, row), "data": data},
        "gaps": found_gaps,
        "history": history,
        "jobs": job_rows,
        "active": any(job["status"] in ("queued", "running") for job in job_rows),
        "diagnosis": report,
    }


def _diagnosis(report: dict[str, Any], record: Any, row: Row) -> dict[str, Any]:
    return {
        "id": record.id,
        "created": local(record.created_at, row.timezone),
        "window": f"{local(record.window_start, row.timezone)} → "
        f"{local(record.window_end, row.timezone)}",
        "verdict": report.get("verdict"),
        "baseline": report.get("baseline") or {},
        "final": report.get("final") or {},
        "findings": [f for f in report.get("findings") or [] if f.get("accepted")],
    }


# --- formatting -------------------------------------------------------------------------------
def local(moment: datetime | pd.Timestamp | None, tz: str) -> str | None:
    """``2017-01-09 08:15 +01:00``: a stored instant in the building's time zone."""
    if moment is None:
        return None
    return pd.Timestamp(moment).tz_convert(tz).strftime("%Y-%m-%d %H:%M %z")


def wall_clock(times: pd.DatetimeIndex, tz: str) -> list[int]:
    """Local wall-clock times for the charts, as milliseconds since 1970 read as UTC, which is
    how plotly's date axes (which know no time zones) take numbers: no text to format."""
    local_naive = times.tz_convert(tz).tz_localize(None)
    return ((local_naive - EPOCH) // pd.Timedelta(milliseconds=1)).tolist()


def _rounded(values: np.ndarray) -> list[float | None]:
    """Values to 3 decimals, NaN as None (JSON null: a gap in the line)."""
    values = np.round(np.asarray(values, dtype=float), 3)
    cells = values.astype(object)
    cells[np.isnan(values)] = None
    return cells.tolist()
