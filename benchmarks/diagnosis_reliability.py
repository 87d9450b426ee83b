"""How far to trust a finding: over test-bed runs already made, how often each effect is found
when it is concealed, and how often each first finding names what is concealed.

    python benchmarks/diagnosis_reliability.py SET=DIR [SET=DIR ...] [--out FILE]

Each ``SET=DIR`` names a test-bed set (``data/SET``: its manifest says what each case conceals)
and a folder holding the reports a run of ``benchmarks/diagnose_testbed.py --set SET --out DIR``
wrote for every case of it. Two tables (markdown, printed and written to ``--out``):

- per concealed effect, over the cases hiding it alone: found first, something else named
  first, nothing accepted (the recall a user can expect where that effect is at work);
- per first finding, over every case in which it was named first: how often it is one of the
  concealed effects (the precision of a report naming it).

Null cases and pairs get a line each. Last line: JSON {"cases", "single_effect_found",
"single_effect_cases", "null_false", "null_cases", "pairs_both_found", "pairs"}. The figures say
nothing of held-out-ness: report which of the sets the diagnosis was tuned on beside them.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `benchmarks` importable

from benchmarks.diagnose_testbed import (  # noqa: E402
    NONE,
    Result,
    set_results,
)
from scripts.energyplus.testbed import SETS  # noqa: E402


def recall_table(results: Sequence[Result]) -> str:
    """Markdown: per effect concealed alone, cases and what was named first."""
    lines = [
        "| concealed alone | cases | found first | other named first | nothing accepted |",
        "|---|---|---|---|---|",
    ]
    singles = [r for r in results if len(r.case["effects"]) == 1]
    for effect in sorted({r.truth for r in singles}):
        cases = [r for r in singles if r.truth == effect]
        found = sum(r.first == effect for r in cases)
        nothing = sum(r.first == NONE for r in cases)
        other = len(cases) - found - nothing
        lines.append(f"| {effect} | {len(cases)} | {found} | {other} | {nothing} |")
    return "\n".join(lines) + "\n"


def precision_table(results: Sequence[Result]) -> str:
    """Markdown: per first finding, the cases naming it first and those where it is concealed."""
    lines = ["| named first | cases | concealed there |", "|---|---|---|"]
    named = [r for r in results if r.first != NONE]
    for effect in sorted({r.first for r in named}):
        cases = [r for r in named if r.first == effect]
        right = sum(effect in r.case["effects"] for r in cases)
        lines.append(f"| {effect} | {len(cases)} | {right} |")
    return "\n".join(lines) + "\n"


def figures(results: Sequence[Result]) -> dict:
    """The last line's counts."""
    singles = [r for r in results if len(r.case["effects"]) == 1]
    nulls = [r for r in results if not r.case["effects"]]
    pairs = [r for r in results if len(r.case["effects"]) == 2]
    return {
        "cases": len(results),
        "single_effect_found": sum(r.first == r.truth for r in singles),
        "single_effect_cases": len(singles),
        "null_false": sum(bool(r.accepted) for r in nulls),
        "null_cases": len(nulls),
        "pairs_both_found": sum(set(r.case["effects"]) <= set(r.accepted) for r in pairs),
        "pairs": len(pairs),
    }


def report(results: Sequence[Result]) -> str:
    """Both tables and the null and pair lines, as markdown."""
    f = figures(results)
    return (
        recall_table(results)
        + "\n"
        + precision_table(results)
        + f"\nNull cases with a finding: {f['null_false']} of {f['null_cases']}. "
        + f"Pairs with both effects found: {f['pairs_both_found']} of {f['pairs']}.\n"
    )


def results_of(source: str) -> list[Result]:
    """Every case's result of one ``SET=DIR`` source."""
    name, sep, folder = source.partition("=")
    if not sep or name not in SETS:
        raise SystemExit(f"expected SET=DIR with SET one of {', '.join(SETS)}, got {source!r}")
    return set_results(name, Path(folder))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sources", nargs="+", help="SET=DIR: a set and the folder of its reports")
    parser.add_argument("--out", type=Path, help="markdown file for the tables")
    args = parser.parse_args()
    results = [r for source in args.sources for r in results_of(source)]
    text = report(results)
    if args.out:
        args.out.write_text(text)
    print(text)
    print(json.dumps(figures(results)))


if __name__ == "__main__":
    main()
