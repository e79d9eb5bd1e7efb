"""Endurance at a throttle: level-flight airspeed, electrical power, pack and flight time.

Paper section 4: one 12S 5000 mAh pack lasts "nearly up to 10 min" at 50 % throttle in
the tunnel at 30 m/s; with two packs per fan and the launch's energy, "a flight time of
15 minutes can be estimated". This module makes that estimate from the discharge runs:

1. **Battery**: the equivalent-circuit model of :mod:`tuflexperf.models.battery` fitted
   to all runs of the battery file (CasADi/IPOPT), and cross-validated: fitted on each
   run alone, it predicts the other runs' time to cut-off.
2. **Power**: ``P(x, V) = P_s x^n (1 - (V/V_j)^2)`` per fan, fitted to the runs' mean
   ``V I`` and the published full-throttle figure (:func:`fit_fan_power`).
3. **Level flight**: the faster root of ``T(x, V) = D(V)`` (front side of the drag
   curve), all engines at throttle ``x`` (SPEC 3).
4. **Pack endurance**: one pack on one fan at ``P(x, V)`` from full to the cut-off
   under load: ``t = 3600 * integral_0^{q_c} dq / i(q, P)`` (constant-power discharge).
5. **Flight endurance**: the mission "take off, climb to the pattern altitude, cruise at
   ``x`` until the reserve" (:func:`endurance_mission`): the full-throttle ground roll
   along the take-off's airspeed history, the full-throttle
   climb at the best rate of climb to the battery file's pattern altitude, then level
   flight at throttle ``x``, each fan on its ``n`` parallel packs at the loaded pack
   voltage, until the first fan has given ``(1 - reserve)`` of its rated capacity (the
   landing reserve) or reaches the cut-off, whichever comes first. With the propulsion
   file's ``reference_voltage_v`` thrust and power fall as the pack sags, and the cruise
   airspeed with them (SPEC 3).
   ``flight_endurance_min`` = climb + cruise time (airborne). The endurance figure is
   the case's point performance: flown at the case's density throughout.

Steps 3-5 are the batch's code on one row (:func:`.batch_endurance.flight_rows`, on
sagging packs :mod:`.batch_sagging`), the very code ``--samples`` flies on N: the fast
level-flight root, the packs' cut-off charge, the launch and the Gauss-Legendre cruise. The
mission integrator then flies the mission once at that cruise time for the flight's record,
and says why where the rows find the flight not attainable. ``--best`` solves two small
IPOPT NLPs: the throttle and airspeed of longest flight, and of longest cruise distance
(constant-power cruise, no voltage effect).

Steps 1-2 live in :mod:`.battery_fit`, the flight of step 5 as a mission in
:mod:`.endurance_plan`; this module holds :class:`EnduranceModel` and its results.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tuflexperf.analysis.airborne import obstacle_height_of
from tuflexperf.analysis.attainable import least_airspeed_m_s
from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.batch_endurance import (
    IMPOSSIBLE_FIGURE_OF_MERIT,
    EnduranceRows,
    battery_side,
    flight_rows,
    level_airspeed,
)
from tuflexperf.analysis.batch_kernels import bracketed_root, stall_speed
from tuflexperf.analysis.battery_fit import (
    RUN_POWER_TOLERANCE,
    BatteryCharacterisation,
    cached_case_battery,
    characterise_battery,
)
from tuflexperf.analysis.cache import BoundedCache, file_key, fingerprint
from tuflexperf.analysis.constants import MAX_SPEED_OVER_STALL, SPEED_GRID_POINTS
from tuflexperf.analysis.endurance_plan import LaunchBudget, endurance_mission_model, launch_of
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.battery import (
    Battery,
)
from tuflexperf.io.case import Case
from tuflexperf.models.agreement import PowerAgreement, agreement_at
from tuflexperf.models.aircraft import level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.battery import (
    current_at_power_a,
    cutoff_residual_v,
    discharge_time_s,
)
from tuflexperf.models.powertrain import PowerSurfaces, engine_power_w
from tuflexperf.models.thrust import (
    is_extrapolated,
    least_throttle_of,
    outside_tested_range,
    total_thrust_n,
    unlapsed_density_warning,
)

# Least airspeed for the --best NLPs: the usual 20 % margin over the 1-g stall speed.
BEST_MIN_AIRSPEED_OVER_STALL = 1.2
_model_cache: BoundedCache[EnduranceModel] = BoundedCache()


# --- results --------------------------------------------------------------------------------
@dataclass(frozen=True)
class EnduranceResult:
    """Endurance at one throttle (SI units; times in minutes as the SPEC's keys say)."""

    throttle: float
    airspeed_m_s: float
    electrical_power_w: float  # per fan
    battery_endurance_min: float  # one pack on one fan, full to cut-off
    flight_endurance_min: float  # climb + cruise to the landing reserve
    cruise_time_min: float
    pack_current_a: float  # one pack, full, at this power
    pack_energy_wh: float  # one pack, full to cut-off at this power
    cutoff_charge_ah: float
    cutoff_voltage_v: float  # of the packs flown (a --set of the cut-off, not the file's)
    cruise_end_charge_ah: float  # per fan (all its packs)
    cruise_ends_at: str  # "landing reserve" or "cut-off"
    engines: int
    packs_in_parallel_per_engine: int
    landing_reserve_fraction: float
    min_throttle: float
    min_throttle_airspeed_m_s: float
    extrapolated: bool
    launch: LaunchBudget
    characterisation: BatteryCharacterisation = field(repr=False)
    warnings: tuple[str, ...] = ()
    # thrust against electrical power at the cruise point, per engine (SPEC 3)
    power_agreement: tuple[PowerAgreement, ...] = ()
    power_used: dict[str, Any] = field(default_factory=dict)
    # the flight itself (take-off, climb, cruise): a MissionResult with its time history
    flight: Any = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        ch = self.characterisation
        return {
            "throttle": self.throttle,
            "airspeed_m_s": self.airspeed_m_s,
            "electrical_power_w": self.electrical_power_w,
            "total_electrical_power_w": self.electrical_power_w * self.engines,
            "battery_endurance_min": self.battery_endurance_min,
            "flight_endurance_min": self.flight_endurance_min,
            "cruise_time_min": self.cruise_time_min,
            "pack_current_a": self.pack_current_a,
            "pack_energy_wh": self.pack_energy_wh,
            "cutoff_charge_ah": self.cutoff_charge_ah,
            "cutoff_voltage_v": self.cutoff_voltage_v,
            "cruise_end_charge_ah": self.cruise_end_charge_ah,
            "cruise_ends_at": self.cruise_ends_at,
            "packs_in_parallel_per_engine": self.packs_in_parallel_per_engine,
            "landing_reserve_fraction": self.landing_reserve_fraction,
            "min_throttle": self.min_throttle,
            "min_throttle_airspeed_m_s": self.min_throttle_airspeed_m_s,
            "extrapolated": self.extrapolated,
            "launch": self.launch.to_dict(),
            "battery_fit": {
                "rms_v": ch.fit.rms_v,
                "max_abs_v": ch.fit.max_abs_v,
                "n_points": ch.fit.n_points,
                "runs": list(ch.fit.runs),
                "parameters": ch.fit.parameters.to_dict(),
            },
            "cross_validation": [c.to_dict() for c in ch.cross_validation],
            "power_model": {
                **ch.power.model.to_dict(),
                "rms_log_error": ch.power.rms_log_error,
                "points": list(ch.power.points),
            },
            "power_used": self.power_used,
            "power_agreement": [a.to_dict() for a in self.power_agreement],
            "warnings": list(self.warnings),
            # the flight as a mission (take-off, climb, cruise), segment by segment
            "flight": self.flight.to_dict() if self.flight is not None else None,
        }


@dataclass(frozen=True)
class BestResult:
    """Throttle and airspeed of the longest flight and of the longest cruise distance."""

    endurance: EnduranceResult
    range_throttle: float
    range_airspeed_m_s: float
    range_km: float
    range_flight_endurance_min: float
    # the least airspeed searched [m/s] and what sets it: an optimum held there would be
    # longer slower (the shipped case's longest flight is 0.2 % longer at 1.17 x stall)
    least_airspeed_m_s: float
    least_airspeed_is: str

    def held_at_least_airspeed(self, airspeed_m_s: float) -> bool:
        """Whether an optimum at ``airspeed_m_s`` [m/s] sits on the least airspeed searched."""
        return airspeed_m_s <= self.least_airspeed_m_s * (1.0 + 1e-6)

    def to_dict(self) -> dict[str, Any]:
        return {
            "best_endurance": {
                "throttle": self.endurance.throttle,
                "airspeed_m_s": self.endurance.airspeed_m_s,
                "electrical_power_w": self.endurance.electrical_power_w,
                "battery_endurance_min": self.endurance.battery_endurance_min,
                "flight_endurance_min": self.endurance.flight_endurance_min,
                "held_at_least_airspeed": self.held_at_least_airspeed(
                    self.endurance.airspeed_m_s),
            },
            "best_range": {
                "throttle": self.range_throttle,
                "airspeed_m_s": self.range_airspeed_m_s,
                "cruise_range_km": self.range_km,
                "flight_endurance_min": self.range_flight_endurance_min,
                "held_at_least_airspeed": self.held_at_least_airspeed(self.range_airspeed_m_s),
            },
            "least_airspeed_m_s": self.least_airspeed_m_s,
            "least_airspeed_is": self.least_airspeed_is,
        }


# --- the model, built once per case + battery ------------------------------------------------
class EnduranceModel:
    """The endurance of one case at any throttle: its battery, least throttle, mission and
    the batch's rows of the case (build once)."""

    def __init__(self, case: Case, battery: Battery) -> None:
        self.case, self.battery = case, battery
        self.ch = characterise_battery(battery, case)
        # the packs' circuit and the power model (the propulsion file's fitted surfaces where
        # every engine has one, SPEC 4, else the battery file's fan-power law), as the
        # batch's rows fly them
        self._side = battery_side(case)
        self.params, self.power = self._side.params, self._side.power
        self.run_checks = self._check_runs(battery)
        aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3
        self.packs = battery.circuit_packs
        # "one pack on one fan" is one pack of the battery's capacity (a scaled one flies as
        # that share of the measured pack's circuit)
        one = self.packs / battery.packs_in_parallel_per_engine
        self.cutoff_v = battery.cutoff_voltage_v
        self.stall_m_s = float(stall_speed_m_s(aircraft, rho))
        # level flight only counts at or above stall x the envelope's margin (SPEC 3)
        self.least_m_s = least_airspeed_m_s(case)
        # Cruise ends when each pack has given (1 - reserve) of its rated capacity.
        usable = 1.0 - battery.landing_reserve_fraction
        self.reserve_ah = battery.packs_in_parallel_per_engine * battery.capacity_ah * usable
        self.min_throttle, self.min_throttle_airspeed = self._least_throttle()
        # the flight: take-off, climb, cruise at a throttle, flown by the mission integrator
        self.mission = self._planned_mission(case, battery)
        self._cruise = len(self.mission.plans) - 1
        self._launch: LaunchBudget | None = None  # from the first flight flown

        def excess(x: Any, v: Any) -> Any:
            return total_thrust_n(propulsion, x, v, rho) - level_flight_drag_n(aircraft, v, rho)

        self.excess = excess
        self._one = one
        # the flight itself: the batch's code on a batch of one row (batch_endurance)
        self._batch = BatchEvaluator(case, blocks=frozenset({"endurance"}))
        self._rows_of: dict[int, tuple[Any, dict[str, np.ndarray], Any, dict[Any, Any]]] = {}
        self._nlp: dict[str, Any] = {}

    # -- the discharge runs against the power and thrust models (SPEC 3) ---------------------
    def run_powers(self, battery: Battery | None = None) -> list[tuple[Any, Any, float, float,
                                                                      float, float]]:
        """Each discharge run against the power model: (run, its engine, throttle [-],
        airspeed [m/s], measured mean ``V I`` under load [W], the model's power there [W]),
        the model being the run's own fan's surface as fitted (test day, as measured), else
        the battery file's fan-power law."""
        battery = self.battery if battery is None else battery
        engines = {e.name: e for e in self.case.propulsion.engines}
        surfaces = isinstance(self.power, PowerSurfaces)
        rows = []
        for ref, run in zip(battery.runs, self.ch.runs, strict=True):
            x, v, measured = run.throttle_setting, run.airspeed_setting_m_s, run.mean_power_w
            engine = engines.get(ref.engine or "", self.case.propulsion.engines[0])
            modelled = float(
                engine_power_w(engine, x, v) if surfaces else self.power.electrical_power_w(x, v)
            )
            rows.append((run, engine, float(x), float(v), float(measured), modelled))
        return rows

    def _check_runs(self, battery: Battery) -> tuple[str, ...]:
        """Warnings where a discharge run's measured power or force disagrees with the models.

        Each run's mean ``V I`` under load is compared with the power model at the run's
        throttle and airspeed (at the test day's density, as measured); more than
        :data:`RUN_POWER_TOLERANCE` apart is a warning naming the run. The run's mean force
        (thrust less the rig's drag, a lower bound on thrust) against its power goes
        through the thrust/power agreement check. Both read the battery file's ``fit.runs``
        (parameters only: no run is opened, issue 43 item 2); the case flown on the measured
        power is the reading of :mod:`tuflexperf.analysis.power_reading`.
        """
        from tuflexperf.models.agreement import power_agreement

        warnings: list[str] = []
        rho_ref = self.case.propulsion.reference_density_kg_m3
        for (run, engine, x, v, measured, modelled) in self.run_powers(battery):
            if abs(modelled - measured) > RUN_POWER_TOLERANCE * measured:
                warnings.append(
                    f"{battery.path.name} fit.runs: {run.path.name}: measured {measured:.0f} W "
                    f"at throttle {x:.2f}, "
                    f"{v:.1f} m/s; the power model used here gives {modelled:.0f} W "
                    f"({100 * (modelled / measured - 1):+.0f} %): thrust and power data disagree"
                )
            force = run.mean_force_n
            check = power_agreement(
                run.path.name, engine.name, x, v, force, measured,
                rho_ref if rho_ref is not None else self.case.density_kg_m3,
                self.case.propulsion.fan_area_m2,
            )
            warnings.extend(check.warnings)
        warnings.extend(battery.scaled_notes)
        return tuple(warnings)

    def _planned_mission(self, case: Case, battery: Battery) -> Any:
        """The endurance mission, its cruise planned at a throttle that holds level flight.

        Each solve flies the cruise at its own throttle; the plan only needs one whose level
        flight exists short of the fans' jet velocity: half throttle where it flies, else full,
        else throttles ever nearer the least one (whose airspeed lies short of it).
        """
        low = self.min_throttle
        candidates = [0.5] if low < 0.5 - 1e-9 else []
        if math.isfinite(low):
            candidates += [low + (1.0 - low) * share for share in (1.0, 0.5, 0.2, 0.05)]
        else:
            candidates.append(1.0)
        failures: list[NotAttainable] = []
        for throttle in candidates:
            try:
                return endurance_mission_model(case, battery, throttle)
            except NotAttainable as exc:
                failures.append(exc)
        if len({str(f) for f in failures}) == 1:  # the launch, whatever the cruise
            raise failures[0]
        tried = ", ".join(f"{x:.3g}" for x in candidates)
        raise NotAttainable(f"{failures[-1]} (the cruise planned at throttle {tried} in turn)",
                            failures[-1].known)

    # -- least throttle for level flight (closed form per airspeed, numpy) -------------------
    def _least_throttle(self) -> tuple[float, float]:
        """Least throttle (all engines) holding level flight at some speed >= stall (and short of
        the fans' jet velocity), and that speed.

        The required throttle at each airspeed is the exact least root of the quadratic
        excess (:func:`least_throttle_of`, the one least-throttle solver), evaluated on a grid
        and then on five successively 50x finer grids around the best point (six vectorised
        calls, about 1e-9 m/s). ``inf`` when no throttle in [0, 1] flies.
        """
        case = self.case
        aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3

        def required(v: np.ndarray) -> np.ndarray:
            drag = np.asarray(level_flight_drag_n(aircraft, v, rho), dtype=float)
            with np.errstate(invalid="ignore", divide="ignore"):
                throttle, reached = least_throttle_of(
                    lambda x: np.asarray(total_thrust_n(propulsion, x, v, rho), dtype=float) - drag
                )
            return np.where(np.asarray(reached) > 0.5, np.asarray(throttle, dtype=float), np.inf)

        from tuflexperf.models.powertrain import jet_velocity_ceiling_m_s

        # short of the fans' jet velocity: beyond it a fan makes no thrust
        ceiling = float(jet_velocity_ceiling_m_s(propulsion, rho))
        speeds = np.linspace(self.least_m_s, MAX_SPEED_OVER_STALL * self.stall_m_s,
                             SPEED_GRID_POINTS)
        for _ in range(6):
            values = np.where(speeds < ceiling, required(speeds), np.inf)
            k = int(np.argmin(values))
            if not np.isfinite(values[k]):
                return math.inf, math.nan
            best = (float(values[k]), float(speeds[k]))
            speeds = np.linspace(speeds[max(k - 1, 0)], speeds[min(k + 1, speeds.size - 1)], 101)
        return best

    def check_throttle(self, throttle: float) -> None:
        """Raise :class:`NotAttainable` if ``throttle`` cannot hold level flight."""
        if not math.isfinite(self.min_throttle):
            raise NotAttainable("no throttle up to full holds level flight at any airspeed")
        if throttle < self.min_throttle - 1e-9:
            raise NotAttainable(
                f"throttle {throttle:g} is below {self.min_throttle:.5g}, the least throttle "
                f"that holds level flight (at {self.min_throttle_airspeed:.1f} m/s)"
            )

    def _launched(self, size: int) -> tuple[Any, dict[str, np.ndarray], Any, dict[Any, Any]]:
        """``size`` rows of the case as given: their physics, battery keys, take-off and
        launches (the same for every throttle, so solved once per size)."""
        if size not in self._rows_of:
            batch, values = self._batch, {}
            m = batch.model(values, size)
            battery = batch._battery_rows(values, size)
            height = np.full(size, obstacle_height_of(self.case))
            self._rows_of[size] = (m, battery, batch.launch(m, size, height, battery), {})
        return self._rows_of[size]

    def rows(self, throttle: np.ndarray) -> EnduranceRows:
        """The endurance flight at each ``throttle`` [-] (the batch's code, one row per
        throttle of the case as given: :func:`.batch_endurance.flight_rows`)."""
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            m, battery, launch, launches = self._launched(int(np.size(throttle)))
            return flight_rows(m, self._side, np.asarray(throttle, dtype=float).reshape(-1),
                               launch, battery, launches)

    @property
    def launch(self) -> LaunchBudget:
        """The take-off and climb to the pattern altitude of the endurance mission."""
        if self._launch is None:
            self._launch = launch_of(self.mission)
        return self._launch

    def level_airspeed_m_s(self, throttle: float) -> float:
        """The level-flight (front side) airspeed [m/s] at ``throttle`` [-], without flying."""
        self.check_throttle(throttle)
        m = self._launched(1)[0]
        speed, ok = level_airspeed(m, np.array([float(throttle)]), stall_speed(m))
        if not ok[0]:
            raise NotAttainable(f"throttle {throttle:g}: no level flight")
        return float(speed[0])

    def solve(self, throttle: float) -> EnduranceResult:
        """Endurance at ``throttle`` (fraction, all engines)."""
        self.check_throttle(throttle)
        row = self.rows(np.array([throttle]))
        speed, power_w = float(row.airspeed_m_s[0]), float(row.power_w[0])
        params, cutoff = self.params, self.cutoff_v
        if not (speed > 0.0 and cutoff_residual_v(params, 0.0, power_w, cutoff, self.packs) > 0):
            raise NotAttainable(
                f"throttle {throttle:g}: the pack is below its cut-off voltage at "
                f"{power_w:.0f} W per fan from the start"
            )
        # one pack alone is the figure of the battery, not of the flight: a fan flies on its
        # packs in parallel, which may hold a power one of them cannot (a full-throttle
        # flight on two 2.5 Ah packs per fan was "not attainable"; outside audit)
        q1 = t1 = 0.0
        if cutoff_residual_v(params, 0.0, power_w, cutoff, self._one) > 0:
            pole = np.array([self._one * params.max_capacity_ah * (1.0 - 1e-12)])
            q1 = float(bracketed_root(
                lambda q: np.asarray(cutoff_residual_v(params, q, power_w, cutoff, self._one),
                                     dtype=float), np.zeros(1), pole)[0])
            t1 = float(discharge_time_s(params, power_w, 0.0, q1, self._one))
        if not (row.level[0] and math.isfinite(row.minutes[0])):
            # not attainable: the mission integrator (the same rules) and the result's checks
            # say why
            flight, cruise_s, ends_at = self._why_not(throttle, speed)
            self._result(throttle, speed, power_w, q1, t1, flight,
                         (cruise_s + self.launch.climb_time_s) / 60.0, cruise_s / 60.0, ends_at)
            raise NotAttainable(f"throttle {throttle:g}: the endurance flight is not attainable")
        cruise_s = float(row.cruise_s[0])
        ends_at = "cut-off" if row.cut_first[0] else "landing reserve"
        flight = self._flown(throttle, speed, cruise_s)
        if not flight.attainable:
            raise NotAttainable(f"throttle {throttle:g}: {flight.reason}")
        return self._result(throttle, speed, power_w, q1, t1, flight,
                            float(row.minutes[0]), cruise_s / 60.0, ends_at,
                            float(row.end_charge_ah[0]))

    def _flown(self, throttle: float, speed: float, cruise_s: float) -> Any:
        """The endurance mission flown with the cruise ``cruise_s`` [s] long at ``throttle``:
        the flight's record (segments, time history)."""
        model = self.mission
        theta = model.theta.copy()
        theta[3 * self._cruise:3 * self._cruise + 3] = (throttle, 0.0, speed)
        durations = model.durations.copy()
        durations[self._cruise] = cruise_s
        flight = model.fly(durations, theta=theta)
        if self._launch is None and flight.attainable:
            self._launch = launch_of(model, flight)
        return flight

    def _why_not(self, throttle: float, speed: float) -> tuple[Any, float, str]:
        """The endurance mission at ``throttle`` flown to the reserve (or cut-off) by the
        mission integrator, raising :class:`NotAttainable` with its reason (see
        :meth:`MissionModel.longest`): where the flight is not attainable, why."""
        model = self.mission
        theta = model.theta.copy()
        theta[3 * self._cruise:3 * self._cruise + 3] = (throttle, 0.0, speed)
        durations = model.durations.copy()
        try:
            cruise_s, ends_at = model.longest(self._cruise, durations, theta)
        except NotAttainable as exc:
            raise NotAttainable(
                f"throttle {throttle:g}: the launch leaves no cruise before the landing reserve "
                f"or the cut-off ({exc})"
            ) from None
        durations[self._cruise] = cruise_s
        flight = model.fly(durations, theta=theta)
        if not flight.attainable:
            raise NotAttainable(f"throttle {throttle:g}: {flight.reason}")
        return flight, cruise_s, ends_at

    def _result(
        self, throttle: float, speed: float, power_w: float, q1: float, t1: float,
        flight: Any, flight_min: float, cruise_min: float, ends_at: str,
        cruise_end_ah: float = math.nan,
    ) -> EnduranceResult:
        warnings: list[str] = []
        propulsion = self.case.propulsion
        low, high = propulsion.tested_airspeed_m_s
        extrapolated = is_extrapolated(propulsion, speed)
        if extrapolated:
            warnings.append(
                f"level-flight airspeed {speed:.1f} m/s is outside the thrust model's tested "
                f"range {low:g}-{high:g} m/s (extrapolated)"
            )
        # the launch and the climb fly the thrust model as well (a roll from rest below a
        # tested range that starts at 15 m/s was not said; outside audit)
        launch = flight.history["airspeed_m_s"][flight.history["segment"] != self._cruise]
        launch = launch[outside_tested_range(propulsion, launch)]
        if launch.size:
            extrapolated = True
            warnings.append(
                f"the launch and climb fly {launch.min():.1f}-{launch.max():.1f} m/s, outside "
                f"the thrust model's tested range {low:g}-{high:g} m/s (extrapolated)"
            )
        envelope = self.case.requirements.envelope
        bounds = envelope.bounds_m_s(self.case.density_kg_m3) if envelope is not None else None
        if bounds is not None and not bounds[0] - 1e-9 <= speed <= bounds[1] + 1e-9:
            warnings.append(
                f"level-flight airspeed {speed:.1f} m/s is outside the envelope "
                f"{bounds[0]:g}-{bounds[1]:g} m/s"
            )
        density_note = unlapsed_density_warning(self.case.propulsion, self.case.density_kg_m3)
        if density_note:
            warnings.append(density_note)
        agreement = agreement_at(
            f"endurance at throttle {throttle:.2f}", self.case.propulsion, throttle, speed,
            self.case.density_kg_m3, power_w,
        )
        warnings.extend(w for a in agreement for w in a.warnings)
        impossible = [a for a in agreement if a.figure_of_merit is not None
                      and a.figure_of_merit > IMPOSSIBLE_FIGURE_OF_MERIT]
        if impossible:
            # a figure of merit above 1 is a warning (SPEC 3: thrust the power cannot make);
            # far above it the power model is no fan's, and an endurance flown on it is no
            # answer (a surface at 1 mW "flew" 2e7 min; outside audit)
            a = impossible[0]
            raise NotAttainable(
                f"throttle {throttle:g}: {a.engine}'s power model gives {a.electrical_power_w:.0f}"
                f" W at {speed:.1f} m/s, under 1/{IMPOSSIBLE_FIGURE_OF_MERIT:g} of the "
                f"{a.ideal_power_w:.0f} W that momentum theory needs for its {a.thrust_n:.1f} N "
                f"(figure of merit {a.figure_of_merit:.3g}): no fan flies on it"
            )
        warnings.extend(self.run_checks)
        if q1 <= 0.0:
            warnings.append(
                f"one pack alone is below its cut-off voltage at {power_w:.0f} W from the "
                f"start (its figures are 0); the {self.battery.packs_in_parallel_per_engine} "
                "packs in parallel per fan hold it"
            )
        u_ref = self.case.propulsion.reference_voltage_v
        if u_ref is not None:  # the flight's own airspeed and power, sagging with the pack
            a, b = self.mission.bounds[self._cruise]
            hist = flight.history
            v = hist["airspeed_m_s"][a:b]
            p = np.max([hist[f"power_w_{name}"][a:b] for name in flight.engines], axis=0)
            warnings.append(
                f"pack-voltage effect (reference {u_ref:g} V): over the cruise the airspeed goes "
                f"{v[0]:.2f} -> {v[-1]:.2f} m/s and the power per fan {p[0]:.0f} -> "
                f"{p[-1]:.0f} W; the airspeed, power and one-pack figures above are at "
                f"{u_ref:g} V, the flight time is flown with the sag"
            )
        if ends_at == "cut-off" and flight is not None and flight.attainable:
            # the charge left at the cut-off is not the landing reserve: the packs no longer
            # hold the cruise's power (outside audit: "lands with 33.7 %, reserve 20 %")
            left = (f"the cruise ends at the packs' cut-off with "
                    f"{100 * flight.landing_charge_fraction:.1f} % of the charge left (reserve "
                    f"{100 * flight.min_landing_charge_fraction:g} %), which the packs do not "
                    "give at the cruise's power: the reserve is charge, not power")
            flight = replace(flight, reason=left)
            warnings.append(left)
        return EnduranceResult(
            throttle=throttle,
            airspeed_m_s=speed,
            electrical_power_w=power_w,
            battery_endurance_min=t1 / 60.0,
            flight_endurance_min=flight_min,
            cruise_time_min=cruise_min,
            # NaN (null in JSON) where one pack cannot give the power at all
            pack_current_a=(float(current_at_power_a(self.params, 0.0, power_w, self._one))
                            if q1 > 0.0 else math.nan),
            pack_energy_wh=power_w * t1 / 3600.0,
            cutoff_charge_ah=q1,
            cutoff_voltage_v=self.cutoff_v,
            cruise_end_charge_ah=cruise_end_ah,
            cruise_ends_at=ends_at,
            engines=len(self.case.propulsion.engines),
            packs_in_parallel_per_engine=self.battery.packs_in_parallel_per_engine,
            landing_reserve_fraction=self.battery.landing_reserve_fraction,
            min_throttle=self.min_throttle,
            min_throttle_airspeed_m_s=self.min_throttle_airspeed,
            extrapolated=extrapolated,
            launch=self.launch,
            characterisation=self.ch,
            warnings=tuple(warnings),
            power_agreement=agreement,
            power_used=self.power.to_dict(),
            flight=flight,
        )

    # -- best endurance and best range (IPOPT) ----------------------------------------------
    def _best_solver(self, objective: str) -> Any:
        """NLP over ``(x, V, q_end)``: maximise flight time or cruise distance.

        Constraints: level flight ``T(x, V) = D(V)``; front side ``dE/dV <= 0``;
        ``V >= 1.2 V_stall``; cruise ends before the cut-off (``residual(q_end) >= 0``)
        and the landing reserve; ``0 <= x <= 1``.
        """
        if objective in self._nlp:
            return self._nlp[objective]
        import casadi as ca

        w = ca.SX.sym("w", 3)
        x, v, q_end = w[0], w[1], w[2]
        sym = self.params
        e = self.excess(x, v)
        pw = self.power.electrical_power_w(x, v)
        q_launch = self.launch.charge_ah
        cruise_s = discharge_time_s(sym, pw, q_launch, q_end, self.packs)
        if objective == "endurance":
            f = -(cruise_s + self.launch.climb_time_s) / 60.0
        else:
            f = -v * cruise_s / 1000.0
        g = ca.vertcat(e, ca.jacobian(e, v), cutoff_residual_v(sym, q_end, pw, self.cutoff_v,
                                                                 self.packs))
        solver = ca.nlpsol(
            f"best_{objective}",
            "ipopt",
            {"x": w, "f": f, "g": g},
            {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-10},
        )
        self._nlp[objective] = solver
        return solver

    def _solve_best(self, objective: str, start: EnduranceResult) -> tuple[float, float, float]:
        solver = self._best_solver(objective)
        q_launch = self.launch.charge_ah
        v_low, v_high = self.best_airspeed_bounds()
        lbx = [max(self.min_throttle - 1e-6, 0.0), v_low, q_launch]
        ubx = [1.0, v_high, self.reserve_ah]
        x0 = [start.throttle, start.airspeed_m_s, start.cruise_end_charge_ah]
        sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=[0.0, -np.inf, 0.0], ubg=[0.0, 0.0, np.inf])
        status = solver.stats()["return_status"]
        if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
            raise NotAttainable(f"best {objective}: the optimiser did not converge ({status})")
        w = np.asarray(sol["x"]).ravel()
        return float(w[0]), float(w[1]), float(-sol["f"])

    def best_airspeed_bounds(self) -> tuple[float, float]:
        """Airspeed range (m/s) for ``--best``: the case's envelope, never below 1.2 V_stall."""
        low = BEST_MIN_AIRSPEED_OVER_STALL * self.stall_m_s
        high = MAX_SPEED_OVER_STALL * self.stall_m_s
        envelope = self.case.requirements.envelope
        if envelope is not None:
            least, greatest = envelope.bounds_m_s(self.case.density_kg_m3)
            low, high = max(low, least), greatest
        if not low < high:
            raise NotAttainable(
                f"no airspeed for --best: the envelope ends at {high:g} m/s, below 1.2 x stall "
                f"speed {low:.1f} m/s"
            )
        return low, high

    def best(self) -> BestResult:
        """Throttle/airspeed of the longest flight, and of the longest cruise distance."""
        self.check_throttle(1.0)
        middle = min(1.0, self.min_throttle + 0.5 * (1.0 - self.min_throttle))
        try:
            start = self.solve(middle)
        except NotAttainable as exc:  # it named a throttle no one asked for (outside audit)
            raise NotAttainable(
                f"no best endurance: its search starts halfway from the least level-flight "
                f"throttle {self.min_throttle:.3f} to full, and there {exc}") from None
        x_e, _, _ = self._solve_best("endurance", start)
        endurance = self.solve(min(max(x_e, self.min_throttle), 1.0))
        x_r, _, range_km = self._solve_best("range", start)
        at_range = self.solve(min(max(x_r, self.min_throttle), 1.0))
        v_low, _ = self.best_airspeed_bounds()
        stall_bound = BEST_MIN_AIRSPEED_OVER_STALL * self.stall_m_s
        return BestResult(
            endurance=endurance,
            range_throttle=at_range.throttle,
            range_airspeed_m_s=at_range.airspeed_m_s,
            range_km=range_km,
            range_flight_endurance_min=at_range.flight_endurance_min,
            least_airspeed_m_s=v_low,
            least_airspeed_is=(f"{BEST_MIN_AIRSPEED_OVER_STALL:g} x stall"
                               if v_low == stall_bound else "the envelope's least airspeed"),
        )


def endurance_model(case: Case) -> EnduranceModel:
    """The case's endurance model, built once and cached (case contents + battery files)."""
    if case.battery_path is None:
        raise InputError(
            f"{case.path}: battery: the case names no battery file; endurance needs one"
        )
    battery = cached_case_battery(case)
    key = fingerprint(
        case.aircraft,
        case.propulsion,
        case.density_kg_m3,
        least_airspeed_m_s(case),  # the stall margin bounds level flight
        battery,
        [file_key(r.path) for r in battery.runs],
    )
    return _model_cache.get(key, lambda: EnduranceModel(case, battery))


def solve_endurance(case: Case, throttle: float) -> EnduranceResult:
    """Level-flight airspeed, electrical power and endurance at ``throttle`` for ``case``.

    Raises :class:`InputError` (naming the case file) when the case has no battery or
    the throttle is not a fraction, and :class:`NotAttainable` with the reason when the
    throttle cannot hold level flight.
    """
    if not (isinstance(throttle, (int, float)) and math.isfinite(throttle)
            and 0.0 <= throttle <= 1.0):
        raise InputError(f"throttle: must be a fraction in [0, 1], got {throttle!r}")
    return endurance_model(case).solve(float(throttle))


def solve_best(case: Case) -> BestResult:
    """Throttle and airspeed of the longest flight and of the longest cruise range."""
    return endurance_model(case).best()
