"""Short gaps bridged before a fit: the states run on across a dropped reading or a day's outage,
longer outages still start a new segment, a sensor that drops readings at random costs the fit
nothing, and a record with missing days is diagnosed as the whole record is."""

import numpy as np
import pandas as pd
import pytest

from rcengine.building import Building
from rcengine.dataset import MAX_BRIDGED_GAP_S, MAX_FILLED_GAP_S, Dataset, bridge_short_gaps
from rcengine.diagnose import DiagnoseSettings, diagnose
from rcengine.estimation.estimator import Estimator
from rcengine.io.timeseries import read_timeseries
from rcengine.models import get_model
from rcengine.signals.derived import prepare

STEP = pd.Timedelta(minutes=15)


def _frame(rows: int = 12) -> pd.DataFrame:
    times = pd.date_range("2017-03-26", periods=rows, freq=STEP, tz="Europe/Rome")
    return pd.DataFrame(
        {
            "t_in": 20.0 + np.arange(rows),
            "t_out": 2.0 * np.arange(rows),
            "q_hvac": 100 * np.arange(rows),
        },
        index=times,
    )


def test_a_dropped_reading_is_bridged_with_interpolated_inputs_and_no_measurement():
    full = _frame()
    bridged = bridge_short_gaps(full.drop(full.index[[3, 7, 8]]))
    assert bridged.index.equals(full.index)
    assert bridged["t_in"].isna().sum() == 3 and np.isnan(bridged["t_in"].iloc[7])
    assert bridged["t_out"].to_numpy() == pytest.approx(full["t_out"].to_numpy())
    assert bridged["q_hvac"].to_numpy() == pytest.approx(full["q_hvac"].to_numpy())
    assert len(Dataset.from_frame(bridged).segments) == 1


def _days(days: int) -> pd.DataFrame:
    """Hourly rows whose inputs repeat a daily course plus a trend, so a day's neighbours differ."""
    times = pd.date_range("2017-01-02", periods=24 * days, freq="h", tz="Europe/Rome")
    hours = np.arange(len(times), dtype=float)
    return pd.DataFrame(
        {
            "t_in": 20.0 + 0.01 * hours,
            "t_out": 5.0 + 4.0 * np.sin(2 * np.pi * hours / 24) + 0.1 * hours,
            "q_hvac": 1000.0 + 10.0 * hours,
        },
        index=times,
    )


def test_a_day_long_outage_is_bridged_with_the_same_hours_of_the_days_either_side():
    full = _days(5)
    lost = full.index[(full.index >= "2017-01-04") & (full.index < "2017-01-05")]
    bridged = bridge_short_gaps(full.drop(lost))
    assert bridged.index.equals(full.index)
    assert bridged.loc[lost, "t_in"].isna().all()
    day = pd.Timedelta(days=1)
    for column in ("t_out", "q_hvac"):
        expected = (full.loc[lost - day, column].to_numpy() + full.loc[lost + day, column]) / 2
        assert bridged.loc[lost, column].to_numpy() == pytest.approx(expected.to_numpy())
    # The trend is linear and the daily course repeats: the neighbours' mean is the truth.
    assert bridged.loc[lost, "t_out"].to_numpy() == pytest.approx(full.loc[lost, "t_out"])
    assert len(Dataset.from_frame(bridged).segments) == 1


def test_an_outage_with_no_day_either_side_or_longer_than_a_day_stays_a_gap():
    full = _days(5)
    at_start = full.drop(full.index[2:12])  # no day before, and the day after is there: filled
    assert bridge_short_gaps(at_start).index.equals(full.index)
    short = _days(1)
    alone = short.drop(short.index[8:14])  # neither day exists
    assert bridge_short_gaps(alone).index.equals(alone.index)
    rows = int(MAX_FILLED_GAP_S / 3600) + 1
    weekend = full.drop(full.index[30 : 30 + rows])
    bridged = bridge_short_gaps(weekend)
    assert bridged.index.equals(weekend.index)
    assert len(Dataset.from_frame(bridged, step_s=3600.0).segments) == 2
    assert bridge_short_gaps(full) is full


def test_an_outage_longer_than_the_interpolation_limit_is_not_interpolated():
    full = _frame(20)
    rows = int(MAX_BRIDGED_GAP_S / STEP.total_seconds()) + 1
    gapped = full.drop(full.index[5 : 5 + rows])
    bridged = bridge_short_gaps(gapped)
    assert bridged.index.equals(gapped.index)
    assert len(Dataset.from_frame(bridged, step_s=900.0).segments) == 2


@pytest.mark.slow
def test_ten_missing_days_leave_the_diagnosis_as_on_the_whole_record(project_data):
    """A heavy building's strong unmetered gain with ten days of its record missing. Restarted
    at each missing day, the fit's free wall and mass temperatures took up the gain's drift and
    nothing was accepted; bridged, the gain is found as on the whole record."""
    case = project_data / "testbed" / "heavy-golden-unmetered_gains-strong"
    building = Building.from_json(case / "building.json")
    whole = read_timeseries(case / "data.csv")
    local = whole.index.tz_convert(building.location.timezone).normalize()
    days = local.unique()
    lost = np.random.default_rng(1).choice(len(days), 10, replace=False)
    frame = whole[~local.isin(days[lost])]
    report = diagnose(frame, building, "basic", DiagnoseSettings(workers=1))
    accepted = [f.effect for f in report.findings if f.accepted]
    assert accepted[:1] == ["unmetered_gains"]
    assert report.clock is not None and report.clock.offset_h == 0.0


def test_random_dropouts_leave_the_fit_as_on_the_whole_record(project_data):
    """An EnergyPlus season with 3 % of its readings dropped at random: bridged, it is one
    segment again and the fit lands where the whole record's does (restarted at every gap, its
    250 segments' free initial states would hide half the model's error)."""
    case = project_data / "testbed_sealed_12" / "open_plan-golden-null"
    building = Building.from_json(case / "building.json")
    whole = read_timeseries(case / "data.csv")
    dropped = whole[np.random.default_rng(0).random(len(whole)) > 0.03]
    network = get_model("basic", building, whole.columns)
    inputs = network.compile().input_names
    fits = []
    for frame in (whole, bridge_short_gaps(dropped)):
        data = prepare(frame, building, inputs)
        fits.append(Estimator(network, random_state=0, warn_bounds=False).fit(data))
        assert len(data.segments) == 1
    assert len(Dataset.from_frame(dropped).segments) > 200
    reference, bridged = fits
    assert bridged.rmse_ == pytest.approx(reference.rmse_, rel=0.05)
    for name, value in reference.params_.items():
        assert bridged.params_[name] == pytest.approx(value, rel=0.1, abs=1e-3), name


def test_a_missing_input_is_named_by_its_column_and_times():
    """Rows of a window cut from a longer record were named by their positions in it."""
    from rcengine.exceptions import DataValidationError

    times = pd.date_range("2017-01-01", periods=4, freq="15min", tz="UTC")
    frame = pd.DataFrame({"q_occ": [1.0, np.nan, np.nan, 4.0], "t_out": 1.0}, index=times)
    with pytest.raises(DataValidationError) as caught:
        Dataset.from_frame(frame).inputs(["t_out", "q_occ"])
    (problem,) = caught.value.problems
    assert (problem.row, problem.column) == (None, "q_occ")
    assert "2 rows, 2017-01-01T00:15:00+00:00 to 2017-01-01T00:30:00+00:00" in problem.message
