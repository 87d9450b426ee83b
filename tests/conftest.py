"""Shared fixtures: where the reference data of ../shared live, skipping cleanly when absent."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"
PROJECT_DATA = ROOT / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """``../shared/data`` of the checkout; tests needing it skip where it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"reference data not found at {SHARED_DATA}")
    return SHARED_DATA


@pytest.fixture(scope="session")
def project_data() -> Path:
    """The project's own committed data (EnergyPlus CSVs and building JSONs)."""
    return PROJECT_DATA
