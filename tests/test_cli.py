"""`rcengine fit` / `rcengine predict` exactly as CONTRACT.md §3, on files, through the CLI.

Two data sets: the committed EnergyPlus office (a realistic week, loose forecast bound) and the
hand-written reference of tests/synthetic.py (the model is exact, so the forecast must match the
held-back measurements to the noise level)."""

import json
from importlib.metadata import entry_points
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from rcengine import __version__
from rcengine.cli import app
from rcengine.columns import T_IN, TIME

from .synthetic import BUILDING, TRUTH_BASIC, basic_reference, weather_and_gains

OFFICE_FIT = ("2017-01-09T00:00:00+01:00", "2017-01-16T00:00:00+01:00")  # Monday to Monday
OFFICE_FORECAST_START = OFFICE_FIT[1]
FORECAST_HOURS = 24
STEPS_PER_DAY = 96
# Stated bound on the 24 h forecast of the EnergyPlus office by `basic` [K] (measured 0.85 K;
# holding the last measured value instead gives 6.3 K).
OFFICE_FORECAST_RMSE_K = 1.2
NOISE_K = 0.02
# The synthetic data are made by the Basic equations: a forecast within 2.5× the noise.
SYNTHETIC_FORECAST_RMSE_K = 2.5 * NOISE_K

runner = CliRunner()


def invoke(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def hold_back(table: pd.DataFrame, start: str) -> pd.DataFrame:
    """The same rows with t_in emptied from ``start`` on (the future a forecast must predict)."""
    future = pd.to_datetime(table[TIME], utc=True) >= pd.Timestamp(start)
    return table.assign(**{T_IN: table[T_IN].where(~future, "")})


@pytest.fixture(scope="module")
def office(project_data, tmp_path_factory) -> dict[str, Path]:
    """CSV excerpts of the EnergyPlus office (cells kept as written): the fit week plus the
    forecast day, once measured and once with t_in held back."""
    folder = tmp_path_factory.mktemp("office")
    source = project_data / "energyplus" / "office"
    table = pd.read_csv(source / "heating.csv", dtype=str, keep_default_na=False)
    times = pd.to_datetime(table[TIME], utc=True)
    end = pd.Timestamp(OFFICE_FORECAST_START) + pd.Timedelta(hours=FORECAST_HOURS)
    table = table[(times >= pd.Timestamp(OFFICE_FIT[0])) & (times < end)]
    files = {"measured": folder / "measured.csv", "future": folder / "future.csv"}
    table.to_csv(files["measured"], index=False)
    hold_back(table, OFFICE_FORECAST_START).to_csv(files["future"], index=False)
    files["building"] = source / "building.json"
    return files


@pytest.fixture(scope="module")
def office_fit(office, tmp_path_factory) -> dict:
    """One `rcengine fit` of the office week: the CLI result, params.json and its path."""
    out = tmp_path_factory.mktemp("fit") / "params.json"
    result = invoke(
        "fit", office["measured"], "--building", office["building"], "--model", "basic",
        "--start", OFFICE_FIT[0], "--end", OFFICE_FIT[1], "-o", out,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    return {"result": result, "params": json.loads(out.read_text()), "path": out}


def test_console_script_is_installed():
    (script,) = entry_points(group="console_scripts", name="rcengine")
    assert script.value == "rcengine.cli:app"


def test_fit_writes_params_json(office_fit):
    params = office_fit["params"]
    assert params["model"] == "basic"
    assert params["engine_version"] == __version__
    names = {"r_wall_ext", "r_wall_int", "r_int", "c_wall", "c_air", "c_int"}
    assert names | {"alpha_wall", "alpha_int"} == set(params["parameters"])
    for name, p in params["parameters"].items():
        assert p["lower"] <= p["value"] <= p["upper"], name
        assert p["unit"], name
    train = params["metrics"]["train"]
    assert {"rmse", "mbe", "cv_rmse", "nmbe", "ashrae14_pass"} <= set(train)
    assert 0.0 < train["rmse"] < 1.0
    assert train["n"] == 7 * STEPS_PER_DAY
    assert f"training RMSE {train['rmse']:.3f} K" in office_fit["result"].output


def test_start_and_end_restrict_the_fit_window(office_fit):
    fit = office_fit["params"]["fit"]
    # The excerpt runs a day longer than the window; only the window was fitted.
    assert pd.Timestamp(fit["start"]) == pd.Timestamp(OFFICE_FIT[0])
    assert pd.Timestamp(fit["end"]) == pd.Timestamp(OFFICE_FIT[1])
    assert fit["rows"] == 7 * STEPS_PER_DAY
    assert fit["step_s"] == 900.0


def test_predict_office_day(office, office_fit, tmp_path):
    out = tmp_path / "forecast.csv"
    result = invoke(
        "predict", office["future"], "--params", office_fit["path"],
        "--start", OFFICE_FORECAST_START, "--hours", FORECAST_HOURS, "-o", out,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert out.read_text().splitlines()[0] == "time,t_in_pred"
    forecast = pd.read_csv(out)
    assert len(forecast) == FORECAST_HOURS * 4
    times = pd.to_datetime(forecast[TIME], utc=True)
    assert times.iloc[0] == pd.Timestamp(OFFICE_FORECAST_START)
    assert (times.diff().dropna() == pd.Timedelta(minutes=15)).all()
    assert forecast[TIME].iloc[0].endswith("+01:00")  # the building's local offset
    measured = pd.read_csv(office["measured"])
    held_back = measured.set_index(TIME).loc[forecast[TIME], T_IN].to_numpy()
    assert rmse(forecast["t_in_pred"], held_back) < OFFICE_FORECAST_RMSE_K


def test_fit_and_predict_recover_synthetic_truth(tmp_path, monkeypatch):
    """Nine days from the reference: a warm-up day, seven fitted, one forecast."""
    monkeypatch.chdir(tmp_path)
    frame = weather_and_gains(days=9)
    frame["q_hvac"] *= 0.25  # keeps the zone at plausible temperatures
    frame[T_IN] = basic_reference(frame, TRUTH_BASIC, x0=(9.0, 19.0, 18.0))
    frame[T_IN] += np.random.default_rng(11).normal(0.0, NOISE_K, len(frame))
    table = frame.rename_axis(TIME).reset_index()
    table[TIME] = [t.isoformat() for t in frame.index]
    start, forecast_start = frame.index[STEPS_PER_DAY], frame.index[8 * STEPS_PER_DAY]
    table.to_csv("measured.csv", index=False)
    hold_back(table.astype({T_IN: str}), forecast_start.isoformat()).to_csv(
        "future.csv", index=False
    )
    Path("building.json").write_text(json.dumps(BUILDING.to_dict()))

    fit = invoke(
        "fit", "measured.csv", "--building", "building.json", "--model", "basic",
        "--start", start.isoformat(), "--end", forecast_start.isoformat(), "-o", "params.json",
    )  # fmt: skip
    assert fit.exit_code == 0, fit.output
    params = json.loads(Path("params.json").read_text())
    assert params["metrics"]["train"]["rmse"] < 1.5 * NOISE_K
    predict = invoke(
        "predict", "future.csv", "--params", "params.json", "--start",
        forecast_start.isoformat(), "--hours", FORECAST_HOURS, "-o", "forecast.csv",
    )  # fmt: skip
    assert predict.exit_code == 0, predict.output
    forecast = pd.read_csv("forecast.csv")
    assert list(forecast.columns) == [TIME, "t_in_pred"]
    held_back = frame[T_IN].to_numpy()[8 * STEPS_PER_DAY :]
    assert len(forecast) == len(held_back) == STEPS_PER_DAY
    assert rmse(forecast["t_in_pred"], held_back) < SYNTHETIC_FORECAST_RMSE_K


# --- bad inputs: non-zero exit and a message naming the problem ----------------------------------


@pytest.fixture
def workdir(office, tmp_path, monkeypatch) -> Path:
    """Short relative names, so that messages (boxed by the CLI at 80 columns) keep them whole."""
    monkeypatch.chdir(tmp_path)
    Path("data.csv").write_text(office["measured"].read_text())
    Path("b.json").write_text(office["building"].read_text())
    return tmp_path


def predict_day(params: str):
    """``predict`` of a day of the working folder's data with the parameter file ``params``."""
    return invoke(
        "predict", "data.csv", "--params", params, "--start", OFFICE_FORECAST_START,
        "--hours", "24", "-o", "f.csv",
    )  # fmt: skip


def test_missing_data_file(workdir):
    result = invoke("fit", "nope.csv", "--building", "b.json", "--model", "basic", "-o", "p.json")
    assert result.exit_code != 0
    assert "'nope.csv' does not exist" in result.output
    assert not Path("p.json").exists()


def test_missing_params_file(workdir):
    result = predict_day("nope.json")
    assert result.exit_code != 0
    assert "'nope.json' does not exist" in result.output


def test_bad_csv_row_is_named(workdir):
    lines = Path("data.csv").read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[11].split(",")  # data row 10, line 12 of the file
    cells[header.index("t_out")] = "warm"
    lines[11] = ",".join(cells)
    Path("data.csv").write_text("\n".join(lines) + "\n")
    result = invoke("fit", "data.csv", "--building", "b.json", "--model", "basic", "-o", "p.json")
    assert result.exit_code != 0
    assert "row 10, column 't_out'" in result.output
    assert "'warm'" in result.output
    assert "line 12" in result.output
    assert not Path("p.json").exists()


def test_unknown_model_is_named(workdir):
    result = invoke("fit", "data.csv", "--building", "b.json", "--model", "3r9c", "-o", "p.json")
    assert result.exit_code != 0
    assert "invalid model '3r9c'" in result.output
    assert "basic" in result.output and "sun" in result.output  # the choices


def test_invalid_params_file_is_named(workdir):
    Path("p.json").write_text("{not json")
    result = predict_day("p.json")
    assert result.exit_code != 0
    assert "p.json: not valid JSON" in result.output
    assert not Path("f.csv").exists()


# --- date options: every command reads the same forms, bad ones name the option -----------------

OFFICE_ZONE_DAY = ("2017-01-09", "2017-01-16")  # local dates of OFFICE_FIT in Europe/Rome
BAD_INSTANTS = {
    "unparseable": "9/1/2017",
    "month 13": "2017-13-01",
    "outside pandas' range": "2300-01-01",
    "skipped by daylight saving": "2017-03-26T02:30",
}


def test_fit_reads_local_dates_in_the_buildings_zone(office, office_fit, tmp_path):
    out = tmp_path / "params.json"
    result = invoke(
        "fit", office["measured"], "--building", office["building"], "--model", "basic",
        "--start", OFFICE_ZONE_DAY[0], "--end", OFFICE_ZONE_DAY[1], "-o", out,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    fit, by_offset = json.loads(out.read_text())["fit"], office_fit["params"]["fit"]
    for key in ("start", "end", "rows"):  # the same window as the offset instants
        assert fit[key] == by_offset[key], key


@pytest.mark.parametrize("zoned", [True, False])
def test_a_building_without_a_time_zone_is_read_in_utc_with_a_warning(workdir, zoned):
    description = json.loads(Path("b.json").read_text())
    if not zoned:
        del description["location"]["timezone"]
    Path("b.json").write_text(json.dumps(description))
    result = invoke(
        "fit", "data.csv", "--building", "b.json", "--model", "basic",
        "--start", OFFICE_FIT[0], "--end", OFFICE_FIT[1], "-o", "p.json",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    warned = "warning: location.timezone is not given" in result.stderr
    assert warned != zoned, result.stderr
    zone = json.loads(Path("p.json").read_text())["building"]["location"]["timezone"]
    assert zone == (description["location"]["timezone"] if zoned else "UTC")


def test_predict_reads_a_local_date_in_the_parameter_files_zone(office, office_fit, tmp_path):
    out = tmp_path / "forecast.csv"
    result = invoke(
        "predict", office["future"], "--params", office_fit["path"],
        "--start", OFFICE_ZONE_DAY[1], "--hours", FORECAST_HOURS, "-o", out,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    first = pd.read_csv(out)[TIME].iloc[0]
    assert pd.Timestamp(first) == pd.Timestamp(OFFICE_FORECAST_START)


@pytest.mark.parametrize("form", [OFFICE_FIT, OFFICE_ZONE_DAY], ids=["offset", "local date"])
def test_study_reads_instants_and_local_dates_alike(workdir, monkeypatch, form):
    """The study's days are chosen from the instants the CLI parsed (run and writing stubbed)."""
    import rcengine.study.report
    import rcengine.study.run

    seen = {}

    def run_study(frame, building, settings, progress):
        seen["settings"] = settings
        return pd.DataFrame({"day": [0]})  # one day predicted

    monkeypatch.setattr(rcengine.study.run, "run_study", run_study)
    monkeypatch.setattr(rcengine.study.report, "write_study", lambda *args: [])
    result = invoke(
        "study", "data.csv", "--building", "b.json", "-o", "out", "--start", form[0],
        "--end", form[1], "--workers", "1",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    settings = seen["settings"]
    assert settings.start == pd.Timestamp(OFFICE_FIT[0])
    assert settings.end == pd.Timestamp(OFFICE_FIT[1])


@pytest.mark.parametrize("criterion", [None, "likelihood"], ids=["default", "likelihood"])
def test_study_passes_the_criterion(workdir, monkeypatch, criterion):
    """--criterion reaches the study's settings; without it the study keeps output error (the
    published figures); an unknown criterion is refused (run and writing stubbed)."""
    import rcengine.study.report
    import rcengine.study.run

    seen, frame = {}, pd.DataFrame({"day": [0]})
    monkeypatch.setattr(
        rcengine.study.run, "run_study", lambda *args: seen.setdefault("s", args[2]) and frame
    )
    monkeypatch.setattr(rcengine.study.report, "write_study", lambda *args: [])
    args = ["study", "data.csv", "--building", "b.json", "-o", "out", "--workers", "1"]
    result = invoke(*args, *([] if criterion is None else ["--criterion", criterion]))
    assert result.exit_code == 0, result.output
    assert seen["s"].criterion == (criterion or "output_error")
    refused = invoke(*args, "--criterion", "bogus")
    assert refused.exit_code == 2 and "invalid criterion 'bogus'" in refused.output


def date_commands(start: str, end: str | None = None) -> dict[str, list[str]]:
    """Each command with date options, its --start (and --end) set; outputs p.json, f.csv, out."""
    fit = ["fit", "data.csv", "--building", "b.json", "--model", "basic", "-o", "p.json"]
    study = ["study", "data.csv", "--building", "b.json", "-o", "out"]
    commands = {"fit": fit, "study": study}
    if end is None:
        commands["predict"] = [
            "predict", "data.csv", "--params", "params.json", "--hours", "24", "-o", "f.csv"
        ]  # fmt: skip
    window = ["--start", start] + ([] if end is None else ["--end", end])
    return {name: args + window for name, args in commands.items()}


def assert_refused(result, message: str) -> None:
    """Exit code 2 (not a traceback's 1), one line naming the option, nothing written."""
    assert result.exit_code == 2, result.output
    assert isinstance(result.exception, SystemExit), result.exception
    assert message in result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert "Traceback" not in result.output
    for written in ("p.json", "f.csv", "out"):
        assert not Path(written).exists(), written


@pytest.mark.parametrize("bad", BAD_INSTANTS.values(), ids=BAD_INSTANTS.keys())
@pytest.mark.parametrize("option", ["--start", "--end"])
def test_bad_date_option_is_named(workdir, office_fit, bad, option):
    Path("params.json").write_text(office_fit["path"].read_text())
    start, end = (OFFICE_FIT[0], bad) if option == "--end" else (bad, None)
    for command, args in date_commands(start, end).items():
        result = invoke(*args)
        assert_refused(result, f"{option} {bad!r} is not an ISO 8601 time")
        assert "Europe/Rome" in result.output, command  # the zone local dates are read in


@pytest.mark.parametrize("end", [OFFICE_FIT[0], "2017-01-08"], ids=["equal", "before"])
def test_start_not_before_end_is_refused(workdir, end):
    for args in date_commands(OFFICE_FIT[0], end).values():
        assert_refused(invoke(*args), f"--start {OFFICE_FIT[0]!r} is not before --end {end!r}")


# --- found by probing the CLI (nineteenth session): each was a traceback ------------------------
FIT = ["fit", "data.csv", "--building", "b.json", "--model", "basic"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["fit", "data.csv", "--building", "adir", "-m", "basic", "-o", "p.json"], "cannot read"),
        (["fit", "data.csv", "--building", "bin.json", "-m", "basic", "-o", "p.json"], "not UTF-8"),
        ([*FIT, "--preset", "nosuch", "-o", "p.json"], "invalid preset 'nosuch'"),
        ([*FIT, "--sky-model", "nosuch", "-o", "p.json"], "--sky-model must be one of"),
        ([*FIT, "-o", "nowhere/p.json"], "does not exist"),
        ([*FIT, "-o", "adir"], "is a directory"),
        ([*FIT, "-o", "/proc/p.json"], "cannot write there"),
        ([*FIT, "-o", "b.json"], "is also an input"),
        (["study", "data.csv", "--building", "b.json", "--models", ",", "-o", "out"], "no model"),
    ],
)
def test_bad_files_and_options_are_one_line_before_any_work(workdir, args, message):
    Path("adir").mkdir()
    Path("bin.json").write_bytes(bytes(range(128, 256)))
    before = Path("b.json").read_text()
    result = invoke(*args)
    assert_refused(result, message)
    assert Path("b.json").read_text() == before


@pytest.mark.parametrize("hours", ["nan", "inf", "1e9"])
def test_a_horizon_that_is_no_number_of_hours_is_refused(workdir, office_fit, hours):
    Path("params.json").write_text(office_fit["path"].read_text())
    result = invoke(
        "predict", "data.csv", "--params", "params.json", "--start", OFFICE_FORECAST_START,
        "--hours", hours, "-o", "f.csv",
    )  # fmt: skip
    assert_refused(result, "--hours must be a finite horizon")


def test_a_result_is_written_whole_or_the_old_file_stays(workdir, office_fit, monkeypatch):
    """Written in place, a failure mid-write (a full disk) left half a file where the previous
    good one had been."""
    import os

    Path("p.json").write_text('{"previous": true}\n')

    class FullDisk:
        def __init__(self, handle):
            self.handle = handle

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.handle.close()

        def write(self, text):
            self.handle.write(text[:100])
            raise OSError(28, "No space left on device")

    real_fdopen = os.fdopen
    monkeypatch.setattr(os, "fdopen", lambda fd, *a, **k: FullDisk(real_fdopen(fd, *a, **k)))
    window = ["--start", OFFICE_FIT[0], "--end", OFFICE_FIT[1], "--preset", "default"]
    result = invoke(*FIT, *window, "-o", "p.json")
    assert result.exit_code == 2 and "No space left on device" in result.output
    assert Path("p.json").read_text() == '{"previous": true}\n'
    assert [p.name for p in Path().iterdir() if p.name.startswith(".p.json")] == []


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"value": float("nan")}, "is outside its bounds"),
        ({"value": -1.0}, "is outside its bounds"),
        ({"value": 1e308}, "is outside its bounds"),
    ],
)
def test_a_hand_edited_parameter_file_is_refused(workdir, office_fit, change, message):
    """A NaN or a negative resistance forecast NaN (or nonsense) with exit code 0."""
    document = json.loads(office_fit["path"].read_text())
    document["parameters"]["r_wall_ext"].update(change)
    Path("params.json").write_text(json.dumps(document))
    assert_refused(predict_day("params.json"), message)


def test_a_parameter_file_of_a_newer_format_is_refused(workdir, office_fit):
    document = {**json.loads(office_fit["path"].read_text()), "format_version": 99}
    Path("params.json").write_text(json.dumps(document))
    assert_refused(predict_day("params.json"), "newer than this engine's")


def test_a_fit_on_fewer_rows_than_unknowns_is_refused(workdir):
    lines = Path("data.csv").read_text().splitlines()[:4]
    Path("data.csv").write_text("\n".join(lines) + "\n")
    result = invoke(*FIT, "-o", "p.json")
    assert result.exit_code == 2 and "cannot calibrate 11 unknowns" in result.output
    assert "Traceback" not in result.output and not Path("p.json").exists()


def test_a_forecast_start_the_data_cannot_start_names_the_option(workdir, office_fit):
    Path("params.json").write_text(office_fit["path"].read_text())
    result = invoke(
        "predict", "data.csv", "--params", "params.json", "--start", "2017-03-01",
        "--hours", "24", "-o", "f.csv",
    )  # fmt: skip
    assert_refused(result, "--start 2017-03-01: column 't_in': no measurements in the step before")
