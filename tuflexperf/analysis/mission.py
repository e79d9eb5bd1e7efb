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
  ``n`` packs in parallel per engine; ``dq_i/dt = i / 3600`` [Ah/s].
- climb and descent with ``L = W`` (small angle): rate of climb ``(T - D) V / W``; a segment
  flown at a climb (descent) rate needs ``T = D + W RC / V``; level flight ``T = D``.
  The throttle that gives a needed thrust is the least root of the quadratic in ``x``
  (:func:`tuflexperf.models.thrust.least_throttle_reaching`), solved at every RK4 stage.
- take-off: the landed take-off analysis (ground roll from rest at full throttle with the
  airspeed history, rotation at ``V_LO``, the airborne part to the obstacle at the transition
  speed, height rising evenly to the obstacle height).

Each segment is integrated by classic RK4 with :data:`STEPS` fixed steps (over time for
level segments and the take-off, over height for climbs and descents, so their end is
exact without an event), all segments chained into ONE CasADi function built once per
case and mission. ``solve_for`` makes one segment's duration a symbol and solves
"landing charge fraction = reserve" with a CasADi Newton rootfinder.

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

from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.io.mission import MissionFile, SegmentSchema
from tuflexperf.models.aircraft import (
    level_flight_drag_n,
    stall_speed_eas_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import G0_M_S2, isa_density_kg_m3
from tuflexperf.models.battery import (
    current_at_power_a,
    open_circuit_voltage_v,
)
from tuflexperf.models.thrust import (
    density_ratio,
    engine_thrust_n,
    least_throttle_reaching,
    windmilling_thrust_n,
)

STEPS = 64  # RK4 steps per segment: the states are smooth, 64 steps give ~1e-9 relative
SECONDS_PER_HOUR = 3600.0
# per-step auxiliary outputs (rows of the aux matrix)
_AUX = ("throttle", "airspeed_m_s", "climb_rate_m_s", "reached", "idle_excess_n")


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
    """A flown mission: per-segment results, the landing charge and the time history."""

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

    @property
    def passed(self) -> bool:
        return self.attainable and self.landing_charge_fraction >= (
            self.min_landing_charge_fraction - 1e-12
        )

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


class MissionModel:
    """The whole mission as one CasADi function of the durations (built once)."""

    def __init__(self, case: Case, mission: MissionFile, min_landing_fraction: float | None):
        from tuflexperf.analysis.endurance import characterise_battery
        from tuflexperf.io.battery import load_battery

        if case.battery_path is None:
            raise InputError(f"{case.path}: battery: a mission needs the case's battery file")
        self.case, self.mission = case, mission
        battery = load_battery(case.battery_path)
        self.battery = battery
        ch = characterise_battery(battery, case)
        self.params = ch.fit.parameters
        self.fan_power = ch.power.model
        self.packs = battery.packs_in_parallel_per_engine
        self.capacity_ah = battery.capacity_ah * self.packs  # per engine
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
        self.plans = self._plan(mission.segments)
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
        for i, s in enumerate(segments):
            label = f"segment {i + 1} ({s.type})"
            if s.type == "engine_failure":
                if s.engine not in self.engines:
                    raise InputError(
                        f"{where}[{i}].engine: {s.engine!r} is not an engine of the propulsion "
                        f"file ({', '.join(self.engines)})"
                    )
                dead = self.engines.index(s.engine)
                plans.append(_Plan(i, s.type, "event", h, h, None, False, 0.0, 0.0, False, 0.0,
                                   dead))
                continue
            if s.type == "takeoff":
                if i != 0:
                    raise InputError(f"{where}[{i}]: takeoff must be the first segment")
                from tuflexperf.analysis.takeoff import obstacle_height_of

                if self.case.aircraft.launch == "catapult":  # airborne at release, 0 m
                    plans.append(_Plan(i, s.type, "event", 0.0, 0.0, None, False, 0.0, 0.0,
                                       False, 0.0, dead))
                    continue
                h = obstacle_height_of(self.case)  # the take-off ends over the obstacle
                plans.append(_Plan(i, s.type, "takeoff", 0.0, h, None, False, 1.0, 0.0,
                                   False, 0.0, dead))
                continue
            eas = s.airspeed_m_s if s.airspeed_m_s is not None else self._best_endurance_eas(h)
            if eas < margin * stall_eas * (1 - 1e-12):
                raise NotAttainable(
                    f"{label}: {eas:.1f} m/s EAS is below stall ({margin:g} x "
                    f"{stall_eas:.1f} m/s EAS): not attainable, below stall"
                )
            if s.type in ("climb", "descent"):
                target = float(s.to_altitude_m)  # type: ignore[arg-type]
                if (s.type == "climb") != (target > h):
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
        return tuple(plans)

    def _rho(self, h: Any) -> Any:
        return isa_density_kg_m3(self.field_m + h, self.dt_k)

    def _best_endurance_eas(self, h: float) -> float:
        """EAS of least electrical power in level flight at height ``h`` (full packs)."""
        aircraft = self.case.aircraft
        rho = float(self._rho(h))
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        stall = margin * float(stall_speed_eas_m_s(aircraft))
        eas = np.linspace(stall, 4.0 * stall, 2001)
        v = np.asarray(true_airspeed_m_s(eas, rho), dtype=float)
        x, ok = self._level_throttle_numpy(v, rho)
        power = np.where(ok, self._power_numpy(x, v, rho), np.inf)
        k = int(np.argmin(power))
        if not np.isfinite(power[k]):
            raise NotAttainable(f"loiter at {h:g} m: no level flight up to full throttle")
        return float(eas[k])

    def _level_throttle_numpy(self, v: np.ndarray, rho: float) -> tuple[np.ndarray, np.ndarray]:
        prop = self.case.propulsion
        sigma = density_ratio(prop, rho)
        t = [sum(np.asarray(engine_thrust_n(e, x, v, sigma), dtype=float) for e in prop.engines)
             for x in (0.0, 0.5, 1.0)]
        a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
        b = t[2] - t[0] - a
        c = t[0] - np.asarray(level_flight_drag_n(self.case.aircraft, v, rho), dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            x, reached = least_throttle_reaching(a, b, c)
        return np.asarray(x, dtype=float), np.asarray(reached) > 0.5

    def _power_numpy(self, x: np.ndarray, v: np.ndarray, rho: float) -> np.ndarray:
        total = sum(np.asarray(self._engine_power(i, x, v, rho), dtype=float)
                    for i in range(self.n))
        return np.asarray(total, dtype=float)

    # -- physics at one instant (backend-neutral) -----------------------------------------
    def _engine_power(self, i: int, x: Any, v: Any, rho: Any) -> Any:
        from tuflexperf.models.powertrain import engine_power_w

        prop = self.case.propulsion
        if self.own_power:
            return density_ratio(prop, rho) * engine_power_w(prop.engines[i], x, v)
        return self.fan_power.electrical_power_w(x, v)

    def _instant(self, q: Any, v: Any, rho: Any, plan_p: Any, dead: int | None) -> dict[str, Any]:
        """Throttle, rate of climb, per-engine current/voltage/power at charges ``q``.

        ``plan_p = [solve_x, throttle, rate, rate_from_excess]`` (CasADi or floats).
        """
        import casadi as ca

        prop, aircraft = self.case.propulsion, self.case.aircraft
        solve_x, x_fixed, rate_cmd, from_excess = plan_p[0], plan_p[1], plan_p[2], plan_p[3]
        sigma = density_ratio(prop, rho)
        weight = aircraft.weight_n
        drag = level_flight_drag_n(aircraft, v, rho)
        u_ref, k_exp = prop.reference_voltage_v, prop.voltage_exponent
        live = [i for i in range(self.n) if i != dead]
        volt = [open_circuit_voltage_v(self.params, q[i], self.packs) for i in range(self.n)]
        # windmilling (or zero) dead engine: a drag independent of the throttle
        dead_t: Any = 0.0
        if dead is not None and self.dead_mode == "windmilling":
            dead_t = windmilling_thrust_n(prop.engines[dead], v, sigma, rho, prop.fan_area_m2)
        iterations = 3 if u_ref is not None else 1  # fixed point on the loaded voltage
        for _ in range(iterations):
            factor = [(volt[i] / u_ref) ** k_exp if u_ref is not None else 1.0
                      for i in range(self.n)]
            t = [sum(factor[i] * engine_thrust_n(prop.engines[i], xs, v, sigma) for i in live)
                 for xs in (0.0, 0.5, 1.0)]
            a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
            b = t[2] - t[0] - a
            needed = drag + weight * rate_cmd / v - dead_t
            x_solved, reached = least_throttle_reaching(a, b, t[0] - needed)
            x = ca.if_else(solve_x > 0.5, x_solved, x_fixed)
            thrust = a * x * x + b * x + t[0] + dead_t
            power = []
            current = []
            for i in range(self.n):
                if i == dead:
                    power.append(0.0 * x)
                    current.append(0.0 * x)
                    continue
                p_i = self._engine_power(i, x, v, rho)
                if u_ref is not None:
                    p_i = p_i * (volt[i] / u_ref) ** (1.5 * k_exp)
                power.append(p_i)
                current.append(current_at_power_a(self.params, q[i], p_i, self.packs))
            volt = [
                open_circuit_voltage_v(self.params, q[i], self.packs)
                - self.params.resistance_ohm / self.packs * current[i]
                for i in range(self.n)
            ]
        rate = ca.if_else(from_excess > 0.5, (thrust - drag) * v / weight, rate_cmd)
        ok = ca.if_else(solve_x > 0.5, reached, 1.0)
        # thrust at idle beyond what a commanded descent needs: it cannot be flown that steep
        idle_excess = ca.if_else(solve_x > 0.5, t[0] - needed, 0.0)
        return {"x": x, "rate": rate, "reached": ok, "idle_excess": idle_excess,
                "power": power, "current": current, "voltage": volt}

    # -- the CasADi build -----------------------------------------------------------------
    def _step_functions(self, dead: int | None) -> tuple[Any, Any, Any]:
        """RK4 steps ``(state, step, p) -> state`` over time and over height."""
        import casadi as ca

        n = self.n
        ns = 2 * n + 3  # q_i, e_i, h, distance, t
        s = ca.SX.sym("s", ns)
        p = ca.SX.sym("p", 9)  # solve_x, x, rate, from_excess, eas, forced, v0, vmid, v1
        step = ca.SX.sym("step")

        def rates(state: Any, v_given: Any) -> tuple[Any, Any]:
            h = state[2 * n]
            rho = self._rho(h)
            v_eas = true_airspeed_m_s(p[4], rho)
            v = ca.if_else(p[5] > 0.5, v_given, v_eas)
            inst = self._instant(state[:n], v, rho, p[:4], dead)
            rate = ca.if_else(p[5] > 0.5, p[2], inst["rate"])
            dq = [inst["current"][i] / SECONDS_PER_HOUR for i in range(n)]
            de = [inst["power"][i] / SECONDS_PER_HOUR for i in range(n)]
            d = ca.vertcat(*dq, *de, rate, v, 1.0)
            return d, rate

        def rk4(derivative: Any) -> Any:
            k1 = derivative(s, p[6])
            k2 = derivative(s + 0.5 * step * k1, p[7])
            k3 = derivative(s + 0.5 * step * k2, p[7])
            k4 = derivative(s + step * k3, p[8])
            return s + step / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)

        def in_time(state: Any, v_given: Any) -> Any:
            return rates(state, v_given)[0]

        def in_height(state: Any, v_given: Any) -> Any:
            d, rate = rates(state, v_given)
            # climbs integrate over height: a rate of the wrong sign is flagged by the aux
            # outputs; here it is kept away from zero so the arithmetic stays finite
            safe = ca.if_else(step > 0, ca.fmax(rate, 1e-6), ca.fmin(rate, -1e-6))
            return d / safe

        f_time = ca.Function("step_time", [s, step, p], [rk4(in_time)])
        f_height = ca.Function("step_height", [s, step, p], [rk4(in_height)])
        # auxiliary outputs at a state
        h = s[2 * n]
        rho = self._rho(h)
        v = ca.if_else(p[5] > 0.5, p[6], true_airspeed_m_s(p[4], rho))
        inst = self._instant(s[:n], v, rho, p[:4], dead)
        rate = ca.if_else(p[5] > 0.5, p[2], inst["rate"])
        aux = ca.vertcat(inst["x"], v, rate, inst["reached"], inst["idle_excess"],
                         *inst["current"], *inst["voltage"], *inst["power"])
        f_aux = ca.Function("aux", [s, p], [aux])
        return f_time, f_height, f_aux

    def _build(self) -> None:
        import casadi as ca

        n = self.n
        durations = ca.MX.sym("durations", len(self.plans))
        state = ca.MX.zeros(2 * n + 3, 1)
        states, auxes, bounds = [], [], []
        functions: dict[Any, Any] = {}
        for plan in self.plans:
            if plan.kind == "event":
                bounds.append((sum(x.shape[1] for x in states), 0))
                continue
            if plan.dead not in functions:
                functions[plan.dead] = self._step_functions(plan.dead)
            f_time, f_height, f_aux = functions[plan.dead]
            if plan.kind == "takeoff":
                phases = self._takeoff_phases(plan)
            else:
                p = [1.0 if plan.solve_x else 0.0, plan.throttle, plan.rate,
                     1.0 if plan.rate_from_excess else 0.0, plan.eas, 0.0, 0.0, 0.0, 0.0]
                if plan.kind == "time":
                    phases = [("time", durations[plan.index] / STEPS, np.tile(p, (STEPS, 1)))]
                else:
                    phases = [("height", (plan.end_h - plan.start_h) / STEPS,
                               np.tile(p, (STEPS, 1)))]
            start = sum(x.shape[1] for x in states)
            for kind, step, p_rows in phases:
                f = f_time if kind == "time" else f_height
                steps = p_rows.shape[0]
                run = f.mapaccum(steps)
                history = run(state, ca.repmat(step, 1, steps) if not isinstance(step, float)
                              else ca.DM(np.full((1, steps), step)), ca.DM(p_rows.T))
                both = ca.horzcat(state, history)
                after = p_rows.copy()
                after[:, 6] = p_rows[:, 8]  # the airspeed at the end of each step
                aux_rows = np.vstack([p_rows[:1], after])
                aux = f_aux.map(steps + 1)(both, ca.DM(aux_rows.T))
                states.append(both)
                auxes.append(aux)
                state = history[:, -1]
            bounds.append((start, sum(x.shape[1] for x in states)))
        self.bounds = bounds
        self._history = ca.Function("mission", [durations],
                                    [ca.horzcat(*states), ca.horzcat(*auxes)])
        landing = [1.0 - state[i] / self.capacity_ah for i in range(n)]
        self._landing = ca.Function("landing", [durations], [ca.vertcat(*landing)])
        self.durations = np.array([p.duration_s for p in self.plans], dtype=float)

    def _takeoff_phases(self, plan: _Plan) -> list[tuple[str, float, np.ndarray]]:
        """Ground roll (airspeed history), rotation and the airborne part to the obstacle."""
        from tuflexperf.analysis.takeoff import solve_takeoff

        result = solve_takeoff(self.case)
        if result.distance_to_obstacle_m is None:
            raise NotAttainable(f"segment {plan.index + 1} (takeoff): {result.obstacle_reason}")
        self.takeoff = result
        t_hist = np.asarray(result.history_time_s, dtype=float)
        v_hist = np.asarray(result.history_airspeed_m_s, dtype=float)
        t_acc = float(t_hist[-1])
        dt = t_acc / STEPS
        grid = np.arange(STEPS) * dt
        rows = np.zeros((STEPS, 9))
        rows[:, 1] = 1.0  # full throttle
        rows[:, 5] = 1.0  # airspeed given, height rate forced (0 on the runway)
        rows[:, 6] = np.interp(grid, t_hist, v_hist)
        rows[:, 7] = np.interp(grid + dt / 2, t_hist, v_hist)
        rows[:, 8] = np.interp(grid + dt, t_hist, v_hist)
        phases: list[tuple[str, float, np.ndarray]] = [("time", dt, rows)]
        v_lo = result.liftoff_speed_m_s
        if result.rotation_time_s > 0:
            rot = np.zeros((8, 9))
            rot[:, 1], rot[:, 5], rot[:, 6:9] = 1.0, 1.0, v_lo
            phases.append(("time", result.rotation_time_s / 8, rot))
        v_tr = result.transition_speed_m_s
        airborne_s = float(result.airborne_distance_m) / v_tr
        air = np.zeros((16, 9))
        air[:, 1], air[:, 5], air[:, 6:9] = 1.0, 1.0, v_tr
        air[:, 2] = result.obstacle_height_m / airborne_s
        phases.append(("time", airborne_s / 16, air))
        return phases

    # -- flying ---------------------------------------------------------------------------
    def fly(self, durations: np.ndarray | None = None, solved: dict[str, Any] | None = None
            ) -> MissionResult:
        """Fly the mission (the file's durations, or ``durations`` [s] per segment)."""
        d = self.durations if durations is None else np.asarray(durations, dtype=float)
        states, aux = (np.asarray(m, dtype=float) for m in self._history(d))
        return self._result(states, aux, solved)

    def _result(self, states: np.ndarray, aux: np.ndarray, solved: dict[str, Any] | None
                ) -> MissionResult:
        n = self.n
        q, e = states[:n], states[n:2 * n]
        h, dist, t = states[2 * n], states[2 * n + 1], states[2 * n + 2]
        x, v, rate, reached, idle = (aux[k] for k in range(5))
        current, voltage = aux[5:5 + n], aux[5 + n:5 + 2 * n]
        reason = ""
        first_bad = None
        segments: list[SegmentResult] = []
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
            cut = np.flatnonzero(~(np.min(volt_live, axis=0) >= self.cutoff_v - 1e-9)
                                 | ~np.isfinite(q[:, sl]).all(axis=0))
            if cut.size:
                problems.append((int(cut[0]), "the pack reaches its cut-off voltage "
                                 f"{self.cutoff_v:.1f} V"))
            bad = np.flatnonzero(reached[sl] < 0.5)
            if bad.size:
                problems.append((int(bad[0]), "needs more than full throttle"))
            if plan.kind == "height":
                climbing = plan.end_h > plan.start_h
                wrong = np.flatnonzero((rate[sl] <= 0) if climbing else (rate[sl] >= 0))
                if wrong.size:
                    verb = "climb" if climbing else "descend"
                    what = ("the rate of climb is not attainable" if plan.solve_x
                            else f"cannot {verb} at throttle {plan.throttle:g}")
                    problems.append((int(wrong[0]), what))
                if plan.solve_x and not climbing:
                    steep = np.flatnonzero(idle[sl] > 1e-9)
                    if steep.size:
                        problems.append((int(steep[0]), f"needs less than idle thrust to descend "
                                         f"at {-plan.rate:g} m/s"))
            if problems and first_bad is None:
                k, why = min(problems)
                at = float(t[a + k])
                first_bad = a + k
                reason = f"{label}: {why} at {at:.1f} s ({at / 60:.2f} min into the mission)"
            xs = x[sl]
            segments.append(SegmentResult(
                index=plan.index, type=plan.type,
                time_s=float(t[b - 1] - t[a]), distance_m=float(dist[b - 1] - dist[a]),
                start_altitude_m=float(h[a]), end_altitude_m=float(h[b - 1]),
                airspeed_eas_m_s=plan.eas,
                charge_ah=tuple(float(q[i, b - 1] - q[i, a]) for i in range(n)),
                energy_wh=tuple(float(e[i, b - 1] - e[i, a]) for i in range(n)),
                min_voltage_v=float(np.nanmin(volt_live)) if volt_live.size else math.nan,
                max_throttle=float(np.nanmax(xs)) if live else None,
                dead_engine=self.engines[plan.dead] if plan.dead is not None else None,
            ))
        landing = float(np.min(1.0 - q[:, -1] / self.capacity_ah))
        history = {"time_s": t, "altitude_m": h, "distance_m": dist, "airspeed_m_s": v,
                   "throttle": x, "climb_rate_m_s": rate}
        for i, name in enumerate(self.engines):
            history[f"current_a_{name}"] = current[i]
            history[f"voltage_v_{name}"] = voltage[i]
            history[f"charge_ah_{name}"] = q[i]
        return MissionResult(
            name=self.mission.name, segments=tuple(segments),
            landing_charge_fraction=landing if first_bad is None else math.nan,
            min_landing_charge_fraction=self.reserve, attainable=first_bad is None,
            reason=reason or (f"lands with {100 * landing:.1f} % charge (reserve "
                              f"{100 * self.reserve:g} %)"),
            engines=self.engines, history=history, solved=solved,
        )

    def solve_for(self) -> MissionResult:
        """Longest duration of the ``solve_for`` segment that lands exactly on the reserve.

        Newton (CasADi rootfinder) on ``min_i landing_fraction_i(T) - reserve = 0``; the
        landing fraction falls monotonically with the segment's duration.
        """
        import casadi as ca

        k = self.mission.solve_for
        assert k is not None
        plan = self.plans[k]
        tau = ca.MX.sym("tau")
        d = ca.MX(ca.DM(self.durations))
        d[k] = tau
        g = ca.mmin(self._landing(d)) - self.reserve
        rf = ca.rootfinder("solve_for", "newton", {"x": tau, "g": g},
                           {"abstol": 1e-10, "max_iter": 50, "error_on_fail": False})
        # start from the first-order estimate around a short segment (always attainable
        # when the rest of the mission is): the landing fraction is near-linear in time
        base = self.durations.copy()
        base[k] = 60.0
        f0 = float(np.min(self._landing(base)) - self.reserve)
        jac = ca.Function("dg", [tau], [ca.jacobian(g, tau)])
        slope = float(jac(60.0))
        guess = 60.0 - f0 / slope if slope < 0 else 60.0
        answer = float(rf(x0=max(guess, 1.0))["x"])
        residual = float(ca.Function("g", [tau], [g])(answer))
        if not (math.isfinite(answer) and answer > 0 and abs(residual) < 1e-8):
            raise NotAttainable(
                f"solve_for {plan.type}: no duration lands with the reserve "
                f"{100 * self.reserve:g} % (the rest of the mission alone leaves "
                f"{100 * (f0 + self.reserve):.1f} %)"
            )
        final = self.durations.copy()
        final[k] = answer
        solved = {"segment": plan.type, "index": k, "time_min": answer / 60.0}
        if plan.eas is not None:
            v_true = float(true_airspeed_m_s(plan.eas, self._rho(plan.start_h)))
            solved["distance_km"] = answer * v_true / 1000.0
        return self.fly(final, solved)


def solve_mission(case: Case, mission: MissionFile,
                  min_landing_fraction: float | None = None) -> MissionResult:
    """Fly ``mission`` for ``case`` (solving its ``solve_for`` segment if it names one)."""
    model = MissionModel(case, mission, min_landing_fraction)
    return model.solve_for() if mission.solve_for is not None else model.fly()


_ = G0_M_S2  # weight comes from the aircraft (m g0); kept for the docstring's equations
