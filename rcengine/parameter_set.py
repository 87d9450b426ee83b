"""A calibrated parameter set and its ``params.json``: everything needed to forecast again.

The file holds the network itself (not only its name), so extended models such as
``basic+window_solar_gains`` from the mismatch diagnosis reload exactly; the building and the
signal options, so derived inputs (solar gains) are recomputed the same way; the parameter
values with units and bounds; the fit window, metrics and engine version.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pandas as pd

from rcengine import __version__
from rcengine.building import Building
from rcengine.dataset import Dataset
from rcengine.estimation.estimator import Estimator
from rcengine.exceptions import ModelError
from rcengine.io.files import write_text_atomic
from rcengine.io.jsonable import jsonable, read_json
from rcengine.kalman import Noise
from rcengine.metrics import evaluate
from rcengine.network import CompiledNetwork, RCNetwork
from rcengine.signals import SignalOptions, prepare

FORMAT_VERSION = 1


@dataclass(frozen=True)
class ParameterSet:
    """A fitted model: the ``network`` of ``model`` and its parameter ``values`` (by name, in
    the parameters' units), the ``building`` and the ``signals`` options it was fitted with, and
    its provenance: ``fit`` (training window, estimator settings, cost and effort, initial
    states; the noise model of a likelihood fit), ``metrics`` ("train"; "holdout" once scored on
    a held-out day), ``engine_version`` and ``created_at`` (UTC, ISO 8601)."""

    model: str
    network: RCNetwork
    values: dict[str, float]
    building: Building
    signals: SignalOptions = field(default_factory=SignalOptions)
    fit: dict[str, Any] = field(default_factory=dict)
    metrics: dict[str, Any] = field(default_factory=dict)
    engine_version: str = __version__
    created_at: str = field(default_factory=lambda: datetime.now(UTC).isoformat())

    @property
    def compiled(self) -> CompiledNetwork:
        return self.network.compile()

    @property
    def noise(self) -> Noise | None:
        """The noise model fitted by maximum likelihood, None for an output-error fit."""
        if "noise" not in self.fit:
            return None
        try:
            return Noise.from_dict(self.fit["noise"], self.network.states)
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelError(f"invalid noise model in the parameter file: {exc}") from exc

    @classmethod
    def from_estimator(
        cls,
        estimator: Estimator,
        data: Dataset,
        building: Building,
        model: str,
        signals: SignalOptions | None = None,
    ) -> ParameterSet:
        """Collect a fitted estimator's results with its training window and metrics."""
        net = estimator.compiled
        fit = {
            "start": data.times[0].isoformat(),
            "end": (data.times[-1] + pd.Timedelta(seconds=data.step_s)).isoformat(),
            "step_s": data.step_s,
            "rows": len(data),
            "segments": len(data.segments),
            "preset": estimator.preset if isinstance(estimator.preset, str) else "custom",
            "criterion": estimator.criterion,
            "cost": estimator.cost,
            "cost_value": estimator.cost_,
            "random_state": estimator.random_state
            if isinstance(estimator.random_state, int | None)
            else None,
            "n_simulations": estimator.n_simulations_,
            "wall_time_s": estimator.wall_time_s_,
            "at_bounds": estimator.at_bounds_,
            "polish": estimator.polish_,
            "initial_states": {
                "nodes": list(net.state_names),
                "per_segment": [s.tolist() for s in estimator.initial_states_],
            },
        }
        if estimator.likelihood_ is not None:
            fit["noise"] = estimator.noise_.to_dict(net.state_names)
            fit["likelihood"] = estimator.likelihood_.to_dict()
        metrics = {"train": evaluate(data.measured, estimator.trajectory_.y).to_dict()}
        return cls(
            model=model,
            network=net.network,
            values=dict(estimator.params_),
            building=building,
            signals=signals or SignalOptions(),
            fit=fit,
            metrics=metrics,
        )

    def prepare(self, frame: pd.DataFrame) -> Dataset:
        """The dataset this model simulates: contract columns plus its derived signals."""
        return prepare(frame, self.building, self.compiled.input_names, self.signals)

    # --- JSON -----------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        compiled = self.compiled
        return {
            "format_version": FORMAT_VERSION,
            "engine_version": self.engine_version,
            "created_at": self.created_at,
            "model": self.model,
            "parameters": {
                p.name: {
                    "value": self.values[p.name],
                    "unit": p.unit,
                    "lower": p.lower,
                    "upper": p.upper,
                    "description": p.description,
                }
                for p in compiled.parameters.values()
            },
            "inputs": list(compiled.input_names),
            "states": list(compiled.state_names),
            "fit": self.fit,
            "metrics": self.metrics,
            "signals": self.signals.to_dict(),
            "building": self.building.to_dict(),
            "network": self.network.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ParameterSet:
        try:
            network = RCNetwork.from_dict(data["network"])
            if not isinstance(data["parameters"], dict):
                raise TypeError("'parameters' must be an object {name: {value, ...}}")
            values = {name: float(p["value"]) for name, p in data["parameters"].items()}
            return cls(
                model=data["model"],
                network=network,
                values=values,
                building=Building.from_dict(data["building"]),
                signals=SignalOptions.from_stored(data.get("signals", {})),
                fit=data.get("fit", {}),
                metrics=data.get("metrics", {}),
                engine_version=data.get("engine_version", "unknown"),
                created_at=data.get("created_at", ""),
            )
        except KeyError as exc:
            raise ModelError(f"invalid parameter file: {_missing_entry(data, exc)}") from exc
        except (TypeError, ValueError) as exc:
            raise ModelError(f"invalid parameter file: {exc}") from exc

    def save(self, path: str | Path) -> None:
        write_text_atomic(path, json.dumps(jsonable(self.to_dict()), indent=2) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> ParameterSet:
        """A parameter file, checked: written by this engine's format or an older one, every
        value finite and within its bounds (a hand-edited NaN or zero capacity forecast NaN
        throughout, with exit code 0)."""
        data = read_json(path, ModelError)
        version = data.get("format_version", FORMAT_VERSION) if isinstance(data, dict) else None
        if isinstance(version, int | float) and version > FORMAT_VERSION:
            raise ModelError(
                f"{path}: parameter file format {version} is newer than this engine's "
                f"({FORMAT_VERSION}); upgrade rcengine"
            )
        pset = cls.from_dict(data)
        for name, p in pset.compiled.parameters.items():
            value = pset.values[name]
            slack = 1e-9 * max(abs(p.lower), abs(p.upper))
            if not (math.isfinite(value) and p.lower - slack <= value <= p.upper + slack):
                raise ModelError(
                    f"{path}: parameter {name} = {value:g} {p.unit} is outside its bounds "
                    f"[{p.lower:g}, {p.upper:g}]"
                )
        return pset


def _missing_entry(data: object, exc: KeyError) -> str:
    """What a parameter document lacks, and what the file probably is instead."""
    found = "" if not isinstance(data, dict) else f"; found {sorted(data)[:8]}"
    hint = (
        " — this looks like a building description, not a parameter file written by `rcengine fit`"
        if isinstance(data, dict) and "location" in data and "network" not in data
        else ""
    )
    needed = "a parameter file has model, network, parameters, building"
    return f"no {exc.args[0]!r} entry ({needed}){found}{hint}"
