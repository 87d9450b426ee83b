"""Service settings from the environment (prefix ``RCSERVICE_``), checked once at start-up."""

from __future__ import annotations

from pathlib import Path
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError

from rcengine.estimation.estimator import check_criterion
from rcengine.estimation.presets import settings_for
from rcengine.models import MODELS

# A shorter admin token is guessable; generated tokens have 43 characters.
MIN_ADMIN_TOKEN_CHARS = 24
ADMIN_TOKEN_FILE_NAME = "rcservice-admin-token"


class Settings(BaseSettings):
    """Everything the service reads from its environment.

    Each field ``name`` is set by the variable ``RCSERVICE_NAME`` (e.g. ``RCSERVICE_WORKERS=2``).
    """

    model_config = SettingsConfigDict(env_prefix="RCSERVICE_", env_file=None, extra="ignore")

    database_url: str = Field(
        "sqlite:///./rcservice.db",
        description="SQLAlchemy URL: SQLite file (default) or postgresql+psycopg://...",
    )
    admin_token: SecretStr | None = Field(
        None,
        description="Token that may register buildings. Unset: one is generated at first start, "
        "stored hashed and written once to admin_token_file.",
    )
    admin_token_file: Path | None = Field(
        None,
        description="Where a generated admin token is written (mode 0600). Default: next to "
        "the SQLite file, or the working directory for other databases.",
    )
    retrain_hour: int = Field(2, ge=0, le=23, description="Local hour of the nightly re-fit.")
    timezone: str = Field("UTC", description="Time zone of retrain_hour (IANA name).")
    scheduler_enabled: bool = True
    training_days: int = Field(7, ge=1, le=365, description="Days fitted by default.")
    model: str = Field("basic", description="Default model of the rcengine library.")
    preset: str = Field("default", description="Estimator preset of rcengine.estimation.estimator.")
    random_state: int = 0
    criterion: str = Field(
        "output_error",
        description="Calibration criterion of rcengine.estimation.estimator: 'output_error' "
        "(open-loop simulation error) or 'likelihood' (Kalman maximum likelihood; the stored "
        "set then carries its fitted noise model, used by the forecast's t_in_std).",
    )
    diagnosis_days: int = Field(
        182,
        ge=2,
        le=3660,
        description="Days of record a diagnosis covers by default, ending at the last measured "
        "t_in (clipped to the stored data).",
    )
    diagnosis_preset: str | None = Field(
        None,
        description="Estimator preset of every fit of a diagnosis (default: the engine's, study).",
    )
    auto_adopt: bool = Field(
        False,
        description="Adopt a diagnosis's model as soon as it accepts findings (as POST "
        "/buildings/{id}/diagnoses/{diagnosis_id}/adopt does, audited as 'auto'): its first "
        "calibration runs at once and is served only if it wins the held-out day.",
    )
    max_body_bytes: int = Field(32 * 1024 * 1024, ge=1024, description="Request size limit.")
    workers: int = Field(
        1,
        ge=0,
        le=64,
        description="Worker processes for jobs (calibrations, diagnoses); 0 runs them on a "
        "thread of the server process (tests, tiny deployments).",
    )
    dask_scheduler: str | None = Field(
        None,
        description="Run jobs on Dask distributed instead of the worker processes: the "
        "scheduler's address (tcp://host:8786), or 'local' for a LocalCluster sized to this "
        "machine. Unset: the in-process pool (docs/fleet.md).",
    )
    forecast_cache_size: int = Field(512, ge=0, description="Forecasts kept in memory.")
    job_lease_s: float = Field(
        30.0,
        ge=1.0,
        le=3600.0,
        description="A running job's lease [s]: renewed every third of it by the job's process; "
        "once expired (its server died) the job is failed and any later write of it refused.",
    )
    log_level: str = "INFO"

    @field_validator("timezone")
    @classmethod
    def _known_timezone(cls, value: str) -> str:
        try:
            ZoneInfo(value)
        except (ZoneInfoNotFoundError, ValueError) as exc:
            raise ValueError(f"unknown time zone {value!r}") from exc
        return value

    @field_validator("model")
    @classmethod
    def _known_model(cls, value: str) -> str:
        if value not in MODELS:
            raise ValueError(f"invalid model {value!r}; choose from {sorted(MODELS)}")
        return value

    @field_validator("preset", "diagnosis_preset")
    @classmethod
    def _known_preset(cls, value: str | None) -> str | None:
        if value is not None:
            settings_for(value)
        return value

    @field_validator("criterion")
    @classmethod
    def _known_criterion(cls, value: str) -> str:
        return check_criterion(value)

    @field_validator("admin_token")
    @classmethod
    def _long_enough(cls, value: SecretStr | None) -> SecretStr | None:
        if value is not None and len(value.get_secret_value()) < MIN_ADMIN_TOKEN_CHARS:
            raise ValueError(
                f"admin token must have at least {MIN_ADMIN_TOKEN_CHARS} characters; "
                "unset it to have one generated"
            )
        return value

    @field_validator("dask_scheduler")
    @classmethod
    def _dask_address(cls, value: str | None) -> str | None:
        if value in (None, "", "local"):
            return value or None
        if "://" not in value:
            raise ValueError(
                f"invalid Dask scheduler {value!r}: give its address (tcp://host:8786) or 'local'"
            )
        return value

    @field_validator("database_url")
    @classmethod
    def _parsable_url(cls, value: str) -> str:
        try:
            make_url(value)
        except ArgumentError as exc:  # not a ValueError: pydantic would let it through raw
            raise ValueError(f"not a database URL ({exc})") from None
        return value

    @field_validator("log_level")
    @classmethod
    def _known_level(cls, value: str) -> str:
        if value.upper() not in ("CRITICAL", "ERROR", "WARNING", "INFO", "DEBUG"):
            raise ValueError(f"unknown log level {value!r}: CRITICAL, ERROR, WARNING, INFO, DEBUG")
        return value.upper()

    @property
    def sqlite_path(self) -> Path | None:
        """The database file, or None for an in-memory or non-SQLite database."""
        url = make_url(self.database_url)
        if url.get_backend_name() != "sqlite" or url.database in (None, "", ":memory:"):
            return None
        return Path(url.database)

    @property
    def several_processes(self) -> bool:
        """Whether several service processes may share the database (PostgreSQL), claiming
        jobs from one queue; SQLite runs one process."""
        return make_url(self.database_url).get_backend_name() != "sqlite"

    def token_file(self) -> Path:
        if self.admin_token_file is not None:
            return self.admin_token_file
        db_file = self.sqlite_path
        folder = db_file.parent if db_file is not None else Path.cwd()
        return folder / ADMIN_TOKEN_FILE_NAME
