"""The promotion gate: checks a fitted set must pass to become current, whatever the held-out
comparison with the current set says.

A stuck sensor (flat ``t_in``), a heating that never changes (nothing to identify the heating
response from), a fit whose parameters mostly ended on their bounds, a set that forecasts the
held-out day worse than persistence (tomorrow = the last measured temperature), or predictions
that are not finite or leave the physically possible range: each is a degenerate fit that a
held-out day just as degenerate can score well. Each check has a name; a refused calibration's
job names the checks that refused it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from rcengine.columns import COLUMNS, Q_HVAC, T_IN
from rcengine.diagnose.health import OnBound
from rcengine.metrics import rmse
from rcengine.parameter_set import ParameterSet
from rcengine.record import MIN_T_IN_STD_K, t_in_spread


@dataclass(frozen=True)
class GateLimits:
    """Where degenerate starts. [K, W, share]"""

    # Standard deviation of the measured t_in over the training rows below which it is flat.
    min_t_in_std_k: float = MIN_T_IN_STD_K
    # Range of q_hvac over the training rows below which the heating never changed.
    min_q_hvac_range_w: float = 1.0
    # Share of the free parameters on a bound above which the fit is pinned by its bounds.
    max_share_on_bounds: float = 0.5


@dataclass(frozen=True)
class Check:
    """One check of the gate: its name, whether it passed, and what it measured."""

    name: str
    passed: bool
    message: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Verdict:
    checks: tuple[Check, ...]

    @property
    def passed(self) -> bool:
        return all(check.passed for check in self.checks)

    @property
    def refused_by(self) -> list[str]:
        return [check.name for check in self.checks if not check.passed]

    def reason(self) -> str:
        """Why the gate refused, one clause per failed check."""
        failed = "; ".join(f"{c.name}: {c.message}" for c in self.checks if not c.passed)
        return f"refused by the promotion gate ({failed})"

    def to_dict(self) -> dict[str, Any]:
        return {
            "passed": self.passed,
            "refused_by": self.refused_by,
            "checks": [check.to_dict() for check in self.checks],
        }


def judge(
    pset: ParameterSet,
    training: pd.DataFrame,
    holdout: pd.DataFrame,
    predicted: np.ndarray,
    limits: GateLimits = GateLimits(),
) -> Verdict:
    """Every check on a set fitted on ``training`` whose day-ahead forecast of the ``holdout``
    rows (measured ``t_in``) is ``predicted``. [°C]"""
    return Verdict(
        (
            _t_in_varies(training, limits),
            _heating_excites(training, limits),
            _inside_bounds(pset, limits),
            _predictions_plausible(predicted),
            _beats_persistence(training, holdout, predicted),
        )
    )


def _t_in_varies(training: pd.DataFrame, limits: GateLimits) -> Check:
    spread = t_in_spread(training)
    return Check(
        "t_in_varies",
        spread >= limits.min_t_in_std_k,
        f"measured t_in varies by {spread:.3f} K (standard deviation; at least "
        f"{limits.min_t_in_std_k:g} K needed: a flat series is a stuck sensor)",
    )


def _heating_excites(training: pd.DataFrame, limits: GateLimits) -> Check:
    q = training[Q_HVAC].to_numpy(dtype=float)
    spread = float(np.nanmax(q) - np.nanmin(q)) if np.isfinite(q).any() else 0.0
    return Check(
        "heating_excites",
        spread >= limits.min_q_hvac_range_w,
        f"q_hvac spans {spread:g} W over the training days (at least "
        f"{limits.min_q_hvac_range_w:g} W needed to identify the heating's effect)",
    )


def _inside_bounds(pset: ParameterSet, limits: GateLimits) -> Check:
    at_bounds = list(pset.fit.get("at_bounds", []))
    idle = [name for name in at_bounds if _resting_at_zero(pset, name)]
    pinned = [name for name in at_bounds if name not in idle]
    share = len(pinned) / max(len(pset.values), 1)
    resting = f"; resting at zero, not counted: {', '.join(idle)}" if idle else ""
    return Check(
        "parameters_inside_bounds",
        share <= limits.max_share_on_bounds,
        f"{len(pinned)} of {len(pset.values)} parameters ended on a bound "
        f"({', '.join(pinned) or 'none'}; at most {limits.max_share_on_bounds:.0%} allowed)"
        + resting,
    )


def _resting_at_zero(pset: ParameterSet, name: str) -> bool:
    """Whether ``name``, one of the fit's parameters on a bound, is a magnitude that cannot be
    negative (a gain, a g-value, an absorptance, an air change rate: its lower bound is zero) and
    ended at zero (``OnBound.physical_none``). Such a parameter says its effect was idle over the
    training days (no plug loads in a holiday fortnight, no sun through a facade's glass), not
    that the search box pinned the fit."""
    parameter = pset.network.parameters.get(name)
    if parameter is None:
        return False
    return OnBound(name, pset.values[name], parameter.lower, parameter.upper).physical_none


def _predictions_plausible(predicted: np.ndarray) -> Check:
    low, high = COLUMNS[T_IN].lower, COLUMNS[T_IN].upper
    finite = np.isfinite(predicted)
    inside = finite & (predicted >= low) & (predicted <= high)
    shown = predicted[~inside][:1]
    return Check(
        "predictions_plausible",
        bool(inside.all()) and predicted.size > 0,
        f"{int((~inside).sum())} of {predicted.size} held-out predictions are not finite or "
        f"outside [{low:g}, {high:g}] °C" + (f", e.g. {shown[0]:g}" if shown.size else ""),
    )


def _beats_persistence(
    training: pd.DataFrame, holdout: pd.DataFrame, predicted: np.ndarray
) -> Check:
    """No worse than "the day ahead stays at the last measured t_in" on the held-out day."""
    measured = holdout[T_IN].to_numpy(dtype=float)
    last = training[T_IN].dropna()
    if last.empty or not np.isfinite(measured).any():
        return Check("beats_persistence", False, "no measured t_in to compare with")
    persistence = rmse(measured, np.full_like(measured, last.iloc[-1]))
    model = rmse(measured, predicted) if np.isfinite(predicted).all() else np.inf
    return Check(
        "beats_persistence",
        bool(model <= persistence),
        f"held-out RMSE {model:.3f} K against persistence's {persistence:.3f} K",
    )
