"""Loaders of the case (requirement file) and the aircraft and propulsion files it names.

The schemas and the loaded :class:`Case` are in :mod:`tuflexperf.io.schemas`; they are named
here too, where every reader has imported them from.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

from tuflexperf.errors import InputError
from tuflexperf.io.schemas import (
    ABSURD_THRUST_TO_WEIGHT,
    MAX_SAMPLES,
    MAX_SOURCE_VALUES,
    AircraftSchema,
    AtmosphereSchema,
    Case,
    CaseSchema,
    OeiRequirement,
    PropulsionSchema,
    Requirements,
    TakeoffSchema,
    UncertaintySchema,
    aircraft_from_schema,
    propulsion_from_schema,
    refuse_absurd_propulsion,
)
from tuflexperf.io.yamlio import load_model

if TYPE_CHECKING:
    from tuflexperf.models.aircraft import Aircraft
    from tuflexperf.models.thrust import Propulsion

__all__ = [
    "ABSURD_THRUST_TO_WEIGHT", "MAX_SAMPLES", "MAX_SOURCE_VALUES", "AircraftSchema",
    "AtmosphereSchema", "Case", "CaseSchema", "OeiRequirement", "PropulsionSchema",
    "Requirements", "TakeoffSchema", "UncertaintySchema", "aircraft_from_schema",
    "case_files", "load_aircraft", "load_case", "load_propulsion", "propulsion_from_schema",
    "refuse_absurd_propulsion", "shipped_case_path",
]


def load_aircraft(path: Path) -> Aircraft:
    """Load and validate an aircraft file."""
    return aircraft_from_schema(load_model(Path(path), AircraftSchema))


def load_propulsion(path: Path) -> Propulsion:
    """Load and validate a propulsion file."""
    return propulsion_from_schema(load_model(Path(path), PropulsionSchema))


def _resolve(case_path: Path, key: str, value: str) -> Path:
    target = (case_path.parent / value).resolve()
    if not target.is_file():
        from tuflexperf.io.files import why_not_a_file

        raise InputError(f"{case_path}: {key}: {why_not_a_file(target)}: {value} (resolved to "
                         f"{target})")
    return target


def shipped_case_path() -> Path:
    """The TU-Flex case shipped with the package (wheel) or the checkout (editable install)."""
    here = Path(__file__).resolve().parent.parent
    for candidate in (
        here / "_shipped" / "requirements" / "tuflex.yaml",
        here.parent / "requirements" / "tuflex.yaml",
    ):
        if candidate.is_file():
            return candidate
    raise InputError("the shipped TU-Flex case is missing from this installation; pass a CASE")


def load_case(path: Path | str | None = None) -> Case:
    """Load a requirement file and the aircraft/propulsion files it names (paths relative to it)."""
    case_path = Path(path) if path is not None else shipped_case_path()
    if case_path.is_dir():
        raise InputError(f"{case_path}: is a directory, expected a requirement file (.yaml)")
    schema = load_model(case_path, CaseSchema)
    aircraft_path = _resolve(case_path, "aircraft", schema.aircraft)
    propulsion_path = _resolve(case_path, "propulsion", schema.propulsion)
    battery_path = _resolve(case_path, "battery", schema.battery) if schema.battery else None
    if battery_path is not None:
        from tuflexperf.io.battery import load_battery  # validate now: bad keys fail early

        load_battery(battery_path)
    aircraft = load_aircraft(aircraft_path)
    propulsion_schema = load_model(propulsion_path, PropulsionSchema)
    propulsion = propulsion_from_schema(propulsion_schema)
    case = Case(
        name=schema.name,
        path=case_path,
        aircraft=aircraft,
        propulsion=propulsion,
        atmosphere=schema.atmosphere,
        requirements=schema.requirements,
        aircraft_path=aircraft_path,
        propulsion_path=propulsion_path,
        battery_path=battery_path,
        uncertainty=schema.uncertainty,
        propulsion_schema=propulsion_schema,
    )
    if not math.isfinite(case.density_kg_m3) or case.density_kg_m3 <= 0:
        raise InputError(f"{case_path}: atmosphere: gives no valid density")
    refuse_absurd_propulsion(case)
    if schema.uncertainty is not None:
        from tuflexperf.io.dotted import check_key  # only a case that samples needs it

        for key in schema.uncertainty.parameters:
            check_key(case, key, f"{case_path}: uncertainty.parameters")
    return case


def case_files(case: Case) -> list[tuple[str, Path]]:
    """(role, path) of every file a case's analyses read: the case, its aircraft, propulsion
    and battery files, the battery's discharge runs and the mission file of its mission
    requirement. Outputs may never replace one of these (SPEC 5)."""
    files: list[tuple[str, Path]] = [
        ("case", case.path),
        ("aircraft", case.aircraft_path),
        ("propulsion", case.propulsion_path),
    ]
    if case.battery_path is not None:
        files.append(("battery", case.battery_path))
        try:
            from tuflexperf.io.battery import load_battery

            files.extend(("discharge run", r.path) for r in load_battery(case.battery_path).runs)
        except InputError:
            pass  # a broken battery file is reported by the analysis that reads it
    mission = case.requirements.mission
    if mission is not None:
        files.append(("mission", (Path(case.path).parent / mission.file).resolve()))
    return files
