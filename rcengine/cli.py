"""Command line (CONTRACT.md §3); ``rcengine COMMAND --help`` describes each option.

- ``fit DATA -b BUILDING (-m MODEL | --model-file SPEC) -o PARAMS [--start --end --preset
  --weekdays --seed --sky-model]``: calibrate MODEL, write its parameter set;
- ``predict DATA -p PARAMS --start START --hours H -o FORECAST``: forecast ``t_in``;
- ``models [--json]``: the model library;
- ``diagnose DATA -b BUILDING [-m MODEL --json REPORT --html REPORT --train-fraction --seed
  --save-model SPEC]``: locate the model–data mismatch, name the missing physics, save the
  extended model for ``fit --model-file``;
- ``study DATA -b BUILDING -o FOLDER [--freefloat --models --start --end --workers --preset
  --seed --criterion]``: the thesis's rolling learn/predict study.

Every ``--start``/``--end`` is an ISO 8601 time with a UTC offset or a local date in the
building's time zone (``rcengine.io.instants``). Engine errors and bad values end in one line,
``error: …``, and exit code 2.
"""

from __future__ import annotations

import io
import json
import math
import os
import sys
import tempfile
import warnings
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Annotated, NoReturn

import pandas as pd
import typer

from rcengine.building import Building
from rcengine.dataset import bridge_short_gaps
from rcengine.estimation import PRESETS, Estimator, settings_for
from rcengine.estimation.estimator import CRITERIA, check_criterion
from rcengine.estimation.likelihood import LikelihoodFit
from rcengine.exceptions import ConvergenceWarning, DataValidationError, RCEngineError
from rcengine.forecast import forecast_frame
from rcengine.io.files import file_error, write_text_atomic
from rcengine.io.instants import parse_instant
from rcengine.io.timeseries import read_timeseries, write_timeseries
from rcengine.models import available_models, get_model
from rcengine.models.spec import ModelSpec, check_columns
from rcengine.network import RCNetwork
from rcengine.parameter_set import ParameterSet
from rcengine.signals import SignalOptions, prepare
from rcengine.signals.solar import SKY_MODELS
from rcengine.statespace import HOLDS

app = typer.Typer(
    help="Grey-box RC thermal models of buildings: calibrate, forecast, diagnose.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)

DataArg = Annotated[Path, typer.Argument(help="time-series CSV (CONTRACT.md §1)", exists=True)]
BuildingOpt = Annotated[
    Path, typer.Option("--building", "-b", help="building JSON (CONTRACT.md §2)", exists=True)
]
WHEN = "ISO 8601 with UTC offset, or a local date in the building's time zone"
# The longest forecast a command computes: a (leap) year. [h]
MAX_HORIZON_H = 8784.0
# Worker processes a study may start: more only queue, and 100,000 hung the machine.
MAX_WORKERS = 256


def fail(message: str) -> NoReturn:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code=2)


def warn(message: str) -> None:
    typer.secho(f"warning: {message}", fg=typer.colors.YELLOW, err=True)


def _building(path: Path) -> Building:
    """The building description, each default it leaves that changes results said as a
    warning (``Building.notes``)."""
    building = Building.from_json(path)
    for note in building.notes:
        warn(note)
    return building


def _check(check: Callable[[str], object], value: str) -> None:
    """Refuse an invalid option value before any work, with the engine's own message."""
    try:
        check(value)
    except ValueError as exc:
        fail(str(exc))


def _run(fn):
    """Turn the engine's own errors, and a file that cannot be read or written (a full disk),
    into a one-line message and exit code 2."""
    try:
        return fn()
    except RCEngineError as exc:
        fail(str(exc))
    except OSError as exc:
        fail(file_error(exc))


def _output(path: Path | None, option: str, *inputs: Path | None) -> None:
    """Refuse, before any work, an output that cannot be written or would replace an input:
    found only after a whole fit, a bad path ended in a traceback."""
    if path is None:
        return
    target = path.resolve()
    if any(i is not None and i.resolve() == target for i in inputs):
        fail(f"{option} {path} is also an input; write the result to another file")
    if target.is_dir():
        fail(f"{option} {path} is a directory; give a file name")
    parent = target.parent
    if not parent.is_dir():
        fail(f"{option} {path}: the folder {parent} does not exist")
    # A file created where the result will be renamed in (``write_text_atomic``): permission
    # bits say nothing of /proc or a read-only mount.
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{target.name}.", dir=parent)
    except OSError as exc:
        fail(f"{option} {path}: cannot write there ({exc.strerror or exc})")
    os.close(fd)
    os.unlink(probe)


def _instant(value: str | None, option: str, timezone: str) -> pd.Timestamp | None:
    """The instant an option names (see ``parse_instant``); a one-line error naming it else."""
    if value is None:
        return None
    try:
        return parse_instant(value, option, timezone)
    except DataValidationError as exc:
        fail("; ".join(p.message for p in exc.problems))


def _period(
    start: str | None, end: str | None, timezone: str
) -> tuple[pd.Timestamp | None, pd.Timestamp | None]:
    """``--start`` and ``--end`` as instants, start before end."""
    first, last = _instant(start, "--start", timezone), _instant(end, "--end", timezone)
    if first is not None and last is not None and first >= last:
        fail(f"--start {start!r} is not before --end {end!r}")
    return first, last


@app.command()
def fit(
    data: DataArg,
    building: BuildingOpt,
    output: Annotated[Path, typer.Option("-o", "--output", help="parameter file to write")],
    model: Annotated[
        str | None, typer.Option("--model", "-m", help="model name, see `rcengine models`")
    ] = None,
    model_file: Annotated[
        Path | None,
        typer.Option(
            help="model specification (`rcengine diagnose --save-model`) instead of -m",
            exists=True,
            dir_okay=False,
        ),
    ] = None,
    start: Annotated[str | None, typer.Option(help=f"first time fitted: {WHEN}")] = None,
    end: Annotated[str | None, typer.Option(help=f"end of the fit (exclusive): {WHEN}")] = None,
    preset: Annotated[str, typer.Option(help=f"estimator preset: {sorted(PRESETS)}")] = "thorough",
    weekdays: Annotated[bool, typer.Option(help="fit Monday–Friday only")] = False,
    seed: Annotated[int, typer.Option(help="random seed", min=0)] = 0,
    sky_model: Annotated[str, typer.Option(help="isotropic | perez | haydavies")] = "isotropic",
    criterion: Annotated[
        str, typer.Option(help=f"estimation criterion: {' | '.join(CRITERIA)}")
    ] = "output_error",
    input_hold: Annotated[
        str,
        typer.Option(
            help="zoh: each row's inputs are means over its step (the contract); foh: samples at "
            "the stamps, linear in between (kept in the parameter file for predict)"
        ),
    ] = "zoh",
) -> None:
    """Calibrate MODEL (or the model of --model-file) on DATA and write the parameter set."""

    _check(check_criterion, criterion)
    _check(settings_for, preset)
    if input_hold not in HOLDS:
        fail(f"--input-hold must be one of {' | '.join(HOLDS)}, not {input_hold!r}")
    if sky_model not in SKY_MODELS:
        fail(f"--sky-model must be one of {' | '.join(SKY_MODELS)}, not {sky_model!r}")
    if (model is None) == (model_file is None):
        fail("give either --model or --model-file")
    _output(output, "-o", data, building, model_file)

    def run() -> None:
        b = _building(building)
        first, last = _period(start, end, b.location.timezone)
        frame = bridge_short_gaps(read_timeseries(data))
        name, net, options = _model_to_fit(model, model_file, b, frame, sky_model)
        options = replace(options, input_hold=input_hold)
        dataset = prepare(frame, b, net.compile().input_names, options).between(first, last)
        if weekdays:
            dataset = dataset.weekdays(b.location.timezone)
        typer.echo(
            f"fitting {name} on {len(dataset)} rows ({len(dataset.segments)} segment(s)), "
            f"{dataset.times[0]} → {dataset.times[-1]}"
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            est = Estimator(net, preset=preset, random_state=seed, criterion=criterion)
            est.fit(dataset)
        params = ParameterSet.from_estimator(est, dataset, b, name, options)
        params.save(output)
        _print_fit(params, est)
        for w in caught:
            warn(str(w.message))
        typer.echo(f"wrote {output}")

    _run(run)


def _model_to_fit(
    model: str | None, model_file: Path | None, building: Building, frame: pd.DataFrame, sky: str
) -> tuple[str, RCNetwork, SignalOptions]:
    """The library model ``model``, or the stored specification ``model_file`` (its network and
    signal settings, its sky model included)."""
    if model_file is None:
        assert model is not None
        return (
            model,
            get_model(model, building, frame.columns),
            SignalOptions.for_columns(frame.columns, sky_model=sky),
        )
    spec = ModelSpec.load(model_file)
    check_columns(spec, frame.columns)
    return spec.name, spec.network(building), spec.signals


def _print_fit(params: ParameterSet, est: Estimator) -> None:
    typer.echo(f"{'parameter':<12} {'value':>12}  {'unit':<10} bounds")
    for name, p in params.compiled.parameters.items():
        flag = "  ← at bound" if name in est.at_bounds_ else ""
        bounds = f"[{p.lower:g}, {p.upper:g}]"
        typer.echo(f"{name:<12} {params.values[name]:>12.4g}  {p.unit:<10} {bounds}{flag}")
    m = params.metrics["train"]
    verdict = "pass" if m["ashrae14_pass"] else "fail"
    typer.echo(
        f"training RMSE {m['rmse']:.3f} K, MBE {m['mbe']:+.3f} K, CV(RMSE) {m['cv_rmse']:.2f} %, "
        f"NMBE {m['nmbe']:+.2f} % (ASHRAE Guideline 14: {verdict}); "
        f"{est.n_simulations_} simulations in {est.wall_time_s_:.2f} s"
    )
    if est.likelihood_ is not None:
        _print_likelihood(est.likelihood_)


def _print_likelihood(fit: LikelihoodFit) -> None:
    """Estimates with standard errors, and the whiteness of the innovations."""
    u, r = fit.uncertainty, fit.residuals
    typer.echo(f"−ln L {fit.nll:.2f}, AIC {fit.aic:.1f}; estimate ± standard error:")
    for name, value, se in zip(u.names, u.estimates, u.std_errors, strict=True):
        flag = "  ← practically not identifiable" if name in u.non_identifiable else ""
        typer.echo(f"  {name:<26} {value:>11.4g} ± {se:<9.2g}{flag}")
    typer.echo("  (process_std_* in K/√h, measurement_std in K)")
    verdict = "white" if r.white else "NOT white: the model misses dynamics"
    typer.echo(
        f"innovations: {r.acf_outside} of {r.acf.size} autocorrelations beyond ±{r.acf_band:.2f}, "
        f"cumulated periodogram {r.cpgram_deviation:.2f} off the diagonal "
        f"(band {r.cpgram_band:.2f}): {verdict}"
    )


@app.command()
def predict(
    data: DataArg,
    params: Annotated[Path, typer.Option("--params", "-p", help="parameter file", exists=True)],
    start: Annotated[str, typer.Option(help=f"forecast start: {WHEN} (the parameter file's)")],
    hours: Annotated[float, typer.Option(help="forecast horizon [h]")],
    output: Annotated[Path, typer.Option("-o", "--output", help="forecast CSV to write")],
    std: Annotated[
        bool, typer.Option("--std", help="add t_in_std, the forecast's standard deviation [K]")
    ] = False,
) -> None:
    """Forecast indoor temperature from START for HOURS; writes time,t_in_pred[,t_in_std]."""
    if not math.isfinite(hours) or hours > MAX_HORIZON_H:
        fail(f"--hours must be a finite horizon of at most {MAX_HORIZON_H} h, not {hours:g}")
    _output(output, "-o", data, params)

    def run() -> None:
        pset = ParameterSet.load(params)
        first = _instant(start, "--start", pset.building.location.timezone)
        frame = read_timeseries(data)
        try:
            fc, _ = forecast_frame(
                pset.compiled, pset.values, frame, pset.prepare, first, hours, noise=pset.noise
            )
        except DataValidationError as exc:
            # What the data lack at or before this start (the state's history, future inputs).
            fail(f"--start {start}: " + "; ".join(str(p) for p in exc.problems[:5]))
        frame = fc.to_frame(std)
        text = io.StringIO()
        write_timeseries(frame, text, pset.building.location.timezone)
        write_text_atomic(output, text.getvalue())
        nominal = "" if pset.noise else " (nominal: no fitted noise model)"
        typer.echo(
            f"forecast {len(frame)} steps from {frame.index[0]}: t_in_pred "
            f"{frame.t_in_pred.min():.2f}–{frame.t_in_pred.max():.2f} °C, t_in_std "
            f"{fc.t_in_std[0]:.2f}→{fc.t_in_std[-1]:.2f} K{nominal}; wrote {output}"
        )

    _run(run)


@app.command()
def models(
    as_json: Annotated[bool, typer.Option("--json", help="machine-readable output")] = False,
) -> None:
    """List the model library."""
    listing = available_models()
    if as_json:
        json.dump(listing, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return
    for name, doc in listing.items():
        typer.echo(f"{name:<8} {doc}")


@app.command()
def diagnose(
    data: DataArg,
    building: BuildingOpt,
    model: Annotated[str, typer.Option("--model", "-m", help="baseline model")] = "basic",
    json_out: Annotated[Path | None, typer.Option("--json", help="JSON report to write")] = None,
    html_out: Annotated[Path | None, typer.Option("--html", help="HTML report to write")] = None,
    train_fraction: Annotated[
        float, typer.Option(help="share of the record fitted, 0.1 to 0.9")
    ] = 0.5,
    seed: Annotated[int, typer.Option(help="random seed", min=0)] = 0,
    save_model: Annotated[
        Path | None,
        typer.Option(help="write the final model's specification (for `fit --model-file`)"),
    ] = None,
    finding: Annotated[
        str | None,
        typer.Option(
            help="with --save-model: write the model the diagnosis refitted with this effect "
            "instead of its final model, whether it accepted it or not"
        ),
    ] = None,
) -> None:
    """Locate model–data mismatch, name the missing physics, add it and show the fit improve."""
    from rcengine.diagnose import DiagnoseSettings, selection
    from rcengine.diagnose.candidates import CANDIDATES
    from rcengine.diagnose.html import render
    from rcengine.diagnose.settings import TRAIN_FRACTION

    if not TRAIN_FRACTION[0] <= train_fraction <= TRAIN_FRACTION[1]:
        raise typer.BadParameter(
            f"{train_fraction:g} is outside [{TRAIN_FRACTION[0]}, {TRAIN_FRACTION[1]}]",
            param_hint="--train-fraction",
        )
    if model not in available_models():
        fail(f"invalid model {model!r}; choose from {sorted(available_models())}")
    if finding is not None and (save_model is None or finding not in CANDIDATES):
        fail(f"--finding names an effect of {sorted(CANDIDATES)} and needs --save-model")
    outputs = {"--json": json_out, "--html": html_out, "--save-model": save_model}
    for option, path in outputs.items():
        _output(path, option, data, building)
    given = [p.resolve() for p in outputs.values() if p is not None]
    if len(set(given)) < len(given):
        fail("--json, --html and --save-model must name different files")

    def run() -> None:
        b = _building(building)
        frame = read_timeseries(data)
        settings = DiagnoseSettings(train_fraction=train_fraction, random_state=seed)
        report = selection.diagnose(frame, b, model, settings, progress=typer.echo)
        d = report.to_dict()
        typer.echo(f"baseline {model}: test RMSE {d['baseline']['rmse_test']:.3f} K")
        typer.echo(f"where/when: {d['mismatch']['summary']}")
        for f in report.findings:
            mark = "ACCEPTED" if f.accepted else "rejected"
            typer.echo(f"  [{mark}] {f.effect}: {f.explanation}")
        typer.echo(
            f"final {d['final']['model']}: test RMSE {d['final']['rmse_test']:.3f} K "
            f"({report.wall_time_s:.1f} s)"
        )
        ahead = d.get("day_ahead")
        if ahead and ahead["rmse_baseline"] is not None:
            typer.echo(
                f"day-ahead forecast RMSE over the test half's {ahead['days']} days: "
                f"{ahead['rmse_baseline']:.3f} K (baseline) → {ahead['rmse_final']:.3f} K (final)"
            )
        if json_out:
            write_text_atomic(json_out, report.to_json() + "\n")
            typer.echo(f"wrote {json_out}")
        if html_out:
            write_text_atomic(html_out, render(report))
            typer.echo(f"wrote {html_out}")
        if save_model:
            _save_model(d, b, frame, model, save_model, finding)

    _run(run)


def _save_model(
    report: dict,
    building: Building,
    frame: pd.DataFrame,
    model: str,
    path: Path,
    finding: str | None = None,
) -> None:
    """The diagnosed model as a specification (with ``finding``, the one refitted with that
    effect); the base model (as the diagnosis bounded it) when nothing was accepted, so that
    `fit --model-file` always has a model to fit."""
    if finding is not None or any(f["accepted"] for f in report["findings"]):
        spec = ModelSpec.from_report(report, building, frame, finding=finding)
    else:
        final = report["final"]
        network = RCNetwork.from_dict(final["network"])
        spec = ModelSpec.base(network, model, building, SignalOptions(**final["signals"]))
    spec.save(path)
    effects = ", ".join(spec.effects) or "none accepted"
    typer.echo(f"wrote {path} (model {spec.name}; effects: {effects})")


@app.command()
def study(
    data: DataArg,
    building: BuildingOpt,
    output: Annotated[Path, typer.Option("-o", "--output", help="folder for tables and figures")],
    freefloat: Annotated[
        Path | None, typer.Option(help="free-floating record for the §3.3 validation")
    ] = None,
    models: Annotated[str, typer.Option(help="comma-separated model names")] = "basic,sun",
    start: Annotated[str | None, typer.Option(help=f"first predicted day: {WHEN}")] = None,
    end: Annotated[str | None, typer.Option(help=f"end of the predicted days: {WHEN}")] = None,
    workers: Annotated[
        int, typer.Option(help="processes (0: every core)", min=0, max=MAX_WORKERS)
    ] = 0,
    preset: Annotated[str, typer.Option(help=f"estimator preset: {sorted(PRESETS)}")] = "study",
    seed: Annotated[int, typer.Option(help="random seed", min=0)] = 0,
    criterion: Annotated[
        str, typer.Option(help=f"estimation criterion: {' | '.join(CRITERIA)}")
    ] = "output_error",
) -> None:
    """The thesis's rolling learn/predict study: tables, summary.json and figures."""
    import time

    from rcengine.study.report import write_study
    from rcengine.study.run import StudySettings, progress_bar, run_study

    _check(settings_for, preset)
    _check(check_criterion, criterion)
    names = tuple(m.strip() for m in models.split(",") if m.strip())
    if not names:
        fail("--models names no model; e.g. --models basic,sun")
    if output.exists() and not output.is_dir():
        fail(f"-o {output} is a file; give a folder for the tables and figures")
    if not output.resolve().parent.is_dir() or not os.access(output.resolve().parent, os.W_OK):
        fail(f"-o {output}: its parent folder does not exist or is not writable")

    def run() -> None:
        started = time.perf_counter()
        b = _building(building)
        first, last = _period(start, end, b.location.timezone)
        frame = read_timeseries(data)
        # Read before the study, not after it: a bad file found then cost the whole run.
        free = read_timeseries(freefloat) if freefloat else None
        settings = StudySettings(
            models=names,
            preset=preset,
            start=first,
            end=last,
            workers=workers or os.cpu_count() or 1,
            random_state=seed,
            criterion=criterion,
        )
        with progress_bar() as progress:
            results = run_study(frame, b, settings, progress)
        if results.empty:
            fail(
                "no day was predicted: the record (and --start/--end) leave no day with the "
                "training days before it"
            )
        typer.echo("writing tables, figures and the free-floating validation …")
        written = write_study(results, settings, frame, b, free, output)
        typer.echo(
            f"{len(results)} trainings in {time.perf_counter() - started:.0f} s; "
            f"wrote {len(written)} files to {output}"
        )

    _run(run)
