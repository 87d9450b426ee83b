"""Writing a finished study: the thesis's tables as CSV, summary.json and the figures."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from rcengine.building import Building
from rcengine.io.jsonable import jsonable
from rcengine.study import figures as figs
from rcengine.study.analysis import (
    daily_clearness,
    free_floating,
    solar_signal_correlation,
    summary,
    sun_vs_basic,
    tables,
)
from rcengine.study.run import StudySettings, example

# Thesis Table 3.2 and 3.3: free-floating 12-day validation of the ISO models and the thesis 3R3C.
THESIS_FREE_FLOATING = {
    "3R3C thesis": {"rmse": 0.72, "nmbe": -3.09, "cv_rmse": 2.1},
    "ISO 13790": {"rmse": 1.16, "nmbe": -4.2, "cv_rmse": 4.7},
    "ISO 52016-1": {"rmse": 0.21, "nmbe": 0.2, "cv_rmse": 0.9},
}
# Thesis §3.3 predicts from 1 February; the other months show how much that one date says.
FREE_FLOATING_START = "2017-02-01"
FREE_FLOATING_OTHER_STARTS = ("2016-11-01", "2016-12-01", "2017-01-01", "2017-03-01")
# Thesis Fig. 3.1–3.3: (learning days, predicted days, figure name).
EXAMPLES = ((1, 1, "fig3_1"), (3, 1, "fig3_2"), (3, 3, "fig3_3"))


def write_study(
    results: pd.DataFrame,
    settings: StudySettings,
    frame: pd.DataFrame,
    building: Building,
    free: pd.DataFrame | None,
    output: Path,
) -> list[Path]:
    """Tables (CSV), summary.json and figures of a finished study."""
    output.mkdir(parents=True, exist_ok=True)
    fig_dir = output / "figures"
    fig_dir.mkdir(exist_ok=True)
    written = []
    for name, table in tables(results, settings).items():
        path = output / f"{name}.csv"
        table.to_csv(path, index=name != "parameters", float_format="%.6g")
        written.append(path)
    info = summary(results, settings)
    comparison = sun_vs_basic(results, daily_clearness(frame, building), settings.horizons)
    if comparison:
        comparison["solar_signal_correlation"] = solar_signal_correlation(frame, building)
        info["sun_vs_basic"] = comparison
        written.append(figs.sun_vs_basic(comparison, fig_dir / "sun_vs_basic.png"))
    written += _rmse_figures(results, settings, fig_dir)
    written += _example_figures(results, settings, frame, building, fig_dir)
    if free is not None:
        info["free_floating"], paths = _free_floating(free, building, settings, fig_dir)
        written += paths
    path = output / "summary.json"
    path.write_text(json.dumps(jsonable(info), indent=2) + "\n")
    written.append(path)
    return written


def _rmse_figures(results: pd.DataFrame, settings: StudySettings, fig_dir: Path) -> list[Path]:
    """Bars per learning length (Fig. 3.4, 3.7, A.1–A.5), heatmaps (Fig. 3.8, A.6) and weekday
    bars (Fig. 3.5, 3.6, A.3)."""
    written = []
    for period in settings.periods:
        if not (results.period == period).any():
            continue
        for h in settings.horizons:
            path = fig_dir / f"bars_{period}_{h}d.png"
            written.append(figs.bars_by_learning(results, period, h, path))
        for model in settings.models:
            path = fig_dir / f"heatmap_{model}_{period}.png"
            written.append(figs.heatmap(results, model, period, path))
    model = settings.models[0]
    for weekday in ("Monday", "Tuesday", "Sunday"):
        if ((results.weekday == weekday) & (results.period == "complete")).any():
            path = fig_dir / f"weekday_{model}_{weekday.lower()}.png"
            written.append(figs.weekday_bars(results, model, "complete", weekday, path))
    return written


def _example_figures(
    results: pd.DataFrame,
    settings: StudySettings,
    frame: pd.DataFrame,
    building: Building,
    fig_dir: Path,
) -> list[Path]:
    """Predictions against EnergyPlus from a mid-season Tuesday (thesis Fig. 3.1–3.3)."""
    days = sorted(results.day.unique())
    tuesdays = [d for d in days if pd.Timestamp(d).day_name() == "Tuesday"]
    if not tuesdays:
        return []
    day, model = tuesdays[len(tuesdays) // 2], settings.models[0]
    written = []
    for learn, horizon, name in EXAMPLES:
        try:
            p = example(frame, building, model, day, learn, horizon, preset=settings.preset)
        except ValueError:
            continue
        title = f"{model}: learn {learn} d, predict {horizon} d from {day}"
        path = fig_dir / f"{name}.png"
        tz = building.location.timezone
        written.append(figs.example(p.times, p.measured, p.predicted, title, path, tz))
    return written


def _free_floating(
    free: pd.DataFrame,
    building: Building,
    settings: StudySettings,
    fig_dir: Path,
) -> tuple[dict, list[Path]]:
    """Thesis §3.3 for every model, from 1 February and, for robustness, from other months."""
    out: dict = {"thesis": THESIS_FREE_FLOATING}
    written = []
    for model in settings.models:
        fit = {"preset": settings.preset, "criterion": settings.criterion}
        ff = free_floating(free, building, model, start=FREE_FLOATING_START, **fit)
        out[model] = {
            k: ff[k] for k in ("model", "learn_days", "predict_days", "start", "metrics", "params")
        }
        out[model]["other_starts"] = {
            start: free_floating(free, building, model, start=start, **fit)["metrics"]
            for start in FREE_FLOATING_OTHER_STARTS
        }
        name = "fig3_9_free_floating" if model == "basic" else f"free_floating_{model}"
        written.append(
            figs.example(
                ff["times"],
                ff["measured"],
                ff["predicted"],
                f"free-floating, {model}: learn 12 d, predict 12 d",
                fig_dir / f"{name}.png",
                building.location.timezone,
            )
        )
    return out, written
