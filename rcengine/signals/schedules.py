"""Weekly schedules: 168 hourly values in local time, learnt from data or given.

Office buildings repeat their week; a gain or ventilation rate missing from the data shows up in
the residuals with that weekly rhythm, so a schedule is the natural shape for such an input.

A schedule runs on one of two clocks: "local", the civil time of the building's zone with its
daylight-saving shifts, or "standard", the zone's standard time all year round — how controllers
that ignore daylight saving (and EnergyPlus runs without a daylight-saving period) keep time.

A weekday on which the metered occupancy shows nobody in (a holiday, a closure) runs the Sunday
profile, as building schedules run holidays (EnergyPlus's "Sunday Holidays" day types, the
closed-day profiles of EN 16798-1 Annex C): equipment and ventilation follow the occupants, and
a weekday pattern played through an empty fortnight would be the model's own invention.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd

from rcengine.columns import Q_OCC

HOURS_PER_WEEK = 168
SUNDAY = 6
CLOCKS = ("local", "standard")
Zone = str | dt.tzinfo


def clock_zone(timezone: str, clock: str) -> Zone:
    """The time zone a schedule on ``clock`` ("local" or "standard") reads its hours in."""
    if clock == "local":
        return timezone
    if clock != "standard":
        raise ValueError(f"unknown schedule clock {clock!r}; choose one of {CLOCKS}")
    # Daylight saving only ever adds to the standard offset, in either hemisphere.
    offsets = [pd.Timestamp(f"2021-{month:02d}-15", tz=timezone).utcoffset() for month in (1, 7)]
    return dt.timezone(min(offsets))


# A weekday is closed when its largest metered occupant heat is below this share of a typical
# weekday's largest (the median over the weekdays): a cleaner or a guard is not the office. [-]
CLOSED_DAY_SHARE = 0.1


def closed_weekdays(frame: pd.DataFrame, timezone: Zone) -> np.ndarray:
    """Rows (bool, len(frame)) on a Monday–Friday date whose metered occupant heat ``q_occ``
    stays under ``CLOSED_DAY_SHARE`` of a typical weekday's: the building is closed. None are
    without ``q_occ`` (or on dates it was not metered), nor when most weekdays would be closed:
    then the column does not tell the office's days apart."""
    closed = np.zeros(len(frame), dtype=bool)
    if Q_OCC not in frame.columns:
        return closed
    local = frame.index.tz_convert(timezone)
    q = pd.Series(frame[Q_OCC].to_numpy(dtype=float), index=local.normalize())
    weekday = pd.Series(local.day_of_week < 5, index=q.index).groupby(level=0).first()
    peaks = q.groupby(level=0).max()[weekday]
    peaks = peaks[np.isfinite(peaks)]
    if peaks.empty or not peaks.median() > 0.0:
        return closed
    shut = peaks.index[peaks < CLOSED_DAY_SHARE * peaks.median()]
    if len(shut) > 0.5 * len(peaks):
        return closed
    return np.asarray(q.index.isin(shut))


def hour_of_week(
    times: pd.DatetimeIndex, timezone: Zone, closed: np.ndarray | None = None
) -> np.ndarray:
    """0 = Monday 00:00–01:00 local time … 167 = Sunday 23:00–24:00; ``closed`` rows (a
    ``closed_weekdays`` mask) read Sunday's hours."""
    local = times.tz_convert(timezone)
    day = np.asarray(local.day_of_week)
    if closed is not None:
        day = np.where(closed, SUNDAY, day)
    return np.asarray(day * 24 + local.hour, dtype=int)


# Day types of building schedules (EnergyPlus's "Weekdays", "Saturday", "Sunday"): index of each
# day of the week, Monday first.
DAY_TYPE_OF_WEEKDAY = np.array([0, 0, 0, 0, 0, 1, 2])
N_DAY_TYPES = 3


def day_type_hour(
    times: pd.DatetimeIndex, timezone: Zone, closed: np.ndarray | None = None
) -> np.ndarray:
    """0–23 = weekday hours, 24–47 = Saturday, 48–71 = Sunday, in local time (``closed`` rows
    on Sunday's, ``hour_of_week``)."""
    how = hour_of_week(times, timezone, closed)
    return DAY_TYPE_OF_WEEKDAY[how // 24] * 24 + how % 24


def weekly_from_day_types(profile: np.ndarray) -> np.ndarray:
    """Expand a (72,) weekday/Saturday/Sunday hourly profile to the (168,) week."""
    profile = np.asarray(profile, dtype=float).reshape(N_DAY_TYPES, 24)
    return profile[DAY_TYPE_OF_WEEKDAY].ravel()


def weekly_profile(values: np.ndarray, times: pd.DatetimeIndex, timezone: Zone) -> np.ndarray:
    """Mean of ``values`` in each hour of the week (168,); hours never seen get 0."""
    how = hour_of_week(times, timezone)
    ok = np.isfinite(values)
    sums = np.bincount(how[ok], weights=values[ok], minlength=HOURS_PER_WEEK)
    counts = np.bincount(how[ok], minlength=HOURS_PER_WEEK)
    return np.divide(sums, counts, out=np.zeros(HOURS_PER_WEEK), where=counts > 0)


def schedule_signal(
    profile: np.ndarray, times: pd.DatetimeIndex, timezone: Zone, closed: np.ndarray | None = None
) -> np.ndarray:
    """The weekly profile played back at ``times`` (``closed`` rows on Sunday's hours)."""
    profile = np.asarray(profile, dtype=float)
    if profile.shape != (HOURS_PER_WEEK,):
        raise ValueError(f"a weekly schedule has {HOURS_PER_WEEK} values, got {profile.shape}")
    return profile[hour_of_week(times, timezone, closed)]


def on_hours(profile: np.ndarray, fraction: float = 0.5) -> np.ndarray:
    """0/1 schedule: hours whose value exceeds ``fraction`` of the profile's peak (all off when
    nothing is positive); any length (a week, or the 72 hours of the day types)."""
    profile = np.asarray(profile, dtype=float)
    peak = np.max(profile)
    if peak <= 0:
        return np.zeros_like(profile)
    return (profile > fraction * peak).astype(float)


def describe(schedule: np.ndarray) -> str:
    """Plain words for a 0/1 weekly schedule, e.g. "Mon–Fri 08:00–18:00", each day's separate
    blocks joined by "&" ("Sat 02:00–06:00 & 18:00–24:00")."""
    days = ["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"]
    spans = [_blocks(np.asarray(schedule[d * 24 : (d + 1) * 24]) > 0.5) for d in range(7)]
    groups: list[tuple[list[str], str]] = []
    for day, span in zip(days, spans, strict=True):
        if span is None:
            continue
        follows = groups and days.index(groups[-1][0][-1]) == days.index(day) - 1
        if follows and groups[-1][1] == span:
            groups[-1][0].append(day)
        else:
            groups.append(([day], span))
    if not groups:
        return "never"
    return ", ".join(
        f"{g[0]}–{g[-1]} {span}" if len(g) > 1 else f"{g[0]} {span}" for g, span in groups
    )


def _blocks(on: np.ndarray) -> str | None:
    """The on-hours of one day (24,) in words, e.g. "08:00–12:00 & 13:00–18:00"; None if none."""
    edges = np.flatnonzero(np.diff(np.concatenate([[False], on, [False]]).astype(int)))
    if not edges.size:
        return None
    starts, ends = edges[::2], edges[1::2]
    return " & ".join(f"{a:02d}:00–{b:02d}:00" for a, b in zip(starts, ends, strict=True))
