"""One parser for instants: every time a user, a file or a request names (CLI options, dataset
slices, forecast starts, service query parameters).

Accepted forms: an ISO 8601 instant with a UTC offset (``2017-01-09T06:15:00+01:00``, ``...Z``),
or — where a building's time zone is given — a local date (``2017-01-09``, the start of that day)
or a local date-time without offset, read as the wall-clock time in that zone. A ``+`` turned
into a space by URL decoding (``...T06:15:00 01:00``) is put back. Other spellings pandas would
guess at (``now``, ``9/1/2017``) are refused; so are local times the clocks skip or repeat at a
change of offset, and times outside ``SUPPORTED`` (1900-01-01 … 2199-12-31 UTC).
"""

from __future__ import annotations

import re

import pandas as pd

from rcengine.exceptions import DataValidationError, Problem

_DATE = r"\d{4}-\d{2}-\d{2}"
_TIME = r"\d{2}(?::\d{2}(?::\d{2}(?:[.,]\d+)?)?)?"
_PLUS_AS_SPACE = re.compile(rf"^({_DATE}[T ]{_TIME}) (\d{{2}}:?\d{{2}})$")
# ISO 8601 extended form: a date, optionally a time, optionally a UTC offset.
_ISO_8601 = re.compile(rf"^{_DATE}(?:[T ]{_TIME})?(?:Z|[+-]\d{{2}}(?::?\d{{2}})?)?$")
_DATE_ONLY = re.compile(rf"^{_DATE}$")

# Times a record, a forecast or a query may name, [start, end) in UTC. pandas holds instants in
# nanoseconds, 1677-09-21 … 2262-04-11: a time accepted up to that edge overflowed later — a
# row at 2262-04-11T23:45Z, stored, could not be shown in Europe/Rome's local time, and a forecast
# start near either edge reached past it with the filter's 48 h look-back or a week's horizon.
# No building's record lies near those edges; this range keeps every such step decades inside.
SUPPORTED = (pd.Timestamp("1900-01-01", tz="UTC"), pd.Timestamp("2200-01-01", tz="UTC"))
SUPPORTED_TEXT = "1900-01-01 … 2199-12-31"


def parse_instant(value: object, name: str = "time", timezone: str | None = None) -> pd.Timestamp:
    """``value`` as a UTC timestamp.

    Parameters
    ----------
    value : str, datetime or Timestamp
        The instant. Text without an offset is accepted only when ``timezone`` is given.
    name : str
        What the value is (an option, a column, a query parameter); named in the error.
    timezone : str, optional
        IANA zone (the building's) in which dates and offset-less times are read.

    Raises
    ------
    DataValidationError : one problem naming ``name`` when the value is no such instant.
    """
    text = value
    if isinstance(value, str):
        text = _PLUS_AS_SPACE.sub(r"\1+\2", value.strip())
        if not _ISO_8601.match(text):
            raise _invalid(value, name, timezone, "")
    try:
        stamp = pd.Timestamp(text)
    except (ValueError, TypeError, OverflowError) as exc:
        raise _invalid(value, name, timezone, f" ({_reason(exc)})") from None
    if pd.isna(stamp):
        raise _invalid(value, name, timezone, "")
    if stamp.tzinfo is None:
        if timezone is None:
            raise _invalid(value, name, timezone, " (no UTC offset)")
        stamp = _localize(stamp, value, name, timezone)
    try:
        utc = stamp.tz_convert("UTC").as_unit("ns")
    except (ValueError, OverflowError) as exc:
        raise _invalid(value, name, timezone, f" ({_reason(exc)})") from None
    if not SUPPORTED[0] <= utc < SUPPORTED[1]:
        raise _invalid(value, name, timezone, f" (outside the supported range {SUPPORTED_TEXT})")
    return utc


def is_local_date(value: object) -> bool:
    """True for a bare ``YYYY-MM-DD`` (a whole local day, e.g. the end of a period)."""
    return isinstance(value, str) and bool(_DATE_ONLY.match(value.strip()))


def _localize(stamp: pd.Timestamp, value: object, name: str, timezone: str) -> pd.Timestamp:
    """The wall-clock ``stamp`` in ``timezone``: a date is the start of that local day (after
    any gap the clocks skip); a time the clocks skip or repeat is refused."""
    day = is_local_date(value)
    try:
        local = stamp.tz_localize(
            timezone,
            ambiguous=True if day else "NaT",
            nonexistent="shift_forward" if day else "NaT",
        )
    except (ValueError, TypeError, OverflowError) as exc:
        raise _invalid(value, name, timezone, f" ({_reason(exc)})") from None
    if pd.isna(local):
        wall = f"{stamp:%Y-%m-%d %H:%M}"
        skipped = pd.isna(stamp.tz_localize(timezone, ambiguous=True, nonexistent="NaT"))
        why = (
            f"the clocks of {timezone} skip {wall}"
            if skipped
            else f"{wall} happens twice in {timezone}; give the UTC offset"
        )
        raise _invalid(value, name, timezone, f" ({why})")
    return local


def _reason(exc: BaseException) -> str:
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if "overflow" in text.lower() or "out of bounds" in text.lower():
        return f"outside the supported range {SUPPORTED_TEXT}"
    if "tzoffset" in text:
        return "a UTC offset lies within ±24 h"
    # pandas ends some messages with the text parsed, already quoted in ours.
    return re.sub(r": [^:]*\d{4}-\d{2}-\d{2}\S*$", "", text)


def _invalid(value: object, name: str, timezone: str | None, why: str) -> DataValidationError:
    forms = "an ISO 8601 time with a UTC offset, e.g. 2017-01-09T06:15:00+01:00"
    if timezone is not None:
        forms += f", or a local date such as 2017-01-09 ({timezone})"
    return DataValidationError([Problem(None, name, f"{name} {value!r} is not {forms}{why}")])
