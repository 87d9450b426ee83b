"""Forecasts: Kalman-estimated start state, missing inputs named, MPC candidate trajectories."""

import numpy as np
import pandas as pd
import pytest

from rcengine.dataset import Dataset
from rcengine.exceptions import DataValidationError
from rcengine.forecast import forecast, trajectories
from rcengine.kalman import kalman_filter
from rcengine.models import get_model

from .synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains


@pytest.fixture(scope="module")
def four_days() -> Dataset:
    frame = weather_and_gains(days=4, seed=11)
    frame["t_in"] = basic_reference(frame, TRUTH_BASIC, x0=(6.0, 18.0, 17.0))
    return Dataset.from_frame(frame)


def test_forecast_with_true_parameters_tracks_truth(four_days):
    net = get_model("basic", BUILDING).compile()
    start = four_days.times[2 * 96]
    fc = forecast(net, TRUTH_BASIC, four_days, start, hours=24)
    truth = four_days.frame["t_in"].to_numpy()[2 * 96 : 3 * 96]
    # The hidden wall and mass states come from the filter; a 5 K wrong start would show here.
    assert np.sqrt(np.mean((fc.t_in_pred - truth) ** 2)) < 0.05
    assert fc.times[0] == start and len(fc.times) == 96


def test_kalman_recovers_hidden_states(four_days):
    net = get_model("basic", BUILDING).compile()
    model = net.discrete(TRUTH_BASIC, 900.0)
    u = four_days.inputs(model.input_names)[:192]
    y = four_days.frame["t_in"].to_numpy()[:192]
    _, states = model.simulate(u, np.array([6.0, 18.0, 17.0]))
    result = kalman_filter(model, u, y)  # starts from every node at y[0] = 18 °C
    np.testing.assert_allclose(result.state, states[-1], atol=0.3)


def test_missing_future_inputs_are_named(four_days):
    frame = four_days.frame.copy()
    frame.loc[frame.index[3 * 96 + 5], "t_out"] = np.nan
    data = Dataset(frame, 900.0)
    net = get_model("basic", BUILDING).compile()
    with pytest.raises(DataValidationError, match=r"t_out.*missing at 1 forecast time"):
        forecast(net, TRUTH_BASIC, data, data.times[3 * 96], hours=12)


def test_no_history_no_forecast(four_days):
    net = get_model("basic", BUILDING).compile()
    with pytest.raises(DataValidationError, match="no measurements in the step before"):
        forecast(net, TRUTH_BASIC, four_days, four_days.times[0], hours=6)
    with pytest.raises(DataValidationError, match="UTC offset"):
        forecast(net, TRUTH_BASIC, four_days, "2017-01-10T00:00:00", hours=6)


def test_candidate_trajectories_equal_one_by_one_simulation(four_days):
    model = get_model("basic", BUILDING).compile().discrete(TRUTH_BASIC, 900.0)
    u = four_days.inputs(model.input_names)[:96]
    x0 = np.array([8.0, 20.0, 19.0])
    rng = np.random.default_rng(0)
    candidates = rng.uniform(0, 30_000, (5, 96))
    batch = trajectories(model, x0, u, candidates)
    for n in range(5):
        u_n = u.copy()
        u_n[:, model.input_names.index("q_hvac")] = candidates[n]
        y_n, _ = model.simulate(u_n, x0)
        np.testing.assert_allclose(batch[n], y_n, atol=1e-9)
    assert pd.Series(batch[1]).notna().all()


def test_a_dropped_reading_before_the_start_does_not_cut_the_filters_history(four_days):
    """One row missing 3 h before the start: the filter runs on across it (inputs interpolated,
    no measurement) and the slow states still come from the whole history; cut there, the
    filter would know only the last 3 h."""
    net = get_model("basic", BUILDING).compile()
    start = four_days.times[2 * 96]
    truth = four_days.frame["t_in"].to_numpy()[2 * 96 : 3 * 96]
    gapped = Dataset(four_days.frame.drop(start - pd.Timedelta(hours=3)), 900.0)

    def error(data: Dataset, history_h: float) -> float:
        fc = forecast(net, TRUTH_BASIC, data, start, hours=24, history_h=history_h)
        return float(np.sqrt(np.mean((fc.t_in_pred - truth) ** 2)))

    assert error(gapped, 48.0) == pytest.approx(error(four_days, 48.0), abs=1e-3)
    assert error(gapped, 48.0) < 0.01 < 0.1 < error(four_days, 2.75)
