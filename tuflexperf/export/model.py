"""The exported thrust model: what it is, where it came from, its CasADi functions and its inverse.

Everything the exporters write (CasADi, C, JSON) is derived here from the one physics code path,
:func:`tuflexperf.models.thrust.engine_thrust_n` / :func:`~tuflexperf.models.thrust.total_thrust_n`
(the paper's poly22 surfaces, section 4), evaluated on CasADi symbols where a formula is needed.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tuflexperf.io.case import Case, PropulsionSchema, load_case
from tuflexperf.io.files import sha256_of
from tuflexperf.io.yamlio import load_model
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    Propulsion,
    delay_samples,
    density_ratio,
    engine_thrust_n,
    lag_factor,
    lag_step,
    least_throttle_reaching,
    max_model_airspeed_m_s,
    total_thrust_n,
)

#: What a user of the exported model must be told about its range of validity.
EXTRAPOLATION_WARNING = (
    "The polynomial was fitted on wind-tunnel data over the tested airspeed range only; "
    "outside it (e.g. the upper flight envelope) thrust is an extrapolation, not a measurement. "
    "Throttle outside [0, 1] is outside the model."
)


def plain_ascii(text: str) -> str:
    """``text`` as printable ASCII, every other character as its Python backslash escape
    (``é`` -> ``\\xe9``, a control byte ``\\x01`` likewise): a control byte makes the
    exported XML unreadable by JSBSim and FMPy."""
    return "".join(ch if " " <= ch <= "~" else ch.encode("unicode_escape").decode("ascii")
                   for ch in str(text))


def xml_comment(text: str) -> str:
    """Text for an XML comment (:func:`plain_ascii`), with no ``--`` (forbidden there)."""
    return re.sub(r"-{2,}", "-", plain_ascii(text))


def model_notes(prop: Any) -> list[str]:
    """What the exported functions leave to their user, said in every format (the voltage
    effect and a dead engine's drag are in no C, CasADi, FMU or JSBSim function).

    The functions give the thrust at the reference pack voltage, and a throttle-0 engine's
    ``T(0, v)``; the tool's own analyses scale by the pack voltage and give a dead engine its
    windmilling drag (SPEC 3).
    """
    notes = []
    if prop.reference_voltage_v is not None:
        notes.append(
            f"Pack voltage: the thrust here is at the reference pack voltage "
            f"{prop.reference_voltage_v!r} V; at pack voltage U it is (U / "
            f"{prop.reference_voltage_v!r})^{prop.voltage_exponent!r} times it (not applied)."
        )
    windmilling = [e for e in prop.engines if e.windmilling_drag_coefficient is not None]
    if windmilling and prop.fan_area_m2 is not None:
        notes.append(
            "A dead engine: the tool gives it a windmilling drag -Cd_wm q A_fan [N] (q = rho "
            f"v^2 / 2, A_fan = {prop.fan_area_m2!r} m^2; Cd_wm "
            + ", ".join(f"{e.name} {e.windmilling_drag_coefficient!r}" for e in windmilling)
            + "), not T(0, v) of these functions: add it for one engine out."
        )
    else:
        notes.append("A dead engine: the tool gives it min(T(0, v), 0) of its own model (drag, "
                     "never thrust).")
    return notes


@dataclass(frozen=True)
class SourceFile:
    """A file the exported model was built from, with its sha256 (provenance).

    ``label`` is what generated files print: a path relative to the case's folder (or the bare
    file name), never an absolute local path (issue 14).
    """

    role: str
    path: Path
    sha256: str
    label: str = ""


@dataclass(frozen=True)
class ExportModel:
    """A propulsion model ready for export.

    ``propulsion`` is the physics object every formula is evaluated from; ``schema`` keeps what only
    the file carries (throttle unit, per-engine fit statistics, free-form ``source`` provenance).
    """

    propulsion: Propulsion
    schema: PropulsionSchema
    files: tuple[SourceFile, ...]

    @property
    def n_engines(self) -> int:
        """Number of engines."""
        return len(self.propulsion.engines)

    @property
    def throttle_scale(self) -> float:
        """Factor from the interface throttle fraction to the coefficients' throttle variable."""
        return float(self.propulsion.engines[0].throttle_scale)

    @property
    def propulsion_sha256(self) -> str:
        """sha256 of the propulsion file."""
        return next(f.sha256 for f in self.files if f.role == "propulsion")


def load_export_model(case_path: Case | Path | str | None = None) -> ExportModel:
    """Load and validate a case (default: the shipped TU-Flex case) and describe its propulsion;
    a loaded :class:`Case` (one whose files a flag replaced) is taken as it is.

    Raises :class:`~tuflexperf.errors.InputError` (exit 2) on any bad input.
    """
    case = case_path if isinstance(case_path, Case) else load_case(case_path)
    # the Case already validated the propulsion file: use its objects, never parse it again
    schema = case.propulsion_schema
    if schema is None:  # a Case built by hand, not by load_case
        schema = load_model(case.propulsion_path, PropulsionSchema)
    case_path = case.path.resolve()
    relative = os.path.relpath(case.propulsion_path, case_path.parent)
    files = (
        SourceFile("case", case_path, sha256_of(case_path), case_path.name),
        SourceFile(
            "propulsion", case.propulsion_path, sha256_of(case.propulsion_path),
            Path(relative).as_posix(),
        ),
    )
    return ExportModel(propulsion=case.propulsion, schema=schema, files=files)


# --- CasADi functions from the physics code ---------------------------------------------------
def thrust_function(propulsion: Propulsion) -> Any:
    """CasADi ``tfp_thrust(throttle[n], airspeed_m_s, density_kg_m3) -> (thrust_n[n], total)``.

    Built by evaluating :func:`engine_thrust_n` and :func:`total_thrust_n` on SX symbols, so it
    is the package's model itself, not a re-typed polynomial. Throttle is a fraction per engine,
    thrust in N, scaled by ``rho / reference_density_kg_m3`` where the model has one (SPEC 3).
    """
    import casadi as ca

    n = len(propulsion.engines)
    throttle = ca.SX.sym("throttle", n)
    airspeed = ca.SX.sym("airspeed_m_s")
    density = ca.SX.sym("density_kg_m3")
    scale = density_ratio(propulsion, density)
    per_engine = ca.vertcat(
        *[
            engine_thrust_n(engine, throttle[i], airspeed, scale)
            for i, engine in enumerate(propulsion.engines)
        ]
    )
    total = total_thrust_n(propulsion, [throttle[i] for i in range(n)], airspeed, density)
    return ca.Function(
        "tfp_thrust",
        [throttle, airspeed, density],
        [per_engine, total],
        ["throttle", "airspeed_m_s", "density_kg_m3"],
        ["thrust_n", "total_thrust_n"],
    )


def _common_throttle_quadratic(
    propulsion: Propulsion, engine: int | None = None
) -> tuple[Any, Any, Any, Any, Any, Any]:
    """Symbols ``(x, v, rho)`` and SX ``(a, b, c0)``: thrust = ``a x^2 + b x + c0``.

    ``x`` is the throttle fraction common to all engines (``engine=None``: total thrust) or of
    engine number ``engine`` alone. The coefficients are Taylor terms at ``x = 0`` of
    :func:`total_thrust_n` / :func:`engine_thrust_n` (exact for a polynomial); a non-zero third
    derivative would mean the model is not quadratic in throttle, and the closed form wrong.
    """
    import casadi as ca

    x = ca.SX.sym("x")
    v = ca.SX.sym("airspeed_m_s")
    rho = ca.SX.sym("density_kg_m3")
    if engine is None:
        total = total_thrust_n(propulsion, x, v, rho)
    else:
        total = engine_thrust_n(
            propulsion.engines[engine], x, v, density_ratio(propulsion, rho)
        )
    first = ca.jacobian(total, x)
    second = ca.jacobian(first, x)
    third = ca.simplify(ca.jacobian(second, x))
    if not third.is_zero():
        raise ValueError("thrust is not quadratic in throttle; no closed-form inverse")

    def at_zero(expr: Any) -> Any:
        return ca.substitute(expr, x, ca.SX(0.0))

    return x, v, rho, 0.5 * at_zero(second), at_zero(first), at_zero(total)


def quadratic_coefficients(propulsion: Propulsion, engine: int | None = None) -> dict[str, float]:
    """Thrust at a throttle fraction ``x`` as a polynomial in ``x`` and ``v``.

    ``T / s = qa x^2 + (qb0 + qb1 v) x + (qc0 + qc1 v + qc2 v^2)`` with ``s`` the density
    ratio: the total at a common throttle (``engine=None``) or one engine's (its index).
    Derived from the physics code (:func:`_common_throttle_quadratic`), evaluated at ``s = 1``;
    used by the C inverses and the numpy reference.
    """
    import casadi as ca

    _, v, rho, a, b, c0 = _common_throttle_quadratic(propulsion, engine)
    reference = propulsion.reference_density_kg_m3 or 1.0
    a, b, c0 = (ca.substitute(e, rho, ca.SX(reference)) for e in (a, b, c0))
    zero = ca.SX(0.0)

    def value(expr: Any) -> float:
        return float(ca.evalf(ca.substitute(expr, v, zero)))

    return {
        "qa": value(a),
        "qb0": value(b),
        "qb1": value(ca.jacobian(b, v)),
        "qc0": value(c0),
        "qc1": value(ca.jacobian(c0, v)),
        "qc2": value(0.5 * ca.jacobian(ca.jacobian(c0, v), v)),
    }


def thrust_step_function(propulsion: Propulsion, sample_time_s: float) -> Any:
    """CasADi ``tfp_thrust_step``: one sample of the dynamic model (dead time, then spool lag).

    Inputs ``delay_state`` (``n x N`` past commands, newest in the last column, ``N`` =
    :func:`delay_samples`), ``lag_state`` (n, lagged thrust of the last sample [N]),
    ``throttle_command`` (n), ``airspeed_m_s``, ``density_kg_m3``; outputs ``thrust_n`` (n),
    ``total_thrust_n`` and the next ``delay_state`` and ``lag_state``. Per engine:
    ``u = command N samples ago``, ``T_k = a T_(k-1) + (1 - a) T_static(u, V, rho)`` with
    ``a = exp(-dt / lag_s)`` (:func:`lag_step`); ``lag_s = 0`` is the paper's pure delay.
    The same recursion as the exported C's ``tfp_step``. ``sample_time_s`` is dt [s].

    References
    ----------
    Paper section 4 (dead time); Franklin, Powell & Workman, *Digital Control of Dynamic
    Systems*, 3rd ed., section 4.3.3 (exact discrete first-order lag).
    """
    import casadi as ca

    n = len(propulsion.engines)
    steps = delay_samples(propulsion.delay_s, sample_time_s)
    factor = lag_factor(propulsion.lag_s, sample_time_s)
    width = max(steps, 1)
    delay_state = ca.SX.sym("delay_state", n, width)
    lag_state = ca.SX.sym("lag_state", n)
    command = ca.SX.sym("throttle_command", n)
    airspeed = ca.SX.sym("airspeed_m_s")
    density = ca.SX.sym("density_kg_m3")
    if steps == 0:
        delayed, next_delay = command, delay_state
    else:
        delayed = delay_state[:, 0]  # pushed N samples ago
        next_delay = ca.horzcat(delay_state[:, 1:], command)
    scale = density_ratio(propulsion, density)
    static = ca.vertcat(
        *[engine_thrust_n(e, delayed[i], airspeed, scale) for i, e in enumerate(propulsion.engines)]
    )
    thrust = lag_step(lag_state, static, factor)
    return ca.Function(
        "tfp_thrust_step",
        [delay_state, lag_state, command, airspeed, density],
        [thrust, ca.sum1(thrust), next_delay, thrust],
        ["delay_state", "lag_state", "throttle_command", "airspeed_m_s", "density_kg_m3"],
        ["thrust_n", "total_thrust_n", "delay_state_next", "lag_state_next"],
    )


#: Sample time of the exported CasADi step function (the paper's rig logged at 1 kHz).
STEP_SAMPLE_TIME_S = 0.001


def inverse_function(propulsion: Propulsion) -> Any:
    """CasADi ``tfp_throttle_for_thrust(total_thrust_n, airspeed_m_s, density_kg_m3)``.

    Outputs ``throttle`` (least common throttle fraction reaching the demand, or the throttle of
    the most thrust when none does) and ``reached`` (1/0). The quadratic's coefficients are
    derivatives of :func:`total_thrust_n` on SX symbols, so this is the physics code inverted.
    """
    import casadi as ca

    _, v, rho, a, b, c0 = _common_throttle_quadratic(propulsion)
    demand = ca.SX.sym("total_thrust_n")
    throttle, reached = least_throttle_reaching(a, b, c0 - demand)
    return ca.Function(
        "tfp_throttle_for_thrust",
        [demand, v, rho],
        [throttle, reached],
        ["total_thrust_n", "airspeed_m_s", "density_kg_m3"],
        ["throttle", "reached"],
    )


# --- JSON description ----------------------------------------------------------------------------
def model_description(model: ExportModel) -> dict[str, Any]:
    """The model as a JSON-ready dict: coefficients, units, validity, delay, density, provenance."""
    from tuflexperf import __version__ as version

    prop = model.propulsion
    engines = []
    for engine, entry in zip(prop.engines, model.schema.engines, strict=True):
        item: dict[str, Any] = {
            "name": engine.name,
            "coefficients": {t: float(engine.coefficients[t]) for t in POLY22_TERMS},
        }
        for key in ("r2", "rmse_n", "n_points"):
            if getattr(entry, key) is not None:
                item[key] = getattr(entry, key)
        if entry.standard_errors is not None:
            item["standard_errors"] = entry.standard_errors.model_dump()
        engines.append(item)
    low, high = prop.tested_airspeed_m_s
    source: Mapping[str, Any] | None = model.schema.source
    return {
        "format": "tuflexperf-thrust-model",
        "format_version": 1,
        "generator": f"tuflexperf {version}",
        "name": prop.name,
        "model": "poly22",
        "equation": (
            "thrust_n = s * (p00 + p10*x + p01*v + p20*x^2 + p11*x*v + p02*v^2), "
            "x = throttle * throttle_scale, v = airspeed_m_s, "
            "s = density_kg_m3 / reference_density_kg_m3 (1 without a reference density)"
        ),
        "throttle_unit": model.schema.throttle_unit,
        "throttle_scale": model.throttle_scale,
        "throttle_interface": "fraction in [0, 1] per engine",
        "airspeed_unit": "m/s",
        "thrust_unit": "N per engine, positive forward",
        "engines": engines,
        "reference_density_kg_m3": prop.reference_density_kg_m3,
        "delay_s": prop.delay_s,
        "lag_s": prop.lag_s,
        "casadi_step_sample_time_s": STEP_SAMPLE_TIME_S,
        "dynamics": (
            "thrust_k = a * thrust_(k-1) + (1 - a) * thrust(throttle_(k - round(delay_s / dt)), "
            "v, rho), a = exp(-dt / lag_s) (0 when lag_s = 0: the paper's pure delay)"
        ),
        # the fitted voltage effect (SPEC 3) is not in the exported functions: they give the
        # thrust at the reference pack voltage, and say so (the fit's own law is kept here)
        "pack_voltage": None if prop.reference_voltage_v is None else {
            "reference_voltage_v": prop.reference_voltage_v,
            "voltage_exponent": prop.voltage_exponent,
            "exported_at": "the reference voltage: thrust at pack voltage U is "
                           "(U / reference_voltage_v)^voltage_exponent times the equation's",
        },
        "dead_engine": {
            "windmilling_drag_coefficient": {
                e.name: e.windmilling_drag_coefficient for e in prop.engines
                if e.windmilling_drag_coefficient is not None} or None,
            "fan_area_m2": prop.fan_area_m2,
            "law": ("-windmilling_drag_coefficient * rho * v^2 / 2 * fan_area_m2 [N] where given, "
                    "else min(T(0, v), 0)"),
        },
        "notes": model_notes(prop),
        "validity": {
            "tested_airspeed_m_s": [low, high],
            "max_model_airspeed_m_s": max_model_airspeed_m_s(prop),
            "throttle": [0.0, 1.0],
            "extrapolation_warning": EXTRAPOLATION_WARNING,
        },
        "provenance": {
            "files": [
                {"role": f.role, "path": f.label, "sha256": f.sha256} for f in model.files
            ],
            "source": _json_plain(dict(source)) if source else None,
        },
    }


def _json_plain(value: Any) -> Any:
    """Free-form provenance as JSON can hold it: what YAML read as a date, a timestamp,
    bytes, a set or a NaN as text."""
    if isinstance(value, dict):
        return {str(key): _json_plain(item) for key, item in value.items()}
    if isinstance(value, (set, frozenset)):
        return sorted((_json_plain(item) for item in value), key=str)
    if isinstance(value, (list, tuple)):
        return [_json_plain(item) for item in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, bytes):
        return value.hex()
    if hasattr(value, "isoformat"):
        return value.isoformat()
    return str(value)
