"""How often one calibration lands in the better basin: the ``default`` preset's one search against
``thorough``'s three independent ones, over ten seeds each, in the same run.

Records: two test-bed fortnights (the first 14 days of two seasons, a nightly re-estimation's
window) and the measured Armadillo box. Per record and setting: the training RMSE of each seed,
the share of seeds within 1 % of the best RMSE any run found, and the wall time per fit.
JSON line last.

    python benchmarks/restarts.py [--seeds 10]
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
from rcengine.estimation.estimator import Estimator
from rcengine.estimation.presets import PRESETS
from rcengine.io.measured import read_armadillo
from rcengine.io.timeseries import read_timeseries
from rcengine.models import get_model
from rcengine.signals import prepare

ROOT = Path(__file__).resolve().parents[1]
TESTBED = ROOT / "data" / "testbed_sealed_12"
ARMADILLO = ROOT.parent / "shared" / "data" / "measured" / "armadillo_data_H2.csv"


def _records() -> list[tuple[str, Building, pd.DataFrame]]:
    out = []
    for name in ("open_plan-golden-null", "light-sanfrancisco-emitter_dynamics-drawn"):
        frame = read_timeseries(TESTBED / name / "data.csv")
        fortnight = frame[frame.index < frame.index[0] + np.timedelta64(14, "D")]
        out.append((name, Building.from_json(TESTBED / name / "building.json"), fortnight))
    if ARMADILLO.exists():
        building = Building.from_json(ROOT / "data" / "measured" / "armadillo.json")
        out.append(("armadillo", building, read_armadillo(ARMADILLO)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    settings = {"default": PRESETS["default"], "thorough": PRESETS["thorough"]}
    summary = {}
    for name, building, frame in _records():
        network = get_model("basic", building, frame.columns)
        data = prepare(frame, building, network.compile().input_names)
        runs = {}
        for label, preset in settings.items():
            started = time.perf_counter()
            rmse = [
                Estimator(network, preset=preset, random_state=s, warn_bounds=False).fit(data).rmse_
                for s in range(args.seeds)
            ]
            runs[label] = (np.array(rmse), (time.perf_counter() - started) / args.seeds)
        best = min(r.min() for r, _ in runs.values())
        print(f"{name} (best RMSE {best:.3f} K)")
        for label, (rmse, wall) in runs.items():
            share = float(np.mean(rmse <= 1.01 * best))
            print(
                f"  {label:10s} RMSE {np.round(rmse, 3).tolist()}  in the best basin "
                f"{share:.0%}, worst {rmse.max() / best - 1:+.0%}, {wall:.2f} s/fit"
            )
            summary.setdefault(name, {})[label] = {
                "share_best": share,
                "worst_excess": float(rmse.max() / best - 1),
                "s_per_fit": wall,
            }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
