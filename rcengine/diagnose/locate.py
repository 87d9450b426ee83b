"""Where and when model and recordings differ.

Residual = measured − simulated (positive: the model under-predicts the indoor temperature).
Both the open-loop simulation errors and the one-step-ahead Kalman innovations are cut by hour
of day × day of week, by operating condition (HVAC on/off, sunny/overcast, windy/calm, cold/mild)
and into the worst days, and the strongest pattern is put in words.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import GHI, Q_HVAC, T_OUT, WIND_SPEED

DAYS = ["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"]
# Below this mean error [K] a pattern is not worth a sentence.
NOTABLE_K = 0.1


def conditions(
    frame: pd.DataFrame, building: Building
) -> dict[str, tuple[str, str, np.ndarray, np.ndarray]]:
    """Row masks of contrasting conditions: name → (label_a, label_b, mask_a, mask_b)."""
    from rcengine.signals.solar import clear_sky_ghi

    out: dict[str, tuple[str, str, np.ndarray, np.ndarray]] = {}
    q = frame[Q_HVAC].to_numpy(dtype=float)
    scale = np.nanpercentile(np.abs(q), 99) if np.any(q != 0) else 0.0
    if scale > 0:
        on = np.abs(q) > 0.02 * scale
        out["hvac"] = ("HVAC on", "HVAC off", on, ~on)
    clear = clear_sky_ghi(frame.index, building.location)
    day = clear > 50.0
    index = np.where(day, frame[GHI].to_numpy(dtype=float) / np.maximum(clear, 1.0), np.nan)
    out["sun"] = ("sunny", "overcast", day & (index > 0.6), day & (index < 0.3))
    if WIND_SPEED in frame.columns and frame[WIND_SPEED].notna().any():
        w = frame[WIND_SPEED].to_numpy(dtype=float)
        lo, hi = np.nanpercentile(w, [25, 75])
        out["wind"] = ("windy", "calm", w >= max(hi, lo + 1e-9), w <= lo)
    t = frame[T_OUT].to_numpy(dtype=float)
    lo, hi = np.nanpercentile(t, [25, 75])
    out["temperature"] = ("cold", "mild", t <= lo, t >= hi)
    return out


def _stats(resid: np.ndarray, mask: np.ndarray) -> dict[str, float]:
    r = resid[mask & np.isfinite(resid)]
    if r.size == 0:
        return {"mean_K": float("nan"), "rmse_K": float("nan"), "share": 0.0}
    return {
        "mean_K": float(r.mean()),
        "rmse_K": float(np.sqrt(np.mean(r**2))),
        "share": float(r.size / max(1, np.isfinite(resid).sum())),
    }


def hour_weekday(resid: np.ndarray, times: pd.DatetimeIndex, timezone: str) -> np.ndarray:
    """Mean residual per (weekday, hour) in local time, shape (7, 24); NaN where no data."""
    local = times.tz_convert(timezone)
    frame = pd.DataFrame({"r": resid, "d": local.day_of_week, "h": local.hour})
    table = frame.pivot_table(index="d", columns="h", values="r", aggfunc="mean")
    return table.reindex(index=range(7), columns=range(24)).to_numpy()


def hour_window(profile: np.ndarray) -> tuple[int, int, float] | None:
    """The contiguous hours around the largest |mean residual| with the same sign and at least
    half its size: (first hour, end hour, mean over the window)."""
    if not np.isfinite(profile).any():
        return None
    p = np.nan_to_num(profile)
    peak = int(np.argmax(np.abs(p)))
    if abs(p[peak]) < NOTABLE_K:
        return None
    sign, start, end = np.sign(p[peak]), peak, peak + 1
    while start > 0 and np.sign(p[start - 1]) == sign and abs(p[start - 1]) >= 0.5 * abs(p[peak]):
        start -= 1
    while end < 24 and np.sign(p[end]) == sign and abs(p[end]) >= 0.5 * abs(p[peak]):
        end += 1
    return start, end, float(p[start:end].mean())


def worst_days(resid: np.ndarray, frame: pd.DataFrame, timezone: str, count: int = 5) -> list[dict]:
    local_day = frame.index.tz_convert(timezone).date
    table = pd.DataFrame(
        {
            "r": resid,
            "day": local_day,
            "t_out": frame[T_OUT].to_numpy(),
            "ghi": frame[GHI].to_numpy(),
        }
    )
    # A day bridged whole (``bridge_short_gaps``) has no measured row to rank it by.
    daily = (
        table.dropna(subset=["r"])
        .groupby("day")
        .agg(
            rmse=("r", lambda r: float(np.sqrt(np.mean(r**2)))),
            mean=("r", "mean"),
            t_out=("t_out", "mean"),
            ghi=("ghi", "mean"),
        )
    )
    daily = daily.dropna().sort_values("rmse", ascending=False).head(count)
    return [
        {
            "date": str(day),
            "weekday": DAYS[pd.Timestamp(day).day_of_week],
            "rmse_K": row.rmse,
            "mean_residual_K": row["mean"],
            "t_out_mean_C": row.t_out,
            "ghi_mean_W_m2": row.ghi,
        }
        for day, row in daily.iterrows()
    ]


RESIDUAL_WORDS = ("the model", "under-predicts", "over-predicts")


def summarize(
    resid: np.ndarray,
    frame: pd.DataFrame,
    building: Building,
    words_for: tuple[str, str, str] = RESIDUAL_WORDS,
) -> dict:
    """The mismatch block of the report for one residual series (or, with other ``words_for``
    = (subject, verb if positive, verb if negative), any other series in kelvin)."""
    subject, rises, falls = words_for
    tz = building.location.timezone
    grid = hour_weekday(resid, frame.index, tz)
    profile = np.nanmean(grid, axis=0)
    cond = conditions(frame, building)
    by_condition = {
        name: {a: _stats(resid, ma), b: _stats(resid, mb)} for name, (a, b, ma, mb) in cond.items()
    }
    words = []
    overall = float(np.nanmean(resid))
    window = hour_window(profile)
    if window is not None:
        start, end, mean = window
        verb = rises if mean > 0 else falls
        words.append(f"{verb} {start:02d}:00–{end:02d}:00 by {abs(mean):.2f} K on average")
    contrasts = []
    for _name, (a, b, _ma, _mb) in cond.items():
        sa, sb = by_condition[_name][a], by_condition[_name][b]
        if np.isfinite(sa["mean_K"]) and np.isfinite(sb["mean_K"]):
            contrasts.append((abs(sa["mean_K"] - sb["mean_K"]), a, sa["mean_K"], b, sb["mean_K"]))
    if contrasts:
        gap, a, ma, b, mb = max(contrasts)
        if gap >= NOTABLE_K:
            words.append(
                f"most when {a if abs(ma) > abs(mb) else b} ({ma:+.2f} K {a} vs {mb:+.2f} K {b})"
            )
    if abs(overall) >= NOTABLE_K:
        words.append(f"overall bias {overall:+.2f} K")
    summary = "; ".join(words) if words else "no notable pattern in the errors"
    return {
        "summary": f"{subject} {summary}" if words else summary,
        "mean_residual_K": overall,
        "hour_of_day_mean_K": profile.tolist(),
        "hour_weekday_mean_K": grid.tolist(),
        "by_condition": by_condition,
        "worst_days": worst_days(resid, frame, tz),
    }
