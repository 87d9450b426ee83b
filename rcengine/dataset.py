"""A validated time series cut into contiguous segments, ready for simulation.

Rows are on a regular step; a missing row (a gap, or weekends removed as in the thesis's
"Selected period") starts a new segment. Each segment is simulated from its own initial state, so
a Friday-to-Monday jump is never taken for model error (the flaw of thesis §3.2).

A fit bridges short gaps first (``bridge_short_gaps``): a building does not stop between two
readings, and a segment restarted after every dropped reading would have the states of its
slow nodes estimated afresh from each stretch — hundreds of free initial temperatures for a
sensor that drops 3 % of its rows, which absorb exactly the slow physics a diagnosis looks for
and multiply the cost of every simulation. A logger down for up to a day is bridged too, with
the same hours of the days either side: restarted there, ten missing days of a six-month record
gave a heavy building's fit free wall and mass temperatures every fortnight, which took up the
drift a missing gain leaves (training RMSE 0.42 → 0.25 K, test 0.78 → 0.88 K) and hid a strong
unmetered gain and a strong ventilation schedule from the diagnosis
(``benchmarks/diagnose_faults.py``).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rcengine.columns import T_IN
from rcengine.exceptions import DataValidationError, ModelError, Problem
from rcengine.io.instants import parse_instant
from rcengine.statespace import check_hold

# Longest stretch of missing rows a fit bridges by interpolating the inputs. A room's air answers
# within its own time constant (c_air·r: minutes to an hour), so an hour of interpolated weather
# and heat errs by little more than the readings' own noise; longer outages (a logger down for a
# day, the thesis's weekends) start a new segment. [s]
MAX_BRIDGED_GAP_S = 3600.0
# Longest outage bridged with the same hours of the days either side: one local day, 25 h on the
# autumn clock change. A day's weather and heat are guessed best from its neighbours (the sun's
# and the occupants' daily course, the weather's persistence); a longer outage, or a weekend cut
# out of a record on purpose (the thesis's "Selected period"), starts a new segment. [s]
MAX_FILLED_GAP_S = 25 * 3600.0


@dataclass(frozen=True)
class Dataset:
    """Time series on a regular step, indexed by UTC time (row time = start of the interval).

    frame : contract columns plus any derived signals (e.g. ``solar_window``). [SI units]
    step_s : the regular step. [s]
    hold : how the inputs run between rows: ``"zoh"``, each row's value held over its interval
        (the contract's means over the step, the default), or ``"foh"``, samples at the stamps
        with the signal linear in between (``rcengine.simulate``).
    """

    frame: pd.DataFrame
    step_s: float
    hold: str = "zoh"

    def __post_init__(self) -> None:
        check_hold(self.hold)

    @classmethod
    def from_frame(
        cls, frame: pd.DataFrame, step_s: float | None = None, hold: str = "zoh"
    ) -> Dataset:
        if not isinstance(frame.index, pd.DatetimeIndex) or frame.index.tz is None:
            raise DataValidationError([Problem(None, "time", "index must be tz-aware times")])
        if len(frame) < 2:
            raise DataValidationError([Problem(None, None, "need at least two rows")])
        if not frame.index.is_monotonic_increasing or frame.index.has_duplicates:
            raise DataValidationError([Problem(None, "time", "times must strictly increase")])
        if step_s is None:
            step_s = float(pd.Series(_step_seconds(frame.index)).mode().iloc[0])
        return cls(frame.tz_convert("UTC"), float(step_s), hold)

    # --- structure ----------------------------------------------------------------------------
    @property
    def times(self) -> pd.DatetimeIndex:
        return self.frame.index

    def __len__(self) -> int:
        return len(self.frame)

    @property
    def segments(self) -> list[slice]:
        """Row slices of the contiguous runs (consecutive rows exactly one step apart)."""
        breaks = np.flatnonzero(np.abs(_step_seconds(self.frame.index) - self.step_s) > 1e-6) + 1
        edges = [0, *breaks.tolist(), len(self.frame)]
        return [slice(a, b) for a, b in itertools.pairwise(edges)]

    # --- selections ---------------------------------------------------------------------------
    def between(self, start: object = None, end: object = None) -> Dataset:
        """Rows with start ≤ time < end (either may be None; instants with a UTC offset)."""
        mask = np.ones(len(self.frame), dtype=bool)
        if start is not None:
            mask &= self.frame.index >= parse_instant(start, "start")
        if end is not None:
            mask &= self.frame.index < parse_instant(end, "end")
        return self._subset(mask)

    def where(self, mask: np.ndarray) -> Dataset:
        """The rows where ``mask`` holds; the others become gaps."""
        return self._subset(np.asarray(mask, dtype=bool))

    def weekdays(self, timezone: str) -> Dataset:
        """Monday–Friday rows (local calendar), the thesis's "Selected period"."""
        local = self.frame.index.tz_convert(timezone)
        return self._subset(np.asarray(local.day_of_week < 5))

    def on_days(self, days: Sequence[pd.Timestamp]) -> Dataset:
        """Rows of the given local days (tz-aware midnights); other days become gaps."""
        local = self.frame.index.tz_convert(days[0].tz).normalize()
        return self._subset(np.asarray(local.isin(list(days))))

    def with_columns(self, extra: pd.DataFrame) -> Dataset:
        """The same rows with more columns (derived signals), aligned on time."""
        joined = self.frame.join(extra, how="left", suffixes=("", "_derived"))
        return Dataset(joined, self.step_s, self.hold)

    def _subset(self, mask: np.ndarray) -> Dataset:
        if not mask.any():
            raise DataValidationError([Problem(None, "time", "no rows in the selected period")])
        return Dataset(self.frame.loc[mask], self.step_s, self.hold)

    # --- arrays -------------------------------------------------------------------------------
    def inputs(self, names: Sequence[str]) -> np.ndarray:
        """Input matrix (T, m) in the given column order; every value must be finite."""
        missing = [n for n in names if n not in self.frame.columns]
        if missing:
            raise ModelError(
                f"the model needs input(s) {missing} that the data do not have "
                f"(columns: {list(self.frame.columns)})"
            )
        u = self.frame[list(names)].to_numpy(dtype=float)
        bad = ~np.isfinite(u)
        if bad.any():
            # One problem per column, by time: the rows of a window cut from a longer record
            # (a calibration's, a forecast's history) are positions nobody can look up.
            problems = []
            for c in np.flatnonzero(bad.any(axis=0)):
                times = self.frame.index[bad[:, c]]
                first, last = times[0].isoformat(), times[-1].isoformat()
                span = f"at {first}"
                if len(times) > 1:
                    span = f"at {len(times)} rows, {first} to {last}"
                problems.append(Problem(None, names[c], f"input missing or not finite {span}"))
            raise DataValidationError(problems)
        return u

    @property
    def measured(self) -> np.ndarray:
        """Measured indoor temperature (T,), NaN where not measured. [°C]"""
        if T_IN not in self.frame.columns:
            return np.full(len(self.frame), np.nan)
        return self.frame[T_IN].to_numpy(dtype=float)


def _step_seconds(index: pd.DatetimeIndex) -> np.ndarray:
    """Differences between consecutive times. [s]"""
    return np.diff(index.as_unit("ns").asi8) / 1e9


def bridge_short_gaps(
    frame: pd.DataFrame,
    max_gap_s: float = MAX_BRIDGED_GAP_S,
    step_s: float | None = None,
    max_filled_s: float = MAX_FILLED_GAP_S,
) -> pd.DataFrame:
    """``frame`` (tz-aware index, regular step) with its short runs of missing rows restored,
    ``t_in`` left unmeasured (NaN) in them, so the states run on across the gap and nothing
    unseen is scored:

    - a run lasting at most ``max_gap_s``: the inputs interpolated linearly in time between the
      rows either side;
    - a longer one lasting at most ``max_filled_s``: each input at the mean of its values at the
      same time a day before and a day after (either alone where the other is missing too); a
      run with a row neither day has stays a gap.

    Longer gaps stay gaps.

    Parameters
    ----------
    frame : contract columns (and any others) on a regular step.
    max_gap_s : longest missing stretch interpolated. [s]
    step_s : the step; default the most common difference between rows. [s]
    max_filled_s : longest missing stretch filled from the days either side. [s]
    """
    if len(frame) < 2:
        return frame
    step = step_s or Dataset.from_frame(frame).step_s
    runs = _missing_runs(frame.index, step)
    short = [run for run in runs if len(run) * step <= max_gap_s + 1e-6]
    daily = [run for run in runs if max_gap_s + 1e-6 < len(run) * step <= max_filled_s + 1e-6]
    if not short and not daily:
        return frame
    full = frame.reindex(frame.index.union(_joined(short + daily)))
    numeric = [c for c in full.columns if c != T_IN and pd.api.types.is_numeric_dtype(full[c])]
    if short:
        inserted = _joined(short)
        interpolated = full[numeric].interpolate(method="time", limit_area="inside")
        full.loc[inserted, numeric] = interpolated.loc[inserted]
    unfilled = [run for run in daily if not _fill_from_neighbour_days(full, frame, run, numeric)]
    return full.drop(_joined(unfilled)) if unfilled else full


def _missing_runs(index: pd.DatetimeIndex, step_s: float) -> list[pd.DatetimeIndex]:
    """The times of each run of rows missing from ``index``, in its zone."""
    index = index.as_unit("ns")
    missing = np.round(_step_seconds(index) / step_s).astype(int) - 1
    delta = pd.Timedelta(seconds=step_s)
    return [
        pd.date_range(index[i] + delta, periods=missing[i], freq=delta)
        for i in np.flatnonzero(missing > 0)
    ]


def _joined(runs: list[pd.DatetimeIndex]) -> pd.DatetimeIndex:
    """The times of several runs in one index."""
    return runs[0].append(runs[1:])


def _fill_from_neighbour_days(
    full: pd.DataFrame, frame: pd.DataFrame, run: pd.DatetimeIndex, columns: list[str]
) -> bool:
    """Fill ``run`` of ``full`` from ``frame``'s rows a day before and after; False (nothing
    written) where some time has neither."""
    day = pd.Timedelta(days=1)
    neighbours = np.stack(
        [frame[columns].reindex(run + shift).to_numpy(dtype=float) for shift in (-day, day)]
    )
    if np.isnan(neighbours).all(axis=0).any():
        return False
    full.loc[run, columns] = np.nanmean(neighbours, axis=0)
    return True


def aggregated(
    frame: pd.DataFrame, step_s: float, record_step_s: float | None = None
) -> pd.DataFrame:
    """``frame`` averaged into intervals of at least ``step_s`` when its own step is finer.

    Rows are interval means (the contract), so the mean of the rows inside a coarser interval is
    that interval's mean: each input's heat over it is kept. The interval is the smallest whole
    multiple of the record's step reaching ``step_s``, counted from the first row; ``t_in`` is
    the mean of the rows that measured it, an interval without rows is left out (a gap), and
    non-numeric columns are dropped.

    Parameters
    ----------
    frame : contract columns (tz-aware index, regular step).
    step_s : the finest step wanted. [s]
    record_step_s : the record's step; default the most common difference between rows. [s]
    """
    if len(frame) < 2:
        return frame
    step = record_step_s or Dataset.from_frame(frame).step_s
    factor = int(np.ceil(step_s / step - 1e-9))
    if factor <= 1:
        return frame
    numeric = frame.select_dtypes("number")
    bins = numeric.resample(pd.Timedelta(seconds=factor * step), origin="start")
    means, rows = bins.mean(), bins.size()
    return means[rows.to_numpy() > 0]
