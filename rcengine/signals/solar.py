"""Solar heat signals of the envelope (thesis §2.4.3, Eq. 15–18), on pvlib.

Sun position, split of the global horizontal irradiance into beam and diffuse, irradiance on
each oriented surface, the glazing's incidence-angle modifier, and the per-facade heat signals
[W] that the RC models scale by their absorption factors.

Time convention
---------------
A contract row is stamped with the START of its interval and its irradiance is the mean over
[t, t + dt). The sun is therefore placed at the interval's MIDPOINT t + dt/2 (dt: the most
common step of the index), the instant whose geometry best represents the interval's mean.
``solar_gains``, ``clear_sky_ghi`` and ``clear_sky_index`` take row-start times and shift them;
the lower-level functions take the instants at which to evaluate the sun as given.
"""

from __future__ import annotations

import calendar
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd
from pvlib import atmosphere, clearsky, iam, irradiance, solarposition

from rcengine.building import Building, Location, Surface
from rcengine.columns import (
    DHI,
    DNI,
    GHI,
    SOLAR_OPAQUE,
    SOLAR_WINDOW,
    orientation_key,
    solar_orientation_signal,
)

DECOMPOSITION_MODELS = ("erbs", "dirint")
SKY_MODELS = ("isotropic", "perez", "haydavies")
IAM_MODELS = ("physical", "ashrae", "none")

# Single pane of soda-lime window glass for the Fresnel/Snell IAM (pvlib.iam.physical):
# refractive index [-], extinction coefficient [1/m], thickness [m].
GLASS_REFRACTIVE_INDEX = 1.526
GLASS_EXTINCTION = 4.0
GLASS_THICKNESS = 0.004
# ASHRAE incidence-angle modifier coefficient of glazing [-] (ASHRAE 93-77, pvlib default).
ASHRAE_B = 0.05

# Largest clear-sky index kept: interval means near sunrise and cloud-edge enhancement exceed 1.
MAX_CLEAR_SKY_INDEX = 1.5


def _check_model(model: str, choices: tuple[str, ...]) -> None:
    if model not in choices:
        raise ValueError(f"invalid model {model}; choose from {', '.join(choices)}")


def interval_midpoints(index: pd.DatetimeIndex) -> pd.DatetimeIndex:
    """Midpoints t + dt/2 of the intervals starting at ``index``, dt the most common step.

    Raises
    ------
    ValueError : fewer than two rows, so no step can be inferred.
    """
    if len(index) < 2:
        raise ValueError("need at least two rows to infer the time step of the intervals")
    steps = pd.Series(np.diff(index.as_unit("ns").asi8))
    step = pd.Timedelta(int(steps.mode().iloc[0]), unit="ns")
    return index + step / 2


def day_of_year(times: pd.DatetimeIndex) -> np.ndarray:
    """Day of the year of each instant, on the UTC calendar as pvlib counts it (1–366). [-]

    pvlib's functions take either instants or these numbers; given instants they read pandas'
    deprecated ``dayofyear``, so the numbers are passed instead.
    """
    return np.asarray(times.tz_convert("UTC").day_of_year, dtype=float)


@contextmanager
def _pvlib_reads_dayofyear() -> Iterator[None]:
    # pvlib 0.16.1's dirint reads the deprecated DatetimeIndex.dayofyear itself and takes no day
    # numbers instead; only that warning is silenced, only here.
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"DatetimeIndex\.dayofyear is deprecated")
        yield


def extra_radiation(times: pd.DatetimeIndex) -> np.ndarray:
    """Extraterrestrial normal irradiance at each instant (pvlib, Spencer 1971). [W/m²]"""
    return np.asarray(irradiance.get_extra_radiation(day_of_year(times)), dtype=float)


def solar_position(times: pd.DatetimeIndex, location: Location) -> pd.DataFrame:
    """Sun position at the given instants (NREL SPA, pvlib.solarposition.get_solarposition).

    Parameters
    ----------
    times : tz-aware instants, usually interval midpoints (``interval_midpoints``).
    location : site latitude, longitude [°] and altitude [m]; the pressure follows the altitude.

    Returns
    -------
    DataFrame indexed by ``times``: ``apparent_zenith`` (refraction-corrected), ``zenith`` and
    ``azimuth`` (clockwise from north). [°]
    """
    position = solarposition.get_solarposition(
        times, location.latitude, location.longitude, altitude=location.altitude
    )
    return position[["apparent_zenith", "zenith", "azimuth"]]


def decompose_ghi(
    times: pd.DatetimeIndex,
    ghi: np.ndarray,
    location: Location,
    model: str = "erbs",
    position: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Direct normal and diffuse horizontal irradiance from the global horizontal irradiance.

    Parameters
    ----------
    times : instants of the sun position (interval midpoints).
    ghi : global horizontal irradiance; small negative sensor noise is read as 0. [W/m²]
    location : the site.
    model : "erbs" (Erbs et al. 1982, diffuse fraction from the clearness index) or "dirint"
        (Perez et al. 1992, uses the GHI time series' stability; meant for hourly or finer data).
    position : ``solar_position(times, location)`` if already computed.

    Returns
    -------
    DataFrame indexed by ``times`` with ``dni`` and ``dhi``. [W/m²] NaN only where ``ghi`` is.

    Notes
    -----
    Both models give dni; dhi follows from the closure ghi = dhi + dni · cos z with the true
    zenith z. Beyond z = 87° (and at night) dni = 0 and all of ghi is diffuse. dni is capped at
    the extraterrestrial normal irradiance (≈1320–1410 W/m²), the physical limit.
    """
    _check_model(model, DECOMPOSITION_MODELS)
    position = solar_position(times, location) if position is None else position
    ghi = np.clip(np.asarray(ghi, dtype=float), 0.0, None)
    zenith = position["zenith"].to_numpy()
    if model == "erbs":
        dni = np.asarray(irradiance.erbs(ghi, zenith, day_of_year(times))["dni"], dtype=float)
    else:
        with _pvlib_reads_dayofyear():
            dni = irradiance.dirint(
                pd.Series(ghi, index=times),
                pd.Series(zenith, index=times),
                times,
                pressure=atmosphere.alt2pres(location.altitude),
            ).to_numpy(dtype=float)
    dni_extra = extra_radiation(times)
    dni = np.clip(np.nan_to_num(dni, nan=0.0, posinf=0.0, neginf=0.0), 0.0, dni_extra)
    cos_zenith = np.clip(np.cos(np.radians(zenith)), 0.0, None)
    dhi = np.clip(ghi - dni * cos_zenith, 0.0, None)
    unknown = np.isnan(ghi)
    return pd.DataFrame(
        {DNI: np.where(unknown, np.nan, dni), DHI: np.where(unknown, np.nan, dhi)}, index=times
    )


def surface_irradiance(
    times: pd.DatetimeIndex,
    ghi: np.ndarray,
    dni: np.ndarray,
    dhi: np.ndarray,
    surface: Surface,
    location: Location,
    sky_model: str = "isotropic",
    albedo: float | None = None,
    position: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Irradiance on an oriented plane (plane of array) from ghi, dni and dhi.

    Parameters
    ----------
    times : instants of the sun position (interval midpoints).
    ghi, dni, dhi : global horizontal, direct normal and diffuse horizontal irradiance. [W/m²]
    surface : orientation (azimuth clockwise from north, tilt from horizontal [°]); area unused.
    location : the site.
    sky_model : "isotropic" (thesis Eq. 17), "perez" (Perez et al. 1990) or "haydavies"
        (Hay & Davies 1980); the extraterrestrial irradiance and air mass they need are computed.
    albedo : ground reflectance [-]; None neglects reflection as the thesis did (Eq. 18 dropped).
    position : ``solar_position(times, location)`` if already computed.

    Returns
    -------
    DataFrame indexed by ``times``: ``poa_direct``, ``poa_sky_diffuse``, ``poa_ground_diffuse``,
    ``poa_global`` [W/m²] and the angle of incidence of the beam ``aoi`` [°].

    Notes
    -----
    Beam: E_b = E_bn · max(cos θ, 0) (Eq. 16), with cos θ = cos β · cos(Ψ − Ψ_s) on a vertical
    plane (Eq. 15). Isotropic sky: E_d = E_dh · (1 + cos φ)/2 (Eq. 17). Ground: E_r = E_th · ρ ·
    (1 − cos φ)/2 (Eq. 18). pvlib.irradiance.get_total_irradiance evaluates them with the
    apparent (refraction-corrected) zenith. When the sun is below the horizon at the midpoint the
    beam is set to 0, so a measured dni of the sunrise hour cannot light a wall from below.
    """
    _check_model(sky_model, SKY_MODELS)
    position = solar_position(times, location) if position is None else position
    zenith = position["apparent_zenith"].to_numpy()
    azimuth = position["azimuth"].to_numpy()
    ghi, dni, dhi = (np.asarray(x, dtype=float) for x in (ghi, dni, dhi))
    extra = {}
    if sky_model in ("perez", "haydavies"):
        extra["dni_extra"] = extra_radiation(times)
    if sky_model == "perez":
        extra["airmass"] = atmosphere.get_relative_airmass(zenith)
    poa = irradiance.get_total_irradiance(
        surface.tilt,
        surface.azimuth,
        zenith,
        azimuth,
        np.where(zenith < 90.0, dni, 0.0),
        ghi,
        dhi,
        albedo=0.0 if albedo is None else albedo,
        model=sky_model,
        **extra,
    )
    # Perez is undefined (NaN) for some low-sun rows with finite inputs: no diffuse there.
    known = np.isfinite(ghi) & np.isfinite(dni) & np.isfinite(dhi)
    components = ("poa_direct", "poa_sky_diffuse", "poa_ground_diffuse")
    out = pd.DataFrame(
        {
            c: np.where(known, np.nan_to_num(np.asarray(poa[c], dtype=float)), np.nan)
            for c in components
        },
        index=times,
    )
    out["poa_global"] = out["poa_direct"] + out["poa_sky_diffuse"] + out["poa_ground_diffuse"]
    out["aoi"] = irradiance.aoi(surface.tilt, surface.azimuth, zenith, azimuth)
    return out


def glazing_iam(aoi: np.ndarray, model: str = "physical") -> np.ndarray:
    """Incidence-angle modifier of glazing for beam irradiance: τ(θ)/τ(0). [-]

    Parameters
    ----------
    aoi : angle of incidence from the glazing's normal. [°]
    model : "physical" (Fresnel reflection at both faces with Snell refraction and absorption
        in one pane of glass, pvlib.iam.physical), "ashrae" (1 − b (1/cos θ − 1), b = 0.05,
        floored at 0), or "none" (1 everywhere).

    Returns
    -------
    Modifier: 1 at normal incidence, 0 at and beyond 90°.
    """
    _check_model(model, IAM_MODELS)
    aoi = np.asarray(aoi, dtype=float)
    if model == "physical":
        modifier = iam.physical(
            aoi, n=GLASS_REFRACTIVE_INDEX, K=GLASS_EXTINCTION, L=GLASS_THICKNESS
        )
    elif model == "ashrae":
        modifier = iam.ashrae(aoi, b=ASHRAE_B)
    else:
        modifier = np.where(aoi < 90.0, 1.0, 0.0)
    return np.asarray(modifier, dtype=float)


@lru_cache(maxsize=64)
def glazing_diffuse_iam(tilt: float, model: str = "physical") -> tuple[float, float]:
    """Incidence-angle modifiers of glazing for isotropic sky and ground-reflected irradiance.

    Parameters
    ----------
    tilt : glazing tilt from horizontal. [°]
    model : as ``glazing_iam``.

    Returns
    -------
    (sky, ground) modifiers [-]: the beam modifier averaged over the sky dome and over the
    ground seen by the plane, weighted by cos θ (Marion 2017, pvlib.iam.marion_diffuse); (1, 1)
    for "none". About 0.94 for sky diffuse on vertical glass with the physical model.
    """
    _check_model(model, IAM_MODELS)
    if model == "none":
        return 1.0, 1.0
    kwargs = (
        {"n": GLASS_REFRACTIVE_INDEX, "K": GLASS_EXTINCTION, "L": GLASS_THICKNESS}
        if model == "physical"
        else {"b": ASHRAE_B}
    )
    modifiers = iam.marion_diffuse(model, tilt, **kwargs)
    return float(modifiers["sky"]), float(modifiers["ground"])


def _glazing_irradiance(poa: pd.DataFrame, tilt: float, iam_model: str) -> np.ndarray:
    """Irradiance passing the glazing's incidence-angle modifier. [W/m²]

    Perez's circumsolar diffuse is modified as sky diffuse, not at the beam's angle.
    """
    sky, ground = glazing_diffuse_iam(tilt, iam_model)
    return (
        poa["poa_direct"].to_numpy() * glazing_iam(poa["aoi"].to_numpy(), iam_model)
        + poa["poa_sky_diffuse"].to_numpy() * sky
        + poa["poa_ground_diffuse"].to_numpy() * ground
    )


def _beam_and_diffuse(
    frame: pd.DataFrame,
    times: pd.DatetimeIndex,
    ghi: np.ndarray,
    location: Location,
    decomposition: str,
    position: pd.DataFrame,
) -> tuple[np.ndarray, np.ndarray]:
    """dni and dhi [W/m²]: measured where both are given, decomposed from ghi elsewhere."""
    nan = np.full(len(frame), np.nan)
    dni = frame[DNI].to_numpy(dtype=float) if DNI in frame.columns else nan
    dhi = frame[DHI].to_numpy(dtype=float) if DHI in frame.columns else nan
    measured = np.isfinite(dni) & np.isfinite(dhi)
    if measured.all():
        return np.clip(dni, 0.0, None), np.clip(dhi, 0.0, None)
    derived = decompose_ghi(times, ghi, location, decomposition, position)
    dni = np.where(measured, np.clip(dni, 0.0, None), derived[DNI].to_numpy())
    dhi = np.where(measured, np.clip(dhi, 0.0, None), derived[DHI].to_numpy())
    return dni, dhi


def _group_by_orientation(surfaces: tuple[Surface, ...]) -> dict[str, tuple[Surface, float]]:
    """Orientation key → (a surface of that orientation, total area [m²])."""
    groups: dict[str, tuple[Surface, float]] = {}
    for s in surfaces:
        key = orientation_key(s.azimuth, s.tilt)
        first, area = groups.get(key, (s, 0.0))
        groups[key] = (first, area + s.area)
    return groups


def solar_signal_names(building: Building) -> list[str]:
    """The columns ``solar_gains`` gives for ``building``: the two totals, then one per
    orientation of its windows and of its walls."""
    surfaces = {SOLAR_WINDOW: building.windows, SOLAR_OPAQUE: building.walls}
    return [
        *surfaces,
        *(
            solar_orientation_signal(total, key)
            for total, group in surfaces.items()
            for key in _group_by_orientation(group)
        ),
    ]


def solar_gains(
    frame: pd.DataFrame,
    building: Building,
    sky_model: str = "isotropic",
    albedo: float | None = None,
    iam_model: str = "physical",
    decomposition: str = "erbs",
) -> pd.DataFrame:
    """Solar heat signals of the building's windows and opaque walls, by orientation.

    Parameters
    ----------
    frame : contract data on a UTC index (row time = start of the interval) with ``ghi``
        [W/m²] and optionally ``dni``, ``dhi`` [W/m²]; rows where either is missing are
        decomposed from ``ghi`` with ``decomposition``.
    building : location, ``windows`` (glazing) and ``walls`` (opaque surfaces).
    sky_model, albedo : as ``surface_irradiance``.
    iam_model : glazing modifier, as ``glazing_iam``.
    decomposition : ghi → dni, dhi model, as ``decompose_ghi``.

    Returns
    -------
    DataFrame indexed like ``frame``, in W:

    * ``solar_window``: Σ window area × (beam · IAM(θ) + sky diffuse · IAM_sky + ground
      reflected · IAM_ground), the irradiance arriving through the glazing's surface before
      the model's absorption factor; 0 without windows.
    * ``solar_opaque``: Σ wall area × total plane irradiance; 0 without walls.
    * ``solar_window_<azimuth>_<tilt>`` and ``solar_opaque_<azimuth>_<tilt>`` (see
      ``orientation_key``): the same per orientation; they sum to the totals.

    Raises
    ------
    ValueError : an unknown model name, or fewer than two rows.
    """
    _check_model(sky_model, SKY_MODELS)
    _check_model(iam_model, IAM_MODELS)
    _check_model(decomposition, DECOMPOSITION_MODELS)
    times = interval_midpoints(frame.index)
    location = building.location
    position = solar_position(times, location)
    ghi = np.clip(frame[GHI].to_numpy(dtype=float), 0.0, None)
    dni, dhi = _beam_and_diffuse(frame, times, ghi, location, decomposition, position)

    def plane(surface: Surface) -> pd.DataFrame:
        return surface_irradiance(
            times, ghi, dni, dhi, surface, location, sky_model, albedo, position
        )

    windows = _group_by_orientation(building.windows)
    walls = _group_by_orientation(building.walls)
    planes = {key: plane(s) for key, (s, _) in {**walls, **windows}.items()}
    per_window = {
        solar_orientation_signal(SOLAR_WINDOW, key): area
        * _glazing_irradiance(planes[key], s.tilt, iam_model)
        for key, (s, area) in windows.items()
    }
    per_wall = {
        solar_orientation_signal(SOLAR_OPAQUE, key): area * planes[key]["poa_global"].to_numpy()
        for key, (_, area) in walls.items()
    }
    zeros = np.zeros(len(frame))
    totals = {
        SOLAR_WINDOW: sum(per_window.values(), zeros),
        SOLAR_OPAQUE: sum(per_wall.values(), zeros),
    }
    return pd.DataFrame({**totals, **per_window, **per_wall}, index=frame.index)


def linke_turbidity(times: pd.DatetimeIndex, latitude: float, longitude: float) -> np.ndarray:
    """Linke turbidity at each instant [-]: pvlib's monthly climatology of the site
    (``LinkeTurbidities.h5``, Remund et al. 2003), each month's value placed at its middle day
    and interpolated linearly over the UTC day of the year, December and January repeated
    across the turn of the year — pvlib's own interpolation (``interp_turbidity=True``), done
    here on day numbers: pvlib's reads the deprecated ``DatetimeIndex.dayofyear``.
    """
    months = pd.date_range("2001-01-01", periods=12, freq="MS", tz="UTC") + pd.Timedelta(days=14)
    monthly = clearsky.lookup_linke_turbidity(
        months, latitude, longitude, interp_turbidity=False
    ).to_numpy()
    values = np.concatenate([monthly[-1:], monthly, monthly[:1]])
    utc = times.tz_convert("UTC")
    day = day_of_year(times)
    out = np.empty(len(times))
    for leap in (False, True):
        rows = np.asarray(utc.is_leap_year) == leap
        out[rows] = np.interp(day[rows], _month_middles(leap), values)
    return out


def _month_middles(leap: bool) -> np.ndarray:
    """Day of the year of the middle of each month, with last December's and next January's
    either side. [day]"""
    lengths = np.array(calendar.mdays[1:], dtype=float)
    lengths[1] += leap
    middles = np.cumsum(lengths) - lengths / 2.0
    return np.concatenate([[-lengths[11] / 2.0], middles, [lengths.sum() + lengths[0] / 2.0]])


def clear_sky_ghi(times: pd.DatetimeIndex, location: Location) -> np.ndarray:
    """Clear-sky global horizontal irradiance of the intervals starting at ``times``. [W/m²]

    Ineichen–Perez model with the monthly Linke turbidity climatology of the site
    (pvlib.clearsky.ineichen, lookup_linke_turbidity), at the interval midpoints; 0 at night.
    """
    # A diagnosis describes every candidate's correction by the sky's clearness over the same
    # rows: dozens of identical solar-position computations, a thirtieth of its time.
    instants = times.as_unit("ns")
    return _clear_sky_ghi(instants.asi8.tobytes(), instants.tz, location).copy()


@lru_cache(maxsize=8)
def _clear_sky_ghi(ns: bytes, tz: Any, location: Location) -> np.ndarray:
    """``clear_sky_ghi`` of the instants ``ns`` (int64 ns since the epoch) in time zone ``tz``."""
    times = pd.DatetimeIndex(np.frombuffer(ns, dtype=np.int64))
    times = times if tz is None else times.tz_localize("UTC").tz_convert(tz)
    midpoints = interval_midpoints(times)
    position = solar_position(midpoints, location)
    airmass = atmosphere.get_absolute_airmass(
        atmosphere.get_relative_airmass(position["apparent_zenith"].to_numpy()),
        atmosphere.alt2pres(location.altitude),
    )
    turbidity = linke_turbidity(midpoints, location.latitude, location.longitude)
    # The night rows (air mass NaN) divide by zero inside pvlib; they are set to 0 below.
    with np.errstate(divide="ignore", invalid="ignore"):
        clear = clearsky.ineichen(
            position["apparent_zenith"].to_numpy(),
            airmass,
            turbidity,
            altitude=location.altitude,
            dni_extra=extra_radiation(midpoints),
        )["ghi"]
    return np.nan_to_num(np.asarray(clear, dtype=float), nan=0.0)


def clear_sky_index(frame: pd.DataFrame, location: Location) -> np.ndarray:
    """Measured over clear-sky global horizontal irradiance, per row. [-]

    About 1 under a clear sky, below 0.3 when overcast. Clipped to [0, 1.5]; 0 at night and
    where ``ghi`` is missing, so the result has no NaN.
    """
    clear = clear_sky_ghi(frame.index, location)
    with np.errstate(divide="ignore", invalid="ignore"):
        index = irradiance.clearsky_index(
            frame[GHI].to_numpy(dtype=float), clear, max_clearsky_index=MAX_CLEAR_SKY_INDEX
        )
    return np.nan_to_num(np.asarray(index, dtype=float), nan=0.0)
