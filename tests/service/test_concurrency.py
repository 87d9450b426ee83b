"""Concurrent writers on SQLite and on a real PostgreSQL server: every accepted upload moves the
building's ``data_revision`` by exactly one (issue 13, defect 7); forecasts are cached per
revision, so none is served for data older than the last upload."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

from service import ingest, repository

# Storage tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True
CLIENTS, UPLOADS = 8, 25


def test_revisions_equal_accepted_uploads_under_concurrent_writers(db, synthetic):
    with db.write() as session:
        building_id = repository.add_building(session, "b", {}, "Europe/Rome", "h" * 64).id
    frames = [synthetic.iloc[k * 4 : k * 4 + 8] for k in range(CLIENTS)]  # overlapping rows

    def client(k: int) -> list[int]:
        upload = ingest.Upload(frames[k])
        return [ingest.store(db, building_id, upload).data_revision for _ in range(UPLOADS)]

    with ThreadPoolExecutor(CLIENTS) as pool:
        revisions = [r for answered in pool.map(client, range(CLIENTS)) for r in answered]
    assert sorted(revisions) == list(range(1, CLIENTS * UPLOADS + 1))
    with db.session() as session:
        building = repository.get_building(session, building_id)
        assert building.data_revision == CLIENTS * UPLOADS
        stored = repository.read_measurements(session, building_id, ["t_in"])
    assert len(stored) == 4 * (CLIENTS - 1) + 8
