"""Sensitivities of every requirement's value to the case's parameters by CasADi AD.

Each requirement's value is written once more on CasADi symbols with the same model
functions (:mod:`tuflexperf.models` is backend-neutral), following the deterministic
analysis at the nominal case: the same quadrature structure, the active grid point or dead
engine, the launch's RK4 with its nominal step count, and one Newton step from each
converged nominal root (exact first derivative by the implicit-function theorem). The
symbolic value at the nominal equals the deterministic one (a test checks it), and its
Jacobian is the sensitivity.

References
----------
Andersson et al. (2019), "CasADi", Math. Prog. Comp. 11, 1-36; Griewank & Walther,
*Evaluating Derivatives*, 2nd ed., ch. 15 (derivatives of implicitly defined functions).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from tuflexperf.analysis.airborne import ROTATION_STEPS, obstacle_height_of
from tuflexperf.analysis.batch import present_requirements
from tuflexperf.analysis.constants import MAX_SPEED_OVER_STALL, SPEED_GRID_POINTS, STEPS
from tuflexperf.analysis.pack_limits import sagging_packs
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    climb_gradient,
    ground_roll_net_force_n,
    level_flight_drag_n,
    liftoff_speed_m_s,
    obstacle_distances_m,
    stall_speed_m_s,
    transition_radius_m,
    transition_speed_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.battery import (
    current_at_power_a,
    cutoff_residual_v,
    discharge_time_s,
    equivalent_packs,
)
from tuflexperf.models.thrust import least_throttle_reaching, total_thrust_n

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(64)


class _Symbolic:
    """The case with some parameters as CasADi symbols."""

    def __init__(self, case: Case, keys: list[str]) -> None:
        import casadi as ca

        self.ca = ca
        self.case = case
        self.symbols = {key: ca.SX.sym(key) for key in keys}
        base = case.aircraft

        def pick(key: str, nominal: Any) -> Any:
            return self.symbols.get(key, nominal)

        takeoff = dataclasses.replace(base.takeoff, **{
            f.name: pick(f"aircraft.takeoff.{f.name}", getattr(base.takeoff, f.name))
            for f in dataclasses.fields(base.takeoff)})
        self.aircraft = dataclasses.replace(base, takeoff=takeoff, **{
            f.name: pick(f"aircraft.{f.name}", getattr(base, f.name))
            for f in dataclasses.fields(base) if f.name not in ("name", "takeoff")})
        atmosphere = case.atmosphere
        altitude = pick("atmosphere.altitude_m", atmosphere.altitude_m)
        offset = pick("atmosphere.temperature_offset_k", atmosphere.temperature_offset_k)
        self.density = isa_density_kg_m3(altitude, offset)
        self.propulsion = case.propulsion
        endurance = case.requirements.endurance
        self.throttle = pick("requirements.endurance.throttle",
                             endurance.throttle if endurance else 0.0)
        self.height = pick("requirements.takeoff.obstacle_height_m", obstacle_height_of(case))

    # -- physics on symbols --------------------------------------------------------------------
    def thrust(self, throttle: Any, speed: Any, dead: int | None = None,
               mode: str = "windmilling") -> Any:
        return total_thrust_n(self.propulsion, throttle, speed, self.density, dead, mode)

    def force(self, speed: Any) -> Any:
        return ground_roll_net_force_n(self.aircraft, self.thrust(1.0, speed), speed,
                                       self.density)

    def liftoff(self) -> Any:
        return liftoff_speed_m_s(self.aircraft, self.density)

    def ground_roll(self) -> tuple[Any, Any]:
        """Ground roll [m] and its time [s]: Gauss-Legendre, split at the friction kink."""
        ca = self.ca
        ac, v_lo = self.aircraft, self.liftoff()
        to = ac.takeoff
        pieces = [(0.0, v_lo)]
        if not (isinstance(to.cl_ground, (int, float)) and to.cl_ground == 0.0):
            kink = ca.sqrt(2.0 * ac.weight_n / (self.density * ac.wing_area_m2 * to.cl_ground))
            middle = ca.fmin(kink, v_lo)
            pieces = [(0.0, middle), (middle, v_lo)]
        distance, time = 0.0, 0.0
        for low, high in pieces:
            nodes = low + (high - low) * 0.5 * (ca.DM(_GL_NODES) + 1.0)
            weights = ca.DM(_GL_WEIGHTS) * 0.5 * (high - low)
            force = self.force(nodes)
            distance = distance + ca.dot(weights, ac.mass_kg * nodes / force)
            time = time + ca.dot(weights, ac.mass_kg / force)
        return distance + v_lo * to.rotation_time_s, time + to.rotation_time_s

    def least_throttle(self, speed: Any, dead: int | None = None,
                       mode: str = "windmilling") -> Any:
        t0 = self.thrust(0.0, speed, dead, mode)
        th = self.thrust(0.5, speed, dead, mode)
        t1 = self.thrust(1.0, speed, dead, mode)
        quadratic = 2.0 * (t1 - 2.0 * th + t0)
        drag = level_flight_drag_n(self.aircraft, speed, self.density)
        throttle, _ = least_throttle_reaching(quadratic, t1 - t0 - quadratic, t0 - drag)
        return throttle

    def newton_step(self, residual: Any, at: float) -> Any:
        """One Newton step of ``residual(x)`` from its converged nominal root ``at``."""
        ca = self.ca
        x = ca.SX.sym("x")
        r = residual(x)
        slope = ca.jacobian(r, x)
        return at - ca.substitute(r / slope, x, ca.SX(at))


def _trim_value(s: _Symbolic) -> Any:
    from tuflexperf.analysis.trim import solve_trim

    result = solve_trim(s.case)
    if not result.all_feasible:
        return None
    return s.least_throttle(_grid_airspeed(s, int(np.argmax(result.throttle))))


def _oei_value(s: _Symbolic) -> Any:
    from tuflexperf.analysis.oei import solve_oei

    mode = s.case.requirements.oei.dead_engine
    result = solve_oei(s.case, mode)
    worst = result.critical
    if worst.min_throttle is None:
        return None
    dead = [c.dead_engine for c in result.cases].index(worst.dead_engine)
    index = int(np.argmin(np.abs(worst.airspeed_m_s - worst.airspeed_at_min_throttle_m_s)))
    return s.least_throttle(_grid_airspeed(s, index), dead, mode)


def _grid_airspeed(s: _Symbolic, index: int) -> Any:
    """The envelope grid's airspeed ``index`` [m/s] as it moves with the symbols: a bound
    given as an equivalent airspeed follows the density, and the grid between the bounds
    with it (``numpy.linspace``'s own arithmetic, so the nominal value is the grid's)."""
    from tuflexperf.analysis.level_flight import airspeed_grid
    from tuflexperf.analysis.trim import envelope_of

    envelope = s.case.requirements.envelope
    grid = airspeed_grid(*envelope_of(s.case))
    if not envelope.in_eas:
        return float(grid[index])
    low, high = envelope.bounds_m_s(s.density)  # an EAS bound as the density moves it
    steps = grid.size - 1
    return high if index == steps else index * ((high - low) / steps) + low


def _endurance_value(s: _Symbolic) -> Any:
    """Flight endurance [min] along the nominal solution's structure (see module doc)."""
    from tuflexperf.analysis import endurance as single
    from tuflexperf.errors import NotAttainable

    ca = s.ca
    model = single.endurance_model(s.case)
    nominal_throttle = float(s.case.requirements.endurance.throttle)
    try:
        result = model.solve(nominal_throttle)
    except NotAttainable:
        return None
    launch, battery = model.launch, model.battery
    ac, rho = s.aircraft, s.density
    count = 101
    catapult = ac.launch == "catapult"
    if catapult:
        # airborne at the release speed (an EAS): no roll, the climb starts there
        from tuflexperf.models.aircraft import true_airspeed_m_s

        v_lo = true_airspeed_m_s(ac.launch_speed_m_s, rho)
        t_hist = v_hist = None
    else:
        # the roll's time history on 101 airspeeds (the launch interpolates power along it)
        v_lo = s.liftoff()
        nodes = v_lo * ca.DM(np.linspace(0.0, 1.0, count))
        g = ac.mass_kg / s.force(nodes)
        h = v_lo / (count - 1)
        left = ca.vertcat(2 * g[0] - g[1], g[0:count - 2])
        right = ca.vertcat(g[2:count], 2 * g[count - 1] - g[count - 2])
        pieces = h / 24.0 * (-left + 13.0 * g[0:count - 1] + 13.0 * g[1:count] - right)
        t_hist = ca.vertcat(0.0, ca.cumsum(pieces))
        v_hist = nodes
    # best climb on the same grid point as the nominal
    stall = stall_speed_m_s(ac, rho)
    n = SPEED_GRID_POINTS
    low0 = launch.liftoff_speed_m_s
    top0 = MAX_SPEED_OVER_STALL * float(stall_speed_m_s(s.case.aircraft,
                                                                  s.case.density_kg_m3))
    k = round((launch.climb_airspeed_m_s - low0) / (top0 - low0) * (n - 1))
    v_climb = v_lo + (MAX_SPEED_OVER_STALL * stall - v_lo) * k / (n - 1)
    rate = (s.thrust(1.0, v_climb) - level_flight_drag_n(ac, v_climb, rho)) * v_climb \
        / ac.weight_n
    height = s.symbols.get("battery.mission.pattern_altitude_m", battery.pattern_altitude_m)
    climb_time = height / rate if battery.pattern_altitude_m > 0 else 0.0
    # the launch's RK4 in the single case's mission's steps: STEPS of equal time along the
    # roll's history, ROTATION_STEPS at the lift-off speed, STEPS of the climb; power looked
    # up as the nominal does; a catapult launch has no roll

    rotation: Any = 0.0 if catapult else ac.takeoff.rotation_time_s
    roll_only = 0.0 if catapult else t_hist[count - 1]
    t_hist0 = None if catapult else (
        np.asarray(ca.evalf(ca.substitute(t_hist, ca.vertcat(*s.symbols.values()),
                                          _nominal_vector(s)))).ravel()
        if s.symbols else np.asarray(ca.evalf(t_hist)).ravel())
    dt0 = 0.0 if catapult else float(t_hist0[-1]) / STEPS
    dt = roll_only / STEPS
    climb_power = _power_w(s, model, 1.0, v_climb)

    def stage_power(j: int) -> Any:
        t0_value = 0.5 * j * dt0
        index = min(max(int(np.searchsorted(t_hist0, t0_value, side="right")) - 1, 0),
                    count - 2)
        if t0_value >= t_hist0[-1]:
            speed = v_hist[count - 1]
        else:
            t = 0.5 * j * dt
            speed = v_hist[index] + (t - t_hist[index]) * (v_hist[index + 1] - v_hist[index]) \
                / (t_hist[index + 1] - t_hist[index])
        return _power_w(s, model, 1.0, speed)

    # a pack of another capacity flies as that many measured packs in parallel
    capacity = s.symbols.get("battery.capacity_ah", battery.capacity_ah)
    packs = equivalent_packs(battery.packs_in_parallel_per_engine, capacity,
                             battery.as_read.capacity_ah)

    def rate_at(power: Any, charge: Any) -> Any:
        return current_at_power_a(model.params, charge, power, packs) / 3600.0

    def rk4(q: Any, h: Any, powers: tuple[Any, Any, Any]) -> Any:
        k1 = rate_at(powers[0], q)
        k2 = rate_at(powers[1], q + h / 2 * k1)
        k3 = rate_at(powers[1], q + h / 2 * k2)
        k4 = rate_at(powers[2], q + h * k3)
        return q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    q: Any = 0.0
    for step in range(0 if catapult else STEPS):
        q = rk4(q, dt, (stage_power(2 * step), stage_power(2 * step + 1),
                        stage_power(2 * step + 2)))
    if not catapult and s.case.aircraft.takeoff.rotation_time_s > 0.0:  # the nominal's steps
        at_liftoff = _power_w(s, model, 1.0, v_lo)
        for _ in range(ROTATION_STEPS):
            q = rk4(q, rotation / ROTATION_STEPS, (at_liftoff,) * 3)
    for _ in range(STEPS):
        q = rk4(q, climb_time / STEPS, (climb_power,) * 3)
    # level flight at the throttle (fast root) and the pack's cut-off charge
    x = s.throttle
    speed = s.newton_step(
        lambda v: s.thrust(x, v) - level_flight_drag_n(ac, v, rho), result.airspeed_m_s)
    power_w = _power_w(s, model, x, speed)
    cutoff = battery.cells_in_series * s.symbols.get("battery.cutoff_voltage_per_cell_v",
                                                     battery.cutoff_voltage_per_cell_v)
    reserve = s.symbols.get("battery.mission.landing_reserve_fraction",
                            battery.landing_reserve_fraction)
    q_cut = s.newton_step(
        lambda c: cutoff_residual_v(model.params, c, power_w, cutoff, packs),
        _nominal_cutoff(model, result))
    reserve_ah = battery.packs_in_parallel_per_engine * capacity * (1.0 - reserve)
    end = reserve_ah if result.cruise_ends_at == "landing reserve" else q_cut
    cruise = discharge_time_s(model.params, power_w, q, end, packs)
    return cruise / 60.0 + climb_time / 60.0


def _power_w(s: _Symbolic, model: Any, throttle: Any, speed: Any) -> Any:
    """Per-fan electrical power [W] as the single case: a propulsion power surface follows
    the density (``rho / rho_ref`` against the nominal's scale), a battery law does not."""
    from tuflexperf.models.powertrain import PowerSurfaces
    from tuflexperf.models.thrust import density_ratio

    power = model.power.electrical_power_w(throttle, speed)
    if isinstance(model.power, PowerSurfaces):
        power = power * density_ratio(s.propulsion, s.density) / model.power.density_scale
    return power


def _nominal_vector(s: _Symbolic) -> Any:
    from tuflexperf.io.dotted import numeric_keys

    nominal = numeric_keys(s.case)
    return s.ca.DM([nominal[k] for k in s.symbols])


def _nominal_cutoff(model: Any, result: Any) -> float:
    """The nominal cut-off charge of the parallel packs [Ah] (the deterministic's root)."""
    from tuflexperf.models.battery import cutoff_charge_ah

    return float(cutoff_charge_ah(model.params, result.electrical_power_w, model.cutoff_v,
                                  model.packs))


def symbolic_values(case: Case, keys: list[str]) -> tuple[Any, dict[str, Any]]:
    """CasADi symbols (in ``keys`` order) and each requirement's value as an expression."""
    s = _Symbolic(case, keys)
    values: dict[str, Any] = {}
    roll = None
    # the take-off and the endurance on sagging packs (the charge a state of the flight) and a
    # catapult's acceleration after the release have no symbolic form here: no derivative,
    # rather than the reference voltage's or the arc's alone
    sagging = sagging_packs(case)
    for requirement in present_requirements(case):
        name = requirement.name
        if sagging and name in ("takeoff_ground_roll", "takeoff_distance_to_obstacle",
                                "flight_endurance"):
            values[name] = None
            continue
        if name == "takeoff_distance_to_obstacle" and _accelerates_after_release(case):
            values[name] = None
            continue
        if name in ("takeoff_ground_roll", "takeoff_distance_to_obstacle"):
            if case.aircraft.launch == "catapult":
                # released airborne: no roll, so none of the runway's terms (SPEC 4; margins
                # gave a catapult the runway's sensitivities, outside audit)
                roll = roll or (0.0 * s.ca.vertcat(*s.symbols.values())[0],)
            roll = roll or s.ground_roll()
            if name == "takeoff_ground_roll":
                values[name] = roll[0]
            else:
                v_tr = transition_speed_m_s(s.aircraft, s.density)
                radius = transition_radius_m(v_tr, s.aircraft.takeoff.transition_load_factor)
                gradient = climb_gradient(s.aircraft, s.thrust(1.0, v_tr), v_tr, s.density)
                arc, climb, _ = obstacle_distances_m(radius, gradient, s.height)
                values[name] = roll[0] + arc + climb
        elif name == "trim_throttle_max":
            values[name] = _trim_value(s)
        elif name == "oei_min_throttle":
            values[name] = _oei_value(s)
        else:
            values[name] = _endurance_value(s)
    return s.ca.vertcat(*s.symbols.values()), values


def _accelerates_after_release(case: Case) -> bool:
    """A catapult released below the transition speed (it accelerates level first)."""
    if case.aircraft.launch != "catapult":
        return False
    rho = case.density_kg_m3
    return bool(true_airspeed_m_s(case.aircraft.launch_speed_m_s, rho)
                < transition_speed_m_s(case.aircraft, rho))


def sensitivities(case: Case, keys: list[str]) -> dict[str, dict[str, float | None]]:
    """d(requirement value)/d(parameter) at the nominal case, by CasADi AD.

    Parameters
    ----------
    case : Case
        The nominal case.
    keys : list of str
        Dotted parameter keys (units as the keys name them).

    Returns
    -------
    dict
        requirement name -> parameter -> derivative [requirement unit / parameter unit];
        None where the requirement is not attainable at the nominal case.

    References
    ----------
    Andersson et al. (2019), "CasADi", Math. Prog. Comp. 11, 1-36.
    """
    import casadi as ca

    from tuflexperf.io.dotted import numeric_keys

    symbols, values = symbolic_values(case, keys)
    nominal = numeric_keys(case)
    point = [nominal[k] for k in keys]
    out: dict[str, dict[str, float | None]] = {}
    for name, expression in values.items():
        if expression is None:
            out[name] = {k: None for k in keys}
            continue
        gradient = ca.Function("gradient", [symbols], [ca.jacobian(expression, symbols)])
        row = np.asarray(gradient(point), dtype=float).ravel()
        out[name] = {k: float(v) if math.isfinite(v) else None for k, v in zip(keys, row,
                                                                                  strict=True)}
    return out


def nominal_values(case: Case, keys: list[str]) -> dict[str, float | None]:
    """The symbolic values at the nominal case (equal to the deterministic ones; tested)."""
    import casadi as ca

    from tuflexperf.io.dotted import numeric_keys

    symbols, values = symbolic_values(case, keys)
    nominal = numeric_keys(case)
    point = [nominal[k] for k in keys]
    out: dict[str, float | None] = {}
    for name, expression in values.items():
        if expression is None:
            out[name] = None
            continue
        out[name] = float(ca.Function("value", [symbols], [expression])(point))
    return out
