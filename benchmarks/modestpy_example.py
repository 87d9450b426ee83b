"""ModestPy's own example (examples/simple: a 2R1C FMU) fitted with this engine.

Same problem and settings as ModestPy's `simple_legacy_ga.py`: learning window 0–50,000 s,
GA 5 generations × 20 individuals from a Latin hypercube, then pattern search (≤ 500 iterations,
tolerance 1e-6), RMSE on the learning window. The model is written as a custom network in a few
lines. Prints a JSON line last.

ModestPy itself is not run here: its figures are a record (``MODESTPY``), ModestPy 0.1.1 running
this same example as shipped, measured side by side on this project's kind of machine (2 cores)
at 31–86 s wall between runs (55 s typical, ~800 simulations; see the peer's README). The speedup
printed is against that record, and is labelled so.

Note on identifiability: C dT/dt = (Ti1 − T)/R1 + (Ti2 − T)/R2 depends on the parameters only
through R1·C and R2·C. Scaling R1, R2 by k and C by 1/k gives the identical output, so no method
can recover R1, R2 and C separately from these data; the engine reports the flat direction and the
identifiable time constants are compared with the truth instead.

    python benchmarks/modestpy_example.py
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import pandas as pd

from rcengine.dataset import Dataset
from rcengine.estimation.estimator import Estimator
from rcengine.exceptions import ConvergenceWarning
from rcengine.network import Parameter, RCNetwork

PEER = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "peers" / "modestpy-simple"
# ModestPy 0.1.1 running its own example as shipped, measured side by side on this kind of
# machine (not in this run): 31–86 s wall between runs, 55 s typical (see the peer's README).
MODESTPY = {
    "wall_s": 55.0,
    "wall_range_s": (31.0, 86.0),
    "simulations": 800,
    "rmse_K": 0.145,
    "R1": 0.163,
    "R2": 0.406,
    "C": 996.0,
}


def simple_2r1c(bounds: dict[str, list[float]]) -> RCNetwork:
    net = RCNetwork("Simple2R1C", description="ModestPy examples/simple")
    net.add_parameter(Parameter("R1", "K/W", *bounds["R1"][1:], "resistance to Ti1"))
    net.add_parameter(Parameter("R2", "K/W", *bounds["R2"][1:], "resistance to Ti2"))
    net.add_parameter(Parameter("C", "J/K", *bounds["C"][1:], "heat capacity"))
    net.add_capacitor("T", "C")
    net.add_resistor("Ti1", "T", "R1")
    net.add_resistor("Ti2", "T", "R2")
    return net.set_output("T")


def main() -> None:
    if not PEER.is_dir():
        sys.exit(f"peer data not found at {PEER}")
    inputs = pd.read_csv(PEER / "inputs.csv")
    result = pd.read_csv(PEER / "result.csv")
    truth = pd.read_csv(PEER / "true_parameters.csv").iloc[0].to_dict()
    bounds = json.loads((PEER / "est.json").read_text())
    index = pd.to_datetime(inputs["time"], unit="s", utc=True)
    frame = pd.DataFrame(
        {
            "Ti1": inputs["Ti1"].to_numpy(),
            "Ti2": inputs["Ti2"].to_numpy(),
            "t_in": result["T"].to_numpy(),
        },
        index=index,
    )
    learn = Dataset.from_frame(frame).between(index[0], index[0] + pd.Timedelta(seconds=50_000))
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        est = Estimator(simple_2r1c(bounds), preset="modestpy", random_state=0).fit(learn)
    wall = time.perf_counter() - started
    ident = est.identifiability()
    p = est.params_
    tau = {"R1C_s": p["R1"] * p["C"], "R2C_s": p["R2"] * p["C"]}
    tau_true = {"R1C_s": truth["R1"] * truth["C"], "R2C_s": truth["R2"] * truth["C"]}
    print(f"ModestPy example: {learn.frame.shape[0]} rows at 60 s, GA 5×20 (LHS) + GPS")
    print(f"  this engine: {wall:.3f} s, {est.n_simulations_} simulations, RMSE {est.rmse_:.4f} K")
    low, high = MODESTPY["wall_range_s"]
    print(
        f"  ModestPy 0.1.1 (recorded, not run here): {MODESTPY['wall_s']} s typical "
        f"({low:g}–{high:g} s side by side on this machine kind), {MODESTPY['simulations']} "
        f"simulations, RMSE {MODESTPY['rmse_K']} K"
    )
    for k in tau:
        print(
            f"  {k}: {tau[k]:.2f} (true {tau_true[k]:.2f}, error {tau[k] / tau_true[k] - 1:+.2%})"
        )
    for direction in ident.flat_directions:
        print(
            f"  not identifiable: scaling by exp(t·w) with w = {direction} leaves the output "
            "unchanged; R1, R2 and C cannot be recovered separately from these data"
        )
    print(
        json.dumps(
            {
                "wall_s": round(wall, 4),
                "simulations": est.n_simulations_,
                "rmse_K": round(est.rmse_, 5),
                "R1": p["R1"],
                "R2": p["R2"],
                "C": p["C"],
                **{k: round(v, 3) for k, v in tau.items()},
                "tau_rel_error": {k: round(tau[k] / tau_true[k] - 1, 5) for k in tau},
                "identifiable": ident.identifiable,
                "modestpy_recorded_s": MODESTPY["wall_s"],
                "modestpy_recorded_range_s": list(MODESTPY["wall_range_s"]),
                "modestpy_recorded_simulations": MODESTPY["simulations"],
                "speedup_vs_modestpy_recorded": round(MODESTPY["wall_s"] / wall, 1),
            }
        )
    )


if __name__ == "__main__":
    main()
