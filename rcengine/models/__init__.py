"""The model library: named RC networks scaled to a building.

``get_model(name, building, inputs)`` is the one place a model is chosen by name. ``inputs`` are
the columns the data provide; an optional gain column that is absent (``q_occ``, ``q_light``) is
unknown physics and its heat input is left out rather than fed zeros.
"""

from __future__ import annotations

from collections.abc import Callable, Collection

from rcengine.building import Building
from rcengine.exceptions import ModelError
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


def get_model(name: str, building: Building, inputs: Collection[str] | None = None) -> RCNetwork:
    """Build the named model for ``building``; ``inputs``: columns the data have (None: all)."""
    try:
        builder = MODELS[name]
    except KeyError:
        raise ModelError(f"invalid model {name!r}; choose from {sorted(MODELS)}") from None
    return builder(building, inputs)


def available_models() -> dict[str, str]:
    """Model names with their one-line descriptions."""
    return {name: (fn.__doc__ or "").strip().splitlines()[0] for name, fn in MODELS.items()}
