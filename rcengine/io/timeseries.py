"""The contract time-series CSV (CONTRACT.md §1): read, validate, write.

``validate_frame`` is the single gate every upload passes (CSV file, JSON rows of the service,
frames built by the other readers). It collects every problem it finds, each naming its row and
column, and raises one :class:`~rcengine.exceptions.DataValidationError`.

Rows and lines
--------------
A problem's ``row`` is the 0-based index of the data row in the input (the first row after the
header is row 0). ``read_timeseries`` also names the line of the file, ``line = row + 2`` (the
header is line 1), e.g. ``row 12, column 't_in': not a number: 'abc' — line 14 of the file``.
Blank lines are not skipped, so that this stays true: a blank line inside the file is an empty
row, reported once; blank lines at the end of the file are ignored.

Rules
-----
* Required columns: ``time``, ``t_in``, ``t_out``, ``ghi``, ``q_hvac``. Columns outside the
  contract are ignored (left out of the result). A column named twice is an error.
* ``time``: ISO 8601 with a UTC offset (``2017-01-09T06:15:00+01:00``; ``Z`` for UTC); strictly
  increasing. The step is the most common difference between consecutive rows and lies in
  60–3600 s; every other difference is a whole multiple of it (missing rows are gaps). The step
  rules are checked once the times are in order, as they mean nothing before.
* Numbers: every cell of a contract column is a number or empty. ``t_out``, ``ghi`` and
  ``q_hvac`` are needed in every row; ``t_in`` may be empty (future rows carry forecast inputs
  only); optional columns may be empty (NaN: unknown at that row). An optional column that is
  empty in every row is dropped (treated as absent); ``t_in`` stays, all NaN.
* Physical ranges from :data:`rcengine.columns.COLUMNS`. Irradiance between the sensor-noise
  level (:data:`~rcengine.columns.IRRADIANCE_NOISE_W_M2`) and 0 is clipped to 0. A temperature
  column whose median lies in 250–330 is reported once as Kelvin instead of row by row.
* At most :data:`MAX_PROBLEMS` problems are collected; a last one says the list was cut.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import numpy as np
import pandas as pd

from rcengine.columns import (
    COLUMNS,
    MAX_STEP_S,
    MIN_STEP_S,
    NUMERIC_COLUMNS,
    REQUIRED_COLUMNS,
    T_IN,
    TEMPERATURE_COLUMNS,
    TIME,
)
from rcengine.exceptions import DataValidationError, Problem
from rcengine.io.instants import SUPPORTED, SUPPORTED_TEXT

MAX_PROBLEMS = 1000
# Data row 0 sits on line 2 of a CSV file, below the header.
FIRST_DATA_LINE = 2
# Needed in every row; t_in is required as a column but may be empty (future rows).
FILLED_EVERY_ROW = tuple(c for c in REQUIRED_COLUMNS if c not in (TIME, T_IN))
IRRADIANCE_COLUMNS = tuple(c.name for c in COLUMNS.values() if c.unit == "W/m²")
# Median of a column in °C that can only be Kelvin (−23 °C … 57 °C expressed in K).
KELVIN_RANGE = (250.0, 330.0)
ZERO_CELSIUS_K = 273.15

_EXAMPLE_TIME = "2017-01-09T06:15:00+01:00"
_LOCAL_TIME = r"\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(?::\d{2}(?:\.\d+)?)?"
_WITH_OFFSET = re.compile(rf"^\s*{_LOCAL_TIME}(?:Z|[+-]\d{{2}}(?::?\d{{2}})?)\s*$")
_WITHOUT_OFFSET = re.compile(rf"^\s*{_LOCAL_TIME}\s*$")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+\s*$")
_NS_PER_S = 1_000_000_000
_NAT = np.iinfo(np.int64).min  # NaT as int64 nanoseconds


@dataclass
class _Problems:
    """Problem collector: caps the list and, for a file, names the line of each row."""

    first_line: int | None = None
    limit: int = MAX_PROBLEMS
    items: list[Problem] = field(default_factory=list)
    cut: bool = False
    # Input row of each row being checked, once empty rows have been set aside.
    positions: np.ndarray | None = None

    @property
    def full(self) -> bool:
        return len(self.items) >= self.limit

    def add(self, row: int | None, column: str | None, message: str) -> None:
        if self.full:
            self.cut = True
            return
        row = self._input_row(row)
        if row is not None and self.first_line is not None:
            message = f"{message} — line {row + self.first_line} of the file"
        self.items.append(Problem(row, column, message))

    def add_rows(self, rows: Iterable[int], column: str | None, message_of) -> None:
        """One problem per row; ``message_of(row)`` is only called for rows that are kept."""
        for row in rows:
            if self.full:
                self.cut = True
                return
            self.add(int(row), column, message_of(int(row)))

    def row(self, row: int) -> str:
        """How a message names another row: ``row 3`` or ``row 3 (line 5)``."""
        row = self._input_row(row)
        if self.first_line is None:
            return f"row {row}"
        return f"row {row} (line {row + self.first_line})"

    def _input_row(self, row: int | None) -> int | None:
        if row is None or self.positions is None:
            return row
        return int(self.positions[row])

    def raise_if_any(self) -> None:
        if not self.items:
            return
        problems = list(self.items)
        if self.cut:
            problems.append(
                Problem(None, None, f"stopped after {self.limit} problems; fix these first")
            )
        raise DataValidationError(problems)


# --- public API -------------------------------------------------------------------------------
def validate_frame(raw: pd.DataFrame, *, first_line: int | None = None) -> pd.DataFrame:
    """Check a table of the contract and return it as the engine's frame.

    Parameters
    ----------
    raw : one row per data row with a ``time`` column; cells as read (strings, numbers or
        missing). A ``time`` column already of tz-aware datetime dtype is taken as is.
    first_line : line of the source file holding data row 0; when given, every problem also
        names its line. None for inputs that are not files.

    Returns
    -------
    DataFrame indexed by a UTC ``DatetimeIndex`` named ``time`` (start of each interval), with a
    float column for every contract column present, in contract order, rows in input order.
    [°C, W/m², W, m/s]

    Raises
    ------
    DataValidationError : every problem found (up to :data:`MAX_PROBLEMS`), see the module
        docstring for the rules.
    """
    problems = _Problems(first_line)
    if len(raw) == 0:
        problems.add(None, None, "no data rows")
        problems.raise_if_any()
    _check_columns(raw.columns, problems)
    raw = _set_empty_rows_aside(raw, problems)
    times = None
    if TIME in raw.columns and not _named_twice(raw.columns, TIME):
        times, text = _parse_times(raw[TIME], problems)
        _check_order_and_step(times, text, problems)
    values = {
        name: _parse_numbers(raw[name], name, problems)
        for name in NUMERIC_COLUMNS
        if name in raw.columns and not _named_twice(raw.columns, name)
    }
    problems.raise_if_any()
    return _frame(times, values)


def read_timeseries(path_or_buffer: str | Path | IO[str]) -> pd.DataFrame:
    """Read and validate a contract CSV (file path or text buffer).

    Every cell is read as text (no silent type guessing); empty cells are missing values.
    Problems name the row and the line of the file (``line = row + 2``).

    Raises
    ------
    DataValidationError : the file cannot be read, is empty, or breaks a rule (see
        :func:`validate_frame`).
    """
    table = _read_text_table(path_or_buffer)
    header = [_header_name(v) for v in table.iloc[0]]
    raw = table.iloc[1:].set_axis(header, axis=1).reset_index(drop=True)
    raw = raw.iloc[: _last_filled_row(raw) + 1]
    if len(header) == 1 and ";" in header[0]:
        raise DataValidationError(
            [Problem(None, None, "columns must be separated by ','; the header has ';'")]
        )
    return validate_frame(raw, first_line=FIRST_DATA_LINE)


def parse_rows(rows: list[dict]) -> pd.DataFrame:
    """Validate rows given as JSON objects (the service's ``{"rows": [...]}`` body).

    Values may be numbers, numeric strings or null; a key missing from a row counts as null, and
    a column exists when at least one row has its key. Problems name the 0-based index of the
    row in the list.

    Raises
    ------
    DataValidationError : see :func:`validate_frame`.
    """
    if not isinstance(rows, list):
        raise DataValidationError([Problem(None, None, "'rows' must be a list of objects")])
    problems = _Problems()
    bad = [i for i, r in enumerate(rows) if not isinstance(r, dict)]
    problems.add_rows(bad, None, lambda i: "a row must be an object of column: value")
    problems.raise_if_any()
    raw = pd.DataFrame.from_records(rows) if rows else pd.DataFrame()
    return validate_frame(raw)


def format_times(index: pd.DatetimeIndex, timezone: str) -> list[str]:
    """ISO 8601 texts with the UTC offset of the IANA ``timezone`` at each instant.

    E.g. ``Europe/Rome``: ``2017-01-09T06:15:00+01:00`` in winter, ``+02:00`` in summer.
    Seconds are always written; fractions of a second only when some time has them.
    """
    if not isinstance(index, pd.DatetimeIndex) or index.tz is None:
        raise ValueError("format_times needs a tz-aware DatetimeIndex")
    local = index.tz_convert(timezone).tz_localize(None)
    offset_s = (local - index.tz_convert("UTC").tz_localize(None)).total_seconds()
    whole_seconds = bool((local.as_unit("ns").asi8 % _NS_PER_S == 0).all())
    wall = np.datetime_as_string(local.values, unit="s" if whole_seconds else "us")
    offsets = {s: _offset_text(s) for s in np.unique(offset_s)}
    return [w + offsets[s] for w, s in zip(wall.tolist(), offset_s.tolist(), strict=True)]


def write_timeseries(
    frame: pd.DataFrame, path_or_buffer: str | Path | IO[str], timezone: str
) -> None:
    """Write ``frame`` as CSV: a ``time`` column in ``timezone`` (see :func:`format_times`),
    then the frame's columns; missing values as empty cells, floats at full precision so that
    :func:`read_timeseries` gives the same frame back."""
    out = frame.reset_index(drop=True)
    out.insert(0, TIME, format_times(frame.index, timezone))
    out.to_csv(path_or_buffer, index=False, na_rep="", lineterminator="\n")


def _set_empty_rows_aside(raw: pd.DataFrame, problems: _Problems) -> pd.DataFrame:
    """An entirely empty row is one problem, not one per column."""
    empty = raw.isna().all(axis=1).to_numpy()
    if not empty.any():
        return raw
    problems.add_rows(np.flatnonzero(empty), None, lambda r: "empty row")
    problems.positions = np.flatnonzero(~empty)
    return raw.iloc[problems.positions]


# --- columns ----------------------------------------------------------------------------------
def _check_columns(columns: pd.Index, problems: _Problems) -> None:
    for name in REQUIRED_COLUMNS:
        if name not in columns:
            hint = _near_miss(name, columns)
            problems.add(None, name, f"required column '{name}' is missing{hint}")
    for name in (TIME, *NUMERIC_COLUMNS):
        if _named_twice(columns, name):
            problems.add(None, name, f"column '{name}' appears more than once")


def _named_twice(columns: pd.Index, name: str) -> bool:
    return int((columns == name).sum()) > 1


def _near_miss(name: str, columns: pd.Index) -> str:
    found = [str(c) for c in columns if str(c).strip().lower() == name and str(c) != name]
    return f" (found {found[0]!r}; names are exactly as in the contract)" if found else ""


# --- time -------------------------------------------------------------------------------------
def _outside_supported(outside: np.ndarray, text: pd.Series, problems: _Problems) -> None:
    """Report the rows whose time lies outside the supported years (``instants.SUPPORTED``)."""
    problems.add_rows(
        np.flatnonzero(outside),
        TIME,
        lambda r: f"time {text[r]!r} is outside the supported range {SUPPORTED_TEXT}",
    )


def _parse_times(cells: pd.Series, problems: _Problems) -> tuple[np.ndarray, pd.Series]:
    """Nanoseconds since the epoch (UTC) per row, NaT where a cell is bad (reported), and the
    cell texts for messages."""
    if isinstance(cells.dtype, pd.DatetimeTZDtype):
        ns = pd.DatetimeIndex(cells).as_unit("ns").asi8.copy()
        text = cells.reset_index(drop=True).astype(str)
        problems.add_rows(np.flatnonzero(ns == _NAT), TIME, lambda r: "time is empty")
        bounds = [SUPPORTED[0].value, SUPPORTED[1].value]
        outside = (ns != _NAT) & ((ns < bounds[0]) | (ns >= bounds[1]))
        _outside_supported(outside, text, problems)
        ns[outside] = _NAT
        return ns, text
    cell_text = _as_text(cells)
    empty = cell_text.isna().to_numpy()
    ok = cell_text.str.match(_WITH_OFFSET).fillna(False).to_numpy(dtype=bool)
    no_offset = np.zeros_like(ok)
    suspect = np.flatnonzero(~ok & ~empty)
    no_offset[suspect] = cell_text.iloc[suspect].str.match(_WITHOUT_OFFSET).to_numpy(dtype=bool)
    parsed = pd.DatetimeIndex(
        pd.to_datetime(cell_text.where(ok), format="ISO8601", utc=True, errors="coerce")
    )
    text = cell_text.map(_shown)
    # pandas parses years 1–9999 at a coarser unit (``instants.SUPPORTED`` says why the range).
    outside = ok & ~np.asarray(parsed.isna() | ((parsed >= SUPPORTED[0]) & (parsed < SUPPORTED[1])))
    _outside_supported(outside, text, problems)
    ok = ok & ~outside
    ns = parsed.where(~outside).as_unit("ns").asi8.copy()
    invalid = ok & (ns == _NAT)
    problems.add_rows(np.flatnonzero(empty), TIME, lambda r: "time is empty")
    lacking = np.flatnonzero(no_offset)
    if lacking.size:  # one problem for all: usually every row of a file lacks it
        more = f" (nor have {lacking.size - 1} later rows)" if lacking.size > 1 else ""
        problems.add(
            int(lacking[0]),
            TIME,
            f"time {text[lacking[0]]!r} has no UTC offset{more}; the contract requires one, "
            f"e.g. '{_EXAMPLE_TIME}' ('Z' for UTC)",
        )
    problems.add_rows(
        np.flatnonzero(~ok & ~empty & ~no_offset & ~outside),
        TIME,
        lambda r: (
            f"unparseable time {text[r]!r}; expected ISO 8601 with a UTC offset, "
            f"e.g. '{_EXAMPLE_TIME}'"
        ),
    )
    problems.add_rows(np.flatnonzero(invalid), TIME, lambda r: f"no such time: {text[r]!r}")
    ns[~ok] = _NAT
    return ns, text


def _check_order_and_step(ns: np.ndarray, text: pd.Series, problems: _Problems) -> None:
    rows = np.flatnonzero(ns != _NAT)
    t = ns[rows]
    if len(t) >= 2 and _check_order(rows, t, text, problems):
        _check_step(rows, t, text, problems)


def _check_order(rows: np.ndarray, t: np.ndarray, text: pd.Series, problems: _Problems) -> bool:
    """Duplicates (naming the first row with that time) and times going back."""
    order = np.argsort(t, kind="stable")
    t_sorted = t[order]
    same = np.r_[False, t_sorted[1:] == t_sorted[:-1]]
    run_start = np.maximum.accumulate(np.where(same, 0, np.arange(len(t))))
    first_of = dict(
        zip(rows[order[same]].tolist(), rows[order[run_start[same]]].tolist(), strict=True)
    )
    problems.add_rows(
        sorted(first_of),
        TIME,
        lambda r: f"duplicate time {text[r]!r}, already at {problems.row(first_of[r])}",
    )
    back = np.flatnonzero(np.diff(t) < 0) + 1
    previous = dict(zip(rows[back].tolist(), rows[back - 1].tolist(), strict=True))
    problems.add_rows(
        [r for r in previous if r not in first_of],
        TIME,
        lambda r: (
            f"time {text[r]!r} is earlier than {problems.row(previous[r])} "
            f"({text[previous[r]]!r}); times must increase"
        ),
    )
    return not first_of and not previous


def _check_step(rows: np.ndarray, t: np.ndarray, text: pd.Series, problems: _Problems) -> None:
    """The step is the most common difference; others must be whole multiples of it (gaps)."""
    diffs = np.diff(t)
    values, counts = np.unique(diffs, return_counts=True)
    step = int(values[np.argmax(counts)])
    if not MIN_STEP_S * _NS_PER_S <= step <= MAX_STEP_S * _NS_PER_S:
        problems.add(
            None,
            TIME,
            f"the time step is {_duration(step)} (the most common difference between rows); "
            f"the contract allows {MIN_STEP_S}–{MAX_STEP_S} s",
        )
        return
    off_grid = np.flatnonzero(diffs % step != 0)
    after = {int(rows[i + 1]): (int(rows[i]), int(diffs[i])) for i in off_grid[: problems.limit]}
    problems.add_rows(
        after,
        TIME,
        lambda r: (
            f"time {text[r]!r} is {_duration(after[r][1])} after "
            f"{problems.row(after[r][0])}, not a whole multiple of the step {_duration(step)} "
            "(mixed steps)"
        ),
    )


def _duration(ns: int) -> str:
    seconds = ns / _NS_PER_S
    if seconds % 3600 == 0:
        return f"{seconds / 3600:g} h"
    if seconds % 60 == 0:
        return f"{seconds / 60:g} min"
    return f"{seconds:g} s"


def _offset_text(seconds: float) -> str:
    sign = "+" if seconds >= 0 else "-"
    minutes = round(abs(seconds) / 60)
    return f"{sign}{minutes // 60:02d}:{minutes % 60:02d}"


# --- numbers ----------------------------------------------------------------------------------
def _parse_numbers(cells: pd.Series, name: str, problems: _Problems) -> np.ndarray | None:
    """Floats of one contract column; None when an optional column is empty in every row."""
    column = COLUMNS[name]
    numbers = _to_float(cells)
    blank = _blank(cells, numbers)
    if blank.all():
        if name in FILLED_EVERY_ROW:
            problems.add(None, name, f"column '{name}' is empty in every row; it is needed in each")
        return None if not column.required else numbers
    problems.add_rows(
        np.flatnonzero(np.isnan(numbers) & ~blank),
        name,
        lambda r: f"not a number: {_shown(cells.iloc[r])!r}{_decimal_hint(cells.iloc[r])}",
    )
    if name in FILLED_EVERY_ROW:
        problems.add_rows(
            np.flatnonzero(blank), name, lambda r: f"empty; '{name}' is needed in every row"
        )
    _check_range(numbers, name, problems)
    if name in IRRADIANCE_COLUMNS:
        # Sensor offset at night: small negatives are noise, irradiance itself is ≥ 0.
        numbers = np.where(numbers < 0.0, 0.0, numbers)
    return numbers


def _check_range(numbers: np.ndarray, name: str, problems: _Problems) -> None:
    column = COLUMNS[name]
    if name in TEMPERATURE_COLUMNS:
        finite = numbers[np.isfinite(numbers)]
        median = float(np.median(finite)) if finite.size else np.nan
        if KELVIN_RANGE[0] <= median <= KELVIN_RANGE[1]:
            problems.add(
                None,
                name,
                f"looks like Kelvin (median {median:.1f}); the contract expects "
                f"°C — subtract {ZERO_CELSIUS_K}",
            )
            return
    with np.errstate(invalid="ignore"):
        low = numbers < column.lower
        high = numbers > column.upper
    if name in IRRADIANCE_COLUMNS:
        problems.add_rows(
            np.flatnonzero(low),
            name,
            lambda r: (
                f"irradiance {numbers[r]:g} {column.unit} is negative beyond the sensor "
                f"noise ({column.lower:g} {column.unit})"
            ),
        )
        low = np.zeros_like(low)
    problems.add_rows(
        np.flatnonzero(low | high),
        name,
        lambda r: (
            f"{numbers[r]:g} {column.unit} is outside the physically possible range "
            f"[{column.lower:g}, {column.upper:g}] {column.unit}"
        ),
    )


def _to_float(cells: pd.Series) -> np.ndarray:
    """Floats; NaN for blanks and for anything that is not a number (booleans included)."""
    if pd.api.types.is_bool_dtype(cells.dtype):
        return np.full(len(cells), np.nan)
    if cells.dtype == object:
        # A JSON integer past a float's range (400 digits) overflows pandas' conversion.
        cells = cells.map(_float_if_int)
    numbers = pd.to_numeric(cells, errors="coerce")
    if cells.dtype == object:
        numbers = numbers.mask(cells.map(lambda v: isinstance(v, bool | np.bool_)).to_numpy())
    return numbers.to_numpy(dtype=float, na_value=np.nan)


# The longest cell text a message quotes whole.
SHOWN_CHARS = 64


def _float_if_int(value: object) -> object:
    """A Python int as a float (±inf past the float range, then refused as out of range)."""
    if not isinstance(value, int) or isinstance(value, bool):
        return value
    try:
        return float(value)
    except OverflowError:
        return float("inf") if value > 0 else float("-inf")


def _blank(cells: pd.Series, numbers: np.ndarray) -> np.ndarray:
    """Missing or whitespace-only cells (only cells that are not numbers need looking at)."""
    blank = cells.isna().to_numpy(copy=True)
    suspect = np.flatnonzero(np.isnan(numbers) & ~blank)
    if suspect.size:
        texts = cells.iloc[suspect].astype(str).str.strip().to_numpy()
        blank[suspect[texts == ""]] = True
    return blank


def _as_text(cells: pd.Series) -> pd.Series:
    """Cell texts for matching and messages (NaN for missing), on a 0-based row index."""
    text = cells.reset_index(drop=True)
    if pd.api.types.is_string_dtype(text.dtype) and text.dtype != object:
        return text
    return text.map(lambda v: v if isinstance(v, str) or pd.isna(v) else str(v), na_action="ignore")


def _shown(cell: object) -> object:
    """A cell as its user wrote it — ``True``, not numpy's ``np.True_`` — and a long text cut:
    a message quoting a 100 kB cell whole would send it back whole."""
    cell = cell.item() if isinstance(cell, np.generic) else cell
    if isinstance(cell, str) and len(cell) > SHOWN_CHARS:
        return cell[: SHOWN_CHARS - 1] + "…"
    return cell


def _decimal_hint(cell: object) -> str:
    comma = isinstance(cell, str) and _DECIMAL_COMMA.match(cell)
    return " (use '.' as the decimal separator)" if comma else ""


# --- result -----------------------------------------------------------------------------------
def _frame(ns: np.ndarray, values: dict[str, np.ndarray | None]) -> pd.DataFrame:
    index = pd.DatetimeIndex(ns.view("datetime64[ns]"), name=TIME).tz_localize("UTC")
    kept = {name: v for name, v in values.items() if v is not None}
    return pd.DataFrame(kept, index=index, columns=list(kept), dtype=float)


# --- CSV reading ------------------------------------------------------------------------------
def _read_text_table(path_or_buffer: str | Path | IO[str]) -> pd.DataFrame:
    """All cells as text, header included as row 0 so that a name given twice stays visible."""
    try:
        table = pd.read_csv(
            path_or_buffer,
            header=None,
            dtype=str,
            keep_default_na=True,
            skip_blank_lines=False,
            skipinitialspace=True,
            encoding="utf-8-sig",
        )
    except pd.errors.EmptyDataError:
        raise DataValidationError([Problem(None, None, "the file is empty")]) from None
    except pd.errors.ParserError as exc:
        raise DataValidationError([Problem(None, None, f"not a readable CSV: {exc}")]) from None
    except UnicodeDecodeError as exc:
        raise DataValidationError([Problem(None, None, f"not UTF-8 text: {exc}")]) from None
    except OSError as exc:
        raise DataValidationError([Problem(None, None, f"cannot read the file: {exc}")]) from None
    if len(table) < 2:
        raise DataValidationError([Problem(None, None, "no data rows (only a header)")])
    return table


def _header_name(value: object) -> str:
    return "" if pd.isna(value) else str(value).strip().lstrip("\ufeff")


def _last_filled_row(raw: pd.DataFrame) -> int:
    filled = np.flatnonzero(raw.notna().any(axis=1).to_numpy())
    return int(filled[-1]) if filled.size else -1
