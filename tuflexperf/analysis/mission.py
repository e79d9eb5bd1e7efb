"""Fly a mission: segments in order from a full battery, with each engine on its own packs.

Equations (SPEC 3, 4; every symbol SI; ``h`` height above the airfield, ``V`` true airspeed
``= EAS sqrt(1.225 / rho(h))``, ``rho`` the ISA density at field elevation + ``h`` with the
case's temperature offset):

- thrust of a live engine ``T_i = sigma T_poly22(x, V) f_i`` with ``sigma = rho / rho_ref``
  (1 without a reference density) and the voltage effect ``f_i = (U_i / U_ref)^k``
  (``k = voltage_exponent``; ``f_i = 1`` without ``reference_voltage_v``); a dead engine adds
  the SPEC's windmilling drag (``oei.dead_engine`` of the case, default windmilling).
- electrical power of a live engine: its own power surface ``sigma P_poly22(x, V)`` when the
  propulsion file gives one for every engine, else the battery file's fan-power law; times
  ``(U_i / U_ref)^(1.5 k)`` with a reference voltage (fan laws: thrust ~ rpm^2, power ~ rpm^3).
- pack current from the power at the terminals, ``U(q, i) i = P`` (the smaller root, see
  :func:`tuflexperf.models.battery.current_at_power_a`), loaded voltage
  ``U = OCV(q/n) - (R/n) i`` with the fitted equivalent circuit of the battery file,
  ``n`` packs in parallel per engine; ``dq_i/dt = i / 3600`` [Ah/s]. With a reference
  voltage the loaded voltage is implicit (power depends on it): solved exactly at every
  RK4 stage by unrolled Newton steps (:data:`NEWTON`).
- climb and descent with ``L = W`` (small angle): rate of climb ``(T - D) V / W``; a segment
  flown at a climb (descent) rate needs ``T = D + W RC / V``; level flight ``T = D``.
  The throttle that gives a needed thrust is the least root of the quadratic in ``x``
  (:func:`tuflexperf.models.thrust.least_throttle_reaching`), solved at every RK4 stage.
  A cruise or loiter at a fixed ``throttle`` flies the fast root of ``T(x, V) = D(V)``
  (Newton with the loaded voltages from the full-pack airspeed): its airspeed falls as
  the packs sag, and below stall it is not attainable.
- take-off: the ground roll from rest at full throttle along the take-off analysis's own
  airspeed history (``m dV/dt = T - D_g - mu max(W - L_g, 0)``, solved by CVODES there:
  flown in time, the charge's rate is smooth where the net force all but vanishes), the
  rotation at ``V_LO``, then the landed take-off analysis's airborne part flown along the
  path at the transition speed: the arc ``h = R (1 - cos(V t / R))`` and the straight climb
  at the full-throttle gradient to the obstacle height (the path's airspeeds are the
  analysis's, which flies on the packs' loaded voltage where the propulsion has a reference
  voltage: the roll's airspeed history is the sagging packs' own).

Each segment is integrated by classic RK4 with :data:`STEPS` fixed steps (over time for
level segments and the take-off, over height for climbs and descents, so their end is
exact without an event), all segments chained into ONE CasADi function of the durations
and the segment settings (throttle, EAS), built once per case and mission. ``solve_for``
makes one segment's duration the unknown and solves "landing charge fraction = reserve"
(or, if the pack cuts off first, "loaded voltage at the segment's end = cut-off"): Newton
with the state equations' own slope for the last segment, regula falsi otherwise, each step
one integration from where that segment begins (no derivative propagation). A cut-off
inside a timed segment is located between two nodes by bisection, and the flight ends
there (segments after it are not flown).

References
----------
Raymer, *Aircraft Design*, 5th ed., 17.2-17.3 (climb, level flight); Anderson, *Aircraft
Performance and Design*, 5.10 (rate of climb); Tremblay & Dessaint (2009) (battery model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.analysis.airborne import ROTATION_STEPS
from tuflexperf.analysis.constants import (
    BURST_OVER_CONTINUOUS,
    RATING_SEGMENT_S,
    SECONDS_PER_HOUR,
    STEPS,
)
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.io.mission import MissionFile, SegmentSchema
from tuflexperf.models.aircraft import (
    MAX_AIRSPEED_M_S,
    climb_sine,
    level_flight_drag_n,
    stall_speed_eas_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.battery import (
    current_at_power_a,
    first_window_beyond,
    open_circuit_voltage_v,
)
from tuflexperf.models.powertrain import (
    beyond_jet_velocity,
    jet_velocity_ceiling_m_s,
    static_jet_velocity_m_s,
)
from tuflexperf.models.thrust import (
    density_ratio,
    engine_thrust_n,
    least_throttle_reaching,
    outside_tested_range,
    total_thrust_n,
    windmilling_thrust_n,
)

ARC_STEPS = 64  # the take-off's transition arc (see MissionModel._airborne_phases)
# unrolled Newton steps on the loaded voltage (and a fixed throttle's airspeed): from the
# open-circuit voltage (a few % off) quadratic convergence reaches rounding in 4; 5 for margin
NEWTON = 5
_P_SIZE = 10  # per-step parameters, see MissionModel._step_functions


@dataclass(frozen=True)
class SegmentResult:
    """One flown segment (SI units; per-engine lists in the propulsion file's order)."""

    index: int
    type: str
    time_s: float
    distance_m: float
    start_altitude_m: float
    end_altitude_m: float
    airspeed_eas_m_s: float | None
    charge_ah: tuple[float, ...]
    energy_wh: tuple[float, ...]
    min_voltage_v: float
    max_throttle: float | None
    dead_engine: str | None

    @property
    def throttle_margin(self) -> float | None:
        """Least ``1 - throttle`` over the segment (``None`` where no engine runs)."""
        return None if self.max_throttle is None else 1.0 - self.max_throttle

    def to_dict(self) -> dict[str, Any]:
        return {
            "type": self.type,
            "index": self.index,
            "time_s": self.time_s,
            "time_min": self.time_s / 60.0,
            "distance_m": self.distance_m,
            "start_altitude_m": self.start_altitude_m,
            "altitude_m": self.end_altitude_m,
            "airspeed_eas_m_s": self.airspeed_eas_m_s,
            "charge_ah": sum(self.charge_ah),
            "charge_ah_per_engine": list(self.charge_ah),
            "energy_wh": sum(self.energy_wh),
            "energy_wh_per_engine": list(self.energy_wh),
            "min_voltage_v": self.min_voltage_v,
            "max_throttle": self.max_throttle,
            "min_throttle_margin": self.throttle_margin,
            "dead_engine": self.dead_engine,
        }


@dataclass(frozen=True)
class MissionResult:
    """A flown mission: per-segment results, the landing charge and the time history.

    ``history`` (one value per integration node, in time order; a flight that ended early
    stops at its event) holds ``time_s`` [s], ``segment`` (index into ``segments``),
    ``altitude_m`` [m above the field], ``distance_m`` [m flown], ``airspeed_m_s`` (true)
    and ``airspeed_eas_m_s`` [m/s], ``throttle`` [-], ``climb_rate_m_s`` [m/s], and per
    engine ``current_a_<name>`` [A], ``voltage_v_<name>`` (loaded, [V]),
    ``charge_ah_<name>`` (drawn, [Ah]), ``charge_fraction_<name>`` (left, [-]),
    ``power_w_<name>`` [W] and ``energy_wh_<name>`` (drawn, [Wh]). A dead engine's current
    and power are 0, its voltage the open-circuit value.
    """

    name: str
    segments: tuple[SegmentResult, ...]
    landing_charge_fraction: float
    min_landing_charge_fraction: float
    attainable: bool
    reason: str
    engines: tuple[str, ...]
    history: dict[str, np.ndarray] = field(repr=False)
    solved: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()
    # when the flight ended early (cut-off, not attainable): the time of that event [s]
    ended_at_s: float | None = None
    # the packs' cut-off voltage [V] flown to (a --set of it, not the battery file's)
    cutoff_voltage_v: float | None = None

    @property
    def passed(self) -> bool:
        """Every verdict of the flight holds (:func:`~tuflexperf.analysis.requirements.
        mission_verdicts`: the landing charge, and with ``solve_for`` the file's own time)."""
        from tuflexperf.analysis.verdict import mission_verdicts

        return all(v.passed for v in mission_verdicts(self))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mission": self.name,
            "passed": self.passed,
            "attainable": self.attainable,
            "reason": self.reason,
            "landing_charge_fraction": self.landing_charge_fraction,
            "min_landing_charge_fraction": self.min_landing_charge_fraction,
            "total_time_min": float(self.history["time_s"][-1]) / 60.0,
            "engines": list(self.engines),
            "segments": [s.to_dict() for s in self.segments],
            "warnings": list(self.warnings),
        }
        if self.solved is not None:
            out["solved"] = self.solved
        if self.ended_at_s is not None:
            out["ended_at_s"] = self.ended_at_s
        return out


@dataclass(frozen=True)
class _Plan:
    """A segment's static data, fixed at build time."""

    index: int
    type: str
    kind: str  # "time", "height", "takeoff" or "event"
    start_h: float
    end_h: float
    eas: float | None
    solve_x: bool
    throttle: float
    rate: float  # commanded rate of climb [m/s] (negative: descent)
    rate_from_excess: bool
    duration_s: float
    dead: int | None
    solve_v: bool = False  # level at a fixed throttle: the airspeed is solved
    v_guess: float = 0.0  # true airspeed [m/s] of that level flight with full packs


class MissionModel:
    """The whole mission as one CasADi function of the durations (built once)."""

    def __init__(self, case: Case, mission: MissionFile, min_landing_fraction: float | None,
                 *, fixed_density_kg_m3: float | None = None,
                 takeoff_to_obstacle: bool = True, battery: Any = None) -> None:
        from tuflexperf.analysis.battery_fit import characterise_battery
        from tuflexperf.io.battery import case_battery

        if case.battery_path is None:
            raise InputError(f"{case.path}: battery: a mission needs the case's battery file")
        self.case, self.mission = case, mission
        if battery is None:  # the caller may hand over the battery it flies already
            battery = case_battery(case)
        self.battery = battery
        ch = characterise_battery(battery, case)
        self.params = ch.fit.parameters
        self.fan_power = ch.power.model
        # the circuit's packs: the file's, or as many measured packs as a changed capacity
        # makes (models.battery.equivalent_packs); ratings and charge count the battery's own
        self.packs = battery.circuit_packs
        self.capacity_ah = battery.capacity_ah * battery.packs_in_parallel_per_engine
        self.cutoff_v = battery.cutoff_voltage_v
        self.reserve = (
            battery.landing_reserve_fraction if min_landing_fraction is None
            else min_landing_fraction
        )
        prop = case.propulsion
        self.engines = tuple(e.name for e in prop.engines)
        self.n = len(self.engines)
        self.field_m = case.atmosphere.altitude_m
        self.dt_k = case.atmosphere.temperature_offset_k
        oei = case.requirements.oei
        self.dead_mode = oei.dead_engine if oei is not None else "windmilling"
        self.own_power = all(e.power_coefficients is not None for e in prop.engines)
        # the endurance figure is the case's point performance: flown at the case's density
        self.fixed_density = fixed_density_kg_m3
        self.takeoff_to_obstacle = takeoff_to_obstacle
        self._instants: dict[Any, Any] = {}
        self._suffixes: dict[int, Any] = {}
        self.plans = self._plan(mission.segments)
        # a plan may well start in the air (a segment flown on its own), but the launch's
        # charge is then not counted and the engineer should know it
        starts_airborne = not mission.segments or mission.segments[0].type != "takeoff"
        self.start_notes: tuple[str, ...] = (
            (f"mission {mission.name!r} has no takeoff segment: it starts airborne over the "
             "field with full packs, the take-off's charge not counted (add {type: takeoff} "
             "first to fly it)",) if starts_airborne else ())
        self._takeoff_speeds: dict[int, np.ndarray] = {}
        self._build()

    # -- static plan ---------------------------------------------------------------------
    def _plan(self, segments: tuple[SegmentSchema, ...]) -> tuple[_Plan, ...]:
        plans: list[_Plan] = []
        h, dead = 0.0, None
        stall_eas = float(stall_speed_eas_m_s(self.case.aircraft))
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        where = f"{self.mission.path}: segments"
        i = 0
        try:
            for i, s in enumerate(segments):
                label = f"segment {i + 1} ({s.type})"
                if s.type == "engine_failure":
                    if s.engine not in self.engines:
                        raise InputError(
                            f"{where}[{i}].engine: {s.engine!r} is not an engine of the propulsion "
                            f"file ({', '.join(self.engines)})"
                        )
                    if dead is not None:  # SPEC 3: one engine inoperative, not two
                        raise InputError(
                            f"{where}[{i}]: a second engine_failure ({s.engine}): "
                            f"{self.engines[dead]} has already failed and the SPEC's OEI rule "
                            "flies on one engine inoperative"
                        )
                    if self.n < 2:
                        raise InputError(f"{where}[{i}]: engine_failure on a single-engine "
                                         "aircraft leaves no engine to fly on")
                    dead = self.engines.index(s.engine)
                    plans.append(_Plan(i, s.type, "event", h, h, None, False, 0.0, 0.0, False, 0.0,
                                       dead))
                    continue
                if s.type == "takeoff":
                    if i != 0:
                        raise InputError(f"{where}[{i}]: takeoff must be the first segment")
                    from tuflexperf.analysis.airborne import obstacle_height_of

                    if self.case.aircraft.launch == "catapult":  # airborne at release, 0 m
                        from tuflexperf.analysis.takeoff import solve_takeoff

                        try:  # the catapult must give the mass its release speed
                            solve_takeoff(self.case)
                        except NotAttainable as exc:
                            raise NotAttainable(f"{label}: {exc}") from None
                        plans.append(_Plan(i, s.type, "event", 0.0, 0.0, None, False, 0.0, 0.0,
                                           False, 0.0, dead))
                        continue
                    # the take-off ends over the obstacle (or, for the endurance launch, at
                    # the lift-off: its climb starts from the runway)
                    h = obstacle_height_of(self.case) if self.takeoff_to_obstacle else 0.0
                    plans.append(_Plan(i, s.type, "takeoff", 0.0, h, None, False, 1.0, 0.0,
                                       False, 0.0, dead))
                    continue
                if s.type in ("cruise", "loiter") and s.throttle is not None:
                    # level at a fixed throttle: the airspeed follows (the fast root)
                    v_guess = self._level_speed_at_throttle(s.throttle, h, dead, label)
                    plans.append(_Plan(i, s.type, "time", h, h, None, False, s.throttle, 0.0,
                                       False, 60.0 * float(s.time_min), dead,  # type: ignore[arg-type]
                                       True, v_guess))
                    continue
                eas = (s.airspeed_m_s if s.airspeed_m_s is not None
                       else self._best_endurance_eas(h, dead))
                if eas < margin * stall_eas * (1 - 1e-12):
                    raise NotAttainable(
                        f"{label}: {eas:.1f} m/s EAS is below stall ({margin:g} x "
                        f"{stall_eas:.1f} m/s EAS): not attainable, below stall"
                    )
                if s.type in ("climb", "descent"):
                    target = float(s.to_altitude_m)  # type: ignore[arg-type]
                    # a descent to its own height is no descent, as a climb to it is no climb
                    if not (target > h if s.type == "climb" else target < h):
                        raise InputError(
                            f"{where}[{i}].to_altitude_m: a {s.type} from {h:g} m must go "
                            f"{'up' if s.type == 'climb' else 'down'}, got {target:g} m"
                        )
                    if s.throttle is not None:
                        plans.append(_Plan(i, s.type, "height", h, target, eas, False, s.throttle,
                                           0.0, True, 0.0, dead))
                    else:
                        rate = s.climb_rate_m_s if s.type == "climb" else -s.descent_rate_m_s
                        plans.append(_Plan(i, s.type, "height", h, target, eas, True, 0.0,
                                           float(rate), False, 0.0, dead))
                    h = target
                    continue
                # cruise / loiter: level at constant height
                if s.time_min is not None:
                    duration = 60.0 * s.time_min
                else:
                    v_true = float(true_airspeed_m_s(eas, self._rho(h)))
                    duration = 1000.0 * s.distance_km / v_true  # type: ignore[operator]
                plans.append(_Plan(i, s.type, "time", h, h, eas, True, 0.0, 0.0, False, duration,
                                   dead))
        except NotAttainable as exc:
            # the segments before it can still be flown (solve_mission reports them)
            exc.segment_index = i  # type: ignore[attr-defined]
            raise
        return tuple(plans)

    def _rho(self, h: Any) -> Any:
        if self.fixed_density is not None:
            return self.fixed_density + 0.0 * h
        # the nodes of a segment after its failure hold no flight (a climb that cannot climb
        # integrates to -4.5e6 m there): the ISA's stratosphere branch overflows on them,
        # harmlessly, as only the nodes before the failure are reported
        with np.errstate(over="ignore"):
            return isa_density_kg_m3(self.field_m + h, self.dt_k)

    def _level_speed_at_throttle(self, throttle: float, h: float, dead: int | None,
                                 label: str) -> float:
        """Fastest true airspeed [m/s] of level flight at ``throttle`` short of the fans' jet
        velocity (full packs, no sag)."""
        aircraft, prop = self.case.aircraft, self.case.propulsion
        rho = float(self._rho(h))
        stall = float(stall_speed_eas_m_s(aircraft)) * math.sqrt(1.225 / rho)
        ceiling = float(jet_velocity_ceiling_m_s(prop, rho))

        def excess(speed: Any) -> Any:
            return np.asarray(total_thrust_n(prop, throttle, speed, rho, dead, self.dead_mode)
                              - level_flight_drag_n(aircraft, speed, rho), dtype=float)

        # up to 8 x stall, further while the throttle still flies level at the top (a large
        # cl_max puts the stall far below the cruise), to the jet velocity or Mach 1 at most
        top = 8.0 * stall
        limit = max(top, min(ceiling, MAX_AIRSPEED_M_S))
        while top < limit and float(excess(top)) >= 0.0:
            top = min(2.0 * top, limit)
        v = np.linspace(0.5 * stall, top, 4001)
        # the fast root short of the jet velocity: past it a fan makes no thrust, so the
        # extrapolated polynomial's rise there (a near-zero cd0) is no level flight
        ok = np.flatnonzero((excess(v) >= 0) & (v < ceiling))
        if not ok.size or ok[-1] == v.size - 1:
            raise NotAttainable(f"{label}: throttle {throttle:g} holds level flight at no "
                                "airspeed")
        low, high = float(v[ok[-1]]), float(v[ok[-1] + 1])
        for _ in range(60):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if excess(mid) >= 0 else (low, mid)
        if high >= ceiling:
            raise NotAttainable(
                f"{label}: throttle {throttle:g} flies level only at or beyond the fans' static "
                f"jet velocity {ceiling:.1f} m/s, where they make no thrust (the thrust model "
                "is extrapolated there): not attainable")
        return 0.5 * (low + high)

    def _best_endurance_eas(self, h: float, dead: int | None = None) -> float:
        """EAS of least electrical power in level flight at height ``h`` (full packs).

        With a ``dead`` engine (after an engine failure) on the live engines alone, the dead
        one windmilling (or not) as in flight.
        """
        aircraft = self.case.aircraft
        rho = float(self._rho(h))
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        stall = margin * float(stall_speed_eas_m_s(aircraft))
        eas = np.linspace(stall, 4.0 * stall, 2001)

        def power_at(speeds_eas: np.ndarray) -> np.ndarray:
            v = np.asarray(true_airspeed_m_s(speeds_eas, rho), dtype=float)
            x, ok = self._level_throttle_numpy(v, rho, dead)
            return np.where(ok, self._power_numpy(x, v, rho, dead), np.inf)

        power = power_at(eas)
        k = int(np.argmin(power))
        if not np.isfinite(power[k]):
            raise NotAttainable(f"loiter at {h:g} m: no level flight up to full throttle")
        if k == 0 or k == eas.size - 1:
            return float(eas[k])
        # the grid's best point is up to half a step off the minimum: golden section on
        # its neighbours (the power is smooth and unimodal there) to 1e-9 m/s
        low, high = float(eas[k - 1]), float(eas[k + 1])
        ratio = 0.5 * (math.sqrt(5.0) - 1.0)
        a, b = high - ratio * (high - low), low + ratio * (high - low)
        f_a, f_b = power_at(np.array([a, b]))
        while high - low > 1e-9:
            if f_a <= f_b:
                high, b, f_b = b, a, f_a
                a = high - ratio * (high - low)
                f_a = float(power_at(np.array([a]))[0])
            else:
                low, a, f_a = a, b, f_b
                b = low + ratio * (high - low)
                f_b = float(power_at(np.array([b]))[0])
        return 0.5 * (low + high)

    def _level_throttle_numpy(self, v: np.ndarray, rho: float, dead: int | None = None
                              ) -> tuple[np.ndarray, np.ndarray]:
        prop = self.case.propulsion
        t = [np.asarray(total_thrust_n(prop, x, v, rho, dead, self.dead_mode), dtype=float)
             for x in (0.0, 0.5, 1.0)]
        a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
        b = t[2] - t[0] - a
        c = t[0] - np.asarray(level_flight_drag_n(self.case.aircraft, v, rho), dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            x, reached = least_throttle_reaching(a, b, c)
        return np.asarray(x, dtype=float), np.asarray(reached) > 0.5

    def _power_numpy(self, x: np.ndarray, v: np.ndarray, rho: float, dead: int | None = None
                     ) -> np.ndarray:
        total = sum(np.asarray(self._engine_power(i, x, v, rho), dtype=float)
                    for i in range(self.n) if i != dead)
        return np.asarray(total, dtype=float)

    # -- physics at one instant (backend-neutral) -----------------------------------------
    def _modelled_power(self, i: int, x: Any, v: Any, rho: Any) -> Any:
        """Engine ``i``'s electrical power [W] as its model gives it (may be negative)."""
        from tuflexperf.models.powertrain import engine_power_w

        prop = self.case.propulsion
        if self.own_power:
            return density_ratio(prop, rho) * engine_power_w(prop.engines[i], x, v)
        return self.fan_power.electrical_power_w(x, v)

    def _engine_power(self, i: int, x: Any, v: Any, rho: Any) -> Any:
        from tuflexperf.models._math import fmax

        # an ESC draws, it does not charge: the power surface extrapolated to idle at high
        # airspeed dips below zero, which "charged" the pack past its circuit (a dive failed
        # on a cut-off it never reached)
        return fmax(self._modelled_power(i, x, v, rho), 0.0)

    def _algebra(self, u: list[Any], v: Any, q: Any, rho: Any, plan_p: Any,
                 dead: int | None) -> dict[str, Any]:
        """Everything at loaded pack voltages ``u`` [V] and true airspeed ``v`` [m/s].

        ``plan_p = [solve_x, throttle, rate, rate_from_excess]``. Without a reference
        voltage ``u`` is ignored and the current is the closed-form constant-power root.
        """
        import casadi as ca

        prop, aircraft = self.case.propulsion, self.case.aircraft
        solve_x, x_fixed, rate_cmd, from_excess = plan_p[0], plan_p[1], plan_p[2], plan_p[3]
        sigma = density_ratio(prop, rho)
        weight = aircraft.weight_n
        drag = level_flight_drag_n(aircraft, v, rho)
        u_ref, k_exp = prop.reference_voltage_v, prop.voltage_exponent
        live = [i for i in range(self.n) if i != dead]
        # windmilling (or zero) dead engine: a drag independent of the throttle
        dead_t: Any = 0.0
        if dead is not None and self.dead_mode == "windmilling":
            dead_t = windmilling_thrust_n(prop.engines[dead], v, sigma, rho, prop.fan_area_m2)
        factor = [(u[i] / u_ref) ** k_exp if u_ref is not None else 1.0 for i in range(self.n)]
        t = [sum(factor[i] * engine_thrust_n(prop.engines[i], xs, v, sigma) for i in live)
             for xs in (0.0, 0.5, 1.0)]
        a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
        b = t[2] - t[0] - a
        needed = drag + weight * rate_cmd / v - dead_t
        x_solved, reached = least_throttle_reaching(a, b, t[0] - needed)
        x = ca.if_else(solve_x > 0.5, x_solved, x_fixed)
        thrust = a * x * x + b * x + t[0] + dead_t
        r = self.params.resistance_ohm / self.packs
        power, current, volt, residual = [], [], [], []
        for i in range(self.n):
            ocv = open_circuit_voltage_v(self.params, q[i], self.packs)
            if i == dead:
                power.append(0.0 * x)
                current.append(0.0 * x)
                volt.append(ocv)
                residual.append(u[i] - ocv)
                continue
            p_i = self._engine_power(i, x, v, rho)
            if u_ref is None:
                i_i = current_at_power_a(self.params, q[i], p_i, self.packs)
                residual.append(u[i] - (ocv - r * i_i))
            else:
                # fan laws: power ~ rpm^3 while thrust ~ rpm^2 (SPEC 3 voltage effect)
                p_i = p_i * (u[i] / u_ref) ** (1.5 * k_exp)
                i_i = p_i / u[i]
                residual.append(ocv - r * i_i - u[i])
            power.append(p_i)
            current.append(i_i)
            volt.append(ocv - r * i_i)
        rate = ca.if_else(from_excess > 0.5, climb_sine((thrust - drag) / weight) * v, rate_cmd)
        ok = ca.if_else(solve_x > 0.5, reached, 1.0)
        # thrust at idle beyond what a commanded descent needs: it cannot be flown that steep
        idle_excess = ca.if_else(solve_x > 0.5, t[0] - needed, 0.0)
        return {"x": x, "rate": rate, "reached": ok, "idle_excess": idle_excess,
                "power": power, "current": current, "voltage": volt, "v": v,
                "u_residual": residual, "level_residual": (thrust - drag) / weight,
                "thrust": thrust}

    def _instant_function(self, dead: int | None, solve_v: bool) -> Any:
        """``(q, v_in, rho, p) -> aux`` with the loaded voltages (and airspeed) solved.

        With a reference voltage the loaded voltage ``U = OCV - (R/n) P(U) / U`` is implicit
        (power follows the voltage); with ``solve_v`` the true airspeed of level flight at the
        fixed throttle is unknown too (the fast root, from the guess ``v_in``). Both are
        solved by :data:`NEWTON` unrolled Newton steps (quadratic convergence from the
        open-circuit voltage and the full-pack airspeed: machine precision).
        """
        import casadi as ca

        key = (dead, solve_v)
        if key in self._instants:
            return self._instants[key]
        n = self.n
        q = ca.SX.sym("q", n)
        v_in, rho = ca.SX.sym("v_in"), ca.SX.sym("rho")
        p = ca.SX.sym("p", 4)
        voltage_unknown = self.case.propulsion.reference_voltage_v is not None
        ocv = [open_circuit_voltage_v(self.params, q[i], self.packs) for i in range(n)]
        m = (n if voltage_unknown else 0) + (1 if solve_v else 0)
        z = ca.SX.sym("z", m)

        def split(zz: Any) -> tuple[list[Any], Any]:
            u = [zz[i] for i in range(n)] if voltage_unknown else ocv
            return u, (zz[m - 1] if solve_v else v_in)

        def equations(zz: Any) -> Any:
            u, v = split(zz)
            alg = self._algebra(u, v, q, rho, p, dead)
            parts = list(alg["u_residual"]) if voltage_unknown else []
            if solve_v:
                parts.append(alg["level_residual"])
            return ca.vertcat(*parts)

        if m:
            res = equations(z)
            newton = ca.Function("newton_step", [z, q, v_in, rho, p],
                                 [z - ca.solve(ca.jacobian(res, z), res)])
            start = ca.vertcat(*(ocv if voltage_unknown else []), *([v_in] if solve_v else []))
            zk = start
            # without the voltage effect a fixed throttle's airspeed does not change along
            # the segment: the guess is the root already (to ~1e-15), one step polishes it
            for _ in range(NEWTON if voltage_unknown else 1):
                zk = newton(zk, q, v_in, rho, p)
            u, v = split(zk)
        else:
            u, v = ocv, v_in
        alg = self._algebra(u, v, q, rho, p, dead)
        out = ca.vertcat(alg["x"], alg["v"], alg["rate"], alg["reached"], alg["idle_excess"],
                         alg["level_residual"], *alg["current"], *alg["voltage"],
                         *alg["power"], alg["thrust"])
        f = ca.Function(f"instant_{dead}_{int(solve_v)}", [q, v_in, rho, p], [out])
        self._instants[key] = f
        return f

    # -- the CasADi build -----------------------------------------------------------------
    def _stepper(self, dead: int | None, solve_v: bool, kind: str) -> Any:
        """One step function of :meth:`_step_functions`, built the first time it is asked for.

        A segment uses one or two of the four (a cruise only ``time`` and ``aux``), so the
        others are never built (each is a few milliseconds of symbolic construction).
        """
        key = (dead, solve_v, kind)
        if key not in self._steps:
            self._steps[key] = self._step_functions(dead, solve_v, kind)
        return self._steps[key]

    def _step_functions(self, dead: int | None, solve_v: bool, kind: str) -> Any:
        """RK4 step ``(state, step, p) -> state`` over ``kind`` (time, height), or the aux.

        A forced phase (the take-off's roll, rotation and path to the obstacle) is flown in
        time at the airspeeds the take-off analysis gives (``p[6:9]``: at the step's start,
        middle and end); the packs' state, current and power follow at their loaded voltage.
        """
        import casadi as ca

        n = self.n
        ns = 2 * n + 3  # q_i, e_i, h, distance, t
        s = ca.SX.sym("s", ns)
        # p: solve_x, x, rate, from_excess, eas, forced, v0, vmid, v1, v_guess
        p = ca.SX.sym("p", _P_SIZE)
        step = ca.SX.sym("step")
        instant = self._instant_function(dead, solve_v)

        def evaluate(state: Any, v_given: Any) -> Any:
            rho = self._rho(state[2 * n])
            v_free = p[9] if solve_v else true_airspeed_m_s(p[4], rho)
            v_in = ca.if_else(p[5] > 0.5, v_given, v_free)
            a = instant(state[:n], v_in, rho, p[:4])
            # a forced phase (the take-off) has its height rate given
            return ca.vertcat(a[:2], ca.if_else(p[5] > 0.5, p[2], a[2]), a[3:])

        def rates(state: Any, v_given: Any) -> tuple[Any, Any]:
            a = evaluate(state, v_given)
            d = ca.vertcat(a[6:6 + n] / SECONDS_PER_HOUR, a[6 + 2 * n:6 + 3 * n]
                           / SECONDS_PER_HOUR, a[2], a[1], 1.0)
            return d, a

        def rk4(derivative: Any) -> Any:
            k1 = derivative(s, p[6])
            k2 = derivative(s + 0.5 * step * k1, p[7])
            k3 = derivative(s + 0.5 * step * k2, p[7])
            k4 = derivative(s + step * k3, p[8])
            return s + step / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)

        def in_time(state: Any, v_given: Any) -> Any:
            return rates(state, v_given)[0]

        def in_height(state: Any, v_given: Any) -> Any:
            d, a = rates(state, v_given)
            rate = a[2]
            # climbs integrate over height: a rate of the wrong sign is flagged by the aux
            # outputs; here it is kept away from zero so the arithmetic stays finite
            safe = ca.if_else(step > 0, ca.fmax(rate, 1e-6), ca.fmin(rate, -1e-6))
            return d / safe

        if kind == "aux":
            return ca.Function("aux", [s, p], [evaluate(s, p[6])])
        derivative = {"time": in_time, "height": in_height}[kind]
        return ca.Function(f"step_{kind}", [s, step, p], [rk4(derivative)])

    def _segment_graph(self, plan: _Plan, state: Any, durations: Any, theta: Any,
                       nodes_aux: bool = True) -> tuple[list[Any], list[Any], Any]:
        """One segment flown from ``state`` (MX): its nodes, their aux outputs, the end state.

        Without ``nodes_aux`` only the aux at the segment's end is computed (a list of one).
        """
        import casadi as ca

        f_aux = self._stepper(plan.dead, plan.solve_v, "aux")
        if plan.kind == "takeoff":
            phases: list[tuple[str, Any, Any]] = [
                (kind, step, ca.DM(rows.T)) for kind, step, rows in self._takeoff_phases(plan)
            ]
        else:
            j = 3 * plan.index
            p = ca.vertcat(1.0 if plan.solve_x else 0.0, theta[j], plan.rate,
                           1.0 if plan.rate_from_excess else 0.0, theta[j + 1],
                           0.0, 0.0, 0.0, 0.0, theta[j + 2])
            rows = ca.repmat(p, 1, STEPS)
            if plan.kind == "time":
                phases = [("time", durations[plan.index] / STEPS, rows)]
            else:
                phases = [("height", (plan.end_h - plan.start_h) / STEPS, rows)]
        nodes, auxes = [], []
        for kind, step, p_rows in phases:
            f = self._stepper(plan.dead, plan.solve_v, kind)
            steps = p_rows.shape[1]
            # a step per row (the roll's, in equal times) or one for all
            step_row = (ca.DM(step.reshape(1, -1)) if isinstance(step, np.ndarray)
                        else ca.repmat(step, 1, steps))
            history = f.mapaccum(steps)(state, step_row, p_rows)
            both = ca.horzcat(state, history)
            # the aux at each node: the airspeed given at a step's start (first node) or end
            after = ca.vertcat(p_rows[:6, :], p_rows[8, :], p_rows[7:, :])
            if nodes_aux:
                auxes.append(f_aux.map(steps + 1)(both, ca.horzcat(p_rows[:, 0], after)))
            nodes.append(both)
            state = history[:, -1]
        if not nodes_aux:
            auxes.append(f_aux(state, after[:, -1]))
        return nodes, auxes, state

    def _segment_function(self, k: int) -> Any:
        """``(start state, durations, theta) -> (end state, aux at the end)`` of segment ``k``."""
        import casadi as ca

        if k not in self._segments:
            m = len(self.plans)
            start = ca.MX.sym("start", 2 * self.n + 3)
            durations, theta = ca.MX.sym("durations", m), ca.MX.sym("theta", 3 * m)
            _, auxes, end = self._segment_graph(self.plans[k], start, durations, theta,
                                                nodes_aux=False)
            # over the segment's nodes: the least loaded voltage of a live engine and
            # whether the charge stays on the discharge curve (rising, short of the pole):
            # a step too long for the discharge leaps past the knee, where the circuit's
            # voltage rises again, and its end alone would look fine
            nodes, node_aux, _ = self._segment_graph(self.plans[k], start, durations, theta)
            states, aux = ca.horzcat(*nodes), ca.horzcat(*node_aux)
            n, dead = self.n, self.plans[k].dead
            live = [i for i in range(n) if i != dead]
            least_v = ca.mmin(ca.vertcat(*(aux[6 + n + i, :].T for i in live)))
            q = states[:n, :]
            fall = ca.mmin(ca.vec(q[:, 1:] - q[:, :-1])) if q.shape[1] > 1 else ca.MX(0.0)
            self._segments[k] = ca.Function(f"segment_{k}", [start, durations, theta],
                                            [end, auxes[-1][:, -1], least_v, fall,
                                             ca.mmax(ca.vec(q))])
        return self._segments[k]

    def _build(self) -> None:
        import casadi as ca

        n = self.n
        durations = ca.MX.sym("durations", len(self.plans))
        # per segment: throttle, EAS [m/s], airspeed guess [m/s] (inputs, so that a study can
        # fly the same mission at another throttle without a rebuild)
        theta = ca.MX.sym("theta", 3 * len(self.plans))
        state = ca.MX.zeros(2 * n + 3, 1)
        states, auxes, bounds, ends = [], [], [], []
        self._steps: dict[Any, Any] = {}
        self._segments: dict[int, Any] = {}
        for plan in self.plans:
            start = sum(x.shape[1] for x in states)
            if plan.kind == "event":
                bounds.append((start, 0))
                ends.append(None)
                continue
            nodes, aux, state = self._segment_graph(plan, state, durations, theta)
            states.extend(nodes)
            auxes.extend(aux)
            bounds.append((start, sum(x.shape[1] for x in states)))
            ends.append(auxes[-1][6 + n:6 + 2 * n, -1])
        self.bounds = bounds
        self._history = ca.Function("mission", [durations, theta],
                                    [ca.horzcat(*states), ca.horzcat(*auxes)])
        landing = [1.0 - state[i] / self.capacity_ah for i in range(n)]
        self._landing = ca.Function("landing", [durations, theta], [ca.vertcat(*landing)])
        # loaded voltage of each pack at each segment's end (events: the open-circuit value
        # is irrelevant; they report +inf so a min over them ignores them)
        end_v = [e if e is not None else ca.MX(ca.DM.inf(n, 1)) for e in ends]
        self._end_voltage = ca.Function("end_voltage", [durations, theta],
                                        [ca.horzcat(*end_v)])
        self.durations = np.array([p.duration_s for p in self.plans], dtype=float)
        self.theta = np.array([[p.throttle, p.eas or 0.0, p.v_guess] for p in self.plans],
                              dtype=float).ravel()

    def _takeoff_phases(self, plan: _Plan) -> list[tuple[str, Any, np.ndarray]]:
        """Ground roll (over the take-off analysis's time), rotation and the airborne part to
        the obstacle."""
        from tuflexperf.analysis.takeoff import solve_takeoff

        result = solve_takeoff(self.case)
        if self.takeoff_to_obstacle and result.distance_to_obstacle_m is None:
            raise NotAttainable(f"segment {plan.index + 1} (takeoff): {result.obstacle_reason}")
        self.takeoff = result
        v_lo = result.liftoff_speed_m_s
        # the ground roll in time along the take-off analysis's own airspeed history, in
        # steps of equal time: the charge's rate is smooth in time. Over airspeed, dt/dV =
        # m/F peaks where the net force all but vanishes, and a node on the peak made a
        # 40 s roll 264 s (steps of equal airspeed had stepped over it: 3.7 %; outside audits)
        time = np.asarray(result.history_time_s, dtype=float)
        speed = np.asarray(result.history_airspeed_m_s, dtype=float)
        roll_s = float(time[-1]) if time.size > 1 else 0.0
        stage = np.linspace(0.0, roll_s, 2 * STEPS + 1)  # each step's start, middle and end
        at = np.interp(stage, time, speed) if roll_s > 0.0 else np.full(stage.size, v_lo)
        rows = np.zeros((STEPS, _P_SIZE))
        rows[:, 1] = 1.0  # full throttle
        rows[:, 5] = 1.0  # airspeed given, height rate forced (0 on the runway)
        rows[:, 6], rows[:, 7], rows[:, 8] = at[0:-1:2], at[1::2], at[2::2]
        phases: list[tuple[str, Any, np.ndarray]] = [("time", roll_s / STEPS, rows)]
        if result.rotation_time_s > 0:
            rot = np.zeros((ROTATION_STEPS, _P_SIZE))
            rot[:, 1], rot[:, 5], rot[:, 6:9] = 1.0, 1.0, v_lo
            phases.append(("time", result.rotation_time_s / ROTATION_STEPS, rot))
        if not self.takeoff_to_obstacle:
            return phases
        phases.extend(self._airborne_phases(result))
        return phases

    @staticmethod
    def _airborne_phases(result: Any) -> list[tuple[str, float, np.ndarray]]:
        """The take-off's airborne part flown along its path at the transition speed.

        The arc of radius ``R`` at ``V_tr`` (height ``R (1 - cos(V_tr t / R))``) up to the
        climb angle ``asin(G)`` of the full-throttle gradient ``G``, or up to the obstacle if
        the arc clears it, then the straight climb at ``V_tr G`` [m/s] to the obstacle height
        (Anderson, *Aircraft Performance and Design*, 6.7): times from the path's length,
        not its horizontal distance. Each arc step climbs its exact height difference.
        """
        v_tr, radius = result.transition_speed_m_s, result.transition_radius_m
        height, gradient = result.obstacle_height_m, result.climb_gradient
        sine = min(gradient, 1.0)  # a gradient of 1 or more climbs vertically (models.aircraft)
        if result.obstacle_cleared_in_transition:
            angle, straight_s = math.acos(1.0 - height / radius), 0.0
        else:
            # the arc ends at the angle of its own gradient (the climb's, unless packs sag)
            angle = math.asin(min(result.transition_gradient, 1.0))
            straight_s = (height - radius * (1.0 - math.cos(angle))) / (v_tr * sine)
        arc_s = radius * angle / v_tr
        # each step climbs its chord at a constant rate: the height inside a step (and so the
        # density the fans see) is off by ~ (dt^2/8) V^2/R; 64 steps keep the charge to 1e-8
        t = np.linspace(0.0, arc_s, ARC_STEPS + 1)
        h = radius * (1.0 - np.cos(v_tr * t / radius))
        arc = np.zeros((ARC_STEPS, _P_SIZE))
        arc[:, 1], arc[:, 5], arc[:, 6:9] = 1.0, 1.0, v_tr
        arc[:, 2] = np.diff(h) / (arc_s / ARC_STEPS)
        phases: list[tuple[str, float, np.ndarray]] = [("time", arc_s / ARC_STEPS, arc)]
        if straight_s > 0:
            climb = np.zeros((8, _P_SIZE))
            climb[:, 1], climb[:, 5], climb[:, 6:9] = 1.0, 1.0, v_tr
            climb[:, 2] = v_tr * sine
            phases.append(("time", straight_s / 8, climb))
        return phases

    # -- flying ---------------------------------------------------------------------------
    def fly(self, durations: np.ndarray | None = None, solved: dict[str, Any] | None = None,
            theta: np.ndarray | None = None) -> MissionResult:
        """Fly the mission (the file's durations, or ``durations`` [s] per segment).

        ``theta`` (per segment: throttle, EAS [m/s], airspeed guess [m/s]) replaces the
        file's settings without a rebuild (the endurance analysis flies its mission so).
        Not attainable (below stall, beyond full throttle, cut-off, ...) is a result with
        ``attainable`` false and the reason naming the segment and time, not an exception.

        References
        ----------
        SPEC 3 (voltage effect, stall), SPEC 4 ("Mission file"); Raymer, *Aircraft Design*,
        17.2-17.3.
        """
        d = self.durations if durations is None else np.asarray(durations, dtype=float)
        th = self.theta if theta is None else np.asarray(theta, dtype=float)
        states, aux = (np.asarray(m, dtype=float) for m in self._history(d, th))
        return self._result(states, aux, solved, th, d)

    def _charge_valid(self, q: np.ndarray, current: np.ndarray) -> np.ndarray:
        """Per node: the packs' state is on the discharge curve (else they were emptied).

        Charges finite, never falling, short of the pole of the model's knee (``n Q_max``),
        currents finite and not negative: past the pole the equivalent circuit means nothing
        (its voltage rises again), so such a node counts as beyond the cut-off.
        """
        pole = self.packs * self.params.max_capacity_ah
        rising = np.ones(q.shape[1], dtype=bool)
        rising[1:] = np.all(np.diff(q, axis=1) >= -1e-12, axis=0)
        with np.errstate(invalid="ignore"):
            return (np.all(np.isfinite(q), axis=0) & np.all(q < pole, axis=0)
                    & np.all(np.isfinite(current), axis=0) & np.all(current >= 0.0, axis=0)
                    & np.logical_and.accumulate(rising))

    def _cutoff_within(self, plan: _Plan, start: np.ndarray, durations: np.ndarray,
                       theta: np.ndarray, low: float, high: float
                       ) -> tuple[float, np.ndarray, np.ndarray]:
        """Time [s] into a timed segment at which the loaded voltage meets the cut-off.

        Bisection on the segment flown from ``start`` for ``tau`` in ``[low, high]`` (the
        voltage is above the cut-off at ``low``, below at ``high``) to 1e-6 s, each ``tau``
        judged by the least voltage over its nodes (and the charge staying on the discharge
        curve); a bracket wider than a minute is first narrowed by doubling steps from
        ``low``. Returns the time and the state and aux outputs there.
        """
        f = self._segment_function(plan.index)
        d = np.array(durations, dtype=float)
        pole = self.packs * self.params.max_capacity_ah

        def margin(tau: float) -> float:
            d[plan.index] = tau
            end, aux, least_v, fall, most = (np.asarray(v, dtype=float).ravel()
                                             for v in f(start, d, theta))
            q = np.stack([start[:self.n], end[:self.n]], axis=1)
            if not (self._charge_valid(q, aux[6:6 + self.n, None] * np.ones((1, 2))).all()
                    and fall[0] >= -1e-12 and most[0] < pole):
                return -1.0
            value = float(least_v[0]) - self.cutoff_v
            return value if math.isfinite(value) else -1.0

        # a bracket far wider than the discharge (a segment of months): march out from
        # ``low`` by doubling, so that every integration tried spans at most twice the time
        # to the cut-off and its nodes see the voltage cross before the knee
        span = high - low
        if span > 60.0:
            step = 60.0
            while step < span:
                if margin(low + step) < 0:
                    high = low + step
                    break
                low, span = low + step, span - step
                step *= 2.0
        for _ in range(200):
            if high - low <= 1e-6:
                break
            mid = 0.5 * (low + high)
            low, high = (mid, high) if margin(mid) >= 0 else (low, mid)
        d[plan.index] = low  # the last time still on the right side of the cut-off
        end, aux = (np.asarray(v_, dtype=float).ravel() for v_ in f(start, d, theta)[:2])
        return low, end, aux

    def _pack_rating_a(self) -> float | None:
        """The pack's continuous rating [A]: ``max_discharge_c x capacity_ah`` (None without
        a rating in the battery file)."""
        c_rate = self.battery.max_discharge_c
        return None if c_rate is None else float(c_rate) * float(self.battery.capacity_ah)

    def _beyond_rating(self, rating: float | None, t: np.ndarray, current: np.ndarray,
                       a: int, b: int, live: list[int], heavy: tuple[float, float, float]
                       ) -> tuple[int, str, float] | None:
        """Where segment ``[a, b)`` draws a pack beyond its rating: the node, why, and the
        time [s] it happens (None: within).

        No current may exceed :data:`BURST_OVER_CONTINUOUS` times the continuous rating
        (:meth:`_pack_rating_a`; the usual burst rating), and the mean current over any
        :data:`RATING_SEGMENT_S` or more of the flight, ``heavy`` = (end, start [s], mean
        [A]) of the earliest such stretch beyond it (:func:`first_window_beyond`), stays
        within the rating: when that stretch ends in this segment the flight ends there. A
        pack asked for 9 C against a 5 C rating 'flew' (outside audit); a take-off a few per
        cent above the continuous rating for seconds is within the burst; a long cruise cut
        into segments under 30 s each passed when the mean was bounded per segment (outside
        audit). The batch applies the same two rules (analysis.batch_endurance).
        """
        if rating is None or not live or b - a < 1:
            return None
        what = (f"(max_discharge_c {self.battery.max_discharge_c:g} C x "
                f"{self.battery.capacity_ah:g} Ah): not attainable, beyond the battery")
        per_pack = self.battery.packs_in_parallel_per_engine
        peak = np.max(current[live, a:b], axis=0) / per_pack
        burst = np.flatnonzero(peak > BURST_OVER_CONTINUOUS * rating * (1.0 + 1e-9))
        found: list[tuple[int, str, float]] = []
        if burst.size:
            k = int(burst[0])
            found.append((k, f"draws {peak[k]:.1f} A per pack, beyond its burst rating "
                          f"{BURST_OVER_CONTINUOUS * rating:.1f} A {what}", float(t[a + k])))
        end, begin, mean = heavy
        if t[a] - 1e-9 <= end <= t[b - 1] + 1e-9:
            k = min(int(np.searchsorted(t[a:b], end - 1e-9)), b - 1 - a)
            # the flight ends where the stretch ends, not at the node after it
            found.append((k, (
                f"draws {mean:.1f} A per pack on average over {end - begin:.0f} s "
                f"({begin:.0f}-{end:.0f} s into the mission{self._spanned(t, begin, end)}), "
                f"beyond its continuous rating {rating:.1f} A {what}"),
                min(float(t[a + k]), end)))
        return min(found, key=lambda item: item[:2]) if found else None

    def _spanned(self, t: np.ndarray, begin: float, end: float) -> str:
        """``, over segments 1-3 (takeoff, climb, cruise)`` where the stretch ``[begin,
        end]`` [s] covers more than the segment it ends in: the flight ends in that one, but
        the current was drawn over all of them (a take-off and climb read as the cruise's)."""
        covered = [plan for plan, (a, b) in zip(self.plans, self.bounds, strict=True)
                   if b > a and t[a] < end - 1e-9 and t[b - 1] > begin + 1e-9]
        if len(covered) < 2:
            return ""
        return (f", over segments {covered[0].index + 1}-{covered[-1].index + 1} "
                f"({', '.join(plan.type for plan in covered)})")

    def _result(self, states: np.ndarray, aux: np.ndarray, solved: dict[str, Any] | None,
                theta: np.ndarray, durations: np.ndarray) -> MissionResult:
        n = self.n
        q, e = states[:n], states[n:2 * n]
        h, dist, t = states[2 * n], states[2 * n + 1], states[2 * n + 2]
        x, v, rate, reached, idle, level_residual = (aux[k] for k in range(6))
        current, voltage = aux[6:6 + n], aux[6 + n:6 + 2 * n]
        power = aux[6 + 2 * n:6 + 3 * n]
        segment_of = np.full(t.size, -1, dtype=int)
        stall_factor = self._stall_factor()
        rating = self._pack_rating_a()
        heavy = (math.inf, math.nan, math.nan)
        if rating is not None and t.size > 1:
            per_pack = self.battery.packs_in_parallel_per_engine
            # the pack does not see the segments: the rating holds over any 30 s or more
            heavy = tuple(float(v[0]) for v in first_window_beyond(  # type: ignore[assignment]
                t[None, :], q[None, :, :] / per_pack, rating, RATING_SEGMENT_S))
        reason = ""
        first_bad, ended_at = None, None
        segments: list[SegmentResult] = []
        vertical: list[str] = []  # climbs whose thrust exceeds weight plus drag
        for plan, (a, b) in zip(self.plans, self.bounds, strict=True):
            label = f"segment {plan.index + 1} ({plan.type})"
            if plan.kind == "event":
                k = max(a - 1, 0)
                segments.append(SegmentResult(plan.index, plan.type, 0.0, 0.0, float(h[k]),
                                              float(h[k]), None, (0.0,) * n, (0.0,) * n,
                                              float(np.nanmin(voltage[:, k])) if states.size
                                              else math.nan, None,
                                              None if plan.dead is None
                                              else self.engines[plan.dead]))
                continue
            sl = slice(a, b)
            live = [i for i in range(n) if i != plan.dead]
            volt_live = voltage[live, sl]
            problems: list[tuple[int, str]] = []
            exact_at: dict[str, float] = {}  # a problem's time where it is not its node's
            cut = np.flatnonzero(~(np.min(volt_live, axis=0) >= self.cutoff_v - 1e-9)
                                 | ~self._charge_valid(q[:, sl], current[:, sl]))
            if cut.size:
                problems.append((int(cut[0]), "the pack reaches its cut-off voltage "
                                 f"{self.cutoff_v:.1f} V"))
            bad = np.flatnonzero(reached[sl] < 0.5)
            if bad.size:
                problems.append((int(bad[0]), "needs more than full throttle"))
            beyond = self._beyond_rating(rating, t, current, a, b, live, heavy)
            if beyond is not None:
                problems.append(beyond[:2])
                exact_at[beyond[1]] = beyond[2]
            segment_of[sl] = plan.index
            if plan.solve_v:
                throttle = float(theta[3 * plan.index])
                off = np.flatnonzero(~(np.abs(level_residual[sl]) < 1e-9))
                if off.size:
                    problems.append((int(off[0]), f"throttle {throttle:g} no longer holds "
                                     "level flight"))
                # the airspeed is an outcome here: stall bounds it (SPEC 3)
                stall_v = stall_factor * np.sqrt(1.225 / np.asarray(self._rho(h[sl]),
                                                                      dtype=float))
                slow = np.flatnonzero(v[sl] < stall_v * (1 - 1e-12))
                if slow.size:
                    k0 = int(slow[0])
                    problems.append((k0, f"throttle {throttle:g} flies level at "
                                     f"{v[a + k0]:.1f} m/s, below stall ({stall_v[k0]:.1f} m/s):"
                                     " not attainable, below stall"))
                braking = self._braking_engine(throttle, v[sl], h[sl], live)
                if braking is not None:
                    problems.append(braking)
            if plan.kind != "takeoff":  # the take-off analysis holds its own lift-off to it
                rho_sl = np.asarray(self._rho(h[sl]), dtype=float)
                # only thrust the fans cannot make counts: an idle dive past the jet velocity
                # needs none (the live engines' thrust is the aux's last row)
                pushing = aux[6 + 3 * n, sl] > 0.0
                fast = np.flatnonzero(beyond_jet_velocity(self.case.propulsion, v[sl], rho_sl)
                                      & pushing)
                if fast.size:
                    k0 = int(fast[0])
                    jet = float(static_jet_velocity_m_s(self.case.propulsion, rho_sl[k0]))
                    problems.append((k0, f"{v[a + k0]:.1f} m/s is beyond the fans' static jet "
                                     f"velocity {jet:.1f} m/s, where they make no thrust "
                                     "(the thrust model is extrapolated there): not attainable"))
            if plan.kind == "height":
                climbing = plan.end_h > plan.start_h
                wrong = np.flatnonzero((rate[sl] <= 0) if climbing else (rate[sl] >= 0))
                if wrong.size:
                    verb = "climb" if climbing else "descend"
                    what = ("the rate of climb is not attainable" if plan.solve_x
                            else f"cannot {verb} at throttle {plan.throttle:g}")
                    problems.append((int(wrong[0]), what))
                if plan.solve_x and np.any(np.abs(plan.rate) >= v[sl]):
                    k0 = int(np.argmax(np.abs(plan.rate) >= v[sl]))
                    problems.append((k0, f"a {'climb' if climbing else 'descent'} at "
                                     f"{abs(plan.rate):g} m/s is steeper than vertical at "
                                     f"{v[a + k0]:.1f} m/s true airspeed: not attainable"))
                if plan.solve_x and not climbing:
                    steep = np.flatnonzero(idle[sl] > 1e-9)
                    if steep.size:
                        problems.append((int(steep[0]), f"needs less than idle thrust to descend "
                                         f"at {-plan.rate:g} m/s"))
                # only the nodes flown: past a failure the integration runs on unphysical states
                flown = level_residual[sl][:min(problems)[0] if problems else None]
                if plan.rate_from_excess and np.any(flown > 1.0):
                    vertical.append(
                        f"{label}: thrust at throttle {plan.throttle:g} exceeds weight plus "
                        "drag: flown as a vertical climb (rate of climb at the airspeed); the "
                        "steady-climb model (L = W) does not hold there, the excess would "
                        "accelerate it")
            if problems and first_bad is None:
                k, why = min(problems)
                at = exact_at.get(why, float(t[a + k]))
                b = a + max(k, 1)  # the flight ends there: nothing after the event is flown
                if why.startswith("the pack reaches") and plan.kind == "time" and k > 0:
                    # the event between two nodes, exactly (the nodes are 1/64 segment apart),
                    # and the state there becomes the flight's last node
                    tau, end_s, end_a = self._cutoff_within(
                        plan, states[:, a], durations, theta, float(t[a + k - 1] - t[a]),
                        float(t[a + k] - t[a]))
                    at = float(t[a]) + tau

                    def put(arr: np.ndarray, value: Any, b: int = b) -> np.ndarray:
                        return np.concatenate(
                            [arr[..., :b], np.reshape(value, arr.shape[:-1] + (1,))], axis=-1)

                    q, e = put(q, end_s[:n]), put(e, end_s[n:2 * n])
                    h, dist = put(h, end_s[2 * n]), put(dist, end_s[2 * n + 1])
                    t, x, v, rate = (put(t, end_s[2 * n + 2]), put(x, end_a[0]),
                                     put(v, end_a[1]), put(rate, end_a[2]))
                    current, voltage = put(current, end_a[6:6 + n]), put(voltage,
                                                                         end_a[6 + n:6 + 2 * n])
                    power, segment_of = put(power, end_a[6 + 2 * n:6 + 3 * n]), put(
                        segment_of, plan.index)
                    b += 1
                first_bad, ended_at = a + k, at
                reason = f"{label}: {why} at {at:.1f} s ({at / 60:.2f} min into the mission)"
                if why.startswith("the pack reaches") and plan.kind != "time" and k > 0:
                    # between two nodes of a climb or descent (integrated over height, 1/64 of
                    # it apart): the flight, its history and ended_at_s end at the last node
                    # before the cut-off, and the reason says so (it named the node after,
                    # past the history's end)
                    ended_at = float(t[a + k - 1])
                    reason = (f"{label}: {why} between {ended_at:.1f} and {at:.1f} s "
                              f"({ended_at / 60:.2f}-{at / 60:.2f} min into the mission)")
                sl = slice(a, b)
                volt_live = voltage[live, sl]
            xs = x[sl]
            eas_flown = plan.eas
            if plan.solve_v:  # the mean EAS the throttle gave
                eas_flown = float(np.mean(v[sl] * np.sqrt(np.asarray(self._rho(h[sl]), dtype=float)
                                                          / 1.225)))
            segments.append(SegmentResult(
                index=plan.index, type=plan.type,
                time_s=float(t[b - 1] - t[a]), distance_m=float(dist[b - 1] - dist[a]),
                start_altitude_m=float(h[a]), end_altitude_m=float(h[b - 1]),
                airspeed_eas_m_s=eas_flown,
                charge_ah=tuple(float(q[i, b - 1] - q[i, a]) for i in range(n)),
                energy_wh=tuple(float(e[i, b - 1] - e[i, a]) for i in range(n)),
                min_voltage_v=float(np.nanmin(volt_live)) if volt_live.size else math.nan,
                max_throttle=float(np.nanmax(xs)) if live else None,
                dead_engine=self.engines[plan.dead] if plan.dead is not None else None,
            ))
            if first_bad is not None:
                end = b
                q, e, h, dist, t = q[:, :end], e[:, :end], h[:end], dist[:end], t[:end]
                x, v, rate, segment_of = x[:end], v[:end], rate[:end], segment_of[:end]
                current, voltage, power = current[:, :end], voltage[:, :end], power[:, :end]
                break
        landing = float(np.min(1.0 - q[:, -1] / self.capacity_ah))
        rho_h = np.asarray(self._rho(h), dtype=float) * np.ones_like(h)
        history = {"time_s": t, "segment": segment_of, "altitude_m": h, "distance_m": dist,
                   "airspeed_m_s": v, "airspeed_eas_m_s": v * np.sqrt(rho_h / 1.225),
                   "throttle": x, "climb_rate_m_s": rate}
        for i, name in enumerate(self.engines):
            history[f"current_a_{name}"] = current[i]
            history[f"voltage_v_{name}"] = voltage[i]
            history[f"charge_ah_{name}"] = q[i]
            history[f"charge_fraction_{name}"] = 1.0 - q[i] / self.capacity_ah
            history[f"power_w_{name}"] = power[i]
            history[f"energy_wh_{name}"] = e[i]
        return MissionResult(
            name=self.mission.name, segments=tuple(segments),
            landing_charge_fraction=landing if first_bad is None else math.nan,
            min_landing_charge_fraction=self.reserve, attainable=first_bad is None,
            reason=reason or (f"lands with {100 * landing:.1f} % charge (reserve "
                              f"{100 * self.reserve:g} %)"),
            engines=self.engines, history=history, solved=solved, ended_at_s=ended_at,
            cutoff_voltage_v=self.cutoff_v,
            warnings=(*self.start_notes, *self.battery.scaled_notes, *vertical,
                      *self._extrapolation_notes(v, segment_of)),
        )

    def _extrapolation_notes(self, v: np.ndarray, segment_of: np.ndarray) -> list[str]:
        """Per segment flown outside the thrust model's tested airspeeds: a note saying so
        (SPEC: extrapolation is said; a mission at 40 m/s said nothing; outside audit)."""
        low, high = self.case.propulsion.tested_airspeed_m_s
        outside = outside_tested_range(self.case.propulsion, v)
        notes = []
        # a set, not np.unique: numpy >= 2.3's unique imports numpy.ma (~20 ms of `check`)
        for k in sorted(set(np.asarray(segment_of)[outside].astype(int).tolist())):
            speeds = v[outside & (segment_of == k)]
            segment = self.mission.segments[k]
            span = (f"{speeds.min():.1f}" if round(speeds.min(), 1) == round(speeds.max(), 1)
                    else f"{speeds.min():.1f}-{speeds.max():.1f}")
            notes.append(f"segment {k + 1} ({segment.type}): thrust model extrapolated at "
                         f"{span} m/s true (tested {low:g}-{high:g} m/s)")
        return notes

    def _braking_engine(self, throttle: float, v: np.ndarray, h: np.ndarray,
                        live: list[int]) -> tuple[int, str] | None:
        """The first node of a level flight at a fixed ``throttle`` where a live engine's
        models give no thrust, or thrust on no power, and why (``None`` if none does).

        The other fan's extrapolated thrust can still balance the drag there, and the ESC
        clamp hides the power the pack would be "given back": a cruise at 99 m/s on one fan
        at -3.6 N and -448 W flew 66.9 min (outside audit). Unflown (NaN) nodes are skipped.
        """
        prop = self.case.propulsion
        rho = np.asarray(self._rho(h), dtype=float) * np.ones_like(v)
        sigma = density_ratio(prop, rho)
        for i in live:
            thrust = np.asarray(engine_thrust_n(prop.engines[i], throttle, v, sigma), dtype=float)
            power = np.asarray(self._modelled_power(i, throttle, v, rho), dtype=float)
            power = power * np.ones_like(v)
            bad = np.flatnonzero((thrust <= 0.0) | (power <= 0.0))
            if bad.size:
                k = int(bad[0])
                return k, (f"{self.engines[i]}'s models give {thrust[k]:.1f} N on "
                           f"{power[k]:.0f} W at throttle {throttle:g}, {v[k]:.1f} m/s "
                           "(extrapolated): a fan that makes no thrust, or thrust on no power, "
                           "flies no cruise")
        return None

    def _stall_factor(self) -> float:
        """Least EAS [m/s] of level flight: the stall speed (EAS) x the envelope's margin."""
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        return margin * float(stall_speed_eas_m_s(self.case.aircraft))

    def _suffix_function(self, k: int) -> Any:
        """``(start, durations, theta) -> (landing state, aux at segment k's end, most charge
        per pack, least loaded voltage of a live engine [V])``.

        The mission from where segment ``k`` begins (``start``, its state) to the landing:
        what the duration of segment ``k`` changes, without the part before it. The least
        voltage is segment ``k``'s at its end and every later segment's at each of its nodes,
        each segment's live engines only (as :meth:`fly` checks the cut-off): a longer cruise
        before a one-engine loiter cuts off in the loiter, which segment ``k``'s end alone
        did not see (outside audit: ``solve_for`` answered a cruise the loiter then refused).
        """
        import casadi as ca

        if k not in self._suffixes:
            m, n = len(self.plans), self.n
            start = ca.MX.sym("start", 2 * n + 3)
            durations, theta = ca.MX.sym("durations", m), ca.MX.sym("theta", 3 * m)
            state, at_k, nodes, least = start, None, [start], []
            for plan in self.plans[k:]:
                if plan.kind == "event":
                    continue
                both, auxes, state = self._segment_graph(plan, state, durations, theta,
                                                         nodes_aux=plan.index != k)
                nodes.extend(both)
                if plan.index == k:
                    at_k = auxes[-1][:, -1]
                aux = ca.horzcat(*auxes)
                least.extend(aux[6 + n + i, :].T for i in range(n) if i != plan.dead)
            # the most charge each pack gave at any node: beyond the model's knee (the pole of
            # the discharge curve) the charge stops rising and the answer means nothing
            drawn = ca.horzcat(*nodes)
            most = ca.vertcat(*(ca.mmax(drawn[i, :]) for i in range(n)))
            self._suffixes[k] = ca.Function(f"from_segment_{k}", [start, durations, theta],
                                            [state, at_k, most, ca.mmin(ca.vertcat(*least))])
        return self._suffixes[k]

    def start_state(self, k: int, durations: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The state where segment ``k`` begins: charges [Ah], energies [Wh] per engine,
        height [m], distance [m], time [s], for ``durations`` [s] and ``theta``.

        References
        ----------
        SPEC 4 ("Mission file"): segments flown in order from full packs.
        """
        states = np.asarray(self._history(durations, theta)[0], dtype=float)
        a = self.bounds[k][0]
        return states[:, a] if a < states.shape[1] else states[:, -1]

    def longest(self, k: int, durations: np.ndarray | None = None,
                theta: np.ndarray | None = None, guess_s: float | None = None,
                start: np.ndarray | None = None) -> tuple[float, str]:
        """Longest duration [s] of segment ``k`` that lands on the reserve without a cut-off.

        A rootfinder on ``g(T) = min_i landing_fraction_i(T) - reserve`` (it falls
        monotonically with the segment's duration ``T``), each evaluation one integration of
        the mission from where segment ``k`` begins (``start``, computed once if not given)
        to the landing. For the last segment, Newton with the slope from the state equations,
        ``dg/dT = -i_j / (3600 Q)`` at the landing for the engine ``j`` that lands with
        least charge (from ``guess_s``, e.g. a closed form); otherwise regula falsi
        (Illinois) on a bracket from ``T = 0``. If the packs are then below their cut-off
        voltage on the way to the landing, the same on ``min U(T) - U_cutoff`` instead (the
        least loaded voltage of a live engine from segment ``k``'s end on).
        Both to 1e-12 (fraction) and 1e-9 V. Returns the duration and what ends it:
        ``"landing reserve"`` or ``"cut-off"``. Raises :class:`NotAttainable` when no
        positive duration does.

        References
        ----------
        Issue 13 item 3 (``solve_for``); Press et al., *Numerical Recipes*, 3rd ed., 9.2
        (regula falsi, the Illinois variant) and 9.4 (Newton-Raphson).
        """
        n = self.n
        d = (self.durations if durations is None else np.asarray(durations, float)).copy()
        th = self.theta if theta is None else np.asarray(theta, dtype=float)
        plan = self.plans[k]
        f = self._suffix_function(k)
        x0 = self.start_state(k, d, th) if start is None else start
        last = all(p.kind == "event" for p in self.plans[k + 1:])

        pole = self.packs * self.params.max_capacity_ah
        memo: dict[float, tuple[float, float, float]] = {}

        def at(tau: float) -> tuple[float, float, float]:
            if tau not in memo:
                memo[tau] = evaluate(tau)
            return memo[tau]

        def evaluate(tau: float) -> tuple[float, float, float]:
            d[k] = tau
            end, aux, most, least = (np.asarray(v, dtype=float).ravel()
                                     for v in f(x0, d, th))
            if not (np.all(np.isfinite(end)) and np.all(most <= end[:n] + 1e-12)
                    and np.all(most < pole)):
                return -1.0, math.nan, -1.0  # the packs were emptied on the way: beyond
            frac = 1.0 - end[:n] / self.capacity_ah
            j = int(np.argmin(frac))
            volt = float(least[0])  # a live engine's, to the landing (_suffix_function)
            slope = -aux[6 + j] / SECONDS_PER_HOUR / self.capacity_ah
            return float(frac[j] - self.reserve), float(slope), float(volt - self.cutoff_v)

        def illinois(which: int, low: float, high: float, f_low: float, f_high: float
                     ) -> float | None:
            side = 0
            for _ in range(200):
                c = high - f_high * (high - low) / (f_high - f_low)
                fc = at(c)[which]
                if not math.isfinite(fc):
                    c, fc = 0.5 * (low + high), at(0.5 * (low + high))[which]
                if abs(fc) <= (1e-12 if which == 0 else 1e-10) or high - low <= 1e-9 * high:
                    return c
                if fc > 0:
                    low, f_low = c, fc
                    f_high = 0.5 * f_high if side == 1 else f_high
                    side = 1
                else:
                    high, f_high = c, fc
                    f_low = 0.5 * f_low if side == -1 else f_low
                    side = -1
            return None

        def bracket(which: int, tau: float, f_tau: float
                    ) -> tuple[float, float, float, float] | None:
            # from a point with f > 0 forwards until f < 0 (finite), by doubling the step
            step = max(tau, 60.0)
            for _ in range(40):
                high = tau + step
                f_high = at(high)[which]
                if math.isfinite(f_high) and f_high < 0:
                    return tau, f_tau, high, f_high
                if not math.isfinite(f_high):
                    step *= 0.5
                else:
                    tau, f_tau, step = high, f_high, 2 * step
            return None

        tau: float | None = None
        if last and guess_s is not None:  # Newton from the guess
            tau = max(guess_s, 1.0)
            g, slope, _ = at(tau)
            for _ in range(50):
                if not (math.isfinite(g) and slope < 0):
                    tau = None
                    break
                step = -g / slope
                tau = max(tau + step, 0.5 * tau)
                g, slope, _ = at(tau)
                if abs(g) <= 1e-12 and abs(step) <= 1e-6 * max(tau, 1.0):
                    break
            else:
                tau = None
        if tau is None:  # regula falsi on a bracket from a segment of no duration
            zero = at(0.0)
            if zero[0] >= 0 and zero[2] >= 0:
                found = bracket(0, 0.0, zero[0])
                tau = None if found is None else illinois(0, found[0], found[2], found[1],
                                                          found[3])
        ends = "landing reserve"
        if tau is not None and at(tau)[2] < 0:  # the pack cuts off before the reserve
            ends = "cut-off"
            zero = at(0.0)
            tau = illinois(2, 0.0, tau, zero[2], at(tau)[2]) if zero[2] >= 0 else None
        if tau is None or not tau > 0 or at(tau)[0] < -1e-8:
            # the rest of the mission flown as it is: a segment before this one that empties
            # the packs is named with its own time, not blamed on this one with "-80 %" left
            # (the marker of an emptied pack; outside audit)
            d[k] = 0.0
            rest = self.fly(d)
            label = f"segment {k + 1} ({plan.type})"
            if not rest.attainable:
                raise NotAttainable(f"{rest.reason} (flown with {label}, the one solved for, "
                                    "of no duration: no duration of it lands)")
            raise NotAttainable(
                f"{label}: no duration lands with the reserve {100 * self.reserve:g} % before "
                f"the cut-off (the rest of the mission alone leaves "
                f"{100 * rest.landing_charge_fraction:.1f} %)"
            )
        return tau, ends

    def solve_for(self) -> MissionResult:
        """Longest duration of the ``solve_for`` segment that lands exactly on the reserve.

        See :meth:`longest`; the answer is then flown as a plain mission.
        """
        k = self.mission.solve_for
        assert k is not None
        plan = self.plans[k]
        answer, ends = self.longest(k)
        final = self.durations.copy()
        final[k] = answer
        # the file's own time (or distance) of the segment: the plan the verdict holds it to
        # (a PASS "landing on the reserve" of a 0.47 min cruise planned at 8 min; outside audit)
        solved = {"segment": plan.type, "index": k, "time_min": answer / 60.0,
                  "ends_at": ends, "written_time_min": float(self.durations[k]) / 60.0}
        if plan.eas is not None:
            v_true = float(true_airspeed_m_s(plan.eas, self._rho(plan.start_h)))
            solved["distance_km"] = answer * v_true / 1000.0
            if self.mission.segments[k].distance_km is not None:
                solved["written_distance_km"] = self.mission.segments[k].distance_km
        return self.fly(final, solved)


def solve_mission(case: Case, mission: MissionFile,
                  min_landing_fraction: float | None = None) -> MissionResult:
    """Fly ``mission`` for ``case`` (solving its ``solve_for`` segment if it names one).

    ``min_landing_fraction`` [-] is the reserve to land with (default: the battery file's
    ``landing_reserve_fraction``). Raises :class:`NotAttainable` for a mission that cannot
    be planned (a segment below stall, a throttle with no level flight).

    References
    ----------
    SPEC 4 ("Mission file"), SPEC 5 (``mission`` command and JSON keys).
    """
    try:
        model = MissionModel(case, mission, min_landing_fraction)
    except NotAttainable as exc:
        flown = _flown_up_to(case, mission, min_landing_fraction, exc)
        if flown is None:
            raise
        return flown
    flown = model.solve_for() if mission.solve_for is not None else model.fly()
    return _said_if_airborne(flown)


AIRBORNE_AT_END_M = 1.0
"""A mission that ends this high above the field [m] or more has not landed."""


def _said_if_airborne(flown: MissionResult) -> MissionResult:
    """A mission whose last segment ends in the air says that its descent and landing are
    not flown: the charge it 'lands' with is the one up there (a take-off and a climb to
    100 m 'landed with 93.4 %' and PASSed, unsaid; outside audit)."""
    import dataclasses

    height = np.asarray(flown.history.get("altitude_m", ()), dtype=float)
    if not flown.attainable or height.size == 0 or not height[-1] >= AIRBORNE_AT_END_M:
        return flown
    note = (f"mission {flown.name!r} ends {height[-1]:.0f} m above the field: its descent and "
            "landing are not flown, the landing charge is the one at the last segment's end "
            "(add {type: descent, to_altitude_m: 0, ...} to fly them)")
    return dataclasses.replace(flown, warnings=(*flown.warnings, note))


def _flown_up_to(case: Case, mission: MissionFile, min_landing_fraction: float | None,
                 exc: NotAttainable) -> MissionResult | None:
    """The flight up to a segment that cannot be planned (below stall, a throttle with no
    level flight), ended there as not attainable; None when nothing precedes it.

    SPEC 5 ("the output says why") and README: a mission that is not attainable names the
    segment and the time, with the segments flown before it (its JSON had none).
    """
    import dataclasses

    k = getattr(exc, "segment_index", 0)
    if k == 0 or mission.solve_for is not None:  # a solved segment needs the whole plan
        return None
    before = dataclasses.replace(mission, segments=mission.segments[:k])
    model = MissionModel(case, before, min_landing_fraction)
    if all(plan.kind == "event" for plan in model.plans):
        return None  # a catapult release or an engine failure flies no time: nothing flown
    flown = model.fly()
    if not flown.attainable:  # ended earlier (a cut-off): that is the answer
        return flown
    # no landing: as a flight ended by its cut-off, the landing charge is not a number
    return dataclasses.replace(flown, attainable=False, reason=str(exc),
                               landing_charge_fraction=math.nan,
                               ended_at_s=float(flown.history["time_s"][-1]))
