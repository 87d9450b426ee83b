"""Bad uploads through the HTTP API: every CONTRACT.md §1 rule, malformed bodies, size limits.

Each rejected upload mixes valid rows that would change stored rows with one defect, and must
leave the stored rows exactly as they were.
"""

from __future__ import annotations

import copy

import pandas as pd
import pytest

from .conftest import ADMIN, SYNTHETIC_BUILDING, json_rows, register

# Storage, API and job tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True

SEED_ROWS = 8  # stored before each test: 2 h at 15 min


@pytest.fixture
def seeded(client, synthetic):
    """A building with 8 stored rows; the candidate upload overlaps rows 4–7 with other values."""
    building_id, headers = register(client)
    seed = json_rows(synthetic.iloc[:SEED_ROWS])
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": seed}, headers=headers
    )
    assert response.status_code == 200, response.text
    changed = synthetic.iloc[4:12].copy()
    changed["t_in"] += 1.0
    return building_id, headers, json_rows(changed)


def stored(client, building_id, headers) -> list[dict]:
    response = client.get(f"/buildings/{building_id}/measurements", headers=headers)
    assert response.status_code == 200
    return response.json()["rows"]


def assert_unchanged(client, building_id, headers, before):
    assert stored(client, building_id, headers) == before
    summary = client.get(f"/buildings/{building_id}", headers=headers).json()
    assert summary["rows"] == SEED_ROWS and summary["data_revision"] == 1


def shift(text: str, minutes: float) -> str:
    stamp = pd.Timestamp(text) + pd.Timedelta(minutes=minutes)
    return stamp.isoformat()


def _unparseable(rows):
    rows[2]["time"] = "yesterday at noon"


def _no_offset(rows):
    rows[3]["time"] = rows[3]["time"][:19]


def _going_back(rows):
    rows[2]["time"], rows[3]["time"] = rows[3]["time"], rows[2]["time"]


def _duplicate(rows):
    rows[5]["time"] = rows[4]["time"]


def _mixed_steps(rows):
    rows[6]["time"] = shift(rows[6]["time"], 5)


def _step_too_short(rows):
    start = pd.Timestamp(rows[0]["time"])
    for i, row in enumerate(rows):
        row["time"] = (start + pd.Timedelta(seconds=30 * i)).isoformat()


def _not_a_number(rows):
    rows[1]["t_out"] = "cold"


def _impossible_t_in(rows):
    rows[2]["t_in"] = 500.0


def _negative_irradiance(rows):
    rows[3]["ghi"] = -50.0


def _kelvin(rows):
    for row in rows:
        row["t_out"] += 273.15


def _missing_column(rows):
    for row in rows:
        del row["q_hvac"]


def _empty_required_cell(rows):
    rows[4]["t_out"] = None


def _row_not_object(rows):
    rows[2] = [1, 2, 3]


def _off_the_stored_grid(rows):
    for row in rows:
        row["time"] = shift(row["time"], 7)


# (mutation, expected row, expected column, words the message must contain)
RULES = {
    "unparseable time": (_unparseable, 2, "time", "unparseable time 'yesterday at noon'"),
    "time without UTC offset": (_no_offset, 3, "time", "has no UTC offset"),
    "non-monotonic times": (_going_back, 3, "time", "times must increase"),
    "duplicate timestamps": (_duplicate, 5, "time", "duplicate time"),
    "mixed steps": (_mixed_steps, 6, "time", "mixed steps"),
    "step outside 60-3600 s": (_step_too_short, None, "time", "the contract allows 60–3600 s"),
    "non-numeric value": (_not_a_number, 1, "t_out", "not a number: 'cold'"),
    "t_in of 500": (_impossible_t_in, 2, "t_in", "outside the physically possible range"),
    "negative irradiance beyond noise": (_negative_irradiance, 3, "ghi", "negative beyond"),
    "Kelvin instead of °C": (_kelvin, None, "t_out", "looks like Kelvin"),
    "missing required column": (_missing_column, None, "q_hvac", "required column 'q_hvac'"),
    "empty required cell": (_empty_required_cell, 4, "t_out", "needed in every row"),
    "row that is not an object": (_row_not_object, 2, None, "must be an object"),
    "off the stored time grid": (_off_the_stored_grid, 0, "time", "not on the 900-s grid"),
}


@pytest.mark.parametrize("rule", list(RULES))
def test_json_upload_breaking_a_rule_is_rejected_whole(client, seeded, rule):
    building_id, headers, rows = seeded
    mutate, row, column, words = RULES[rule]
    before = stored(client, building_id, headers)
    bad = copy.deepcopy(rows)
    mutate(bad)
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": bad}, headers=headers
    )
    assert response.status_code == 422, response.text
    problems = response.json()["problems"]
    assert any(
        p["row"] == row and p["column"] == column and words in p["message"] for p in problems
    ), problems
    assert words in response.json()["detail"]
    assert_unchanged(client, building_id, headers, before)


def test_the_same_rows_without_the_defect_are_accepted(client, seeded):
    """The control of the test above: the candidate upload itself is valid."""
    building_id, headers, rows = seeded
    response = client.post(
        f"/buildings/{building_id}/measurements", json={"rows": rows}, headers=headers
    )
    assert response.status_code == 200
    assert response.json()["inserted"] == 4 and response.json()["updated"] == 4
    assert stored(client, building_id, headers)[4]["t_in"] == pytest.approx(rows[0]["t_in"])


def csv_text(rows: list[dict]) -> str:
    frame = pd.DataFrame(rows)
    return frame.to_csv(index=False, na_rep="")


def test_csv_problem_names_row_column_and_line(client, seeded):
    building_id, headers, rows = seeded
    before = stored(client, building_id, headers)
    bad = copy.deepcopy(rows)
    bad[3]["t_in"] = 500.0
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=csv_text(bad),
        headers={**headers, "content-type": "text/csv"},
    )
    assert response.status_code == 422
    (problem,) = response.json()["problems"]
    assert (problem["row"], problem["column"]) == (3, "t_in")
    assert "line 5 of the file" in problem["message"]  # header is line 1, row 0 is line 2
    assert_unchanged(client, building_id, headers, before)


def test_csv_in_kelvin_is_rejected(client, seeded):
    building_id, headers, rows = seeded
    before = stored(client, building_id, headers)
    bad = copy.deepcopy(rows)
    for row in bad:
        row["t_in"] += 273.15
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=csv_text(bad),
        headers={**headers, "content-type": "text/csv; charset=utf-8"},
    )
    assert response.status_code == 422
    assert "looks like Kelvin" in response.json()["detail"]
    assert "subtract 273.15" in response.json()["detail"]
    assert_unchanged(client, building_id, headers, before)


@pytest.mark.parametrize(
    ("content_type", "body", "words"),
    [
        ("application/json", b'{"rows": [{"time": ', "not valid JSON at line 1 column"),
        ("application/json", b"[1, 2]", 'must be an object {"rows": [...]}'),
        ("application/json", b'{"rows": []}', "no data rows"),
        ("text/csv", b"time;t_in;t_out;ghi;q_hvac\n2017-01-09T00:00+01:00;20;1;0;0\n", "';'"),
        ("text/csv", b'time,t_in\n"2017-01-09T00:00+01:00,20\n', "not a readable CSV"),
        ("text/csv", b"\xff\xfe\x00t\x00i\x00m\x00e", "not UTF-8"),
        ("text/csv", b"", "the file is empty"),
    ],
    ids=[
        "truncated JSON",
        "JSON array",
        "no rows",
        "CSV with ;",
        "broken quote",
        "UTF-16",
        "empty",
    ],
)
def test_malformed_bodies_are_rejected(client, seeded, content_type, body, words):
    building_id, headers, _ = seeded
    before = stored(client, building_id, headers)
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=body,
        headers={**headers, "content-type": content_type},
    )
    assert response.status_code == 422, response.text
    assert words in response.json()["detail"]
    assert_unchanged(client, building_id, headers, before)


def test_unsupported_content_type_is_415(client, seeded):
    building_id, headers, _ = seeded
    before = stored(client, building_id, headers)
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=b"<rows/>",
        headers={**headers, "content-type": "application/xml"},
    )
    assert response.status_code == 415
    assert "text/csv" in response.json()["detail"]
    assert_unchanged(client, building_id, headers, before)


def test_body_over_the_limit_is_413_from_content_length(client, seeded, settings):
    building_id, headers, _ = seeded
    before = stored(client, building_id, headers)
    body = b" " * (settings.max_body_bytes + 1)
    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=body,
        headers={**headers, "content-type": "application/json"},
    )
    assert response.status_code == 413
    assert f"limit of {settings.max_body_bytes} bytes" in response.json()["detail"]
    assert_unchanged(client, building_id, headers, before)


def test_streamed_body_over_the_limit_is_413(client, seeded, settings):
    """A chunked body has no Content-Length; the limit is enforced while it streams in."""
    building_id, headers, _ = seeded
    before = stored(client, building_id, headers)

    def chunks():
        for _ in range(settings.max_body_bytes // 10_000 + 2):
            yield b" " * 10_000

    response = client.post(
        f"/buildings/{building_id}/measurements",
        content=chunks(),
        headers={**headers, "content-type": "application/json"},
    )
    assert response.status_code == 413
    assert "exceeds the limit" in response.json()["detail"]
    assert_unchanged(client, building_id, headers, before)


def test_large_building_description_is_413(client, settings):
    """The limit guards every route, also those whose body FastAPI parses itself."""
    big = {
        **SYNTHETIC_BUILDING,
        "name": "x" * 100,
        "windows": [{"azimuth": 0, "tilt": 90, "area": 1}] * 9000,
    }
    response = client.post("/buildings", json=big, headers=ADMIN)
    assert response.status_code == 413
    assert client.get("/buildings", headers=ADMIN).json()["items"] == []


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"floor_area": -5.0}, "floor_area"),
        ({"location": {"latitude": 95.0, "longitude": 7.0}}, "location.latitude"),
        ({"location": {"latitude": 45.0, "longitude": 7.0, "timezone": "Mars/Base"}}, "timezone"),
        # A folder of the zone database and an over-long name raised OS errors (500s).
        ({"location": {"latitude": 45.0, "longitude": 7.0, "timezone": "Europe"}}, "timezone"),
        ({"location": {"latitude": 45.0, "longitude": 7.0, "timezone": "A" * 300}}, "timezone"),
        ({"location": {"latitude": 45.0, "longitude": 7.0, "timezone": "posixrules"}}, "timezone"),
        # Lax parsing read true as 1 m² and a text as a number.
        ({"floor_area": True}, "floor_area"),
        ({"volume": "300"}, "volume"),
        ({"name": "office\x00"}, "name"),
        ({"windows": [{"azimuth": 90.0, "tilt": 200.0, "area": 4.0}]}, "windows[0].tilt"),
    ],
)
def test_invalid_building_description_names_the_field(client, change, field):
    response = client.post("/buildings", json={**SYNTHETIC_BUILDING, **change}, headers=ADMIN)
    assert response.status_code == 422
    assert field in response.text
    # The field is the problem's column, as for a request that fails the schema.
    assert any(field in (p["column"] or "") for p in response.json()["problems"]), response.text
    assert client.get("/buildings", headers=ADMIN).json()["items"] == []


def test_a_description_without_a_time_zone_is_registered_with_a_warning(client):
    location = {k: v for k, v in SYNTHETIC_BUILDING["location"].items() if k != "timezone"}
    response = client.post(
        "/buildings", json={**SYNTHETIC_BUILDING, "location": location}, headers=ADMIN
    )
    assert response.status_code == 201, response.text
    (warning,) = response.json()["warnings"]
    assert "location.timezone is not given" in warning and "in UTC" in warning
    named = client.post("/buildings", json={**SYNTHETIC_BUILDING, "name": "zoned"}, headers=ADMIN)
    assert named.json()["warnings"] == []
