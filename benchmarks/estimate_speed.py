"""Speed of one calibration: `basic` on 7 days at 15 min with the thesis's GA + GPS settings.

Baseline, timed in the same run: the obvious hand-written alternative — every candidate simulated
with scipy.integrate.solve_ivp (LSODA, inputs held over each step) inside the same GA + GPS. It is
run until a budget of simulations and its per-simulation cost extrapolated to the engine's count.
Also reports throughput of the batched simulator alone (week-long simulations per second, one
core). Prints a JSON line last.

    python benchmarks/estimate_speed.py [--data CSV --building JSON --start ISO]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core, as the target says
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
from rcengine.io.timeseries import read_timeseries
from scipy.integrate import solve_ivp

from rcengine.building import Building
from rcengine.dataset import Dataset
from rcengine.estimate import Estimator, search, settings_for
from rcengine.exceptions import ConvergenceWarning
from rcengine.models import get_model
from rcengine.network import CompiledNetwork
from rcengine.search_space import SearchSpace
from rcengine.signals import prepare
from rcengine.simulate import modal_system, simulate_modal

ROOT = Path(__file__).resolve().parents[1]
OFFICE = ROOT / "data" / "energyplus" / "office"
BASELINE_BUDGET = 60  # solve_ivp simulations actually run


class BudgetSpentError(Exception):
    pass


class SolveIvpObjective:
    """Cost of each candidate from one solve_ivp integration per candidate (no batching)."""

    def __init__(self, network: CompiledNetwork, data: Dataset, budget: int):
        self.network, self.budget = network, budget
        self.u = data.inputs(network.input_names)
        self.y = data.measured
        self.dt = data.step_s
        self.count = 0

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        A, B, C, _ = self.network.state_space(theta)
        costs = np.empty(len(theta))
        steps = self.u.shape[0]
        t_eval = np.arange(steps) * self.dt
        for s in range(len(theta)):
            if self.count >= self.budget:
                raise BudgetSpentError
            self.count += 1

            def rhs(t, x, a=A[s], b=B[s]):
                return a @ x + b @ self.u[min(int(t // self.dt), steps - 1)]

            x0 = np.full(A.shape[1], self.y[0])
            sol = solve_ivp(
                rhs,
                (0, t_eval[-1]),
                x0,
                method="LSODA",
                t_eval=t_eval,
                max_step=self.dt,
                rtol=1e-6,
                atol=1e-6,
            )
            y_sim = C[s] @ sol.y if sol.success else np.full(steps, np.inf)
            costs[s] = np.mean((self.y - y_sim) ** 2)
        return costs


def load(args: argparse.Namespace) -> tuple[Building, Dataset]:
    building = Building.from_json(args.building)
    frame = read_timeseries(args.data)
    net = get_model("basic", building, frame.columns).compile()
    data = prepare(frame, building, net.input_names)
    start = data.times[0] if args.start is None else args.start
    end = (data.between(start).times[0]) + np.timedelta64(7, "D")
    return building, data.between(start, end)


def simulator_throughput(net: CompiledNetwork, data: Dataset, population: int = 1000) -> float:
    """Week-long simulations per second of the batched simulator alone (best of 5)."""
    rng = np.random.default_rng(0)
    unit = rng.random((population, net.n_params))
    lo, hi = np.log(np.maximum(net.lower, 1e-3)), np.log(net.upper)
    theta = np.exp(lo + unit * (hi - lo))
    u = data.inputs(net.input_names)
    best = np.inf
    for _ in range(5):
        t = time.perf_counter()
        system = modal_system(net.rc_matrices(theta), data.step_s)
        simulate_modal(system, u, system.modal_state(np.full((population, net.n_states), 20.0)))
        best = min(best, time.perf_counter() - t)
    return population / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(OFFICE / "heating.csv"))
    parser.add_argument("--building", default=str(OFFICE / "building.json"))
    parser.add_argument("--start", default="2017-01-09T00:00:00+01:00")
    args = parser.parse_args()
    building, week = load(args)
    net = get_model("basic", building, week.frame.columns)
    compiled = net.compile()
    warnings.simplefilter("ignore", ConvergenceWarning)

    started = time.perf_counter()
    est = Estimator(net, preset="thesis", random_state=0).fit(week)
    wall = time.perf_counter() - started

    baseline = SolveIvpObjective(compiled, week, BASELINE_BUDGET)
    space = SearchSpace(compiled)
    t0 = time.perf_counter()
    with contextlib.suppress(BudgetSpentError):  # same GA + GPS, each candidate by solve_ivp
        search(
            lambda unit: baseline(space.to_physical(unit)),
            space.dim,
            settings_for("thesis"),
            np.random.default_rng(0),
        )
    per_sim = (time.perf_counter() - t0) / max(1, baseline.count)
    baseline_wall = per_sim * est.n_simulations_
    throughput = simulator_throughput(compiled, week)

    print("basic, 7 days × 96 steps, thesis GA (15 × 20) + GPS (≤ 500 it.)")
    print(
        f"  engine:   {wall:.3f} s, {est.n_simulations_} simulations "
        f"({est.n_simulations_ / wall:,.0f}/s inside the estimator), RMSE {est.rmse_:.3f} K"
    )
    print(
        f"  solve_ivp baseline: {per_sim * 1e3:.1f} ms per simulation (measured on "
        f"{baseline.count}), so {baseline_wall:,.0f} s for the same search "
        f"({baseline_wall / wall:,.0f}× slower)"
    )
    print(f"  batched simulator alone: {throughput:,.0f} week-long simulations/s on one core")
    print(
        json.dumps(
            {
                "model": "basic",
                "days": 7,
                "wall_s": round(wall, 3),
                "simulations": est.n_simulations_,
                "sims_per_s": round(est.n_simulations_ / wall),
                "baseline_wall_s": round(baseline_wall, 1),
                "baseline_s_per_sim": round(per_sim, 4),
                "speedup": round(baseline_wall / wall),
                "simulator_sims_per_s": round(throughput),
                "rmse_K": round(est.rmse_, 4),
            }
        )
    )


if __name__ == "__main__":
    main()
