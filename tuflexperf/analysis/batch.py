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
[N per m/s] added times the distance beyond the tested airspeed range (SPEC 4, uncertainty
block).
``tests/verification/test_batch_equals_deterministic.py`` holds this module to the
deterministic analyses.

This module holds the requirements' registry of the batch and :class:`BatchEvaluator`;
the rows' physics is :class:`~tuflexperf.analysis.batch_model.BatchModel`, its take-off
:mod:`.ground_roll`, the helpers they share :mod:`.batch_kernels`.

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
from tuflexperf.analysis.batch_kernels import fan_power_rows
from tuflexperf.analysis.batch_model import BatchModel, SharedRows
from tuflexperf.analysis.cache import ByObject
from tuflexperf.analysis.level_flight import airspeed_grid, airspeed_grids
from tuflexperf.analysis.model_form_mean import centres_model_form, residual_surfaces
from tuflexperf.analysis.pack_limits import (
    pack_rows,
    pack_side,
    power_limit_w,
    sagging_packs,
)
from tuflexperf.analysis.verdict import requirement_met
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    EAS_REFERENCE_DENSITY_KG_M3,
    MAX_AIRSPEED_M_S,
    Aircraft,
    stall_speed_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    Propulsion,
    density_ratio,
    engine_thrust_n,
    outside_tested_range,
    outside_tested_span,
)

Array = NDArray[np.float64]
_CANDIDATE_HALF_WIDTH = 3  # grid points each side of the nominal's extreme tried first
# the roll's quadrature nodes and weights on [0, 1] (composite, as _integrate places them)


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
    # where readings of disputed evidence bear on a requirement (analysis.batch_readings):
    # ``values`` are then the worse reading's, ``reading_values`` each reading's ("nominal"
    # first) and ``disputed`` the rows met on some reading but not on another (UNPROVEN)
    reading_values: dict[str, dict[str, Array]] = field(default_factory=dict)
    disputed: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    # the airspeed a requirement is flown at, where it has one [m/s] (the endurance's cruise)
    airspeeds: dict[str, Array] = field(default_factory=dict)

    def met(self, name: str) -> NDArray[np.bool_]:
        """Met per sample, by the verdict rule of :mod:`tuflexperf.analysis.verdict`."""
        return requirement_met(self.values[name], self.limits[name], self.kinds[name])


_IMPLAUSIBLE: ByObject[Any] = ByObject()


def _implausible(case: Case) -> Any:
    """:func:`~tuflexperf.analysis.plausibility.implausible` of ``case``, once per case object
    (a case's evaluators for other blocks, e.g. its endurance's batch of one, ask again)."""
    from tuflexperf.analysis.plausibility import implausible

    return _IMPLAUSIBLE.get(case, lambda: implausible(case))


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

    def __init__(self, case: Case, blocks: frozenset[str] | None = None) -> None:
        self.case = case
        # ``blocks``: only these requirement blocks (a reading's case evaluates the ones it
        # bears on; analysis.batch_readings)
        self.requirements = [r for r in present_requirements(case)
                             if blocks is None or r.block in blocks]
        self.implausible = _implausible(case)
        self._side: Any = None
        if case.battery_path is not None:
            self._side = pack_side(case)  # the plausibility rule's packs (cached fit)
        if any(r.block == "oei" for r in self.requirements):
            # as solve_oei refuses it (the sweep tabulated "not attainable" for every point)
            from tuflexperf.analysis.oei import refuse_one_engine

            refuse_one_engine(case)
        self._endurance: Any = None
        if any(r.block == "endurance" for r in self.requirements):
            from tuflexperf.analysis.batch_endurance import battery_side

            self._endurance = battery_side(case)
        # trim and OEI are flown on the packs as the single case flies them (pack_limits)
        self._packs: Any = None
        if self.requirements or case.requirements.mission is not None or (
                blocks is not None and "endurance" in blocks):  # the endurance of one case
            self._packs = pack_side(case)
        self._identity: tuple[str, str] | None = None

    @property
    def thrust_identity(self) -> tuple[str, str]:
        """What the case's thrust reads (:func:`~tuflexperf.analysis.readings.thrust_identity`)."""
        if self._identity is None:
            from tuflexperf.analysis.readings import thrust_identity

            self._identity = thrust_identity(self.case)
        return self._identity

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
        # each term's rows contiguous (not a view striding the (E, B, 6) draws): every thrust
        # of the batch reads them, ~40 % quicker so
        # drawn about the fit's residual surface: each row adds its mean (error_model)
        surfaces = (residual_surfaces(base) if centres_model_form(self.case)
                    else (None,) * len(base.engines))
        engines = tuple(
            dataclasses.replace(
                engine,
                coefficients={t: np.ascontiguousarray(coefficients[j, :, i])[:, None]
                              for i, t in enumerate(POLY22_TERMS)},
                thrust_offset=surfaces[j],
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
        power_scale: Array | None = None,
        shared: dict[Any, Any] | None = None,
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
            Thrust error [N per m/s] per engine and sample, added times the distance
            beyond the tested airspeed range [m/s].
        power_scale : array ``(B,)``, optional
            Factor [-] per sample on every fan's electrical power (the error model's).
        shared : dict, optional
            The results of these rows on another reading of the case that read only the
            thrust (:class:`~tuflexperf.analysis.batch_model.SharedRows`): taken where
            this case's thrust is that reading's, and added to.

        Returns
        -------
        BatchResult
            NaN where a requirement is not attainable for that parameter set.
        """
        # a row far outside the models (a pack drained far below its cut-off, a 1e300 kg
        # mass) may overflow on its way to NaN, "not attainable": numpy's warnings about it
        # would only clutter stderr (margins and sweeps; samples said so already)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return self._evaluate(values, size, coefficients, extrapolation_n, power_scale,
                                  shared)

    def model(self, values: Mapping[str, Array], size: int,
              coefficients: Array | None = None, extrapolation_n: Array | None = None,
              power_scale: Array | None = None,
              shared: dict[Any, Any] | None = None) -> BatchModel:
        """The physics of ``size`` rows of ``values`` (absent keys nominal; as
        :meth:`evaluate`'s arguments)."""
        return BatchModel(
            aircraft=self._aircraft(values, size),
            propulsion=self._propulsion(coefficients),
            density=self._density(values, size),
            extrapolation_n=extrapolation_n,
            size=size,
            stall_margin=_column(values, "requirements.envelope.stall_margin",
                                 stall_margin_of(self.case), size),
            power_scale=None if power_scale is None else np.asarray(power_scale, dtype=float),
            shared=None if shared is None else SharedRows(shared, *self.thrust_identity),
        )

    def _evaluate(self, values: Mapping[str, Array] | None, size: int | None,
                  coefficients: Array | None, extrapolation_n: Array | None,
                  power_scale: Array | None = None,
                  shared: dict[Any, Any] | None = None) -> BatchResult:
        values = dict(values or {})
        if size is None:
            if values:
                size = int(np.asarray(next(iter(values.values()))).size)
            elif coefficients is not None:
                size = int(coefficients.shape[1])
            else:
                size = 1
        model = self.model(values, size, coefficients, extrapolation_n, power_scale, shared)
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

        def launched() -> tuple[Array, Array, Array, Array]:
            return self.launch(model, size, height, battery)

        beyond: dict[str, NDArray[np.bool_]] = {}
        airspeeds: dict[str, Array] = {}
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
                if self._packs is not None:
                    value = _on_packs_where_they_bind(model, grid, self._packs, battery, value,
                                                      (None,), "windmilling")
                out[requirement.name] = np.where(unflown, np.nan, value)
            elif requirement.block == "oei":
                mode = self.case.requirements.oei.dead_engine
                value = model.oei_min_throttle(grid, mode, self._candidates()[1])
                if self._packs is not None:
                    value = _on_packs_where_they_bind(
                        model, grid, self._packs, battery, value,
                        tuple(range(len(self.case.propulsion.engines))), mode,
                        top=np.ones(size))
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
                airspeeds[requirement.name] = np.asarray(speed, dtype=float).reshape(-1)
                # the roll and the climb fly the thrust model too, as the single case's
                # mission (a catapult's release is no node of it): a roll from rest below
                # the tested range was not said
                flown = (speed, climb) if catapult else (launch[2], speed, climb)
                beyond[requirement.name] = np.asarray(outside_tested_span(
                    propulsion, *flown_span(*flown, from_rest=not catapult)), dtype=bool)
        self._refuse_implausible(out, battery, size)
        return BatchResult(
            values=out,
            limits=limits,
            kinds={r.name: r.kind for r in self.requirements},
            units={r.name: r.unit for r in self.requirements},
            refused=self.rows_refused(values, size, coefficients),
            without_envelope=unflown,
            extrapolated=beyond,
            airspeeds=airspeeds,
        )

    def launch(self, model: BatchModel, size: int, height: Any, battery: dict[str, Array]
               ) -> tuple[Array, Array, Array, Array]:
        """The take-off's roll tuple per row (:meth:`.GroundRollRows.ground_roll`): a
        runway's roll or a catapult's release, on the sagging packs where the propulsion
        has a reference voltage (then ``model.packs_roll``/``packs_air`` hold its history
        and airborne part), attainable only within the packs. ``height`` the obstacle [m],
        ``battery`` the rows' battery keys (:meth:`_battery_rows`)."""
        catapult = self.case.aircraft.launch == "catapult"
        # a catapult's "roll" is its release: no runway (SPEC 4), as solve_takeoff; the
        # packs give full throttle over it (GroundRollRows.launch_on_packs)
        found = model.catapult_release() if catapult else model.ground_roll()
        if self._packs is not None and sagging_packs(self.case):
            # rolled on the packs' loaded voltage, as solve_takeoff rolls
            from tuflexperf.analysis import batch_takeoff_packs as packs_takeoff

            rows = pack_rows(self._packs.battery, battery)
            if catapult:
                model.release = packs_takeoff.release_on_packs(model, self._packs, rows)
                model.packs_roll = packs_takeoff.RollOnPacks(
                    *found, np.zeros((size, 1)), model.release[2])
            else:
                model.packs_roll = packs_takeoff.roll_on_packs(model, self._packs, rows)
            model.packs_airborne, model.packs_beyond, model.packs_air = \
                packs_takeoff.airborne_on_packs(model, self._packs, rows, model.packs_roll,
                                                height)
            found = model.packs_roll.as_roll()
        elif catapult:
            model.release = model.release_run()
        if catapult:  # one that does not accelerate to the arc's speed never gets there
            found = (*found[:3], np.where(model.release[3], found[3], 0.0))
        if self._packs is None:
            return found
        within = model.launch_within_packs(found, height, catapult, self._packs, battery)
        return found[0], found[1], found[2], np.where(within, found[3], 0.0)

    def _refuse_implausible(self, out: dict[str, Array], battery: dict[str, Array],
                            size: int) -> None:
        """NaN (not met) where the data are what physics forbids (issue 43 item 3, the
        registry's FAIL): the momentum rule as the nominal case's scan (the rows vary no
        thrust or power surface), the packs' rated C per row of the capacity."""
        from tuflexperf.analysis.plausibility import rating_rows

        bad = {name: np.zeros(size, dtype=bool) for name in out}
        for f in self.implausible:
            if f.rule == "battery_rating" and battery:
                continue  # judged per row below
            for requirement in self.requirements:
                if requirement.block in f.blocks:
                    bad[requirement.name] |= True
        if battery and self._side is not None:
            rows = rating_rows(self.case, self._side, battery["battery.capacity_ah"])
            for requirement in self.requirements:
                bad[requirement.name] |= rows.reshape(-1) * np.ones(size, dtype=bool)
        for name, mask in bad.items():
            out[name] = np.where(mask, np.nan, out[name])

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
        model = BatchModel(aircraft=self._aircraft({}, 1), propulsion=self._propulsion(None),
                       density=self._density({}, 1), extrapolation_n=None, size=1,
                       stall_margin=stall_margin_of(self.case))

        def beside(index: int) -> Array:
            near = np.arange(index - _CANDIDATE_HALF_WIDTH, index + _CANDIDATE_HALF_WIDTH + 1)
            # sorted(set()), not np.unique: numpy >= 2.3's unique imports numpy.ma (~20 ms)
            return np.array(sorted({int(i) for i in np.clip(np.concatenate([near, [0, last]]),
                                                                0, last)}), dtype=np.intp)

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




def _on_packs_where_they_bind(model: BatchModel, grid: Array, packs: Any,
                              battery: dict[str, Array], value: Array,
                              dead: tuple[int | None, ...], mode: str,
                              top: Array | None = None) -> Array:
    """``value`` with the rows the packs may bind (:meth:`BatchModel.rows_packs_may_bind`)
    flown on the packs: trim (``dead`` (None,)) or the worse dead engine's least throttle;
    the other rows' answer stands (their packs change nothing), so only the rows that need
    the slower solution take it (the error model's spread puts a few rows near the packs'
    limit, where the whole batch took it)."""
    top = value if top is None else top
    # rows a bound shared by all shows free first; the row-by-row test on the others alone
    unsure = np.flatnonzero(~rows_surely_never_bind(model, grid, packs, battery, top))
    if not unsure.size:
        return value
    asked = model if unsure.size == model.size else model.rows(unsure)
    pick = grid if np.shape(grid)[0] != model.size or unsure.size == model.size \
        else grid[unsure]
    theirs = {k: v[unsure] if np.ndim(v) and np.shape(v)[0] == model.size else v
              for k, v in battery.items()}
    rows = unsure[asked.rows_packs_may_bind(pick, packs, theirs,
                                            np.asarray(top, dtype=float)[unsure]
                                            if np.ndim(top) else top)]
    if not rows.size:
        return value
    some = model if rows.size == model.size else model.rows(rows)
    part = grid if np.shape(grid)[0] != model.size or rows.size == model.size else grid[rows]
    own = {k: v[rows] if np.ndim(v) and np.shape(v)[0] == model.size else v
           for k, v in battery.items()}
    worst = np.full(rows.size, -np.inf)
    for engine in dead:
        worst = np.maximum(worst, some.over_grid_on_packs(part, engine, mode, packs, own))
    out = np.array(value, dtype=float, copy=True)
    out[rows] = worst
    return out


_SURE_MARGIN = 1e-6
"""Relative slack of :func:`packs_surely_never_bind`'s bound: far above its rounding."""


def packs_surely_never_bind(model: BatchModel, grid: Array, packs: Any,
                            battery: dict[str, Array], top_throttle: Array) -> bool:
    """True when one bound shared by every row already shows what
    ``BatchModel.packs_never_bind`` would find row by row (:func:`rows_surely_never_bind`
    in every row)."""
    return bool(np.all(rows_surely_never_bind(model, grid, packs, battery, top_throttle)))


def rows_surely_never_bind(model: BatchModel, grid: Array, packs: Any,
                           battery: dict[str, Array], top_throttle: Array) -> NDArray[np.bool_]:
    """Per row, True where one bound shared by every row already shows what
    ``BatchModel.rows_packs_may_bind`` would find: each fan's power [W] over the grid and
    throttles in ``[0, max top_throttle]`` at the batch's densest air, times the row's
    sampled power scale, within the row's pack power limit. False means "not sure" (ask the
    row-by-row test), so the answer is the same, for a fraction of its work on ``(B, K)``
    arrays.

    The per-fan power scales with ``rho / rho_ref`` (a positive factor, rising with the
    density) on a surface shared by the rows (nominal power coefficients); the maximum of a
    quadratic in throttle over ``[0, T]`` is at the ends or the vertex, and ``[0, T]``
    holds every row's ``[0, top]``.
    """
    unsure = np.zeros(model.size, dtype=bool)
    if model.propulsion.reference_voltage_v is not None or np.shape(grid)[0] != 1:
        return unsure
    limit = np.asarray(power_limit_w(packs, battery), dtype=float)
    tops = np.nan_to_num(np.asarray(top_throttle, dtype=float))
    if tops.size == 0 or float(np.min(tops)) < 0.0:  # a throttle below idle: row by row
        return unsure
    top = float(np.max(tops))
    densest = float(np.max(np.asarray(model.density, dtype=float)))
    if not (limit.size and np.isfinite(densest) and densest > 0.0 and np.isfinite(top)):
        return unsure
    shared = _DensestAir(model.propulsion, densest)
    scale = getattr(model, "power_scale", None)
    scale = np.ones(model.size) if scale is None else np.asarray(scale, dtype=float)
    engines = model.propulsion.engines if packs.own_surfaces else (None,)
    sure = np.ones(model.size, dtype=bool)
    for engine in engines:
        p0, ph, p1 = (np.asarray(fan_power_rows(packs, shared, x, grid, engine), dtype=float)
                      for x in (0.0, 0.5 * top, top))
        curvature = 2.0 * (p1 - 2.0 * ph + p0)
        with np.errstate(invalid="ignore", divide="ignore"):
            vertex = np.clip(0.5 - (p1 - p0) / (2.0 * curvature), 0.0, 1.0)
        vertex = np.where(np.isfinite(vertex), vertex, 0.0)
        pv = np.asarray(fan_power_rows(packs, shared, vertex * top, grid, engine), dtype=float)
        most = float(np.max(np.maximum(np.maximum(p0, p1), np.maximum(pv, 0.0))))
        if not np.isfinite(most):
            return unsure
        with np.errstate(invalid="ignore"):
            sure &= (most * scale * (1.0 + _SURE_MARGIN) + _SURE_MARGIN
                     <= limit * (1.0 - 1e-9))
    return sure


@dataclass(frozen=True)
class _DensestAir:
    """The rows' propulsion at one density [kg/m^3], for :func:`fan_power_rows`."""

    propulsion: Propulsion
    density: float
