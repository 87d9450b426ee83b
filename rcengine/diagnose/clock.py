"""Whether the building's logger keeps the weather's clock in summer time, before any physics is
judged.

A record joins two clocks: the building's logger (``t_in``, ``q_hvac``, the metered gains) and
the weather's. A logger kept on standard time all year, its readings labelled with the civil
time's offsets, stamps every summer-time reading an hour early against the weather, and the
diagnosis would read that hour of the sun's course as physics.

The sun is what tells the clocks apart: its course is known to the minute, and the declared
glazing and the ``ghi`` apertures answer it within the hour. So where the training half holds
both summer and standard time, the base model, fitted as stamped, is refitted (least squares
from its optimum) with the building's summer-time readings taken an hour later and an hour
earlier than stamped; where one cuts the training RMSE by more than ``CLOCK_MARGIN``, the record
is re-aligned so before anything else is judged, and the report says so. No physics moves the
sun's hour in summer time alone by as much: over the records of the benchmark as committed or
with the other faults, the twenty-fourth sealed set and the variants, the better offset helped
by 4.1 % at most (the window variant), while the benchmark's loggers kept on standard time were
re-aligned by 7.9–28 % (12 of 14, ``benchmarks/diagnose_faults.py``: not a ventilation case whose
base errs by 2 K, nor a 1R1C base erring by 1.6 K, which gained 0.1 % and 1.5 %).

A slip of the whole record (a logger an hour late all year, interval ends stamped as starts) is
not checked: a concealed window's sun, coming at other hours than the declared glazing's, looks
the same — the window variant fitted 9.1 % better read an hour earlier, more than a main-bed
null made an hour late (6.3 %).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from rcengine.columns import Q_HVAC, Q_LIGHT, Q_OCC, T_IN
from rcengine.diagnose.fitting import Fit, FitJob, fit_many
from rcengine.diagnose.settings import FOLD_REFIT
from rcengine.signals.schedules import clock_zone

if TYPE_CHECKING:
    from rcengine.diagnose.selection import Problem

# The columns the building's logger writes; the rest (t_out, the sun, wind, cloud) is weather.
BUILDING_SIDE = (T_IN, Q_HVAC, Q_OCC, Q_LIGHT)
# Offsets tried on the summer-time rows: the hour daylight saving adds or takes. [h]
CLOCK_OFFSETS_H = (-1.0, 1.0)
# Relative cut of the base model's training RMSE an offset must bring to be taken [-]: between
# the most a record without the fault gained (4.1 %, the window variant, whose concealed window
# takes October's sun at other hours) and the least a logger on standard time did (7.9 %).
CLOCK_MARGIN = 0.07


@dataclass(frozen=True)
class ClockCheck:
    """offset_h: how much later than stamped the building's summer-time readings were taken to
    belong (0: as stamped) [h]; rmse_train: the base model's training RMSE per offset tried [K]
    (none tried where the training half does not hold both summer and standard time)."""

    offset_h: float
    rmse_train: dict[float, float]

    def words(self) -> str:
        if not self.offset_h:
            return "the building's readings fit the weather best as stamped"
        before, after = self.rmse_train[0.0], self.rmse_train[self.offset_h]
        later = self.offset_h > 0
        return (
            f"the building's readings ({', '.join(BUILDING_SIDE)}) fit the weather best read "
            f"{abs(self.offset_h):g} h {'later' if later else 'earlier'} than stamped in summer "
            f"time (training RMSE {before:.3f} → {after:.3f} K, "
            f"{100 * (after - before) / before:+.0f} %): the logger keeps "
            f"{'civil time against weather on standard' if later else 'standard time all year'}"
            "; the record is judged re-aligned"
        )

    def to_dict(self) -> dict:
        return {
            "offset_h": self.offset_h,
            "rows": "summer time",
            "rmse_train_K": {f"{h:+g}": v for h, v in sorted(self.rmse_train.items())},
            "margin": CLOCK_MARGIN,
            "note": self.words(),
        }


def summer_time(index: pd.DatetimeIndex, timezone: str) -> np.ndarray:
    """Rows whose civil time in ``timezone`` is ahead of its standard time (the schedules'
    "standard" clock, ``signals.schedules.clock_zone``)."""
    civil = index.tz_convert(timezone).tz_localize(None)
    standard = index.tz_convert(clock_zone(timezone, "standard")).tz_localize(None)
    return np.asarray(civil != standard)


def read_later(frame: pd.DataFrame, hours: float, rows: np.ndarray | None = None) -> pd.DataFrame:
    """``frame`` with the building readings of ``rows`` (default all) taken from ``hours``
    later (earlier where negative); rows whose source time the record does not hold are
    dropped."""
    moved = np.ones(len(frame), dtype=bool) if rows is None else rows
    columns = [c for c in BUILDING_SIDE if c in frame.columns]
    source = frame.index + pd.Timedelta(hours=hours)
    held = source.isin(frame.index) | ~moved
    out = frame.loc[held].copy()
    taken = moved[held]
    out.loc[taken, columns] = frame[columns].reindex(source[held][taken]).to_numpy()
    return out


def realigned(frame: pd.DataFrame, offset_h: float, timezone: str) -> pd.DataFrame:
    """``frame`` with its summer-time building readings taken ``offset_h`` later."""
    if not offset_h:
        return frame
    return read_later(frame, offset_h, summer_time(frame.index, timezone))


def check_clock(problem: Problem, baseline: Fit) -> ClockCheck:
    """The offset of the building's summer-time readings that the base model fits best, as
    stamped unless it cuts the training RMSE by more than ``CLOCK_MARGIN``."""
    index = problem.frame.index
    summer = summer_time(index, problem.building.location.timezone)
    in_training = summer[index < problem.boundary]
    if in_training.all() or not in_training.any():
        return ClockCheck(0.0, {0.0: baseline.rmse_train})
    jobs = []
    for hours in CLOCK_OFFSETS_H:
        shifted = replace(problem, frame=read_later(problem.frame, hours, summer))
        split = shifted.split(baseline.network, baseline.options)
        jobs.append(
            FitJob(
                baseline.network,
                baseline.options,
                split,
                FOLD_REFIT,
                problem.settings.random_state,
                [baseline.params],
            )
        )
    fits = fit_many(jobs, problem.settings.workers)
    rmse = {0.0: baseline.rmse_train} | {
        h: f.rmse_train for h, f in zip(CLOCK_OFFSETS_H, fits, strict=True)
    }
    best = min(rmse, key=rmse.__getitem__)
    taken = best if rmse[best] < (1.0 - CLOCK_MARGIN) * rmse[0.0] else 0.0
    return ClockCheck(taken, rmse)
