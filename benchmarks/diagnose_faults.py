"""Mismatch diagnosis on records with the faults of real data (issue 11: does the answer survive?).

    python benchmarks/diagnose_faults.py [--jobs N] [--faults NAME ...] [--out DIR] [CASE ...]

Each test-bed case (``data/testbed/<case>``; default: the main bed's six nulls and eight of its
single-effect cases, one per effect the committed run finds first) is diagnosed with the model
its manifest names, as committed and with each fault laid on its record, all in the same run:

- ``sensor_0.1K``: the room sensor reads to 0.1 K, with 0.05 K of noise before rounding;
- ``sensor_0.5K``: a thermostat's display, 0.5 K steps;
- ``noise_0.2K``: 0.2 K of white noise on the room temperature;
- ``days_missing``: ten whole local days missing (a logger down), drawn at random;
- ``logger_1h_late``: the building's readings (``t_in``, ``q_hvac``, ``q_occ``, ``q_light``)
  stamped an hour late against the weather's;
- ``logger_standard_time``: the building's logger keeps standard time all year, so in summer
  time its readings are stamped an hour early;
- ``other_station``: weather from a station nearby, not at the building: outdoor temperature off
  by 0.4 K (correlated over four hours), irradiance by ±25 %, wind by ±20 % at 80 % of the
  exposure.

A null case's run is right when nothing is accepted; a single-effect case's when its first
accepted finding is the concealed effect. Each fault draws from its own seeded generator, the
same for every run. Printed: a table of each case's first finding per fault, then per fault the
nulls' false findings, the singles found and the runs the clock check re-aligned
(``diagnose.clock``); last line JSON {"cases", "faults", "null_runs", "null_false_findings",
"single_runs", "single_found", "clean_single_found", "realigned", "wall_s_per_diagnosis"}.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `benchmarks` importable

from benchmarks._cases import accepted_effects, diagnose_folder  # noqa: E402
from rcengine.building import Building  # noqa: E402
from rcengine.columns import DHI, DNI, GHI, T_IN, T_OUT, WIND_SPEED  # noqa: E402
from rcengine.diagnose import DiagnoseSettings  # noqa: E402
from rcengine.diagnose.clock import read_later, summer_time  # noqa: E402

BED = ROOT / "data" / "testbed"
CASES = (
    "heavy-chicago-null",
    "heavy-torino-null",
    "light-sterling-null",
    "light-torino-null",
    "open_plan-chicago-null",
    "open_plan-golden-null",
    "heavy-chicago-wind_infiltration-weak",
    "heavy-golden-unmetered_gains-strong",
    "heavy-torino-ventilation_schedule-strong",
    "light-chicago-sky_radiation-weak",
    "light-chicago-thermal_mass-strong",
    "light-golden-opaque_solar_gains-strong",
    "light-golden-window_solar_gains-strong",
    "light-torino-emitter_dynamics-weak",
)
CLEAN = "as_committed"
# Each case is diagnosed with the model its manifest names (``1r1c`` for the thermal-mass cases,
# whose concealed storage the Basic model's internal mass would already hold).
MODELS = {c["case"]: c["model"] for c in json.loads((BED / "manifest.json").read_text())}
Fault = Callable[[pd.DataFrame, Building, np.random.Generator], pd.DataFrame]


def _sensor(resolution_k: float, noise_k: float) -> Fault:
    def fault(frame: pd.DataFrame, _: Building, rng: np.random.Generator) -> pd.DataFrame:
        noisy = frame[T_IN] + rng.normal(0.0, noise_k, len(frame))
        read = np.round(noisy / resolution_k) * resolution_k if resolution_k else noisy
        return frame.assign(**{T_IN: read})

    return fault


def _days_missing(frame: pd.DataFrame, building: Building, rng: np.random.Generator):
    local = frame.index.tz_convert(building.location.timezone).normalize()
    days = local.unique()
    lost = days[rng.choice(len(days), 10, replace=False)]
    return frame[~local.isin(lost)]


def _logger_late(frame: pd.DataFrame, _: Building, __: np.random.Generator) -> pd.DataFrame:
    return read_later(frame, -1.0)


def _standard_time(frame: pd.DataFrame, building: Building, _: np.random.Generator):
    return read_later(frame, 1.0, summer_time(frame.index, building.location.timezone))


def _smooth(rng: np.random.Generator, n: int, std: float, rows: int) -> np.ndarray:
    """Noise of standard deviation ``std`` correlated over ``rows`` rows."""
    raw = pd.Series(rng.normal(0.0, std * np.sqrt(rows), n))
    return raw.rolling(rows, min_periods=1).mean().to_numpy()


def _other_station(frame: pd.DataFrame, _: Building, rng: np.random.Generator):
    n, out = len(frame), frame.copy()
    out[T_OUT] = frame[T_OUT] + _smooth(rng, n, 0.4, 8)
    cloudier = np.exp(_smooth(rng, n, 0.25, 4))
    for column in (GHI, DNI, DHI):
        if column in out:
            out[column] = frame[column] * cloudier
    if WIND_SPEED in out:
        out[WIND_SPEED] = 0.8 * frame[WIND_SPEED] * np.exp(_smooth(rng, n, 0.2, 4))
    return out


FAULTS: dict[str, Fault] = {
    "sensor_0.1K": _sensor(0.1, 0.05),
    "sensor_0.5K": _sensor(0.5, 0.0),
    "noise_0.2K": _sensor(0.0, 0.2),
    "days_missing": _days_missing,
    "logger_1h_late": _logger_late,
    "logger_standard_time": _standard_time,
    "other_station": _other_station,
}


def _run(job: tuple[str, str, Path | None]) -> tuple[str, str, list[str], float, float]:
    case, fault, out = job
    folder = BED / case
    alter = None
    if fault != CLEAN:
        seed = list(FAULTS).index(fault)

        def alter(frame: pd.DataFrame, building: Building) -> pd.DataFrame:
            return FAULTS[fault](frame, building, np.random.default_rng(seed))

    target = None
    if out is not None:
        target = out / fault
        target.mkdir(parents=True, exist_ok=True)
    report, wall = diagnose_folder(
        folder,
        MODELS[case],
        target,
        figures=False,
        settings=DiagnoseSettings(workers=1),
        alter=alter,
    )
    return case, fault, accepted_effects(report), (report["clock"] or {}).get("offset_h", 0.0), wall


def _concealed(case: str) -> str:
    effect = case.split("-")[2]
    return "" if effect == "null" else effect


def _table(results: dict[tuple[str, str], list[str]], cases: list[str], faults: list[str]) -> str:
    lines = ["| case | " + " | ".join(faults) + " |", "|---" * (len(faults) + 1) + "|"]
    for case in cases:
        cells = []
        for fault in faults:
            accepted = results[case, fault]
            right = accepted[:1] == [_concealed(case)] if _concealed(case) else not accepted
            cells.append(f"{'+'.join(accepted) or '–'}{'' if right else ' ✗'}")
        lines.append(f"| {case} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("cases", nargs="*", default=list(CASES))
    parser.add_argument("--faults", nargs="+", choices=list(FAULTS), default=list(FAULTS))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="write each report under DIR")
    args = parser.parse_args(argv)
    faults = [CLEAN, *args.faults]
    jobs = [(case, fault, args.out) for case in args.cases for fault in faults]
    started, results, realigned = time.perf_counter(), {}, {}
    with ProcessPoolExecutor(args.jobs) as pool:
        for k, (case, fault, accepted, offset_h, wall) in enumerate(pool.map(_run, jobs), 1):
            results[case, fault], realigned[case, fault] = accepted, offset_h
            clock = f" (re-aligned by {offset_h:+g} h)" if offset_h else ""
            print(
                f"[{k}/{len(jobs)}] {case} {fault}: {', '.join(accepted) or 'nothing'}{clock}, "
                f"{wall:.0f} s"
            )
    print(_table(results, args.cases, faults))
    nulls = [c for c in args.cases if not _concealed(c)]
    singles = [c for c in args.cases if _concealed(c)]

    def found(fault: str) -> int:
        return sum(results[c, fault][:1] == [_concealed(c)] for c in singles)

    for fault in faults:
        false = sum(len(results[c, fault]) for c in nulls)
        moved = sum(bool(realigned[c, fault]) for c in args.cases)
        print(
            f"{fault}: {false} false findings on {len(nulls)} nulls, {found(fault)} / "
            f"{len(singles)} single effects found first, {moved} re-aligned by the clock check"
        )
    summary = {
        "cases": len(args.cases),
        "faults": len(args.faults),
        "null_runs": len(nulls) * len(args.faults),
        "null_false_findings": sum(len(results[c, f]) for c in nulls for f in args.faults),
        "single_runs": len(singles) * len(args.faults),
        "single_found": sum(found(f) for f in args.faults),
        "clean_single_found": found(CLEAN),
        "realigned": {f: sum(bool(realigned[c, f]) for c in args.cases) for f in faults},
        "wall_s_per_diagnosis": round((time.perf_counter() - started) / len(jobs), 1),
    }
    print(json.dumps(summary))
    return summary


if __name__ == "__main__":
    main()
