"""What a learnt gain is worth while the heater is off: the hours that tell a missing gain from
a heater whose heat the model delivers at the wrong time.

While the heater holds the set point, a gain on the occupied hours shows only in the heat the
heater no longer gives; a lower envelope conductance asks the same of the training weeks, and
a gain on the hours the heater starts stands in as well for what an emitter's lag leaves of its
heat. With the heater off long enough for an emitter's stored heat to have gone, neither
stands in: the gain's heat raises the room directly, and a stand-in for the heater's timing only
warms a room it does not heat. A gain the rolling folds rejected is judged again over the season
(``selection._gains_over_the_season``) only where it forecasts those hours better.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rcengine.columns import Q_HVAC
from rcengine.diagnose.fitting import Fit

# Hours the heater must have been off before a row counts as free of its heat. A hydronic
# emitter's water and metal release what they hold within about an hour (radiators' time
# constants are 0.3–1 h, EN 442-2); three hours leave a floor heating's screed the most of it.
OFF_FOR_H = 3.0

# Fewest such hours, on the gain's own schedule, over the held-out blocks: one working day's.
MIN_OFF_HOURS = 8.0


def off_rows(frame: pd.DataFrame, off_for_h: float = OFF_FOR_H) -> pd.Series:
    """Per row (by time), whether the heater output ``q_hvac`` [W] has been zero (no heating)
    over the last ``off_for_h`` hours, the row itself included; the first row, without a
    history, is not."""
    if Q_HVAC not in frame.columns:
        return pd.Series(False, index=frame.index)
    heating = pd.Series(np.nan_to_num(frame[Q_HVAC].to_numpy(dtype=float)) > 0.0, frame.index)
    recent = heating.astype(float).rolling(pd.Timedelta(hours=off_for_h)).max()
    return (recent == 0.0) & (np.arange(len(frame)) > 0)


def heater_off_change(
    current: list[Fit], extended: list[Fit], signal: str, heater_off: pd.Series
) -> dict | None:
    """The test RMSE [K] of the ``current`` model and of the ``extended`` one (with the gain),
    pooled over the held-out blocks' test rows where the gain's input ``signal`` is on and the
    heater has been off ``OFF_FOR_H`` hours (``heater_off``: ``off_rows`` of the whole record,
    by time, so that a block's first hours are read with the heat given before the block
    began); None where those rows add up to fewer than ``MIN_OFF_HOURS``."""
    before, after = [], []
    hours = 0.0
    for c, e in zip(current, extended, strict=True):
        test = e.split.test
        frame = test.frame
        off = heater_off.reindex(frame.index, fill_value=False).to_numpy(dtype=bool)
        rows = off & (np.nan_to_num(frame[signal].to_numpy(dtype=float)) > 0.0)
        rows &= np.isfinite(c.residual_test) & np.isfinite(e.residual_test)
        before.append(c.residual_test[rows])
        after.append(e.residual_test[rows])
        hours += rows.sum() * test.step_s / 3600.0
    if hours < MIN_OFF_HOURS:
        return None
    b, a = np.concatenate(before), np.concatenate(after)
    return {
        "signal": signal,
        "hours": hours,
        "rmse_before": float(np.sqrt(np.mean(b**2))),
        "rmse_after": float(np.sqrt(np.mean(a**2))),
    }
