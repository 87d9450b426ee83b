"""Parameter estimation: GA + pattern search over batched simulations, with a least-squares polish.

``estimator`` holds :class:`Estimator`; ``presets`` its settings; ``objective`` the cost with the
initial states profiled out; ``search_space`` the unit-cube map; ``ga`` and ``pattern_search`` the
two optimisers.
"""

from rcengine.estimation.estimator import Estimator, Identifiability
from rcengine.estimation.presets import PRESETS, EstimatorSettings, settings_for

__all__ = ["PRESETS", "Estimator", "EstimatorSettings", "Identifiability", "settings_for"]
