"""A fit rendered: the result, the summary, the propulsion file's text, the table rows, the writing.

Everything is rendered in memory first; the propulsion file is validated against the
schema ``check`` uses before anything is written, atomically
(:func:`tuflexperf.io.files.write_files_atomically`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tuflexperf.errors import InputError
from tuflexperf.io.files import FIT_PROPULSION_HEADER
from tuflexperf.io.runs import TABLE_COLUMNS, TABLE_EXTRA_COLUMNS
from tuflexperf.models.thrust import POLY22_TERMS
from tuflexperf.reduction.electrical_fit import ElectricalFits
from tuflexperf.reduction.fit_checks import tested_range, tested_range_notes
from tuflexperf.reduction.lack_of_fit import EngineLackOfFit
from tuflexperf.reduction.poly22fit import Poly22Fit
from tuflexperf.reduction.step_runs import Point, StepRunResult, SweepRunResult, finite_or_none


@dataclass
class FitResult:
    """Everything ``fit`` found: the JSON summary and the rendered output files."""

    summary: dict[str, Any]
    propulsion_text: str
    table_text: str | None
    engines: dict[str, Poly22Fit] = field(default_factory=dict)
    power: dict[str, Poly22Fit] = field(default_factory=dict)
    step_runs: list[StepRunResult] = field(default_factory=list)
    sweep_runs: list[SweepRunResult] = field(default_factory=list)


# the table's columns that hold no value where a point has none (NaN there is empty)
_MISSING_AS_NONE = frozenset({"glauert_ratio", "voltage_v", "current_a", "electrical_power_w",
                              "ideal_power_w", "figure_of_merit", "overall_efficiency"})


def table_row(p: Point) -> dict[str, Any]:
    """A point as a row of fit's thrust table, its columns in the table's order."""
    row = {key: getattr(p, key) for key in (*TABLE_COLUMNS, *TABLE_EXTRA_COLUMNS)}
    return {key: None if key in _MISSING_AS_NONE and not math.isfinite(value) else value
            for key, value in row.items()}


def fit_summary(
    kind: str,
    input_path: Path,
    fits: dict[str, Poly22Fit],
    delay: float | None,
    speeds: dict[str, list[float]],
    lack_of_fit: dict[str, EngineLackOfFit | None] | None = None,
) -> dict[str, Any]:
    engines = []
    for name, fit in fits.items():
        engines.append(
            {
                "name": name,
                "coefficients": fit.coefficients,
                "r2": finite_or_none(fit.r2),
                "rmse_n": finite_or_none(fit.rmse_n),
                "standard_errors": {k: finite_or_none(v) for k, v in fit.standard_errors.items()},
                "n_points": fit.n_points,
                **{k: v for k, v in _uncertainty_entry(fit).items() if k != "covariance"},
                "residuals_n": [float(r) for r in fit.residuals_n],
                "full_throttle_thrust_n": {
                    f"{v:g}": float(fit.predict([1.0], [v])[0]) for v in (0.0, 30.0, 40.0)
                },
                "lack_of_fit": _lack_of_fit_entry((lack_of_fit or {}).get(name)),
            }
        )
    return {
        "input": str(input_path),
        "kind": kind,
        "engines": engines,
        "delay_s": delay,
        "lag_s": None,
        "tested_airspeed_m_s": tested_range(speeds, str(input_path)),
        "warnings": tested_range_notes(speeds),
    }


def render_propulsion(
    name: str,
    fits: dict[str, Poly22Fit],
    speeds: dict[str, list[float]],
    delay: float | None,
    density: float | None,
    source: dict[str, Any],
    lag: float | None = None,
    electrical: ElectricalFits | None = None,
    fan_area_m2: float | None = None,
    lack_of_fit: dict[str, EngineLackOfFit | None] | None = None,
    rig_uncertainty: dict[str, Any] | None = None,
) -> str:
    """The propulsion file (SPEC 4), validated against the schema ``check`` loads."""
    from tuflexperf.io.case import PropulsionSchema

    document: dict[str, Any] = {
        "name": name,
        "model": "poly22",
        "tested_airspeed_m_s": tested_range(speeds, name),
    }
    if delay is not None:
        document["delay_s"] = max(float(delay), 0.0)
    if lag is not None and math.isfinite(lag):
        document["lag_s"] = round(max(float(lag), 0.0), 6)
    if density is not None:
        document["reference_density_kg_m3"] = float(density)
    if electrical is not None and electrical.reference_voltage_v is not None:
        document["reference_voltage_v"] = electrical.reference_voltage_v
        if electrical.exponent is not None:
            document["voltage_exponent"] = round(electrical.exponent, 3)
    if fan_area_m2 is not None:
        # the campaign's fan area is the disk's: format 2 says so (docs/formats.md)
        document["format"] = 2
        document["fan_area_m2"] = float(fan_area_m2)
    document["engines"] = []
    for engine, fit in fits.items():
        entry: dict[str, Any] = {
            "name": engine,
            "coefficients": {t: fit.coefficients[t] for t in POLY22_TERMS},
            "n_points": fit.n_points,
        }
        if math.isfinite(fit.r2):
            entry["r2"] = fit.r2
        if math.isfinite(fit.rmse_n):
            entry["rmse_n"] = fit.rmse_n
        if all(math.isfinite(v) for v in fit.standard_errors.values()):
            entry["standard_errors"] = {t: fit.standard_errors[t] for t in POLY22_TERMS}
        entry.update(_uncertainty_entry(fit))
        lack = _lack_of_fit_entry((lack_of_fit or {}).get(engine))
        if lack is not None:
            entry["lack_of_fit"] = lack
        if electrical is not None and engine in electrical.windmilling:
            entry["windmilling_drag_coefficient"] = round(
                electrical.windmilling[engine].drag_coefficient, 4
            )
        if electrical is not None and engine in electrical.power:
            power = electrical.power[engine]
            entry["power"] = {
                "model": "poly22",
                "coefficients": {t: power.coefficients[t] for t in POLY22_TERMS},
                "n_points": power.n_points,
            }
            if math.isfinite(power.r2):
                entry["power"]["r2"] = power.r2
            if math.isfinite(power.rmse_n):
                entry["power"]["rmse_w"] = power.rmse_n
        document["engines"].append(entry)
    if rig_uncertainty is not None:
        document["rig_uncertainty"] = rig_uncertainty
    document["source"] = source
    header = (
        f"{FIT_PROPULSION_HEADER} by ordinary least squares, paper section 4).\n"
        "# T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2, x throttle fraction, v m/s.\n"
    )
    if electrical is not None and electrical.windmilling:
        # say where the coefficient comes from: estimated, not a datasheet's or a guess
        header += ("# windmilling_drag_coefficient: estimated from the throttle-0 holds ("
                   + ", ".join(f"{name} {fit.n_points}"
                               for name, fit in electrical.windmilling.items())
                   + "), on fan_area_m2 (the disk).\n")
    # libyaml's emitter and parser where PyYAML has them (same text, ~10x faster)
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    text = header + yaml.dump(_plain(document), Dumper=dumper, sort_keys=False,
                              allow_unicode=True)
    try:
        PropulsionSchema.model_validate(yaml.load(text, Loader=loader))  # noqa: S506 - safe
    except Exception as exc:  # noqa: BLE001 - the fit must never write a file check refuses
        from pydantic import ValidationError

        from tuflexperf.io.yamlio import validation_problems

        problems = (validation_problems(source.get("input", "the fit"), exc, PropulsionSchema)
                    if isinstance(exc, ValidationError) else [str(exc).splitlines()[0]])
        raise InputError.of([f"the fitted propulsion file would not be valid: {problem}"
                             for problem in problems]) from None
    return text


def _uncertainty_entry(fit: Poly22Fit) -> dict[str, Any]:
    """The fit's covariance, residual and leave-one-airspeed-out error (SPEC 4), if defined."""
    from tuflexperf.reduction.uncertainty import leave_one_airspeed_out

    entry: dict[str, Any] = {}
    if np.all(np.isfinite(fit.covariance)):
        entry["covariance"] = [[float(c) for c in row] for row in fit.covariance]
        entry["residual_sd_n"] = float(fit.residual_sd_n)
    if fit.points:
        left_out = leave_one_airspeed_out(*fit.points)
        extrapolation = left_out.extrapolation_sd_n
        if extrapolation is not None and math.isfinite(extrapolation):
            entry["extrapolation_sd_n"] = extrapolation
            distance = left_out.extrapolation_distance_m_s
            if distance is not None and distance > 0.0:
                entry["extrapolation_distance_m_s"] = distance
            worst = left_out.extrapolation_worst_n
            if worst is not None and math.isfinite(worst):
                entry["extrapolation_worst_n"] = worst
            bias = left_out.extrapolation_bias_n_per_m_s
            se = left_out.extrapolation_bias_se_n_per_m_s
            if bias is not None and se is not None and math.isfinite(bias + se):
                entry["extrapolation_bias_n_per_m_s"] = bias
                entry["extrapolation_bias_se_n_per_m_s"] = se
    return entry


def _lack_of_fit_entry(result: EngineLackOfFit | None) -> dict[str, Any] | None:
    """The engine's ``lack_of_fit`` block (None: not tested), NaN as None."""
    if result is None:
        return None
    return _plain(result.as_dict())


def _plain(value: Any) -> Any:
    """numpy scalars and NaN out, so the YAML is plain and loads strictly."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(float(value)) else None
    if isinstance(value, np.integer):
        return int(value)
    return value

