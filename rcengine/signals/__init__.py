"""Input signals derived from the contract columns and the building: plane-of-array solar
(``solar``), sky temperature (``sky``), ground temperature (``ground``), learnt schedules
(``schedules``), and ``derived``, which turns a validated frame into the dataset a network
simulates.
"""

from rcengine.signals.derived import SignalOptions, derive, mask_measured, prepare

__all__ = ["SignalOptions", "derive", "mask_measured", "prepare"]
