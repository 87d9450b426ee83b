"""Mismatch diagnosis over the project's concealed-effect EnergyPlus variants.

    python benchmarks/diagnose_speed.py [--out docs/diagnosis] [CASE ...]

Each variant (data/energyplus/variants/, made by scripts/make_energyplus_data.py) hides exactly
one effect of the vocabulary — never as a column — or none ("plain"). A case is correct when the
first accepted finding is the hidden effect and the final model's test RMSE is at most 0.7 × the
baseline's, or, for "plain", when nothing is accepted. The table also gives the base and final
models' day-ahead forecast RMSE over the test half (the report's ``day_ahead``). With ``--out``
the JSON reports, their figures (PNG) and a markdown table are written there (``rcengine
diagnose --html`` gives the full HTML report of one case). Last line: JSON {"cases",
"wall_s_per_case", "correct"}.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `benchmarks` importable

from benchmarks._cases import accepted_effects, diagnose_folder  # noqa: E402

VARIANTS = ROOT / "data" / "energyplus" / "variants"
MAX_RATIO = 0.7


def is_correct(effect: str | None, report: dict) -> bool:
    accepted = accepted_effects(report)
    if effect is None:
        return not accepted
    ratio = report["final"]["rmse_test"] / report["baseline"]["rmse_test"]
    return bool(accepted) and accepted[0] == effect and ratio <= MAX_RATIO


def table_row(case: dict, report: dict, wall: float, correct: bool) -> str:
    accepted = accepted_effects(report)
    base, final = report["baseline"]["rmse_test"], report["final"]["rmse_test"]
    ahead = report["day_ahead"]
    return (
        f"| {case['case']} | {case['effect'] or '—'} | {accepted[0] if accepted else 'none'} | "
        f"{', '.join(accepted[1:]) or '—'} | {base:.3f} | {final:.3f} | {final / base:.2f} | "
        f"{ahead['rmse_baseline']:.3f} | {ahead['rmse_final']:.3f} | "
        f"{wall:.0f} | {'yes' if correct else 'NO'} |"
    )


def case_section(case: dict, report: dict) -> str:
    """Markdown for one case: what was hidden, what the tool said, its figures."""
    name = case["case"]
    lines = [
        f"### {name}",
        "",
        f"*Hidden:* {case['description']} *Model:* `{case['model']}`.",
        "",
        f"*Where/when (test period):* {report['mismatch']['summary']}.",
        "",
        f"*Verdict:* {report['verdict']}.",
        "",
    ]
    lines += [f"- **{f['effect']}** — {f['explanation']}" for f in report["findings"][:3]]
    lines += ["", f"![{name}: measured vs predicted]({name}_timeseries.png)"]
    lines += [f"![{name}: residual by hour and weekday]({name}_heatmaps.png)", ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", help="variant names (default: all)")
    parser.add_argument("--out", type=Path, help="folder for the reports and table")
    args = parser.parse_args()
    manifest = json.loads((VARIANTS / "manifest.json").read_text())
    cases = [c for c in manifest if not args.cases or c["case"] in args.cases]
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
    rows = [
        "| case | concealed effect | first finding | further findings | test RMSE before [K] "
        "| after [K] | ratio | day-ahead before [K] | after [K] | wall [s] | correct |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    walls, correct, sections = [], 0, []
    for case in cases:
        report, wall = diagnose_folder(VARIANTS / case["case"], case["model"], args.out)
        sections.append(case_section(case, report))
        ok = is_correct(case["effect"], report)
        walls.append(wall)
        correct += ok
        rows.append(table_row(case, report, wall, ok))
        print(rows[-1], flush=True)
    if args.out:
        (args.out / "table.md").write_text("\n".join(rows) + "\n")
        (args.out / "cases.md").write_text("\n".join(sections))
    print(
        json.dumps(
            {
                "cases": len(cases),
                "wall_s_per_case": round(sum(walls) / max(len(walls), 1), 1),
                "correct": correct,
            }
        )
    )


if __name__ == "__main__":
    main()
