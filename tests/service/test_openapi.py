"""The OpenAPI document: every endpoint shows an example of its answer, its body and its
parameters, and the error statuses it can give."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def spec(tmp_path_factory):
    from fastapi.testclient import TestClient

    from service.core.config import Settings
    from service.main import create_app

    folder = tmp_path_factory.mktemp("openapi")
    settings = Settings(
        database_url=f"sqlite:///{folder / 'rc.db'}",
        admin_token="test-admin-token-0123456789abcdef",
        workers=0,
        scheduler_enabled=False,
    )
    with TestClient(create_app(settings)) as client:
        return client.get("/openapi.json").json()


def operations(spec):
    return [
        (f"{method.upper()} {path}", op)
        for path, ops in spec["paths"].items()
        for method, op in ops.items()
    ]


def has_example(media: dict, spec: dict) -> bool:
    if "example" in media or "examples" in media:
        return True
    schema = media.get("schema", {})
    refs = [schema.get("$ref")] + [s.get("$ref") for s in schema.get("anyOf", [])]
    components = spec["components"]["schemas"]
    return any(ref and "examples" in components[ref.split("/")[-1]] for ref in refs)


def test_every_answer_and_body_has_an_example(spec):
    missing = []
    for name, op in operations(spec):
        success = next(code for code in op["responses"] if code.startswith("2"))
        for media_type, media in op["responses"][success].get("content", {}).items():
            if not has_example(media, spec):
                missing.append(f"{name} {success} {media_type}")
        for media_type, media in op.get("requestBody", {}).get("content", {}).items():
            if not has_example(media, spec):
                missing.append(f"{name} body {media_type}")
        for parameter in op.get("parameters", []):
            documented = {**parameter, **parameter.get("schema", {})}
            if "examples" not in documented and "example" not in documented:
                missing.append(f"{name} parameter {parameter['name']}")
    assert missing == []


def test_every_call_but_health_declares_bearer_auth_and_401(spec):
    for name, op in operations(spec):
        if name == "GET /health":
            assert "security" not in op
            continue
        assert op["security"] == [{"HTTPBearer": []}], name
        assert "401" in op["responses"], name


def test_contract_calls_exist(spec):
    names = {name for name, _ in operations(spec)}
    assert {
        "POST /buildings",
        "POST /buildings/{building_id}/measurements",
        "POST /buildings/{building_id}/calibrations",
        "GET /jobs/{job_id}",
        "GET /buildings/{building_id}/parameters",
        "GET /buildings/{building_id}/forecast",
        "GET /health",
        "POST /buildings/{building_id}/simulate",
        "GET /buildings/{building_id}/model",
    } <= names
