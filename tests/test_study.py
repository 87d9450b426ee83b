"""The rolling learn/predict study on a few days of the EnergyPlus office: table shapes, summary,
the persistence baseline computed by hand, and the learned models beating it."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from rcengine.building import Building
from rcengine.estimation import EstimatorSettings
from rcengine.estimation.ga import GASettings
from rcengine.estimation.pattern_search import GPSSettings
from rcengine.io.timeseries import read_timeseries
from rcengine.study.analysis import sky_class, tables
from rcengine.study.report import write_study
from rcengine.study.run import StudySettings, run_study

TZ = "Europe/Rome"
# Friday 18 – Monday 21 November 2016: the Complete period predicts all four days, the Selected
# period only Friday and Monday (whose "yesterday" is Friday).
FIRST, END = "2016-11-18", "2016-11-22"
COMPLETE_DAYS = ["2016-11-18", "2016-11-19", "2016-11-20", "2016-11-21"]
SELECTED_DAYS = ["2016-11-18", "2016-11-21"]
# A small budget keeps the test in seconds; the learned models must still beat persistence.
SMALL = EstimatorSettings(
    GASettings(population=24, generations=3, lhs=True), GPSSettings(max_iter=0), polish=True
)


@pytest.fixture(scope="module")
def office(project_data):
    folder = project_data / "energyplus" / "office"
    building = Building.from_json(folder / "building.json")
    return (
        read_timeseries(folder / "heating.csv"),
        read_timeseries(folder / "freefloat.csv"),
        building,
    )


@pytest.fixture(scope="module")
def settings() -> StudySettings:
    return StudySettings(preset=SMALL, start=FIRST, end=END, workers=1)


@pytest.fixture(scope="module")
def results(office, settings) -> pd.DataFrame:
    heating, _, building = office
    return run_study(heating, building, settings)


@pytest.fixture(scope="module")
def written(office, settings, results, tmp_path_factory):
    heating, free, building = office
    out = tmp_path_factory.mktemp("study")
    write_study(results, settings, heating, building, free, out)
    return out


def test_one_training_per_day_model_period_and_learning_length(results):
    counts = results.groupby(["model", "period"])["day"].agg(lambda d: sorted(set(d)))
    for model in ("basic", "sun"):
        assert counts[(model, "complete")] == COMPLETE_DAYS
        assert counts[(model, "selected")] == SELECTED_DAYS
    assert len(results) == 2 * (len(COMPLETE_DAYS) + len(SELECTED_DAYS)) * 4
    assert not results.duplicated(["model", "period", "day", "learn_days"]).any()


def test_thesis_tables_have_4_training_and_12_validation_columns(results, settings):
    out = tables(results, settings)
    for model in ("basic", "sun"):
        for period, days in (("complete", COMPLETE_DAYS), ("selected", SELECTED_DAYS)):
            train = out[f"training_rmse_{model}_{period}"]
            assert list(train.columns) == ["learn_1d", "learn_3d", "learn_5d", "learn_7d"]
            assert list(train.index) == days
            valid = out[f"validation_rmse_{model}_{period}"]
            assert list(valid.columns) == [
                f"learn_{learn}d_predict_{h}d" for learn in (1, 3, 5, 7) for h in (1, 3, 7)
            ]
            assert list(valid.index) == days
            assert np.isfinite(train.to_numpy()).all() and np.isfinite(valid.to_numpy()).all()


def _local_day_t_in(frame: pd.DataFrame, day: str) -> np.ndarray:
    local = frame["t_in"].tz_convert(TZ)
    return local[local.index.normalize() == pd.Timestamp(day, tz=TZ)].to_numpy()


@pytest.mark.parametrize(
    ("period", "day", "yesterday"),
    [
        ("complete", "2016-11-21", "2016-11-20"),  # Monday after Sunday
        ("selected", "2016-11-21", "2016-11-18"),  # Monday after Friday: weekends are gaps
        ("complete", "2016-11-19", "2016-11-18"),
    ],
)
def test_persistence_is_yesterdays_measured_t_in(office, results, period, day, yesterday):
    heating = office[0]
    today, before = _local_day_t_in(heating, day), _local_day_t_in(heating, yesterday)
    assert today.size == before.size == 96
    by_hand = np.sqrt(np.mean((today - before) ** 2))
    rows = results[(results.period == period) & (results.day == day)]
    assert len(rows) == 8  # 2 models × 4 learning lengths, all the same naive forecast
    np.testing.assert_allclose(rows["rmse_persistence_h1"], by_hand, rtol=1e-9)


def test_learned_models_beat_persistence_on_the_same_days(results):
    learned = results[results.learn_days >= 3]
    for (model, period), group in learned.groupby(["model", "period"]):
        for h in (1, 3, 7):
            model_rmse = group[f"rmse_h{h}"].mean()
            naive = group.drop_duplicates("day")[f"rmse_persistence_h{h}"].mean()
            assert model_rmse < 0.75 * naive, (model, period, h, model_rmse, naive)


def test_summary_json(written, results):
    info = json.loads((written / "summary.json").read_text())
    assert {
        "settings",
        "average_rmse",
        "headline",
        "estimation_wall_s",
        "estimation_cpu_s",
        "trainings",
        "sun_vs_basic",
        "free_floating",
    } <= set(info)
    assert info["trainings"] == len(results)
    for model in ("basic", "sun"):
        assert set(info["estimation_wall_s"][model]) == {f"learn_{d}d" for d in (1, 3, 5, 7)}
        for period in ("complete", "selected"):
            entry = info["average_rmse"][model][period]["learn_3d"]
            assert set(entry) == {"predict_1d", "predict_3d", "predict_7d", "train"}
            table = pd.read_csv(written / f"validation_rmse_{model}_{period}.csv", index_col=0)
            assert entry["predict_1d"] == pytest.approx(table["learn_3d_predict_1d"].mean())
            assert info["headline"][f"{model}_{period}"]["days"] == table.shape[0]
        metrics = info["free_floating"][model]["metrics"]
        assert {"rmse", "mbe", "nmbe", "cv_rmse", "ashrae14_pass"} <= set(metrics)
        assert info["free_floating"][model]["learn_days"] == 12
    assert info["free_floating"]["thesis"]["ISO 52016-1"]["rmse"] == 0.21


def test_sun_vs_basic_pairs_the_same_days(written, results):
    info = json.loads((written / "summary.json").read_text())["sun_vs_basic"]
    stats = info["by_learning"]["complete"]["learn_3d"]
    assert stats["pairs"] == len(COMPLETE_DAYS)
    rows = results[(results.period == "complete") & (results.learn_days == 3)]
    by_model = rows.groupby("model")["rmse_h1"].mean()
    assert stats["diff_1d"] == pytest.approx(by_model["basic"] - by_model["sun"])
    assert -1.0 < info["solar_signal_correlation"]["daily_solar_window"] <= 1.0


def test_figures_written(written):
    names = {p.name for p in (written / "figures").glob("*.png")}
    assert {
        "bars_complete_1d.png",
        "bars_selected_7d.png",
        "heatmap_basic_selected.png",
        "weekday_basic_monday.png",
        "sun_vs_basic.png",
        "fig3_9_free_floating.png",
    } <= names


@pytest.mark.parametrize(("index", "name"), [(0.2, "overcast"), (0.55, "mixed"), (0.95, "sunny")])
def test_sky_class(index, name):
    assert sky_class(index) == name


def test_likelihood_criterion_gives_finite_tables(office, settings):
    """The study with the maximum-likelihood criterion on a sub-period (the short study's
    settings, one model, the complete period): every training and validation RMSE is finite."""
    heating, _, building = office
    short = replace(settings, models=("basic",), periods=("complete",), criterion="likelihood")
    results = run_study(heating, building, short)
    assert len(results) == len(COMPLETE_DAYS) * len(short.learn_days)
    out = tables(results, short)
    train = out["training_rmse_basic_complete"]
    valid = out["validation_rmse_basic_complete"]
    assert list(train.index) == COMPLETE_DAYS and list(valid.index) == COMPLETE_DAYS
    assert valid.shape[1] == len(short.learn_days) * len(short.horizons)
    assert np.isfinite(train.to_numpy()).all() and np.isfinite(valid.to_numpy()).all()
    assert (valid.to_numpy() > 0).all()
