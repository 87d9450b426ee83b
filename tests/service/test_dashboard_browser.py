"""The dashboard end to end in a real browser: Debian's Chromium (``/usr/bin/chromium``, which
``make test`` installs) driven by Playwright, against ``rcservice serve`` in a subprocess.

An admin signs in, sorts the fleet, opens a building, sees both charts drawn with data, starts a
calibration from the page and sees it finish (the page refreshes itself), with no console
error on the way; a building's token cannot open another building. With ``RC_SCREENSHOTS=1``
the pages are saved to ``docs/dashboard/`` for ``docs/dashboard.md``.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import httpx
import pandas as pd
import pytest

from .conftest import ADMIN_TOKEN, SYNTHETIC_BUILDING, LiveServer, json_rows, wait_for_job

sync_api = pytest.importorskip("playwright.sync_api")

pytestmark = pytest.mark.slow

CHROMIUM = Path("/usr/bin/chromium")
# What Chromium needs here: no sandbox as root, no GPU, no calls home on a closed network.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SCREENSHOTS = Path(__file__).resolve().parents[2] / "docs" / "dashboard"
FIRST_DAY = pd.Timestamp("2017-01-22T00:00:00+01:00")
FORECAST_DAY = pd.Timestamp("2017-01-30T00:00:00+01:00")
CALIBRATION_TIMEOUT_MS = 120_000


def screenshot(page, name: str) -> None:
    """Saved for the docs only when RC_SCREENSHOTS=1, so that test runs leave the tree clean."""
    if os.environ.get("RC_SCREENSHOTS") == "1":
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(SCREENSHOTS / f"{name}.png"), full_page=True)


@pytest.fixture(scope="module")
def browser() -> Iterator:
    if not CHROMIUM.exists() and shutil.which("chromium") is None:
        pytest.skip("Debian's chromium is not installed (make test installs it)")
    with sync_api.sync_playwright() as playwright:
        launched = playwright.chromium.launch(
            executable_path=str(CHROMIUM if CHROMIUM.exists() else shutil.which("chromium")),
            args=CHROMIUM_ARGS,
            headless=True,
        )
        yield launched
        launched.close()


@pytest.fixture
def page(browser) -> Iterator:
    """A fresh browser context (no cookies); console errors and page errors collected in
    ``page.errors``."""
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    new_page = context.new_page()
    new_page.errors = []
    # On the context: pages it opens (the diagnosis report's tab) are heard too.
    context.on(
        "console", lambda m: m.type == "error" and new_page.errors.append(f"console: {m.text}")
    )
    new_page.on("pageerror", lambda e: new_page.errors.append(f"page error: {e}"))
    yield new_page
    context.close()


@pytest.fixture(scope="module")
def fleet(tmp_path_factory, office, three_days_measured) -> Iterator[tuple[LiveServer, dict]]:
    """A live server with the EnergyPlus office (eight measured days and the next day's inputs,
    never calibrated) and the synthetic office (three days, calibrated and diagnosed by the
    API)."""
    # Three days fitted by the page's calibration (the default is seven): the test's budget.
    folder = tmp_path_factory.mktemp("dashboard")
    server = LiveServer(folder, RCSERVICE_TRAINING_DAYS="3").start()
    try:
        with server.client() as client:
            buildings = {
                "office": _office(client, *office),
                "synthetic": _synthetic(client, three_days_measured),
            }
        yield server, buildings
    finally:
        server.stop()


def _register(client: httpx.Client, description: dict) -> tuple[int, dict]:
    response = client.post(
        "/buildings", json=description, headers={"Authorization": f"Bearer {ADMIN_TOKEN}"}
    )
    assert response.status_code == 201, response.text
    return response.json()["id"], response.json()["token"]


def _office(client: httpx.Client, description: dict, raw: pd.DataFrame) -> dict:
    building_id, token = _register(client, description)
    past = raw[(raw.index >= FIRST_DAY) & (raw.index < FORECAST_DAY)]
    future = raw[(raw.index >= FORECAST_DAY) & (raw.index < FORECAST_DAY + pd.Timedelta("1D"))]
    future = future.assign(t_in="")
    upload = client.post(
        f"/buildings/{building_id}/measurements",
        content=pd.concat([past, future]).to_csv(index=False),
        headers={"Authorization": f"Bearer {token}", "content-type": "text/csv"},
    )
    assert upload.status_code == 200, upload.text
    return {"id": building_id, "token": token, "name": description["name"]}


def _synthetic(client: httpx.Client, frame: pd.DataFrame) -> dict:
    building_id, token = _register(client, SYNTHETIC_BUILDING)
    headers = {"Authorization": f"Bearer {token}"}
    rows = {"rows": json_rows(frame)}
    upload = client.post(f"/buildings/{building_id}/measurements", json=rows, headers=headers)
    assert upload.status_code == 200, upload.text
    job = client.post(f"/buildings/{building_id}/calibrations", json={"days": 1}, headers=headers)
    assert wait_for_job(client, job.json()["id"], headers)["status"] == "succeeded"
    # Two effects of the vocabulary only: a diagnosis of every effect takes a quarter minute.
    effects = {"effects": ["unmetered_gains", "window_solar_gains"]}
    job = client.post(f"/buildings/{building_id}/diagnoses", json=effects, headers=headers)
    assert wait_for_job(client, job.json()["id"], headers)["status"] == "succeeded"
    return {"id": building_id, "token": token, "name": SYNTHETIC_BUILDING["name"]}


def sign_in(page, server: LiveServer, token: str) -> None:
    page.goto(f"{server.url}/ui")
    assert page.url.endswith("/ui/login")
    page.fill("#token", token)
    page.click("button[type=submit]")
    page.wait_for_load_state("load")
    assert token not in page.url


def traces_drawn(page, chart: str) -> int:
    """Plotly traces of ``chart`` drawn with at least one line segment."""
    paths = page.locator(f"#{chart} .scatterlayer .trace path.js-line")
    return sum(1 for k in range(paths.count()) if len(paths.nth(k).get_attribute("d") or "") > 20)


def test_admin_sees_the_fleet_opens_a_building_and_calibrates_it(page, fleet):
    server, buildings = fleet
    office, synthetic = buildings["office"], buildings["synthetic"]
    page.goto(f"{server.url}/ui/fleet")
    screenshot(page, "sign-in")
    sign_in(page, server, ADMIN_TOKEN)
    assert page.url.endswith("/ui/fleet")
    rows = page.locator("#fleet tbody tr")
    assert rows.count() == 2
    page.click("#fleet th:has-text('held-out RMSE')")  # ascending: no set (-1) first
    assert page.locator("#fleet tbody tr").first.get_attribute("data-building") == str(office["id"])
    synthetic_row = page.locator(f"#fleet tr[data-building='{synthetic['id']}']")
    assert "promoted" in synthetic_row.inner_text() and "stale data" in synthetic_row.inner_text()
    assert synthetic_row.locator("td.verdict").inner_text().strip() not in ("", "–")
    screenshot(page, "fleet")

    page.click(f"#fleet a[href='/ui/buildings/{office['id']}']")
    page.wait_for_selector("body[data-charts=drawn]")
    assert traces_drawn(page, "chart-data") == 3  # t_in, t_out, q_hvac
    assert "no parameter set yet" in page.inner_text("body")

    page.click("#start-calibration")
    page.wait_for_selector(".flash:has-text('calibration job')")
    finished = "#jobs-table tr[data-status=succeeded]"
    page.wait_for_selector(finished, timeout=CALIBRATION_TIMEOUT_MS)
    page.wait_for_selector("body[data-charts=drawn]")
    assert "promoted" in page.inner_text("#jobs-table")
    # measured, day-ahead predicted and the forecast (its ±2σ band is drawn as a fill).
    assert traces_drawn(page, "chart-forecast") >= 3
    assert page.locator("#sets tbody tr.current").count() == 1
    page.hover("#chart-forecast .nsewdrag")  # plotly's hover layer answers
    screenshot(page, "building")
    assert page.errors == []

    page.goto(f"{server.url}/ui/buildings/{synthetic['id']}")
    page.wait_for_selector("body[data-charts=drawn]")
    assert page.inner_text("#verdict").strip()
    screenshot(page, "building-diagnosed")
    with page.expect_popup() as popup:
        page.click("a:has-text('Full report')")
    report = popup.value
    report.wait_for_load_state("load")
    assert "<img" in report.content() or "<svg" in report.content()
    report.close()
    assert page.errors == []


def test_a_building_token_cannot_open_another_building(page, fleet):
    server, buildings = fleet
    own, other = buildings["synthetic"], buildings["office"]
    sign_in(page, server, own["token"])
    assert page.url.endswith(f"/ui/buildings/{own['id']}")
    page.wait_for_selector("body[data-charts=drawn]")
    assert traces_drawn(page, "chart-forecast") >= 3
    assert page.errors == []
    response = page.goto(f"{server.url}/ui/buildings/{other['id']}")
    assert response.status == 404
    assert "not found" in page.inner_text("main") and other["name"] not in page.content()
    assert [e for e in page.errors if "404" not in e] == []  # Chromium logs the 404 itself
    page.errors.clear()
    page.goto(f"{server.url}/ui/fleet")
    assert page.url.endswith(f"/ui/buildings/{own['id']}")
    assert page.errors == []
