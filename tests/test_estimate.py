"""Parameter recovery against data made by an independent reference (hand ODEs + solve_ivp)."""

import warnings
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from rcengine.building import Building
from rcengine.dataset import Dataset
from rcengine.estimation.estimator import Estimator
from rcengine.exceptions import ConvergenceWarning, ModelError, NotFittedError
from rcengine.io.timeseries import read_timeseries
from rcengine.models import get_model
from rcengine.signals import prepare

from .synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains

NOISE_K = 0.02
# Stated tolerance for recovered parameters with 7 days of rich excitation and 0.02 K noise.
RECOVERY_TOL = 0.05


@pytest.fixture(scope="module")
def basic_week() -> Dataset:
    frame = weather_and_gains(days=8)
    t_in = basic_reference(frame, TRUTH_BASIC, x0=(9.0, 19.0, 18.0))
    frame["t_in"] = t_in + np.random.default_rng(7).normal(0.0, NOISE_K, len(frame))
    # First day is a warm-up from an arbitrary state; fit on the following 7 days.
    return Dataset.from_frame(frame).between(frame.index[96], None)


def test_basic_parameters_recovered(basic_week):
    est = Estimator(get_model("basic", BUILDING), random_state=0).fit(basic_week)
    for name, true in TRUTH_BASIC.items():
        assert est.params_[name] == pytest.approx(true, rel=RECOVERY_TOL), name
    assert est.rmse_ < 1.5 * NOISE_K
    assert est.polish_["improved"] in (True, False)
    # The unmeasured wall and mass temperatures at the start were estimated, not guessed.
    assert len(est.initial_states_) == 1 and est.initial_states_[0].shape == (3,)


def test_same_seed_same_result(basic_week):
    net = get_model("basic", BUILDING)
    a = Estimator(net, preset="thesis", random_state=3, warn_bounds=False).fit(basic_week)
    b = Estimator(net, preset="thesis", random_state=3, warn_bounds=False).fit(basic_week)
    assert a.params_ == b.params_
    assert a.n_simulations_ == b.n_simulations_


def test_thesis_preset_settings_and_fit_quality(basic_week):
    est = Estimator(get_model("basic", BUILDING), preset="thesis", random_state=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        est.fit(basic_week)
    assert est.ga_.population.shape[0] == 20
    assert len(est.ga_.history) <= 15
    assert est.gps_.iterations <= 500
    assert est.polish_ is None
    # GA + GPS alone lands in the right basin (RMSE well under the 0.5 K of a poor fit).
    assert est.rmse_ < 0.5


def test_polish_is_reported_against_gps(basic_week):
    est = Estimator(get_model("basic", BUILDING), preset="thesis", polish=True, random_state=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        est.fit(basic_week)
    assert est.polish_["cost_polished"] <= est.polish_["cost_gps"] or not est.polish_["improved"]
    assert est.cost_ == pytest.approx(min(est.polish_["cost_polished"], est.polish_["cost_gps"]))


def test_known_parameters_are_held(basic_week):
    known = {"c_air": TRUTH_BASIC["c_air"], "alpha_wall": TRUTH_BASIC["alpha_wall"]}
    est = Estimator(get_model("basic", BUILDING), known=known, random_state=1).fit(basic_week)
    assert est.params_["c_air"] == known["c_air"]
    assert est.space_.dim == 6
    assert est.params_["r_int"] == pytest.approx(TRUTH_BASIC["r_int"], rel=RECOVERY_TOL)


def test_bound_override_and_bound_warning(basic_week):
    est = Estimator(
        get_model("basic", BUILDING), preset="thesis", bounds={"c_air": (1e5, 1e6)}, random_state=0
    )
    with pytest.warns(ConvergenceWarning, match="c_air"):
        est.fit(basic_week)
    assert est.params_["c_air"] <= 1e6
    assert "c_air" in est.at_bounds_
    quiet = replace(est, warn_bounds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        quiet.fit(basic_week)
    assert quiet.at_bounds_ == est.at_bounds_  # recorded for the caller to report


def test_errors():
    est = Estimator(get_model("basic", BUILDING))
    with pytest.raises(NotFittedError):
        est.simulate(None)
    with pytest.raises(ModelError, match="no parameter"):
        frame = weather_and_gains(days=1)
        frame["t_in"] = 20.0
        Estimator(get_model("basic", BUILDING), known={"r_nope": 1.0}).fit(
            Dataset.from_frame(frame)
        )
    with pytest.raises(ValueError, match="invalid preset"):
        Estimator(get_model("basic", BUILDING), preset="fast").fit(None)


def test_missing_input_named():
    frame = weather_and_gains(days=1).drop(columns=["ghi"])
    frame["t_in"] = 20.0
    with pytest.raises(ModelError, match="ghi"):
        Estimator(get_model("basic", BUILDING)).fit(Dataset.from_frame(frame))


def test_weekend_gap_is_not_model_error():
    """Selected-period data: a Friday→Monday jump starts a new segment with its own state."""
    frame = weather_and_gains(days=8)
    frame["t_in"] = basic_reference(frame, TRUTH_BASIC, x0=(9.0, 19.0, 18.0))
    data = Dataset.from_frame(frame).weekdays("UTC")
    assert len(data.segments) == 2
    net = get_model("basic", BUILDING).compile()
    from rcengine.estimation.objective import Objective

    cost = Objective(net, data)(net.as_theta(TRUTH_BASIC))[0]
    assert cost < 1e-7  # exact model + per-segment initial states: no spurious Monday error
    joined = Dataset(
        data.frame.set_axis(pd.date_range(data.frame.index[0], periods=len(data), freq="15min")),
        900.0,
    )
    assert Objective(net, joined)(net.as_theta(TRUTH_BASIC))[0] > 100 * cost + 1e-4


def test_restarts_find_the_better_basin_that_one_search_misses(project_data):
    """A test-bed fortnight whose two basins swap the roles of c_wall and c_int: one "default"
    search from seeds 3–5 settles in the worse (+22 % RMSE); "thorough" runs three independent
    ones, reaches the better from every seed, and its first search is the "default" one."""
    case = project_data / "testbed_sealed_12" / "open_plan-golden-null"
    building = Building.from_json(case / "building.json")
    frame = read_timeseries(case / "data.csv")
    frame = frame[frame.index < frame.index[0] + pd.Timedelta(days=14)]
    network = get_model("basic", building, frame.columns)
    data = prepare(frame, building, network.compile().input_names)
    fits = {
        s: Estimator(network, preset="thorough", random_state=s, warn_bounds=False).fit(data)
        for s in range(6)
    }
    best = min(f.rmse_ for f in fits.values())
    for seed, fit in fits.items():
        assert fit.rmse_ == pytest.approx(best, rel=0.01), seed
        assert len(fit.restart_costs_) == 3 and fit.cost_ == min(fit.restart_costs_)
        single = Estimator(network, random_state=seed, warn_bounds=False).fit(data)
        assert single.cost_ == pytest.approx(fit.restart_costs_[0])
        if seed in (3, 4, 5):
            assert single.rmse_ > 1.15 * best
