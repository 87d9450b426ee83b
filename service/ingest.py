"""Uploads of measurements: parse a body, validate it whole, store it in one transaction.

Validation is the engine's (:mod:`rcengine.io.timeseries`), so the service rejects exactly what
``rcengine`` rejects. One rule only the service can check: rows must lie on the time grid of the
rows already stored (same step, same phase), or the stored series would have mixed steps.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass

import numpy as np
import pandas as pd
from sqlalchemy.orm import Session

from rcengine.columns import MAX_STEP_S, MIN_STEP_S, T_IN, TIME
from rcengine.dataset import Dataset
from rcengine.exceptions import DataValidationError, Problem
from rcengine.io.timeseries import FIRST_DATA_LINE, format_times, parse_rows, read_timeseries

from . import bridge, repository
from .core.db import Database
from .models import BuildingRecord

_NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class Upload:
    """A validated upload: the engine's frame, and the file line of row 0 for CSV bodies."""

    frame: pd.DataFrame
    first_line: int | None = None


@dataclass(frozen=True)
class UploadResult:
    inserted: int
    updated: int
    rows: int
    first_time: pd.Timestamp
    last_time: pd.Timestamp
    data_revision: int


def from_json(body: bytes) -> Upload:
    """``{"rows": [{"time": ..., "t_in": ...}, ...]}``; problems name the index in ``rows``."""
    try:
        document = json.loads(body, parse_constant=_not_json)
    except (ValueError, UnicodeDecodeError) as exc:
        # JSONDecodeError, and integers longer than Python converts (4,300 digits).
        where = f" at line {exc.lineno} column {exc.colno}" if hasattr(exc, "lineno") else ""
        raise _not_valid(f"{where}: {_reason(exc)}") from None
    except RecursionError:
        raise _not_valid(": nested too deeply") from None
    if not isinstance(document, dict) or "rows" not in document:
        raise DataValidationError(
            [Problem(None, None, 'the JSON body must be an object {"rows": [...]}')]
        )
    rows = document["rows"]
    if isinstance(rows, list) and rows and isinstance(rows[0], dict) and T_IN not in rows[0]:
        # A forecast-only upload may leave t_in out (CONTRACT.md §1: empty in future rows); a
        # column exists when one row has its key.
        rows = [{**rows[0], T_IN: None}, *rows[1:]]
    return Upload(parse_rows(rows))


def _not_json(constant: str) -> float:
    """``NaN``, ``Infinity``: Python's JSON reader takes them, JSON has no such literals."""
    raise _not_valid(f": {constant} is not a JSON value; send null for an empty value")


def _not_valid(why: str) -> DataValidationError:
    return DataValidationError([Problem(None, None, f"the body is not valid JSON{why}")])


def from_csv(body: bytes) -> Upload:
    """CSV of CONTRACT.md §1; problems name the row and the line of the body."""
    try:
        text = body.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataValidationError([Problem(None, None, f"the CSV is not UTF-8: {exc}")]) from None
    header, newline, rows = text.partition("\n")
    names = {name.strip().strip('"') for name in header.rstrip("\r").split(",")}
    if TIME in names and T_IN not in names:
        # A forecast-only upload may leave t_in out (see from_json); short rows read as empty.
        text = f"{header.rstrip(chr(13))},{T_IN}{newline}{rows}"
    return Upload(read_timeseries(io.StringIO(text)), FIRST_DATA_LINE)


def store(db: Database, building_id: int, upload: Upload) -> UploadResult:
    """Upsert the rows by time in one transaction; nothing is written if a check fails."""
    frame = upload.frame
    _check_not_ahead(frame, upload.first_line)
    rows = bridge.frame_to_rows(frame)
    first, last = frame.index[0], frame.index[-1]
    with db.write() as session:
        building = repository.lock_building(session, building_id)
        step_s = _series_step_s(session, building, frame)
        _check_grid(building, frame, step_s, upload.first_line)
        existing = repository.existing_times(
            session, building_id, bridge.to_datetime(first), bridge.to_datetime(last)
        )
        updated = len(existing.intersection(r[TIME] for r in rows))
        repository.upsert_measurements(session, building_id, list(frame.columns), rows)
        _remember(building, frame, step_s)
        revision = repository.next_data_revision(session, building_id)
    return UploadResult(len(rows) - updated, updated, len(rows), first, last, revision)


@dataclass(frozen=True)
class RemovalResult:
    deleted: int
    last_measured_time: pd.Timestamp | None
    data_revision: int


def remove(db: Database, building_id: int, start: pd.Timestamp, end: pd.Timestamp) -> RemovalResult:
    """Delete the rows with start ≤ time < end in one transaction: the way to take back rows a
    device sent wrongly (a clock a year off), which an upload cannot (an empty value never
    erases a stored one). The last measured time is read again; a building left with no rows
    forgets its grid, so the next upload sets it anew."""
    if end <= start:
        raise DataValidationError([Problem(None, "end", "end must be after start")])
    with db.write() as session:
        building = repository.lock_building(session, building_id)
        deleted = repository.delete_measurements(
            session, building_id, bridge.to_datetime(start), bridge.to_datetime(end)
        )
        building.last_measured_at = repository.last_measured_time(session, building_id)
        if not repository.has_measurements(session, building_id):
            building.grid_origin = None
            building.step_s = None
        revision = repository.next_data_revision(session, building_id)
        last = building.last_measured_at
    return RemovalResult(deleted, None if last is None else pd.Timestamp(last), revision)


# How far a measured row may lie ahead of the server's clock: a device's clock may run minutes
# fast; a measurement an hour or more ahead comes from a wrong clock or a local time sent as UTC.
# Stored, such a row became the building's last measurement, every calibration then asked for
# data up to it, and no upload could take it back.
MAX_AHEAD = pd.Timedelta(hours=1)


def _check_not_ahead(frame: pd.DataFrame, first_line: int | None) -> None:
    """Measured t_in may not lie in the future; forecast rows (no t_in) may."""
    now = pd.Timestamp.now(tz="UTC")
    ahead = np.flatnonzero(frame[T_IN].notna().to_numpy() & (frame.index > now + MAX_AHEAD))
    if not ahead.size:
        return
    line = "" if first_line is None else " — line {} of the file"
    raise DataValidationError(
        [
            Problem(
                int(row),
                T_IN,
                f"t_in measured at {frame.index[row].isoformat()}, after the server's clock "
                f"({now:%Y-%m-%dT%H:%MZ}): check the device's clock and UTC offset; rows of the "
                "future carry the forecast inputs with t_in empty"
                + line.format(row + (first_line or 0)),
            )
            for row in ahead[:100]
        ]
    )


def _upload_step_s(frame: pd.DataFrame) -> float | None:
    return Dataset.from_frame(frame).step_s if len(frame) >= 2 else None


def _series_step_s(session: Session, building: BuildingRecord, frame: pd.DataFrame) -> float | None:
    """The step of the building's series: the one stored, else this upload's, else — a device
    that uploads one row at a time — the step of the rows stored before with this one (None
    while the building holds a single time). Without it a streamed series took any time, its
    steps mixed, and the building could never be calibrated (its step stayed unknown)."""
    if building.step_s is not None:
        return building.step_s
    step_s = _upload_step_s(frame)
    if step_s is not None or building.grid_origin is None:
        return step_s
    stored = pd.DatetimeIndex(repository.stored_times(session, building.id), tz="UTC")
    times = stored.append(frame.index.tz_convert("UTC")).unique().sort_values()
    # Only an interval the contract allows as a step can be one: two rows two days apart are a
    # gap (the step stayed 190,800 s, and every later row was off that grid).
    seconds = np.diff(times.as_unit("ns").asi8) / _NS_PER_S
    steps = seconds[(seconds >= MIN_STEP_S) & (seconds <= MAX_STEP_S)]
    return float(pd.Series(steps).mode().min()) if steps.size else None


def _check_grid(
    building: BuildingRecord, frame: pd.DataFrame, step_s: float | None, first_line: int | None
) -> None:
    """Every time must be the stored grid origin plus a whole number of the series' steps."""
    if building.grid_origin is None or step_s is None:
        return
    origin_ns = pd.Timestamp(building.grid_origin).as_unit("ns").value
    offsets = frame.index.as_unit("ns").asi8 - origin_ns
    off_grid = np.flatnonzero(offsets % round(step_s * _NS_PER_S) != 0)
    if not off_grid.size:
        return
    shown = off_grid[:100]
    grid, *times = format_times(
        pd.DatetimeIndex([building.grid_origin]).append(frame.index[shown]), building.timezone
    )
    line = "" if first_line is None else " — line {} of the file"
    raise DataValidationError(
        [
            Problem(
                int(row),
                TIME,
                f"time {time} is not on the {step_s:g}-s grid of the rows already stored "
                f"(e.g. {grid}); the step of a building's series cannot change (mixed steps)"
                + line.format(row + (first_line or 0)),
            )
            for row, time in zip(shown, times, strict=True)
        ]
    )


def _remember(building: BuildingRecord, frame: pd.DataFrame, step_s: float | None) -> None:
    """Grid of the series (first upload), its step and the latest measured time."""
    measured = frame.index[frame[T_IN].notna().to_numpy()]
    if len(measured):
        latest = bridge.to_datetime(measured[-1])
        if building.last_measured_at is None or latest > building.last_measured_at:
            building.last_measured_at = latest
    if building.grid_origin is None:
        building.grid_origin = bridge.to_datetime(frame.index[0])
    if building.step_s is None:
        building.step_s = step_s


def _reason(exc: Exception) -> str:
    return getattr(exc, "msg", None) or str(exc)
