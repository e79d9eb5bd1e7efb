"""How much margin each requirement has in each parameter: limit values and sensitivities.

For every requirement and every numeric parameter of the case (aircraft, atmosphere, the
endurance throttle and the obstacle height):

- **limit value**: the parameter's value at which the requirement just holds (the others
  nominal), e.g. the largest mass for the 60 m ground roll. All parameters are scanned in
  one batch (:class:`tuflexperf.analysis.batch.BatchEvaluator`) over their range, the
  crossing nearest the nominal bracketed, and all brackets refined together, each batch
  call cutting every bracket into 16 (15 points in each: a batch call costs about the same
  for one row as for hundreds), to below 1e-15 of the range (a rootfinder on the met / not
  met boundary, so a requirement that becomes not attainable binds too; trim and OEI bind
  "where the envelope ends" when their bounds cross there, and every requirement where
  ``check`` refuses the aircraft, e.g. a lift-off speed below stall). "none in range" when it
  never binds.
- **sensitivity** d(value)/d(parameter) at the nominal case, from the batch's own values
  (the same rows as every other answer, no copy of the physics): four rows per parameter
  about the nominal, all parameters in one batch call, combined by the five-point rule
  (Richardson's extrapolation of central differences). Where the deterministic value is a
  discrete choice (the grid airspeed of the highest trim throttle, the critical dead engine,
  the endurance's climb-speed grid point) the derivative is the one of the active choice: a
  stencil that spans a switch is retried narrower (:func:`sensitivities`).

References
----------
Press et al., *Numerical Recipes*, 3rd ed., 5.7 (numerical derivatives); Raymer, *Aircraft
Design*, 17.8; Anderson, *Aircraft Performance and Design*, 5.3, 6.7.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.batch import present_requirements
from tuflexperf.analysis.batch_readings import readings_evaluator
from tuflexperf.analysis.evaluators import evaluator_for
from tuflexperf.errors import InputError
from tuflexperf.io.case import Case
from tuflexperf.io.dotted import numeric_keys

_SCAN_POINTS = 65
_SECTIONS = 16
"""Each refinement call cuts every bracket into this many parts (points inside: one less)."""
_REFINEMENTS = 12
"""Refinement calls: a 1/64 scan cell shrinks by 16**12 = 2**48, as 48 bisections would."""
# Ranges where "0.5x to 2x the nominal" does not fit [low, high] in the key's unit.
_RANGES: dict[str, tuple[float, float]] = {
    "atmosphere.altitude_m": (-500.0, 5000.0),
    "atmosphere.temperature_offset_k": (-50.0, 50.0),
    "aircraft.takeoff.rotation_time_s": (0.0, 5.0),
}
_UPPER: dict[str, float] = {
    "aircraft.takeoff.rolling_friction": 1.0,
    "requirements.endurance.throttle": 1.0,
    "battery.cutoff_voltage_per_cell_v": 4.2,
    "battery.mission.landing_reserve_fraction": 0.95,
    "battery.mission.pattern_altitude_m": 5000.0,
}
_LOWER: dict[str, float] = {
    "aircraft.takeoff.liftoff_speed_factor": 1.0,
    "aircraft.takeoff.transition_load_factor": 1.01,
    "battery.cutoff_voltage_per_cell_v": 2.5,
}
_EXTRA_KEYS = ("requirements.endurance.throttle", "requirements.takeoff.obstacle_height_m")


def margin_parameters(case: Case) -> dict[str, float]:
    """The parameters ``margins`` varies, with their nominal values (SI units of their keys)."""
    keys = numeric_keys(case)
    return {k: v for k, v in keys.items()
            if k.startswith(("aircraft.", "atmosphere.", "battery.")) or k in _EXTRA_KEYS}


def parameter_range(key: str, nominal: float) -> tuple[float, float]:
    """Search range [unit of the key]: 0.5x to 2x the nominal, or the table's for offsets."""
    if key in _RANGES:
        low, high = _RANGES[key]
        return min(low, nominal), max(high, nominal)
    if nominal == 0.0:
        return 0.0, 1.0
    low, high = sorted((0.5 * nominal, 2.0 * nominal))
    low = max(low, _LOWER.get(key, -math.inf))
    high = min(high, _UPPER.get(key, math.inf))
    return low, high


@dataclass(frozen=True)
class Margin:
    """One requirement against one parameter (SPEC 5 ``margins`` keys, plus context)."""

    requirement: str
    parameter: str
    value: float  # the parameter's nominal value
    limit_value: float | None  # where the requirement just holds; None: none in range
    sensitivity: float | None  # d(requirement value)/d(parameter) at the nominal
    unit: str  # the requirement's unit
    search_range: tuple[float, float]
    binds: str  # "limit", "not attainable", "envelope ends", "aircraft refused", "none in range"
    # the requirement's answer at the limit value flies the thrust model beyond its tested
    # airspeeds (None: no limit value); at the nominal: ``extrapolated_at_nominal``
    extrapolated: bool | None = None
    extrapolated_at_nominal: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {
            "requirement": self.requirement,
            "parameter": self.parameter,
            "value": self.value,
            "limit_value": self.limit_value,
            "sensitivity": self.sensitivity,
            "unit": self.unit,
            "search_range": list(self.search_range),
            "binds": self.binds,
            "extrapolated": self.extrapolated,
        }


def _rows(nominal: dict[str, float], keys: list[str], columns: list[np.ndarray]) -> dict:
    """Batch values: row block ``i`` varies ``keys[i]`` over ``columns[i]``, others nominal."""
    sizes = [c.size for c in columns]
    total = sum(sizes)
    values = {k: np.full(total, nominal[k]) for k in keys}
    start = 0
    for key, column in zip(keys, columns, strict=True):
        values[key][start:start + column.size] = column
        start += column.size
    return values


def limit_values(case: Case, parameters: dict[str, float] | None = None
                 ) -> dict[tuple[str, str], tuple[float | None, str, tuple[float, float]]]:
    """(requirement, parameter) -> (limit value, how it binds, search range); see module doc."""
    nominal = parameters or margin_parameters(case)
    keys = list(nominal)
    # one per case (its candidates once), judged on every reading of disputed evidence: a
    # limit value is where the requirement just holds on the worse reading
    evaluator = readings_evaluator(case)
    ranges = {k: parameter_range(k, nominal[k]) for k in keys}
    with np.errstate(over="ignore", invalid="ignore"):  # 2 x 1e308 is inf: not attainable
        grids = [np.unique(np.concatenate([np.linspace(*ranges[k], _SCAN_POINTS),
                                           [nominal[k]]])) for k in keys]
    scan = evaluator.evaluate(_rows(nominal, keys, grids))
    # an aircraft check refuses (a lift-off speed below a heavier aircraft's stall) is where
    # the search ends: no requirement holds there (OEI "held" up to 51 kg where check refuses
    # the case beyond 36.6 kg)
    refused = scan.refused
    names = list(scan.values)
    out: dict[tuple[str, str], tuple[float | None, str, tuple[float, float]]] = {}
    brackets: list[tuple[str, str, float, float, bool]] = []  # (req, key, lo, hi, met_at_lo)
    start = 0
    for key, grid in zip(keys, grids, strict=True):
        part = slice(start, start + grid.size)
        start += grid.size
        for name in names:
            met = scan.met(name)[part] & ~refused[part]
            changes = np.nonzero(met[1:] != met[:-1])[0]
            if changes.size == 0:
                out[(name, key)] = (None, "none in range", ranges[key])
                continue
            # the crossing nearest the nominal value
            distance = np.minimum(np.abs(grid[changes] - nominal[key]),
                                  np.abs(grid[changes + 1] - nominal[key]))
            j = int(changes[np.argmin(distance)])
            brackets.append((name, key, grid[j], grid[j + 1], bool(met[j])))
    if brackets:
        low = np.array([b[2] for b in brackets])
        high = np.array([b[3] for b in brackets])
        met_low = np.array([b[4] for b in brackets])
        inside = np.arange(1, _SECTIONS) / _SECTIONS
        # every bracket's inner points in one batch: row i * 15 + j is point j of bracket i
        rows = np.repeat(np.arange(len(brackets)), inside.size)
        row_brackets = [brackets[i] for i in rows]
        row_names = np.array([b[0] for b in row_brackets])
        at = np.arange(len(brackets))
        for _ in range(_REFINEMENTS):
            points = low[:, None] + (high - low)[:, None] * inside[None, :]
            result = evaluator.evaluate(_rows_pairs(nominal, row_brackets, points.ravel()))
            met = np.zeros(rows.size, dtype=bool)
            for name in set(row_names):  # each requirement's verdicts once, not once a row
                mine = row_names == name
                met[mine] = result.met(name)[mine] & ~result.refused[mine]
            changed = met.reshape(points.shape) != met_low[:, None]
            # the first point past the crossing (the high end when none is): the crossing
            # lies between it and the point before it, as a bisection would keep it
            first = np.where(changed.any(axis=1), np.argmax(changed, axis=1), inside.size)
            edges = np.column_stack([low, points, high])
            low, high = edges[at, first], edges[at, first + 1]
        # how it binds is judged at the bracket's failing end, the first value past the
        # limit (a midpoint of a bracket a float wide would land on either side)
        failing = np.where(met_low, high, low)
        edge = evaluator.evaluate(_rows_pairs(nominal, brackets, failing))
        # past the bracket the envelope's bounds may cross (an EAS bound at altitude): trim
        # and OEI end there with the envelope, as the single case does (bad input), not fail
        flies = {r.name for r in evaluator.requirements if r.block in ("envelope", "oei")}
        for i, (name, key, _, _, _) in enumerate(brackets):
            root = 0.5 * (low[i] + high[i])
            binds = "limit" if np.isfinite(edge.values[name][i]) else "not attainable"
            if name in flies and edge.without_envelope[i]:
                binds = "envelope ends"
            if edge.refused[i]:
                binds = "aircraft refused"
            out[(name, key)] = (float(root), binds, ranges[key])
    return out


def _rows_pairs(nominal: dict[str, float], brackets: list, column: np.ndarray) -> dict:
    """Row ``i`` sets ``brackets[i]``'s parameter to ``column[i]``, the others nominal."""
    keys = sorted({b[1] for b in brackets})
    values = {k: np.full(len(brackets), nominal[k]) for k in keys}
    for i, b in enumerate(brackets):
        values[b[1]][i] = column[i]
    return values


_STEP = 1e-3
"""A derivative's first step relative to the parameter's nominal (its range's width at 0):
the five-point rule's error, about (step/nominal)^4, sits below the batch's rounding."""
_SHRINK = 16.0
"""Each refinement round divides the step by this: a stencil that spans a discrete switch
(the endurance's climb-speed grid point) rarely spans one 16 times narrower."""
_ROUNDS = 4
_AGREE = 1e-5
"""Smooth across the stencil, the forward and backward estimates agree to this relative (their
O(step^2) errors are equal; measured at most 1.4e-9 apart on the shipped and test cases); a
switch inside the stencil parts them by 7e-4 or more."""


def _stencil(value: float, step: float, low: float, high: float) -> tuple[np.ndarray, str]:
    """Four offsets [key unit] about ``value``: central (-h, -h/2, h/2, h) inside the search
    range, else one-sided into it (h/4 to h) where the nominal sits at a range end."""
    if value - step >= low and value + step <= high:
        return step * np.array([-1.0, -0.5, 0.5, 1.0]), "central"
    quarters = step * np.array([0.25, 0.5, 0.75, 1.0])
    return (quarters, "forward") if value + step <= high else (-quarters, "backward")


def _slope(f0: float, f: np.ndarray, step: float, shape: str, scale: float,
           last: bool) -> float | None:
    """The derivative from a stencil's values (``f0`` the nominal's), or None where the
    stencil cannot say yet (a later round retries it narrower); NaN: none at the nominal."""
    finite = np.isfinite(f)
    if not np.isfinite(f0):
        return math.nan  # not attainable at the nominal: no derivative, as before
    if shape != "central":  # at a range end: no other side to check smoothness against
        if not finite.all():
            return math.nan if last else None
        d = step / 4.0 if shape == "forward" else -step / 4.0
        # the five-point one-sided rule on the nominal and four points a quarter step apart
        return float((-25 * f0 + 48 * f[0] - 36 * f[1] + 16 * f[2] - 3 * f[3]) / (12 * d))
    minus, half_minus, half_plus, plus = f
    # Richardson on each side alone (O(h^2)) and on both, the five-point central rule (O(h^4))
    forward = (4 * (half_plus - f0) - (plus - f0)) / step
    backward = (4 * (f0 - half_minus) - (f0 - minus)) / step
    if finite.all():
        central = (8 * (half_plus - half_minus) - (plus - minus)) / (6 * step)
        if abs(forward - backward) <= _AGREE * (abs(central) + abs(f0) / scale):
            return float(central)
    if not last:
        return None
    # at a switch or an edge of attainability however narrow: the smoother finite side, the
    # branch the nominal sits on
    sides = [(abs((plus - f0) / step - 2 * (half_plus - f0) / step), forward),
             (abs((f0 - minus) / step - 2 * (f0 - half_minus) / step), backward)]
    sides = [s for s in sides if np.isfinite(s[1])]
    return float(min(sides)[1]) if sides else math.nan


def sensitivities(case: Case, keys: list[str]) -> dict[str, dict[str, float | None]]:
    """d(requirement value)/d(parameter) at the nominal case, from the batch itself.

    Each parameter gets four rows about its nominal (others nominal), all parameters in one
    batch call with the nominal row; the five-point rule (Richardson's extrapolation of
    central differences at steps h and h/2) gives the derivative. Where the value is not
    smooth across the stencil (the one-sided estimates disagree, or a row is not
    attainable), the parameter is retried with a 16 times narrower stencil, at most
    ``_ROUNDS`` calls in all; the last keeps the side the nominal sits on.

    Parameters
    ----------
    case : Case
        The nominal case, as given (its first reading of disputed evidence).
    keys : list of str
        Dotted parameter keys (units as the keys name them).

    Returns
    -------
    dict
        requirement name -> parameter -> derivative [requirement unit / parameter unit];
        None where the requirement is not attainable at the nominal case.

    References
    ----------
    Press et al., *Numerical Recipes*, 3rd ed., 5.7 (numerical derivatives, Richardson's
    extrapolation); Abramowitz & Stegun 25.3.6 (the five-point rule).
    """
    evaluator = evaluator_for(case)
    nominal = numeric_keys(case)
    ranges = {k: parameter_range(k, nominal[k]) for k in keys}
    # a zero nominal scales with its search range (the altitude's 5.5 km, not 1 m)
    scales = {k: abs(nominal[k]) or (ranges[k][1] - ranges[k][0]) for k in keys}
    steps = {k: _STEP * scales[k] for k in keys}
    names = [r.name for r in evaluator.requirements]
    out: dict[str, dict[str, float | None]] = {n: {} for n in names}
    pending = list(keys)
    for round_ in range(_ROUNDS):
        last = round_ == _ROUNDS - 1
        stencils = {k: _stencil(nominal[k], steps[k], *ranges[k]) for k in pending}
        # row 0 the nominal, then four rows per pending key
        values = {k: np.full(1 + 4 * len(pending), nominal[k]) for k in pending}
        for i, key in enumerate(pending):
            values[key][1 + 4 * i:5 + 4 * i] += stencils[key][0]
        result = evaluator.evaluate(values).values
        retry = []
        for i, key in enumerate(pending):
            shape = stencils[key][1]
            for name in names:
                if key in out[name]:
                    continue
                rows = result[name]
                slope = _slope(float(rows[0]), rows[1 + 4 * i:5 + 4 * i], steps[key], shape,
                               scales[key], last)
                if slope is not None:
                    out[name][key] = slope if math.isfinite(slope) else None
            if any(key not in out[name] for name in names):
                retry.append(key)
        pending = retry
        if not pending:
            break
        for key in pending:
            steps[key] /= _SHRINK
    return {name: {k: out[name][k] for k in keys} for name in names}


def solve_margins(case: Case) -> list[Margin]:
    """Every requirement against every parameter: limit value and sensitivity.

    References
    ----------
    Press et al., *Numerical Recipes*, 3rd ed., 5.7 (numerical derivatives) and 9.1
    (bracketing and bisection).
    """
    requirements = present_requirements(case)
    if not requirements:
        raise InputError(f"{case.path}: requirements: the case states none; nothing to do")
    nominal = margin_parameters(case)
    limits = limit_values(case, nominal)
    slopes = sensitivities(case, list(nominal))
    # where each answer extrapolates the thrust model, in one batch: every finite limit
    # value with the other parameters nominal, then the nominal itself (its first key set to
    # its own value)
    found = [(name, key, limit) for (name, key), (limit, _, _) in limits.items()
             if limit is not None]
    first = next(iter(nominal))
    at = evaluator_for(case).evaluate(_rows_pairs(
        nominal, [(None, key) for _, key, _ in found] + [(None, first)],
        np.array([limit for *_, limit in found] + [nominal[first]]))).extrapolated
    beyond = {(name, key): bool(at[name][i]) for i, (name, key, _) in enumerate(found)}
    margins = []
    for requirement in requirements:
        for key, value in nominal.items():
            limit, binds, search = limits[(requirement.name, key)]
            slope = slopes.get(requirement.name, {}).get(key)
            margins.append(Margin(
                requirement=requirement.name,
                parameter=key,
                value=value,
                limit_value=limit,
                sensitivity=slope,
                unit=requirement.unit,
                search_range=search,
                binds=binds,
                extrapolated=beyond.get((requirement.name, key)),
                extrapolated_at_nominal=bool(at[requirement.name][-1]),
            ))
    return margins


def extrapolation_notes(margins: list[Margin], tested_m_s: tuple[float, float]) -> list[str]:
    """One line per requirement whose answer extrapolates the thrust model at the nominal or
    at a limit value (SPEC: extrapolation is said)."""
    notes = []
    for name in dict.fromkeys(m.requirement for m in margins):
        rows = [m for m in margins if m.requirement == name]
        limits = [m for m in rows if m.extrapolated is not None]
        beyond = [m.parameter for m in limits if m.extrapolated]
        where = []
        if rows[0].extrapolated_at_nominal:
            where.append("the nominal")
        if beyond:
            where.append("every limit value" if len(beyond) == len(limits) else
                         "the limit values of " + ", ".join(beyond))
        if where:
            notes.append(f"{name}: thrust model extrapolated beyond its tested "
                         f"{tested_m_s[0]:g}-{tested_m_s[1]:g} m/s at {' and '.join(where)}")
    return notes



@dataclass(frozen=True)
class TornadoBar:
    """A requirement's value with one parameter moved down and up (others nominal)."""

    parameter: str
    low_parameter: float
    high_parameter: float
    value_at_low: float | None  # None: not attainable there
    value_at_high: float | None

    @property
    def swing(self) -> float:
        """The bar's length [requirement unit] (inf when an end is not attainable)."""
        if self.value_at_low is None or self.value_at_high is None:
            return math.inf
        return abs(self.value_at_high - self.value_at_low)


@dataclass(frozen=True)
class Tornado:
    """Data of a tornado figure for one requirement: bars sorted longest first."""

    requirement: str
    unit: str
    nominal_value: float | None
    limit: float
    relative_change: float
    bars: tuple[TornadoBar, ...]


def tornado(case: Case, requirement: str, relative_change: float = 0.1) -> Tornado:
    """Each parameter moved by -/+ ``relative_change`` of its nominal (the temperature offset
    by -/+ 10 K, the altitude by -/+ 500 m; never below its physical bound); one batch.

    Returns
    -------
    Tornado
        For the report's tornado figure (``report/`` draws it; nothing is computed there).
    """
    evaluator = readings_evaluator(case)  # the worse reading's values, as limit_values
    nominal = margin_parameters(case)
    offsets = {"atmosphere.temperature_offset_k": 10.0, "atmosphere.altitude_m": 500.0}
    keys = [k for k in nominal if nominal[k] != 0.0 or k in offsets]
    ends = []
    for key in keys:
        step = offsets.get(key, relative_change * abs(nominal[key]))
        low, high = nominal[key] - step, nominal[key] + step
        if not key.startswith("atmosphere."):  # physical quantities keep their sign
            low = max(low, _LOWER.get(key, 0.0))
        high = min(high, _UPPER.get(key, math.inf))
        ends.append(np.array([low, high]))
    result = evaluator.evaluate(_rows(nominal, keys, ends))
    if requirement not in result.values:
        raise InputError(f"{case.path}: requirements: no requirement named {requirement!r}")
    values = result.values[requirement]
    bars = []
    for i, key in enumerate(keys):
        low_v, high_v = values[2 * i], values[2 * i + 1]
        bars.append(TornadoBar(key, float(ends[i][0]), float(ends[i][1]),
                               float(low_v) if np.isfinite(low_v) else None,
                               float(high_v) if np.isfinite(high_v) else None))
    bars = [b for b in bars if b.swing > 0.0]
    bars.sort(key=lambda b: b.swing, reverse=True)
    base = evaluator.evaluate().values[requirement][0]
    limit = float(result.limits[requirement][0])
    unit = next(r.unit for r in present_requirements(case) if r.name == requirement)
    return Tornado(requirement, unit, float(base) if np.isfinite(base) else None, limit,
                   relative_change, tuple(bars))
