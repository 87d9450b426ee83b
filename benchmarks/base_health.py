"""The base model's health over test-bed sets: which bounds its fits press on, which they rest on.

    python benchmarks/base_health.py [--set SET ...] [--jobs N] [CASE ...]

Each case's base model is fitted as the diagnosis fits it and checked (``diagnose/health.py``)
— the diagnosis stopped before its first round (``max_rounds=0``, only the ``thermal_mass``
repair step offered, no sun judged after). Per case: the verdict, every parameter on a bound with
the share of the training RMSE a refit past that bound gains (``baseline.health.bound_pressure``),
and whether the repair step was taken. A base model is *inadequate* where the data press on a
bound (or its envelope or test error says so), *resting* where it is healthy but rests a
parameter on a bound, *settled* on no bound. Last line: JSON {"cases", "inadequate", "resting",
"settled", "repaired", "bounds", "bounds_by_gain"}, the bounds counted by what a fit past them
gains (shares of the training RMSE).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `benchmarks` importable

from benchmarks._cases import diagnose_folder  # noqa: E402
from benchmarks.diagnose_testbed import read_set  # noqa: E402
from rcengine.diagnose import DiagnoseSettings  # noqa: E402
from scripts.energyplus.testbed import SETS  # noqa: E402

# Upper edges of the bins a bound's pressure is counted in (a share of the training RMSE).
GAIN_BINS = (0.005, 0.01, 0.02, 0.03, float("inf"))


# The diagnosis up to its base model and the repair step, nothing judged after; one worker
# process per case, the cases themselves run ``--jobs`` at a time.
BASE_ONLY = DiagnoseSettings(max_rounds=0, excess_sun=False, effects=("thermal_mass",), workers=1)


def state(health: dict) -> str:
    if health["verdict"] == "inadequate":
        return "inadequate"
    return "resting" if health["bound_pressure"] else "settled"


def repaired(report: dict) -> bool:
    """Was the repair step taken (and kept)?"""
    return any(f["baseline_repair"] and f["accepted"] for f in report["findings"])


def _one(job: tuple[str, Path, str]) -> tuple[str, dict]:
    key, folder, model = job
    report, _ = diagnose_folder(folder, model, settings=BASE_ONLY)
    return key, report


def case_line(key: str, report: dict) -> str:
    health = report["baseline"]["health"]
    repair = health.get("repair") or {}
    taken = repaired(report)
    bounds = " ".join(f"{p} {g:+.1%}" for p, g in health["bound_pressure"].items()) or "-"
    tried = f"repair {'taken' if taken else repair.get('verdict', 'not tried')}"
    return f"{key:70s} {state(health):10s} {tried:21s} {bounds}"


def summary(reports: list[dict]) -> dict:
    healths = [r["baseline"]["health"] for r in reports]
    states = Counter(state(h) for h in healths)
    gains = [g for h in healths for g in h["bound_pressure"].values()]
    low = 0.0
    by_gain = {}
    for high in GAIN_BINS:
        label = f"{low:.1%}–{high:.1%}" if high != float("inf") else f"≥ {low:.1%}"
        by_gain[label] = sum(low <= g < high for g in gains)
        low = high
    return {
        "cases": len(reports),
        "inadequate": states["inadequate"],
        "resting": states["resting"],
        "settled": states["settled"],
        "repaired": sum(repaired(r) for r in reports),
        "bounds": len(gains),
        "bounds_by_gain": by_gain,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", help="case names (default: all)")
    parser.add_argument(
        "--set", action="append", choices=SETS, help="test-bed sets (default: testbed)"
    )
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="cases at a time")
    args = parser.parse_args()
    jobs = []
    for name in args.set or ["testbed"]:
        folder, manifest, _ = read_set(name)
        jobs.extend(
            (f"{name}/{case['case']}", folder / case["case"], case["model"])
            for case in manifest
            if not args.cases or case["case"] in args.cases
        )
    reports = []
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for key, report in pool.map(_one, jobs):
            print(case_line(key, report), flush=True)
            reports.append(report)
    print(json.dumps(summary(reports), ensure_ascii=False))


if __name__ == "__main__":
    main()
