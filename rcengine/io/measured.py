"""The two measured buildings of the reference data (``shared/data/measured``) as contract frames.

Both files count time from the start of the experiment and carry no date; the start instant is
a parameter, with the defaults below. Rows keep the files' own step. A contract row's inputs
(heating power, irradiance, outdoor temperature) are their means over [t, t + dt), which the
engine holds over the step (zero-order hold); its indoor temperature is the value at t. SYSLAB's
input rows are such means already and are kept as they are; Armadillo's are samples at t and are
converted to interval means (below). How the files say which: their values, the indoor
temperature's response to the heating switches, and the likelihood of the ``2r2c`` fits of
``benchmarks/likelihood_peers.py`` (−ln L, lower is better) under each reading.

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

Inputs: means over the 5 minutes after the stamp, kept as they are. The source does not say so;
the data do. The values are averages of faster readings (``Ph`` 5.236667 kW); where the heaters
switch, the first row after the switch holds a partial value (0.44–0.60 kW when off, 4.7–5.0 kW
when on, against about 0.04 and 5.2 kW), and the indoor temperature's trend turns in the interval
after that row, not in the one before. With the heaters as a state of their own (``2r2c+heater``,
as in the CTSM-R models of these data): −ln L −3481 with the rows as they are, −3042 with each
row replaced by the mean of it and the next (the reading of samples), −2670 with each row moved
to the interval before its stamp.

Armadillo Box (``armadillo_data_H2.csv``)
-----------------------------------------
Copy of the 42 m² lightweight wooden house of the 2010 Solar Decathlon Europe built on the INES
test site, Le Bourget-du-Lac, France (pySIP examples). ``Time`` [s], ``T_ext`` [°C], ``P_hea``
heating [W], ``I_sol`` solar irradiance [W/m²], ``T_int`` indoor mean [°C]; 30-minute rows.

Inputs: samples at the stamp, converted to interval means. pySIP's own example for this file
builds its model with ``hold_order=1``, the inputs interpolated linearly between the samples
(locie/pySIP ``docs/examples/thermal_network/armadillo/fit_frequentist.ipynb``). The data agree:
the heating starts and stops between stamps. At row 40 (20:00), the first non-zero ``P_hea``, the
indoor temperature has already risen 0.9 K since row 39, whose sample reads 0 W; after row 135,
the last non-zero sample, it falls 0.45 K in the first half hour and 1.56 K in the second.
Holding each sample over the step after it misplaces that heat by up to a step. Each input is
therefore replaced by its mean over [t_k, t_k+1) under linear interpolation, (s_k + s_k+1)/2:

* ``P_hea`` and ``I_sol``, powers: the energy over the step is what enters the heat balance (and
  the engine takes the sun's position at mid-interval, the instant of a mean, not of a sample).
* ``T_ext``: it drives the envelope's heat flow linearly, so its mean over the step is the held
  value that carries the same heat.
* ``T_int`` stays the sample at t: the model's output is compared at the instants.

The last row has no successor: its inputs keep their samples (held, not dropped). They only drive
the state beyond the record's end, so the hold changes no fit or prediction within the record,
while the row's indoor temperature is a measurement worth keeping. With the ``2r2c`` likelihood
fit of the benchmark (no sun, 162 training rows): −ln L −205.8 with the interval means, −135.3
with the samples held over the step after them, −158.1 with each sample taken as the mean of the
step before it.

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
    Validated frame on a UTC index, 5-minute rows; inputs as in the file, already means over the
    5 minutes after the stamp (module docstring). [°C, W/m², W]
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


def read_armadillo(
    path: str | Path, start: str | pd.Timestamp = ARMADILLO_START, inputs: str = "means"
) -> pd.DataFrame:
    """Armadillo Box experiment as a contract frame (``t_in``, ``t_out``, ``ghi``, ``q_hvac``).

    Parameters
    ----------
    path : ``armadillo_data_H2.csv``.
    start : instant of ``Time = 0``, with a UTC offset (a placeholder date by default, see the
        module docstring).
    inputs : ``"means"`` (default): ``t_out``, ``ghi`` and ``q_hvac`` are the means over
        [t_k, t_k+1) of the linearly interpolated samples, (s_k + s_k+1)/2, the last row's
        samples held — the contract's rows, for a zero-order hold; ``"samples"``: the samples at
        the stamps as recorded, for a first-order hold (``Dataset(hold="foh")``).

    Returns
    -------
    Validated frame on a UTC index, 30-minute rows; ``ghi`` is ``I_sol`` taken as horizontal;
    ``t_in`` is the sample at t (module docstring). [°C, W/m², W]
    """
    if inputs not in ("means", "samples"):
        raise ValueError(f"inputs must be 'means' or 'samples', not {inputs!r}")
    raw = pd.read_csv(path)
    held = _interval_means if inputs == "means" else (lambda samples: samples)
    return _contract_frame(
        start,
        raw["Time"].to_numpy(float),
        {
            T_IN: raw["T_int"],
            T_OUT: held(raw["T_ext"]),
            GHI: held(raw["I_sol"]),
            Q_HVAC: held(raw["P_hea"]),
        },
    )


def _interval_means(samples: pd.Series) -> pd.Series:
    """Mean over each step [t_k, t_k+1) of the samples interpolated linearly, (s_k + s_k+1)/2;
    the last sample, which has no successor, held (same unit as ``samples``)."""
    return 0.5 * (samples + samples.shift(-1).fillna(samples))


def _contract_frame(
    start: str | pd.Timestamp, elapsed_s: np.ndarray, columns: dict[str, pd.Series]
) -> pd.DataFrame:
    """Rows at ``start + elapsed`` (rounded to the second: hours as decimals are inexact),
    checked by the contract's own validation."""
    origin = parse_instant(start, "start")
    times = origin + pd.to_timedelta(np.round(elapsed_s), unit="s")
    return validate_frame(pd.DataFrame({TIME: times, **columns}))
