"""The model library: named RC networks scaled to a building.

``get_model(name, building, inputs)`` is the one place a model is chosen by name. ``inputs`` are
the columns the data provide; an optional gain column that is absent (``q_occ``, ``q_light``) is
unknown physics and its heat input is left out rather than fed zeros. ``bounds`` chooses the
parameter bounds: the thesis's fixed ones or those derived from the building
(:mod:`rcengine.models.bounds`).
"""

from __future__ import annotations

from collections.abc import Callable, Collection

from rcengine.building import Building
from rcengine.exceptions import ModelError
from rcengine.models.bounds import building_bounds, with_bounds
from rcengine.models.iso13790 import iso13790_5r1c
from rcengine.models.simple import r1c1, r2c2
from rcengine.models.thesis import basic, sun
from rcengine.network import RCNetwork

ModelBuilder = Callable[[Building, Collection[str] | None], RCNetwork]

MODELS: dict[str, ModelBuilder] = {
    "basic": basic,
    "sun": sun,
    "1r1c": r1c1,
    "2r2c": r2c2,
    "5r1c": iso13790_5r1c,
}


BOUNDS = ("thesis", "building")


def get_model(
    name: str, building: Building, inputs: Collection[str] | None = None, bounds: str = "thesis"
) -> RCNetwork:
    """Build the named model for ``building``; ``inputs``: columns the data have (None: all).

    ``bounds``: "thesis" (the default) keeps the fixed per-area bounds of thesis Table 2.3
    (whole-building ones scaled from the thesis office; the non-thesis models' own fixed
    bounds), which the fit command, the service and the thesis study use and their tests and
    published figures assert; "building" derives every bound from the building description
    (``building_bounds``), for the diagnosis.
    """
    try:
        builder = MODELS[name]
    except KeyError:
        raise ModelError(f"invalid model {name!r}; choose from {sorted(MODELS)}") from None
    if bounds not in BOUNDS:
        raise ModelError(f"invalid bounds {bounds!r}; choose from {list(BOUNDS)}")
    network = builder(building, inputs)
    if bounds == "building":
        with_bounds(network, building_bounds(name, building))
    return network


def available_models() -> dict[str, str]:
    """Model names with their one-line descriptions."""
    return {name: (fn.__doc__ or "").strip().splitlines()[0] for name, fn in MODELS.items()}
