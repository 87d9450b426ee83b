"""Estimator settings and the named presets (``thesis``, ``modestpy``, ``default``, ``thorough``,
``study``)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from rcengine.estimation.ga import GASettings
from rcengine.estimation.likelihood import LikelihoodSettings
from rcengine.estimation.pattern_search import GPSSettings


@dataclass(frozen=True)
class EstimatorSettings:
    """GA and GPS settings; ``polish`` runs a least-squares polish from the GPS optimum and from
    the next ``polish_starts − 1`` best distinct GA individuals (each a cheap local solve);
    ``likelihood``: the search of ``criterion="likelihood"``; ``restarts``: independent
    output-error searches (GA, GPS and polish, each from its own random stream), the best kept."""

    ga: GASettings = field(default_factory=GASettings)
    gps: GPSSettings = field(default_factory=GPSSettings)
    polish: bool = False
    polish_starts: int = 1
    restarts: int = 1
    likelihood: LikelihoodSettings = field(default_factory=LikelihoodSettings)


# Batched simulation makes populations cheap: GA explores, a short GPS walks to the basin floor,
# and Gauss–Newton steps from several distinct basins finish the narrow valleys that compass
# moves crawl along.
DEFAULT = EstimatorSettings(
    GASettings(population=60, generations=25, tol=1e-4, patience=5, lhs=True),
    GPSSettings(max_iter=60, tol=1e-4, initial_step=0.05, expand=2.0),
    polish=True,
    polish_starts=4,
)

PRESETS: dict[str, EstimatorSettings] = {
    # Thesis §2.4.2: ModestPy GA 15 generations, tolerance 1e-3; GPS 500 iterations, 1e-6.
    "thesis": EstimatorSettings(
        GASettings(population=20, generations=15, tol=1e-3),
        GPSSettings(max_iter=500, tol=1e-6),
    ),
    # ModestPy's examples/simple: GA 5 generations × 20 from a Latin hypercube, then PS.
    "modestpy": EstimatorSettings(
        GASettings(population=20, generations=5, lhs=True),
        GPSSettings(max_iter=500, tol=1e-6),
    ),
    "default": DEFAULT,
    # One "default" search still settles in a worse basin from some seeds (two capacitors
    # swapping roles): 4 of 10 on a test-bed fortnight (+22 % RMSE), 1 of 10 on Armadillo
    # (+79 %), 6 of 10 on a fortnight with a concealed emitter (+43 %). Three independent
    # searches, the best kept: 0, 0 and 4 of 10, at three times the cost
    # (python benchmarks/restarts.py). The CLI's one-off fits use it; the service's nightly
    # fleet keeps one search (its capacity, docs/fleet.md), seeded with the current set.
    "thorough": replace(DEFAULT, restarts=3),
    # The rolling study's thousands of short fits: a short Latin-hypercube GA only to find the
    # basins, then least squares from the four best distinct ones (after which compass moves gain
    # nothing). Half the cost of "default" and a lower training cost more often (docs/study.md).
    "study": EstimatorSettings(
        GASettings(population=64, generations=5, tol=1e-4, patience=3, lhs=True),
        GPSSettings(max_iter=0),
        polish=True,
        polish_starts=4,
    ),
}


def settings_for(preset: str | EstimatorSettings) -> EstimatorSettings:
    if isinstance(preset, EstimatorSettings):
        return preset
    if preset not in PRESETS:
        raise ValueError(f"invalid preset {preset!r}; choose from {sorted(PRESETS)}")
    return PRESETS[preset]
