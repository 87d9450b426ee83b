"""Parameter estimation: GA + pattern search over batched simulations, with a least-squares polish.

``estimator`` holds :class:`Estimator`; ``presets`` its settings; ``objective`` the cost with the
initial states profiled out; ``search_space`` the unit-cube map; ``ga`` and ``pattern_search`` the
two optimisers. ``likelihood`` the maximum-likelihood criterion (Kalman filter, standard errors,
likelihood-ratio test); ``residuals`` the whiteness checks of its innovations.
"""

from rcengine.estimation.estimator import Estimator, Identifiability
from rcengine.estimation.likelihood import LikelihoodFit, likelihood_ratio_test
from rcengine.estimation.presets import PRESETS, EstimatorSettings, settings_for

__all__ = [
    "PRESETS",
    "Estimator",
    "EstimatorSettings",
    "Identifiability",
    "LikelihoodFit",
    "likelihood_ratio_test",
    "settings_for",
]
