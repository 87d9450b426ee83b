"""Derived input signals: model inputs computed from the contract columns and the building.

A network's inputs are contract columns (``t_out``, ``ghi``, ``q_hvac`` …) or derived signals
named here. ``prepare`` is the one bridge from a validated frame to the dataset a network
simulates, used by the CLI, the study and the service alike.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass

import pandas as pd

from .building import Building
from .columns import NUMERIC_COLUMNS
from .dataset import Dataset
from .exceptions import ModelError


@dataclass(frozen=True)
class SignalOptions:
    """How derived signals are computed (stored with a parameter set so forecasts match fits).

    sky_model: "isotropic" (thesis Eq. 16–17), "perez" or "haydavies"; albedo: ground reflectance
    or None to neglect reflection; iam_model: glazing incidence-angle modifier; decomposition:
    ghi → dni/dhi model when those columns are absent.
    """

    sky_model: str = "isotropic"
    albedo: float | None = None
    iam_model: str = "physical"
    decomposition: str = "erbs"

    def to_dict(self) -> dict:
        return asdict(self)


Deriver = Callable[[pd.DataFrame, Building, SignalOptions], pd.DataFrame]


def _solar(frame: pd.DataFrame, building: Building, options: SignalOptions) -> pd.DataFrame:
    from .solar import solar_gains

    return solar_gains(
        frame,
        building,
        sky_model=options.sky_model,
        albedo=options.albedo,
        iam_model=options.iam_model,
        decomposition=options.decomposition,
    )


# Prefix of a derived signal name → the function computing every signal of that family.
DERIVERS: dict[str, Deriver] = {"solar_": _solar}


def register(prefix: str, deriver: Deriver) -> None:
    """Make signals named ``prefix…`` derivable (used by the mismatch diagnosis)."""
    DERIVERS[prefix] = deriver


def derive(
    frame: pd.DataFrame, building: Building, names: Iterable[str], options: SignalOptions
) -> pd.DataFrame:
    """Compute the requested derived signals (columns already in ``frame`` are left alone)."""
    wanted = [n for n in dict.fromkeys(names) if n not in frame.columns]
    out = pd.DataFrame(index=frame.index)
    for prefix, deriver in DERIVERS.items():
        family = [n for n in wanted if n.startswith(prefix)]
        if not family:
            continue
        computed = deriver(frame, building, options)
        missing = [n for n in family if n not in computed.columns]
        if missing:
            raise ModelError(f"cannot derive signal(s) {missing}; available: {list(computed)}")
        out = out.join(computed[family])
    unknown = [n for n in wanted if n not in out.columns]
    if unknown:
        absent = [n for n in unknown if n in NUMERIC_COLUMNS]
        why = (
            f"column(s) {absent} are absent from the data"
            if absent
            else f"signal(s) {unknown} are neither data columns nor derivable"
        )
        raise ModelError(f"the model needs inputs the data cannot give: {why}")
    return out


def prepare(
    frame: pd.DataFrame,
    building: Building,
    inputs: Iterable[str],
    options: SignalOptions | None = None,
    step_s: float | None = None,
) -> Dataset:
    """Dataset holding the contract columns plus every derived signal in ``inputs``."""
    options = options or SignalOptions()
    extra = derive(frame, building, inputs, options)
    data = Dataset.from_frame(frame, step_s)
    return data.with_columns(extra) if len(extra.columns) else data
