"""What the app's lifespan creates and the routers use: one instance per server process."""

from __future__ import annotations

from dataclasses import dataclass

from .core.config import Settings
from .core.db import Database
from .forecasting import Forecaster
from .jobs import JobRunner
from .tokens import TokenIndex


@dataclass(frozen=True)
class ServiceContext:
    settings: Settings
    db: Database
    admin_token_hash: str
    tokens: TokenIndex
    runner: JobRunner
    forecaster: Forecaster
