"""What a record must hold before anything can be learnt from it: an indoor temperature that
moves, and for a diagnosis measured days on both sides of its train/test boundary.

A stuck sensor reports a flat series; fitted to it, a model "explains" it with parameters on
their bounds, and a diagnosis finds every candidate idle, a clean bill of health. A record whose
measurements all fall on one side of the boundary leaves nothing to fit or nothing to test. The
service's promotion gate refuses a set fitted to a flat series; a diagnosis refuses the record.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.columns import T_IN
from rcengine.dataset import Dataset
from rcengine.exceptions import DataValidationError, Problem

# Standard deviation of the measured t_in below which the series is flat: a room sensor's
# accuracy. [K]
MIN_T_IN_STD_K = 0.1
# Measured t_in needed on each side of the train/test boundary. [days]
MIN_MEASURED_DAYS = 1.0


def t_in_spread(frame: pd.DataFrame) -> float:
    """Standard deviation of the measured indoor temperature, 0 without any. [K]"""
    t_in = frame[T_IN].to_numpy(dtype=float)
    return float(np.nanstd(t_in)) if np.isfinite(t_in).any() else 0.0


def check_diagnosable(frame: pd.DataFrame, boundary: pd.Timestamp) -> None:
    """Raise DataValidationError (column ``t_in``) when ``frame`` (contract frame, UTC index)
    cannot be diagnosed with the train/test ``boundary``: a flat t_in, or less than
    MIN_MEASURED_DAYS of measured t_in before or after the boundary."""
    t_in = frame[T_IN]
    problems = []
    spread = t_in_spread(frame)
    if spread < MIN_T_IN_STD_K:
        problems.append(
            Problem(
                None,
                T_IN,
                f"the measured indoor temperature varies by {spread:.3f} K (standard deviation) "
                f"over the record; a diagnosis needs at least {MIN_T_IN_STD_K:g} K — a flat "
                "series is a stuck sensor",
            )
        )
    step_s = Dataset.from_frame(frame).step_s
    for side, rows in (("training", t_in.index < boundary), ("test", t_in.index >= boundary)):
        days = float(t_in[rows].notna().sum()) * step_s / 86400.0
        if days < MIN_MEASURED_DAYS:
            problems.append(
                Problem(
                    None,
                    T_IN,
                    f"{days:.1f} day(s) of measured indoor temperature in the {side} period "
                    f"(the record is split at {boundary.isoformat()}); a diagnosis needs at "
                    f"least {MIN_MEASURED_DAYS:g} on each side",
                )
            )
    if problems:
        raise DataValidationError(problems)
