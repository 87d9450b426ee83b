"""The HTTP layer: routers, dependencies, error mapping, middleware (the only code that knows
HTTP status codes)."""

from fastapi import APIRouter

from .routes import buildings, calibrations, forecast, health, measurements, parameters

api_router = APIRouter()
for module in (health, buildings, measurements, calibrations, parameters, forecast):
    api_router.include_router(module.router)
