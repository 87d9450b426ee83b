"""The HTTP layer: routers, dependencies, error mapping, middleware (the only code that knows
HTTP status codes)."""

from fastapi import APIRouter

from .routes import (
    buildings,
    calibrations,
    diagnoses,
    forecast,
    health,
    jobs,
    measurements,
    parameters,
)

# In the order of the OpenAPI page.
ROUTES = (health, buildings, measurements, calibrations, diagnoses, jobs, parameters, forecast)

api_router = APIRouter()
for module in ROUTES:
    api_router.include_router(module.router)
