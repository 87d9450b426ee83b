"""Analysis of a finished study: the thesis's tables, the summary (averages, headline figures,
estimation times), the Sun-versus-Basic comparison by sky and weekday, and the free-floating
validation of thesis §3.3."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.building import Building
from rcengine.columns import GHI, SOLAR_OPAQUE, SOLAR_WINDOW, T_IN
from rcengine.estimation import Estimator, EstimatorSettings
from rcengine.forecast import forecast
from rcengine.metrics import evaluate
from rcengine.models import get_model
from rcengine.study.run import StudySettings, prepared


def tables(results: pd.DataFrame, settings: StudySettings) -> dict[str, pd.DataFrame]:
    """The thesis's three tables per model and period: parameters, training RMSE (one column per
    learning length) and validation RMSE (learning length × horizon, 12 columns)."""
    out = {"parameters": results}
    for (model, period), group in results.groupby(["model", "period"]):
        train = group.pivot(index="day", columns="learn_days", values="rmse_train")
        train.columns = [f"learn_{c}d" for c in train.columns]
        out[f"training_rmse_{model}_{period}"] = train
        cols = {}
        for learn in settings.learn_days:
            sub = group[group.learn_days == learn].set_index("day")
            for h in settings.horizons:
                cols[f"learn_{learn}d_predict_{h}d"] = sub[f"rmse_h{h}"]
        out[f"validation_rmse_{model}_{period}"] = pd.DataFrame(cols)
    return out


def summary(results: pd.DataFrame, settings: StudySettings) -> dict:
    """Average RMSE per model, period, learning length and horizon, the persistence forecast's on
    the same days, and the estimation times (wall and CPU) per model and learning length."""
    avg: dict = {}
    for (model, period, learn), group in results.groupby(["model", "period", "learn_days"]):
        entry = avg.setdefault(model, {}).setdefault(period, {})
        entry[f"learn_{learn}d"] = {
            f"predict_{h}d": float(group[f"rmse_h{h}"].mean()) for h in settings.horizons
        }
        entry[f"learn_{learn}d"]["train"] = float(group["rmse_train"].mean())
    long = results[results.learn_days >= 3]
    headline = {}
    for (model, period), g in long.groupby(["model", "period"]):
        days = g.drop_duplicates("day")
        headline[f"{model}_{period}"] = {
            **{f"rmse_{h}d_learn_ge_3d": float(g[f"rmse_h{h}"].mean()) for h in settings.horizons},
            **{
                f"persistence_{h}d": float(days[f"rmse_persistence_h{h}"].mean())
                for h in settings.horizons
            },
            "rmse_1d_heating_on": float(g["rmse_day1_heating_on"].mean()),
            "rmse_1d_heating_off": float(g["rmse_day1_heating_off"].mean()),
            "days": len(days),
        }
    return {
        "settings": {
            "models": list(settings.models),
            "periods": list(settings.periods),
            "learn_days": list(settings.learn_days),
            "horizons": list(settings.horizons),
            "preset": settings.preset
            if isinstance(settings.preset, str)
            else repr(settings.preset),
            "first_day": results["day"].min() if len(results) else None,
            "last_day": results["day"].max() if len(results) else None,
        },
        "average_rmse": avg,
        "headline": headline,
        "estimation_wall_s": _per_learning(results, "wall_s"),
        "estimation_cpu_s": _per_learning(results, "cpu_s"),
        "trainings": len(results),
    }


def _per_learning(results: pd.DataFrame, column: str) -> dict:
    """Mean of ``column`` per model and learning length (thesis Table 3.1)."""
    return {
        model: {
            f"learn_{learn}d": float(g[column].mean()) for learn, g in group.groupby("learn_days")
        }
        for model, group in results.groupby("model")
    }


# Daily clearness index (Σ ghi / Σ clear-sky ghi) separating overcast, mixed and sunny days.
SKY_CLASSES = ((0.0, 0.4, "overcast"), (0.4, 0.7, "mixed"), (0.7, np.inf, "sunny"))


def daily_clearness(frame: pd.DataFrame, building: Building) -> pd.Series:
    """Clearness index of each local day, Σ ghi / Σ clear-sky ghi (Ineichen–Perez), indexed by
    ISO date. [-]"""
    from rcengine.signals.solar import clear_sky_ghi

    local_day = frame.index.tz_convert(building.location.timezone).normalize()
    clear = pd.Series(clear_sky_ghi(frame.index, building.location), index=frame.index)
    index = frame[GHI].groupby(local_day).sum() / clear.groupby(local_day).sum()
    return pd.Series(index.to_numpy(), index=index.index.strftime("%Y-%m-%d"))


def sky_class(clearness: float) -> str:
    return next(name for low, high, name in SKY_CLASSES if low <= clearness < high)


def _paired(results: pd.DataFrame, horizons: tuple[int, ...]) -> pd.DataFrame:
    """Basic and Sun RMSE side by side per (period, day, learning length); ``diff_h*`` = Basic −
    Sun, positive where the Sun model forecast better."""
    key = ["period", "day", "learn_days"]
    cols = [f"rmse_h{h}" for h in horizons]
    basic = results.loc[results.model == "basic", [*key, "weekday", *cols]]
    sun = results.loc[results.model == "sun", [*key, *cols]]
    both = basic.merge(sun, on=key, suffixes=("_basic", "_sun"))
    for h in horizons:
        both[f"diff_h{h}"] = both[f"rmse_h{h}_basic"] - both[f"rmse_h{h}_sun"]
    return both


def _diff_stats(group: pd.DataFrame, horizons: tuple[int, ...]) -> dict:
    out: dict = {"pairs": len(group)}
    for h in horizons:
        d = group[f"diff_h{h}"]
        out[f"basic_{h}d"] = float(group[f"rmse_h{h}_basic"].mean())
        out[f"sun_{h}d"] = float(group[f"rmse_h{h}_sun"].mean())
        out[f"diff_{h}d"] = float(d.mean())
        # Neighbouring days share training data, so this standard error is a lower bound.
        out[f"diff_{h}d_se"] = float(d.std(ddof=1) / np.sqrt(len(d))) if len(d) > 1 else None
        out[f"sun_better_share_{h}d"] = float((d > 0).mean())
    return out


def sun_vs_basic(
    results: pd.DataFrame, clearness: pd.Series, horizons: tuple[int, ...] = (1, 3, 7)
) -> dict:
    """Does the Sun model help? Paired Basic − Sun RMSE differences on the same days by period and
    learning length, by the sky of the first predicted day and by weekday (≥ 3 learning days),
    and the fitted absorption parameters of both models. Empty without both models."""
    if not {"basic", "sun"} <= set(results.model):
        return {}
    pairs = _paired(results, horizons)
    pairs["sky"] = pairs["day"].map(clearness).map(sky_class)
    long = pairs[pairs.learn_days >= 3]
    fitted = results[results.learn_days >= 3]
    return {
        "difference": "basic − sun [°C]; positive: the Sun model forecast better",
        "by_learning": {
            period: {
                f"learn_{learn}d": _diff_stats(g, horizons) for learn, g in pg.groupby("learn_days")
            }
            for period, pg in pairs.groupby("period")
        },
        "by_sky_learn_ge_3d": {
            period: {
                sky: _diff_stats(pg[pg.sky == sky], horizons)
                for _, _, sky in SKY_CLASSES
                if (pg.sky == sky).any()
            }
            for period, pg in long.groupby("period")
        },
        "by_weekday_learn_ge_3d": {
            period: {day: _diff_stats(g, horizons) for day, g in pg.groupby("weekday")}
            for period, pg in long.groupby("period")
        },
        "absorption_quartiles_learn_ge_3d": {
            model: {
                name: [float(v) for v in g[name].quantile([0.25, 0.5, 0.75])]
                for name in ("alpha_wall", "alpha_int")
            }
            for model, g in fitted.groupby("model")
        },
    }


def solar_signal_correlation(frame: pd.DataFrame, building: Building) -> dict:
    """Correlation of the Basic model's solar input (ghi) with the Sun model's geometric ones,
    per timestep and per daily mean: how much the geometry can add beyond a scale factor. [-]"""
    signals = prepared(frame, building, "sun").frame[[GHI, SOLAR_WINDOW, SOLAR_OPAQUE]]
    daily = signals.groupby(signals.index.tz_convert(building.location.timezone).date).mean()
    return {
        f"{step}_{name}": float(table[GHI].corr(table[name]))
        for step, table in (("step", signals), ("daily", daily))
        for name in (SOLAR_WINDOW, SOLAR_OPAQUE)
    }


def free_floating(
    frame: pd.DataFrame,
    building: Building,
    model: str = "basic",
    learn_days: int = 12,
    predict_days: int = 12,
    start: str = "2017-02-01",
    preset: str | EstimatorSettings = "study",
    criterion: str = "output_error",
) -> dict:
    """Thesis §3.3: learn on the ``learn_days`` before ``start`` of a free-floating record (by the
    estimator's ``criterion``) and predict ``predict_days``; RMSE, MBE, NMBE ("MBS"), CV(RMSE)
    and ASHRAE Guideline 14."""
    data = prepared(frame, building, model)
    tz = building.location.timezone
    day0 = pd.Timestamp(start).tz_localize(tz)
    train = data.between(day0 - pd.Timedelta(days=learn_days), day0)
    net = get_model(model, building, frame.columns)
    est = Estimator(net, preset=preset, random_state=0, criterion=criterion, warn_bounds=False).fit(
        train
    )
    fc = forecast(est.compiled, est.params_, data, day0, hours=24 * predict_days, noise=est.noise_)
    measured = data.frame[T_IN].reindex(fc.times).to_numpy(dtype=float)
    metrics = evaluate(measured, fc.t_in_pred).to_dict()
    return {
        "model": model,
        "learn_days": learn_days,
        "predict_days": predict_days,
        "start": day0.isoformat(),
        "metrics": metrics,
        "params": est.params_,
        "times": fc.times,
        "predicted": fc.t_in_pred,
        "measured": measured,
    }
