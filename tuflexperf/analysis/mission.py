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
from typing import Any

import numpy as np

from tuflexperf.analysis.cache import BoundedCache, file_key, fingerprint
from tuflexperf.analysis.mission_equations import (
    _P_SIZE,
    ARC_STEPS,
    BURST_OVER_CONTINUOUS,
    CORRECTION_SIZE,
    NEWTON,
    RATING_SEGMENT_S,
    SAMPLED_AIRCRAFT,
    SECONDS_PER_HOUR,
    STEPS,
    AirbornePath,
    SegmentEquations,
    airborne_path,
    takeoff_layout,
    takeoff_matrix,
)
from tuflexperf.analysis.mission_flight import FlightChecks
from tuflexperf.analysis.mission_plan import MissionPlanning, _Plan
from tuflexperf.analysis.mission_results import (
    AIRBORNE_AT_END_M,
    MissionResult,
    SegmentResult,
    _said_if_airborne,
)
from tuflexperf.analysis.mission_solve import SolveFor
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.io.mission import MissionFile

__all__ = ["AIRBORNE_AT_END_M", "ARC_STEPS", "BURST_OVER_CONTINUOUS", "NEWTON",
           "RATING_SEGMENT_S", "SAMPLED_AIRCRAFT", "SECONDS_PER_HOUR", "STEPS",
           "AirbornePath", "MissionModel", "MissionResult", "SegmentResult", "airborne_path",
           "mission_model", "solve_mission", "takeoff_layout", "takeoff_matrix"]


class MissionModel(SegmentEquations, MissionPlanning, FlightChecks, SolveFor):
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
        # the circuit's packs last
        self.n_par = len(SAMPLED_AIRCRAFT) + 2 + 7 * self.n + CORRECTION_SIZE * (self.n + 1) + 1
        self._build()

    def _segment_function(self, k: int) -> Any:
        """``(start state, durations, theta) -> (end state, aux at the end)`` of segment ``k``."""
        import casadi as ca

        if k not in self._segments:
            start = ca.MX.sym("start", 2 * self.n + 3)
            durations, theta, par, tk = self._symbols()
            _, auxes, end = self._segment_graph(self.plans[k], start, durations, theta, par, tk,
                                                nodes_aux=False)
            # over the segment's nodes: the least loaded voltage of a live engine and
            # whether the charge stays on the discharge curve (rising, short of the pole):
            # a step too long for the discharge leaps past the knee, where the circuit's
            # voltage rises again, and its end alone would look fine
            nodes, node_aux, _ = self._segment_graph(self.plans[k], start, durations, theta, par,
                                                     tk)
            states, aux = ca.horzcat(*nodes), ca.horzcat(*node_aux)
            n, dead = self.n, self.plans[k].dead
            live = [i for i in range(n) if i != dead]
            least_v = ca.mmin(ca.vertcat(*(aux[6 + n + i, :].T for i in live)))
            q = states[:n, :]
            fall = ca.mmin(ca.vec(q[:, 1:] - q[:, :-1])) if q.shape[1] > 1 else ca.MX(0.0)
            self._segments[k] = ca.Function(f"segment_{k}", [start, durations, theta, par, tk],
                                            [end, auxes[-1][:, -1], least_v, fall,
                                             ca.mmax(ca.vec(q))])
        return self._segments[k]

    def _build(self) -> None:
        self._steps: dict[Any, Any] = {}
        self._segments: dict[int, Any] = {}
        self.par = self.parameters()
        self.tk_layout: list[tuple[str, int]] = []
        self.tk = np.zeros((_P_SIZE + 1, 0))
        if self.plans and self.plans[0].kind == "takeoff":
            self.tk_layout, self.tk = self._takeoff_rows(self.plans[0])
        self._history, self.bounds = self._chain()
        self.durations = np.array([p.duration_s for p in self.plans], dtype=float)
        self.theta = np.array([[p.throttle, p.eas or 0.0, p.v_guess] for p in self.plans],
                              dtype=float).ravel()

    def _symbols(self) -> tuple[Any, Any, Any, Any]:
        """The chained functions' inputs: durations [s], per segment (throttle, EAS [m/s],
        airspeed guess [m/s]), the sampled parameters and the take-off's step rows."""
        import casadi as ca

        m = len(self.plans)
        return (ca.MX.sym("durations", m), ca.MX.sym("theta", 3 * m),
                ca.MX.sym("par", self.n_par), ca.MX.sym("tk", _P_SIZE + 1, self.tk.shape[1]))

    def _chain(self) -> tuple[Any, list[tuple[int, int]]]:
        """``(durations, theta, par, tk) -> (states, aux)`` at every node of every segment,
        and each segment's node range: the whole mission as ONE function."""
        import casadi as ca

        n = self.n
        durations, theta, par, tk = self._symbols()
        state = ca.MX.zeros(2 * n + 3, 1)
        states: list[Any] = []
        auxes: list[Any] = []
        bounds = []
        for plan in self.plans:
            start = sum(x.shape[1] for x in states)
            if plan.kind == "event":
                bounds.append((start, 0))
                continue
            nodes, aux, state = self._segment_graph(plan, state, durations, theta, par, tk)
            states.extend(nodes)
            auxes.extend(aux)
            bounds.append((start, sum(x.shape[1] for x in states)))
        history = ca.Function("mission", [durations, theta, par, tk],
                              [ca.horzcat(*states), ca.horzcat(*auxes)])
        return history, bounds

    def _takeoff_rows(self, plan: _Plan) -> tuple[list[tuple[str, int]], np.ndarray]:
        """The take-off's phases (name, steps) and their step rows ``(P + 1, columns)``: the
        ground roll over the take-off analysis's time, the rotation and the airborne part to
        the obstacle (:func:`takeoff_matrix`)."""
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
        air = None
        if self.takeoff_to_obstacle:
            air = airborne_path(*(np.array([float(x)]) for x in (
                result.transition_speed_m_s, result.transition_radius_m,
                result.obstacle_height_m, result.climb_gradient, result.transition_gradient)),
                np.array([bool(result.obstacle_cleared_in_transition)]))
        layout = takeoff_layout(result.rotation_time_s > 0, air is not None,
                                air is not None and bool(air.straight_s[0] > 0))
        rows = takeoff_matrix(layout, at[None, :], np.array([roll_s]),
                              np.array([float(result.rotation_time_s)]), np.array([v_lo]), air)
        return layout, rows[0]

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
        states, aux = (np.asarray(m, dtype=float)
                       for m in self._history(d, th, self.par, self.tk))
        return self._result(states, aux, solved, th, d)


_MODELS: BoundedCache[MissionModel] = BoundedCache(8)  # a case and its readings, twice


def mission_model(case: Case, mission: MissionFile,
                  min_landing_fraction: float | None = None) -> MissionModel:
    """``MissionModel(case, mission, min_landing_fraction)``, built once per process for
    equal inputs: ``check`` flies it and ``--samples`` flies its rows (a model is not changed
    once built). Raises :class:`NotAttainable` as the model does (nothing kept then)."""
    battery = case.battery_path
    key = fingerprint(str(case.path), case.aircraft, case.propulsion, case.atmosphere,
                      case.requirements, case.overrides, str(battery),
                      file_key(battery) if battery is not None and battery.exists() else None,
                      repr(mission), min_landing_fraction)
    return _MODELS.get(key, lambda: MissionModel(case, mission, min_landing_fraction))


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
        model = mission_model(case, mission, min_landing_fraction)
    except NotAttainable as exc:
        flown = _flown_up_to(case, mission, min_landing_fraction, exc)
        if flown is None:
            raise
        return flown
    flown = model.solve_for() if mission.solve_for is not None else model.fly()
    return _with_launch_energy(case, _said_if_airborne(flown))


def _with_launch_energy(case: Case, flown: MissionResult) -> MissionResult:
    """The mission's energy with a catapult's kinetic energy at release, ``m V^2 / 2`` at the
    field's density (issue 43: the flight's energy left out what the catapult gave it)."""
    import dataclasses

    from tuflexperf.models.aircraft import true_airspeed_m_s

    aircraft = case.aircraft
    if aircraft.launch != "catapult" or aircraft.launch_speed_m_s is None:
        return flown
    release = float(true_airspeed_m_s(aircraft.launch_speed_m_s, case.density_kg_m3))
    kinetic_wh = 0.5 * aircraft.mass_kg * release * release / 3600.0
    return dataclasses.replace(flown, launch_kinetic_energy_wh=kinetic_wh)


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
