"""What the committed reports of the test-bed sets found, by concealed effect and archetype.

    python benchmarks/census.py [--set SET ...]

Reads, for each set (default: every set with reports in ``docs/diagnosis/<set>/``), the reports a
judged or regenerated run committed there (each made by the code of the session that ran it, not
by the code now) beside the set's manifest. Per concealed effect and archetype: how many cases
were right (``diagnose_testbed.is_correct``; a pair counts for each of its two effects, right only
where both were found). Per archetype: the base model's test RMSE over its training RMSE, median
and range, on the nulls and on each effect concealed alone — how far a base model's forecast
drifts from its training fit over the season, which an effect the base model's own parameters
take in autumn may leave unchanged. Last line: JSON {"cases", "correct", "found": {effect:
{archetype: [right, cases]}}}.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `benchmarks` importable

from benchmarks.diagnose_testbed import NONE, Result, set_results  # noqa: E402
from scripts.energyplus.testbed import SETS  # noqa: E402

REPORTS = ROOT / "docs" / "diagnosis"


def committed(name: str) -> list[Result]:
    """Every case of set ``name`` from the reports committed under ``docs/diagnosis/<name>``."""
    return set_results(name, REPORTS / name)


def found_table(cases: list[Result]) -> dict[str, dict[str, list[int]]]:
    """{effect: {archetype: [right, cases]}}, the nulls under ``none``."""
    table: dict[str, dict[str, list[int]]] = defaultdict(lambda: defaultdict(lambda: [0, 0]))
    for r in cases:
        for effect in r.case["effects"] or [NONE]:
            cell = table[effect][r.case["archetype"]]
            cell[0] += r.correct
            cell[1] += 1
    return {e: dict(sorted(by.items())) for e, by in sorted(table.items())}


def drift_lines(cases: list[Result]) -> list[str]:
    """Per archetype and effect concealed alone (or none): the base model's test RMSE over its
    training RMSE, median (range, cases)."""
    ratios: dict[tuple[str, str], list[float]] = defaultdict(list)
    for r in cases:
        if len(r.case["effects"]) > 1:
            continue
        base = r.report["baseline"]
        ratios[r.case["archetype"], r.truth].append(base["rmse_test"] / base["rmse_train"])
    return [
        f"{archetype:10s} {effect:22s} test/train {statistics.median(v):4.1f} "
        f"({min(v):.1f}–{max(v):.1f}, {len(v)} cases)"
        for (archetype, effect), v in sorted(ratios.items())
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", action="append", choices=SETS, help="sets (default: all)")
    args = parser.parse_args()
    names = args.set or [name for name in SETS if (REPORTS / name).is_dir()]
    cases = [case for name in names for case in committed(name)]
    table = found_table(cases)
    for effect, by_archetype in table.items():
        cells = "  ".join(f"{a} {right}/{n}" for a, (right, n) in by_archetype.items())
        print(f"{effect:22s} {cells}")
    print()
    print("\n".join(drift_lines(cases)))
    print(
        json.dumps({"cases": len(cases), "correct": sum(r.correct for r in cases), "found": table})
    )


if __name__ == "__main__":
    main()
