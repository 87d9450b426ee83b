"""What the diagnosis benchmarks share: diagnose one committed case folder and read its answer.

A case folder holds ``data.csv`` (CONTRACT.md §1) and ``building.json`` (§2), as
``data/energyplus/variants/<case>/`` and ``data/testbed/<case>/`` do.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

import pandas as pd

from rcengine.building import Building
from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.diagnose.html import save_figures
from rcengine.io.timeseries import read_timeseries


def accepted_effects(report: dict) -> list[str]:
    """The accepted findings in the report's order; the first is the tool's answer."""
    return [f["effect"] for f in report["findings"] if f["accepted"]]


def diagnose_folder(
    folder: Path,
    model: str,
    out: Path | None = None,
    figures: bool = True,
    settings: DiagnoseSettings | None = None,
    cloud_from: Path | None = None,
    alter: Callable[[pd.DataFrame, Building], pd.DataFrame] | None = None,
) -> tuple[dict, float]:
    """Diagnose the case in ``folder`` with ``model``: its report as JSON data and the wall time
    of the diagnosis [s]. With ``out``, ``<case>.json`` (and its figures) are written there;
    with ``cloud_from``, the weather file's cloud cover is added as the ``cloud_cover`` column;
    ``alter`` changes the record first (a fault of real data, ``diagnose_faults``)."""
    name = folder.name
    building = Building.from_json(folder / "building.json")
    frame = read_timeseries(folder / "data.csv")
    if cloud_from is not None:
        from benchmarks.sky_temperature import weather_cloud_cover

        frame = frame.assign(cloud_cover=weather_cloud_cover(cloud_from, frame.index))
    if alter is not None:
        frame = alter(frame, building)
    started = time.perf_counter()
    report = diagnose(frame, building, model, settings)
    wall = time.perf_counter() - started
    if out is not None:
        (out / f"{name}.json").write_text(report.to_json() + "\n")
        if figures:
            save_figures(report, out, name)
    return json.loads(report.to_json()), wall
