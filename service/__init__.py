"""rcservice: the FastAPI calibration service over :mod:`rcengine` (CONTRACT.md §4).

Kept free of imports so that calibration worker processes start light (see ``service.pool``).
"""
