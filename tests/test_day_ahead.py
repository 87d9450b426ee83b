"""The diagnosis's day-ahead figures: the test half forecast from each local midnight, as the
service forecasts for an MPC (rcengine.diagnose.day_ahead)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rcengine.diagnose.day_ahead import day_ahead_errors
from rcengine.diagnose.fitting import split_data
from rcengine.models import get_model
from rcengine.signals import SignalOptions
from tests.synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains

DAYS = 8
# The test rows: three whole local days (the record's last 45 minutes run into a fourth).
TEST_DAYS = 3


@pytest.fixture(scope="module")
def record():
    frame = weather_and_gains(DAYS)
    t_in = basic_reference(frame, TRUTH_BASIC, (15.0, 19.0, 19.0))
    return frame.assign(t_in=t_in)


def _split(frame):
    network = get_model("basic", BUILDING, frame.columns)
    first_day = frame.index[0].tz_convert(BUILDING.location.timezone).normalize()
    boundary = first_day + pd.Timedelta(days=DAYS - TEST_DAYS)
    return network, split_data(frame, BUILDING, network, SignalOptions(), boundary)


def test_the_generating_model_forecasts_each_day_ahead_to_the_sensor_noise(record):
    network, split = _split(record)
    errors, days = day_ahead_errors(network, TRUTH_BASIC, split, BUILDING.location.timezone)
    assert days == TEST_DAYS
    assert errors.shape == (days * 96,)
    # Noise-free data from the same 3R3C: the filter's state is the true one to within a few
    # hundredths of a kelvin after 48 h, and the forecast carries it.
    assert np.sqrt(np.mean(errors**2)) < 0.02


def test_a_wrong_model_errs_by_kelvins_a_day_ahead(record):
    network, split = _split(record)
    # Half the envelope's resistance: twice the heat loss.
    wrong = {
        **TRUTH_BASIC,
        "r_wall_ext": TRUTH_BASIC["r_wall_ext"] / 2,
        "r_wall_int": TRUTH_BASIC["r_wall_int"] / 2,
    }
    errors, _ = day_ahead_errors(network, wrong, split, BUILDING.location.timezone)
    assert np.sqrt(np.mean(errors**2)) > 0.3


def test_days_an_outage_cuts_are_not_forecast(record):
    """Two hours of rows missing before a midnight: that midnight has no state to start from,
    and the day before has no inputs for the end of its horizon."""
    network, split = _split(record)
    zone = BUILDING.location.timezone
    _, days = day_ahead_errors(network, TRUTH_BASIC, split, zone)
    local = record.index.tz_convert(zone)
    midnight = record.index[(local.hour == 0) & (local.minute == 0)][-2]
    # A two-hour outage ending at that midnight: longer than a bridged gap.
    outage = (record.index >= midnight - np.timedelta64(2, "h")) & (record.index < midnight)
    gappy = record.loc[~outage]
    network, split = _split(gappy)
    _, fewer = day_ahead_errors(network, TRUTH_BASIC, split, zone)
    assert fewer == days - 2


def test_rows_stamped_off_the_hour_start_each_day_at_its_first_row(record):
    """SYSLAB's rows fall at :11, :26, ...: no row at midnight, yet every day is forecast."""
    network, split = _split(record)
    _, days = day_ahead_errors(network, TRUTH_BASIC, split, BUILDING.location.timezone)
    shifted = record.set_axis(record.index + pd.Timedelta(minutes=11))
    network, split = _split(shifted)
    _, shifted_days = day_ahead_errors(network, TRUTH_BASIC, split, BUILDING.location.timezone)
    assert shifted_days == days == TEST_DAYS
