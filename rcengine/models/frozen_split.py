"""A split across facades that a diagnosis identified, kept when its model is adopted.

The window candidate (``rcengine.diagnose.candidates.window_solar_gains``) fits one extra g-value
per orientation. Which facades carry the extra glass is what months of record identify — the
sun's course moves the light from one facade to the next over the season — and a nightly
calibration on a fortnight cannot: on the window variant, adopted and calibrated on the 14 days
before March, every orientation's extra g fell to zero (the declared glazing's single g-value
carried the sun), 7 of the 12 parameters ended on a bound and the promotion gate refused the set.
So a specification made from a diagnosis keeps the diagnosed split and fits one scale: each
orientation's input keeps its share g_k / g_max of the largest fitted g-value, and the scale,
starting from zero, is that largest g-value (its bounds the largest orientation's). It is the
principle the ground's annual cycle follows already (``ModelSpec.with_fixed_signals``): what only
a long record shows is fixed when the model is made, what a fortnight shows is refitted.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from rcengine.network import Parameter, RCNetwork

# The window gains' parameters, one per orientation key (``g_window_<azimuth>_<tilt>``), and
# the scale that replaces them.
WINDOW_EFFECT = "window_solar_gains"
WINDOW_PREFIX = "g_window_"
WINDOW_SCALE = "g_window_scale"


def window_parameters(detail: Mapping) -> list[str]:
    """The window finding's per-orientation parameters, from its report detail."""
    return [f"{WINDOW_PREFIX}{key}" for key in detail.get("orientations", {})]


def frozen_split(
    network: RCNetwork, fitted: Mapping[str, float], names: list[str], scale: str
) -> RCNetwork:
    """``network`` with the parameters ``names`` replaced by one, ``scale``: each heat input
    they drove keeps its share of the largest fitted value (``fitted``), those fitted at zero
    drop out. ``network`` itself when it has none of them or none was fitted above zero."""
    split = {n: float(fitted[n]) for n in names if n in network.parameters and n in fitted}
    largest = max(split.values(), default=0.0)
    if largest <= 0.0:
        return network
    widest = max(split, key=split.__getitem__)
    net = network.copy()
    removed = {n: net.parameters.pop(n) for n in split}
    shares = ", ".join(
        f"{n.removeprefix(WINDOW_PREFIX)} {v / largest:.2f}" for n, v in split.items()
    )
    net.add_parameter(
        Parameter(
            scale,
            removed[widest].unit,
            removed[widest].lower,
            removed[widest].upper,
            f"{removed[widest].description}; the other orientations in the diagnosed shares "
            f"({shares})",
        )
    )
    net.heat_inputs = [
        replace(h, gain=scale, factor=h.factor * split[h.gain] / largest)
        if isinstance(h.gain, str) and h.gain in split
        else h
        for h in net.heat_inputs
        if not (isinstance(h.gain, str) and split.get(h.gain, 1.0) == 0.0)
    ]
    return net
