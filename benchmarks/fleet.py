"""Fleet benchmark: one nightly re-estimation pass of a synthetic fleet on each backend.

Makes a fleet from the EnergyPlus office (``data/energyplus/office``): building ``i`` is the office
over its own 14 days of the heating season, with ``t_in`` simulated by the *Basic* 3R3C model
fitted once on the office and then perturbed per building (each parameter × a log-normal factor,
σ = 20 %, kept inside its bounds), the outdoor temperature offset by up to ±3 K, 0.05 K sensor
noise, and measurement gaps (one to three outages of 1–6 h of ``t_in``). The fleet is stored in a
service database (SQLite file in a temporary folder) through the service's own ingest, copied once
per pass, and each copy gets one nightly pass (``service.fleet.retrain_all``, the code of
``rcservice retrain-all``: queue every due building, claim and run the queue on every slot,
store each decision) with

1. the process pool, ``--workers`` processes (default 2);
2. Dask distributed, a ``LocalCluster`` of ``--workers`` single-threaded worker processes;
3. Dask with one worker (for the 1 → 2 workers scaling).

Every fit is a 7-day ``basic`` fit with the service's defaults (preset ``default``, seed 0) and
the held-out day after it. Prints one line per pass and a JSON line last::

    {"buildings": N, "pool_wall_s": ..., "dask_wall_s": ..., "dask_overhead_ratio": ...,
     "buildings_per_core_hour": ..., "scaling_1_to_2_workers": ...}

``dask_overhead_ratio`` = Dask wall / pool wall (same workers); ``buildings_per_core_hour`` of
the Dask pass = N / (wall × cores / 3600); ``scaling_1_to_2_workers`` = 1-worker wall / 2-worker
wall. Targets on a 2-core machine: ratio ≤ 1.15, scaling ≥ 1.7, ≥ 5,000 buildings per core-hour.

    python benchmarks/fleet.py                       # 1,000 buildings × 14 days (~15 min, 2 cores)
    python benchmarks/fleet.py --buildings 50        # a quick run
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import shutil
import sys
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

from rcengine.building import Building  # noqa: E402
from rcengine.columns import T_IN, T_OUT  # noqa: E402
from rcengine.dataset import Dataset  # noqa: E402
from rcengine.estimation import Estimator  # noqa: E402
from rcengine.estimation.objective import Objective  # noqa: E402
from rcengine.io.timeseries import read_timeseries  # noqa: E402
from rcengine.models import get_model  # noqa: E402
from rcengine.signals import prepare  # noqa: E402
from service import ingest, repository  # noqa: E402
from service.backends import Backend, PoolBackend  # noqa: E402
from service.core.config import Settings  # noqa: E402
from service.core.db import Database  # noqa: E402
from service.fleet import FleetSummary, retrain_all  # noqa: E402

OFFICE = ROOT / "data" / "energyplus" / "office"
# The office week the base parameters are fitted on.
BASE_WEEK = ("2017-01-09T00:00+01:00", "2017-01-16T00:00+01:00")
DAY_ROWS = 96
PARAMETER_SIGMA = 0.2
T_OUT_OFFSET_K = 3.0
NOISE_K = 0.05


class FleetMaker:
    """The office, its base fit, and a generator of perturbed buildings."""

    def __init__(self, seed: int = 0):
        self.description = json.loads((OFFICE / "building.json").read_text())
        self.building = Building.from_dict(self.description)
        self.frame = read_timeseries(OFFICE / "heating.csv")
        network = get_model("basic", self.building, self.frame.columns)
        self.compiled = network.compile()
        self.data = prepare(self.frame, self.building, self.compiled.input_names)
        # The fit only seeds the synthetic fleet's truths, which are clipped to the bounds anyway:
        # a parameter ending on its bound (alpha_int, r_wall_int on this week) is a valid truth.
        estimator = Estimator(network, random_state=seed, warn_bounds=False)
        fit = estimator.fit(self.data.between(*BASE_WEEK))
        self.params = fit.params_
        self.bounds = {p.name: (p.lower, p.upper) for p in network.parameters.values()}
        self.rng = np.random.default_rng(seed)

    def variant(self, days: int) -> pd.DataFrame:
        """The contract columns of one building over ``days`` days (UTC index)."""
        rows = days * DAY_ROWS
        start = int(self.rng.integers(0, len(self.frame) - rows) // DAY_ROWS * DAY_ROWS)
        window = self.data.frame.iloc[start : start + rows].copy()
        window[T_OUT] += self.rng.uniform(-T_OUT_OFFSET_K, T_OUT_OFFSET_K)
        factors = self.rng.lognormal(0.0, PARAMETER_SIGMA, len(self.params))
        params = {
            name: float(np.clip(value * factor, *self.bounds[name]))
            for (name, value), factor in zip(self.params.items(), factors, strict=True)
        }
        simulated = Objective(self.compiled, Dataset(window, self.data.step_s)).trajectory(params)
        t_in = simulated.y + self.rng.normal(0.0, NOISE_K, rows)
        for _ in range(int(self.rng.integers(1, 4))):  # sensor outages
            at, length = int(self.rng.integers(0, rows)), int(self.rng.integers(4, 25))
            t_in[at : at + length] = np.nan
        t_in[-DAY_ROWS // 4 :] = simulated.y[-DAY_ROWS // 4 :]  # ends on a measured row
        out = self.frame.iloc[start : start + rows].copy()
        out[T_OUT], out[T_IN] = window[T_OUT].to_numpy(), np.round(t_in, 3)
        return out


def make_fleet(db: Database, buildings: int, days: int = 14, seed: int = 0) -> list[int]:
    """``buildings`` perturbed offices of ``days`` days each, stored through the ingest."""
    maker = FleetMaker(seed)
    frames = (maker.variant(days) for _ in range(buildings))
    shown = tqdm(frames, total=buildings, desc="fleet", unit="building", disable=buildings < 20)
    return store_fleet(db, maker.description, shown, seed)


def store_fleet(
    db: Database, description: dict, frames: Iterable[pd.DataFrame], seed: int = 0
) -> list[int]:
    """One building named ``office-variant-i`` per frame, its rows stored as an upload."""
    ids = []
    for i, frame in enumerate(frames):
        token = hashlib.sha256(f"fleet-{seed}-{i}".encode()).hexdigest()
        name = f"office-variant-{i}"
        with db.write() as session:
            record = repository.add_building(
                session, name, {**description, "name": name}, "Europe/Rome", token
            )
        ingest.store(db, record.id, ingest.Upload(frame))
        ids.append(record.id)
    return ids


def one_pass(settings: Settings, backend: Backend, label: str) -> FleetSummary:
    db = Database(settings.database_url)
    try:
        summary = retrain_all(settings, db, backend, progress=sys.stderr.isatty())
    finally:
        db.dispose()
    print(f"{label}: " + " | ".join(summary.lines()), flush=True)
    return summary


def run(args: argparse.Namespace, folder: Path) -> dict:
    from service.backends.dask import DaskBackend

    base = folder / "fleet.db"
    db = Database(f"sqlite:///{base}")
    db.migrate()
    started = time.perf_counter()
    make_fleet(db, args.buildings, args.days, args.seed)
    db.dispose()
    print(
        f"fleet of {args.buildings} × {args.days} days stored in "
        f"{time.perf_counter() - started:.0f} s",
        flush=True,
    )

    def settings(name: str) -> Settings:
        shutil.copy(base, folder / name)
        return Settings(
            database_url=f"sqlite:///{folder / name}",
            admin_token="fleet-benchmark-admin-token-0123456789",
            workers=args.workers,
            training_days=args.training_days,
            preset=args.preset,
            log_level="WARNING",
        )

    pool = one_pass(settings("pool.db"), PoolBackend(settings("pool.db")), "pool")
    dask = one_pass(settings("dask.db"), DaskBackend("local", args.workers), "dask")
    single = one_pass(settings("dask1.db"), DaskBackend("local", 1), "dask, 1 worker")
    return {
        "buildings": args.buildings,
        "pool_wall_s": pool.wall_s,
        "dask_wall_s": dask.wall_s,
        "dask_overhead_ratio": round(dask.wall_s / pool.wall_s, 3),
        "buildings_per_core_hour": round(dask.buildings_per_core_hour),
        "scaling_1_to_2_workers": round(single.wall_s / dask.wall_s, 3),
        "workers": args.workers,
        "decisions": {k: getattr(dask, k) for k in ("promoted", "kept", "refused", "failed")},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buildings", type=int, default=1000)
    parser.add_argument("--days", type=int, default=14, help="days stored per building")
    parser.add_argument("--training-days", type=int, default=7, help="days each fit uses")
    parser.add_argument("--workers", type=int, default=2, help="pool processes / Dask workers")
    parser.add_argument("--preset", default="default", help="estimator preset of every fit")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    logging.getLogger("distributed").setLevel(logging.WARNING)
    with tempfile.TemporaryDirectory(prefix="rcservice-fleet-") as folder:
        print(json.dumps(run(args, Path(folder))))


if __name__ == "__main__":
    main()
