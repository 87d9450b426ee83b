"""Map physical parameters to the unit cube the optimisers search, and back.

A strictly positive parameter whose bounds span a decade or more (resistances, capacities) is
searched on a log scale: equal steps then mean equal ratios, which is how the cost varies with
an RC time constant. Others (absorption factors, bounds touching 0) are searched linearly.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rcengine.exceptions import ModelError
from rcengine.network import CompiledNetwork

_LOG_SPAN = 10.0


class SearchSpace:
    """Free parameters of ``network`` with their bounds; ``known`` ones are held fixed."""

    def __init__(
        self,
        network: CompiledNetwork,
        known: Mapping[str, float] | None = None,
        bounds: Mapping[str, tuple[float, float]] | None = None,
    ):
        known = dict(known or {})
        bounds = dict(bounds or {})
        unknown = [k for k in [*known, *bounds] if k not in network.param_names]
        if unknown:
            raise ModelError(
                f"{network.name} has no parameter(s) {unknown}; it has {list(network.param_names)}"
            )
        self.network = network
        self.known = known
        self.free = [p for p in network.param_names if p not in known]
        lower = dict(zip(network.param_names, network.lower, strict=True))
        upper = dict(zip(network.param_names, network.upper, strict=True))
        for name, (lo, hi) in bounds.items():
            if not lo <= hi:
                raise ModelError(f"bounds of '{name}': lower {lo} > upper {hi}")
            lower[name], upper[name] = float(lo), float(hi)
        self.lower = np.array([lower[p] for p in self.free])
        self.upper = np.array([upper[p] for p in self.free])
        self.log = (self.lower > 0) & (self.upper >= _LOG_SPAN * self.lower)
        self._free_idx = np.array([network.param_names.index(p) for p in self.free], dtype=int)
        self._template = np.array([known.get(p, np.nan) for p in network.param_names])

    @property
    def dim(self) -> int:
        return len(self.free)

    def to_physical(self, unit: np.ndarray) -> np.ndarray:
        """Unit-cube points (S, dim) → full parameter arrays (S, p) including known values."""
        unit = np.atleast_2d(unit)
        lo = np.where(self.log, np.log(np.where(self.log, self.lower, 1.0)), self.lower)
        hi = np.where(self.log, np.log(np.where(self.log, self.upper, 1.0)), self.upper)
        values = lo + unit * (hi - lo)
        return self.full(np.where(self.log, np.exp(np.where(self.log, values, 0.0)), values))

    def full(self, values: np.ndarray) -> np.ndarray:
        """Free parameter values (S, dim) → full parameter arrays (S, p) with the known ones."""
        values = np.atleast_2d(values)
        theta = np.tile(self._template, (values.shape[0], 1))
        theta[:, self._free_idx] = values
        return theta

    def free_values(self, theta: np.ndarray) -> np.ndarray:
        """Full parameter arrays (S, p) → the free parameters' values (S, dim)."""
        return np.atleast_2d(theta)[:, self._free_idx]

    def to_unit(self, theta: np.ndarray) -> np.ndarray:
        """Full parameter arrays (S, p) → unit-cube points (S, dim)."""
        values = self.free_values(theta)
        with np.errstate(divide="ignore", invalid="ignore"):
            lo = np.where(self.log, np.log(self.lower), self.lower)
            hi = np.where(self.log, np.log(self.upper), self.upper)
            v = np.where(self.log, np.log(np.maximum(values, 1e-300)), values)
            unit = np.where(hi > lo, (v - lo) / (hi - lo), 0.5)
        return np.clip(unit, 0.0, 1.0)

    def seeds(self, partial: list[Mapping[str, float]]) -> np.ndarray:
        """Unit-cube points for (possibly partial) parameter dicts; missing values mid-range."""
        rows = []
        for values in partial:
            unit = np.full(self.dim, 0.5)
            for i, name in enumerate(self.free):
                if name in values:
                    theta = self._template.copy()
                    theta[self._free_idx[i]] = values[name]
                    theta = np.where(np.isnan(theta), 1.0, theta)
                    unit[i] = self.to_unit(theta[None, :])[0, i]
            rows.append(unit)
        return np.array(rows).reshape(len(rows), self.dim)

    def as_dict(self, theta: np.ndarray) -> dict[str, float]:
        return {p: float(v) for p, v in zip(self.network.param_names, theta, strict=True)}

    def at_bounds(self, unit: np.ndarray, margin: float = 1e-3) -> list[str]:
        """Free parameters within ``margin`` (unit cube) of a bound: a sign the bounds bind."""
        return [p for p, u in zip(self.free, unit, strict=True) if u < margin or u > 1 - margin]
