"""pySIP on issue 12's Armadillo split, measured as ``likelihood_peers.py`` measures the engine.

pySIP (https://github.com/locie/pySIP) is not on PyPI and needs pydantic 1 (the service needs 2),
so it runs in an environment of its own, never in the project's:

    python -m venv /tmp/pysip && /tmp/pysip/bin/pip install numpy scipy pandas xarray numba \
        "pydantic<2" typing_extensions flatten_dict makefun pylfsr matplotlib jinja2 networkx \
        tqdm joblib platformdirs loguru numdifftools
    git clone https://github.com/locie/pySIP /tmp/pysip-src   # tested at da70d25
    /tmp/pysip/bin/pip install --no-deps /tmp/pysip-src
    /tmp/pysip/bin/python benchmarks/pysip_armadillo.py

``pysip.regressors`` imports PyMC and PyTensor at module level for its
Bayesian sampler; ``fit``, ``eval_residuals`` and ``predict`` do not use them, so when they are
not installed this script puts empty stand-ins in ``sys.modules`` first.

The model and settings are pySIP's Armadillo example
(``docs/examples/thermal_network/armadillo/fit_frequentist.ipynb``): TwTi_RoRi, time in days, the
air's process noise and initial state fixed, first 162 rows train, last 70 test. Three input
treatments: the file's samples with pySIP's first-order hold (its example), the samples held
(zero-order), and the step means (s_k + s_k+1)/2 held — what ``rcengine.io.read_armadillo``
gives the engine. Figures: fit seconds (median of 5 cold fits from the example's initial values,
after one), test one-step RMSE of the innovations y − C x⁻ (the filter run from the record's
start), test open-loop RMSE (outputs hidden after row 162), train open-loop RMSE.
Prints a JSON line last.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
import os
import sys
import time
import types
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core, as likelihood_peers.py

import numpy as np
import pandas as pd

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "measured"
N_TRAIN = 162
S_PER_DAY = 86400.0
INPUTS, OUTPUT = ["T_ext", "P_hea"], "T_int"
PARAMETERS = [  # pySIP's Armadillo example, verbatim in meaning
    dict(name="Ro", scale=1e-2, transform="log"),
    dict(name="Ri", scale=1e-3, transform="log"),
    dict(name="Cw", scale=1e7 / S_PER_DAY, transform="log"),
    dict(name="Ci", scale=1e6 / S_PER_DAY, transform="log"),
    dict(name="sigw_w", scale=1e-3 * S_PER_DAY**0.5, transform="log"),
    dict(name="sigw_i", value=0.0, transform="fixed"),
    dict(name="sigv", scale=1e-2, transform="log"),
    dict(name="x0_w", loc=25.0, scale=7.0, transform="none"),
    dict(name="x0_i", value=26.7, transform="fixed"),
    dict(name="sigx0_w", value=0.1, transform="fixed"),
    dict(name="sigx0_i", value=0.1, transform="fixed"),
]


def _stand_in_for_pymc() -> None:
    """Empty ``pymc`` / ``pytensor`` packages when absent (only pySIP's sampler uses them)."""

    class Op:  # pySIP subclasses pytensor's Op at import
        pass

    def attribute(name: str) -> type:
        if name.startswith("__"):
            raise AttributeError(name)
        return Op

    absent = {top for top in ("pymc", "pytensor") if importlib.util.find_spec(top) is None}
    for name in ("pymc", "pytensor", "pytensor.tensor"):
        if name.split(".")[0] not in absent:
            continue
        module = types.ModuleType(name)
        module.__path__ = []  # a package, so that ``pytensor.tensor`` imports
        module.__getattr__ = attribute  # type: ignore[method-assign]
        sys.modules[name] = module
    if "pytensor" in absent:
        sys.modules["pytensor"].tensor = sys.modules["pytensor.tensor"]  # type: ignore[attr-defined]


def records() -> dict[str, tuple[pd.DataFrame, int]]:
    """The three input treatments: (frame in days, pySIP hold order)."""
    df = pd.read_csv(DATA / "armadillo_data_H2.csv").set_index("Time")
    df = df.drop(df.index[-1])
    df.index = df.index / S_PER_DAY
    # rcengine.io.measured.read_armadillo's step means, written out: this script runs where pySIP is
    # installed, not the engine.
    means = df.copy()
    for column in INPUTS:
        samples = means[column].to_numpy()
        means[column] = np.append(0.5 * (samples[:-1] + samples[1:]), samples[-1])
    return {
        "samples, first-order hold (pySIP's example)": (df, 1),
        "samples, zero-order hold": (df, 0),
        "step means, zero-order hold (as rcengine)": (means, 0),
    }


def measure(frame: pd.DataFrame, hold: int, repeats: int = 5) -> dict:
    from pysip.regressors import Regressor
    from pysip.statespace import TwTi_RoRi

    walls = []
    for _ in range(repeats + 1):
        reg = Regressor(TwTi_RoRi(PARAMETERS, hold_order=hold), inputs=INPUTS, outputs=OUTPUT)
        with contextlib.redirect_stdout(io.StringIO()):
            started = time.perf_counter()
            reg.fit(df=frame.iloc[:N_TRAIN])
            walls.append(time.perf_counter() - started)
    residuals = reg.eval_residuals(df=frame)  # standardised: k = e / S, S the sqrt of s
    innovations = residuals["residual"].values[:, 0] * residuals["residual_std"].values[:, 0, 0]
    measured = frame[OUTPUT].to_numpy()
    hidden_test = frame.copy()
    hidden_test.loc[hidden_test.index[N_TRAIN:], OUTPUT] = np.nan
    open_loop = reg.predict(df=hidden_test)["y_mean"].values[:, 0]
    simulated = reg.predict(df=frame.assign(**{OUTPUT: np.nan}))["y_mean"].values[:, 0]

    def test_rmse(error: np.ndarray) -> float:
        return float(np.sqrt(np.mean(error[N_TRAIN:] ** 2)))

    return {
        "fit_s_median": float(np.median(walls[1:])),
        "test_one_step_K": test_rmse(innovations),
        "test_open_loop_K": test_rmse(measured - open_loop),
        "train_open_loop_K": float(np.sqrt(np.mean((measured - simulated)[:N_TRAIN] ** 2))),
    }


def main() -> None:
    _stand_in_for_pymc()
    warnings.filterwarnings("ignore", category=UserWarning, module="xarray")
    results = {}
    for label, (frame, hold) in records().items():
        results[label] = row = measure(frame, hold)
        print(f"{label}: " + ", ".join(f"{k} {v:.5f}" for k, v in row.items()))
    print(f"load average at the end: {os.getloadavg()}")
    print(json.dumps(results))


if __name__ == "__main__":
    main()
