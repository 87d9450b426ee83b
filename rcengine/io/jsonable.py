"""The one numpy/pandas-to-JSON hook: ``json.dumps(obj, default=jsonable)``."""

from __future__ import annotations

import math

import pandas as pd


def jsonable(value: object) -> object:
    """A JSON-native equivalent of ``value`` (numpy arrays and scalars, timestamps); non-finite
    floats become ``None`` so the output is strict JSON.

    Raises
    ------
    TypeError : for anything else, as ``json.dumps`` expects of a ``default`` hook.
    """
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    if hasattr(value, "tolist"):
        return _finite(value.tolist())
    if hasattr(value, "item"):
        return _finite(value.item())
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _finite(value: object) -> object:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value
