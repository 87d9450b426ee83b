"""Mismatch diagnosis of the thesis office (EnergyPlus) and the two real measured buildings.

    python benchmarks/diagnose_real.py [--out docs/diagnosis]

No effect is concealed here, so there is no right answer to score: the script prints each
building's verdict and its strongest candidates (test RMSE after a refit), the figures of
docs/diagnosis.md's second table. The measured records are read from ``../shared/data/measured``.
Last line: JSON {building: {"baseline_rmse_test", "accepted", "wall_s"}}.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

import pandas as pd

from rcengine.building import Building
from rcengine.diagnose import diagnose
from rcengine.diagnose.html import save_figures
from rcengine.io.measured import read_armadillo, read_syslab
from rcengine.io.timeseries import read_timeseries

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "measured"
BUILDINGS: dict[str, tuple[Path, Callable[[], pd.DataFrame]]] = {
    "office": (
        ROOT / "data" / "energyplus" / "office" / "building.json",
        lambda: read_timeseries(ROOT / "data" / "energyplus" / "office" / "heating.csv"),
    ),
    "syslab": (
        ROOT / "data" / "measured" / "syslab.json",
        lambda: read_syslab(SHARED / "syslab_inputPRBS1.csv"),
    ),
    "armadillo": (
        ROOT / "data" / "measured" / "armadillo.json",
        lambda: read_armadillo(SHARED / "armadillo_data_H2.csv"),
    ),
}


def strongest(report: dict, n: int = 3) -> str:
    """The ``n`` refitted candidates with the lowest test RMSE, as 'effect RMSE (change against
    the model it extended)'."""
    refitted = [f for f in report["findings"] if f.get("rmse_test_after") is not None]
    refitted.sort(key=lambda f: f["rmse_test_after"])
    return ", ".join(
        f"{f['effect']} {f['rmse_test_after']:.3f} "
        f"({f['rmse_test_after'] / f['rmse_test_before'] - 1:+.0%})"
        for f in refitted[:n]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="folder for the JSON reports and figures")
    args = parser.parse_args()
    summary = {}
    for name, (building_json, load) in BUILDINGS.items():
        building, frame = Building.from_json(building_json), load()
        started = time.perf_counter()
        report = diagnose(frame, building, "basic")
        wall = time.perf_counter() - started
        d = json.loads(report.to_json())
        accepted = [f["effect"] for f in d["findings"] if f["accepted"]]
        print(
            f"{name}: baseline test RMSE {d['baseline']['rmse_test']:.3f} K; "
            f"accepted {accepted or 'nothing'}; strongest: {strongest(d)}",
            flush=True,
        )
        if args.out:
            args.out.mkdir(parents=True, exist_ok=True)
            (args.out / f"{name}.json").write_text(report.to_json() + "\n")
            save_figures(report, args.out, name)
        summary[name] = {
            "baseline_rmse_test": round(d["baseline"]["rmse_test"], 3),
            "accepted": accepted,
            "wall_s": round(wall, 1),
        }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
