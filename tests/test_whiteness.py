"""Ljung–Box: white noise passes, a daily rhythm does not."""

import numpy as np
import pandas as pd

from rcengine.diagnose.whiteness import ljung_box


def test_ljung_box_separates_noise_from_structure():
    times = pd.date_range("2017-01-01", periods=24 * 60, freq="1h", tz="UTC")
    noise = np.random.default_rng(0).normal(size=times.size)
    white = ljung_box(noise, times)
    assert white["p_value"] > 0.01
    daily = noise + 2.0 * np.sin(np.arange(times.size) / 24 * 2 * np.pi)
    coloured = ljung_box(daily, times)
    assert coloured["p_value"] < 1e-6 and coloured["rho_24h"] > 0.5
