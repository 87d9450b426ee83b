"""The thesis's rolling learn/predict study (§2.4.4, §3), reproduced on any record.

For every day of the season, learn on the previous 1, 3, 5 and 7 days and predict 1, 3 and 7 days
ahead, for each model, on the "Complete period" (all days) and the "Selected period" (weekdays
only). In the Selected period the weekends are gaps: training simulates each weekday run from its
own initial state, and a forecast that spans a weekend restarts on Monday from the state the
Kalman filter estimates over the (measured) weekend, so Friday never flows into Monday.
Predictions start from the state filtered over the 48 h of measurements before them. Beside
every forecast the naive one, "tomorrow = today" (persistence), is scored on the same days.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import Q_HVAC, T_IN
from rcengine.dataset import Dataset
from rcengine.estimation import Estimator, EstimatorSettings
from rcengine.forecast import forecast
from rcengine.io.instants import parse_instant
from rcengine.kalman import Noise
from rcengine.metrics import rmse
from rcengine.models import get_model
from rcengine.parallel import process_pool
from rcengine.signals import SignalOptions, prepare

PERIODS = ("complete", "selected")


@dataclass(frozen=True)
class StudySettings:
    """models, learning lengths [d], horizons [d], estimator preset; start ≤ day < end restrict
    the days predicted (instants, or local dates: ``parse_instant``); workers: processes (default:
    every core); criterion: the estimator's ("output_error", the published figures, or
    "likelihood", whose fitted noise model then also sets the forecasts' start state)."""

    models: tuple[str, ...] = ("basic", "sun")
    periods: tuple[str, ...] = PERIODS
    learn_days: tuple[int, ...] = (1, 3, 5, 7)
    horizons: tuple[int, ...] = (1, 3, 7)
    preset: str | EstimatorSettings = "study"
    start: str | pd.Timestamp | None = None
    end: str | pd.Timestamp | None = None
    workers: int = field(default_factory=lambda: os.cpu_count() or 1)
    random_state: int = 0
    criterion: str = "output_error"


@dataclass(frozen=True)
class Task:
    model: str
    period: str
    day: pd.Timestamp  # local midnight of the first predicted day


# Per-process state: the prepared record of each model (set by _init_worker).
_STATE: dict[str, object] = {}


def _init_worker(frame: pd.DataFrame, building: Building, settings: StudySettings) -> None:
    _STATE["building"] = building
    _STATE["settings"] = settings
    _STATE["data"] = {m: prepared(frame, building, m) for m in settings.models}


def prepared(frame: pd.DataFrame, building: Building, model: str) -> Dataset:
    """The record with the inputs ``model`` needs, derived with the default signal options."""
    net = get_model(model, building, frame.columns)
    return prepare(frame, building, net.compile().input_names, SignalOptions())


def local_days(data: Dataset, timezone: str) -> pd.DatetimeIndex:
    """Local midnights of the whole days in the record."""
    local = data.times.tz_convert(timezone)
    days = local.normalize().unique()
    per_day = pd.Series(1, index=local.normalize()).groupby(level=0).size()
    full = per_day[per_day >= round(86400 / data.step_s)].index
    return days[days.isin(full)]


def _window(
    days: pd.DatetimeIndex, day: pd.Timestamp, count: int, period: str, before: bool
) -> list[pd.Timestamp] | None:
    """``count`` days before (or from) ``day`` in the period's calendar; None if not available."""
    pool = days if period == "complete" else days[days.day_of_week < 5]
    chosen = pool[pool < day][-count:] if before else pool[pool >= day][:count]
    return list(chosen) if len(chosen) == count else None


def _forecast_days(
    compiled,
    params: dict,
    data: Dataset,
    chosen: list[pd.Timestamp],
    noise: Noise | None = None,
) -> tuple[pd.DatetimeIndex, np.ndarray, np.ndarray]:
    """Times, predicted and measured t_in over ``chosen`` days; each run of consecutive days is
    one forecast from the Kalman state at its start (``noise``: the fitted noise model, None for
    the filter's defaults)."""
    runs, current = [], [chosen[0]]
    for day in chosen[1:]:
        if day - current[-1] == pd.Timedelta(days=1):
            current.append(day)
        else:
            runs.append(current)
            current = [day]
    runs.append(current)
    times, predicted, measured = [], [], []
    for run in runs:
        fc = forecast(compiled, params, data, run[0], hours=24 * len(run), noise=noise)
        times.append(fc.times)
        predicted.append(fc.t_in_pred)
        measured.append(data.frame[T_IN].reindex(fc.times).to_numpy(dtype=float))
    return times[0].append(times[1:]), np.concatenate(predicted), np.concatenate(measured)


@dataclass(frozen=True)
class Prediction:
    """The fitted estimator, its wall and CPU time [s], and the forecast against the record."""

    estimator: Estimator
    wall_s: float
    cpu_s: float
    times: pd.DatetimeIndex
    predicted: np.ndarray
    measured: np.ndarray


def learn_and_predict(
    data: Dataset,
    network,
    past: list[pd.Timestamp],
    ahead: list[pd.Timestamp],
    preset: str | EstimatorSettings,
    random_state: int,
    criterion: str = "output_error",
) -> Prediction:
    """Fit on the ``past`` days by ``criterion``, forecast the ``ahead`` days."""
    # CPU time beside wall time: other processes sharing the cores inflate only the latter.
    started, started_cpu = time.perf_counter(), time.process_time()
    est = Estimator(
        network, preset=preset, random_state=random_state, criterion=criterion, warn_bounds=False
    ).fit(data.on_days(past))
    wall, cpu = time.perf_counter() - started, time.process_time() - started_cpu
    times, predicted, measured = _forecast_days(est.compiled, est.params_, data, ahead, est.noise_)
    return Prediction(est, wall, cpu, times, predicted, measured)


def persistence(
    data: Dataset, yesterday: pd.Timestamp, times: pd.DatetimeIndex, timezone: str
) -> np.ndarray:
    """The naive forecast "tomorrow = today": every predicted step takes the t_in measured at the
    same local time of ``yesterday`` (the last day before the forecast in the period's calendar,
    a local midnight). [°C]"""
    wall_clock = times.tz_convert(timezone).tz_localize(None)
    source = yesterday.tz_localize(None) + (wall_clock - wall_clock.normalize())
    # The hour repeated or skipped by a daylight-saving change has no single match: left out.
    source = source.tz_localize(timezone, ambiguous="NaT", nonexistent="NaT").tz_convert("UTC")
    return data.frame[T_IN].reindex(source).to_numpy(dtype=float)


def run_task(task: Task) -> list[dict]:
    """Every learning length for one (model, period, first predicted day)."""
    settings: StudySettings = _STATE["settings"]  # type: ignore[assignment]
    building: Building = _STATE["building"]  # type: ignore[assignment]
    data: Dataset = _STATE["data"][task.model]  # type: ignore[index]
    days = local_days(data, building.location.timezone)
    net = get_model(task.model, building, data.frame.columns)
    ahead = _window(days, task.day, max(settings.horizons), task.period, before=False)
    yesterday = _window(days, task.day, 1, task.period, before=True)
    steps_per_day = round(86400 / data.step_s)
    out = []
    for learn in settings.learn_days:
        past = _window(days, task.day, learn, task.period, before=True)
        if past is None or ahead is None or yesterday is None:
            continue
        p = learn_and_predict(
            data, net, past, ahead, settings.preset, settings.random_state, settings.criterion
        )
        naive = persistence(data, yesterday[0], p.times, building.location.timezone)
        row = {
            "model": task.model,
            "period": task.period,
            "day": task.day.date().isoformat(),
            "weekday": task.day.day_name(),
            "learn_days": learn,
            "rmse_train": p.estimator.rmse_,
            "wall_s": p.wall_s,
            "cpu_s": p.cpu_s,
            "n_simulations": p.estimator.n_simulations_,
            **p.estimator.params_,
        }
        for h in settings.horizons:
            n = h * steps_per_day
            row[f"rmse_h{h}"] = rmse(p.measured[:n], p.predicted[:n])
        for h in settings.horizons:
            n = h * steps_per_day
            row[f"rmse_persistence_h{h}"] = rmse(p.measured[:n], naive[:n])
        # Where the first day's error lies: while the heating runs (setpoint held, morning
        # recovery) or while the building floats (nights, weekends).
        first = slice(0, steps_per_day)
        heating = data.frame[Q_HVAC].reindex(p.times[first]).to_numpy(dtype=float) > 0
        for label, mask in (("on", heating), ("off", ~heating)):
            row[f"rmse_day1_heating_{label}"] = _rmse_where(
                p.measured[first], p.predicted[first], mask
            )
        out.append(row)
    return out


def _rmse_where(measured: np.ndarray, predicted: np.ndarray, mask: np.ndarray) -> float:
    """RMSE over the steps in ``mask``; NaN when there are none. [K]"""
    return rmse(measured[mask], predicted[mask]) if mask.any() else float("nan")


def example(
    frame: pd.DataFrame,
    building: Building,
    model: str,
    day: str,
    learn_days: int,
    horizon_days: int,
    period: str = "complete",
    preset: str | EstimatorSettings = "study",
) -> Prediction:
    """One learn/predict pair for the example figures (thesis Fig. 3.1–3.3)."""
    data = prepared(frame, building, model)
    days = local_days(data, building.location.timezone)
    start = pd.Timestamp(day).tz_localize(building.location.timezone)
    past = _window(days, start, learn_days, period, before=True)
    ahead = _window(days, start, horizon_days, period, before=False)
    if past is None or ahead is None:
        raise ValueError(f"{day}: not enough days around it for {learn_days}+{horizon_days} days")
    net = get_model(model, building, frame.columns)
    return learn_and_predict(data, net, past, ahead, preset, 0)


@contextmanager
def progress_bar() -> Iterator[Callable[[int, int], None]]:
    """A tqdm bar over the study's (model, period, day) tasks, as ``run_study``'s progress."""
    from tqdm import tqdm

    with tqdm(total=0, unit="day", desc="learn/predict") as bar:

        def progress(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        yield progress


def tasks_for(data: Dataset, building: Building, settings: StudySettings) -> list[Task]:
    days = local_days(data, building.location.timezone)
    first_possible = (
        days[max(settings.learn_days)] if len(days) > max(settings.learn_days) else None
    )
    chosen = days[days >= first_possible] if first_possible is not None else days[:0]
    zone = building.location.timezone
    if settings.start is not None:
        chosen = chosen[chosen >= parse_instant(settings.start, "start", zone)]
    if settings.end is not None:
        chosen = chosen[chosen < parse_instant(settings.end, "end", zone)]
    # Every learning length and horizon needs its days inside the record, so that each average
    # over days is over the same days.
    tasks = []
    for period in settings.periods:
        for day in chosen:
            if period == "selected" and day.day_of_week >= 5:
                continue
            if _window(days, day, max(settings.horizons), period, before=False) is None:
                continue
            if _window(days, day, max(settings.learn_days), period, before=True) is None:
                continue
            tasks.extend(Task(m, period, day) for m in settings.models)
    return tasks


def run_study(
    frame: pd.DataFrame,
    building: Building,
    settings: StudySettings,
    progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:
    """Run every task (in parallel over days) and return one row per training."""
    probe = prepared(frame, building, settings.models[0])
    tasks = tasks_for(probe, building, settings)
    rows: list[dict] = []
    done = 0
    if settings.workers <= 1:
        _init_worker(frame, building, settings)
        for task in tasks:
            rows.extend(run_task(task))
            done += 1
            if progress:
                progress(done, len(tasks))
    else:
        with process_pool(settings.workers, _init_worker, (frame, building, settings)) as pool:
            for result in pool.map(run_task, tasks, chunksize=2):
                rows.extend(result)
                done += 1
                if progress:
                    progress(done, len(tasks))
    return pd.DataFrame(rows)
