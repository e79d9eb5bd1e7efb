"""Every requirement for a batch of parameter sets at once (samples, sweep grids, margins).

The batch is vectorised, never a loop of single-case analyses: the model functions of
:mod:`tuflexperf.models` are called once with array-valued aircraft, engines and
densities (shape ``(B, 1)`` against airspeed nodes ``(1, K)``), and each analysis's
iteration is replaced by its closed form or a fixed-node rule:

- **take-off**: ``s = int_0^V_LO m V / F(V) dV`` and ``t = int m / F dV`` by composite
  Gauss-Legendre quadrature, split where the friction clamp ``max(W - L, 0)`` kinks;
  "never reaches lift-off" where ``F <= 0`` on the check grid (as :mod:`.takeoff`);
- **trim / OEI**: the least throttle per envelope airspeed is the least root of the
  thrust excess, a quadratic in throttle (poly22), by
  :func:`tuflexperf.models.thrust.least_throttle_reaching`;
- **endurance**: the same steps as :class:`tuflexperf.analysis.endurance.EnduranceModel`
  (launch charge by the same RK4, level-flight speed, cut-off charge, Gauss-Legendre
  discharge time) with bisection vectorised over the batch instead of Newton per case; a
  ``launch: catapult`` aircraft starts airborne at its release speed (no roll).

Speed without a smaller problem: the roll's net force is a quadratic in airspeed between its
kinks, so three evaluations per piece replace one per node (checked by a fourth); trim and
OEI look first at the airspeeds beside the nominal case's extremes and verify every row
against the whole grid (rows the check rejects are solved at every airspeed); sampled thrust
coefficients meet the grid's airspeeds in one matrix product. Each shortcut is held to the
plain way in ``tests/verification/test_batch_shortcuts.py``.

A not-attainable parameter set gives NaN, never a dropped row. The thrust model may be
perturbed per sample: coefficients ``(E, B, 6)`` and an extrapolation error ``(E, B)``
[N] added beyond the tested airspeed range (SPEC 4, uncertainty block).
``tests/verification/test_batch_equals_deterministic.py`` holds this module to the
deterministic analyses.

References
----------
Raymer, *Aircraft Design*, 17.8 (ground roll); Anderson, *Aircraft Performance and
Design*, 5.3 (level flight); Abramowitz & Stegun 25.4.29 (Gauss-Legendre).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.airborne import obstacle_height_of
from tuflexperf.analysis.attainable import stall_margin_of
from tuflexperf.analysis.level_flight import airspeed_grid, airspeed_grids
from tuflexperf.analysis.pack_limits import (
    least_throttle_where,
    operating_point,
    pack_rows,
    pack_side,
    power_limit_w,
    sagging_packs,
    within_limits,
)
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    EAS_REFERENCE_DENSITY_KG_M3,
    MAX_AIRSPEED_M_S,
    Aircraft,
    catapult_energy_shortfall,
    climb_gradient,
    ground_roll_net_force_n,
    level_flight_drag_n,
    liftoff_speed_m_s,
    obstacle_distances_m,
    stall_speed_m_s,
    transition_beyond_cl_max,
    transition_radius_m,
    transition_speed_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.powertrain import beyond_jet_velocity
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    Propulsion,
    density_ratio,
    engine_thrust_n,
    least_throttle_reaching,
    outside_tested_range,
    outside_tested_span,
    poly22,
    total_thrust_n,
    windmilling_thrust_n,
)

Array = NDArray[np.float64]
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(16)
_PANELS = 4  # composite rule: 4 panels x 16 nodes per smooth piece
_CANDIDATE_HALF_WIDTH = 3  # grid points each side of the nominal's extreme tried first
# the roll's quadrature nodes and weights on [0, 1] (composite, as _integrate places them)


def _unit_rule(panels: int) -> tuple[Array, Array]:
    """Composite Gauss-Legendre nodes and weights on [0, 1], ``(1, panels x 16)`` each."""
    nodes = ((np.arange(panels)[:, None] + 0.5 * (_GL_NODES + 1.0)) / panels).reshape(1, -1)
    return nodes, np.tile(_GL_WEIGHTS, panels)[None, :] * 0.5 / panels


_ROLL_PROBES = np.array([0.25, 0.5, 0.75, 0.9])  # three fix a piece's quadratic, one checks it
_UNIT = {t: {u: float(u == t) for u in POLY22_TERMS} for t in POLY22_TERMS}  # basis picks
_HISTORY_POINTS = 101  # as analysis.ground_roll.HISTORY_POINTS: the time history
_CHECK_POINTS = 2001  # as analysis.ground_roll._CHECK_POINTS: where the net force must be > 0
_STEEP_FORCE_SHARE = 0.05  # a least net force below this share of the greatest: a peak
_FINE_PANELS = 256
_PEAK_PANELS = 16  # Gauss panels on each monotone half of a piece, in the stretched variable
# the roll's quadrature on each piece's own coordinate (as _integrate places its nodes)
_ROLL_RULE, _PEAK_RULE = _unit_rule(_PANELS), _unit_rule(_PEAK_PANELS)


def roll_integrals_near_a_peak(low: Array, width: Array, c0: Array, c1: Array, c2: Array,
                               mass: Array, rule: tuple[Array, Array] = _PEAK_RULE
                               ) -> tuple[Array, Array]:
    """``integral m V / F dV`` [m] and ``integral m / F dV`` [s] per row over one piece of
    airspeed ``V = low + width (s + 1/2)``, ``s`` in [-1/2, 1/2], whose net force is the
    positive quadratic ``F = c0 + c1 s + c2 s^2`` [N] however nearly it vanishes.

    Where ``F`` all but vanishes ``1/F`` is a spike as narrow as ``F_min / |F'|`` (or
    ``sqrt(F_min / c2)`` at a vertex): fixed nodes miss it (4,096 of them gave a roll 40 %
    short; outside audit). Each half of the piece on which ``F`` is monotone (split at the
    vertex) is stretched about its least force ``F*`` at ``s*``, ``s = s* +- w sinh(t)``
    with ``w`` the spike's width, so the integrand in ``t`` is smooth and bounded (``w /
    (F* cosh t)`` for the vertex's Lorentzian) and a composite Gauss rule on ``t`` is exact
    to ~1e-12 for any ``F* > 0``; where nothing vanishes ``w`` is the half's length and
    the stretch is mild.

    References
    ----------
    Davis & Rabinowitz, *Methods of Numerical Integration*, 2nd ed., 3.9 (a change of
    variable that removes a near-singularity).
    """
    u, weights = rule
    distance = np.zeros(np.shape(c0)[0])
    time = np.zeros(np.shape(c0)[0])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        vertex = -c1 / (2.0 * c2)
    split = np.where(np.isfinite(vertex) & (np.abs(vertex) < 0.5), vertex, 0.0)
    for a, b in ((np.full_like(split, -0.5), split), (split, np.full_like(split, 0.5))):
        f_a, f_b = c0 + a * (c1 + a * c2), c0 + b * (c1 + b * c2)
        at_a = f_a <= f_b
        s_least = np.where(at_a, a, b)
        f_least = np.minimum(f_a, f_b)
        slope = c1 + 2.0 * c2 * s_least
        length = b - a
        with np.errstate(divide="ignore", invalid="ignore"):
            width_of_spike = f_least / np.maximum(
                np.abs(slope), np.sqrt(np.abs(f_least * c2)))
        stretch = np.maximum(np.minimum(np.nan_to_num(width_of_spike, nan=np.inf), length),
                             1e-300)
        span = np.arcsinh(length / stretch)
        t = span * u
        offset = np.where(at_a, 1.0, -1.0) * stretch * np.sinh(t)  # s - s*
        # about s*, where the force is least: its cancellation is not repeated node by node
        force = f_least + offset * (slope + offset * c2)
        ds = stretch * np.cosh(t) * span * weights
        speed = low + width * (s_least + offset + 0.5)
        with np.errstate(divide="ignore", invalid="ignore"):
            over = ds * width * mass / force
            distance = distance + np.sum(over * speed, axis=1)
            time = time + np.sum(over, axis=1)
    return distance, time


@dataclass(frozen=True)
class Requirement:
    """One requirement of the case: its name, unit, kind ("max"/"min") and block."""

    name: str
    unit: str
    kind: str
    block: str
    limit_key: str


REQUIREMENTS: tuple[Requirement, ...] = (
    Requirement("takeoff_ground_roll", "m", "max", "takeoff", "max_ground_roll_m"),
    Requirement("takeoff_distance_to_obstacle", "m", "max", "takeoff",
                "max_distance_to_obstacle_m"),
    Requirement("trim_throttle_max", "fraction", "max", "envelope", "max_trim_throttle"),
    Requirement("oei_min_throttle", "fraction", "max", "oei", "max_throttle"),
    Requirement("flight_endurance", "min", "min", "endurance", "min_flight_time_min"),
)


def present_requirements(case: Case) -> list[Requirement]:
    """The case's requirements, in the order ``check`` reports them."""
    out = []
    for r in REQUIREMENTS:
        block = getattr(case.requirements, r.block)
        if block is not None and getattr(block, r.limit_key) is not None:
            out.append(r)
    return out


@dataclass(frozen=True)
class BatchResult:
    """Per requirement: values (NaN = not attainable) and limits, each of shape ``(B,)``."""

    values: dict[str, Array]
    limits: dict[str, Array]
    kinds: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    # rows the single case refuses as bad input (BatchEvaluator.rows_refused), and rows whose
    # envelope bounds cross (trim and OEI are NaN there): each consumer says what they mean
    refused: NDArray[np.bool_] | None = None
    without_envelope: NDArray[np.bool_] | None = None
    # rows whose answer flies the thrust model outside its tested airspeeds, as the single
    # case's `extrapolated` (SPEC: extrapolation is said; a sweep said nothing)
    extrapolated: dict[str, NDArray[np.bool_]] = field(default_factory=dict)

    def met(self, name: str) -> NDArray[np.bool_]:
        """Met per sample, by the verdict rule of :mod:`tuflexperf.analysis.requirements`."""
        from tuflexperf.analysis.verdict import requirement_met

        return requirement_met(self.values[name], self.limits[name], self.kinds[name])


def _within(candidates: Array | None, grid: Array) -> Array | None:
    """The nominal grid's candidate indices that exist on ``grid`` (rows of its own bounds
    may be shorter); only where to look first, so any index is as exact as another."""
    if candidates is None:
        return None
    return np.unique(np.minimum(candidates, grid.shape[1] - 1))


def _column(values: Mapping[str, Array], key: str, nominal: Any, size: int) -> Any:
    """The batch's values of ``key`` as ``(B, 1)``, or the nominal when it does not vary."""
    if key in values:
        return np.asarray(values[key], dtype=float).reshape(size, 1)
    return nominal


class BatchEvaluator:
    """All requirements of one case for batches of parameter values (build once per case).

    Parameters
    ----------
    case : Case
        The nominal case; its keys not in a batch keep their nominal values.
    """

    def __init__(self, case: Case) -> None:
        self.case = case
        self.requirements = present_requirements(case)
        if any(r.block == "oei" for r in self.requirements):
            # as solve_oei refuses it (the sweep tabulated "not attainable" for every point)
            from tuflexperf.analysis.oei import refuse_one_engine

            refuse_one_engine(case)
        self._endurance: Any = None
        if case.requirements.endurance is not None:
            from tuflexperf.analysis.batch_endurance import battery_side

            self._endurance = battery_side(case)
        # trim and OEI are flown on the packs as the single case flies them (pack_limits)
        self._packs: Any = None
        if self.requirements:
            self._packs = pack_side(case)

    # -- the batch's model objects -----------------------------------------------------------
    def _aircraft(self, values: Mapping[str, Array], size: int) -> Aircraft:
        base = self.case.aircraft
        top = {f.name: _column(values, f"aircraft.{f.name}", getattr(base, f.name), size)
               for f in dataclasses.fields(base)
               if f.name not in ("name", "takeoff", "launch")}
        takeoff = dataclasses.replace(
            base.takeoff,
            **{f.name: _column(values, f"aircraft.takeoff.{f.name}",
                               getattr(base.takeoff, f.name), size)
               for f in dataclasses.fields(base.takeoff)},
        )
        return dataclasses.replace(base, **top, takeoff=takeoff)

    def _density(self, values: Mapping[str, Array], size: int) -> Any:
        if not any(key.startswith("atmosphere.") for key in values):
            return self.case.density_kg_m3
        atmosphere = self.case.atmosphere
        altitude = _column(values, "atmosphere.altitude_m", atmosphere.altitude_m, size)
        offset = _column(values, "atmosphere.temperature_offset_k",
                         atmosphere.temperature_offset_k, size)
        return np.asarray(isa_density_kg_m3(altitude * np.ones((size, 1)), offset), dtype=float)

    def _propulsion(self, coefficients: Array | None) -> Propulsion:
        base = self.case.propulsion
        if coefficients is None:
            return base
        engines = tuple(
            dataclasses.replace(
                engine,
                coefficients={t: coefficients[j, :, i][:, None]
                              for i, t in enumerate(POLY22_TERMS)},
            )
            for j, engine in enumerate(base.engines)
        )
        return dataclasses.replace(base, engines=engines)

    def _limit(self, values: Mapping[str, Array], requirement: Requirement, size: int) -> Array:
        block = getattr(self.case.requirements, requirement.block)
        key = f"requirements.{requirement.block}.{requirement.limit_key}"  # a dotted key
        nominal = float(getattr(block, requirement.limit_key))
        column = np.asarray(_column(values, key, nominal, size), dtype=float)
        return np.broadcast_to(column.reshape(-1), (size,)).copy()

    # -- evaluation ---------------------------------------------------------------------------
    def evaluate(
        self,
        values: Mapping[str, Array] | None = None,
        size: int | None = None,
        coefficients: Array | None = None,
        extrapolation_n: Array | None = None,
    ) -> BatchResult:
        """Every requirement's value for each of ``B`` parameter sets.

        Parameters
        ----------
        values : mapping of dotted key to array ``(B,)``
            Parameter values (SI units as the key names); absent keys stay nominal.
        size : int, optional
            ``B``; inferred from ``values`` or ``coefficients`` when omitted.
        coefficients : array ``(E, B, 6)``, optional
            Thrust coefficients per engine and sample (POLY22_TERMS order, the file's units).
        extrapolation_n : array ``(E, B)``, optional
            Thrust error [N] per engine and sample added beyond the tested airspeed range.

        Returns
        -------
        BatchResult
            NaN where a requirement is not attainable for that parameter set.
        """
        # a row far outside the models (a pack drained far below its cut-off, a 1e300 kg
        # mass) may overflow on its way to NaN, "not attainable": numpy's warnings about it
        # would only clutter stderr (margins and sweeps; samples said so already)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return self._evaluate(values, size, coefficients, extrapolation_n)

    def _evaluate(self, values: Mapping[str, Array] | None, size: int | None,
                  coefficients: Array | None, extrapolation_n: Array | None) -> BatchResult:
        values = dict(values or {})
        if size is None:
            if values:
                size = int(np.asarray(next(iter(values.values()))).size)
            elif coefficients is not None:
                size = int(coefficients.shape[1])
            else:
                size = 1
        model = _Model(
            aircraft=self._aircraft(values, size),
            propulsion=self._propulsion(coefficients),
            density=self._density(values, size),
            extrapolation_n=extrapolation_n,
            size=size,
            stall_margin=_column(values, "requirements.envelope.stall_margin",
                                 stall_margin_of(self.case), size),
        )
        out: dict[str, Array] = {}
        limits: dict[str, Array] = {}
        roll: tuple[Array, Array, Array, Array] | None = None
        unflown = np.zeros(size, dtype=bool)
        if any(r.block in ("envelope", "oei") for r in self.requirements):
            grid, unflown = self._grids(values, model.density, size)  # trim's and OEI's
        catapult = self.case.aircraft.launch == "catapult"
        height = _column(values, "requirements.takeoff.obstacle_height_m",
                         obstacle_height_of(self.case), size)
        battery = (self._battery_rows(values, size)
                   if self._packs is not None or self._endurance is not None else {})

        sagging = self._packs is not None and sagging_packs(self.case)

        def launched() -> tuple[Array, Array, Array, Array]:
            # a catapult's "roll" is its release: no runway (SPEC 4), as solve_takeoff; the
            # packs give full throttle over it (pack_limits.takeoff_beyond_battery)
            found = model.catapult_release() if catapult else model.ground_roll()
            if sagging:  # rolled on the packs' loaded voltage, as solve_takeoff rolls
                from tuflexperf.analysis import batch_takeoff_packs as packs_takeoff

                rows = pack_rows(self._packs.battery, battery)
                if catapult:
                    model.release = packs_takeoff.release_on_packs(model, self._packs, rows)
                    model.packs_roll = packs_takeoff.RollOnPacks(
                        *found, np.zeros((size, 1)), model.release[2])
                else:
                    model.packs_roll = packs_takeoff.roll_on_packs(model, self._packs, rows)
                model.packs_airborne, model.packs_beyond = packs_takeoff.airborne_on_packs(
                    model, self._packs, rows, model.packs_roll, height)
                found = model.packs_roll.as_roll()
            elif catapult:
                model.release = model.release_run()
            if catapult:  # one that does not accelerate to the arc's speed never gets there
                found = (*found[:3], np.where(model.release[3], found[3], 0.0))
            if self._packs is None:
                return found
            within = model.launch_within_packs(found, height, catapult, self._packs, battery)
            return found[0], found[1], found[2], np.where(within, found[3], 0.0)

        beyond: dict[str, NDArray[np.bool_]] = {}
        propulsion = self.case.propulsion

        def flown_span(*speeds: Array, from_rest: bool) -> tuple[Array, Array]:
            # the slowest and fastest airspeeds [m/s] flown on the thrust model: from rest on
            # a runway; fmin/fmax: a speed a row does not fly (NaN) is no bound
            stacked = np.stack(np.broadcast_arrays(*speeds))
            slowest = np.zeros(size) if from_rest else np.fmin.reduce(stacked, axis=0)
            return slowest, np.fmax.reduce(stacked, axis=0)

        def airborne_beyond(launch: tuple[Array, Array, Array, Array]) -> NDArray[np.bool_]:
            # as solve_takeoff: a runway's roll from rest to the lift-off speed, a catapult's
            # release, and the arc's 1.15 V_stall
            return np.asarray(outside_tested_span(propulsion, *flown_span(
                launch[2], model.transition_speed(), from_rest=not catapult)), dtype=bool)

        for requirement in self.requirements:
            limits[requirement.name] = self._limit(values, requirement, size)
            if requirement.block in ("envelope", "oei"):
                flown = np.where(np.isfinite(grid), grid, propulsion.tested_airspeed_m_s[0])
                beyond[requirement.name] = np.broadcast_to(
                    np.any(outside_tested_range(propulsion, flown), axis=1), (size,)).copy()
            if requirement.name == "takeoff_ground_roll":
                roll = roll or launched()
                out[requirement.name] = np.where(roll[3] > 0.5, roll[0], np.nan)
                beyond[requirement.name] = airborne_beyond(roll)
            elif requirement.name == "takeoff_distance_to_obstacle":
                roll = roll or launched()
                out[requirement.name] = model.distance_to_obstacle(roll, height)
                beyond[requirement.name] = airborne_beyond(roll)
            elif requirement.block == "envelope":
                value = model.trim_max_throttle(grid, self._candidates()[0])
                if self._packs is not None and not model.packs_never_bind(
                        grid, self._packs, battery, value):
                    value = model.over_grid_on_packs(grid, None, "windmilling", self._packs,
                                                     battery)
                out[requirement.name] = np.where(unflown, np.nan, value)
            elif requirement.block == "oei":
                mode = self.case.requirements.oei.dead_engine
                value = model.oei_min_throttle(grid, mode, self._candidates()[1])
                if self._packs is not None and not model.packs_never_bind(
                        grid, self._packs, battery, np.ones(size)):
                    worst = np.full(size, -np.inf)
                    for dead in range(len(self.case.propulsion.engines)):
                        worst = np.maximum(worst, model.over_grid_on_packs(
                            grid, dead, mode, self._packs, battery))
                    value = worst
                out[requirement.name] = np.where(unflown, np.nan, value)
            else:
                # a catapult launch starts airborne at its release speed (no runway)
                launch = roll or launched()
                roll = launch
                key = "requirements.endurance.throttle"
                throttle = _column(values, key, self.case.requirements.endurance.throttle, size)
                throttle = np.asarray(throttle, dtype=float).reshape(-1) * np.ones(size)
                out[requirement.name], speed, climb = model.flight_endurance_min(
                    self._endurance, throttle, launch, battery
                )
                # the roll and the climb fly the thrust model too, as the single case's
                # mission (a catapult's release is no node of it): a roll from rest below
                # the tested range was not said
                flown = (speed, climb) if catapult else (launch[2], speed, climb)
                beyond[requirement.name] = np.asarray(outside_tested_span(
                    propulsion, *flown_span(*flown, from_rest=not catapult)), dtype=bool)
        return BatchResult(
            values=out,
            limits=limits,
            kinds={r.name: r.kind for r in self.requirements},
            units={r.name: r.unit for r in self.requirements},
            refused=self.rows_refused(values, size, coefficients),
            without_envelope=unflown,
            extrapolated=beyond,
        )

    def _battery_nominal(self) -> dict[str, float]:
        from tuflexperf.io.dotted import battery_key_values

        side = self._endurance if self._endurance is not None else self._packs
        return battery_key_values(side.battery)

    def _battery_rows(self, values: Mapping[str, Array], size: int) -> dict[str, Array]:
        """The battery keys that vary (dotted.BATTERY_KEYS), one value per row."""
        return {k: np.asarray(_column(values, k, v, size), dtype=float).reshape(-1)
                * np.ones(size) for k, v in self._battery_nominal().items()}

    def _candidates(self) -> tuple[Array | None, dict[int, Array]]:
        """Grid indices beside the nominal case's highest trim throttle (and the envelope's
        ends) and, per dead engine, beside its least OEI throttle (memoised).

        Only where to look first: the batch verifies every row against all airspeeds and
        solves the rows the candidates do not settle at every airspeed.
        """
        if getattr(self, "_candidate_cache", None) is not None:
            return self._candidate_cache
        grid = self._nominal_grid()[None, :]
        last = grid.shape[1] - 1
        model = _Model(aircraft=self._aircraft({}, 1), propulsion=self._propulsion(None),
                       density=self._density({}, 1), extrapolation_n=None, size=1,
                       stall_margin=stall_margin_of(self.case))

        def beside(index: int) -> Array:
            near = np.arange(index - _CANDIDATE_HALF_WIDTH, index + _CANDIDATE_HALF_WIDTH + 1)
            return np.unique(np.clip(np.concatenate([near, [0, last]]), 0, last))

        terms = model._grid_terms(grid)
        above = model._flyable(grid)[0]
        throttle = np.where(above, model.least_throttle(grid, terms=terms)[0], np.nan)
        trim = beside(int(np.nanargmax(throttle))) if np.any(np.isfinite(throttle)) else None
        oei: dict[int, Array] = {}
        mode = self.case.requirements.oei.dead_engine if self.case.requirements.oei else \
            "windmilling"
        for dead in range(len(self.case.propulsion.engines)):
            throttle = np.where(
                above, model.least_throttle(grid, dead, mode, terms)[0], np.nan)
            if np.any(np.isfinite(throttle)):
                oei[dead] = beside(int(np.nanargmin(throttle)))
        self._candidate_cache = (trim, oei)
        return self._candidate_cache

    def _nominal_grid(self) -> Array:
        if getattr(self, "_grid_cache", None) is not None:
            return self._grid_cache
        from tuflexperf.analysis.trim import envelope_of

        # the single case's checks (no envelope, bounds out of order, beyond Mach 1) and grid
        self._grid_cache = airspeed_grid(*envelope_of(self.case))
        return self._grid_cache

    def envelope_bounds(self, values: Mapping[str, Array], density: Any,
                        size: int) -> tuple[Array, Array, NDArray[np.bool_]]:
        """Each row's envelope as true airspeeds [m/s] (least, greatest), and where it is none.

        A row's bounds are the case's unless ``values`` varies them; an equivalent-airspeed
        bound follows the row's density [kg/m^3] (SPEC 3). A row has no envelope where its
        least airspeed is not above 0 and below its greatest, or the greatest is beyond the
        speed of sound (the single case's bad input, :func:`tuflexperf.analysis.trim.envelope_of`
        and the schema), so no row builds a grid longer than the speed of sound allows.
        """
        self._nominal_grid()  # the case's own envelope first: missing or crossed, bad input
        envelope = self.case.requirements.envelope
        bounds = []
        for end in ("min", "max"):
            true_key = f"requirements.envelope.{end}_airspeed_m_s"
            eas_key = f"requirements.envelope.{end}_airspeed_eas_m_s"
            true = getattr(envelope, f"{end}_airspeed_m_s")
            if true is not None:
                bound = _column(values, true_key, float(true), size)
            else:
                eas = _column(values, eas_key, float(getattr(envelope, f"{end}_airspeed_eas_m_s")),
                              size)
                bound = true_airspeed_m_s(eas, density)
            bounds.append(np.asarray(bound, dtype=float).reshape(-1) * np.ones(size))
        low, high = bounds
        with np.errstate(invalid="ignore"):
            none = ~((low > 0.0) & (low < high) & (high <= MAX_AIRSPEED_M_S))
        return low, high, none

    def rows_refused(self, values: Mapping[str, Array], size: int,
                     coefficients: Array | None = None) -> NDArray[np.bool_]:
        """Rows whose aircraft the single case refuses as bad input
        (:func:`tuflexperf.io.case.refuse_absurd_propulsion`, the aircraft schema's rules
        across its keys): an engine's full-throttle static thrust [N] not positive, or above
        ``ABSURD_THRUST_TO_WEIGHT`` x the row's weight (a 0.01 kg draw of a 26 kg aircraft
        passed everything; outside audit); a stall speed beyond the speed of sound; a
        catapult's release or a given lift-off speed below the row's stall (EAS); a runway's
        ground-roll lift coefficient above ``cl_max``."""
        from tuflexperf.io.case import ABSURD_THRUST_TO_WEIGHT

        aircraft = self._aircraft(values, size)
        weight = np.asarray(aircraft.weight_n, dtype=float).reshape(-1) * np.ones(size)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            stall_eas = np.asarray(stall_speed_m_s(aircraft, EAS_REFERENCE_DENSITY_KG_M3),
                                   dtype=float).reshape(-1) * np.ones(size)
        refused = ~(stall_eas <= MAX_AIRSPEED_M_S)
        for speed in (aircraft.launch_speed_m_s if aircraft.launch == "catapult" else None,
                      aircraft.takeoff.liftoff_speed_m_s):
            if speed is not None:
                refused |= np.asarray(speed, dtype=float).reshape(-1) < stall_eas
        if aircraft.launch == "runway":
            refused |= (np.asarray(aircraft.takeoff.cl_ground, dtype=float).reshape(-1)
                        > np.asarray(aircraft.cl_max, dtype=float).reshape(-1))
        propulsion = self._propulsion(coefficients)
        # at the row's air density, as the single case's analyses scale the thrust
        scale = density_ratio(propulsion, self._density(values, size))
        for engine in propulsion.engines:
            static = np.asarray(engine_thrust_n(engine, 1.0, 0.0, scale),
                                dtype=float).reshape(-1) * np.ones(size)
            with np.errstate(invalid="ignore", over="ignore"):
                refused |= ~((static > 0.0) & (static <= ABSURD_THRUST_TO_WEIGHT * weight))
        return refused

    def rows_without_envelope(self, values: Mapping[str, Array],
                              size: int) -> NDArray[np.bool_]:
        """Rows of ``values`` whose envelope is none (:meth:`envelope_bounds`); none without
        trim or OEI requirements, which alone fly the envelope."""
        if not any(r.block in ("envelope", "oei") for r in self.requirements):
            return np.zeros(size, dtype=bool)
        return self.envelope_bounds(values, self._density(values, size), size)[2]

    def _grids(self, values: Mapping[str, Array], density: Any,
               size: int) -> tuple[Array, NDArray[np.bool_]]:
        """Trim's and OEI's airspeeds: ``(1, K)``, the case's grid, when every row shares it,
        else one row each (:func:`airspeed_grids`); and the rows that have no envelope."""
        envelope = self.case.requirements.envelope
        grid = self._nominal_grid()[None, :]  # the case's own envelope is checked first
        varied = any(key.startswith("requirements.envelope.") and "airspeed" in key
                     for key in values)
        if not varied and not (envelope.in_eas and np.ndim(density) > 0):
            return grid, np.zeros(size, dtype=bool)
        low, high, none = self.envelope_bounds(values, density, size)
        # a row without an envelope is solved on the case's own bounds, then left out (NaN)
        low = np.where(none, grid[0, 0], low)
        high = np.where(none, grid[0, -1], high)
        return airspeed_grids(low, high), none


@dataclass
class _Model:
    """The batch's physics: array-valued aircraft/engines through the model functions."""

    aircraft: Aircraft
    propulsion: Propulsion
    density: Any
    extrapolation_n: Array | None
    size: int
    stall_margin: Any = 1.0  # envelope's stall_margin (scalar or per row)
    _uniform: Array | None = None
    _drag: Any = None  # (airspeeds, level-flight drag there) of the last grid
    _pieces: Any = None  # memo of _roll_pieces (False: evaluate node by node)
    _terms: Any = None
    _force_range: tuple[Array, Array] | None = None  # memo of force_range
    # the take-off on sagging packs (batch_takeoff_packs.RollOnPacks), where one is flown
    packs_roll: Any = None
    # a catapult's level acceleration from release to the transition speed (distance [m],
    # time [s], charge per fan [Ah] or None, accelerates): ground_roll.release_acceleration
    release: Any = None
    # the arc and climb to the obstacle on sagging packs [m] (batch_takeoff_packs)
    packs_airborne: Array | None = None
    # where those packs reach their cut-off in the climb, before the obstacle
    packs_beyond: NDArray[np.bool_] | None = None

    def transition_speed(self) -> Array:
        """The take-off arc's true airspeed [m/s] per row ``(B,)``: 1.15 V_stall."""
        return np.asarray(transition_speed_m_s(self.aircraft, self.density),
                          dtype=float).reshape(-1) * np.ones(self.size)

    def least_airspeed(self) -> Array:
        """Least level-flight airspeed [m/s] per row: stall x the envelope's margin (SPEC 3)."""
        return np.asarray(self.stall_margin, dtype=float).reshape(-1) * stall_speed(self)

    def _flyable(self, grid: Array) -> Array:
        """Where level flight may be attainable per row: at or above the least airspeed and
        short of the fans' jet velocity (the single-case ``stall_bounded``); ``grid`` is
        ``(1, K)`` or one row of airspeeds [m/s] per row of the batch."""
        above = grid >= self.least_airspeed()[:, None] * (1.0 - 1e-12)
        density = np.asarray(self.density, dtype=float).reshape(-1, 1)
        return above & ~beyond_jet_velocity(self.propulsion, grid, density)

    def extrapolation_errors_n(self, speed: Array) -> list[Array] | None:
        """Per engine, the row's sampled thrust error [N] at ``speed``: its draw beyond the
        tested range, scaled to the row's density as the thrust is; ``None`` without draws."""
        if self.extrapolation_n is None:
            return None
        beyond = density_ratio(self.propulsion, self.density) \
            * outside_tested_range(self.propulsion, speed).astype(float)
        return [beyond * error[:, None] for error in self.extrapolation_n]

    def _per_row(self, value: Any) -> Array:
        """``value`` [N] as an array with one row per batch row (a view where it is shared)."""
        value = np.asarray(value, dtype=float)
        return np.broadcast_to(value, np.broadcast_shapes(value.shape, (self.size, 1)))

    def thrust(self, throttle: Any, speed: Array, dead: int | None = None,
               mode: str = "windmilling") -> Array:
        """Total thrust [N]; the extrapolation error adds to each live engine beyond the range."""
        total = total_thrust_n(self.propulsion, throttle, speed, self.density, dead, mode)
        errors = self.extrapolation_errors_n(speed)
        for j, error in enumerate(errors or ()):
            if j != dead:
                total = total + error
        return self._per_row(total)

    def engine_thrust(self, index: int, throttle: Any, speed: Array) -> Array:
        """One live engine's thrust [N], as :meth:`thrust` counts it in the total (its model
        at the row's density, its extrapolation error beyond the tested range)."""
        own = engine_thrust_n(self.propulsion.engines[index], throttle, speed,
                              density_ratio(self.propulsion, self.density))
        errors = self.extrapolation_errors_n(speed)
        return self._per_row(own if errors is None else own + errors[index])

    # -- take-off -----------------------------------------------------------------------------
    def net_force(self, speed: Array) -> Array:
        thrust = self.thrust(1.0, speed)
        return np.asarray(
            ground_roll_net_force_n(self.aircraft, thrust, speed, self.density), dtype=float
        ) * np.ones((self.size, 1))

    def liftoff_speed(self) -> Array:
        return np.asarray(liftoff_speed_m_s(self.aircraft, self.density), dtype=float) \
            * np.ones((self.size, 1))

    def _breaks(self, v_lo: Array) -> list[Array]:
        """Where the integrand kinks in [0, V_LO]: friction clamp (L = W), tested range end."""
        to = self.aircraft.takeoff
        with np.errstate(divide="ignore", invalid="ignore"):
            clamp = np.sqrt(2.0 * self.aircraft.weight_n
                            / (self.density * self.aircraft.wing_area_m2 * to.cl_ground))
        clamp = np.where(np.isfinite(clamp), clamp, np.inf) * np.ones_like(v_lo)
        edge = np.full_like(v_lo, self.propulsion.tested_airspeed_m_s[1])
        first = np.minimum(np.minimum(clamp, edge), v_lo)
        second = np.minimum(np.maximum(clamp, edge), v_lo)
        return [np.zeros_like(v_lo), first, second, v_lo]

    def _integrate(self, low: Array, high: Array, panels: int) -> tuple[Array, Array]:
        """Composite Gauss-Legendre of ``m V / F`` and ``m / F`` over [low, high] per row
        (the force evaluated node by node: the fallback of :meth:`_roll_pieces`)."""
        width = (high - low) / panels
        starts = low + width * np.arange(panels)[None, :]
        nodes = (starts[:, :, None] + 0.5 * width[:, :, None] * (_GL_NODES + 1.0)).reshape(
            self.size, -1)
        weights = np.tile(_GL_WEIGHTS, panels)[None, :] * 0.5 * width
        force = self.net_force(nodes)
        mass = np.asarray(self.aircraft.mass_kg, dtype=float) * np.ones((self.size, 1))
        with np.errstate(divide="ignore", invalid="ignore"):
            distance = np.sum(weights * mass * nodes / force, axis=1)
            time = np.sum(weights * mass / force, axis=1)
        return distance, time

    def _roll_pieces(self) -> tuple[list[Array], list[tuple[Array, ...]]] | None:
        """The net force on each smooth piece of [0, V_LO] as a quadratic (memoised).

        Between the kinks of :meth:`_breaks` the full-throttle net force is quadratic in
        airspeed (poly22 thrust at a fixed throttle, drag, lift and wheel load all ~V^2, the
        extrapolation error constant), so three values of :meth:`net_force` per piece give
        it exactly, as ``c0 + c1 s + c2 s^2`` with ``s = u - 1/2`` and ``u`` the piece's own
        coordinate in [0, 1] (Lagrange through u = 1/4, 1/2, 3/4). A fourth value checks it;
        where it does not hold (a model that is not quadratic, a jump inside a piece) the
        force is evaluated node by node instead (None).
        """
        if self._pieces is not None:
            return self._pieces or None
        low_edge = self.propulsion.tested_airspeed_m_s[0]
        if self.extrapolation_n is not None and low_edge > 0.0:
            self._pieces = False  # a jump at the low edge lies inside the first piece
            return None
        breaks = self._breaks(self.liftoff_speed())
        fits = []
        ok = True
        for low, high in zip(breaks[:-1], breaks[1:], strict=True):
            width = high - low
            f = self.net_force(low + width * _ROLL_PROBES[None, :])
            c0 = f[:, 1:2]
            c1 = 2.0 * (f[:, 2:3] - f[:, 0:1])
            c2 = 8.0 * (f[:, 0:1] - 2.0 * f[:, 1:2] + f[:, 2:3])
            s = _ROLL_PROBES[3] - 0.5
            predicted = c0 + s * (c1 + s * c2)
            scale = np.max(np.abs(f), axis=1, keepdims=True) + 1.0
            with np.errstate(invalid="ignore"):
                ok = ok and bool(np.all((np.abs(predicted - f[:, 3:4]) <= 1e-9 * scale)
                                        | ~np.isfinite(f[:, 3:4])))
            fits.append((low, width, c0, c1, c2))
        self._pieces = (breaks, fits) if ok else False
        return self._pieces or None

    def _integrate_piece(self, piece: tuple[Array, ...]) -> tuple[Array, Array]:
        """:meth:`_integrate` on one piece of :meth:`_roll_pieces`: the same nodes, the force
        from the piece's quadratic."""
        mass = np.asarray(self.aircraft.mass_kg, dtype=float) * np.ones((self.size, 1))
        low, width, c0, c1, c2 = piece
        u, w = _ROLL_RULE
        s = u - 0.5
        force = c0 + s * (c1 + s * c2)
        speed = low + width * u
        weights = w * width
        with np.errstate(divide="ignore", invalid="ignore"):
            over = weights * mass / force
            return np.sum(over * speed, axis=1), np.sum(over, axis=1)

    def _integrate_piece_near_a_peak(self, piece: tuple[Array, ...], rows: Array
                                     ) -> tuple[Array, Array]:
        """:func:`roll_integrals_near_a_peak` on one piece of :meth:`_roll_pieces`, ``rows``
        (indices) only."""
        mass = np.asarray(self.aircraft.mass_kg, dtype=float) * np.ones((self.size, 1))
        low, width, c0, c1, c2 = (a[rows] for a in piece)
        return roll_integrals_near_a_peak(low, width, c0, c1, c2, mass[rows])

    def force_range(self) -> tuple[Array, Array]:
        """Least and greatest full-throttle net force [N] per row from rest to lift-off.

        On the quadratic pieces of :meth:`_roll_pieces` both are exact (each piece's ends and
        vertex), so a dip between any check points counts; node by node, the single case's
        2001 equally spaced airspeeds (``analysis.takeoff``). Memoised: the roll, its
        history and the launch ask for it.
        """
        if self._force_range is None:
            self._force_range = self._least_and_greatest_force()
        return self._force_range

    def _least_and_greatest_force(self) -> tuple[Array, Array]:
        pieces = self._roll_pieces()
        if pieces is None:
            speeds = self.liftoff_speed() * np.linspace(0.0, 1.0, _CHECK_POINTS)[None, :]
            force = self.net_force(speeds)
            return np.min(force, axis=1), np.max(force, axis=1)
        least = np.full(self.size, np.inf)
        most = np.full(self.size, -np.inf)
        for _, width, c0, c1, c2 in pieces[1]:
            # s in [-1/2, 1/2]: the ends, and the vertex where it lies inside
            ends = (c0 - 0.5 * c1 + 0.25 * c2, c0 + 0.5 * c1 + 0.25 * c2)
            with np.errstate(divide="ignore", invalid="ignore"):
                vertex = -c1 / (2.0 * c2)
                inside = (np.abs(vertex) <= 0.5) & (c2 != 0.0)
                top = c0 - c1 * c1 / (4.0 * c2)
            used = (np.asarray(width) > 0.0).reshape(-1)
            low = np.minimum(np.minimum(*ends), np.where(inside, top, np.inf)).reshape(-1)
            high = np.maximum(np.maximum(*ends), np.where(inside, top, -np.inf)).reshape(-1)
            least = np.where(used, np.minimum(least, low), least)
            most = np.where(used, np.maximum(most, high), most)
        return least, most

    def uniform_force(self) -> Array:
        """Net force [N] at 101 equally spaced airspeeds from rest to V_LO (memoised)."""
        if self._uniform is None:
            v_lo = self.liftoff_speed()
            speeds = v_lo * np.linspace(0.0, 1.0, _HISTORY_POINTS)[None, :]
            pieces = self._roll_pieces()
            if pieces is None:
                self._uniform = self.net_force(speeds)
                return self._uniform
            breaks, fits = pieces
            # a roll that is one smooth piece (no kink before lift-off): the airspeeds' own
            # coordinate on it is k/100
            u = np.linspace(0.0, 1.0, _HISTORY_POINTS)[None, :] - 0.5
            _, _, c0, c1, c2 = fits[0]
            force = c0 + u * (c1 + u * c2)
            kinked = np.flatnonzero(breaks[1][:, 0] < v_lo[:, 0])
            if kinked.size:
                # each airspeed on its piece; an airspeed within 1e-9 above the tested
                # range's end still counts as tested, as the thrust model decides (thrust)
                edge = self.propulsion.tested_airspeed_m_s[1]
                at = speeds[kinked]
                index = sum((at > np.where(b[kinked] == edge, b[kinked] + 1e-9, b[kinked]))
                            .astype(np.intp) for b in breaks[1:3])
                low, width, c0, c1, c2 = (np.take_along_axis(
                    np.concatenate([f[i][kinked] for f in fits], axis=1), index, axis=1)
                    for i in range(5))
                with np.errstate(divide="ignore", invalid="ignore"):
                    s = (at - low) / width - 0.5
                force[kinked] = c0 + s * (c1 + s * c2)
            self._uniform = force
        return self._uniform

    def ground_roll(self) -> tuple[Array, Array, Array, Array]:
        """Ground roll [m], time [s], lift-off speed [m/s], and attainable (1/0) per row.

        Not attainable where the net force is not positive on the 101-point check grid
        from rest to the lift-off speed (a vanishing force means no lift-off).
        """
        v_lo = self.liftoff_speed()
        # a sampled lift-off speed below stall cannot lift off (bad input for one case)
        stall = stall_speed(self)[:, None]
        least, most = self.force_range()
        attainable = (least > 0.0) & (v_lo >= stall * (1.0 - 1e-12))[:, 0]
        # beyond the fans' jet velocity an extrapolated thrust model is not physics (as
        # solve_takeoff says); v_lo is a column, as the jet velocity of sampled rows is
        attainable &= ~beyond_jet_velocity(self.propulsion, v_lo, self.density)[:, 0]
        pieces = self._roll_pieces()
        breaks = self._breaks(v_lo) if pieces is None else pieces[0]
        distance = np.zeros(self.size)
        time = np.zeros(self.size)
        # 1/F peaks where the force all but vanishes: 64 nodes a piece missed it by 17 % (a
        # roll of 812 m for 976; outside audit); such rows take 64 times the panels
        with np.errstate(divide="ignore", invalid="ignore"):
            steep = attainable & (least < _STEEP_FORCE_SHARE * most)
        for k, (low, high) in enumerate(zip(breaks[:-1], breaks[1:], strict=True)):
            if np.all(high <= low):
                continue  # this kink lies beyond lift-off for every row
            d, t = (self._integrate(low, high, _PANELS) if pieces is None
                    else self._integrate_piece(pieces[1][k]))
            if steep.any() and pieces is None:
                fine = self._integrate(low, high, _FINE_PANELS)
                d, t = np.where(steep, fine[0], d), np.where(steep, fine[1], t)
            elif steep.any():  # the spike-resolving rule on those rows alone
                rows = np.flatnonzero(steep)
                d, t = d.copy(), t.copy()
                d[rows], t[rows] = self._integrate_piece_near_a_peak(pieces[1][k], rows)
            distance, time = distance + d, time + t
        # a sum over 1/F is no roll unless it is positive (a force negative between check
        # points summed to -796 m and passed; outside audit)
        ok = attainable & (distance > 0.0) & (time > 0.0) & np.isfinite(distance) \
            & np.isfinite(time)
        # rotation on the ground at the lift-off speed (Raymer 17.8.2: S_R = V_LO t_R)
        rotation = np.asarray(self.aircraft.takeoff.rotation_time_s, dtype=float).reshape(-1) \
            * np.ones(self.size)
        distance = distance + v_lo[:, 0] * rotation
        time = time + rotation
        return (np.where(ok, distance, np.nan), np.where(ok, time, np.nan), v_lo[:, 0],
                ok.astype(float))

    def release_run(self, thrust_and_current: Any = None
                    ) -> tuple[Array, Array, Array | None, Array]:
        """A catapult's acceleration after the release per row
        (:func:`tuflexperf.analysis.ground_roll.release_acceleration`): at the model's thrust, or
        at ``thrust_and_current(V)`` (thrust [N], current per fan [A]; on sagging packs)."""
        from tuflexperf.analysis.ground_roll import release_acceleration

        release = np.asarray(true_airspeed_m_s(self.aircraft.launch_speed_m_s, self.density),
                             dtype=float).reshape(-1) * np.ones(self.size)
        v_tr = self.transition_speed()

        def forces(speed: Array) -> tuple[Array, Array | None]:
            drag = np.asarray(level_flight_drag_n(self.aircraft, speed, self.density),
                              dtype=float)
            if thrust_and_current is None:
                return self.thrust(1.0, speed) - drag, None
            thrust, current = thrust_and_current(speed)
            return thrust - drag, current

        return release_acceleration(self.aircraft.mass_kg, release, v_tr, forces)

    def catapult_release(self) -> tuple[Array, Array, Array, Array]:
        """A catapult launch as :meth:`ground_roll` reports a roll: no distance, no time, the
        release true airspeed [m/s] (``launch_speed_m_s`` is an EAS) and attainable (1/0).

        The catapult's energy is the ground equipment's, not the battery's (SPEC 4): the
        flight starts airborne at the release speed, which must not be below stall (bad input
        for one case; not attainable for a sampled mass or ``cl_max`` that raises the stall),
        and which the catapult's ``launch_energy_j`` must give the mass (m V^2 / 2).
        """
        release = np.asarray(true_airspeed_m_s(self.aircraft.launch_speed_m_s, self.density),
                             dtype=float).reshape(-1) * np.ones(self.size)
        mass = np.asarray(self.aircraft.mass_kg, dtype=float).reshape(-1) * np.ones(self.size)
        energy = self.aircraft.launch_energy_j
        short = catapult_energy_shortfall(
            mass, release, None if energy is None else np.asarray(energy, dtype=float).reshape(-1))
        ok = (release >= stall_speed(self) * (1.0 - 1e-12)) & ~short
        # no thrust to climb away beyond the fans' jet velocity (solve_takeoff)
        density = np.asarray(self.density, dtype=float).reshape(-1, 1)
        ok &= ~np.asarray(beyond_jet_velocity(self.propulsion, release[:, None], density),
                          dtype=bool).reshape(-1)
        zero = np.zeros(self.size)
        return zero, zero, release, ok.astype(float)

    def launch_within_packs(self, roll: tuple[Array, Array, Array, Array], height: Any,
                            catapult: bool, packs: Any, battery: dict[str, Array]
                            ) -> NDArray[np.bool_]:
        """Per row: the packs give full throttle over the take-off, as the single case
        checks it (:func:`tuflexperf.analysis.pack_limits.takeoff_beyond_battery`): over the
        roll's 101 history airspeeds (a catapult: its release) and the transition speed, on
        full packs and after the charge the most current for the whole take-off (roll,
        rotation, and the arc and climb to the obstacle at the transition speed) would draw,
        the loaded voltage at or above the cut-off and each pack within its burst rating;
        and, on sagging packs, the climb reaching the obstacle before their cut-off
        (:attr:`packs_beyond`)."""
        from tuflexperf.analysis.batch_endurance import _power_w
        from tuflexperf.analysis.constants import BURST_OVER_CONTINUOUS, SECONDS_PER_HOUR
        from tuflexperf.analysis.ground_roll import HISTORY_POINTS

        prop = self.propulsion
        v_tr = self.transition_speed()[:, None]
        airborne = self.airborne_m(height)
        airborne = np.where(np.isfinite(airborne), airborne, 0.0)
        seconds = np.nan_to_num(roll[1]) + airborne / v_tr[:, 0]
        if catapult:  # and its level acceleration after the release, as the single case
            seconds = seconds + np.nan_to_num(self.release[1])
        v_lo = np.nan_to_num(roll[2]).reshape(-1, 1)
        along = (v_lo if catapult else
                 v_lo * np.linspace(0.0, 1.0, HISTORY_POINTS)[None, :])
        speeds = np.concatenate([along * np.ones((self.size, 1)), v_tr], axis=1)
        rows = pack_rows(packs.battery, battery)
        circuit, cutoff = rows.circuit_packs[:, None], rows.cutoff_v[:, None]
        burst = (None if rows.rating_a is None
                 else BURST_OVER_CONTINUOUS * rows.rating_a[:, None])
        ok = np.ones(self.size, dtype=bool)
        for engine in prop.engines if packs.own_surfaces else (None,):
            power = np.maximum(_power_w(packs, self, 1.0, speeds, engine), 0.0)
            power = power * np.ones_like(speeds)
            charge = np.zeros((self.size, 1))
            for _ in range(2):
                _, current, _ = point = operating_point(
                    packs.params, charge, power, circuit, rows.packs_per_engine,
                    prop.reference_voltage_v, prop.voltage_exponent)
                ok &= np.all(within_limits(point[0], current, cutoff, burst), axis=1)
                charge = (np.max(current, axis=1) * rows.packs_per_engine * seconds
                          / SECONDS_PER_HOUR)[:, None]
        if self.packs_beyond is not None:  # the packs give out in the climb (solve_takeoff)
            ok &= ~self.packs_beyond
        return ok

    def airborne_m(self, height: Any) -> Array:
        """Transition arc + climb to the obstacle [m] per row (``inf`` where never cleared):
        on the sagging packs where they were flown (:attr:`packs_airborne`), else at the
        model's thrust (as :func:`solve_takeoff`)."""
        if self.packs_airborne is not None:
            return self.packs_airborne
        v_tr = self.transition_speed()[:, None]
        radius = transition_radius_m(v_tr, self.aircraft.takeoff.transition_load_factor)
        gradient = climb_gradient(self.aircraft, self.thrust(1.0, v_tr), v_tr, self.density)
        arc, climb, _ = obstacle_distances_m(radius, gradient, height)
        return (np.asarray(arc, dtype=float) + np.asarray(climb, dtype=float))[:, 0]

    def distance_to_obstacle(self, roll: tuple[Array, Array, Array, Array],
                             height: Any) -> Array:
        """Ground roll + transition arc + climb to the obstacle [m] (as :func:`solve_takeoff`),
        a catapult's level acceleration after the release included."""
        airborne = self.airborne_m(height)
        if self.release is not None:
            airborne = airborne + self.release[0]
        total = roll[0] + airborne
        # a launch that is not attainable (a catapult's "roll" of 0 m included) reaches nothing;
        # nor does an arc that needs more than cl_max (solve_takeoff)
        flown = ~np.asarray(transition_beyond_cl_max(np.asarray(
            self.aircraft.takeoff.transition_load_factor, dtype=float)), dtype=bool).reshape(-1)
        return np.where(np.isfinite(total) & (roll[3] > 0.5) & flown, total, np.nan)

    def roll_history(self, wanted: NDArray[np.bool_] | None = None) -> Array:
        """Time [s] at 101 equally spaced airspeeds from rest to V_LO (as the CVODES history);
        only the ``wanted`` rows exactly where the force all but vanishes (the others are
        not flown: a chunk of them cost 2.5 s; outside audit).

        Cumulative integral of ``m / F`` on the uniform nodes by the four-point rule
        ``h/24 (-g_{i-1} + 13 g_i + 13 g_{i+1} - g_{i+2})`` (trapezoid-corrected, O(h^5) per
        panel; one-sided at the ends), from the same force values as the check grid.
        """
        v_lo = self.liftoff_speed()
        h = v_lo / (_HISTORY_POINTS - 1)
        mass = np.asarray(self.aircraft.mass_kg, dtype=float).reshape(-1, 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = mass / self.uniform_force()
        left = np.concatenate([2 * g[:, :1] - g[:, 1:2], g[:, :-2]], axis=1)
        right = np.concatenate([g[:, 2:], 2 * g[:, -1:] - g[:, -2:-1]], axis=1)
        pieces = h / 24.0 * (-left + 13.0 * g[:, :-1] + 13.0 * g[:, 1:] - right)
        history = np.concatenate([np.zeros((self.size, 1)), np.cumsum(pieces, axis=1)], axis=1)
        least, most = self.force_range()
        with np.errstate(invalid="ignore"):
            steep = (least > 0.0) & (least < _STEEP_FORCE_SHARE * most)
        steep = np.flatnonzero(steep if wanted is None else steep & wanted)
        if steep.size and self._roll_pieces() is not None:
            # where the force all but vanishes the four-point rule misses the peak of 1/F
            # (and the launch's airspeed follows this history): each interval exactly
            history[steep] = self._exact_history(steep, most[steep])
        return history

    def _exact_history(self, rows: Array, most: Array) -> Array:
        """:meth:`roll_history` of ``rows`` (indices) by the pieces' quadratics: each of its
        100 intervals cut at the pieces' kinks, each part's ``integral m / F dV`` by 16 Gauss
        nodes, or by :func:`roll_integrals_near_a_peak` where its least force is below
        ``_STEEP_FORCE_SHARE`` of the roll's greatest ``most`` [N]."""
        breaks, fits = self._roll_pieces()  # type: ignore[misc]
        v_lo = self.liftoff_speed()[rows]
        nodes = v_lo * np.linspace(0.0, 1.0, _HISTORY_POINTS)[None, :]
        start, end = nodes[:, :-1], nodes[:, 1:]
        kinks = [np.clip(b[rows], start, end) for b in breaks[1:3]]
        cuts = np.sort(np.stack([start, *kinks, end], axis=-1), axis=-1)
        a, b = cuts[..., :-1], cuts[..., 1:]  # (rows, 100, 3): each part on one piece
        middle = 0.5 * (a + b)
        which = sum((middle > k[..., None]) for k in (breaks[1][rows], breaks[2][rows]))
        low, width, c0, c1, c2 = (np.take_along_axis(
            np.concatenate([f[i][rows] for f in fits], axis=1)[:, None, :],
            which.astype(np.intp), axis=2) for i in range(5))

        def force(speed: Array) -> Array:
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (speed - low) / width - 0.5
            return c0 + s * (c1 + s * c2)

        f_a, f_m, f_b = force(a), force(middle), force(b)
        # each part's own quadratic on its own coordinate in [-1/2, 1/2]
        local = (a, b - a, f_m, f_b - f_a, 2.0 * (f_a - 2.0 * f_m + f_b))
        with np.errstate(divide="ignore", invalid="ignore"):
            vertex = -local[3] / (2.0 * local[4])
            top = np.where(np.abs(vertex) < 0.5, f_m - local[3] ** 2 / (4.0 * local[4]),
                           np.inf)
        peaked = np.minimum(np.minimum(f_a, f_b), top) < _STEEP_FORCE_SHARE * most[:, None, None]
        mass = np.asarray(self.aircraft.mass_kg, dtype=float) * np.ones((self.size, 1))
        mass = np.broadcast_to(mass[rows][:, :, None], a.shape)
        time = np.zeros(a.shape)
        for chosen, rule in ((~peaked, _unit_rule(1)), (peaked, _PEAK_RULE)):
            if chosen.any():
                _, time[chosen] = roll_integrals_near_a_peak(
                    *(part[chosen][:, None] for part in local), mass[chosen][:, None], rule)
        time = np.where(b > a, time, 0.0)
        return np.concatenate([np.zeros((rows.size, 1)), np.cumsum(time.sum(axis=2), axis=1)],
                              axis=1)

    # -- level flight --------------------------------------------------------------------------
    def _engine_thrusts(self, speed: Array) -> tuple[list[tuple[Array, Array, Array]],
                                                      list[Array]]:
        """Per engine: its thrust [N] as ``a x^2 + b x + c`` in throttle at these airspeeds
        (the extrapolation error in ``c``), and its dead-engine contribution, as
        :func:`total_thrust_n` sums them.

        poly22 is quadratic in throttle: ``a, b, c`` from its values at throttle 0, 1/2
        and 1. Sampled coefficients against airspeeds common to all rows: poly22 is linear
        in its coefficients, so the three values are each row's coefficients times
        poly22's basis functions, one matrix product per coefficient.
        """
        scale = density_ratio(self.propulsion, self.density)
        errors = self.extrapolation_errors_n(speed)
        live, dead = [], []
        for j, engine in enumerate(self.propulsion.engines):
            error = 0.0 if errors is None else errors[j]
            coefficients = engine.coefficients
            if np.shape(speed)[0] == 1 and all(np.ndim(coefficients[t]) == 2
                                               for t in POLY22_TERMS):
                rows = np.concatenate([coefficients[t] for t in POLY22_TERMS], axis=1)
                f0, fh, f1 = (np.stack([
                    np.broadcast_to(poly22(x * engine.throttle_scale, speed[0], _UNIT[t]),
                                    speed[0].shape) for t in POLY22_TERMS])
                    for x in (0.0, 0.5, 1.0))
                basis_a = 2.0 * (f1 - 2.0 * fh + f0)
                a_j, b_j, c_j = (scale * (rows @ basis)
                                 for basis in (basis_a, f1 - f0 - basis_a, f0))
            else:
                t0, th, t1 = (engine_thrust_n(engine, x, speed, scale) for x in (0.0, 0.5, 1.0))
                a_j = 2.0 * (t1 - 2.0 * th + t0)
                b_j, c_j = t1 - t0 - a_j, t0
            live.append((a_j, b_j, c_j + error))
            dead.append(windmilling_thrust_n(engine, speed, scale, self.density,
                                             self.propulsion.fan_area_m2))
        return live, dead

    def _excess_quadratic(self, speed: Array, dead: int | None, mode: str,
                          terms: tuple[list[tuple[Array, Array, Array]], list[Array]]
                          ) -> tuple[Array, Array, Array]:
        """Level-flight thrust excess ``a x^2 + b x + c`` [N] in throttle at each airspeed:
        the live engines' sum (a windmilling dead engine adds its drag to ``c``) less the
        drag."""
        live, windmill = terms
        a, b, c = (sum(live[j][i] for j in range(len(live)) if j != dead) for i in range(3))
        if dead is not None and mode == "windmilling":
            c = c + windmill[dead]
        if self._drag is None or self._drag[0] is not speed:  # shared by trim and OEI
            self._drag = (speed, np.asarray(
                level_flight_drag_n(self.aircraft, speed, self.density), dtype=float))
        drag = self._drag[1]
        shape = np.broadcast_shapes(np.shape(a), np.shape(c), np.shape(drag), (self.size, 1))
        return (np.broadcast_to(a, shape), np.broadcast_to(b, shape),
                np.broadcast_to(c - drag, shape))

    @staticmethod
    def _roots(a: Array, b: Array, c: Array) -> Array:
        """:func:`least_throttle_reaching` (one closed form for trim, OEI, endurance and the
        export), NaN where no throttle in [0, 1] reaches."""
        with np.errstate(invalid="ignore", divide="ignore"):
            throttle, reached = least_throttle_reaching(a, b, c)
        return np.where(np.asarray(reached) > 0.5, np.asarray(throttle, dtype=float), np.nan)

    def least_throttle(self, speed: Array, dead: int | None = None,
                       mode: str = "windmilling",
                       terms: tuple[list[tuple[Array, Array, Array]], list[Array]] | None = None
                       ) -> Array:
        """Least throttle [fraction] for level flight at each airspeed; NaN where none.

        ``terms`` reuses the engines' thrusts at these airspeeds across dead-engine cases.
        """
        terms = terms if terms is not None else self._engine_thrusts(speed)
        return self._roots(*self._excess_quadratic(speed, dead, mode, terms))

    def trim_max_throttle(self, grid: Array, candidates: Array | None = None) -> Array:
        """Highest least throttle over the envelope grid ``(1, K)`` or ``(B, K)`` [m/s]; NaN if
        any airspeed is not attainable.

        ``candidates`` (grid indices where the highest least throttle is expected, from the
        nominal case) make it cheap and leave it exact: the largest least throttle ``m`` over
        the candidates is the answer of every row whose excess at throttle ``m`` is >= 0 at
        all other airspeeds (there the least throttle is <= m); the other rows are solved at
        every airspeed. Each row's answer depends on that row alone.
        """
        above = self._flyable(grid)
        a, b, c = self._excess_quadratic(grid, None, "windmilling", self._grid_terms(grid))
        candidates = _within(candidates, grid)
        everywhere = np.all(above, axis=1)  # below stall somewhere: not attainable there
        if candidates is None:
            rows = np.arange(self.size)
            result = np.full(self.size, np.nan)
        else:
            m = np.max(self._roots(a[:, candidates], b[:, candidates], c[:, candidates]), axis=1)
            with np.errstate(invalid="ignore"):
                excess = (a * m[:, None] + b) * m[:, None] + c
            excess[:, candidates] = 0.0  # the candidates' roots are m or below, computed
            holds = np.all(excess >= 0.0, axis=1)
            # NaN at a candidate: that airspeed is not attainable, so neither is the envelope
            result = np.where(np.isnan(m) | holds, m, np.nan)
            rows = np.flatnonzero(everywhere & ~np.isnan(m) & ~holds)
        if rows.size:
            throttle = self._roots(a[rows], b[rows], c[rows])
            result[rows] = np.where(np.all(np.isfinite(throttle), axis=1),
                                    np.max(throttle, axis=1), np.nan)
        return np.where(everywhere, result, np.nan)

    def oei_min_throttle(self, grid: Array, mode: str,
                         candidates: dict[int, Array] | None = None) -> Array:
        """Worse dead engine's least throttle over the grid; NaN if one has no level flight.

        ``candidates`` per dead engine (grid indices where the least throttle is expected to
        be lowest, from the nominal case): with ``m`` the least over the attainable
        candidates, a row's answer is ``m`` when at every other airspeed above stall the
        excess is < 0 at throttle ``m`` and rising in throttle on [0, m] (so its least
        throttle is above ``m``); the other rows are solved at every airspeed.
        """
        worst = np.full(self.size, -np.inf)
        terms = self._grid_terms(grid)
        above = self._flyable(grid)
        for dead in range(len(self.propulsion.engines)):
            a, b, c = self._excess_quadratic(grid, dead, mode, terms)
            picked = None if candidates is None else _within(candidates.get(dead), grid)
            if picked is None:
                rows = np.arange(self.size)
                best = np.full(self.size, np.inf)
            else:
                roots = self._roots(a[:, picked], b[:, picked], c[:, picked])
                roots = np.where(above[:, picked] & np.isfinite(roots), roots, np.inf)
                m = np.min(roots, axis=1)
                mc = np.where(np.isfinite(m), m, 0.0)[:, None]
                with np.errstate(invalid="ignore"):
                    higher = ((((a * mc + b) * mc + c) < 0.0) & (b >= 0.0)
                              & (2.0 * a * mc + b >= 0.0))
                higher |= ~above  # below stall: no level flight to compare with
                higher[:, picked] = True
                holds = np.isfinite(m) & np.all(higher, axis=1)
                best = np.where(holds, m, np.inf)
                rows = np.flatnonzero(~holds)
            if rows.size:
                throttle = self._roots(a[rows], b[rows], c[rows])
                throttle = np.where(above[rows] & np.isfinite(throttle), throttle, np.inf)
                best[rows] = np.min(throttle, axis=1)
            worst = np.maximum(worst, best)
        return np.where(np.isfinite(worst), worst, np.nan)

    def packs_never_bind(self, grid: Array, packs: Any, battery: dict[str, Array],
                         top_throttle: Array) -> bool:
        """True when the packs change no row's answer, so the candidates' answer stands: no
        reference voltage (the thrust does not depend on the packs) and, in every row, each
        fan's greatest power over the grid and throttles in ``[0, top_throttle]`` within the
        power its packs give at the landing reserve (``pack_limits.power_limit_w``; power
        is quadratic in throttle for a surface, monotone for the fan law, so the ends and
        the vertex bound it). A row whose answer is NaN binds nothing."""
        from tuflexperf.analysis.batch_endurance import _power_w

        if self.propulsion.reference_voltage_v is not None:
            return False
        limit = power_limit_w(packs, battery)[:, None]
        top = np.nan_to_num(np.asarray(top_throttle, dtype=float)).reshape(-1, 1)
        engines = self.propulsion.engines if packs.own_surfaces else (None,)
        for engine in engines:
            p0, ph, p1 = (np.maximum(_power_w(packs, self, x, grid, engine), 0.0)
                          for x in (0.0 * top, 0.5 * top, top))
            curvature = 2.0 * (p1 - 2.0 * ph + p0)
            with np.errstate(invalid="ignore", divide="ignore"):
                vertex = np.clip(0.5 - (p1 - p0) / (2.0 * curvature), 0.0, 1.0)
            vertex = np.where(np.isfinite(vertex), vertex, 0.0)
            pv = np.maximum(_power_w(packs, self, vertex * top, grid, engine), 0.0)
            most = np.max(np.maximum(np.maximum(p0, p1), pv), axis=1, keepdims=True)
            with np.errstate(invalid="ignore"):
                if not np.all(most <= limit * (1.0 - 1e-9)):
                    return False
        return True

    def over_grid_on_packs(self, grid: Array, dead: int | None, mode: str, packs: Any,
                           battery: dict[str, Array]) -> Array:
        """Trim's highest (``dead`` None) or one dead engine's least throttle over the grid,
        flown on the packs at the landing reserve as the single case flies it
        (:func:`tuflexperf.analysis.pack_limits.level_flight_on_packs`); NaN where not
        attainable (trim: at some airspeed; OEI: at every one).

        Every airspeed of every row is solved (no candidates): where the packs bind depends
        on the power, not only on the throttle.
        """
        from tuflexperf.analysis.batch_endurance import _power_w

        prop = self.propulsion
        terms = self._grid_terms(grid)
        live = [j for j in range(len(prop.engines)) if j != dead]
        # the level-flight excess at idle; its shape is every row's grid
        idle = self._excess_quadratic(grid, dead, mode, terms)[2]
        shape = idle.shape
        flyable = np.broadcast_to(self._flyable(grid), shape)
        rows = pack_rows(packs.battery, battery)
        charge, circuit = rows.reserve_charge_ah[:, None], rows.circuit_packs[:, None]
        rating = None if rows.rating_a is None else rows.rating_a[:, None]

        def on_packs(x: Array) -> list[tuple[Array, Array, Array]]:
            engines = [prop.engines[j] if packs.own_surfaces else None for j in live]
            return [operating_point(packs.params, charge,
                                    np.maximum(_power_w(packs, self, x, grid, engine), 0.0),
                                    circuit, rows.packs_per_engine, prop.reference_voltage_v,
                                    prop.voltage_exponent) for engine in engines]

        if prop.reference_voltage_v is None:
            x = np.where(flyable, self.least_throttle(grid, dead, mode, terms), np.nan)
        else:  # the thrust follows the sagging pack: no closed form (pack_limits)
            # the excess without the live engines: the dead one's drag less the airframe's
            other = idle - sum(terms[0][j][2] for j in live)

            def excess(xs: Array) -> Array:
                total = np.broadcast_to(other, shape)
                for j, (_, _, factor) in zip(live, on_packs(xs), strict=True):
                    a_j, b_j, c_j = terms[0][j]
                    total = total + factor * ((a_j * xs + b_j) * xs + c_j)
                return total

            x = np.where(flyable, least_throttle_where(excess, shape), np.nan)
        ok = np.isfinite(x)
        for u, current, _ in on_packs(np.nan_to_num(x)):
            ok &= within_limits(u, current, rows.cutoff_v[:, None], rating)
        x = np.where(ok, x, np.nan)
        if dead is None:
            return np.where(np.all(ok, axis=1), np.max(x, axis=1), np.nan)
        least = np.min(np.where(ok, x, np.inf), axis=1)
        return np.where(np.isfinite(least), least, np.nan)

    def _grid_terms(self, grid: Array) -> tuple[list[tuple[Array, Array, Array]], list[Array]]:
        """:meth:`_engine_thrusts` on the grid, shared by trim and OEI (keyed on the object)."""
        if self._terms is None or self._terms[0] is not grid:
            self._terms = (grid, self._engine_thrusts(grid))
        return self._terms[1]

    # -- endurance ----------------------------------------------------------------------------
    def flight_endurance_min(self, model: Any, throttle: Array,
                             roll: tuple[Array, Array, Array, Array],
                             battery: dict[str, Array]) -> tuple[Array, Array, Array]:
        """Flight endurance [min] at ``throttle`` per row (see :class:`EnduranceModel`), the
        level-flight airspeed [m/s] on full packs and the launch's climb airspeed [m/s]."""
        from tuflexperf.analysis import batch_endurance

        return batch_endurance.flight_endurance_min(self, model, throttle, roll, battery)


def stall_speed(model: _Model) -> Array:
    """1-g stall speed [m/s] per row."""
    return np.asarray(stall_speed_m_s(model.aircraft, model.density), dtype=float).reshape(-1) \
        * np.ones(model.size)


def nominal_engines(propulsion: Propulsion) -> Array:
    """The nominal coefficients as ``(E, 6)`` (POLY22_TERMS order)."""
    return np.array([[e.coefficients[t] for t in POLY22_TERMS] for e in propulsion.engines])
