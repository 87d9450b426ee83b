"""Tokens: admin registers, each building's token reaches only that building (others: 404),
missing or invalid tokens get 401, tokens are stored hashed, a generated admin token is kept
in a 0600 file."""

from __future__ import annotations

import hashlib
import sqlite3
import stat

import pytest
from fastapi.testclient import TestClient

from service.core.config import Settings
from service.main import create_app

from .conftest import ADMIN, SYNTHETIC_BUILDING, bearer, json_rows, register

BUILDING_ROUTES = [
    ("GET", "/buildings/{id}"),
    ("GET", "/buildings/{id}/measurements"),
    ("POST", "/buildings/{id}/measurements"),
    ("POST", "/buildings/{id}/calibrations"),
    ("GET", "/buildings/{id}/calibrations"),
    ("GET", "/buildings/{id}/parameters"),
    ("GET", "/buildings/{id}/forecast"),
    ("POST", "/buildings/{id}/simulate"),
    ("GET", "/buildings/{id}/model"),
]


@pytest.fixture
def two_buildings(client, synthetic):
    first = register(client)
    second = register(client, {**SYNTHETIC_BUILDING, "name": "second"})
    for building_id, headers in (first, second):
        rows = json_rows(synthetic.iloc[:4])
        response = client.post(
            f"/buildings/{building_id}/measurements", json={"rows": rows}, headers=headers
        )
        assert response.status_code == 200
    return first, second


def call(client, method, path, headers, json_body=None):
    return client.request(method, path, headers=headers, json=json_body)


@pytest.mark.parametrize(("method", "path"), BUILDING_ROUTES)
def test_other_buildings_token_gets_404_and_changes_nothing(client, two_buildings, method, path):
    (_, first_headers), (second_id, second_headers) = two_buildings
    body = {"rows": json_rows_for_other()} if path.endswith("measurements") else None
    response = call(client, method, path.format(id=second_id), first_headers, body)
    assert response.status_code == 404
    assert response.json()["detail"] == f"building {second_id} not found"
    # The same answer as for a building that does not exist: ids cannot be probed.
    missing = call(client, method, path.format(id=999), first_headers, body)
    assert (missing.status_code, missing.json()) == (404, {"detail": "building 999 not found"})
    summary = client.get(f"/buildings/{second_id}", headers=second_headers).json()
    assert (summary["rows"], summary["data_revision"]) == (4, 1)


def json_rows_for_other():
    return [{"time": "2017-01-09T00:00:00+01:00", "t_in": 20, "t_out": 1, "ghi": 0, "q_hvac": 0}]


@pytest.mark.parametrize(("method", "path"), [*BUILDING_ROUTES, ("GET", "/buildings")])
@pytest.mark.parametrize(
    "headers",
    [{}, bearer("not-a-token"), {"Authorization": "Basic dXNlcjpwYXNz"}],
    ids=["missing", "invalid", "not bearer"],
)
def test_missing_or_invalid_token_is_401(client, two_buildings, method, path, headers):
    (first_id, _), _ = two_buildings
    body = {"rows": json_rows_for_other()} if path.endswith("measurements") else None
    response = call(client, method, path.format(id=first_id), headers, body)
    assert response.status_code == 401
    assert response.headers["www-authenticate"] == "Bearer"
    assert "token" in response.json()["detail"]
    summary = client.get(f"/buildings/{first_id}", headers=ADMIN).json()
    assert (summary["rows"], summary["data_revision"]) == (4, 1)


def test_health_needs_no_token(client):
    response = client.get("/health")
    assert response.status_code == 200 and response.json()["status"] == "ok"


def test_building_token_cannot_register_or_list(client, two_buildings):
    (_, headers), _ = two_buildings
    assert client.post("/buildings", json=SYNTHETIC_BUILDING, headers=headers).status_code == 403
    assert client.get("/buildings", headers=headers).status_code == 403
    assert len(client.get("/buildings", headers=ADMIN).json()["items"]) == 2


def test_admin_reads_any_building(client, two_buildings):
    (first_id, _), (second_id, _) = two_buildings
    for building_id in (first_id, second_id):
        response = client.get(f"/buildings/{building_id}", headers=ADMIN)
        assert response.status_code == 200 and response.json()["rows"] == 4
    assert client.get("/buildings/999", headers=ADMIN).status_code == 404


def test_other_buildings_job_is_not_found(client, synthetic):
    _, first_headers = register(client)
    second_id, second_headers = register(client, {**SYNTHETIC_BUILDING, "name": "second"})
    rows = json_rows(synthetic)
    client.post(f"/buildings/{second_id}/measurements", json={"rows": rows}, headers=second_headers)
    job = client.post(
        f"/buildings/{second_id}/calibrations", json={"days": 1}, headers=second_headers
    ).json()
    assert client.get(f"/jobs/{job['id']}", headers=first_headers).status_code == 404
    assert client.get(f"/jobs/{job['id']}", headers=second_headers).status_code == 200
    assert client.get(f"/jobs/{job['id']}", headers=ADMIN).status_code == 200


def test_tokens_are_random_and_stored_only_hashed(client, settings):
    tokens = [
        client.post("/buildings", json=SYNTHETIC_BUILDING, headers=ADMIN).json()["token"]
        for _ in range(2)
    ]
    assert tokens[0] != tokens[1] and all(len(t) == 43 for t in tokens)  # 32 bytes, base64url
    with sqlite3.connect(settings.sqlite_path) as db:
        stored = [row[0] for row in db.execute("SELECT token_hash FROM buildings ORDER BY id")]
    assert stored == [hashlib.sha256(t.encode()).hexdigest() for t in tokens]
    dump = (
        settings.sqlite_path.read_bytes() + settings.sqlite_path.with_suffix(".db-wal").read_bytes()
    )
    assert not any(t.encode() in dump for t in tokens)


def test_rotated_token_replaces_the_old_one(client, two_buildings):
    (first_id, old_headers), _ = two_buildings
    assert client.get(f"/buildings/{first_id}", headers=old_headers).status_code == 200
    rotated = client.post(f"/buildings/{first_id}/token", headers=ADMIN)
    assert rotated.status_code == 200
    assert client.get(f"/buildings/{first_id}", headers=old_headers).status_code == 401
    new_headers = bearer(rotated.json()["token"])
    assert client.get(f"/buildings/{first_id}", headers=new_headers).json()["rows"] == 4


def test_generated_admin_token_is_written_once_with_0600(tmp_path):
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'db' / 'rc.db'}", workers=0, scheduler_enabled=False
    )
    with TestClient(create_app(settings)) as client:
        token_file = tmp_path / "db" / "rcservice-admin-token"
        token = token_file.read_text().strip()
        assert stat.S_IMODE(token_file.stat().st_mode) == 0o600
        assert (
            client.post("/buildings", json=SYNTHETIC_BUILDING, headers=bearer(token)).status_code
            == 201
        )
    with sqlite3.connect(settings.sqlite_path) as db:
        (stored,) = db.execute("SELECT token_hash FROM admin_tokens").fetchone()
    assert stored == hashlib.sha256(token.encode()).hexdigest()
    # A restart keeps the token: no new one is generated or written.
    with TestClient(create_app(settings)) as client:
        assert token_file.read_text().strip() == token
        assert client.get("/buildings", headers=bearer(token)).status_code == 200


def test_short_admin_token_is_refused_at_start():
    with pytest.raises(ValueError, match="at least 24 characters"):
        Settings(admin_token="short")
