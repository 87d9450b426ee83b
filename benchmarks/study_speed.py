"""Speed of the full thesis study (issue 3): both models, both periods, learning 1/3/5/7 days,
horizons 1/3/7 days, every day of the EnergyPlus office's heating season, plus the free-floating
validation and every table and figure — exactly what ``rcengine study`` does.

Prints the load average before and after (the cores may be shared: a load above the core count
inflates wall times, not CPU times), the run's CPU time and the wall time it means on idle cores,
the CPU time per estimation, the key accuracy figures, and
as its last line JSON {"wall_s", "estimations", "s_per_estimation"}: wall_s is the whole run,
s_per_estimation the mean wall time of one estimation inside a worker (thesis Table 3.1 measures
the same, 130–880 s).

    python benchmarks/study_speed.py [--output out/study] [--workers N] [--preset study]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from pathlib import Path

from rcengine.building import Building
from rcengine.io.timeseries import read_timeseries
from rcengine.study.report import write_study
from rcengine.study.run import StudySettings, progress_bar, run_study

ROOT = Path(__file__).resolve().parents[1]
OFFICE = ROOT / "data" / "energyplus" / "office"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=ROOT / "out" / "study")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--preset", default="study")
    args = parser.parse_args()

    load_before = os.getloadavg()
    started = time.perf_counter()
    building = Building.from_json(OFFICE / "building.json")
    heating = read_timeseries(OFFICE / "heating.csv")
    free = read_timeseries(OFFICE / "freefloat.csv")
    settings = StudySettings(preset=args.preset, workers=args.workers)
    with progress_bar() as progress:
        results = run_study(heating, building, settings, progress)
    study_s = time.perf_counter() - started
    write_study(results, settings, heating, building, free, args.output)
    wall = time.perf_counter() - started
    load_after = os.getloadavg()
    cpu = sum(
        r.ru_utime + r.ru_stime
        for r in (
            resource.getrusage(who) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)
        )
    )

    info = json.loads((args.output / "summary.json").read_text())
    print(f"cores {os.cpu_count()}, workers {args.workers}, preset {args.preset}")
    print(f"load average (1, 5, 15 min) before {load_before}, after {load_after}")
    print(f"learn/predict {study_s:.1f} s, tables + figures + free-floating {wall - study_s:.1f} s")
    print(
        f"CPU time of the run (main process + workers) {cpu:.0f} s: about "
        f"{cpu / args.workers:.0f} s of wall time on {args.workers} otherwise idle core(s)"
    )
    print(
        f"per estimation: wall {results.wall_s.mean():.3f} s, CPU {results.cpu_s.mean():.3f} s; "
        f"throughput {wall / len(results):.3f} s of run per estimation"
    )
    for key, h in sorted(info["headline"].items()):
        print(
            f"{key:<16} ≥ 3 learning days: 1-day {h['rmse_1d_learn_ge_3d']:.3f} °C, "
            f"7-day {h['rmse_7d_learn_ge_3d']:.3f} °C; persistence "
            f"{h['persistence_1d']:.3f} / {h['persistence_7d']:.3f} °C"
        )
    for model in settings.models:
        m = info["free_floating"][model]["metrics"]
        print(
            f"free-floating {model:<6} RMSE {m['rmse']:.3f} °C, MBE {m['mbe']:+.3f} °C, "
            f"NMBE {m['nmbe']:+.1f} %, CV(RMSE) {m['cv_rmse']:.1f} %, "
            f"ASHRAE 14 {'pass' if m['ashrae14_pass'] else 'fail'}"
        )
    print(
        json.dumps(
            {
                "wall_s": round(wall, 1),
                "estimations": len(results),
                "s_per_estimation": round(float(results.wall_s.mean()), 4),
            }
        )
    )


if __name__ == "__main__":
    main()
