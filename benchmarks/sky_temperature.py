"""The sky temperature the engine estimates, against the one the weather files record.

The ``sky_radiation`` candidate (``rcengine.diagnose.candidates.sky_radiation``) is driven by
``sky_delta`` = T_sky − t_out, estimated from the contract's columns alone (``signals.sky``: the
clear sky's emissivity from a dew point taken as the lowest air temperature of the day around,
raised for a cloud cover read from each day's clear-sky index and interpolated across nights).
EnergyPlus, which made the test bed, takes the sky's long-wave from the EPW's horizontal
infrared field instead: T_sky = (IR / σ)^¼. This compares them over each heating season
(October–March) of the project's weather files (the Torino IWEC of ``../shared/data/weather`` and
every TMY3 file the EnergyPlus wheel ships), on every row and on the night rows alone (no
clear-sky irradiance), where the sky loss is not masked by the sun.

Per file, estimate and rows: R² (squared correlation of the estimate with the record), the slope
of the record on the estimate (below 1: the estimate swings more than the record, which a
least-squares fit of its gain answers by shrinking it) and the mean bias [K]. Measured beside it
in the same run: Swinbank's emissivity from the air temperature alone (the engine's estimate
before, ``sky_emissivity="swinbank"``), and the dew-point estimate fed the file's own opaque sky
cover as the contract's optional ``cloud_cover`` column (``SignalOptions.cloud_cover="column"``)
— the gap to it is what the cloud-cover estimate costs, and what data with a cloud column gain.

    python benchmarks/sky_temperature.py

Prints a table, then a JSON line: per file and estimate its figures, and the medians.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from pvlib.iotools import read_epw as pvlib_read_epw

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a file: make `scripts` importable

from rcengine.columns import CLOUD_COVER, T_OUT  # noqa: E402
from rcengine.io.epw import hour_ends_utc, read_epw  # noqa: E402
from rcengine.signals.sky import (  # noqa: E402
    KELVIN,
    sky_delta,
)
from rcengine.signals.solar import clear_sky_ghi  # noqa: E402
from scripts.energyplus.testbed import WEATHER, tmy3  # noqa: E402

STEFAN_BOLTZMANN = 5.670374419e-8  # [W/(m²K⁴)]
HEATING_MONTHS = (10, 11, 12, 1, 2, 3)
# The calendar year a typical-year file's rows are read into.
TYPICAL_YEAR = 2017
ESTIMATE = "dew point"
COLUMN = "cloud column"
ESTIMATES = (ESTIMATE, "swinbank", COLUMN)


def weather_files() -> list[Path]:
    return [WEATHER, *sorted(tmy3("file.epw").parent.glob("*.epw"))]


def recorded(path: Path, index: pd.DatetimeIndex) -> pd.DataFrame:
    """The file's sky temperature [°C] and opaque sky cover [tenths] on the contract rows (the
    row of EPW hour h starts at h − 1, as ``read_epw`` stamps the irradiance)."""
    data, meta = pvlib_read_epw(path, coerce_year=TYPICAL_YEAR)
    starts = hour_ends_utc(data, meta["TZ"]) - pd.Timedelta(hours=1)
    t_sky = (data["ghi_infrared"].to_numpy(float) / STEFAN_BOLTZMANN) ** 0.25 - KELVIN
    cover = data["opaque_sky_cover"].to_numpy(float)
    return pd.DataFrame({"t_sky": t_sky, "cover": cover}, index=starts).reindex(index)


def weather_cloud_cover(path: Path, index: pd.DatetimeIndex) -> pd.Series:
    """The EPW's opaque sky cover as the contract's ``cloud_cover`` [%] on the rows of
    ``index`` (UTC; each row takes its hour's value, the typical year's on the same date)."""
    year = TYPICAL_YEAR
    typical = recorded(path, pd.date_range(f"{year}-01-01", periods=366 * 24, freq="h", tz="UTC"))
    hours = index.floor("h")
    same_date = pd.DatetimeIndex([t.replace(year=year) for t in hours])
    cover = typical["cover"].reindex(same_date).to_numpy()
    return pd.Series(10.0 * cover, index=index, name=CLOUD_COVER)


def agreement(estimate: np.ndarray, record: np.ndarray) -> dict[str, float]:
    r = np.corrcoef(estimate, record)[0, 1]
    return {
        "r2": round(float(r * r), 3),
        "slope": round(float(np.polyfit(estimate, record, 1)[0]), 3),
        "bias_k": round(float(np.mean(estimate - record)), 2),
    }


def compare(path: Path) -> dict[str, dict[str, dict[str, float]]]:
    frame, location = read_epw(path)
    record = recorded(path, frame.index)
    t_out = frame[T_OUT].to_numpy(float)
    # The file's opaque sky cover [tenths] as a weather service's cloud cover [%].
    clouded = frame.assign(**{CLOUD_COVER: 10.0 * record["cover"]})
    estimates = {
        ESTIMATE: sky_delta(frame, location),
        "swinbank": sky_delta(frame, location, "swinbank"),
        COLUMN: sky_delta(clouded, location, cloud="column"),
    }
    truth = record["t_sky"].to_numpy() - t_out
    season = frame.index.month.isin(HEATING_MONTHS) & np.isfinite(truth)
    night = season & (clear_sky_ghi(frame.index, location) <= 0.0)
    return {
        name: {
            rows: agreement(value[mask], truth[mask])
            for rows, mask in (("all", season), ("night", night))
        }
        for name, value in estimates.items()
    }


def main() -> None:
    results = {path.stem: compare(path) for path in weather_files()}
    print(f"{'weather file':42s} {'sky_delta from':16s} {'rows':6s} R²     slope  bias [K]")
    for file, by_estimate in results.items():
        for estimate, by_rows in by_estimate.items():
            for rows, f in by_rows.items():
                print(
                    f"{file[:42]:42s} {estimate:16s} {rows:6s} "
                    f"{f['r2']:.2f}   {f['slope']:.2f}   {f['bias_k']:+.1f}"
                )
    medians = {
        estimate: {
            rows: {
                k: float(np.median([results[f][estimate][rows][k] for f in results]))
                for k in ("r2", "slope", "bias_k")
            }
            for rows in ("all", "night")
        }
        for estimate in ESTIMATES
    }
    print(json.dumps({"files": results, "median": medians}))


if __name__ == "__main__":
    main()
