"""Writing a finished study: the thesis's tables as CSV, summary.json and the figures."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from . import study_figures as figs
from .building import Building
from .study import StudySettings, example, free_floating, summary, tables

# Thesis Table 3.2 and 3.3: free-floating 12-day validation of the ISO models and the thesis 3R3C.
THESIS_FREE_FLOATING = {
    "3R3C thesis": {"rmse": 0.72, "nmbe": -3.09, "cv_rmse": 2.1},
    "ISO 13790": {"rmse": 1.16, "nmbe": -4.2, "cv_rmse": 4.7},
    "ISO 52016-1": {"rmse": 0.21, "nmbe": 0.2, "cv_rmse": 0.9},
}


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
    (output / "figures").mkdir(exist_ok=True)
    written = []
    for name, table in tables(results, settings).items():
        path = output / f"{name}.csv"
        table.to_csv(path, index=name != "parameters", float_format="%.6g")
        written.append(path)
    info = summary(results, settings)
    fig = output / "figures"
    tz = building.location.timezone
    for period in settings.periods:
        for h in settings.horizons:
            written.append(
                figs.bars_by_learning(results, period, h, fig / f"bars_{period}_{h}d.png")
            )
        for model in settings.models:
            written.append(
                figs.heatmap(results, model, period, fig / f"heatmap_{model}_{period}.png")
            )
    for weekday in ("Monday", "Tuesday", "Sunday"):
        model = settings.models[0]
        if (results.weekday == weekday).any():
            written.append(
                figs.weekday_bars(
                    results,
                    model,
                    "complete",
                    weekday,
                    fig / f"weekday_{model}_{weekday.lower()}.png",
                )
            )
    days = sorted(results.day.unique())
    if days:
        mid = days[len(days) // 2]
        for learn, horizon, label in ((1, 1, "fig3_1"), (3, 1, "fig3_2"), (7, 3, "fig3_3")):
            try:
                p = example(
                    frame, building, settings.models[0], mid, learn, horizon, preset=settings.preset
                )
            except ValueError:
                continue
            title = f"{settings.models[0]}: learn {learn} d, predict {horizon} d from {mid}"
            written.append(
                figs.example(p.times, p.measured, p.predicted, title, fig / f"{label}.png", tz)
            )
    if free is not None:
        ff = free_floating(free, building, preset=settings.preset)
        info["free_floating"] = {
            k: ff[k] for k in ("model", "learn_days", "predict_days", "start", "metrics", "params")
        }
        info["free_floating"]["thesis"] = THESIS_FREE_FLOATING
        written.append(
            figs.example(
                ff["times"],
                ff["measured"],
                ff["predicted"],
                "free-floating: learn 12 d, predict 12 d",
                fig / "fig3_9_free_floating.png",
                tz,
            )
        )
    path = output / "summary.json"
    path.write_text(json.dumps(info, indent=2, default=float) + "\n")
    written.append(path)
    return written
