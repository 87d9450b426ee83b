"""The test half forecast one day at a time, as the service forecasts for an MPC.

A diagnosis judges each candidate on the open-loop simulation of its whole test half (months
carried on from the training rows' state: ``fitting.carried_on``), which weighs the slow drifts
a grey-box model makes over weeks. An MPC instead receives a forecast of the next 24 hours from
the state a Kalman filter reads from the last measurements (``rcengine.forecast``). Here every
local midnight of the test half starts such a forecast — the filter over the preceding
``DEFAULT_HISTORY_H`` hours, the model's inputs over the horizon — and the errors of all of them
are pooled: the figure the served model would have had over those days, for the base model and
the final one (the report's ``day_ahead`` block).

The air-exchange losses are linearised at the measured t_in, as in the diagnosis's own test
simulations (``signals.derived.indoor_operating_point``); the service linearises them at its own
forecast instead (``forecast.forecast_frame``). Reported, not judged on: run as a judge beside
the open-loop test over the dev pool of the test bed (nineteenth session), a candidate's cut of
the day-ahead RMSE did not separate concealed effects from what null cases' candidates fit
(docs/diagnosis.md, "What the data cannot tell").
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.dataset import Dataset
from rcengine.diagnose.fitting import Fit, Split
from rcengine.exceptions import DataValidationError
from rcengine.forecast import DEFAULT_HISTORY_H, forecast
from rcengine.network import RCNetwork

# The MPC's horizon. [h]
HORIZON_H = 24.0


def day_ahead_errors(
    network: RCNetwork,
    params: dict[str, float],
    split: Split,
    timezone: str,
    horizon_h: float = HORIZON_H,
    history_h: float = DEFAULT_HISTORY_H,
) -> tuple[np.ndarray, int]:
    """measured − forecast t_in over ``split.test`` [K] of ``network`` with ``params``, each
    forecast starting at a local midnight of the test rows (the day's first row within a step of
    it) and running ``horizon_h`` hours (NaN where unmeasured), and the number of days forecast.
    A day without a measurement in the step before its start, or whose horizon runs past the
    record, is skipped."""
    train, test = split.train, split.test
    whole = Dataset(pd.concat([train.frame, test.frame]), test.step_s, test.hold)
    compiled = network.compile()
    step = pd.Timedelta(seconds=test.step_s)
    local = test.times.tz_convert(timezone)
    day = local.normalize()
    # A record whose rows are stamped off the hour (SYSLAB's at :11, :26, ...) has no row at
    # midnight: each day starts at its row within one step after it.
    starts = test.times[~day.duplicated() & ((local - day) < step)]
    horizon = pd.Timedelta(hours=horizon_h)
    errors, days = [], 0
    for start in starts:
        if start + horizon > test.times[-1] + step:
            continue
        try:
            predicted = forecast(compiled, params, whole, start, horizon_h, history_h)
        except DataValidationError:
            continue
        measured = whole.frame["t_in"].reindex(predicted.times).to_numpy(dtype=float)
        errors.append(measured - predicted.t_in_pred)
        days += 1
    return (np.concatenate(errors) if errors else np.zeros(0)), days


def day_ahead_block(baseline: Fit, final: Fit, timezone: str) -> dict:
    """The report's ``day_ahead``: pooled RMSE [K] of the base and final models' day-ahead
    forecasts over the test half's days."""
    rmse_baseline, days = _pooled_rmse(baseline, timezone)
    rmse_final = rmse_baseline if final is baseline else _pooled_rmse(final, timezone)[0]
    return {
        "horizon_h": HORIZON_H,
        "history_h": DEFAULT_HISTORY_H,
        "rmse_baseline": rmse_baseline,
        "days": days,
        "rmse_final": rmse_final,
    }


def _pooled_rmse(fit: Fit, timezone: str) -> tuple[float | None, int]:
    errors, days = day_ahead_errors(fit.network, fit.params, fit.split, timezone)
    errors = errors[np.isfinite(errors)]
    return (float(np.sqrt(np.mean(errors**2))) if errors.size else None), days
