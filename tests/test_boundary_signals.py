"""Weekly schedules, the ground-temperature estimate and the sky temperature, by hand."""

import numpy as np
import pandas as pd
import pytest

import rcengine.signals.derived
from rcengine.building import Building
from rcengine.columns import T_GROUND, VENT_LOSS, VENT_SCHEDULE, WIND_LOSS, schedule_signal_name
from rcengine.exceptions import ModelError
from rcengine.io.timeseries import read_timeseries
from rcengine.signals.derived import SignalOptions, derive, derivers, mask_measured
from rcengine.signals.film import facade_wind, film_factor, film_resistance
from rcengine.signals.ground import YEAR_S, ground_depth, ground_temperature
from rcengine.signals.schedules import (
    clock_zone,
    closed_weekdays,
    describe,
    hour_of_week,
    on_hours,
    schedule_signal,
    weekly_profile,
)
from rcengine.signals.sky import (
    cloud_cover,
    cloud_cover_from_index,
    dew_point_estimate,
    sky_delta,
    sky_temperature,
)
from rcengine.signals.solar import solar_signal_names


def test_hour_of_week_is_local_time():
    # Monday 2017-01-09 07:00 UTC is 08:00 in Rome (UTC+1).
    times = pd.DatetimeIndex(["2017-01-09T07:00Z", "2017-01-15T22:30Z"])
    np.testing.assert_array_equal(hour_of_week(times, "Europe/Rome"), [8, 167])


def test_standard_clock_ignores_daylight_saving():
    # Monday 2017-07-10 07:00 UTC: 09:00 on Rome's summer clock, 08:00 on its standard time;
    # Sydney keeps daylight saving in January, its standard time is UTC+10.
    times = pd.DatetimeIndex(["2017-07-10T07:00Z"])
    assert hour_of_week(times, clock_zone("Europe/Rome", "local"))[0] == 9
    assert hour_of_week(times, clock_zone("Europe/Rome", "standard"))[0] == 8
    january = pd.DatetimeIndex(["2017-01-09T00:00Z"])
    assert hour_of_week(january, clock_zone("Australia/Sydney", "standard"))[0] == 10
    assert hour_of_week(january, clock_zone("Australia/Sydney", "local"))[0] == 11
    with pytest.raises(ValueError, match="unknown schedule clock 'solar'"):
        clock_zone("Europe/Rome", "solar")


def test_weekly_profile_round_trip_and_description():
    times = pd.date_range("2017-01-09", periods=4 * 7 * 96, freq="15min", tz="Europe/Rome")
    truth = np.zeros(168)
    for day in range(5):
        truth[day * 24 + 8 : day * 24 + 18] = 1.0
    signal = schedule_signal(truth, times, "Europe/Rome")
    profile = weekly_profile(signal + 0.01, times, "Europe/Rome")
    np.testing.assert_allclose(profile, truth + 0.01)
    np.testing.assert_array_equal(on_hours(profile), truth)
    assert describe(truth) == "Mon–Fri 08:00–18:00"
    # Two blocks in a day are two blocks in words, not one span over the hours between.
    saturday = truth.copy()
    saturday[5 * 24 + 2 : 5 * 24 + 6] = saturday[5 * 24 + 18 : 6 * 24] = 1.0
    assert describe(saturday) == "Mon–Fri 08:00–18:00, Sat 02:00–06:00 & 18:00–24:00"
    np.testing.assert_array_equal(on_hours(-np.ones(72)), np.zeros(72))
    with pytest.raises(ValueError, match="168"):
        schedule_signal(np.ones(24), times, "UTC")


def _office_weeks(weeks: int) -> pd.DataFrame:
    """``weeks`` of 15-min rows from Monday 2017-01-09 (Rome) with 5 kW of occupants on
    weekdays 08:00–18:00 and none otherwise."""
    times = pd.date_range("2017-01-09", periods=weeks * 7 * 96, freq="15min", tz="Europe/Rome")
    office_hours = (times.day_of_week < 5) & (times.hour >= 8) & (times.hour < 18)
    return pd.DataFrame({"q_occ": np.where(office_hours, 5000.0, 0.0)}, index=times)


def test_a_weekday_without_occupants_runs_the_sunday_schedule():
    frame = _office_weeks(3)
    local = frame.index.tz_convert("Europe/Rome")
    holiday = local.normalize() == pd.Timestamp("2017-01-18", tz="Europe/Rome")  # a Wednesday
    frame.loc[holiday, "q_occ"] = 0.0
    frame.loc[holiday & (local.hour == 10), "q_occ"] = 300.0  # a cleaner is not the office
    closed = closed_weekdays(frame, "Europe/Rome")
    np.testing.assert_array_equal(closed, holiday)
    weekdays_on = np.zeros(168)
    for day in range(5):
        weekdays_on[day * 24 + 8 : day * 24 + 18] = 1.0
    weekdays_on[6 * 24 + 10] = 0.5  # Sunday 10:00
    played = schedule_signal(weekdays_on, frame.index, "Europe/Rome", closed)
    assert played[holiday & (local.hour == 9)].max() == 0.0
    assert (played[holiday & (local.hour == 10)] == 0.5).all()
    np.testing.assert_array_equal(
        played[~holiday], schedule_signal(weekdays_on, frame.index[~holiday], "Europe/Rome")
    )
    # The derived schedule signal plays the closure too.
    building = Building.from_dict(
        {
            "name": "b",
            "location": {"latitude": 45.0, "longitude": 7.7, "timezone": "Europe/Rome"},
            "floor_area": 100.0,
            "volume": 300.0,
            "wall_area": 120.0,
        }
    )
    options = SignalOptions(schedules={"gains": weekdays_on.tolist()})
    signal = derive(frame, building, [schedule_signal_name("gains")], options)
    np.testing.assert_array_equal(signal[schedule_signal_name("gains")].to_numpy(), played)


def test_occupancy_that_does_not_tell_the_days_apart_closes_no_day():
    frame = _office_weeks(2)
    assert not closed_weekdays(frame.drop(columns="q_occ"), "Europe/Rome").any()
    assert not closed_weekdays(frame.assign(q_occ=0.0), "Europe/Rome").any()
    local = frame.index.tz_convert("Europe/Rome")
    mostly_empty = frame.assign(q_occ=np.where(local.day_of_week == 0, frame["q_occ"], 0.0))
    assert not closed_weekdays(mostly_empty, "Europe/Rome").any()
    unmetered = frame.assign(q_occ=np.where(local.day_of_week == 2, np.nan, frame["q_occ"]))
    assert not closed_weekdays(unmetered, "Europe/Rome").any()


def test_ground_temperature_is_a_slow_running_mean():
    step = 3600.0
    t_out = np.r_[np.full(24 * 60, 10.0), np.full(24 * 60, 0.0)]
    g = ground_temperature(t_out, step, tau_days=30)
    assert g[24 * 60 - 1] == pytest.approx(10.0)
    # one time constant after the step the soil has covered 1 − 1/e of it
    assert g[24 * 60 + 24 * 30] == pytest.approx(10.0 * np.exp(-1), rel=0.02)
    # daily swings are damped by ~1/(2π·30) ≈ 0.5 %
    daily = 5 * np.sin(np.arange(24 * 90) / 24 * 2 * np.pi)
    assert np.ptp(ground_temperature(daily, step)[-24 * 10 :]) < 0.2


def test_sky_temperature_by_hand():
    # Clark & Allen at a dew point of 0 °C: ε = 0.787 + 0.764 ln(273.15 / 273) = 0.7874
    t_sky = sky_temperature(np.array([5.0]), np.array([0.0]), np.array([0.0]))[0]
    assert t_sky == pytest.approx(0.7874**0.25 * 278.15 - 273.15, abs=0.05)
    drier = sky_temperature(np.array([5.0]), np.array([0.0]), np.array([-10.0]))[0]
    overcast = sky_temperature(np.array([5.0]), np.array([10.0]), np.array([0.0]))[0]
    assert drier < t_sky < overcast < 5.0  # dry air and clear skies are cold; clouds warm
    # Swinbank at 0 °C: ε = 9.365e-6 · 273.15² = 0.6987; T_sky = ε^¼ · T
    swinbank = sky_temperature(np.array([0.0]), np.array([0.0]), model="swinbank")[0]
    assert swinbank == pytest.approx(0.6987**0.25 * 273.15 - 273.15, abs=0.05)
    np.testing.assert_allclose(cloud_cover_from_index(np.array([1.0, 0.25, 0.0])), [0, 10, 10])
    with pytest.raises(ValueError, match="needs the dew point"):
        sky_temperature(np.array([0.0]), np.array([0.0]))


def test_the_dew_point_is_the_lowest_temperature_of_the_day_around():
    times = pd.date_range("2017-01-01", periods=72, freq="h", tz="UTC")
    t_out = pd.Series(5.0 + 5.0 * np.sin(2 * np.pi * np.arange(72) / 24), index=times)
    t_dew = dew_point_estimate(t_out)
    assert np.all(t_dew <= t_out.to_numpy())
    np.testing.assert_allclose(t_dew[12:-12], 0.0, atol=1e-9)


def test_stored_options_without_a_sky_model_keep_swinbank():
    """A parameter set stored before the dew point was estimated was fitted to Swinbank's sky;
    new options and stored ones that name their model keep what they say."""
    assert SignalOptions().sky_emissivity == "clark_allen"
    assert SignalOptions.from_stored({"sky_model": "perez"}).sky_emissivity == "swinbank"
    stored = SignalOptions(sky_emissivity="clark_allen").to_dict()
    assert SignalOptions.from_stored(stored) == SignalOptions()


def test_the_outer_film_follows_iso_6946_annex_c():
    """h_se = 4 + 4·v + ε·h_r0 (ε 0.9, 0 °C): 0.082 m²K/W at 1 m/s (a sheltered facade), the
    design 0.04 at 4 m/s. The facade's wind is the station's carried to 5 m of a suburban site
    (ASHRAE's power law: (270/10)^0.14 · (5/370)^0.22 = 0.615); the factor is 1 where the facade
    has 1 m/s, and a gale cuts a calm day's share by more than half."""
    h_re = 0.9 * 4 * 5.67e-8 * 273.15**3
    np.testing.assert_allclose(
        film_resistance([0.0, 1.0, 4.0]), 1 / (4.0 + h_re + 4.0 * np.array([0.0, 1.0, 4.0]))
    )
    assert film_resistance(1.0) == pytest.approx(0.082, abs=5e-4)
    assert film_resistance(4.0) == pytest.approx(0.04, abs=2e-3)
    ratio = (270 / 10) ** 0.14 * (5 / 370) ** 0.22
    assert ratio == pytest.approx(0.615, abs=1e-3)
    np.testing.assert_allclose(facade_wind([0.0, 10.0]), [0.0, 10.0 * ratio])
    assert film_factor(1.0 / ratio) == pytest.approx(1.0)
    assert film_factor(0.0) / film_factor(15.0) > 2.0
    assert film_factor(-1.0) == film_factor(0.0)  # no negative wind


def test_the_wind_strips_the_sun_of_the_opaque_facades_only(project_data):
    """With the film "wind", each orientation's opaque sun is scaled by the film factor of the
    row's wind; the window's sun, the thesis's summed opaque sun and the sky are not. Stored
    options without the setting keep the fixed film, and a model so fitted says it needs the
    wind."""
    office = project_data / "energyplus" / "office"
    building = Building.from_json(office / "building.json")
    frame = read_timeseries(office / "heating.csv").iloc[: 2 * 96]
    frame = frame.assign(wind_speed=np.linspace(0.0, 9.0, len(frame)))
    names = [n for n in solar_signal_names(building) if n.startswith("solar_")]
    names += ["sky_delta"]
    fixed = derive(frame, building, names, SignalOptions())
    windy = SignalOptions(exterior_film="wind")
    filmed = derive(frame, building, names, windy)
    factor = film_factor(frame["wind_speed"].to_numpy())
    for name in names:
        scaled = name.startswith("solar_opaque_")
        expected = fixed[name] * factor if scaled else fixed[name]
        np.testing.assert_allclose(filmed[name], expected, err_msg=name)
    assert any(n.startswith("solar_opaque_") for n in names)
    assert SignalOptions.from_stored({"sky_model": "isotropic"}).exterior_film == "fixed"
    assert SignalOptions.from_stored(windy.to_dict()) == windy
    calm = frame.drop(columns="wind_speed")
    with pytest.raises(ModelError, match="needs the column 'wind_speed'"):
        derive(calm, building, names, windy)
    # A model with the setting but no opaque sun (it was dropped) needs no wind.
    others = [n for n in names if not n.startswith("solar_opaque_")]
    pd.testing.assert_frame_equal(derive(calm, building, others, windy), fixed[others])
    with pytest.raises(ValueError, match="exterior_film"):
        SignalOptions(exterior_film="calm")


def test_t_ground_reads_the_soil_at_the_stored_depth(project_data):
    """A model stored before the depth was a setting was fitted to the wave a month deep (1.66 m)
    and keeps it; one fitted a month and a half deep is served that wave, damped further."""
    building = Building.from_json(project_data / "energyplus" / "office" / "building.json")
    times = pd.date_range("2017-01-01", "2017-12-31 23:00", freq="h", tz="UTC")
    coldest = pd.Timestamp("2017-01-16", tz="UTC")
    phase = 2 * np.pi * (times - coldest).total_seconds().to_numpy() / YEAR_S
    frame = pd.DataFrame({"t_out": 12.0 - 9.0 * np.cos(phase)}, index=times)
    old = SignalOptions.from_stored({"sky_model": "isotropic"})
    assert old.ground_depth_m == pytest.approx(1.66, abs=0.005)
    deeper = SignalOptions(ground_depth_m=ground_depth(YEAR_S / 8))
    assert SignalOptions.from_stored(deeper.to_dict()) == deeper
    swing = {
        lag: np.ptp(derive(frame, building, [T_GROUND], options)[T_GROUND]) / 2.0
        for lag, options in ((12, old), (8, deeper))
    }
    assert swing[12] == pytest.approx(9.0 * np.exp(-2 * np.pi / 12), abs=0.01)
    assert swing[8] == pytest.approx(9.0 * np.exp(-2 * np.pi / 8), abs=0.01)


def test_a_cloud_cover_column_drives_the_sky_where_it_has_values(project_data):
    """The data's cloud cover [%] replaces the daylight estimate row by row (rows without one
    keep the estimate); an overcast sky is warmer than a clear one; the options ask for it when
    the data have the column, and a model fitted so cannot run on data without it."""
    office = project_data / "energyplus" / "office"
    building = Building.from_json(office / "building.json")
    frame = read_timeseries(office / "heating.csv").iloc[: 3 * 96]
    location = building.location
    estimate = cloud_cover(frame, location)
    clouded = frame.assign(cloud_cover=np.where(np.arange(len(frame)) < 96, 100.0, np.nan))
    measured = cloud_cover(clouded, location, "column")
    np.testing.assert_allclose(measured[:96], 10.0)
    np.testing.assert_allclose(measured[96:], estimate[96:])
    clear = frame.assign(cloud_cover=0.0)
    assert np.all(
        sky_delta(clouded, location, cloud="column")[:96]
        > sky_delta(clear, location, cloud="column")[:96]
    )
    with pytest.raises(ValueError, match="cloud_cover"):
        cloud_cover(frame, location, "column")
    with pytest.raises(ValueError, match="unknown cloud cover source"):
        cloud_cover(frame, location, "satellite")
    options = SignalOptions.for_columns(clouded.columns)
    assert options.cloud_cover == "column"
    assert SignalOptions.for_columns(frame.columns, sky_model="perez") == SignalOptions(
        sky_model="perez"
    )
    with pytest.raises(ModelError, match="needs the column 'cloud_cover'"):
        derive(frame, building, ["sky_delta"], options)


def test_the_dew_point_sky_follows_the_weather_files_infrared(shared_data):
    """Against the sky the EPW's infrared field records (EnergyPlus's), over each heating season
    of the project's weather files: the dew-point estimate tracks it better than Swinbank's and
    is less biased (``benchmarks/sky_temperature.py``)."""
    from benchmarks.sky_temperature import COLUMN, ESTIMATE, compare, weather_files

    files = [f for f in weather_files() if f.exists()]
    assert files
    for path in files:
        figures = compare(path)
        new, old = figures[ESTIMATE]["all"], figures["swinbank"]["all"]
        assert new["r2"] > old["r2"], (path.name, new, old)
        assert abs(new["bias_k"]) < abs(old["bias_k"]), (path.name, new, old)
        # The file's own cloud cover as the data's column: the night is no longer a guess.
        column = figures[COLUMN]["night"]
        assert column["r2"] > 0.85 > figures[ESTIMATE]["night"]["r2"], (path.name, column)


def test_each_deriver_runs_once_for_all_its_signals(project_data, monkeypatch):
    """Every derivable signal in one request: each function runs once — the sun too, for the
    summed and the per-orientation signals, the windows' and the walls' — and every column equals
    the one it gives when asked alone (wind_loss and vent_loss share no work, so they are not
    computed twice)."""
    office = project_data / "energyplus" / "office"
    building = Building.from_json(office / "building.json")
    frame = read_timeseries(office / "heating.csv").iloc[: 3 * 96]
    week = np.tile(np.r_[np.zeros(8), np.ones(10), np.zeros(6)], 7).tolist()
    options = SignalOptions(schedules={VENT_SCHEDULE: week, "gains": week}, exterior_film="wind")
    names = list(derivers(building, options))
    assert {WIND_LOSS, VENT_LOSS, schedule_signal_name("gains")} <= set(names)
    alone = {n: derive(frame, building, [n], options)[n] for n in names}
    calls: dict[str, int] = {}

    def counted(name: str):
        function = getattr(rcengine.signals.derived, name)

        def wrapper(*args, **kwargs):
            calls[name] = calls.get(name, 0) + 1
            return function(*args, **kwargs)

        return wrapper

    for function in {f.__name__ for f in derivers(building, options).values()} | {"solar_gains"}:
        monkeypatch.setattr(rcengine.signals.derived, function, counted(function))
    together = derive(frame, building, names, options)
    assert sorted(together.columns) == sorted(names)
    assert calls and set(calls.values()) == {1}, calls
    for name in names:
        pd.testing.assert_series_equal(together[name], alone[name], check_exact=True)


def test_signals_are_routed_by_name_not_prefix(project_data):
    office = project_data / "energyplus" / "office"
    building = Building.from_json(office / "building.json")
    frame = read_timeseries(office / "heating.csv").iloc[:96]
    # The office has no south-facing window; a solar-looking name is not a solar signal.
    with pytest.raises(ModelError, match="solar_window_180_90"):
        derive(frame, building, ["solar_window_180_90"], SignalOptions())
    with pytest.raises(ModelError, match="needs a 'vent' schedule"):
        derive(frame, building, [VENT_LOSS], SignalOptions())
    with pytest.raises(ModelError, match="needs the column 'wind_speed'"):
        derive(frame.drop(columns="wind_speed"), building, [WIND_LOSS], SignalOptions())


def test_air_exchange_losses_run_on_the_measured_indoor_temperature(project_data):
    """wind_loss = wind·(t_out − t_in): the measured t_in, carried over a gap and past the last
    measurement, 20 °C before the first; a forecast's horizon is masked (``mask_measured``) so
    its inputs cannot hold the temperature it predicts."""
    office = project_data / "energyplus" / "office"
    building = Building.from_json(office / "building.json")
    frame = read_timeseries(office / "heating.csv").iloc[:6].copy()
    frame["t_out"], frame["wind_speed"] = 0.0, 2.0
    frame["t_in"] = [np.nan, 18.0, np.nan, 16.0, 25.0, 26.0]
    loss = derive(frame, building, [WIND_LOSS], SignalOptions())[WIND_LOSS]
    np.testing.assert_allclose(loss, [-40.0, -36.0, -36.0, -32.0, -50.0, -52.0])
    masked = mask_measured(frame, frame.index[4])
    assert masked["t_in"].iloc[:4].equals(frame["t_in"].iloc[:4])
    assert masked["t_in"].iloc[4:].isna().all() and frame["t_in"].iloc[4:].notna().all()
    ahead = derive(masked, building, [WIND_LOSS], SignalOptions())[WIND_LOSS]
    np.testing.assert_allclose(ahead.iloc[3:], [-32.0, -32.0, -32.0])
    no_sensor = derive(frame.drop(columns="t_in"), building, [WIND_LOSS], SignalOptions())
    np.testing.assert_allclose(no_sensor[WIND_LOSS], -40.0)
