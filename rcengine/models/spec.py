"""A storable model specification: the network a building is calibrated and served with.

A diagnosis ends in an extended network (``basic+wind_infiltration`` …) whose inputs are derived
signals (wind × ΔT, a learnt schedule × ΔT, the ground temperature, plane-of-array irradiance)
that need settings of their own (the schedule and its clock, the ground's annual cycle). A
``ModelSpec`` keeps all of it generically — the RC network itself (nodes, capacitors, resistors,
heat inputs, parameters with units and bounds, output), the ``SignalOptions`` and the provenance
(base model, effect ids, the diagnosis it came from, each effect's detail) — so that a later fit,
forecast or state-space export rebuilds exactly that network without knowing how the diagnosis
built it.

The JSON document carries ``spec_version``; ``from_dict`` reads the versions in
``READABLE_VERSIONS`` and answers any other with a clear :class:`ModelError`.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Collection, Iterable
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import pandas as pd

from rcengine import __version__
from rcengine.building import Building
from rcengine.columns import (
    CLOUD_COVER,
    DERIVED_FROM,
    GHI,
    NUMERIC_COLUMNS,
    SKY_DELTA,
    SOLAR_OPAQUE,
    SOLAR_WINDOW,
    T_GROUND,
    T_OUT,
    WIND_SPEED,
    is_orientation_signal,
)
from rcengine.exceptions import DataValidationError, ModelError, Problem
from rcengine.io.files import write_text_atomic
from rcengine.io.jsonable import jsonable, read_json
from rcengine.models.frozen_split import (
    WINDOW_EFFECT,
    WINDOW_SCALE,
    frozen_split,
    window_parameters,
)
from rcengine.network import RCNetwork
from rcengine.signals import SignalOptions
from rcengine.signals.ground import annual_cycle

SPEC_VERSION = 1
# Versions this engine reads. A future version that changes the document adds its number here
# with an upgrade of the older documents in ``_upgrade``.
READABLE_VERSIONS = (1,)
BASE = "base"  # source of a specification that is just a library model


def building_key(building: Building) -> str:
    """A fingerprint of the physics of a building description (its name left out): the
    network's element values are scaled by its areas, so a specification fits one building."""
    physics = {k: v for k, v in building.to_dict().items() if k != "name"}
    text = json.dumps(jsonable(physics), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def columns_needed(inputs: Iterable[str], signals: SignalOptions | None = None) -> list[str]:
    """The contract columns the model inputs ``inputs`` are read or derived from (with the
    derived-signal settings ``signals``: a sky read from measured cloud cover needs it, an opaque
    sun through an outer film that follows the wind the wind speed)."""
    needed: list[str] = []
    for name in inputs:
        if name == SKY_DELTA and signals is not None and signals.cloud_cover == "column":
            needed.append(CLOUD_COVER)
        filmed = is_orientation_signal(name, SOLAR_OPAQUE)
        if filmed and signals is not None and signals.exterior_film == "wind":
            needed.append(WIND_SPEED)
        if name in NUMERIC_COLUMNS:
            needed.append(name)
        elif name in DERIVED_FROM:
            needed.extend(DERIVED_FROM[name])
        elif name.startswith((SOLAR_WINDOW, SOLAR_OPAQUE)):
            needed.append(GHI)  # dni/dhi are used when given, decomposed from ghi otherwise
        # sched_<name>: a stored schedule, played back from the clock alone.
    return list(dict.fromkeys(needed))


@dataclass(frozen=True)
class ModelSpec:
    """The model a building uses: ``rc`` (the network, built for one building description),
    ``signals`` (how its derived inputs are computed), ``base_model`` (the library model it
    extends), ``effects`` (accepted extensions, in the order they were added) and ``source``
    (``kind``: "base" or "diagnosis", ``diagnosis_id``, ``details`` by effect)."""

    base_model: str
    rc: RCNetwork
    signals: SignalOptions = field(default_factory=SignalOptions)
    effects: tuple[str, ...] = ()
    source: dict[str, Any] = field(default_factory=lambda: {"kind": BASE})
    building: str | None = None  # building_key of the description the network was built for
    engine_version: str = __version__

    @property
    def name(self) -> str:
        """The model's name, e.g. ``basic+wind_infiltration``."""
        return self.rc.name

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.rc.compile().input_names

    @property
    def required_columns(self) -> list[str]:
        """Contract columns the data (and a forecast's future rows) must hold."""
        return columns_needed(self.inputs, self.signals)

    def network(self, building: Building) -> RCNetwork:
        """A fresh copy of the network for ``building``; a different building is an error."""
        if self.building is not None and self.building != building_key(building):
            raise ModelError(
                f"the model specification '{self.name}' was built for another building "
                "description (areas, orientations or location differ); diagnose this building "
                "and save its model again"
            )
        return self.rc.copy()

    # --- construction ---------------------------------------------------------------------
    @classmethod
    def base(
        cls,
        network: RCNetwork,
        model: str,
        building: Building,
        signals: SignalOptions | None = None,
    ) -> ModelSpec:
        """The specification of a library model (``get_model``) as it stands."""
        options = signals or SignalOptions()
        return cls(model, network.copy(), options, building=building_key(building))

    @classmethod
    def from_report(
        cls,
        report: dict[str, Any],
        building: Building,
        frame: pd.DataFrame | None = None,
        diagnosis_id: int | None = None,
        finding: str | None = None,
    ) -> ModelSpec:
        """The final model of a diagnosis report (``Report.to_dict``, as stored), or with
        ``finding`` the refitted model that adds that effect, whether the diagnosis accepted it or
        not (an engineer's choice, which a calibration's held-out day still has to bear out). With
        the record ``frame`` it diagnosed, slow signals fitted to that record (the ground's annual
        cycle) are fixed (``with_fixed_signals``), so that a one-day forecast sees the ground the
        months of the diagnosis saw; ``needs_record`` says whether that is needed.
        """
        if finding is not None:
            spec = cls._of_finding(report, building, finding, diagnosis_id)
            spec = spec.with_diagnosed_split(_window_fit(report))
            return spec if frame is None else spec.with_fixed_signals(frame, building)
        final = report.get("final") or {}
        if "network" not in final or "signals" not in final:
            raise ModelError(
                "this diagnosis report holds no final network (it was written by an older "
                "engine); run the diagnosis again to adopt its model"
            )
        accepted = [f for f in report.get("findings", []) if f.get("accepted")]
        if not accepted:
            raise ModelError(
                "the diagnosis accepted no extension: its model is the base model, nothing to adopt"
            )
        spec = cls(
            base_model=report["baseline"]["model"],
            rc=RCNetwork.from_dict(final["network"]),
            signals=_signal_options(final["signals"]),
            effects=tuple(f["effect"] for f in accepted),
            source={
                "kind": "diagnosis",
                "diagnosis_id": diagnosis_id,
                "details": {f["effect"]: f.get("detail", {}) for f in accepted},
            },
            building=building_key(building),
        )
        spec = spec.with_diagnosed_split(final.get("parameters", {}))
        return spec if frame is None else spec.with_fixed_signals(frame, building)

    @classmethod
    def _of_finding(
        cls, report: dict[str, Any], building: Building, effect: str, diagnosis_id: int | None
    ) -> ModelSpec:
        """The model a report's finding on ``effect`` was refitted as: the model of its round
        (the base model and the extensions accepted before) with the effect added."""
        judged = {f["effect"]: f for f in report.get("findings", [])}
        if effect not in judged:
            named = ", ".join(judged) or "none"
            raise ModelError(f"the diagnosis judged no '{effect}' (it judged: {named})")
        model = judged[effect].get("model")
        if not model:
            raise ModelError(
                f"'{effect}' was screened, not refitted (or the report was written by an older "
                "engine): the diagnosis holds no fitted model with it; diagnose again with only "
                "that effect to refit it"
            )
        base = report["baseline"]["model"]
        rc = RCNetwork.from_dict(model["network"])
        # Each extension names its network ``<model>+<effect>`` (``candidates._name``).
        effects = tuple(rc.name.removeprefix(f"{base}+").split("+"))
        return cls(
            base_model=base,
            rc=rc,
            signals=_signal_options(model["signals"]),
            effects=effects,
            source={
                "kind": "diagnosis",
                "diagnosis_id": diagnosis_id,
                "finding": effect,
                "accepted": bool(judged[effect].get("accepted")),
                "details": {e: judged[e].get("detail", {}) for e in effects if e in judged},
            },
            building=building_key(building),
        )

    def with_diagnosed_split(self, fitted: dict[str, float]) -> ModelSpec:
        """This specification with the window gains' split across orientations, as ``fitted``
        by the diagnosis, kept and one scale left to fit (``frozen_split``)."""
        detail = self.source.get("details", {}).get(WINDOW_EFFECT)
        if detail is None:
            return self
        rc = frozen_split(self.rc, fitted, window_parameters(detail), WINDOW_SCALE)
        return self if rc is self.rc else replace(self, rc=rc)

    @property
    def needs_record(self) -> bool:
        """Whether a signal setting is still to be fitted to a long record (the ground's)."""
        return T_GROUND in self.inputs and self.signals.ground_cycle is None

    def with_fixed_signals(self, frame: pd.DataFrame, building: Building) -> ModelSpec:
        """This specification with the ground's annual cycle fitted to ``frame`` (if it has a
        ground input and no cycle yet) — what ``prepare`` would fit to each frame anew."""
        if not self.needs_record:
            return self
        t_out = frame[T_OUT].to_numpy(dtype=float)
        cycle = annual_cycle(frame.index, t_out, building.location.latitude)
        return replace(self, signals=replace(self.signals, ground_cycle=cycle.to_dict()))

    # --- JSON -----------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return {
            "spec_version": SPEC_VERSION,
            "engine_version": self.engine_version,
            "name": self.name,
            "base_model": self.base_model,
            "effects": list(self.effects),
            "source": self.source,
            "building": self.building,
            "inputs": list(self.inputs),
            "required_columns": self.required_columns,
            "network": self.rc.to_dict(),
            "signals": self.signals.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: Any) -> ModelSpec:
        """Read a stored document; an unreadable version or field is a clear ModelError."""
        data = _upgrade(data)
        try:
            return cls(
                base_model=str(data["base_model"]),
                rc=RCNetwork.from_dict(data["network"]),
                signals=_signal_options(data.get("signals", {})),
                effects=tuple(data.get("effects", ())),
                source=dict(data.get("source") or {"kind": BASE}),
                building=data.get("building"),
                engine_version=str(data.get("engine_version", "unknown")),
            )
        except KeyError as exc:
            raise ModelError(f"invalid model specification: no {exc.args[0]!r} entry") from exc
        except (TypeError, ValueError) as exc:
            raise ModelError(f"invalid model specification: {exc}") from exc

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(jsonable(self.to_dict()), indent=indent, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> ModelSpec:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ModelError(f"a model specification must be JSON: {exc}") from exc
        return cls.from_dict(data)

    def save(self, path: str | Path) -> None:
        write_text_atomic(path, self.to_json() + "\n")

    @classmethod
    def load(cls, path: str | Path) -> ModelSpec:
        return cls.from_dict(read_json(path, ModelError))


def _upgrade(data: Any) -> dict[str, Any]:
    """The document in the current version's shape, or a ModelError saying why not."""
    if not isinstance(data, dict) or "spec_version" not in data:
        hint = ""
        if isinstance(data, dict) and "parameters" in data and "network" in data:
            hint = " (this looks like a parameter file: use it with `rcengine predict`)"
        raise ModelError(f"not a model specification: no 'spec_version' entry{hint}")
    version = data["spec_version"]
    if version not in READABLE_VERSIONS:
        newer = isinstance(version, int) and version > SPEC_VERSION
        why = "newer than this engine; upgrade rcengine" if newer else "not one this engine reads"
        raise ModelError(
            f"model specification version {version!r} is {why} (it reads versions "
            f"{list(READABLE_VERSIONS)}); adopt the diagnosis or save the model again"
        )
    return data


def _window_fit(report: dict[str, Any]) -> dict[str, float]:
    """The window gains' per-orientation values as the diagnosis fitted them, where it did."""
    window = [f for f in report.get("findings", []) if f.get("effect") == WINDOW_EFFECT]
    return dict(window[0].get("parameters") or {}) if window else {}


def _signal_options(data: dict[str, Any]) -> SignalOptions:
    """SignalOptions from a stored document; settings an older engine did not write take their
    defaults, settings this engine does not know are refused by name."""
    known = {f.name for f in fields(SignalOptions)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise ModelError(
            f"the model's signal settings {unknown} are unknown to this engine "
            f"(version {__version__}); upgrade rcengine"
        )
    return SignalOptions.from_stored(data)


def check_columns(spec_or_inputs: ModelSpec | Collection[str], columns: Collection[str]) -> None:
    """ModelError naming the contract columns the model needs that ``columns`` lack."""
    needed = (
        spec_or_inputs.required_columns
        if isinstance(spec_or_inputs, ModelSpec)
        else columns_needed(spec_or_inputs)
    )
    missing = [c for c in needed if c not in columns]
    if missing:
        raise ModelError(f"the model needs the column(s) {missing}, absent from the data")


def check_future_columns(
    frame: pd.DataFrame,
    inputs: Collection[str],
    start: pd.Timestamp,
    end: pd.Timestamp,
    signals: SignalOptions | None = None,
) -> None:
    """DataValidationError naming each contract column the model's ``inputs`` are computed from
    that the rows in [start, end) — a forecast's future rows — lack, with how many and the first
    time; derived inputs (wind × ΔT, plane-of-array irradiance …) would otherwise be reported
    by their own names, which no upload has."""
    rows = frame.loc[(frame.index >= start) & (frame.index < end)]
    problems = []
    for column in columns_needed(inputs, signals):
        values = rows[column] if column in rows.columns else pd.Series(float("nan"), rows.index)
        missing = rows.index[values.isna().to_numpy()]
        if len(missing):
            problems.append(
                Problem(
                    None,
                    column,
                    f"the model needs '{column}' over the forecast: missing at {len(missing)} of "
                    f"{len(rows)} future row(s), first {missing[0].isoformat()}",
                )
            )
    if problems:
        raise DataValidationError(problems)
