"""Command line: ``rcservice serve | retrain-all | reset-admin-token``.

Heavy imports stay inside the commands: calibration worker processes (spawned) import this
module as their ``__main__`` when the server was started through it.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Annotated

import typer

from rcengine.io.files import file_error

app = typer.Typer(
    help="The rcengine calibration service (FastAPI).",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)


def _settings():
    from pydantic import ValidationError

    from .core.config import Settings
    from .core.logging import configure_logging

    try:
        settings = Settings()
    except ValidationError as exc:
        typer.secho(f"error: invalid RCSERVICE_* setting:\n{exc}", fg=typer.colors.RED, err=True)
        raise typer.Exit(code=2) from None
    configure_logging(settings.log_level)
    return settings


@contextmanager
def _database_errors(settings) -> Iterator[None]:
    """A database that cannot be opened, a schema newer than this code, a token file that
    cannot be written: one line and exit code 2, not a traceback."""
    from alembic.util.exc import CommandError
    from sqlalchemy import make_url
    from sqlalchemy.exc import SQLAlchemyError

    try:
        yield
    except (SQLAlchemyError, CommandError, ModuleNotFoundError) as exc:
        where = make_url(settings.database_url).render_as_string(hide_password=True)
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        typer.secho(f"error: database {where}: {reason}", fg=typer.colors.RED, err=True)
        raise typer.Exit(code=2) from None
    except OSError as exc:
        typer.secho(f"error: {file_error(exc)}", fg=typer.colors.RED, err=True)
        raise typer.Exit(code=2) from None


def _backend(make_backend, settings, dask: str | None):
    """The backend ``--dask`` names; a malformed address is one line naming the option."""
    try:
        return make_backend(settings, dask)
    except (ValueError, RuntimeError, OSError) as exc:
        typer.secho(f"error: --dask {dask}: {exc}", fg=typer.colors.RED, err=True)
        raise typer.Exit(code=2) from None


@app.command()
def serve(
    host: Annotated[str, typer.Option(help="interface to listen on")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="TCP port", min=1, max=65535)] = 8000,
) -> None:
    """Run the HTTP service (uvicorn) until Ctrl-C."""
    import uvicorn

    from .main import create_app

    settings = _settings()
    if settings.sqlite_path is None:
        # A database server that cannot be reached or migrated: one line before uvicorn starts,
        # not the startup's traceback inside a JSON log line.
        from .core.db import Database

        with _database_errors(settings):
            db = Database(settings.database_url)
            try:
                db.migrate()
            finally:
                db.dispose()
    shown = "localhost" if host in ("0.0.0.0", "::") else host
    typer.echo(f"rcservice: API docs at http://{shown}:{port}/docs (OpenAPI: /openapi.json)")
    if settings.admin_token is not None:
        typer.echo("rcservice: admin token = the value of RCSERVICE_ADMIN_TOKEN")
    else:
        typer.echo(
            f"rcservice: admin token printed at first start and kept in {settings.token_file()} "
            "(mode 0600); `rcservice reset-admin-token` makes a new one"
        )
    uvicorn.run(create_app(settings), host=host, port=port, log_config=None, access_log=False)


@app.command("retrain-all")
def retrain_all(
    dask: Annotated[
        str | None,
        typer.Option(
            help="run the fits on Dask: a scheduler address (tcp://host:8786) or 'local' "
            "(default: RCSERVICE_DASK_SCHEDULER, else the process pool of RCSERVICE_WORKERS)",
        ),
    ] = None,
    progress: Annotated[bool, typer.Option(help="show a progress bar")] = True,
) -> None:
    """Calibrate every building with new data since its last job, once (for an external cron,
    or beside running replicas: they share the queue). Prints a summary; exits with 1 if any
    job failed.
    """
    import json

    from .backends import make_backend
    from .core.db import Database
    from .fleet import retrain_all as run_pass

    settings = _settings()
    with _database_errors(settings):
        db = Database(settings.database_url)
    try:
        with _database_errors(settings):
            db.migrate()
            backend = _backend(make_backend, settings, dask)
            summary = run_pass(settings, db, backend, progress=progress)
    finally:
        db.dispose()
    for line in summary.lines():
        typer.echo(line)
    typer.echo(json.dumps(summary.to_dict()))
    if summary.failed:
        raise typer.Exit(code=1)


@app.command("reset-admin-token")
def reset_admin_token() -> None:
    """Replace the generated admin token; prints the new one (the old one stops working)."""
    from .core.db import Database
    from .tokens import reset_admin_token as reset

    settings = _settings()
    if settings.admin_token is not None:
        typer.echo("RCSERVICE_ADMIN_TOKEN is set: that value is the admin token; change it there")
        raise typer.Exit(code=2)
    with _database_errors(settings):
        db = Database(settings.database_url)
    try:
        with _database_errors(settings):
            db.migrate()
            token, path = reset(settings, db)
    finally:
        db.dispose()
    typer.echo(f"new admin token {token}\n  (also written to {path}); restart the server")


if __name__ == "__main__":
    app()
