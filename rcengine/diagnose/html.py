"""HTML rendering of a diagnosis: one self-contained page, figures embedded as PNG."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from rcengine.diagnose.fitting import Fit
from rcengine.diagnose.locate import DAYS, hour_weekday
from rcengine.diagnose.report import Finding, Report

_STYLE = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;color:#222;line-height:1.45}
h1{font-size:1.6em}h2{margin-top:2em;border-bottom:1px solid #ccc}
table{border-collapse:collapse}td,th{padding:.3em .7em;border-bottom:1px solid #ddd;text-align:left}
.ok{color:#0a6d2c;font-weight:600}.no{color:#8a1c1c}.box{background:#f5f7fa;padding:1em;border-radius:6px}
img{max-width:100%}
"""
_COLOURS = {"before": "#d62728", "after": "#1f77b4"}


def _png(fig: plt.Figure | None) -> str:
    if fig is None:
        return ""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode()
    return f'<img alt="figure" src="data:image/png;base64,{data}">'


def _before_after(report: Report) -> list[tuple[str, str, Fit]]:
    """("before", model, fit) of the baseline and, when the diagnosis extended it, ("after",
    model, fit) of the final model."""
    fits = [("before", report.model, report.baseline)]
    if report.final is not report.baseline:
        fits.append(("after", report.final.network.name, report.final))
    return fits


def timeseries_figure(report: Report, days: int = 14) -> plt.Figure:
    test = report.baseline.split.test
    local = test.times.tz_convert(report.building.location.timezone)
    n = min(len(test), int(days * 86400 / test.step_s))
    fig, ax = plt.subplots(figsize=(11, 3.6))
    ax.plot(local[:n], test.measured[:n], color="k", lw=1.2, label="measured")
    for when, name, fit in _before_after(report):
        ax.plot(
            local[:n],
            fit.simulated_test[:n],
            color=_COLOURS[when],
            lw=1,
            label=f"{name} (test RMSE {fit.rmse_test:.2f} K)",
        )
    ax.set_ylabel("indoor temperature [°C]")
    ax.set_title(f"Test period, first {days} days: measured vs predicted before and after")
    ax.legend(loc="upper right", fontsize=8)
    fig.autofmt_xdate()
    return fig


def heatmaps_figure(report: Report) -> plt.Figure:
    tz = report.building.location.timezone
    grids = [(f"{when}: {name}", fit) for when, name, fit in _before_after(report)]
    fig, axes = plt.subplots(1, len(grids), figsize=(5.5 * len(grids), 3.2), squeeze=False)
    values = [hour_weekday(f.residual_test, f.split.test.times, tz) for _, f in grids]
    limit = max(0.1, float(np.nanmax([np.nanmax(np.abs(v)) for v in values])))
    for ax, (title, _), grid in zip(axes[0], grids, values, strict=True):
        im = ax.imshow(grid, aspect="auto", cmap="RdBu_r", vmin=-limit, vmax=limit)
        ax.set_yticks(range(7), DAYS)
        ax.set_xticks(range(0, 24, 3))
        ax.set_xlabel("hour of day (local)")
        ax.set_title(f"mean test residual [K], {title}", fontsize=9)
    fig.colorbar(im, ax=axes[0].tolist(), label="measured − predicted [K]")
    return fig


def conditions_figure(report: Report) -> plt.Figure:
    block = report.locate["test"]["by_condition"]
    labels, means = [], []
    for groups in block.values():
        for label, stats in groups.items():
            labels.append(label)
            means.append(stats["mean_K"])
    fig, ax = plt.subplots(figsize=(8, 2.8))
    ax.bar(labels, means, color=["#d62728" if m > 0 else "#1f77b4" for m in means])
    ax.axhline(0, color="k", lw=0.8)
    ax.set_ylabel("mean residual [K]")
    ax.set_title("Baseline test residual by condition (positive: model too cold)")
    return fig


def evidence_figure(report: Report, finding: Finding) -> plt.Figure | None:
    screen = finding.screen
    if screen is None:
        return None
    train = report.baseline.split.train  # every model shares the training rows
    resid = _residual_before(report, finding)
    n = min(len(train), int(7 * 86400 / train.step_s))
    local = train.times.tz_convert(report.building.location.timezone)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.2), gridspec_kw={"width_ratios": [2.2, 1]})
    a1.plot(local[:n], resid[:n], color="k", lw=1, label="residual before")
    a1.plot(
        local[:n],
        screen.response[:n],
        color="#2ca02c",
        lw=1,
        label=f"{finding.effect}: fitted contribution",
    )
    a1.legend(fontsize=8)
    a1.set_ylabel("[K]")
    a1.set_title("Training residual and what the candidate explains (first week)", fontsize=9)
    ok = np.isfinite(resid)
    a2.plot(screen.response[ok][::4], resid[ok][::4], ".", ms=2, alpha=0.4)
    a2.set_xlabel("candidate contribution [K]")
    a2.set_ylabel("residual before [K]")
    fig.autofmt_xdate()
    return fig


def _residual_before(report: Report, finding: Finding) -> np.ndarray:
    # The residual the candidate was screened against: the model of the round it was judged in,
    # the fit of the finding accepted in the latest earlier round (a repair is round 0). Found
    # by round, not by place: the accepted findings are listed by strength of evidence.
    earlier = [f for f in report.accepted if f.round < finding.round]
    fit = max(earlier, key=lambda f: f.round).fit if earlier else report.baseline
    return fit.residual_train


def save_figures(report: Report, folder: Path, stem: str) -> list[Path]:
    """Write the report's figures as PNG files ``<stem>_<figure>.png``; returns their paths."""
    figures = {
        "timeseries": timeseries_figure(report),
        "heatmaps": heatmaps_figure(report),
        "conditions": conditions_figure(report),
    }
    if report.accepted:
        figures["evidence"] = evidence_figure(report, report.accepted[0])
    paths = []
    for name, fig in figures.items():
        if fig is None:
            continue
        path = folder / f"{stem}_{name}.png"
        fig.savefig(path, dpi=80, bbox_inches="tight")
        plt.close(fig)
        paths.append(path)
    return paths


def _health_box(d: dict) -> str:
    """The base model's health: its verdict, the reasons and notes."""
    health = d["baseline"].get("health")
    if health is None:
        return ""
    esc = html.escape
    items = "".join(f"<li>{esc(r)}</li>" for r in health["reasons"]) + "".join(
        f"<li><i>note:</i> {esc(n)}</li>" for n in health["notes"]
    )
    cls = "ok" if health["verdict"] == "healthy" else "no"
    return f"<p>Base model: <span class={cls}>{esc(health['verdict'])}</span></p><ul>{items}</ul>"


def _fold_tables(finding: dict) -> str:
    """A finding's fold evidence when it was judged, and its backward check's when it had one."""
    effect, folds = finding["effect"], finding["folds"]
    across = (folds or {}).get("training", "rolling folds")
    return _folds_table(f"{effect} across {across}", folds) + _folds_table(
        f"{effect} added last, to the other findings (backward check)", finding.get("backward")
    )


def _folds_table(title: str, folds: dict | None) -> str:
    """Per-fold test RMSE before and after an extension, and the pooled test."""
    if not folds:
        return ""
    rows = "".join(
        f"<tr><td>{html.escape(f.get('test', str(k + 1)))}</td>"
        f"<td>{f['rmse_test_before']:.3f}</td><td>{f['rmse_test_after']:.3f}</td>"
        f"<td class={'ok' if f['outcome'] == 'helped' else 'no'}>{f['outcome']}</td></tr>"
        for k, f in enumerate(folds["folds"])
    )
    tied = f", {folds['tied']} tied" if folds["tied"] else ""
    return (
        f"<h4>{html.escape(title)}: helps in {folds['helped']} "
        f"of {len(folds['folds'])}{tied} (confidence {folds['confidence']:.0%})</h4>"
        "<table><tr><th>test period</th><th>RMSE before [K]</th><th>after [K]</th><th></th></tr>"
        f"{rows}<tr><td><b>pooled</b></td><td>{folds['pooled_rmse_test_before']:.3f}</td>"
        f"<td>{folds['pooled_rmse_test_after']:.3f}</td><td></td></tr></table>"
    )


def _day_ahead(d: dict) -> str:
    """The base and final models' day-ahead forecasts over the test half, as an MPC gets them."""
    block = d.get("day_ahead")
    if not block or block.get("rmse_baseline") is None:
        return ""
    return (
        f"<p>Forecast {block['horizon_h']:g} h ahead from each local midnight of the test half "
        f"({block['days']} days, the state filtered from the {block['history_h']:g} h before), "
        f"as the service forecasts for an MPC: RMSE {block['rmse_baseline']:.3f} K with the "
        f"base model, {block['rmse_final']:.3f} K with the final one.</p>"
    )


def _clock(d: dict) -> str:
    """A re-aligned record's note (``diagnose.clock``); nothing where the readings kept time."""
    clock = d.get("clock")
    if not clock or not clock["offset_h"]:
        return ""
    return f"<p class=no>Clock: {html.escape(clock['note'])}.</p>"


def _no_folds(d: dict) -> str:
    if d["evidence"]["method"] == "split":
        return "<p>Judged on the single split alone (no folds asked for, or a short record).</p>"
    return "<p>No candidate passed the single split, so none was refitted on the folds.</p>"


def local_day(instant: str, timezone: str) -> str:
    """The date of an ISO 8601 instant in ``timezone`` (a UTC text cut to 10 characters gives
    the day before for a local midnight east of Greenwich)."""
    return pd.Timestamp(instant).tz_convert(timezone).strftime("%Y-%m-%d")


def render(report: Report) -> str:
    """The report as a standalone HTML page."""
    d = report.to_dict()
    esc = html.escape
    zone = report.building.location.timezone

    def day(instant: str) -> str:
        return local_day(instant, zone)

    rows = "".join(
        f"<tr><td>{esc(f['effect'])}</td>"
        + ("<td class=ok>accepted</td>" if f["accepted"] else "<td class=no>rejected</td>")
        + f"<td>{f['screening']['explained_share']:.0%}</td>"
        f"<td>{f['rmse_test_before']:.3f}</td>"
        f"<td>{'' if f['rmse_test_after'] is None else format(f['rmse_test_after'], '.3f')}</td>"
        f"<td>{'' if f['delta_bic'] is None else format(f['delta_bic'], '+.1f')}</td>"
        f"<td>{esc(f['reason'])}</td></tr>"
        for f in d["findings"]
    )
    skipped = "".join(f"<li><b>{esc(k)}</b>: {esc(v)}</li>" for k, v in d["skipped"].items())
    evidence = "".join(
        f"<h3>{esc(f.effect)}</h3><p>{esc(f.explanation)}</p>{_png(evidence_figure(report, f))}"
        for f in report.accepted
    )
    folds = "".join(_fold_tables(f) for f in d["findings"]) + "".join(
        f"<p>Fold testing {esc(f['test'])} left out: {esc(f['reason'])}.</p>"
        for f in d["evidence"]["left_out"]
    )
    white = d["whiteness"]
    return f"""<!doctype html><html><head><meta charset="utf-8">
<title>Mismatch diagnosis — {esc(report.building.name)}</title><style>{_STYLE}</style></head><body>
<h1>Mismatch diagnosis — {esc(report.building.name)}</h1>
<div class="box"><p><b>{esc(d["verdict"])}</b></p>{_health_box(d)}
<p>Baseline <b>{esc(report.model)}</b>: train RMSE {d["baseline"]["rmse_train"]:.3f} K,
test RMSE {d["baseline"]["rmse_test"]:.3f} K. Final <b>{esc(d["final"]["model"])}</b>:
train {d["final"]["rmse_train"]:.3f} K, test {d["final"]["rmse_test"]:.3f} K.
Training {esc(day(d["periods"]["train"][0]))} – {esc(day(d["periods"]["train"][1]))},
test until {esc(day(d["periods"]["test"][1]))}.</p>{_clock(d)}{_day_ahead(d)}
<p>Where and when: {esc(d["mismatch"]["summary"])}.</p></div>
<h2>Measured vs predicted</h2>{_png(timeseries_figure(report))}
<h2>Where the errors concentrate</h2>{_png(heatmaps_figure(report))}
{_png(conditions_figure(report))}
<h2>Findings</h2><table><tr><th>effect</th><th>verdict</th><th>screening</th>
<th>test RMSE before [K]</th><th>after [K]</th><th>ΔBIC</th><th>reason</th></tr>{rows}</table>
<h2>Evidence for accepted findings</h2>{evidence or "<p>None accepted.</p>"}
<h2>Evidence across rolling folds</h2>{folds or _no_folds(d)}
<h2>Residual whiteness (Ljung–Box, hourly one-step-ahead errors, 24 lags)</h2>
<p>Before: Q = {white["baseline"]["q"]:.0f},
lag-1 h autocorrelation {white["baseline"]["rho_1h"]:.2f};
after: Q = {white["final"]["q"]:.0f},
lag-1 h autocorrelation {white["final"]["rho_1h"]:.2f}.</p>
<h2>Candidates not built</h2><ul>{skipped or "<li>none</li>"}</ul>
<p><small>rcengine diagnose, {report.wall_time_s:.1f} s.</small></p>
</body></html>"""
