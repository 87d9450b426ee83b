"""The two measured buildings of the reference data (``shared/data/measured``) as contract frames.

Both files count time from the start of the experiment and carry no date; the start instant is
a parameter, with the defaults below. Rows keep the files' own sampling: an input row (heating
power, irradiance, outdoor temperature) is taken as holding over [t, t + dt), the indoor
temperature as the value at t — the zero-order hold both source tools (CTSM-R, pySIP) apply.

SYSLAB (``syslab_inputPRBS1.csv``)
----------------------------------
Office building of lightweight wood construction in DTU's SYSLAB facility, Risø campus, Denmark,
heated by electric heaters switched by a pseudo-random binary sequence (Bacher & Madsen 2011;
the CTSM-R building example). ``;``-separated: ``t`` [h], ``Ta`` outdoor [°C], ``Ps`` global
solar [kW/m²], ``Ph`` heating [kW], ``yTi`` indoor [°C]; 5-minute rows.

Start: 2009-02-05 14:26 UTC, the instant the CTSM-R example gives to ``t = 0``
(``asP("2009-02-05 14:26:00")``, whose default zone there is GMT). The sun confirms UTC rather
than Danish time (UTC+1): with this start, the irradiance follows the computed sun elevation
more closely than with the start an hour earlier or later (checked in the tests).

Armadillo Box (``armadillo_data_H2.csv``)
-----------------------------------------
Copy of the 42 m² lightweight wooden house of the 2010 Solar Decathlon Europe built on the INES
test site, Le Bourget-du-Lac, France (pySIP examples). ``Time`` [s], ``T_ext`` [°C], ``P_hea``
heating [W], ``I_sol`` solar irradiance [W/m²], ``T_int`` indoor mean [°C]; 30-minute rows.

Assumptions, not documented by the source:

* ``I_sol`` is global horizontal irradiance (peaks near 1,000 W/m² at midday, as horizontal
  irradiance does in summer; a vertical façade would see about half). It reads about 14 W/m² at
  night — a sensor offset left as measured.
* The date is unknown. The daily irradiance peak falls near 13:30 of the file's clock, which
  matches solar noon at the site in French summer time (UTC+2) with ``Time = 0`` at local
  midnight; of the dates April–September, clear-sky irradiance fits late August best, if
  weakly. The default start, 2015-08-19 00:00 +02:00, is therefore a plausible placeholder
  that only sets the sun's path.
* pySIP drops the last row (the indoor temperature jumps 0.8 K in one step); it is kept here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rcengine.columns import GHI, Q_HVAC, T_IN, T_OUT, TIME
from rcengine.io.instants import parse_instant
from rcengine.io.timeseries import validate_frame

SYSLAB_START = "2009-02-05T14:26:00+00:00"
ARMADILLO_START = "2015-08-19T00:00:00+02:00"
W_PER_KW = 1000.0
S_PER_H = 3600.0


def read_syslab(path: str | Path, start: str | pd.Timestamp = SYSLAB_START) -> pd.DataFrame:
    """SYSLAB PRBS experiment as a contract frame (``t_in``, ``t_out``, ``ghi``, ``q_hvac``).

    Parameters
    ----------
    path : ``syslab_inputPRBS1.csv``.
    start : instant of ``t = 0``, with a UTC offset (see the module docstring).

    Returns
    -------
    Validated frame on a UTC index, 5-minute rows. [°C, W/m², W]
    """
    raw = pd.read_csv(path, sep=";")
    return _contract_frame(
        start,
        raw["t"].to_numpy(float) * S_PER_H,
        {
            T_IN: raw["yTi"],
            T_OUT: raw["Ta"],
            GHI: raw["Ps"] * W_PER_KW,
            Q_HVAC: raw["Ph"] * W_PER_KW,
        },
    )


def read_armadillo(path: str | Path, start: str | pd.Timestamp = ARMADILLO_START) -> pd.DataFrame:
    """Armadillo Box experiment as a contract frame (``t_in``, ``t_out``, ``ghi``, ``q_hvac``).

    Parameters
    ----------
    path : ``armadillo_data_H2.csv``.
    start : instant of ``Time = 0``, with a UTC offset (a placeholder date by default, see the
        module docstring).

    Returns
    -------
    Validated frame on a UTC index, 30-minute rows; ``ghi`` is the measured ``I_sol`` taken as
    horizontal. [°C, W/m², W]
    """
    raw = pd.read_csv(path)
    return _contract_frame(
        start,
        raw["Time"].to_numpy(float),
        {T_IN: raw["T_int"], T_OUT: raw["T_ext"], GHI: raw["I_sol"], Q_HVAC: raw["P_hea"]},
    )


def _contract_frame(
    start: str | pd.Timestamp, elapsed_s: np.ndarray, columns: dict[str, pd.Series]
) -> pd.DataFrame:
    """Rows at ``start + elapsed`` (rounded to the second: hours as decimals are inexact),
    checked by the contract's own validation."""
    origin = parse_instant(start, "start")
    times = origin + pd.to_timedelta(np.round(elapsed_s), unit="s")
    return validate_frame(pd.DataFrame({TIME: times, **columns}))
