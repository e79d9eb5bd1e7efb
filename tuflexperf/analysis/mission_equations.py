"""A mission's equations at one instant and over one RK4 step, on backend-neutral kernels.

The physics of :mod:`tuflexperf.analysis.mission` (see its docstring for the equations):
thrust, power and the packs' loaded voltage at one instant (:meth:`SegmentEquations._algebra`,
:meth:`~SegmentEquations._instant_function`), the RK4 step over time or height
(:meth:`~SegmentEquations._step_functions`) and one segment's graph of steps
(:meth:`~SegmentEquations._segment_graph`). The sampled parameters (aircraft, field,
thrust coefficients, extrapolation error, power corrections, packs) are inputs of every
function (:meth:`SegmentEquations.parameters`); the take-off's step rows too
(:func:`takeoff_matrix`). The same equations build the single case's CasADi functions and
fly a batch's numpy rows (:mod:`tuflexperf.analysis.mission_rows`).

References
----------
Raymer, *Aircraft Design*, 5th ed., 17.2-17.3; Anderson, *Aircraft Performance and Design*,
5.10, 6.7; Tremblay & Dessaint (2009) (battery model).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.airborne import ROTATION_STEPS
from tuflexperf.analysis.cache import BoundedCache, fingerprint
from tuflexperf.analysis.constants import (  # re-exported: the mission's own names
    BURST_OVER_CONTINUOUS as BURST_OVER_CONTINUOUS,
)
from tuflexperf.analysis.constants import (
    RATING_SEGMENT_S as RATING_SEGMENT_S,
)
from tuflexperf.analysis.constants import (
    SECONDS_PER_HOUR,
    STEPS,
)
from tuflexperf.analysis.mission_plan import _Plan
from tuflexperf.models.aircraft import (
    climb_sine,
    level_flight_drag_n,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.battery import (
    current_at_power_a,
    open_circuit_voltage_v,
)
from tuflexperf.models.power_correction import PowerCorrection
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    beyond_tested_m_s,
    density_ratio,
    engine_thrust_n,
    least_throttle_reaching,
    thrust_part,
    windmilling_thrust_n,
)

ARC_STEPS = 64  # the take-off's transition arc (see MissionModel._airborne_phases)
# unrolled Newton steps on the loaded voltage (and a fixed throttle's airspeed): from the
# open-circuit voltage (a few % off) quadratic convergence reaches rounding in 4; 5 for margin
NEWTON = 5
_P_SIZE = 10  # per-step parameters, see MissionModel._step_functions
SAMPLED_AIRCRAFT = ("mass_kg", "wing_area_m2", "cd0", "k")
"""The aircraft's numbers the flight's equations read (its others bound the plan: stall)."""
STRAIGHT_STEPS = 8  # the take-off's straight climb to the obstacle (constant airspeed and rate)
CORRECTION_SIZE = 7
"""A power correction law's entries in ``par``: ``c0``, ``c_x``, ``c_V`` and its throttle and
airspeed spans (:class:`tuflexperf.models.power_correction.PowerCorrection`)."""
_NO_CORRECTION = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0)  # r = 1 exactly: the power as modelled
STEP_FUNCTIONS: BoundedCache[Any] = BoundedCache(64)
"""The step functions of every mission model of the process, keyed on what they read
(:meth:`SegmentEquations._equations_key`): a reading of the case that moves only the fans'
power (a parameter) flies the nominal's functions, not a new build."""


def _known(flag: Any) -> bool:
    """Whether a flag of the plan is a plain number (numpy rows), not a CasADi symbol."""
    return isinstance(flag, (int, float))


def _law_entries(law: PowerCorrection | None) -> tuple[float, ...]:
    """A power correction's :data:`CORRECTION_SIZE` entries of ``par`` (none: ratio 1)."""
    if law is None:
        return _NO_CORRECTION
    return (law.constant, law.per_throttle, law.per_airspeed_s_m, *law.throttle_span,
            *law.airspeed_span_m_s)


class SegmentEquations:
    """The equations of :class:`tuflexperf.analysis.mission.MissionModel` (a mixin: the
    model's case, battery fit, engines and plans are its attributes)."""

    case: Any
    n: int
    n_par: int

    def parameters(self, aircraft: Any = None, density: tuple[Any, Any] | None = None,
                   coefficients: np.ndarray | None = None,
                   extrapolation_n: np.ndarray | None = None, size: int = 1,
                   packs: np.ndarray | None = None) -> np.ndarray:
        """The chained function's ``par`` per row, ``(n_par, size)``: the aircraft's
        :data:`SAMPLED_AIRCRAFT` fields, the field's height [m] and temperature offset [K],
        each engine's six thrust coefficients (POLY22_TERMS order) and extrapolation error
        [N per m/s beyond the tested range], each engine's power correction and the fan-power
        law's (:data:`CORRECTION_SIZE` each, the case's), and the circuit's measured packs per
        engine [-] (a drawn capacity changes them:
        :func:`tuflexperf.models.battery.equivalent_packs`). Each argument left out is the
        case's own (no error)."""
        craft = self.case.aircraft if aircraft is None else aircraft
        atmosphere = self.case.atmosphere
        field_m, dt_k = ((atmosphere.altitude_m, atmosphere.temperature_offset_k)
                         if density is None else density)
        columns = [getattr(craft, name) for name in SAMPLED_AIRCRAFT] + [field_m, dt_k]
        rows = [np.broadcast_to(np.asarray(c, dtype=float).reshape(-1), (size,))
                for c in columns]
        nominal = np.array([[e.coefficients[t] for t in POLY22_TERMS]
                            for e in self.case.propulsion.engines])
        coef = (np.repeat(nominal[:, None, :], size, axis=1) if coefficients is None
                else np.asarray(coefficients, dtype=float))
        rows.extend(coef[j, :, i] for j in range(self.n) for i in range(len(POLY22_TERMS)))
        errors = (np.zeros((self.n, size)) if extrapolation_n is None
                  else np.asarray(extrapolation_n, dtype=float))
        rows.extend(errors[j] for j in range(self.n))
        rows.extend(np.full(size, value) for law in self._corrections()
                    for value in _law_entries(law))
        rows.append(np.broadcast_to(np.asarray(self.packs if packs is None else packs,
                                               dtype=float).reshape(-1), (size,)))
        return np.stack(rows)

    def _corrections(self) -> list[PowerCorrection | None]:
        """Each engine's power correction, then the fan-power law's (the case's)."""
        return ([e.power_correction for e in self.case.propulsion.engines]
                + [getattr(self.fan_power, "power_correction", None)])

    def _symbolic_models(self, par: Any) -> tuple[Any, Any, list[Any], Any]:
        """The aircraft, propulsion and fan-power law with ``par``'s symbols in place of their
        sampled numbers and power corrections, and each engine's extrapolation error [N per m/s
        beyond the tested range] (see :meth:`parameters`)."""
        import dataclasses

        k = len(SAMPLED_AIRCRAFT)
        aircraft = dataclasses.replace(self.case.aircraft,
                                       **{name: par[i] for i, name in enumerate(SAMPLED_AIRCRAFT)})
        base = self.case.propulsion
        terms = len(POLY22_TERMS)
        errors = [par[k + 2 + terms * self.n + j] for j in range(self.n)]
        first = k + 2 + (terms + 1) * self.n
        laws = [PowerCorrection(par[i], par[i + 1], par[i + 2], (par[i + 3], par[i + 4]),
                                (par[i + 5], par[i + 6]))
                for i in range(first, first + CORRECTION_SIZE * (self.n + 1), CORRECTION_SIZE)]
        engines = tuple(dataclasses.replace(engine, power_correction=laws[j], coefficients={
            t: par[k + 2 + terms * j + i] for i, t in enumerate(POLY22_TERMS)})
            for j, engine in enumerate(base.engines))
        fan = self.fan_power
        if dataclasses.is_dataclass(fan) and hasattr(fan, "power_correction"):
            fan = dataclasses.replace(fan, power_correction=laws[-1])
        return aircraft, dataclasses.replace(base, engines=engines), errors, fan

    def _equations_key(self) -> str:
        """What the step functions read besides ``par`` (the power corrections are in it)."""
        import dataclasses

        known = getattr(self, "_known_key", None)
        if known is not None:
            return known
        fan = self.fan_power
        if dataclasses.is_dataclass(fan) and hasattr(fan, "power_correction"):
            fan = dataclasses.replace(fan, power_correction=None)
        self._known_key: str = fingerprint(
            "mission-steps", self.case.aircraft, thrust_part(self.case.propulsion), self.params,
            fan, self.fixed_density, self.field_m, self.dt_k, self.dead_mode, self.own_power,
            self.n, self.n_par)
        return self._known_key

    def _flight_key(self, dead: int | None) -> str:
        """What a phase with engine ``dead`` out reads besides ``par`` and its inputs
        (:meth:`_equations_key`); with every engine alive not how a dead one would drag, so
        a reading that changes only that flies the same phases before its engine failure."""
        import dataclasses

        if dead is not None:
            return self._equations_key()
        known = getattr(self, "_alive_key", None)
        if known is None:
            prop = thrust_part(self.case.propulsion)
            prop = dataclasses.replace(prop, engines=tuple(
                dataclasses.replace(e, windmilling_drag_coefficient=None) for e in prop.engines))
            fan = self.fan_power
            if dataclasses.is_dataclass(fan) and hasattr(fan, "power_correction"):
                fan = dataclasses.replace(fan, power_correction=None)
            known = self._alive_key = fingerprint(
                "mission-alive", self.case.aircraft, prop, self.params, fan, self.fixed_density,
                self.field_m, self.dt_k, self.own_power, self.n, self.n_par)
        return known

    def _rho(self, h: Any, par: Any = None) -> Any:
        """ISA density [kg/m^3] at ``h`` [m] above the field (the sampled field height and
        temperature offset of ``par`` where given)."""
        if self.fixed_density is not None:
            return self.fixed_density + 0.0 * h
        if par is not None:
            return isa_density_kg_m3(par[4] + h, par[5])
        # the nodes of a segment after its failure hold no flight (a climb that cannot climb
        # integrates to -4.5e6 m there): the ISA's stratosphere branch overflows on them,
        # harmlessly, as only the nodes before the failure are reported
        with np.errstate(over="ignore"):
            return isa_density_kg_m3(self.field_m + h, self.dt_k)

    def _modelled_power(self, i: int, x: Any, v: Any, rho: Any, prop: Any = None,
                        fan: Any = None) -> Any:
        """Engine ``i``'s electrical power [W] as its model gives it (may be negative): the
        case's propulsion and fan-power law, or ``prop`` and ``fan`` where given."""
        from tuflexperf.models.powertrain import engine_power_w

        prop = self.case.propulsion if prop is None else prop
        if self.own_power:
            return density_ratio(prop, rho) * engine_power_w(prop.engines[i], x, v)
        return (self.fan_power if fan is None else fan).electrical_power_w(x, v)

    def _engine_power(self, i: int, x: Any, v: Any, rho: Any, prop: Any = None,
                      fan: Any = None) -> Any:
        from tuflexperf.models._math import fmax

        # an ESC draws, it does not charge: the power surface extrapolated to idle at high
        # airspeed dips below zero, which "charged" the pack past its circuit (a dive failed
        # on a cut-off it never reached)
        return fmax(self._modelled_power(i, x, v, rho, prop, fan), 0.0)

    def _algebra(self, u: list[Any], v: Any, q: Any, rho: Any, plan_p: Any,
                 dead: int | None, par: Any) -> dict[str, Any]:
        """Everything at loaded pack voltages ``u`` [V] and true airspeed ``v`` [m/s]: the
        flight (:meth:`_flight`) and the packs (:meth:`_packs`).

        ``plan_p = [solve_x, throttle, rate, rate_from_excess]``. Without a reference
        voltage ``u`` is ignored and the current is the closed-form constant-power root.
        ``par`` holds the sampled parameters (:meth:`parameters`). Backend-neutral: CasADi
        symbols build the step functions, numpy rows fly a batch
        (:mod:`tuflexperf.analysis.mission_rows`).
        """
        flight = self._flight(u, v, rho, plan_p, dead, par)
        flight["power"] = self._powers(u, flight["x"], v, rho, dead, par)
        return {**flight, **self._packs(u, q, flight["power"], dead, par)}

    def _flight(self, u: Any, v: Any, rho: Any, plan_p: Any, dead: int | None,
                par: Any) -> dict[str, Any]:
        """Throttle, thrust [N] and height rate [m/s] at loaded voltages ``u`` [V] (ignored
        without a reference voltage: None will do) and true airspeed ``v`` [m/s]; the
        power is :meth:`_powers`' (a reading of the measured power flies the same flight
        on other powers). Each engine's
        extrapolation error [N per m/s] adds to its thrust, times the distance beyond the
        tested airspeeds. A flag of ``plan_p`` given as a number takes its branch alone
        (numpy rows: the other is not computed)."""
        from tuflexperf.models._math import where

        aircraft, prop, errors, fan = self._symbolic_models(par)
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
        # the extrapolation error is drawn per m/s beyond the tested range
        beyond = sigma * beyond_tested_m_s(prop, v)
        t = [sum(factor[i] * (engine_thrust_n(prop.engines[i], xs, v, sigma)
                              + beyond * errors[i]) for i in live)
             for xs in (0.0, 0.5, 1.0)]
        a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
        b = t[2] - t[0] - a
        needed = drag + weight * rate_cmd / v - dead_t
        if _known(solve_x) and solve_x <= 0.5:  # a fixed throttle: no root to find
            x, ok, idle_excess = x_fixed, 1.0, 0.0 * v
        else:
            x_solved, reached = least_throttle_reaching(a, b, t[0] - needed)
            x = where(solve_x > 0.5, x_solved, x_fixed)
            ok = where(solve_x > 0.5, reached, 1.0)
            # thrust at idle beyond what a commanded descent needs: it cannot be flown that
            # steep
            idle_excess = where(solve_x > 0.5, t[0] - needed, 0.0)
        thrust = a * x * x + b * x + t[0] + dead_t
        if _known(from_excess):
            rate = climb_sine((thrust - drag) / weight) * v if from_excess > 0.5 else rate_cmd
        else:
            rate = where(from_excess > 0.5, climb_sine((thrust - drag) / weight) * v, rate_cmd)
        return {"x": x, "rate": rate, "reached": ok, "idle_excess": idle_excess,
                "v": v, "level_residual": (thrust - drag) / weight, "thrust": thrust}

    def _powers(self, u: Any, x: Any, v: Any, rho: Any, dead: int | None,
                par: Any) -> list[Any]:
        """Each engine's electrical power [W] at throttle ``x`` and true airspeed ``v``
        [m/s] (times ``(U/U_ref)^(1.5 k)`` at loaded voltages ``u`` [V] with a reference
        voltage), with ``par``'s power corrections; a dead engine's is 0."""
        _, prop, _, fan = self._symbolic_models(par)
        u_ref, k_exp = prop.reference_voltage_v, prop.voltage_exponent
        power = []
        for i in range(self.n):
            if i == dead:
                power.append(0.0 * x)
                continue
            p_i = self._engine_power(i, x, v, rho, prop, fan)
            if u_ref is not None:
                # fan laws: power ~ rpm^3 while thrust ~ rpm^2 (SPEC 3 voltage effect)
                p_i = p_i * (u[i] / u_ref) ** (1.5 * k_exp)
            power.append(p_i)
        return power

    def _packs(self, u: Any, q: Any, power: list[Any], dead: int | None,
               par: Any) -> dict[str, Any]:
        """Each engine's current [A] and loaded voltage [V] drawing ``power`` [W] with
        charges ``q`` [Ah] drawn, and the residuals of the loaded voltages ``u`` [V] (with a
        reference voltage the power follows them: :meth:`_instant_function` solves them)."""
        packs = par[self.n_par - 1]
        r = self.params.resistance_ohm / packs
        u_ref = self.case.propulsion.reference_voltage_v
        current, volt, residual = [], [], []
        for i in range(self.n):
            ocv = open_circuit_voltage_v(self.params, q[i], packs)
            if i == dead:
                current.append(0.0 * power[i])
                volt.append(ocv)
                residual.append(u[i] - ocv if u is not None else 0.0 * ocv)
                continue
            if u_ref is None:
                i_i = current_at_power_a(self.params, q[i], power[i], packs)
                residual.append(u[i] - (ocv - r * i_i) if u is not None else 0.0 * ocv)
            else:
                i_i = power[i] / u[i]
                residual.append(ocv - r * i_i - u[i])
            current.append(i_i)
            volt.append(ocv - r * i_i)
        return {"current": current, "voltage": volt, "u_residual": residual}

    def _instant_function(self, dead: int | None, solve_v: bool) -> Any:
        """``(q, v_in, rho, p, par) -> aux`` with the loaded voltages (and airspeed) solved.

        With a reference voltage the loaded voltage ``U = OCV - (R/n) P(U) / U`` is implicit
        (power follows the voltage); with ``solve_v`` the true airspeed of level flight at the
        fixed throttle is unknown too (the fast root, from the guess ``v_in``). Both are
        solved by :data:`NEWTON` unrolled Newton steps (quadratic convergence from the
        open-circuit voltage and the full-pack airspeed: machine precision).
        """

        key = (dead, solve_v)
        if key in self._instants:
            return self._instants[key]
        self._instants[key] = STEP_FUNCTIONS.get(
            f"{self._equations_key()}:instant:{dead}:{solve_v}",
            lambda: self._build_instant_function(dead, solve_v))
        return self._instants[key]

    def _build_instant_function(self, dead: int | None, solve_v: bool) -> Any:
        """:meth:`_instant_function`, built."""
        import casadi as ca

        n = self.n
        q = ca.SX.sym("q", n)
        v_in, rho = ca.SX.sym("v_in"), ca.SX.sym("rho")
        p = ca.SX.sym("p", 4)
        par = ca.SX.sym("par", self.n_par)
        voltage_unknown = self.case.propulsion.reference_voltage_v is not None
        ocv = [open_circuit_voltage_v(self.params, q[i], par[self.n_par - 1]) for i in range(n)]
        m = (n if voltage_unknown else 0) + (1 if solve_v else 0)
        z = ca.SX.sym("z", m)

        def split(zz: Any) -> tuple[list[Any], Any]:
            u = [zz[i] for i in range(n)] if voltage_unknown else ocv
            return u, (zz[m - 1] if solve_v else v_in)

        def equations(zz: Any) -> Any:
            u, v = split(zz)
            alg = self._algebra(u, v, q, rho, p, dead, par)
            parts = list(alg["u_residual"]) if voltage_unknown else []
            if solve_v:
                parts.append(alg["level_residual"])
            return ca.vertcat(*parts)

        if m:
            res = equations(z)
            newton = ca.Function("newton_step", [z, q, v_in, rho, p, par],
                                 [z - ca.solve(ca.jacobian(res, z), res)])
            start = ca.vertcat(*(ocv if voltage_unknown else []), *([v_in] if solve_v else []))
            zk = start
            # without the voltage effect a fixed throttle's airspeed does not change along
            # the segment: the guess is the root already (to ~1e-15), one step polishes it
            for _ in range(NEWTON if voltage_unknown else 1):
                zk = newton(zk, q, v_in, rho, p, par)
            u, v = split(zk)
        else:
            u, v = ocv, v_in
        alg = self._algebra(u, v, q, rho, p, dead, par)
        out = ca.vertcat(alg["x"], alg["v"], alg["rate"], alg["reached"], alg["idle_excess"],
                         alg["level_residual"], *alg["current"], *alg["voltage"],
                         *alg["power"], alg["thrust"])
        return ca.Function(f"instant_{dead}_{int(solve_v)}", [q, v_in, rho, p, par], [out])

    # -- the CasADi build -----------------------------------------------------------------
    def _stepper(self, dead: int | None, solve_v: bool, kind: str) -> Any:
        """One step function of :meth:`_step_functions`, built the first time it is asked for.

        A segment uses one or two of the four (a cruise only ``time`` and ``aux``), so the
        others are never built (each is a few milliseconds of symbolic construction).
        """
        key = (dead, solve_v, kind)
        if key not in self._steps:
            self._steps[key] = STEP_FUNCTIONS.get(
                f"{self._equations_key()}:step:{dead}:{solve_v}:{kind}",
                lambda: self._step_functions(dead, solve_v, kind))
        return self._steps[key]

    def _step_functions(self, dead: int | None, solve_v: bool, kind: str) -> Any:
        """RK4 step ``(state, step, p, par) -> state`` over ``kind`` (time, height), or the aux.

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
        par = ca.SX.sym("par", self.n_par)
        step = ca.SX.sym("step")
        instant = self._instant_function(dead, solve_v)

        def evaluate(state: Any, v_given: Any) -> Any:
            rho = self._rho(state[2 * n], par)
            v_free = p[9] if solve_v else true_airspeed_m_s(p[4], rho)
            v_in = ca.if_else(p[5] > 0.5, v_given, v_free)
            a = instant(state[:n], v_in, rho, p[:4], par)
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
            return ca.Function("aux", [s, p, par], [evaluate(s, p[6])])
        derivative = {"time": in_time, "height": in_height}[kind]
        return ca.Function(f"step_{kind}", [s, step, p, par], [rk4(derivative)])

    def _segment_graph(self, plan: _Plan, state: Any, durations: Any, theta: Any, par: Any,
                       tk: Any, nodes_aux: bool = True) -> tuple[list[Any], list[Any], Any]:
        """One segment flown from ``state`` (MX): its nodes, their aux outputs, the end state.

        ``par`` the sampled parameters, ``tk`` the take-off's step rows (:meth:`_takeoff_rows`).
        Without ``nodes_aux`` only the aux at the segment's end is computed (a list of one).
        """
        import casadi as ca

        f_aux = self._stepper(plan.dead, plan.solve_v, "aux")
        if plan.kind == "takeoff":
            phases: list[tuple[str, Any, Any]] = []
            first = 0
            for _, cols in self.tk_layout:  # every phase of the take-off flown in time
                phases.append(("time", tk[_P_SIZE, first:first + cols],
                               tk[:_P_SIZE, first:first + cols]))
                first += cols
        else:
            j = 3 * plan.index
            p = ca.vertcat(1.0 if plan.solve_x else 0.0, theta[j], plan.rate,
                           1.0 if plan.rate_from_excess else 0.0, theta[j + 1],
                           0.0, 0.0, 0.0, 0.0, theta[j + 2])
            rows = ca.repmat(p, 1, STEPS)
            if plan.kind == "time":
                phases = [("time", durations[plan.index] / STEPS, rows)]
            else:
                phases = [("height", ca.MX((plan.end_h - plan.start_h) / STEPS), rows)]
        nodes, auxes = [], []
        for kind, step, p_rows in phases:
            f = self._stepper(plan.dead, plan.solve_v, kind)
            steps = p_rows.shape[1]
            # a step per row (the take-off's, from its rows) or one for all
            step_row = step if step.shape[1] == steps else ca.repmat(step, 1, steps)
            history = f.mapaccum(steps)(state, step_row, p_rows, ca.repmat(par, 1, steps))
            both = ca.horzcat(state, history)
            # the aux at each node: the airspeed given at a step's start (first node) or end
            after = ca.vertcat(p_rows[:6, :], p_rows[8, :], p_rows[7:, :])
            if nodes_aux:
                auxes.append(f_aux.map(steps + 1)(both, ca.horzcat(p_rows[:, 0], after),
                                                  ca.repmat(par, 1, steps + 1)))
            nodes.append(both)
            state = history[:, -1]
        if not nodes_aux:
            auxes.append(f_aux(state, after[:, -1], par))
        return nodes, auxes, state


@dataclass(frozen=True)
class AirbornePath:
    """The take-off's path from lift-off to the obstacle, one value per row: transition
    speed [m/s], arc time [s], the arc's climb rates per step ``(B, ARC_STEPS)`` [m/s], the
    straight climb's time [s] and sine of its angle [-]."""

    speed: np.ndarray
    arc_s: np.ndarray
    arc_rates: np.ndarray
    straight_s: np.ndarray
    sine: np.ndarray


def airborne_path(v_tr: np.ndarray, radius: np.ndarray, height: np.ndarray,
                  gradient: np.ndarray, arc_gradient: np.ndarray,
                  cleared: np.ndarray, steps: int = ARC_STEPS) -> AirbornePath:
    """The take-off's airborne part flown along its path at the transition speed.

    The arc of radius ``R`` [m] at ``V_tr`` [m/s] (height ``R (1 - cos(V_tr t / R))``) up to
    the climb angle ``asin(G)`` of the arc's gradient, or up to the obstacle ``height`` [m]
    if the arc clears it, then the straight climb at ``V_tr G`` [m/s] to the obstacle height
    (Anderson, *Aircraft Performance and Design*, 6.7): times from the path's length, not its
    horizontal distance. Each of the arc's ``steps`` climbs its exact height difference.
    Arrays ``(B,)``.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        sine = np.minimum(gradient, 1.0)  # a gradient of 1 or more climbs vertically
        over = np.arccos(1.0 - height / radius)
        angle = np.arcsin(np.minimum(arc_gradient, 1.0))
        straight = (height - radius * (1.0 - np.cos(angle))) / (v_tr * sine)
        angle = np.where(cleared, over, angle)
        straight_s = np.where(cleared, 0.0, straight)
        arc_s = radius * angle / v_tr
        # each step climbs its chord at a constant rate: the height inside a step (and so the
        # density the fans see) is off by ~ (dt^2/8) V^2/R; 64 steps keep the charge to 1e-8
        step = arc_s / steps
        t = np.arange(steps + 1)[None, :] * step[:, None]
        t[:, -1] = arc_s
        h = radius[:, None] * (1.0 - np.cos(v_tr[:, None] * t / radius[:, None]))
        rates = np.diff(h, axis=1) / step[:, None]
    return AirbornePath(v_tr, arc_s, rates, straight_s, sine)


def takeoff_layout(rotation: bool, airborne: bool, straight: bool, steps: int = STEPS
                   ) -> list[tuple[str, int]]:
    """The take-off's phases and their steps: roll, rotation (when it takes time), arc (to
    the obstacle) and straight climb (when the arc does not clear the obstacle); the roll
    and the arc in ``steps``, the rotation and the straight climb (a few seconds at one
    airspeed) in as many fewer (the single case's :data:`STEPS`: :data:`ARC_STEPS`,
    ``ROTATION_STEPS``, :data:`STRAIGHT_STEPS`)."""
    layout = [("roll", steps)]
    if rotation:
        layout.append(("rotation", max(1, ROTATION_STEPS * steps // STEPS)))
    if airborne:
        layout.append(("arc", steps * ARC_STEPS // STEPS))
        if straight:
            layout.append(("straight", max(1, STRAIGHT_STEPS * steps // STEPS)))
    return layout


def takeoff_matrix(layout: list[tuple[str, int]], stages: np.ndarray, roll_s: np.ndarray,
                   rotation_s: np.ndarray, v_lo: np.ndarray,
                   air: AirbornePath | None) -> np.ndarray:
    """The take-off's step rows per row of a batch, ``(B, P + 1, columns)``: per step the
    parameters of :meth:`MissionModel._step_functions` (full throttle, airspeed given at the
    step's start, middle and end, height rate) and, last, the step [s].

    ``stages`` ``(B, 2 S + 1)`` the roll's airspeeds [m/s] at each of its ``S`` steps'
    start, middle and end; ``roll_s``, ``rotation_s`` [s], ``v_lo`` [m/s] per row. A phase
    a row does not fly has steps of no time.
    """
    size = stages.shape[0]
    blocks = []
    for name, cols in layout:
        block = np.zeros((size, _P_SIZE + 1, cols))
        block[:, 1, :] = 1.0  # full throttle
        block[:, 5, :] = 1.0  # airspeed given, height rate forced (0 on the runway)
        if name == "roll":
            block[:, 6, :], block[:, 7, :] = stages[:, 0:-1:2], stages[:, 1::2]
            block[:, 8, :] = stages[:, 2::2]
            block[:, _P_SIZE, :] = (roll_s / cols)[:, None]
        elif name == "rotation":
            block[:, 6:9, :] = v_lo[:, None, None]
            block[:, _P_SIZE, :] = (rotation_s / cols)[:, None]
        elif name == "arc" and air is not None:
            block[:, 6:9, :] = air.speed[:, None, None]
            block[:, 2, :] = air.arc_rates
            block[:, _P_SIZE, :] = (air.arc_s / cols)[:, None]
        elif air is not None:
            block[:, 6:9, :] = air.speed[:, None, None]
            block[:, 2, :] = (air.speed * air.sine)[:, None]
            block[:, _P_SIZE, :] = (air.straight_s / cols)[:, None]
        blocks.append(block)
    return np.concatenate(blocks, axis=2) if blocks else np.zeros((size, _P_SIZE + 1, 0))
