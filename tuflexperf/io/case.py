"""Loaders of the case (requirement file) and the aircraft and propulsion files it names.

The schemas and the loaded :class:`Case` are in :mod:`tuflexperf.io.schemas`; they are named
here too, where every reader has imported them from.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tuflexperf.errors import InputError
from tuflexperf.io.files import listed_file
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
    "Requirements", "TakeoffSchema", "UncertaintySchema", "FILE_KEYS", "aircraft_from_schema",
    "case_files", "load_aircraft", "load_case", "load_propulsion", "propulsion_from_schema",
    "refuse_absurd_propulsion", "shipped_case_path",
]


def load_aircraft(path: Path) -> Aircraft:
    """Load and validate an aircraft file."""
    return aircraft_from_schema(load_model(Path(path), AircraftSchema))


def load_propulsion(path: Path) -> Propulsion:
    """Load and validate a propulsion file."""
    return propulsion_from_schema(load_model(Path(path), PropulsionSchema))


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


# the files a case names that a flag may replace for one run (--aircraft, --propulsion,
# --battery), in the order their problems are reported
FILE_KEYS = ("battery", "aircraft", "propulsion")


def _named_files(case_path: Path) -> dict[str, str]:
    """The file names a case that its schema refused writes (its other problems are said
    already): each named file is still checked, so one run reports them all."""
    from tuflexperf.io.yamlio import read_yaml

    try:
        data = read_yaml(case_path)
    except InputError:
        return {}
    if not isinstance(data, dict):
        return {}
    return {key: data[key] for key in FILE_KEYS if isinstance(data.get(key), str) and data[key]}


def _given(value: Path, flag: str) -> Path:
    """A file given by a flag (relative to the working directory), resolved."""
    target = Path(value).resolve()
    if not target.is_file():
        from tuflexperf.io.files import why_not_a_file

        raise InputError(f"{flag}: {why_not_a_file(target)}: {value}")
    return target


def _validate_battery(path: Path) -> None:
    from tuflexperf.io.battery import load_battery  # validate now: bad keys fail early

    load_battery(path)


def load_case(path: Path | str | None = None,
              replace: Mapping[str, Path] | None = None) -> Case:
    """Load a requirement file and the aircraft/propulsion files it names (paths relative to it).

    ``replace`` maps ``aircraft``, ``propulsion`` or ``battery`` to a file (relative to the
    working directory) read instead of the one the case names, for this run: the
    ``--aircraft``, ``--propulsion`` and ``--battery`` flags, which its problems name.

    Raises one :class:`InputError` holding every problem of the case and of every file it
    names (three misspelt keys in one file and a bad value in another: four lines).
    """
    case_path = Path(path) if path is not None else shipped_case_path()
    if case_path.is_dir():
        raise InputError(f"{case_path}: is a directory, expected a requirement file (.yaml)")
    replace = dict(replace or {})
    problems: list[str] = []
    schema: CaseSchema | None = None
    try:
        schema = load_model(case_path, CaseSchema)
        named = {key: getattr(schema, key) for key in FILE_KEYS if getattr(schema, key)}
    except InputError as exc:
        problems.extend(exc.problems)
        named = _named_files(case_path)
    paths: dict[str, Path] = {}
    for key in FILE_KEYS:
        try:
            if key in replace:
                paths[key] = _given(replace[key], f"--{key}")
            elif key in named:
                paths[key] = listed_file(case_path, key, named[key], shown=True)
        except InputError as exc:
            problems.extend(exc.problems)
    loaders = {"battery": _validate_battery, "aircraft": load_aircraft,
               "propulsion": lambda p: load_model(p, PropulsionSchema)}
    loaded: dict[str, Any] = {}
    for key, target in paths.items():
        try:
            loaded[key] = loaders[key](target)
        except InputError as exc:
            flag = f"--{key}: " if key in replace else ""
            problems.extend(flag + problem for problem in exc.problems)
    flights: list[Path] = []
    if schema is not None and schema.validation is not None:
        from tuflexperf.io.flight_summary import load_flight_summary

        for index, name in enumerate(schema.validation.flights):
            try:
                target = listed_file(case_path, f"validation.flights[{index}]", name,
                                     shown=True)
                load_flight_summary(target)  # validate now: bad keys fail early
                flights.append(target)
            except InputError as exc:
                problems.extend(exc.problems)
    if problems or schema is None:
        raise InputError.of(problems)
    propulsion_schema = loaded["propulsion"]
    case = Case(
        name=schema.name,
        path=case_path,
        aircraft=loaded["aircraft"],
        propulsion=propulsion_from_schema(propulsion_schema),
        atmosphere=schema.atmosphere,
        requirements=schema.requirements,
        aircraft_path=paths["aircraft"],
        propulsion_path=paths["propulsion"],
        battery_path=paths.get("battery"),
        uncertainty=schema.uncertainty,
        propulsion_schema=propulsion_schema,
        replaced=tuple(key for key in FILE_KEYS if key in replace),
        validation_flights=tuple(flights),
    )
    try:
        refuse_absurd_propulsion(case)
    except InputError as exc:
        raise InputError(("--propulsion: " if "propulsion" in replace else "") + str(exc)
                         ) from None
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
    files.extend(("flight summary", path) for path in case.validation_flights)
    return files
