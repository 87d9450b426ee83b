"""Command line: ``rcengine fit | predict | models`` (CONTRACT.md §3), plus the study and the
mismatch diagnosis registered by their modules."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from typing import Annotated

import typer

from rcengine.building import Building
from rcengine.estimation import PRESETS, Estimator
from rcengine.exceptions import ConvergenceWarning, RCEngineError
from rcengine.forecast import forecast
from rcengine.io.timeseries import read_timeseries, write_timeseries
from rcengine.models import available_models, get_model
from rcengine.parameter_set import ParameterSet
from rcengine.signals import SignalOptions, prepare

app = typer.Typer(
    help="Grey-box RC thermal models of buildings: calibrate, forecast, diagnose.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)

DataArg = Annotated[Path, typer.Argument(help="time-series CSV (CONTRACT.md §1)", exists=True)]
BuildingOpt = Annotated[
    Path, typer.Option("--building", "-b", help="building JSON (CONTRACT.md §2)", exists=True)
]


def fail(message: str) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code=2)


def _run(fn):
    """Turn the engine's own errors into a one-line message and exit code 2."""
    try:
        return fn()
    except RCEngineError as exc:
        fail(str(exc))


@app.command()
def fit(
    data: DataArg,
    building: BuildingOpt,
    model: Annotated[str, typer.Option("--model", "-m", help="model name, see `rcengine models`")],
    output: Annotated[Path, typer.Option("-o", "--output", help="parameter file to write")],
    start: Annotated[str | None, typer.Option(help="first time fitted (ISO 8601)")] = None,
    end: Annotated[str | None, typer.Option(help="end of the fit window (exclusive)")] = None,
    preset: Annotated[str, typer.Option(help=f"estimator preset: {sorted(PRESETS)}")] = "default",
    weekdays: Annotated[bool, typer.Option(help="fit Monday–Friday only")] = False,
    seed: Annotated[int, typer.Option(help="random seed")] = 0,
    sky_model: Annotated[str, typer.Option(help="isotropic | perez | haydavies")] = "isotropic",
) -> None:
    """Calibrate MODEL on DATA and write the parameter set as JSON."""

    def run() -> None:
        b = Building.from_json(building)
        frame = read_timeseries(data)
        net = get_model(model, b, frame.columns)
        options = SignalOptions(sky_model=sky_model)
        dataset = prepare(frame, b, net.compile().input_names, options).between(start, end)
        if weekdays:
            dataset = dataset.weekdays(b.location.timezone)
        typer.echo(
            f"fitting {model} on {len(dataset)} rows ({len(dataset.segments)} segment(s)), "
            f"{dataset.times[0]} → {dataset.times[-1]}"
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            est = Estimator(net, preset=preset, random_state=seed).fit(dataset)
        params = ParameterSet.from_estimator(est, dataset, b, model, options)
        params.save(output)
        _print_fit(params, est)
        for w in caught:
            typer.secho(f"warning: {w.message}", fg=typer.colors.YELLOW, err=True)
        typer.echo(f"wrote {output}")

    _run(run)


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


@app.command()
def predict(
    data: DataArg,
    params: Annotated[Path, typer.Option("--params", "-p", help="parameter file", exists=True)],
    start: Annotated[str, typer.Option(help="forecast start (ISO 8601 with offset)")],
    hours: Annotated[float, typer.Option(help="forecast horizon [h]")],
    output: Annotated[Path, typer.Option("-o", "--output", help="forecast CSV to write")],
) -> None:
    """Forecast indoor temperature from START for HOURS; writes time,t_in_pred."""

    def run() -> None:
        pset = ParameterSet.load(params)
        dataset = pset.prepare(read_timeseries(data))
        fc = forecast(pset.compiled, pset.values, dataset, start, hours)
        frame = fc.to_frame()
        write_timeseries(frame, output, pset.building.location.timezone)
        typer.echo(
            f"forecast {len(frame)} steps from {frame.index[0]}: t_in_pred "
            f"{frame.t_in_pred.min():.2f}–{frame.t_in_pred.max():.2f} °C; wrote {output}"
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
    train_fraction: Annotated[float, typer.Option(help="share of the record fitted")] = 0.5,
    seed: Annotated[int, typer.Option(help="random seed")] = 0,
) -> None:
    """Locate model–data mismatch, name the missing physics, add it and show the fit improve."""
    from rcengine.diagnose import DiagnoseSettings
    from rcengine.diagnose import diagnose as run_diagnosis
    from rcengine.diagnose.html import render

    def run() -> None:
        b = Building.from_json(building)
        frame = read_timeseries(data)
        settings = DiagnoseSettings(train_fraction=train_fraction, random_state=seed)
        report = run_diagnosis(frame, b, model, settings, progress=typer.echo)
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
        if json_out:
            json_out.write_text(report.to_json() + "\n")
            typer.echo(f"wrote {json_out}")
        if html_out:
            html_out.write_text(render(report))
            typer.echo(f"wrote {html_out}")

    _run(run)


@app.command()
def study(
    data: DataArg,
    building: BuildingOpt,
    output: Annotated[Path, typer.Option("-o", "--output", help="folder for tables and figures")],
    freefloat: Annotated[
        Path | None, typer.Option(help="free-floating record for the §3.3 validation")
    ] = None,
    models: Annotated[str, typer.Option(help="comma-separated model names")] = "basic,sun",
    start: Annotated[str | None, typer.Option(help="first predicted day (YYYY-MM-DD)")] = None,
    end: Annotated[str | None, typer.Option(help="last predicted day, exclusive")] = None,
    workers: Annotated[int, typer.Option(help="processes (0: every core)")] = 0,
    preset: Annotated[str, typer.Option(help=f"estimator preset: {sorted(PRESETS)}")] = "study",
    seed: Annotated[int, typer.Option(help="random seed")] = 0,
) -> None:
    """The thesis's rolling learn/predict study: tables, summary.json and figures."""
    import os
    import time

    from rcengine.study.report import write_study
    from rcengine.study.run import StudySettings, progress_bar, run_study

    if preset not in PRESETS:
        fail(f"invalid preset {preset!r}; choose from {sorted(PRESETS)}")

    def run() -> None:
        started = time.perf_counter()
        b = Building.from_json(building)
        frame = read_timeseries(data)
        settings = StudySettings(
            models=tuple(m.strip() for m in models.split(",") if m.strip()),
            preset=preset,
            start=start,
            end=end,
            workers=workers or os.cpu_count() or 1,
            random_state=seed,
        )
        with progress_bar() as progress:
            results = run_study(frame, b, settings, progress)
        typer.echo("writing tables, figures and the free-floating validation …")
        free = read_timeseries(freefloat) if freefloat else None
        written = write_study(results, settings, frame, b, free, output)
        typer.echo(
            f"{len(results)} trainings in {time.perf_counter() - started:.0f} s; "
            f"wrote {len(written)} files to {output}"
        )

    _run(run)
