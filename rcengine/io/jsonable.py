"""JSON in and out: the one numpy/pandas-to-JSON hook, ``json.dumps(obj, default=jsonable)``,
and ``read_json``, which turns a file that does not parse into the caller's one-line error."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pandas as pd


def jsonable(value: object) -> object:
    """A JSON-native copy of ``value``: dicts (keys as text) and lists/tuples item by item,
    numpy arrays and scalars as Python lists and numbers, timestamps as ISO 8601; non-finite
    floats become ``None`` so the output is strict JSON.

    ``json.dumps(jsonable(obj))`` nulls every NaN; as ``json.dumps(obj, default=jsonable)`` it
    converts what ``json`` cannot, but ``json`` never hands it a Python float, whose NaN it writes.

    Raises
    ------
    TypeError : for anything else, as ``json.dumps`` expects of a ``default`` hook.
    """
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, float):
        return float(value) if math.isfinite(value) else None
    if value is None or isinstance(value, str | int):
        return value
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    if hasattr(value, "tolist"):
        return jsonable(value.tolist())
    if hasattr(value, "item"):
        return jsonable(value.item())
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def read_json(path: str | Path, error: type[Exception]) -> Any:
    """The JSON document in the file at ``path``.

    Raises
    ------
    error : ``"<path>: not valid JSON (<where>)"`` when it does not parse.
    """
    try:
        return json.loads(Path(path).read_text())
    except json.JSONDecodeError as exc:
        raise error(f"{path}: not valid JSON ({exc})") from exc
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not a JSON text file (not UTF-8: {exc.reason})") from exc
    except OSError as exc:
        raise error(f"{path}: cannot read the file ({exc.strerror or exc})") from exc
