"""The HTTP layer: routers, dependencies, error mapping, middleware (the only code that knows
HTTP status codes)."""

from fastapi import APIRouter

from .routes import (
    adoption,
    buildings,
    calibrations,
    diagnoses,
    forecast,
    health,
    jobs,
    measurements,
    parameters,
    plan,
)

# In the order of the OpenAPI page.
ROUTES = (
    health,
    buildings,
    measurements,
    calibrations,
    diagnoses,
    adoption,
    jobs,
    parameters,
    forecast,
    plan,
)

api_router = APIRouter()
for module in ROUTES:
    api_router.include_router(module.router)
