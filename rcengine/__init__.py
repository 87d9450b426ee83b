"""rcengine: grey-box RC thermal models of buildings for model predictive control."""

__version__ = "0.1.0"
