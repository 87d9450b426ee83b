"""Storage: the migration matches the tables, SQLite settings, constraints the database itself
enforces, retraining selection, the scheduler and the ``rcservice`` command line."""

from __future__ import annotations

import hashlib
import io
import sqlite3
from datetime import UTC, datetime, timedelta, timezone

import numpy as np
import pytest
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from fastapi.testclient import TestClient
from sqlalchemy import String, Text, insert, text
from sqlalchemy.dialects import postgresql
from sqlalchemy.exc import IntegrityError, StatementError
from typer.testing import CliRunner

from service import bridge, repository
from service.cli import app as cli
from service.core.config import Settings
from service.core.db import Database, alembic_config
from service.jobs import JobRunner
from service.main import create_app
from service.models import Base, JobRecord, ParameterSetRecord
from service.scheduler import JOB_ID, start_scheduler

from .conftest import app_settings, json_rows, register

# Storage, API and job tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True


def _same_text_on_sqlite(context, inspected, metadata, inspected_type, metadata_type):
    """SQLite stores VARCHAR(n) and TEXT alike (TEXT affinity, no length enforced), which is
    why migration 0006 widens model names on other databases only; any other type difference
    is left to alembic's own comparison (None)."""
    text_types = (String, Text)
    if context.dialect.name == "sqlite" and all(
        isinstance(t, text_types) for t in (inspected_type, metadata_type)
    ):
        return False
    return None


def test_migration_creates_exactly_the_tables_of_the_models(db):
    with db.engine.connect() as connection:
        context = MigrationContext.configure(
            connection, opts={"compare_type": _same_text_on_sqlite}
        )
        differences = compare_metadata(context, Base.metadata)
    assert differences == []


def test_sqlite_runs_in_wal_with_foreign_keys_and_a_busy_timeout(db, backend):
    if backend != "sqlite":
        pytest.skip("SQLite settings")
    with db.session() as session:
        assert session.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert session.execute(text("PRAGMA foreign_keys")).scalar() == 1
        assert session.execute(text("PRAGMA busy_timeout")).scalar() == 30_000


def test_times_are_stored_as_utc_instants(db):
    rome = timezone(timedelta(hours=1))
    with db.write() as session:
        building = repository.add_building(session, "b", {}, "Europe/Rome", "h" * 64)
        building.grid_origin = datetime(2017, 1, 9, 6, 15, tzinfo=rome)
    with db.session() as session:
        stored = repository.get_building(session, building.id).grid_origin
    assert stored == datetime(2017, 1, 9, 5, 15, tzinfo=UTC) and stored.tzinfo == UTC
    with pytest.raises(StatementError, match="naive datetime"), db.write() as session:
        repository.get_building(session, building.id).grid_origin = datetime(2017, 1, 9)


def _job_values(building_id: int, status: str) -> dict:
    return {
        "building_id": building_id,
        "status": status,
        "trigger": "api",
        "model": "basic",
        "days": 7,
        "data_revision": 0,
        "created_at": datetime.now(UTC),
    }


def test_database_refuses_a_second_active_job_for_a_building(db):
    with db.write() as session:
        building = repository.add_building(session, "b", {}, "UTC", "h" * 64)
        session.execute(insert(JobRecord), [_job_values(building.id, "running")])
        session.execute(insert(JobRecord), [_job_values(building.id, "failed")])
    with pytest.raises(IntegrityError), db.write() as session:
        session.execute(insert(JobRecord), [_job_values(building.id, "queued")])


def test_database_refuses_two_current_sets_for_a_building(db):
    def values(building_id):
        now = datetime.now(UTC)
        return {
            "building_id": building_id,
            "model": "basic",
            "status": "current",
            "is_current": True,
            "train_start": now,
            "train_end": now,
            "metrics": {},
            "engine_version": "0",
            "document": {},
            "created_at": now,
        }

    with db.write() as session:
        building = repository.add_building(session, "b", {}, "UTC", "h" * 64)
        session.execute(insert(ParameterSetRecord), [values(building.id)])
    with pytest.raises(IntegrityError), db.write() as session:
        session.execute(insert(ParameterSetRecord), [values(building.id)])


def test_deleting_a_building_deletes_its_rows(client, settings, synthetic):
    building_id, headers = register(client)
    client.post(
        f"/buildings/{building_id}/measurements",
        json={"rows": json_rows(synthetic.iloc[:4])},
        headers=headers,
    )
    database = Database(settings.database_url)
    with database.write() as session:
        session.execute(text("DELETE FROM buildings WHERE id = :id"), {"id": building_id})
    with database.session() as session:
        assert session.execute(text("SELECT count(*) FROM measurements")).scalar() == 0
    database.dispose()


def test_an_uploaded_cloud_cover_is_stored_and_read_back(client, settings, synthetic):
    """The contract's optional cloud_cover column (%) goes through the upload into storage."""
    building_id, headers = register(client)
    rows = synthetic.iloc[:4].assign(cloud_cover=[0.0, 25.0, None, 100.0])
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": json_rows(rows)}, headers=headers
    )
    assert response.status_code < 300, response.text
    database = Database(settings.database_url)
    with database.session() as session:
        frame = bridge.load_frame(session, building_id)
    np.testing.assert_array_equal(frame["cloud_cover"].to_numpy(), [0.0, 25.0, np.nan, 100.0])
    database.dispose()


def test_retraining_picks_buildings_with_new_data_since_their_last_job(client, settings, synthetic):
    with_data, headers = register(client)
    register(client)  # no data: never due
    database = Database(settings.database_url)
    with database.session() as session:
        assert repository.buildings_with_new_data(session) == []
    rows = json_rows(synthetic.iloc[:96])
    client.post(f"/buildings/{with_data}/measurements", json={"rows": rows}, headers=headers)
    with database.session() as session:
        assert repository.buildings_with_new_data(session) == [with_data]
    with database.write() as session:
        job = repository.add_job(session, with_data, "schedule", "basic", 7)
        repository.finish_job(session, job.id, "failed", error="x")
    with database.session() as session:
        assert repository.buildings_with_new_data(session) == []  # nothing new since that job
    client.post(f"/buildings/{with_data}/measurements", json={"rows": rows[:4]}, headers=headers)
    with database.session() as session:
        assert repository.buildings_with_new_data(session) == [with_data]
    database.dispose()


def test_retrain_all_command_calibrates_due_buildings_once(
    client, settings, synthetic, monkeypatch
):
    building_id, headers = register(client)
    client.post(
        f"/buildings/{building_id}/measurements",
        json={"rows": json_rows(synthetic.iloc[: 3 * 96])},
        headers=headers,
    )
    monkeypatch.setenv("RCSERVICE_DATABASE_URL", settings.database_url)
    monkeypatch.setenv("RCSERVICE_TRAINING_DAYS", "1")
    runner = CliRunner()
    first = runner.invoke(cli, ["retrain-all"])
    assert first.exit_code == 0, first.output
    assert "promoted 1" in first.output and "1 job(s) run" in first.output
    sets = client.get(f"/buildings/{building_id}/parameters", headers=headers).json()
    assert sets["current_id"] is not None
    jobs = client.get(f"/buildings/{building_id}/calibrations", headers=headers).json()["items"]
    assert [(j["trigger"], j["days"]) for j in jobs] == [("cli", 1)]
    second = runner.invoke(cli, ["retrain-all"])
    assert second.exit_code == 0 and "0 job(s) run" in second.output


def test_nightly_job_is_scheduled_at_the_local_hour(settings):
    local = Settings(**{**settings.model_dump(), "retrain_hour": 3, "timezone": "Europe/Rome"})
    database = Database(local.database_url)
    database.migrate()
    runner = JobRunner(local, database)
    scheduler = start_scheduler(local, database, runner)
    try:
        next_run = scheduler.get_job(JOB_ID).next_run_time
        assert (next_run.hour, next_run.minute) == (3, 0)
        assert str(next_run.tzinfo) == "Europe/Rome"
    finally:
        scheduler.shutdown(wait=False)
        runner.shutdown()
        database.dispose()


@pytest.mark.parametrize(
    ("env", "args", "message"),
    [
        ({"RCSERVICE_DATABASE_URL": "sqlite:////nonexistent/dir/x.db"}, [], "unable to open"),
        ({"RCSERVICE_DATABASE_URL": "notaurl"}, [], "not a database URL"),
        ({"RCSERVICE_LOG_LEVEL": "NOPE"}, [], "unknown log level"),
        ({}, ["--dask", "bogus"], "--dask bogus"),
    ],
)
def test_the_service_command_says_what_is_wrong_in_one_line(
    tmp_path, monkeypatch, env, args, message
):
    """Each was a traceback (probe of the command line, nineteenth session)."""
    monkeypatch.setenv("RCSERVICE_DATABASE_URL", f"sqlite:///{tmp_path / 'rc.db'}")
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    result = CliRunner().invoke(cli, ["retrain-all", "--no-progress", *args])
    assert result.exit_code == 2, result.output
    assert message in result.output and "Traceback" not in result.output


def test_serve_says_in_one_line_that_its_database_server_cannot_be_reached(monkeypatch):
    monkeypatch.setenv("RCSERVICE_DATABASE_URL", "postgresql+psycopg://nobody@127.0.0.1:1/x")
    result = CliRunner().invoke(cli, ["serve", "--port", "18767"])
    assert result.exit_code == 2, result.output
    assert "Connection refused" in result.output and "Traceback" not in result.output


def test_a_token_file_that_cannot_be_written_keeps_the_old_token(tmp_path, monkeypatch):
    """The new hash was stored before the file was written: a failed write left a token nobody
    had."""
    monkeypatch.setenv("RCSERVICE_DATABASE_URL", f"sqlite:///{tmp_path / 'rc.db'}")
    monkeypatch.setenv("RCSERVICE_ADMIN_TOKEN_FILE", str(tmp_path / "token"))
    assert CliRunner().invoke(cli, ["reset-admin-token"]).exit_code == 0
    token = (tmp_path / "token").read_text().strip()
    # Under a file, not a folder: the new token cannot be written.
    monkeypatch.setenv("RCSERVICE_ADMIN_TOKEN_FILE", str(tmp_path / "token" / "new"))
    failed = CliRunner().invoke(cli, ["reset-admin-token"])
    assert failed.exit_code == 2 and "Traceback" not in failed.output
    with sqlite3.connect(tmp_path / "rc.db") as db:
        (stored,) = db.execute("SELECT token_hash FROM admin_tokens").fetchone()
    assert stored == hashlib.sha256(token.encode()).hexdigest()


def test_invalid_settings_fail_at_start():
    with pytest.raises(ValueError, match="invalid model"):
        Settings(model="7r7c")
    with pytest.raises(ValueError, match="unknown time zone"):
        Settings(timezone="Mars/Base")
    with pytest.raises(ValueError, match="invalid preset"):
        Settings(preset="fastest")
    with pytest.raises(ValueError, match="invalid preset"):
        Settings(diagnosis_preset="fastest")


def test_schema_and_upsert_compile_for_postgresql():
    """No PostgreSQL server here: check the SQL the same code emits for it."""
    config = alembic_config("postgresql://user@localhost/rcservice")
    config.output_buffer = io.StringIO()
    command.upgrade(config, "head", sql=True)
    ddl = config.output_buffer.getvalue()
    assert (
        "CREATE UNIQUE INDEX uq_jobs_active_building ON jobs (building_id) "
        "WHERE status IN ('queued', 'running')" in ddl
    )
    assert "CREATE UNIQUE INDEX uq_parameter_sets_current_building ON parameter_sets " in ddl
    assert "time TIMESTAMP WITH TIME ZONE NOT NULL" in ddl
    upsert = str(
        repository.upsert_statement("postgresql", ["t_in"]).compile(dialect=postgresql.dialect())
    )
    assert (
        "ON CONFLICT (building_id, time) DO UPDATE SET "
        "t_in = coalesce(excluded.t_in, measurements.t_in)" in upsert
    )


def test_a_missing_database_folder_is_made_and_said(tmp_path, caplog):
    """The embedded database's folder is created at start-up, and the log says so: a mistyped
    RCSERVICE_DATABASE_URL shows there instead of as an empty service."""
    folder = tmp_path / "not" / "yet"
    settings = app_settings(f"sqlite:///{folder / 'rcservice.db'}")

    def made() -> list:
        return [r for r in caplog.records if r.getMessage() == "created the database folder"]

    with caplog.at_level("WARNING", logger="service.main"), TestClient(create_app(settings)):
        assert (folder / "rcservice.db").exists()
    (record,) = made()
    assert record.folder == str(folder)
    caplog.clear()
    with caplog.at_level("WARNING", logger="service.main"), TestClient(create_app(settings)):
        pass
    assert not made()
