"""Mismatch diagnosis over the test bed of buildings it was never tuned on (issue 11).

    python benchmarks/diagnose_testbed.py [--set testbed|testbed_fresh|testbed_sealed|...]
        [--half tuning|heldout] [--jobs N] [--out DIR] [--cloud-from-weather] [CASE ...]

The cases of ``data/testbed/`` (made by ``scripts/make_testbed.py``; ``manifest.json`` says what
each conceals, ``split.json`` which half it belongs to) — or of a further set,
``data/testbed_fresh/`` or one of the sealed sets (``data/testbed_sealed*/``), each held out
whole — are diagnosed ``--jobs`` at a time (default: every core, one worker process each) with
the model the manifest names. A case is correct when the first accepted finding is its concealed
effect; with two concealed effects, when both are accepted and the first accepted is one of them;
with none, when nothing is accepted (each accepted finding on a null case is a false finding).
Only the held-out half counts. ``--out`` writes each JSON report, ``confusion.md`` (true effect ×
first finding), ``tables.md`` (results per archetype and per climate) and ``separation.md`` (every
candidate's first-round test gain, the concealed ones marked: how far the true effect stands from
what the other candidates gain on the same case); ``--tables-only --out DIR`` writes the tables
again from the reports already in DIR, diagnosing nothing. ``--cloud-from-weather`` adds each
case's weather-file cloud cover as the optional ``cloud_cover`` column, as data from a weather
service with cloud cover would have it (the committed CSVs have none). Last line: JSON {"cases",
"heldout_cases", "heldout_correct", "tuning_correct", "null_false_findings",
"two_effect_both_found", "wall_s_per_case"}.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `benchmarks` importable

from benchmarks._cases import accepted_effects, diagnose_folder  # noqa: E402
from rcengine.diagnose import DiagnoseSettings  # noqa: E402
from scripts.energyplus.testbed import CLIMATES, SETS  # noqa: E402

HALVES = ("tuning", "heldout")
NONE = "none"


@dataclass(frozen=True)
class Result:
    """One diagnosed case: its manifest entry, its half, the report and the wall time [s]."""

    case: dict
    half: str
    report: dict
    wall_s: float

    @property
    def accepted(self) -> list[str]:
        return accepted_effects(self.report)

    @property
    def first(self) -> str:
        return self.accepted[0] if self.accepted else NONE

    @property
    def truth(self) -> str:
        return " + ".join(self.case["effects"]) or NONE

    @property
    def correct(self) -> bool:
        return is_correct(self.case["effects"], self.report)


def is_correct(effects: Sequence[str], report: dict) -> bool:
    """The first accepted finding is the concealed effect (one of the two, both accepted);
    nothing accepted where nothing is concealed."""
    accepted = accepted_effects(report)
    if not effects:
        return not accepted
    return bool(accepted) and accepted[0] in effects and set(effects) <= set(accepted)


def false_findings(effects: Sequence[str], report: dict) -> int:
    """Accepted findings on a null case (0 where something is concealed)."""
    return 0 if effects else len(accepted_effects(report))


def summary(results: Sequence[Result], elapsed_s: float) -> dict:
    """The benchmark's last line; ``elapsed_s``: wall time of all the diagnoses together."""
    heldout = [r for r in results if r.half == "heldout"]
    return {
        "cases": len(results),
        "heldout_cases": len(heldout),
        "heldout_correct": sum(r.correct for r in heldout),
        "tuning_correct": sum(r.correct for r in results if r.half == "tuning"),
        "null_false_findings": sum(false_findings(r.case["effects"], r.report) for r in results),
        "two_effect_both_found": sum(
            set(r.case["effects"]) <= set(r.accepted)
            for r in results
            if len(r.case["effects"]) == 2
        ),
        "wall_s_per_case": round(elapsed_s / max(len(results), 1), 1),
    }


def confusion_matrix(results: Iterable[Result]) -> str:
    """Markdown table: true effect (rows) × first accepted finding (columns), case counts."""
    results = list(results)
    rows = sorted({r.truth for r in results}, key=lambda t: (t != NONE, t))
    columns = sorted({r.first for r in results}, key=lambda t: (t != NONE, t))
    lines = [
        "| concealed \\ first finding | " + " | ".join(columns) + " |",
        "|---" * (len(columns) + 1) + "|",
    ]
    for truth in rows:
        counts = [sum(r.truth == truth and r.first == c for r in results) for c in columns]
        lines.append(f"| {truth} | " + " | ".join(str(n) if n else "·" for n in counts) + " |")
    return "\n".join(lines) + "\n"


def grouped_table(results: Iterable[Result], key: str) -> str:
    """Markdown table of correct cases per ``key`` (``archetype`` or ``climate``), by half."""
    results = list(results)
    lines = [f"| {key} | held-out correct | tuning correct | all |", "|---|---|---|---|"]
    for value in sorted({r.case[key] for r in results}):
        group = [r for r in results if r.case[key] == value]
        cells = []
        for half in (*HALVES[::-1], None):
            part = [r for r in group if half is None or r.half == half]
            cells.append(f"{sum(r.correct for r in part)}/{len(part)}")
        lines.append(f"| {value} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def first_round_gains(report: dict) -> dict[str, tuple[float, str]]:
    """Per candidate refitted in the first round: the relative change of the single split's test
    RMSE [-] and its mark ("accepted", "implausible" or ""). A round that accepted a finding keeps
    only that one's: the report holds each other candidate's latest verdict, of a later round."""
    gains = {}
    for f in report["findings"]:
        if f["round"] != 1 or f.get("rmse_test_after") is None or f.get("baseline_repair"):
            continue
        implausible = "implausible" in f["reason"]
        mark = "accepted" if f["accepted"] else "implausible" if implausible else ""
        gains[f["effect"]] = (f["rmse_test_after"] / f["rmse_test_before"] - 1.0, mark)
    return gains


def separation_table(results: Iterable[Result]) -> str:
    """Markdown: per case, every first-round candidate's test gain (bold: a concealed effect; ✓
    accepted, ✗ implausible), then the largest plausible gain a candidate took on a null case."""
    results = list(results)
    gains_of = [first_round_gains(r.report) for r in results]
    effects = sorted({e for gains in gains_of for e in gains})
    lines = [
        "| case | half | correct | " + " | ".join(effects) + " |",
        "|---" * (len(effects) + 3) + "|",
    ]
    spurious = []
    for r, gains in zip(results, gains_of, strict=True):
        cells = []
        for effect in effects:
            if effect not in gains:
                cells.append("·")
                continue
            gain, mark = gains[effect]
            text = f"{gain:+.0%}" + {"accepted": " ✓", "implausible": " ✗"}.get(mark, "")
            cells.append(f"**{text}**" if effect in r.case["effects"] else text)
            if not r.case["effects"] and mark != "implausible":
                spurious.append((gain, r.case["case"], effect))
        verdict = "yes" if r.correct else "NO"
        lines.append(f"| {r.case['case']} | {r.half} | {verdict} | " + " | ".join(cells) + " |")
    table = "\n".join(lines) + "\n"
    if spurious:
        gain, case, effect = min(spurious)
        table += f"\nLargest plausible gain on a null case: {gain:+.0%} ({effect}, {case}).\n"
    return table


def write_tables(out: Path, results: Sequence[Result]) -> None:
    """``confusion.md`` (held-out half, then all cases), ``tables.md`` and ``separation.md`` in
    ``out``."""
    heldout = [r for r in results if r.half == "heldout"]
    confusion = "## Held-out half\n\n" + confusion_matrix(heldout)
    confusion += "\n## All cases\n\n" + confusion_matrix(results)
    (out / "confusion.md").write_text(confusion)
    tables = grouped_table(results, "archetype") + "\n" + grouped_table(results, "climate")
    (out / "tables.md").write_text(tables)
    (out / "separation.md").write_text(separation_table(results))


def stored_results(out: Path, chosen: Sequence[tuple[dict, str]]) -> list[Result]:
    """The chosen cases' results from the reports a run wrote to ``out`` (wall time unknown: 0)."""
    missing = [e["case"] for e, _ in chosen if not (out / f"{e['case']}.json").exists()]
    if missing:
        raise SystemExit(f"no report in {out} for: {', '.join(missing)}")
    return [
        Result(entry, half, json.loads((out / f"{entry['case']}.json").read_text()), 0.0)
        for entry, half in chosen
    ]


def set_results(name: str, folder: Path) -> list[Result]:
    """Every case of set ``name`` from the reports a run wrote to ``folder``."""
    _, manifest, split = read_set(name)
    return stored_results(folder, select(manifest, split, None, ()))


def case_line(r: Result) -> str:
    return (
        f"{r.case['case']:58s} {r.half:8s} concealed: {r.truth:45s} first: {r.first:22s} "
        f"accepted: {', '.join(r.accepted) or '-':40s} {'yes' if r.correct else 'NO':3s} "
        f"{r.wall_s:5.0f} s"
    )


def read_set(name: str) -> tuple[Path, list[dict], dict]:
    """A test-bed set's folder (``data/<name>``), its manifest and its split."""
    folder = ROOT / "data" / name
    manifest = json.loads((folder / "manifest.json").read_text())
    return folder, manifest, json.loads((folder / "split.json").read_text())


def select(manifest: list[dict], split: dict, half: str | None, names: Sequence[str]) -> list:
    """(manifest entry, half) of the cases asked for, in manifest order."""
    half_of = {name: h for h in HALVES for name in split[h]}
    unknown = sorted(set(names) - set(half_of))
    if unknown:
        raise SystemExit(f"unknown case(s): {', '.join(unknown)}")
    return [
        (entry, half_of[entry["case"]])
        for entry in manifest
        if (not names or entry["case"] in names) and half in (None, half_of[entry["case"]])
    ]


def _diagnose(
    folder: Path, entry: dict, out: Path | None, workers: int | None, cloud: bool
) -> tuple[dict, float]:
    settings = None if workers is None else DiagnoseSettings(workers=workers)
    weather = CLIMATES[entry["climate"]].epw if cloud else None
    return diagnose_folder(folder / entry["case"], entry["model"], out, False, settings, weather)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", help="case names (default: all)")
    parser.add_argument("--set", choices=SETS, default="testbed", help="which cases (data/SET)")
    parser.add_argument("--half", choices=HALVES, help="only this half of the split")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="cases at a time")
    parser.add_argument("--out", type=Path, help="folder for the reports and tables")
    parser.add_argument(
        "--tables-only", action="store_true", help="tables from the reports in --out, no diagnosis"
    )
    parser.add_argument(
        "--cloud-from-weather",
        action="store_true",
        help="add each case's weather-file cloud cover as the optional cloud_cover column",
    )
    args = parser.parse_args()
    if args.tables_only and not args.out:
        parser.error("--tables-only needs --out, the folder of a run's reports")
    folder, manifest, split = read_set(args.set)
    chosen = select(manifest, split, args.half, args.cases)
    if args.tables_only:
        write_tables(args.out, stored_results(args.out, chosen))
        print(f"confusion.md, tables.md and separation.md written from the reports in {args.out}")
        return
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
    # Cases side by side, one worker each; a single case gets the diagnosis's own pool.
    workers = 1 if args.jobs > 1 else None
    started = time.perf_counter()
    results = []
    with ProcessPoolExecutor(args.jobs) as pool:
        runs = [
            pool.submit(_diagnose, folder, entry, args.out, workers, args.cloud_from_weather)
            for entry, _ in chosen
        ]
        for (entry, half), run in zip(chosen, runs, strict=True):
            results.append(Result(entry, half, *run.result()))
            print(case_line(results[-1]), flush=True)
    elapsed = time.perf_counter() - started
    if args.out:
        write_tables(args.out, results)
    print(json.dumps(summary(results, elapsed)))


if __name__ == "__main__":
    main()
