"""The dashboard's reads on both databases: the data overview parses the stored times as text
(``repository.read_series``), which SQLite and PostgreSQL write differently."""

from __future__ import annotations

import json
import re

import pandas as pd

from service import repository
from service.ui.views import data_overview, wall_clock

from .conftest import ADMIN_TOKEN, TIMEZONE

ON_BOTH_DATABASES = True


def test_building_page_series_have_the_stored_times(client, measured, three_days_measured):
    building_id, _ = measured
    page = client.get("/ui/login")
    csrf = re.search(r'name="csrf" value="([^"]+)"', page.text).group(1)
    client.post("/ui/login", data={"token": ADMIN_TOKEN, "csrf": csrf})
    html = client.get(f"/ui/buildings/{building_id}").text
    charts = json.loads(re.search(r'id="chart-json">(.*?)</script>', html, re.S).group(1))
    expected = wall_clock(three_days_measured.index, TIMEZONE)
    assert charts["data"]["x"] == expected
    measured_t_in = three_days_measured["t_in"].round(3)
    assert charts["data"]["t_in"] == [None if pd.isna(v) else v for v in measured_t_in]

    ctx = client.app.state.context
    with ctx.db.session() as session:
        row = repository.building_summary(session, building_id)
        _, gaps = data_overview(session, row)
    assert gaps == []
