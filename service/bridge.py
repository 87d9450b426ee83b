"""The one bridge between stored rows and engine objects, for routers, jobs and CLI alike.

- measurement rows ↔ the engine's frame (UTC ``DatetimeIndex`` named ``time``, float columns of
  the contract, NaN for missing values);
- building rows → :class:`~rcengine.building.Building`;
- parameter-set rows ↔ :class:`~rcengine.parameter_set.ParameterSet` (the stored document is exactly
  the ``params.json`` that ``rcengine predict`` reads).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from datetime import datetime
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy import Row
from sqlalchemy.orm import Session

from rcengine.building import Building
from rcengine.columns import COLUMNS, NUMERIC_COLUMNS, TIME
from rcengine.io.jsonable import jsonable
from rcengine.parameter_set import ParameterSet

from . import repository
from .models import ParameterSetRecord


# --- times ------------------------------------------------------------------------------------
def to_datetime(stamp: pd.Timestamp) -> datetime:
    return stamp.tz_convert("UTC").to_pydatetime()


# --- measurements -----------------------------------------------------------------------------
def frame_to_rows(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """Rows for the upsert: ``time`` as a UTC datetime, values as floats or None."""
    values = frame.to_numpy(dtype=float)
    cells = values.astype(object)
    cells[np.isnan(values)] = None
    keys = (TIME, *frame.columns)
    times = frame.index.tz_convert("UTC").to_pydatetime()
    return [
        dict(zip(keys, (t, *row), strict=True))
        for t, row in zip(times, cells.tolist(), strict=True)
    ]


def rows_to_frame(rows: Sequence[Row], columns: Sequence[str]) -> pd.DataFrame:
    """The engine's frame from ``(time, *columns)`` rows; an optional column with no value in
    any row is left out (absent physics, as the validator treats it)."""
    index = pd.DatetimeIndex([r[0] for r in rows], name=TIME, tz="UTC")
    values = np.array([r[1:] for r in rows], dtype=float).reshape(len(rows), len(columns))
    frame = pd.DataFrame(values, index=index, columns=list(columns))
    empty = [c for c in columns if not COLUMNS[c].required and not frame[c].notna().any()]
    return frame.drop(columns=empty)


def load_frame(
    session: Session,
    building_id: int,
    start: pd.Timestamp | None = None,
    end: pd.Timestamp | None = None,
) -> pd.DataFrame:
    """Stored rows of a building with start ≤ time < end as the engine's frame."""
    rows = repository.read_measurements(
        session,
        building_id,
        NUMERIC_COLUMNS,
        None if start is None else to_datetime(start),
        None if end is None else to_datetime(end),
    )
    return rows_to_frame(rows, NUMERIC_COLUMNS)


def whole_columns(frame: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """``frame`` without the optional columns that some of its rows lack, and a note for each.

    Uploads may carry an optional column (q_occ, dni, wind_speed, ...) on some days and not on
    others, and an upload cannot erase a value once stored. A model fed such a column meets
    missing inputs; without it, the window is fitted on what every row has (the note says
    so). Required columns stay: a row without them is refused at upload."""
    missing = frame.isna()
    partial = [
        c for c in frame.columns if c in COLUMNS and not COLUMNS[c].required and missing[c].any()
    ]
    notes = [
        f"column '{c}' left out: missing in {int(missing[c].sum())} of {len(frame)} rows "
        f"of the window ({missing.index[missing[c]][0].isoformat()} first)"
        for c in partial
    ]
    return frame.drop(columns=partial), notes


# --- buildings and parameter sets -------------------------------------------------------------
def building_of(description: dict[str, Any]) -> Building:
    return Building.from_dict(description)


def parameter_set_of(record: ParameterSetRecord) -> ParameterSet:
    return ParameterSet.from_dict(record.document)


def parameter_set_record(
    pset: ParameterSet, building_id: int, job_id: int | None, reason: str | None
) -> ParameterSetRecord:
    """A row holding ``pset`` (status and ``is_current`` are set when it is stored)."""
    # Strict JSON as ParameterSet.save writes it: non-finite floats (e.g. the standard error of
    # a non-identifiable parameter of a likelihood fit) become null; PostgreSQL refuses NaN.
    document = json.loads(json.dumps(jsonable(pset.to_dict()), allow_nan=False))
    holdout = pset.metrics.get("holdout") or {}
    return ParameterSetRecord(
        building_id=building_id,
        job_id=job_id,
        model=pset.model,
        reason=reason,
        train_start=to_datetime(pd.Timestamp(pset.fit["start"])),
        train_end=to_datetime(pd.Timestamp(pset.fit["end"])),
        rmse_train=pset.metrics["train"]["rmse"],
        rmse_holdout=holdout.get("rmse"),
        metrics=document["metrics"],
        engine_version=pset.engine_version,
        document=document,
    )
