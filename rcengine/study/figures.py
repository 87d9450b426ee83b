"""The study's figures, as the thesis shows them (Fig. 3.1–3.9, A.1–A.6), written as PNG."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

COLOURS = {"basic": "#1f77b4", "sun": "#ff7f0e"}


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def bars_by_learning(results: pd.DataFrame, period: str, horizon: int, path: Path) -> Path:
    """Average RMSE of ``horizon``-day predictions per learning length, one bar per model, and the
    persistence forecast ("tomorrow = today") on the same days as a dashed line (thesis Fig. 3.4,
    3.7, A.1, A.2, A.4, A.5)."""
    sub = results[results.period == period]
    table = sub.groupby(["learn_days", "model"])[f"rmse_h{horizon}"].mean().unstack("model")
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    width = 0.8 / max(1, len(table.columns))
    x = np.arange(len(table.index))
    for i, model in enumerate(table.columns):
        ax.bar(x + i * width, table[model], width, label=model, color=COLOURS.get(model))
        for xi, v in zip(x + i * width, table[model], strict=True):
            ax.text(xi, v, f"{v:.2f}", ha="center", va="bottom", fontsize=7)
    naive = sub.drop_duplicates("day")[f"rmse_persistence_h{horizon}"].mean()
    ax.axhline(naive, color="grey", linestyle="--", label=f"persistence ({naive:.2f})")
    ax.set_xticks(x + width * (len(table.columns) - 1) / 2, [f"{d} d" for d in table.index])
    ax.set_xlabel("learning length")
    ax.set_ylabel("average RMSE [°C]")
    ax.set_title(f"Average RMSE of {horizon}-day predictions, {period} period")
    ax.legend()
    return _save(fig, path)


def weekday_bars(results: pd.DataFrame, model: str, period: str, weekday: str, path: Path) -> Path:
    """Average RMSE of predictions starting on ``weekday``: per learning length, one bar per
    horizon (thesis Fig. 3.5, 3.6, A.3)."""
    sub = results[(results.model == model) & (results.period == period)]
    sub = sub[sub.weekday == weekday]
    horizons = sorted(int(c[6:]) for c in sub.columns if c.startswith("rmse_h"))
    table = sub.groupby("learn_days")[[f"rmse_h{h}" for h in horizons]].mean()
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    width = 0.8 / len(horizons)
    x = np.arange(len(table.index))
    for i, h in enumerate(horizons):
        ax.bar(x + i * width, table[f"rmse_h{h}"], width, label=f"{h}-day prediction")
    ax.set_xticks(x + width * (len(horizons) - 1) / 2, [f"{d} d" for d in table.index])
    ax.set_xlabel("learning length")
    ax.set_ylabel("average RMSE [°C]")
    ax.set_title(f"Predictions starting on {weekday}s, {model}, {period} period")
    ax.legend()
    return _save(fig, path)


def heatmap(results: pd.DataFrame, model: str, period: str, path: Path) -> Path:
    """Average RMSE, learning length × prediction length (thesis Fig. 3.8, A.6)."""
    sub = results[(results.model == model) & (results.period == period)]
    horizons = sorted(int(c[6:]) for c in sub.columns if c.startswith("rmse_h"))
    table = sub.groupby("learn_days")[[f"rmse_h{h}" for h in horizons]].mean().T
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    im = ax.imshow(table.to_numpy(), cmap="inferno_r", origin="lower", aspect="auto")
    for (i, j), v in np.ndenumerate(table.to_numpy()):
        ax.text(
            j,
            i,
            f"{v:.2f}",
            ha="center",
            va="center",
            fontsize=8,
            color="white" if v > np.nanmean(table.to_numpy()) else "black",
        )
    ax.set_xticks(range(len(table.columns)), [f"{d} d" for d in table.columns])
    ax.set_yticks(range(len(horizons)), [f"{h} d" for h in horizons])
    ax.set_xlabel("learning length")
    ax.set_ylabel("prediction length")
    ax.set_title(f"Average RMSE [°C], {model}, {period} period")
    fig.colorbar(im, ax=ax)
    return _save(fig, path)


def example(
    times: pd.DatetimeIndex,
    measured: np.ndarray,
    predicted: np.ndarray,
    title: str,
    path: Path,
    timezone: str,
) -> Path:
    """A prediction against the reference (thesis Fig. 3.1–3.3, 3.9)."""
    local = times.tz_convert(timezone)
    fig, ax = plt.subplots(figsize=(8, 3.4))
    ax.plot(local, predicted, label="RC model", color=COLOURS["basic"])
    ax.plot(local, measured, label="EnergyPlus", color=COLOURS["sun"])
    err = np.sqrt(np.nanmean((measured - predicted) ** 2))
    ax.set_title(f"{title} (RMSE {err:.2f} °C)")
    ax.set_ylabel("indoor temperature [°C]")
    # Beside the axes, not loc="best": searching a week of quarter-hours for the emptiest corner
    # is slow (matplotlib warns), and no corner of a temperature trace stays empty anyway.
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.autofmt_xdate()
    return _save(fig, path)


def sun_vs_basic(comparison: dict, path: Path) -> Path:
    """Paired Basic − Sun RMSE difference (positive: Sun better) of 1- and 7-day predictions, per
    learning length and per sky of the first predicted day (``study.sun_vs_basic``)."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    panels = (
        (axes[0], comparison["by_learning"], "learning length"),
        (
            axes[1],
            comparison["by_sky_learn_ge_3d"],
            "sky of the first predicted day (≥ 3 d learning)",
        ),
    )
    for ax, table, xlabel in panels:
        bars = [(period, h) for period in table for h in (1, 7)]
        labels = list(dict.fromkeys(k for period in table.values() for k in period))
        width = 0.8 / len(bars)
        x = np.arange(len(labels))
        for i, (period, h) in enumerate(bars):
            stats = [table[period].get(k, {}) for k in labels]
            diffs = [st.get(f"diff_{h}d", np.nan) for st in stats]
            errs = [st.get(f"diff_{h}d_se") or 0.0 for st in stats]
            ax.bar(x + i * width, diffs, width, yerr=errs, capsize=2, label=f"{period}, {h}-day")
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.set_xticks(x + width * (len(bars) - 1) / 2, [k.replace("learn_", "") for k in labels])
        ax.set_xlabel(xlabel)
    axes[0].set_ylabel("RMSE Basic − RMSE Sun [°C]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Does the Sun model help? (> 0: Sun more accurate; bars ± 1 standard error)")
    return _save(fig, path)
