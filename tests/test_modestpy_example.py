"""ModestPy's example problem: the identifiable time constants are recovered, and the engine says
that R1, R2 and C are not separately identifiable (the output depends on R1·C and R2·C only)."""

import json
import warnings

import pandas as pd
import pytest

from benchmarks.modestpy_example import simple_2r1c
from rcengine.dataset import Dataset
from rcengine.estimation.estimator import Estimator
from rcengine.exceptions import ConvergenceWarning


def test_modestpy_simple_example(shared_data):
    peer = shared_data / "peers" / "modestpy-simple"
    inputs = pd.read_csv(peer / "inputs.csv")
    measured = pd.read_csv(peer / "result.csv")["T"].to_numpy()
    index = pd.to_datetime(inputs["time"], unit="s", utc=True)
    frame = pd.DataFrame(
        {"Ti1": inputs["Ti1"].to_numpy(), "Ti2": inputs["Ti2"].to_numpy(), "t_in": measured},
        index=index,
    )
    learn = Dataset.from_frame(frame).between(index[0], index[0] + pd.Timedelta(seconds=50_000))
    net = simple_2r1c(json.loads((peer / "est.json").read_text()))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        est = Estimator(net, preset="modestpy", random_state=0).fit(learn)
    p = est.params_
    assert p["R1"] * p["C"] == pytest.approx(0.1 * 2000, rel=0.02)
    assert p["R2"] * p["C"] == pytest.approx(0.25 * 2000, rel=0.02)
    assert est.rmse_ <= 0.01
    flat = est.identifiability().flat_directions
    assert len(flat) == 1
    w = flat[0]
    # The flat direction is R1 ×k, R2 ×k, C ÷k.
    assert w["R1"] == pytest.approx(w["R2"], rel=1e-3) and w["C"] == pytest.approx(
        -w["R1"], rel=1e-3
    )
