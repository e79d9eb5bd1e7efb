"""Dotted parameter keys of a case (``aircraft.mass_kg``, ``atmosphere.altitude_m``, ...).

One place that lists a case's numeric keys with their nominal values and builds a case
with some of them changed, validated by the same schemas as the files. Used by the
``uncertainty:`` block, ``margins`` and ``sweep --vary``.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import BaseModel, TypeAdapter, ValidationError

from tuflexperf.errors import InputError
from tuflexperf.io.battery import BATTERY_FIELDS
from tuflexperf.io.schemas import AircraftSchema, Case, Requirements, refuse_absurd_propulsion
from tuflexperf.models.aircraft import Aircraft

if TYPE_CHECKING:
    from tuflexperf.io.battery import Battery

BATTERY_KEYS = tuple(BATTERY_FIELDS)
"""Battery keys that vary without refitting the pack model (the others are refused)."""

# The envelope's bounds, each a true or an equivalent airspeed: a batch varies the kind the
# case gives; --set may also switch a bound to the other kind (then an unset key).
_BOUND_KEYS = {
    "requirements.envelope.min_airspeed_m_s",
    "requirements.envelope.max_airspeed_m_s",
    "requirements.envelope.min_airspeed_eas_m_s",
    "requirements.envelope.max_airspeed_eas_m_s",
}


_OTHER_KIND_OF_BOUND = {
    "min_airspeed_m_s": "min_airspeed_eas_m_s", "min_airspeed_eas_m_s": "min_airspeed_m_s",
    "max_airspeed_m_s": "max_airspeed_eas_m_s", "max_airspeed_eas_m_s": "max_airspeed_m_s",
}


def _flatten(prefix: str, value: Any, out: dict[str, float]) -> None:
    if isinstance(value, Mapping):
        for key, item in value.items():
            _flatten(f"{prefix}.{key}", item, out)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        out[prefix] = float(value)


def battery_key_values(battery: Battery) -> dict[str, float]:
    """A loaded battery's values of the keys in :data:`BATTERY_KEYS` [units of the keys]."""
    return {key: float(getattr(battery, field)) for key, field in BATTERY_FIELDS.items()}


def battery_values(case: Case) -> dict[str, float]:
    """The case's battery keys of :data:`BATTERY_KEYS` with their values (none: no battery)."""
    if case.battery_path is None:
        return {}
    from tuflexperf.io.battery import case_battery

    return battery_key_values(case_battery(case))


def numeric_keys(case: Case, battery: bool = True) -> dict[str, float]:
    """Every numeric key of the case, aircraft, atmosphere (and battery) that may vary."""
    out: dict[str, float] = {}
    _flatten("aircraft", dataclasses.asdict(case.aircraft), out)
    _flatten("atmosphere", case.atmosphere.model_dump(), out)
    _flatten("requirements", case.requirements.model_dump(exclude_none=True), out)
    if battery:
        out.update(battery_values(case))
    return out


def unset_optional_keys(case: Case) -> set[str]:
    """Optional numeric keys the case leaves unset, e.g. ``aircraft.takeoff.liftoff_speed_m_s``.

    ``--set`` may give them (the file could); they have no nominal value, so samples,
    sweeps and margins, which vary a key about its nominal, do not take them.
    """
    import typing

    from tuflexperf.io.schemas import AtmosphereSchema, TakeoffSchema

    def numeric_optional(annotation: Any) -> bool:
        stack, kinds = [annotation], set()
        while stack:
            kind = stack.pop()
            args = typing.get_args(kind)
            if typing.get_origin(kind) is typing.Annotated:
                stack.append(args[0])
            elif args:
                stack += list(args)
            else:
                kinds.add(kind)
        return type(None) in kinds and bool(kinds & {float, int})

    blocks: list[tuple[str, type[BaseModel], Mapping[str, Any]]] = [
        ("aircraft", AircraftSchema, dataclasses.asdict(case.aircraft)),
        ("aircraft.takeoff", TakeoffSchema, dataclasses.asdict(case.aircraft.takeoff)),
        ("atmosphere", AtmosphereSchema, case.atmosphere.model_dump()),
    ]
    for name in type(case.requirements).model_fields:
        block = getattr(case.requirements, name)
        if block is not None:
            blocks.append((f"requirements.{name}", type(block), block.model_dump()))
    return {
        f"{prefix}.{name}"
        for prefix, schema, values in blocks
        for name, field in schema.model_fields.items()
        if values.get(name) is None and numeric_optional(field.annotation)
    }


UNVARIED_KEY = "requirements.extrapolation.required_probability"
"""A numeric key a batch (sweep, samples, margins) does not vary: it sets the evidence's bound."""


def check_key(case: Case, key: str, where: str, unset: bool = False) -> None:
    """Raise :class:`InputError` naming ``where`` and the closest key if ``key`` is unknown.

    With ``unset`` (``--set``: one case, not a batch), an optional numeric key the case leaves
    unset is known too, and so is either kind of envelope bound (true or equivalent).
    """
    known = numeric_keys(case)
    if key == UNVARIED_KEY and not unset:
        # the readings are made once per run from the case, not per row of a batch
        raise InputError(f"{where}: {key}: the probability a requirement resting on "
                         "extrapolated thrust must reach is one number per run: give it in "
                         "the case or with --set, it cannot be varied or drawn")
    if key in known or (unset and key in _BOUND_KEYS and case.requirements.envelope is not None):
        return
    optional = unset_optional_keys(case) if unset else set()
    if key in optional:
        return
    parts = key.split(".")
    if (len(parts) == 3 and parts[0] == "requirements" and parts[1] in Requirements.model_fields
            and getattr(case.requirements, parts[1]) is None):
        # a real key of a block the case leaves out ("did you mean" another block's misleads)
        raise InputError(f"{where}: {key}: the case has no requirements.{parts[1]} block "
                         "to change; add it to the case file")
    if key in _BOUND_KEYS:
        other = f"requirements.envelope.{_OTHER_KIND_OF_BOUND[parts[-1]]}"
        kind = "an equivalent" if other.endswith("_eas_m_s") else "a true"
        raise InputError(f"{where}: {key}: the case gives this bound as {kind} airspeed; vary "
                         f"{other}, or --set this one for a single case")
    if key.startswith("propulsion."):
        raise InputError(
            f"{where}: {key}: the propulsion file's keys cannot be varied (they are the fitted "
            "thrust model: refit with `tuflexperf fit`; its uncertainty is "
            "`uncertainty.propulsion`)"
        )
    if key.startswith("battery.") and case.battery_path is None:
        raise InputError(f"{where}: {key}: the case names no battery file")
    if key.startswith("battery."):
        raise InputError(
            f"{where}: {key}: cannot be varied (of the battery only "
            f"{', '.join(BATTERY_KEYS)}: the pack model is fitted to its discharge runs)"
        )
    close = difflib.get_close_matches(key, [*known, *optional], n=1)
    hint = f" (did you mean {close[0]}?)" if close else ""
    raise InputError(f"{where}: unknown or non-numeric key {key!r}{hint}")


def _schema_field(case: Case, key: str) -> Any:
    from tuflexperf.io.schemas import AtmosphereSchema, TakeoffSchema

    head, *rest = key.split(".")
    if head == "battery":
        from tuflexperf.io.battery import BatterySchema, MissionSchema

        schema: Any = MissionSchema if rest[0] == "mission" else BatterySchema
    elif head == "aircraft":
        schema = TakeoffSchema if rest[0] == "takeoff" and len(rest) > 1 else AircraftSchema
    elif head == "atmosphere":
        schema = AtmosphereSchema
    else:
        schema = type(getattr(case.requirements, rest[0]))
    return schema.model_fields[rest[-1]]


def value_bounds(case: Case, key: str) -> tuple[float, bool, float, bool]:
    """The key's schema bounds: (low, low inclusive, high, high inclusive) in its unit."""
    import typing

    field = _schema_field(case, key)
    constraints = list(field.metadata)
    stack = [field.annotation]
    while stack:  # constraints of an Optional[Annotated[float, ...]] sit inside the union
        kind = stack.pop()
        if typing.get_origin(kind) is typing.Annotated:
            constraints += list(typing.get_args(kind)[1:])
        stack += [a for a in typing.get_args(kind) if a is not type(None)]
    low, low_in, high, high_in = -math.inf, False, math.inf, False
    for item in list(constraints):  # a Field(...) inside Annotated carries its own metadata
        constraints += list(getattr(item, "metadata", None) or [])
    for c in constraints:
        for name, value in (("gt", False), ("ge", True)):
            if getattr(c, name, None) is not None and float(getattr(c, name)) >= low:
                low, low_in = float(getattr(c, name)), value
        for name, value in (("lt", False), ("le", True)):
            if getattr(c, name, None) is not None and float(getattr(c, name)) <= high:
                high, high_in = float(getattr(c, name)), value
    return low, low_in, high, high_in


def check_value(case: Case, key: str, value: float, where: str, unset: bool = False) -> None:
    """Raise :class:`InputError` if ``value`` breaks the key's own bounds in its schema.

    Only the field itself is checked (e.g. a positive mass); cross-field rules (a lift-off
    speed below a heavier aircraft's stall) are the analyses' to report per point. ``unset``
    as in :func:`check_key` (``--set``).
    """
    check_key(case, key, where, unset)
    field = _schema_field(case, key)
    try:
        kind = Annotated[(field.annotation, *field.metadata)] if field.metadata \
            else field.annotation
        TypeAdapter(kind).validate_python(value)
    except ValidationError as exc:
        raise InputError(f"{where}: {key}={float(value)!r}: {_problem(exc)}") from None


def _problem(exc: ValidationError) -> str:
    """The first error's message, without pydantic's "Value error, " prefix."""
    return str(exc.errors()[0]["msg"]).removeprefix("Value error, ")


def _set_in(data: dict[str, Any], path: list[str], value: float) -> dict[str, Any]:
    """``value`` at the nested ``path`` of ``data`` (in place); the innermost mapping."""
    for part in path[:-1]:
        data = data[part]
    data[path[-1]] = value
    return data


def with_values(case: Case, values: Mapping[str, float], where: str = "--set") -> Case:
    """The case with the dotted keys set to ``values``, validated like the files.

    Raises
    ------
    InputError
        Naming ``where`` and the key when a key is unknown or a value out of range.
    """
    aircraft = dataclasses.asdict(case.aircraft)
    atmosphere, requirements = case.atmosphere, case.requirements
    changed: dict[str, tuple[list[str], float]] = {}  # requirement keys, validated together
    for key, value in values.items():
        check_key(case, key, where, unset=True)
        head, *rest = key.split(".")
        try:
            if head == "battery":
                # the battery file is read where it is flown (io.battery.case_battery), with
                # the case's overrides: only the value's own bounds here
                check_value(case, key, float(value), where, unset=True)
            elif head == "aircraft":
                _set_in(aircraft, rest, float(value))
            elif head == "atmosphere":
                data = atmosphere.model_dump()
                _set_in(data, rest, float(value))
                atmosphere = type(atmosphere).model_validate(data)
            else:
                # each value against its own field now; a rule across fields (the envelope's
                # min below its max) once all are set, so both bounds may move together
                check_value(case, key, float(value), where, unset=True)
                changed[key] = (rest, float(value))
        except ValidationError as exc:
            raise InputError(f"{where}: {key}={float(value)!r}: {_problem(exc)}") from None
    if changed:
        data = requirements.model_dump(exclude_none=True)  # absent blocks stay absent
        for rest, value in changed.values():
            node = _set_in(data, rest, value)
            # an envelope bound set as true airspeed replaces its equivalent one, and back
            other = _OTHER_KIND_OF_BOUND.get(rest[-1]) if rest[0] == "envelope" else None
            if other is not None and not any(r[-1] == other for r, _ in changed.values()):
                node.pop(other, None)
        try:
            requirements = type(requirements).model_validate(data)
        except ValidationError as exc:
            keys = ", ".join(f"{k}={v:g}" for k, (_, v) in changed.items())
            raise InputError(f"{where}: {keys}: {_problem(exc)}") from None
    try:
        AircraftSchema.model_validate(aircraft)
    except ValidationError as exc:
        error = exc.errors()[0]
        loc = ".".join(["aircraft", *(str(p) for p in error["loc"])])
        raise InputError(f"{where}: {loc}: {_problem(exc)}") from None
    takeoff = dataclasses.replace(case.aircraft.takeoff, **aircraft.pop("takeoff"))
    new_aircraft = Aircraft(**{**aircraft, "takeoff": takeoff})
    assert isinstance(requirements, Requirements)
    changed_case = dataclasses.replace(
        case, aircraft=new_aircraft, atmosphere=atmosphere, requirements=requirements,
        overrides=(*case.overrides, *((k, float(v)) for k, v in values.items())),
    )
    # the files' cross checks hold for the changed case too (a 1e-9 kg aircraft on --set as
    # in its file)
    try:
        refuse_absurd_propulsion(changed_case)
    except InputError as exc:
        keys = ", ".join(f"{k}={v:g}" for k, v in values.items())
        raise InputError(f"{where} {keys}: {exc}") from None
    return changed_case
