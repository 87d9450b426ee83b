"""Speed of one calibration: `basic` on 7 days at 15 min with the thesis's GA + GPS settings.

Data: the committed EnergyPlus office (data/energyplus/office/heating.csv, building.json), the
week from Monday 2017-01-09. Baseline, timed in the same run: the obvious hand-written
alternative — every candidate simulated with scipy.integrate.solve_ivp (LSODA, inputs held over
each step) inside the same GA + GPS. It is run for a budget of simulations only and its
per-simulation cost extrapolated to the engine's count (the output says so). Also reports the
throughput of the batched simulator alone, CPU time next to wall time (other jobs may share the
cores: the load average is printed with the timings), and whether the least-squares polish beats
GPS on the same week for `basic` and `sun`. Prints a JSON line last.

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
from scipy.integrate import solve_ivp

from rcengine.building import Building
from rcengine.dataset import Dataset
from rcengine.estimation import settings_for
from rcengine.estimation.estimator import Estimator, search
from rcengine.estimation.search_space import SearchSpace
from rcengine.exceptions import ConvergenceWarning
from rcengine.io.timeseries import read_timeseries
from rcengine.models import get_model
from rcengine.network import CompiledNetwork, RCNetwork
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


def load(args: argparse.Namespace, model: str) -> tuple[RCNetwork, Dataset]:
    """The model for the building and the 7 days from ``args.start``, its signals derived."""
    building = Building.from_json(args.building)
    frame = read_timeseries(args.data)
    net = get_model(model, building, frame.columns)
    data = prepare(frame, building, net.compile().input_names)
    start = data.times[0] if args.start is None else args.start
    end = (data.between(start).times[0]) + np.timedelta64(7, "D")
    return net, data.between(start, end)


def load_average() -> str:
    """The 1, 5 and 15 min load averages (as `uptime` prints them), for the record."""
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def polish_report(net: RCNetwork, week: Dataset) -> dict:
    """Thesis GA + GPS, then the least-squares polish: does it lower the cost?"""
    est = Estimator(net, preset="thesis", polish=True, random_state=0).fit(week)
    gps, polished = est.polish_["cost_gps"], est.polish_["cost_polished"]
    return {
        "rmse_gps_K": round(float(np.sqrt(gps)), 6),
        "rmse_polished_K": round(float(np.sqrt(polished)), 6),
        "cost_reduction_pct": round(100.0 * (1.0 - polished / gps), 4),
        "improved": est.polish_["improved"],
        "wall_s": round(est.wall_time_s_, 3),
    }


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
    net, week = load(args, "basic")
    compiled = net.compile()
    warnings.simplefilter("ignore", ConvergenceWarning)

    load_before = load_average()
    started, cpu_started = time.perf_counter(), time.process_time()
    est = Estimator(net, preset="thesis", random_state=0).fit(week)
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    load_engine = load_average()

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
    polish = {"basic": polish_report(net, week), "sun": polish_report(*load(args, "sun"))}

    print(f"basic, 7 days × 96 steps from {week.times[0]}, thesis GA (15 × 20) + GPS (≤ 500 it.)")
    print(f"  load average before / after the engine's fit: {load_before} / {load_engine}")
    print(
        f"  engine:   {wall:.3f} s wall, {cpu:.3f} s CPU, {est.n_simulations_} simulations "
        f"({est.n_simulations_ / wall:,.0f}/s wall, {est.n_simulations_ / cpu:,.0f}/s per CPU "
        f"second), RMSE {est.rmse_:.3f} K"
    )
    print(
        f"  solve_ivp baseline: {per_sim * 1e3:.1f} ms per simulation, measured on the first "
        f"{baseline.count} candidates of its search and extrapolated to {est.n_simulations_}: "
        f"{baseline_wall:,.0f} s ({baseline_wall / wall:,.0f}× slower)"
    )
    print(f"  batched simulator alone: {throughput:,.0f} week-long simulations/s on one core")
    for model, p in polish.items():
        verdict = "beats" if p["improved"] else "does not beat"
        print(
            f"  polish ({model}, thesis GA + GPS then least squares): training RMSE "
            f"{p['rmse_gps_K']:.6f} K after GPS, {p['rmse_polished_K']:.6f} K polished — "
            f"{verdict} GPS, cost {p['cost_reduction_pct']:.4f} % lower ({p['wall_s']:.2f} s)"
        )
    print(f"  load average at the end: {load_average()}")
    print(
        json.dumps(
            {
                "model": "basic",
                "days": 7,
                "wall_s": round(wall, 3),
                "simulations": est.n_simulations_,
                "sims_per_s": round(est.n_simulations_ / wall),
                "baseline_wall_s": round(baseline_wall, 1),
                "baseline_extrapolated_from": baseline.count,
                "baseline_s_per_sim": round(per_sim, 4),
                "speedup": round(baseline_wall / wall),
                "cpu_s": round(cpu, 3),
                "sims_per_cpu_s": round(est.n_simulations_ / cpu),
                "simulator_sims_per_s": round(throughput),
                "rmse_K": round(est.rmse_, 4),
                "polish": polish,
                "load_avg": load_engine,
            }
        )
    )


if __name__ == "__main__":
    main()
