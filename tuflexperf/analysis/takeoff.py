"""Take-off at full throttle: ground roll, rotation, transition arc and climb to the obstacle.

Equation of motion on the runway (Raymer, *Aircraft Design*, section 17.8.1):
``m dV/dt = T(1, V) - D_g(V) - mu max(W - L_g(V), 0)``. With the airspeed as the
independent variable, ``ds/dV = m V / F(V)`` and ``dt/dV = m / F(V)``, integrated by
CasADi's CVODES from 0 to the lift-off true airspeed (no wind, level runway). Rotation
adds ``V_LO t_R`` (Raymer 17.8.2); the airborne part is an arc at ``1.15 V_stall`` and
load factor ``n`` followed by the full-throttle straight climb (Anderson, *Aircraft
Performance and Design*, 6.7.2).
"""

from __future__ import annotations

import contextlib
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import stall_margin_of
from tuflexperf.analysis.cache import BoundedCache, fingerprint
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    DEFAULT_OBSTACLE_HEIGHT_M,
    TRANSITION_SPEED_OVER_STALL,
    Aircraft,
    catapult_energy_shortfall,
    climb_gradient,
    ground_roll_net_force_n,
    ground_roll_resistance_n,
    level_flight_drag_n,
    liftoff_speed_eas_m_s,
    liftoff_speed_m_s,
    obstacle_distances_m,
    stall_speed_eas_m_s,
    stall_speed_m_s,
    transition_beyond_cl_max,
    transition_radius_m,
    transition_speed_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.battery import SECONDS_PER_HOUR
from tuflexperf.models.powertrain import beyond_jet_velocity, static_jet_velocity_m_s
from tuflexperf.models.thrust import (
    Propulsion,
    outside_tested_span,
    reference_voltage_note,
    total_thrust_n,
    unlapsed_density_warning,
)

HISTORY_POINTS = 101
_CHECK_POINTS = 2001
_cache: BoundedCache[Any] = BoundedCache()


def net_force_n(
    aircraft: Aircraft, propulsion: Propulsion, airspeed_m_s: Any, density_kg_m3: float
) -> Any:
    """Accelerating force at full throttle on the runway in N (floats, numpy or CasADi)."""
    thrust = total_thrust_n(propulsion, 1.0, airspeed_m_s, density_kg_m3)
    return ground_roll_net_force_n(aircraft, thrust, airspeed_m_s, density_kg_m3)


@dataclass(frozen=True)
class TakeoffResult:
    """Take-off to the obstacle (SI units; airspeeds true unless named ``_eas``).

    ``ground_roll_m`` and ``time_s`` run from rest to the end of rotation (the
    acceleration plus ``V_LO t_R``); ``distance_to_obstacle_m`` adds the airborne
    part (transition arc and straight climb) and is ``None`` when the obstacle is
    never cleared (``obstacle_reason`` says why). The history covers the
    acceleration only (rotation holds the lift-off speed for ``rotation_time_s``);
    its force arrays are at the history's airspeeds: full-throttle thrust, the
    ground-run aerodynamic drag and the rolling friction [N] (net = thrust - drag -
    friction), empty where a result was built without them.
    """

    ground_roll_m: float
    liftoff_speed_m_s: float
    time_s: float
    history_time_s: np.ndarray = field(repr=False)
    history_airspeed_m_s: np.ndarray = field(repr=False)
    history_distance_m: np.ndarray = field(repr=False)
    extrapolated: bool = False
    warnings: tuple[str, ...] = ()
    liftoff_speed_eas_m_s: float = math.nan
    stall_speed_m_s: float = math.nan
    density_kg_m3: float = math.nan
    acceleration_distance_m: float = math.nan
    rotation_time_s: float = 0.0
    rotation_distance_m: float = 0.0
    transition_speed_m_s: float = math.nan
    transition_load_factor: float = math.nan
    transition_radius_m: float = math.nan
    climb_gradient: float = math.nan
    # the gradient whose angle ends the arc: the climb's, but on packs that sag on the way
    transition_gradient: float = math.nan
    transition_distance_m: float = math.nan
    transition_height_m: float = math.nan
    climb_distance_m: float | None = None
    airborne_distance_m: float | None = None
    distance_to_obstacle_m: float | None = None
    obstacle_height_m: float = DEFAULT_OBSTACLE_HEIGHT_M
    obstacle_cleared_in_transition: bool = False
    obstacle_reason: str = ""
    history_thrust_n: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    history_drag_n: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    history_friction_n: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    launch: str = "runway"  # or "catapult": released airborne, no ground roll

    @property
    def climb_angle_deg(self) -> float | None:
        """Full-throttle climb angle after the arc [deg]; ``None`` if it cannot climb."""
        if not (math.isfinite(self.climb_gradient) and -1.0 <= self.climb_gradient):
            return None
        # a gradient of 1 or more climbs vertically (models.aircraft.obstacle_distances_m)
        return math.degrees(math.asin(min(self.climb_gradient, 1.0)))

    def to_dict(self) -> dict[str, Any]:
        return {
            "ground_roll_m": self.ground_roll_m,
            "liftoff_speed_m_s": self.liftoff_speed_m_s,
            "liftoff_speed_eas_m_s": self.liftoff_speed_eas_m_s,
            "time_s": self.time_s,
            "stall_speed_m_s": self.stall_speed_m_s,
            "density_kg_m3": self.density_kg_m3,
            "acceleration_distance_m": self.acceleration_distance_m,
            "rotation_time_s": self.rotation_time_s,
            "rotation_distance_m": self.rotation_distance_m,
            "transition_speed_m_s": self.transition_speed_m_s,
            "transition_load_factor": self.transition_load_factor,
            "transition_radius_m": self.transition_radius_m,
            "transition_distance_m": self.transition_distance_m,
            "transition_height_m": self.transition_height_m,
            "climb_gradient": self.climb_gradient,
            "transition_gradient": self.transition_gradient,
            "climb_angle_deg": self.climb_angle_deg,
            "climb_distance_m": self.climb_distance_m,
            "airborne_distance_m": self.airborne_distance_m,
            "obstacle_height_m": self.obstacle_height_m,
            "obstacle_cleared_in_transition": self.obstacle_cleared_in_transition,
            "distance_to_obstacle_m": self.distance_to_obstacle_m,
            "obstacle_reason": self.obstacle_reason,
            "extrapolated": self.extrapolated,
            "warnings": list(self.warnings),
        }


def build_ground_roll_integrator(
    aircraft: Aircraft, propulsion: Propulsion, density_kg_m3: float, points: int = HISTORY_POINTS
) -> Any:
    """CasADi function ``V_LO -> (s, t)`` on ``points`` airspeeds from 0 to ``V_LO``.

    The airspeed is normalised, ``V = u V_LO`` with ``u`` in [0, 1], so one
    integrator serves any lift-off speed (it is a parameter).
    """
    import casadi as ca

    u = ca.MX.sym("u")
    state = ca.MX.sym("state", 2)  # distance m, time s
    v_lo = ca.MX.sym("v_lo")
    speed = u * v_lo
    force = net_force_n(aircraft, propulsion, speed, density_kg_m3)
    mass = aircraft.mass_kg
    rhs = ca.vertcat(mass * speed / force, mass / force) * v_lo
    grid = np.linspace(0.0, 1.0, points)
    integrator = ca.integrator(
        "ground_roll",
        "cvodes",
        {"x": state, "p": v_lo, "t": u, "ode": rhs},
        0.0,
        grid[1:],
        {"abstol": 1e-12, "reltol": 1e-11, "max_num_steps": 100000,
         "disable_internal_warnings": True},
    )
    v_lo_in = ca.MX.sym("v_lo_in")
    states = integrator(x0=ca.DM.zeros(2), p=v_lo_in)["xf"]
    return ca.Function("ground_roll_history", [v_lo_in], [states])


def _integrator_for(case: Case) -> Any:
    return _cache.get(
        fingerprint(case.aircraft, case.propulsion, case.density_kg_m3),
        lambda: build_ground_roll_integrator(case.aircraft, case.propulsion, case.density_kg_m3),
    )


ROTATION_STEPS = 8  # RK4 steps of the rotation's charge at the lift-off speed (the mission's)


def rotation_charge(rate: Any, charge_ah: Any, seconds: Any) -> Any:
    """The charge per engine [Ah] after the rotation's ``seconds`` [s] (one or per row) at
    full throttle at the lift-off speed: :data:`ROTATION_STEPS` RK4 steps of
    ``dq/dt = rate(q)`` [Ah/s] (the single case and the batch alike)."""
    h = seconds / ROTATION_STEPS
    q = charge_ah
    for _ in range(ROTATION_STEPS):
        k1 = rate(q)
        k2 = rate(q + 0.5 * h * k1)
        k3 = rate(q + 0.5 * h * k2)
        k4 = rate(q + h * k3)
        q = q + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return q


class _Packs:
    """The take-off on sagging packs (a battery and the propulsion's ``reference_voltage_v``).

    Each fan makes ``T (U/U_ref)^k`` at its packs' loaded voltage ``U``, which falls as the
    roll draws charge (:func:`tuflexperf.analysis.pack_limits.full_throttle_on_packs`): the
    roll integrates the charge drawn per engine beside the distance and the time (CVODES,
    ``dq/dV = I m / (3600 F)``), the rotation adds its own at the lift-off speed, and the
    arc and climb to the obstacle fly at the packs' thrust on the way
    (:func:`settle_airborne`).
    """

    def __init__(self, case: Case, side: Any) -> None:
        import casadi as ca

        from tuflexperf.analysis.pack_limits import full_throttle_on_packs

        aircraft, rho = case.aircraft, case.density_kg_m3
        n = len(case.propulsion.engines)
        self.n = n
        self.cutoff_v = float(side.battery.cutoff_voltage_v)  # the packs' [V]
        q, v = ca.SX.sym("q", n), ca.SX.sym("v")
        thrust, currents, volts = full_throttle_on_packs(case, side, [q[j] for j in range(n)], v)
        self.at = ca.Function("full_throttle_on_packs", [q, v],
                              [thrust, ca.vertcat(*currents), ca.vertcat(*volts)])
        self._maps: dict[int, Any] = {}
        u, v_lo = ca.SX.sym("u"), ca.SX.sym("v_lo")
        state = ca.SX.sym("state", 2 + n)  # distance m, time s, charge Ah per engine
        speed = u * v_lo
        thrust_u, current_u, _ = self.at(state[2:], speed)
        dt_dv = aircraft.mass_kg / ground_roll_net_force_n(aircraft, thrust_u, speed, rho)
        rhs = ca.vertcat(speed * dt_dv, dt_dv, current_u * dt_dv / SECONDS_PER_HOUR) * v_lo
        grid = np.linspace(0.0, 1.0, HISTORY_POINTS)
        integrator = ca.integrator(
            "ground_roll_on_packs", "cvodes",
            {"x": state, "p": v_lo, "t": u, "ode": rhs}, 0.0, grid[1:],
            {"abstol": 1e-12, "reltol": 1e-11, "max_num_steps": 100000,
             "disable_internal_warnings": True},
        )
        given = ca.MX.sym("v_lo_in")
        self.roll = ca.Function("ground_roll_on_packs_history", [given],
                                [integrator(x0=ca.DM.zeros(2 + n), p=given)["xf"]])

    def point(self, charge_ah: np.ndarray, speeds: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Thrust [N] ``(K,)``, current [A] and loaded voltage [V] per engine ``(n, K)`` at
        the airspeeds ``speeds`` [m/s] ``(K,)`` after ``charge_ah`` ``(n,)`` or ``(n, K)``."""
        v = np.atleast_1d(np.asarray(speeds, dtype=float)).reshape(1, -1)
        q = np.asarray(charge_ah, dtype=float).reshape(self.n, -1) * np.ones((1, v.shape[1]))
        size = v.shape[1]
        if size not in self._maps:  # building a map costs more than calling it (the airborne
            self._maps[size] = self.at.map(size)  # part's solve calls it some hundred times)
        thrust, current, volts = self._maps[size](q, v)
        return (np.asarray(thrust, dtype=float).reshape(-1), np.asarray(current, dtype=float),
                np.asarray(volts, dtype=float))

    def rotation(self, charge_ah: np.ndarray, v_lo: float, seconds: float) -> np.ndarray:
        """The charge per engine [Ah] after ``seconds`` [s] at full throttle at ``v_lo``."""
        return rotation_charge(
            lambda q: self.point(q, np.array([v_lo]))[1][:, 0] / SECONDS_PER_HOUR,
            np.asarray(charge_ah, dtype=float), seconds)


# the airborne charge on sagging packs: a settled fixed point, or why not (settle_airborne)
CHARGE_TOLERANCE_AH = 1e-9  # settled: the charge per engine known to within this [Ah]
_INNER_TOLERANCE_AH = 1e-12  # the climb's midpoint charge at a given climb time [Ah]
SETTLE_ITERATIONS = 200  # cap of each iteration and each bisection (then: not settled)
_SCAN_RATIO = 1.1  # growth of the climb times scanned for the obstacle (a bracket)
_SCAN_STEPS = 400  # 1.1^400 ~ 4e16 times the sag-free climb: the packs are long empty
_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)

# per row of :class:`AirborneOnPacks`: the obstacle reached, or why not
REACHED = 0
NO_CLIMB = 1  # the full-throttle gradient at the arc's end is not positive
TOPS_OUT = 2  # the climb stops gaining height below the obstacle as the packs sag
BEYOND_THE_BATTERY_STATUS = 3  # the packs reach their cut-off (or power) before the obstacle
UNSETTLED = 4  # the charge drawn on the way did not settle within SETTLE_ITERATIONS


@dataclass(frozen=True)
class AirborneOnPacks:
    """The airborne part of a take-off on sagging packs, per row (:func:`settle_airborne`).

    Attributes
    ----------
    arc_gradient : ndarray
        Full-throttle climb gradient at the transition arc's end [-] ``(rows,)``: it sets
        the arc's end angle.
    climb_gradient : ndarray
        Full-throttle gradient halfway up the straight climb [-] ``(rows,)``; the arc's
        where the arc clears the obstacle; NaN where the obstacle is not reached (then
        :func:`tuflexperf.models.aircraft.obstacle_distances_m` gives an infinite climb).
    arc_charge_ah, climb_charge_ah, charge_ah : ndarray
        Charge drawn per engine [Ah] ``(engines, rows)`` at the arc's end, halfway up the
        climb and at the obstacle (where it is not reached: the arc's end).
    climb_s : ndarray
        Time of the straight climb [s] ``(rows,)`` (0 where the arc clears the obstacle,
        NaN where it is not reached).
    status : ndarray
        :data:`REACHED`, :data:`NO_CLIMB`, :data:`TOPS_OUT`,
        :data:`BEYOND_THE_BATTERY_STATUS` or :data:`UNSETTLED` per row.
    apex_m : ndarray
        Where the climb tops out (:data:`TOPS_OUT`): the height it reaches [m] ``(rows,)``;
        NaN elsewhere.
    """

    arc_gradient: np.ndarray
    climb_gradient: np.ndarray
    arc_charge_ah: np.ndarray
    climb_charge_ah: np.ndarray
    charge_ah: np.ndarray
    climb_s: np.ndarray
    status: np.ndarray
    apex_m: np.ndarray


def settle_airborne(radius_m: Any, speed_m_s: Any, height_m: Any, charge_ah: Any,
                    point: Callable[[np.ndarray], tuple[Any, Any, Any]],
                    gradient_of: Callable[[Any], Any], cutoff_v: Any) -> AirborneOnPacks:
    """The transition arc and the straight climb to the obstacle on sagging packs, with the
    charge they draw settled; rows broadcast (the single case is one row, the batch's many:
    one code path for both).

    The packs sag as the arc and the climb draw their charge, the thrust and so the
    gradient fall, and the time to the obstacle grows with it. From ``charge_ah``
    ``(engines, rows)`` at the arc's start, two fixed points, each settled to
    :data:`CHARGE_TOLERANCE_AH` per row:

    - the arc: ``q_arc = q0 + I(q_arc) t_arc / 3600``, ``t_arc = R gamma / V`` with
      ``sin(gamma) = G(q_arc)`` (or ``R acos(1 - h/R) / V`` where the arc clears the
      obstacle ``h``); the map is a strong contraction (the arc lasts seconds), so plain
      iteration settles;
    - the straight climb from the arc's top ``h_TR``: ``q_mid = q_arc + I(q_mid) t / 7200``
      with ``t = (h - h_TR) / (V G(q_mid))``, the gradient halfway up standing for the
      climb's (the packs sag almost linearly over these seconds: second order; a test holds
      the distance to an integration with the charge along the path). The charge at the
      obstacle is ``q_arc + I(q_mid) t / 3600``. Near the edge of climbing the gradient
      falls far over the climb and the midpoint stands for it less well: with a 44 V
      reference and k = 0.272 it gives 846 m where an integration in time gives 765 m, and
      at 0.274 it tops out at 13.6 m where the integration clears 15 m at 1084 m (long,
      not short: early in the packs' discharge the gradient falls fastest, convex in the
      charge).

    The climb's map is not a contraction near the edge of climbing: as ``G -> 0`` the time
    to the obstacle goes to infinity, and four plain iterations (the earlier code)
    oscillated there, the obstacle distance jumping up and down in the induced-drag factor
    (outside audit). It is solved in the climb time ``t`` instead: the height reached,
    ``phi(t) = t V G(q_mid(t))``, rises from 0, and the obstacle is reached at its first
    crossing of ``h - h_TR``. More charge lowers the voltage, the thrust and the gradient,
    so ``t0 = (h - h_TR) / (V G(q_arc))`` (the climb without further sag) is a lower bound:
    the scan steps up from it by :data:`_SCAN_RATIO` until the obstacle is reached, or the
    packs' loaded voltage at the obstacle's charge falls below ``cutoff_v`` [V] (or they
    cannot give the power: NaN), or ``phi`` falls (past its peak: a golden-section search
    finds it, and below the obstacle the climb tops out), then bisects the bracket until
    the charge at the obstacle is known to :data:`CHARGE_TOLERANCE_AH`. The returned climb
    is the bracket's upper end: the obstacle is reached there, at a gradient no higher
    than the fixed point's (a distance never short). Each row's iterates depend on that
    row alone, so a batch row gives the single case's numbers.

    Parameters
    ----------
    radius_m : float or ndarray
        Transition arc's radius [m] (one or ``(rows,)``).
    speed_m_s : float or ndarray
        Transition (and climb) true airspeed [m/s].
    height_m : float or ndarray
        Obstacle height [m].
    charge_ah : ndarray
        Charge drawn per engine at the arc's start [Ah] ``(engines, rows)``.
    point : callable
        ``point(q)`` with ``q`` ``(engines, rows)`` [Ah]: the full-throttle thrust [N]
        ``(rows,)``, the current per engine [A] and the packs' loaded voltage per engine [V]
        ``(engines, rows)`` (NaN: beyond their power) at the transition speed.
    gradient_of : callable
        ``gradient_of(thrust)``: the climb gradient [-] ``(rows,)`` at that thrust [N].
    cutoff_v : float or ndarray
        The packs' cut-off voltage [V] (one or per row).

    Returns
    -------
    AirborneOnPacks

    References
    ----------
    Anderson, *Aircraft Performance and Design*, 6.7.2 (the arc and the climb); SPEC 3
    (thrust and pack voltage; take-off to the obstacle); Press et al., *Numerical
    Recipes*, 9.1 and 10.2 (bisection, golden-section search).
    """
    from tuflexperf.analysis.pack_limits import within_limits

    q0 = np.asarray(charge_ah, dtype=float)
    rows = q0.shape[1]
    radius = np.asarray(radius_m, dtype=float) * np.ones(rows)
    speed = np.asarray(speed_m_s, dtype=float) * np.ones(rows)
    height = np.asarray(height_m, dtype=float) * np.ones(rows)

    def evaluate(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        thrust, current, volts = point(q)
        current = np.asarray(current, dtype=float).reshape(q.shape)
        volts = np.asarray(volts, dtype=float).reshape(q.shape)
        gradient = np.asarray(gradient_of(thrust), dtype=float).reshape(-1) * np.ones(rows)
        holds = np.all(within_limits(volts, current, cutoff_v, None), axis=0)
        return gradient, current, volts, holds & np.isfinite(gradient)

    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        cleared_at = np.arccos(np.clip(1.0 - height / radius, -1.0, 1.0))

        def arc(gradient: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            angle = np.arcsin(np.clip(gradient, 0.0, 1.0))
            top = radius * (1.0 - np.cos(angle))
            cleared = top >= height
            return (np.nan_to_num(radius * np.where(cleared, cleared_at, angle) / speed),
                    top, cleared)

        # the arc: a contraction (its seconds are few); each row frozen once settled
        q_arc, arc_settled = q0, np.zeros(rows, dtype=bool)
        for _ in range(SETTLE_ITERATIONS):
            gradient, current = evaluate(q_arc)[:2]
            new = q0 + current * arc(gradient)[0] / SECONDS_PER_HOUR
            moved = np.max(np.abs(new - q_arc), axis=0)
            q_arc = np.where(arc_settled, q_arc, new)
            arc_settled |= moved < CHARGE_TOLERANCE_AH
            if arc_settled.all():
                break
        g_arc, current_arc, _, holds_arc = evaluate(q_arc)
        top, cleared = arc(g_arc)[1:]
        need = height - top
        status = np.full(rows, REACHED)
        status[~holds_arc] = BEYOND_THE_BATTERY_STATUS
        status[holds_arc & ~cleared & ~(g_arc > 0.0)] = NO_CLIMB
        status[~arc_settled] = UNSETTLED
        climbing = (status == REACHED) & ~cleared

        def at(seconds: np.ndarray, guess: np.ndarray, active: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
            """Halfway up a climb of ``seconds`` [s] (the ``active`` rows; the others at no
            climb): the charge [Ah], the gradient, the height reached above the arc's top
            ``phi`` [m], whether the packs hold at the obstacle's charge and whether the
            charge settled."""
            seconds = np.where(active, seconds, 0.0)
            q, settled = np.where(active, guess, q_arc), np.zeros(rows, dtype=bool)
            for _ in range(SETTLE_ITERATIONS):
                new = q_arc + evaluate(q)[1] * seconds / (2.0 * SECONDS_PER_HOUR)
                moved = np.max(np.abs(new - q), axis=0)
                q = np.where(settled, q, new)
                # a charge beyond the packs' power is NaN: no fixed point, the packs are out
                settled |= (moved < _INNER_TOLERANCE_AH) | ~np.all(np.isfinite(new), axis=0)
                if settled.all():
                    break
            gradient = evaluate(q)[0]
            holds = evaluate(2.0 * q - q_arc)[3] & np.isfinite(gradient)
            return q, gradient, seconds * speed * gradient, holds, settled

        def event(phi: np.ndarray, holds: np.ndarray) -> np.ndarray:
            return (phi >= need) | ~holds  # the obstacle reached, or the packs out first

        # the scan: from the sag-free climb time (a lower bound) up, until an event or phi
        # falls; each row keeps its own bracket [low, high] (and the point before low)
        before, low, phi_low = np.zeros(rows), np.zeros(rows), np.zeros(rows)
        q_before, q_low = q_arc, q_arc
        high = np.where(climbing, need / (speed * np.where(climbing, g_arc, 1.0)), 0.0)
        q_high, g_high = q_arc, g_arc
        holds_high = np.ones(rows, dtype=bool)
        scanning = climbing.copy()
        bracketed, peaked = np.zeros(rows, dtype=bool), np.zeros(rows, dtype=bool)
        for _ in range(_SCAN_STEPS):
            if not scanning.any():
                break
            q, g, phi, holds, settled = at(high, q_low, scanning)
            status[scanning & ~settled] = UNSETTLED
            live = scanning & settled
            found = live & event(phi, holds)
            fell = live & ~found & ~(phi > phi_low)
            keep = live & ~found & ~fell
            q_high = np.where(found, q, q_high)
            g_high = np.where(found, g, g_high)
            holds_high = np.where(found, holds, holds_high)
            bracketed |= found
            peaked |= fell
            before, q_before = np.where(keep, low, before), np.where(keep, q_low, q_before)
            low, q_low = np.where(keep, high, low), np.where(keep, q, q_low)
            phi_low = np.where(keep, phi, phi_low)
            high = np.where(keep, high * _SCAN_RATIO, high)
            scanning &= keep
        status[scanning] = UNSETTLED

        # the packs out at the scan's point (the obstacle maybe reached there too): where do
        # they give out? (their charge only grows: a bisection); the climb may have topped
        # out before, or reached the obstacle in between: the peak's search below decides
        out = bracketed & ~holds_high
        bracketed &= ~out
        end, q_end_low, phi_end = high.copy(), q_low, phi_low.copy()
        if out.any():
            gone, q_gone, onset = high.copy(), q_high, out.copy()
            end = np.where(out, low, end)
            for _ in range(SETTLE_ITERATIONS):
                onset &= ~(2.0 * np.max(np.abs(q_gone - q_end_low), axis=0)
                           < CHARGE_TOLERANCE_AH)
                if not onset.any():
                    break
                middle = 0.5 * (end + gone)
                q, _, phi, holds, settled = at(middle, q_end_low, onset)
                status[onset & ~settled] = UNSETTLED
                onset &= settled
                held, lost = onset & holds, onset & ~holds
                end, q_end_low = np.where(held, middle, end), np.where(held, q, q_end_low)
                phi_end = np.where(held, phi, phi_end)
                gone, q_gone = np.where(lost, middle, gone), np.where(lost, q, q_gone)
            status[onset] = UNSETTLED
            peaked |= out & (status == REACHED)

        # past phi's peak below the obstacle, or the packs out: golden section for the peak
        # on [before, end] (phi rose up to low; it fell at high, or the packs give out at
        # end); high enough, the crossing is before it; a peak at end is the packs' limit
        apex = np.full(rows, np.nan)
        if peaked.any():
            a, b = before.copy(), end.copy()
            c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
            q_c, _, phi_c, _, ok_c = at(c, q_low, peaked)
            q_d, _, phi_d, _, ok_d = at(d, q_low, peaked)
            searching = peaked & ok_c & ok_d
            status[peaked & ~searching] = UNSETTLED
            for _ in range(SETTLE_ITERATIONS):
                # settled where the peak's time is known to a charge within the tolerance
                width = np.max(np.abs(evaluate(q_c)[1]), axis=0) * (b - a) / SECONDS_PER_HOUR
                searching &= ~(width < CHARGE_TOLERANCE_AH)
                if not searching.any():
                    break
                left = searching & (phi_c >= phi_d)  # the peak in [a, d]: d <- c, a new c
                right = searching & ~left  # the peak in [c, b]: c <- d, a new d
                b, a = np.where(left, d, b), np.where(right, c, a)
                q_d, phi_d, q_c, phi_c = (np.where(left, q_c, q_d), np.where(left, phi_c, phi_d),
                                          np.where(right, q_d, q_c), np.where(right, phi_d, phi_c))
                c, d = (np.where(left, b - _GOLDEN * (b - a), np.where(right, d, c)),
                        np.where(left, c, np.where(right, a + _GOLDEN * (b - a), d)))
                q_new, _, phi_new, _, ok_new = at(np.where(left, c, d), q_low, searching)
                q_c, phi_c = np.where(left, q_new, q_c), np.where(left, phi_new, phi_c)
                q_d, phi_d = np.where(right, q_new, q_d), np.where(right, phi_new, phi_d)
                status[searching & ~ok_new] = UNSETTLED
                searching &= ok_new
            status[searching] = UNSETTLED
            peak_s = np.where(phi_c >= phi_d, c, d)
            q_p, g_p, phi_p, holds_p, ok_p = at(peak_s, q_low, peaked)
            candidate = peaked & (status == REACHED) & ok_p
            high_enough = candidate & event(phi_p, holds_p)
            highest = np.fmax(phi_p, np.fmax(phi_c, phi_d))
            # the packs out while the climb still gains height: beyond the battery; where it
            # stopped gaining before (the peak inside), it topped out first
            gave_out = candidate & ~high_enough & out & ~(highest > phi_end)
            tops = candidate & ~high_enough & ~gave_out
            status[tops] = TOPS_OUT
            status[gave_out] = BEYOND_THE_BATTERY_STATUS
            apex = np.where(tops, top + highest, np.nan)
            low, q_low = np.where(high_enough, before, low), np.where(high_enough, q_before,
                                                                       q_low)
            high, q_high = np.where(high_enough, peak_s, high), np.where(high_enough, q_p,
                                                                         q_high)
            g_high = np.where(high_enough, g_p, g_high)
            holds_high = np.where(high_enough, holds_p, holds_high)
            bracketed |= high_enough

        # bisection of each bracket for the first event: the charge at the obstacle settled
        bracketed &= status == REACHED
        bisecting = bracketed.copy()
        for _ in range(SETTLE_ITERATIONS):
            # the obstacle's charge is 2 q_mid - q_arc: known to within 2 |dq_mid|
            spread = 2.0 * np.max(np.abs(q_high - q_low), axis=0)
            bisecting &= ~(spread < CHARGE_TOLERANCE_AH)
            if not bisecting.any():
                break
            middle = 0.5 * (low + high)
            q, g, phi, holds, settled = at(middle, q_low, bisecting)
            status[bisecting & ~settled] = UNSETTLED
            bisecting &= settled
            up = bisecting & event(phi, holds)
            down = bisecting & ~up
            high, q_high = np.where(up, middle, high), np.where(up, q, q_high)
            g_high = np.where(up, g, g_high)
            holds_high = np.where(up, holds, holds_high)
            low, q_low = np.where(down, middle, low), np.where(down, q, q_low)
        status[bisecting] = UNSETTLED
        status[bracketed & (status == REACHED) & ~holds_high] = BEYOND_THE_BATTERY_STATUS

        reached = status == REACHED
        climbed = reached & ~cleared
        climb_s = np.where(climbed, high, np.where(reached, 0.0, np.nan))
        q_mid = np.where(climbed, q_high, q_arc)
        q_end = np.where(climbed, 2.0 * q_high - q_arc, q_arc)
        straight = np.where(climbed, g_high, np.where(reached, g_arc, np.nan))
    return AirborneOnPacks(g_arc, straight, q_arc, q_mid, q_end, climb_s, status, apex)


RELEASE_NODES = 32  # Gauss-Legendre nodes of a catapult's acceleration after the release
_RELEASE_CHECK = 201  # airspeeds where its excess thrust must stay positive


def release_acceleration(mass_kg: Any, release_m_s: Any, transition_m_s: Any, forces: Any
                         ) -> tuple[Any, Any, Any, Any]:
    """A catapult's level full-throttle acceleration from the release to the transition
    speed per row: distance [m], time [s], charge drawn per engine [Ah] (``None`` where
    ``forces`` gives no current) and whether it accelerates at all (the excess thrust
    positive at :data:`_RELEASE_CHECK` airspeeds); none where the release is already that
    fast.

    ``s = int m V / (T - D) dV`` and ``t = int m / (T - D) dV`` from ``V_rel`` to ``V_tr``
    (``L = W``: the level-flight drag), by :data:`RELEASE_NODES`-point Gauss-Legendre;
    ``forces(V)`` gives ``T - D`` [N] at airspeeds ``(rows, K)`` and the current per engine
    [A] ``(engines, rows, K)`` or None (on full packs: the seconds are few). The
    arc and the climb to the obstacle follow at ``V_tr`` (Anderson's transition, 1.15
    V_stall): a release below it had started the arc at ``V_tr`` for nothing, 11.7 m short
    of the obstacle distance (outside audit).

    References
    ----------
    Raymer, *Aircraft Design*, 17.8.1 (the acceleration integral); Anderson, *Aircraft
    Performance and Design*, 6.7.2 (the transition speed).
    """
    release = np.atleast_1d(np.asarray(release_m_s, dtype=float))
    span = np.maximum(np.atleast_1d(np.asarray(transition_m_s, dtype=float)) - release, 0.0)
    nodes, weights = np.polynomial.legendre.leggauss(RELEASE_NODES)
    speeds = release[:, None] + span[:, None] * 0.5 * (nodes[None, :] + 1.0)
    check = release[:, None] + span[:, None] * np.linspace(0.0, 1.0, _RELEASE_CHECK)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        accelerates = (span == 0.0) | np.all(np.asarray(forces(check)[0]) > 0.0, axis=1)
        excess, current = forces(speeds)
        dt_dv = np.atleast_1d(np.asarray(mass_kg, dtype=float)).reshape(-1, 1) / np.asarray(
            excess)
        half = 0.5 * span
        time = half * np.sum(weights * dt_dv, axis=1)
        distance = half * np.sum(weights * speeds * dt_dv, axis=1)
        charge = None if current is None else half * np.sum(
            weights * np.asarray(current) * dt_dv, axis=-1) / SECONDS_PER_HOUR
    return (np.where(span > 0.0, distance, 0.0), np.where(span > 0.0, time, 0.0),
            None if charge is None else np.where(span > 0.0, charge, 0.0), accelerates)


_ON_PACKS = " at the packs' loaded voltage"


def _on_packs_force(case: Case, packs: _Packs, charge_ah: np.ndarray,
                    speeds: np.ndarray) -> np.ndarray:
    """Full-throttle net force on the runway [N] at ``speeds`` on the sagging packs."""
    thrust = packs.point(charge_ah, speeds)[0]
    return np.asarray(ground_roll_net_force_n(case.aircraft, thrust, speeds,
                                              case.density_kg_m3), dtype=float)


def _packs_note(case: Case, start_v: np.ndarray, liftoff_v: np.ndarray | None,
                air: _Airborne) -> str:
    """What the take-off flew on: the packs' least loaded voltage [V] at the brake release
    (a catapult's release), at lift-off and at the obstacle."""
    prop = case.propulsion
    start = "the release" if liftoff_v is None else "the brake release"
    return (f"the take-off at the packs' loaded voltage: thrust x (U/"
            f"{prop.reference_voltage_v:g} V)^{prop.voltage_exponent:g}, U "
            f"{float(np.min(start_v)):.1f} V at {start}"
            + ("" if liftoff_v is None else f", {float(np.min(liftoff_v)):.1f} V at lift-off")
            + (f", {air.least_voltage_v:.1f} V at the obstacle" if air.distance_m is not None
               else ""))


def _packs_of(case: Case) -> _Packs | None:
    """The sagging packs the take-off flies on, or None (no battery, or no reference
    voltage: the thrust model's own thrust)."""
    from tuflexperf.analysis.pack_limits import pack_side, sagging_packs

    if not sagging_packs(case):
        return None
    side = pack_side(case)
    if side is None:
        return None
    return _cache.get(
        fingerprint("packs", case.aircraft, case.propulsion, case.density_kg_m3,
                    side.battery, side.params, side.power, side.own_surfaces,
                    side.density_scale),
        lambda: _Packs(case, side),
    )


def obstacle_height_of(case: Case) -> float:
    """The case's obstacle height [m] (requirements.takeoff.obstacle_height_m, default 15 m)."""
    requirement = case.requirements.takeoff
    if requirement is None or requirement.obstacle_height_m is None:
        return DEFAULT_OBSTACLE_HEIGHT_M
    return float(requirement.obstacle_height_m)


@dataclass(frozen=True)
class _Airborne:
    """The airborne part of a take-off: the arc at 1.15 V_stall, then the straight climb."""

    speed_m_s: float
    radius_m: float
    gradient: float
    arc_m: float
    climb_m: float
    arc_top_m: float
    reason: str
    least_voltage_v: float = math.nan  # the packs' at the obstacle (sagging packs only)
    arc_gradient: float = math.nan  # sets the arc's end angle (the climb's, but on sagging packs)
    # the packs reach their cut-off before the obstacle: the take-off is not attainable
    beyond_battery: bool = False

    @property
    def distance_m(self) -> float | None:
        total = self.arc_m + self.climb_m
        return total if math.isfinite(total) else None

    def fields(self, ground_roll_m: float, load_factor: float, height_m: float) -> dict[str, Any]:
        """The :class:`TakeoffResult` fields after a ground roll (or none) of ``ground_roll_m``."""
        airborne = self.distance_m
        return {
            "transition_speed_m_s": self.speed_m_s,
            "transition_load_factor": load_factor,
            "transition_radius_m": self.radius_m,
            "climb_gradient": self.gradient,
            "transition_gradient": (self.arc_gradient if math.isfinite(self.arc_gradient)
                                    else self.gradient),
            "transition_distance_m": self.arc_m,
            "transition_height_m": self.arc_top_m,
            "climb_distance_m": self.climb_m if math.isfinite(self.climb_m) else None,
            "airborne_distance_m": airborne,
            "distance_to_obstacle_m": None if airborne is None else ground_roll_m + airborne,
            "obstacle_height_m": height_m,
            # a vertical climb (gradient >= 1) also covers no ground: the arc's top says it
            "obstacle_cleared_in_transition": bool(self.arc_top_m >= height_m),
            "obstacle_reason": self.reason,
        }


def _airborne(case: Case, height: float, packs: _Packs | None = None,
              charge_ah: np.ndarray | None = None) -> _Airborne:
    """Transition arc at 1.15 V_stall and n, then the full-throttle climb (Anderson 6.7.2);
    on sagging ``packs`` from ``charge_ah`` drawn per engine at the arc's start, each at the
    packs' thrust on the way (:func:`settle_airborne`)."""
    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3
    v_tr = float(transition_speed_m_s(aircraft, rho))
    radius = float(transition_radius_m(v_tr, aircraft.takeoff.transition_load_factor))
    least_voltage = math.nan
    why, beyond = "", False
    if packs is None:
        thrust_tr = total_thrust_n(propulsion, 1.0, v_tr, rho)
        gradient = straight = reported = float(climb_gradient(aircraft, thrust_tr, v_tr, rho))
    else:
        start = np.zeros((packs.n, 1)) if charge_ah is None else np.reshape(charge_ah, (-1, 1))
        air = settle_airborne(
            radius, v_tr, height, start, lambda q: packs.point(q, np.array([v_tr])),
            lambda thrust: np.asarray(climb_gradient(aircraft, thrust, v_tr, rho), dtype=float),
            packs.cutoff_v)
        gradient, straight = float(air.arc_gradient[0]), float(air.climb_gradient[0])
        # where the obstacle is not reached the climb's gradient is NaN (an infinite climb):
        # the result reports the gradient the climb starts at
        reported = straight if math.isfinite(straight) else gradient
        least_voltage = float(np.min(packs.point(air.charge_ah, np.array([v_tr]))[2]))
        beyond = bool(air.status[0] == BEYOND_THE_BATTERY_STATUS)
        why = _not_reached(int(air.status[0]), height, v_tr, gradient, float(air.apex_m[0]),
                           packs.cutoff_v)
    arc_m, climb_m, arc_top_m = (float(x) for x in obstacle_distances_m(
        radius, gradient, height, straight))
    reason = "" if math.isfinite(arc_m + climb_m) else why or (
        f"the {height:g} m obstacle is never cleared: the arc tops out at {arc_top_m:.1f} m "
        f"and the full-throttle climb gradient at {v_tr:.1f} m/s is {reported:.3f} (no climb)"
    )
    n = aircraft.takeoff.transition_load_factor
    if transition_beyond_cl_max(n):
        arc_m = climb_m = math.nan
        reason = (f"the transition arc at {v_tr:.1f} m/s ({TRANSITION_SPEED_OVER_STALL:g} "
                  f"V_stall) with load factor {n:g} needs CL = "
                  f"{n / TRANSITION_SPEED_OVER_STALL ** 2:.2f} cl_max, beyond cl_max (at most "
                  f"n = {TRANSITION_SPEED_OVER_STALL ** 2:.5g})")
    return _Airborne(v_tr, radius, reported, arc_m, climb_m, arc_top_m, reason, least_voltage,
                     gradient, beyond)


def _not_reached(status: int, height: float, speed: float, gradient: float, apex: float,
                 cutoff_v: float) -> str:
    """Why the climb on sagging packs does not reach the obstacle (:func:`settle_airborne`'s
    status; "" where it does, or no climb at all: the caller says that), the obstacle height
    and the apex [m], the airspeed [m/s], the arc's gradient [-], the cut-off [V]."""
    from tuflexperf.analysis.attainable import BEYOND_THE_BATTERY

    if status == TOPS_OUT:
        return (f"the {height:g} m obstacle is never cleared: the full-throttle climb gradient "
                f"at {speed:.1f} m/s falls from {gradient:.3f} at the arc's end as the packs "
                f"sag, and the climb tops out at {apex:.2f} m")
    if status == BEYOND_THE_BATTERY_STATUS:
        return (f"full throttle in the climb to the {height:g} m obstacle at {speed:.1f} m/s "
                f"takes the packs below their cut-off {cutoff_v:.2f} V (or beyond their "
                f"power) before they reach it: not attainable, {BEYOND_THE_BATTERY}")
    if status == UNSETTLED:
        return (f"the {height:g} m obstacle is not attainable: the charge drawn in the arc and "
                f"the climb at {speed:.1f} m/s did not settle to {CHARGE_TOLERANCE_AH:g} Ah "
                f"in {SETTLE_ITERATIONS} iterations")
    return ""


def _release_forces(case: Case, packs: _Packs | None) -> Any:
    """``forces`` of :func:`release_acceleration` for the case (on full packs where they
    sag)."""
    aircraft, rho = case.aircraft, case.density_kg_m3

    def forces(v: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        drag = np.asarray(level_flight_drag_n(aircraft, v, rho), dtype=float)
        if packs is None:
            thrust = np.asarray(total_thrust_n(case.propulsion, 1.0, v, rho), dtype=float)
            return thrust - drag, None
        thrust, current, _ = packs.point(np.zeros(packs.n), v.ravel())
        return thrust.reshape(v.shape) - drag, current.reshape(packs.n, *v.shape)

    return forces


def _after_release(fields: dict[str, Any], accelerate_m: float) -> dict[str, Any]:
    """A catapult's airborne fields with its level acceleration before the arc [m]."""
    for key in ("airborne_distance_m", "distance_to_obstacle_m"):
        if fields[key] is not None:
            fields[key] += accelerate_m
    return fields


def _catapult_launch(case: Case, height: float) -> TakeoffResult:
    """A catapult launch (SPEC 4): no runway, airborne at the release speed, then the arc and
    the climb to the obstacle; not attainable when the catapult's energy cannot give the
    aircraft its release speed."""
    aircraft, rho = case.aircraft, case.density_kg_m3
    release = float(true_airspeed_m_s(aircraft.launch_speed_m_s, rho))
    stall = float(stall_speed_m_s(aircraft, rho))
    kinetic = 0.5 * aircraft.mass_kg * release ** 2
    known = {"liftoff_speed_m_s": release, "stall_speed_m_s": stall}
    if catapult_energy_shortfall(aircraft.mass_kg, release, aircraft.launch_energy_j):
        raise NotAttainable(
            f"the catapult's launch_energy_j {aircraft.launch_energy_j:g} J is below the "
            f"kinetic energy at release, m V^2 / 2 = {kinetic:.0f} J ({aircraft.mass_kg:g} kg "
            f"at {release:.1f} m/s)", known)
    if beyond_jet_velocity(case.propulsion, release, rho):  # as a lift-off there (audit)
        jet = float(static_jet_velocity_m_s(case.propulsion, rho))
        raise NotAttainable(
            f"release at {release:.1f} m/s is beyond the fans' jet velocity {jet:.1f} m/s "
            "(momentum theory), where they make no thrust to climb away", known)
    warnings = [f"catapult launch at {aircraft.launch_speed_m_s:g} m/s EAS: no runway, no "
                "ground roll"]
    if aircraft.launch_energy_j is None:
        warnings.append(f"launch_energy_j not given: the catapult's energy is not checked "
                        f"(the release needs m V^2 / 2 = {kinetic:.0f} J)")
    v_tr = float(transition_speed_m_s(aircraft, rho))
    packs = _packs_of(case)
    if packs is not None:  # full packs give full throttle at all (else no voltage to fly on)
        _refuse_beyond_battery(case, np.array([release, v_tr]), 0.0, known)
    accelerate, seconds, charge, accelerates = release_acceleration(
        aircraft.mass_kg, release, v_tr, _release_forces(case, packs))
    if not accelerates[0]:
        raise NotAttainable(
            f"after the release at {release:.1f} m/s full throttle does not accelerate to the "
            f"transition speed {v_tr:.1f} m/s ({TRANSITION_SPEED_OVER_STALL:g} x stall): "
            "thrust below the level-flight drag on the way", known)
    air = _airborne(case, height, packs, None if charge is None else charge[:, 0])
    _refuse_beyond_battery(case, np.array([release, air.speed_m_s]),
                           float(seconds[0]) + (air.distance_m or 0.0) / air.speed_m_s, known)
    if air.beyond_battery:  # the packs give out in the climb, before the obstacle
        raise NotAttainable(air.reason, known)
    if accelerate[0] > 0.0:
        warnings.append(f"released at {release:.1f} m/s, below the transition speed "
                        f"{v_tr:.1f} m/s: {float(accelerate[0]):.1f} m of level acceleration at "
                        f"full throttle ({float(seconds[0]):.2f} s) before the arc")
    # released airborne: the airspeeds between the release and the arc's are flown
    extrapolated, beyond = flown_span_note(case.propulsion, min(release, air.speed_m_s),
                                           max(release, air.speed_m_s))
    warnings.extend(beyond)
    if packs is not None:
        warnings.append(_packs_note(case, packs.point(np.zeros(packs.n), np.array([release]))[2],
                                    None, air))
    else:
        note = reference_voltage_note(case.propulsion, "the take-off")
        warnings.extend([note] if note else [])
    return TakeoffResult(
        ground_roll_m=0.0,
        liftoff_speed_m_s=release,
        time_s=0.0,
        history_time_s=np.zeros(1),
        history_airspeed_m_s=np.full(1, release),
        history_distance_m=np.zeros(1),
        extrapolated=extrapolated,
        warnings=tuple(warnings),
        liftoff_speed_eas_m_s=float(aircraft.launch_speed_m_s),
        stall_speed_m_s=stall,
        density_kg_m3=rho,
        acceleration_distance_m=float(accelerate[0]),
        **_after_release(air.fields(0.0, aircraft.takeoff.transition_load_factor, height),
                         float(accelerate[0])),
        launch="catapult",
    )


def _refuse_beyond_battery(case: Case, speeds: np.ndarray, seconds: float,
                           known: dict[str, Any]) -> None:
    """Full throttle on the packs over these airspeeds [m/s] for ``seconds``, or not
    attainable (:func:`tuflexperf.analysis.pack_limits.takeoff_beyond_battery`; no battery:
    nothing)."""
    from tuflexperf.analysis.pack_limits import pack_side, takeoff_beyond_battery

    side = pack_side(case)
    why = None if side is None else takeoff_beyond_battery(case, side, speeds, seconds)
    if why is not None:
        raise NotAttainable(why, known)


def flown_span_note(propulsion: Propulsion, slowest_m_s: float, fastest_m_s: float
                    ) -> tuple[bool, list[str]]:
    """Whether a take-off flying every airspeed from ``slowest_m_s`` to ``fastest_m_s``
    [m/s] uses the thrust model outside its tested range, and the warnings saying where.

    References
    ----------
    SPEC 3 (extrapolation is said); :func:`~tuflexperf.models.thrust.outside_tested_span`.
    """
    low, high = propulsion.tested_airspeed_m_s
    warnings: list[str] = []
    if outside_tested_span(propulsion, slowest_m_s, low):
        warnings.append(
            f"take-off airspeeds {slowest_m_s:.1f}-{min(fastest_m_s, low):.1f} m/s are below "
            f"the thrust model's tested airspeed range {low:g}-{high:g} m/s (extrapolated)"
        )
    if outside_tested_span(propulsion, high, fastest_m_s):
        warnings.append(
            f"take-off airspeed {fastest_m_s:.1f} m/s is outside the thrust model's tested "
            f"airspeed range {low:g}-{high:g} m/s (extrapolated)"
        )
    return bool(warnings), warnings


def solve_takeoff(case: Case, obstacle_height_m: float | None = None) -> TakeoffResult:
    """Take-off at full throttle for ``case``: ground roll, rotation, arc and climb to the obstacle.

    Raises :class:`NotAttainable` with the reason when lift-off is never reached.
    The lift-off speed is an EAS converted to true airspeed at the case's density
    (SPEC 3); thrust is scaled by ``rho / rho_ref`` where the model has a reference
    density.

    References
    ----------
    Raymer, *Aircraft Design*, sections 17.8.1-17.8.3; Anderson, *Aircraft
    Performance and Design*, section 6.7.
    """
    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3
    to = aircraft.takeoff
    height = obstacle_height_of(case) if obstacle_height_m is None else float(obstacle_height_m)
    if aircraft.launch == "catapult":
        return _catapult_launch(case, height)
    v_lo = float(liftoff_speed_m_s(aircraft, rho))
    stall = float(stall_speed_m_s(aircraft, rho))
    if v_lo < stall * (1.0 - 1e-12):
        raise InputError(
            f"{case.aircraft_path}: takeoff.liftoff_speed_m_s: lift-off speed "
            f"{liftoff_speed_eas_m_s(aircraft):.2f} m/s EAS is below the stall speed "
            f"{stall_speed_eas_m_s(aircraft):.2f} m/s EAS"
        )
    speeds = np.linspace(0.0, v_lo, _CHECK_POINTS)
    known = {"liftoff_speed_m_s": v_lo, "stall_speed_m_s": stall}
    packs = _packs_of(case)
    if packs is None:
        force = np.asarray(net_force_n(aircraft, propulsion, speeds, rho), dtype=float)
    else:
        # full packs give full throttle over the roll at all (else no voltage to fly on)
        _refuse_beyond_battery(case, speeds[::(_CHECK_POINTS - 1) // (HISTORY_POINTS - 1)],
                               0.0, known)
        force = _on_packs_force(case, packs, np.zeros((packs.n, 1)), speeds)
    if force[0] <= 0.0:
        raise NotAttainable(
            f"never starts rolling: static thrust does not overcome rolling friction "
            f"(net force {force[0]:.2f} N at rest)", known
        )
    if np.any(force <= 0.0):
        i = int(np.argmax(force <= 0.0))
        # where the net force crosses zero, between the two check points around it
        stuck = speeds[i - 1] + (speeds[i] - speeds[i - 1]) * force[i - 1] / (
            force[i - 1] - force[i])
        raise NotAttainable(
            f"never reaches lift-off: the net force vanishes at {stuck:.2f} m/s, below the "
            f"lift-off speed {v_lo:.2f} m/s", known
        )
    if beyond_jet_velocity(propulsion, v_lo, rho):
        # the extrapolated polynomial may still give thrust there; a fan does not
        jet = float(static_jet_velocity_m_s(propulsion, rho))
        raise NotAttainable(
            f"lift-off at {v_lo:.1f} m/s is beyond the fans' jet velocity {jet:.1f} m/s "
            f"(momentum theory, full-throttle static thrust on fan_area_m2), where they make "
            f"no thrust; the thrust model is extrapolated there (tested "
            f"{propulsion.tested_airspeed_m_s[0]:g}-{propulsion.tested_airspeed_m_s[1]:g} m/s)",
            known,
        )
    rows = 2 if packs is None else 2 + packs.n
    try:
        # CasADi prints the failed call's inputs (8 lines per try) through Python's stderr:
        # the reason below says what failed, in one line
        with contextlib.redirect_stderr(io.StringIO()):
            states = np.asarray(_integrator_for(case)(v_lo) if packs is None
                                else packs.roll(v_lo))
    except RuntimeError:  # CVODES failed: the net force nearly vanishes between check points
        states = np.full((rows, HISTORY_POINTS - 1), np.nan)
    if not np.all(np.isfinite(states)):
        raise NotAttainable(
            f"never reaches lift-off: the net force all but vanishes below the lift-off speed "
            f"{v_lo:.2f} m/s (least {force.min():.3g} N{_ON_PACKS if packs else ''})", known
        )
    distance = np.concatenate([[0.0], states[0, :]])
    time = np.concatenate([[0.0], states[1, :]])
    history_speed = np.linspace(0.0, v_lo, distance.size)
    charge = np.zeros((0, distance.size)) if packs is None else np.concatenate(
        [np.zeros((packs.n, 1)), states[2:, :]], axis=1)
    if packs is None:
        history_thrust = np.asarray(total_thrust_n(propulsion, 1.0, history_speed, rho),
                                    dtype=float)
    else:
        history_thrust, _, history_volts = packs.point(charge, history_speed)
        # the force where the packs have sagged (between the history's nodes, its charge
        # interpolated): a roll that stalls as they sag never lifts off
        along = np.stack([np.interp(speeds, history_speed, q) for q in charge])
        sagged = _on_packs_force(case, packs, along, speeds)
        if np.any(sagged <= 0.0):
            stuck = float(speeds[int(np.argmax(sagged <= 0.0))])
            raise NotAttainable(
                f"never reaches lift-off: the net force vanishes at {stuck:.2f} m/s as the "
                f"packs sag{_ON_PACKS}, below the lift-off speed {v_lo:.2f} m/s", known)
    history_drag, history_friction = (
        np.broadcast_to(np.asarray(f, dtype=float), history_speed.shape).copy()
        for f in ground_roll_resistance_n(aircraft, history_speed, rho)
    )
    rotation_m = v_lo * to.rotation_time_s  # Raymer 17.8.2: rotation at the lift-off speed

    air = _airborne(case, height, packs, None if packs is None else packs.rotation(
        charge[:, -1], v_lo, to.rotation_time_s))
    airborne_s = (air.distance_m or 0.0) / air.speed_m_s
    _refuse_beyond_battery(case, np.append(history_speed, air.speed_m_s),
                           float(time[-1]) + to.rotation_time_s + airborne_s, known)
    if air.beyond_battery:  # the packs give out in the climb, before the obstacle
        raise NotAttainable(air.reason, known)
    ground_roll = float(distance[-1]) + rotation_m

    # the roll flies every airspeed from rest up to the lift-off's, the arc its own
    extrapolated, warnings = flown_span_note(propulsion, 0.0, max(v_lo, air.speed_m_s))
    if packs is None:
        voltage_note = reference_voltage_note(propulsion, "the take-off")
        if voltage_note:
            warnings.append(voltage_note)
    else:
        warnings.append(_packs_note(case, history_volts[:, 0], history_volts[:, -1], air))
    density_note = unlapsed_density_warning(propulsion, rho)
    if density_note:
        warnings.append(density_note)
    margin = stall_margin_of(case)
    if air.speed_m_s < margin * stall * (1.0 - 1e-12):
        # SPEC 3 fixes the take-off's arc at 1.15 V_stall; the envelope's margin bounds the
        # other climbs (an engineer comparing them should not have to find this out)
        warnings.append(
            f"the transition arc and the climb to the obstacle are flown at {air.speed_m_s:.1f}"
            f" m/s (1.15 x stall, the take-off's convention), below the envelope's "
            f"{margin:g} x stall = {margin * stall:.1f} m/s that bounds level flight and climb"
        )
    if not air.gradient > 0.0:
        # the roll's distance is reached, but nothing flies away from it (outside audit: a
        # poor polar lifted off below its least level-flight speed and said nothing)
        warnings.append(
            f"after lift-off the full-throttle climb gradient at {air.speed_m_s:.1f} m/s "
            f"(1.15 x stall) is {air.gradient:.3f}: the aircraft cannot climb away"
        )
    if to.cl_ground > 0.0:
        # ground lift equal to the weight before lift-off: the wheels carry nothing from there
        unloaded = math.sqrt(2.0 * aircraft.weight_n / (rho * aircraft.wing_area_m2 * to.cl_ground))
        if unloaded < v_lo:
            warnings.append(
                f"cl_ground {to.cl_ground:g} lifts the weight at {unloaded:.1f} m/s, below the "
                f"lift-off speed {v_lo:.1f} m/s: no runway friction from there (clamped at "
                "zero); check cl_ground against the lift-off lift coefficient"
            )
    return TakeoffResult(
        ground_roll_m=ground_roll,
        liftoff_speed_m_s=v_lo,
        time_s=float(time[-1]) + to.rotation_time_s,
        history_time_s=time,
        history_airspeed_m_s=history_speed,
        history_distance_m=distance,
        extrapolated=extrapolated,
        warnings=tuple(warnings),
        liftoff_speed_eas_m_s=float(liftoff_speed_eas_m_s(aircraft)),
        stall_speed_m_s=stall,
        density_kg_m3=rho,
        acceleration_distance_m=float(distance[-1]),
        rotation_time_s=to.rotation_time_s,
        rotation_distance_m=rotation_m,
        **air.fields(ground_roll, to.transition_load_factor, height),
        history_thrust_n=history_thrust,
        history_drag_n=history_drag,
        history_friction_n=history_friction,
    )
