"""A sensor that drops readings: one season's fit restarted at every gap against bridged.

Data: committed test-bed seasons (six months at 30 min, EnergyPlus). Each is fitted (`basic`,
the default GA + GPS + polish) three times in the same run: on the whole record (the reference),
and with a share of its rows dropped at random (``--drop``, default 3 %), once cut into a segment
at every gap (each with its own estimated initial states, as before ``bridge_short_gaps``) and
once with the short gaps bridged. Printed per case: segments, wall time, training RMSE and the
largest relative parameter change against the reference fit. JSON line last.

    python benchmarks/dropouts.py [--drop 0.03] [CASE_DIR ...]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.dataset import bridge_short_gaps
from rcengine.estimation.estimator import Estimator
from rcengine.io.timeseries import read_timeseries
from rcengine.models import get_model
from rcengine.network import RCNetwork
from rcengine.signals import prepare

ROOT = Path(__file__).resolve().parents[1]
CASES = [
    ROOT / "data" / "testbed_sealed_12" / name
    for name in (
        "open_plan-golden-null",
        "light-chicago-window_solar_gains-drawn",
        "heavy-sterling-wind_infiltration-drawn",
    )
]


def _fit(frame: pd.DataFrame, building: Building, network: RCNetwork) -> dict:
    data = prepare(frame, building, network.compile().input_names)
    started = time.perf_counter()
    est = Estimator(network, random_state=0, warn_bounds=False).fit(data)
    return {
        "segments": len(data.segments),
        "wall_s": time.perf_counter() - started,
        "rmse_train": est.rmse_,
        "params": est.params_,
    }


def _drift(fit: dict, reference: dict) -> float:
    """Largest relative parameter change against the reference fit."""
    ref = reference["params"]
    return max(abs(fit["params"][k] - v) / max(abs(v), 1e-12) for k, v in ref.items())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", type=Path, default=CASES)
    parser.add_argument("--drop", type=float, default=0.03, help="share of rows dropped")
    args = parser.parse_args()
    rows = []
    for case in args.cases:
        building = Building.from_json(case / "building.json")
        whole = read_timeseries(case / "data.csv")
        dropped = whole[np.random.default_rng(0).random(len(whole)) > args.drop]
        network = get_model("basic", building, whole.columns)
        fits = {
            "whole": _fit(whole, building, network),
            "restarted": _fit(dropped, building, network),
            "bridged": _fit(bridge_short_gaps(dropped), building, network),
        }
        print(case.name)
        for how, fit in fits.items():
            drift = _drift(fit, fits["whole"])
            print(
                f"  {how:9s} {fit['segments']:4d} segment(s) {fit['wall_s']:6.1f} s  "
                f"RMSE {fit['rmse_train']:.3f} K  largest parameter change {drift:.1%}"
            )
        rows.append(
            {how: {k: v for k, v in fit.items() if k != "params"} for how, fit in fits.items()}
        )
        rows[-1]["drift"] = {how: _drift(fit, fits["whole"]) for how, fit in fits.items()}

    def mean(how: str, key: str) -> float:
        return float(np.mean([r[how][key] for r in rows]))

    print(
        json.dumps(
            {
                "cases": len(rows),
                "drop": args.drop,
                "wall_s_restarted": mean("restarted", "wall_s"),
                "wall_s_bridged": mean("bridged", "wall_s"),
                "speedup": mean("restarted", "wall_s") / mean("bridged", "wall_s"),
                "rmse_whole": mean("whole", "rmse_train"),
                "rmse_restarted": mean("restarted", "rmse_train"),
                "rmse_bridged": mean("bridged", "rmse_train"),
                "max_drift_restarted": max(r["drift"]["restarted"] for r in rows),
                "max_drift_bridged": max(r["drift"]["bridged"] for r in rows),
            }
        )
    )


if __name__ == "__main__":
    main()
