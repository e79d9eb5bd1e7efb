"""Take-off ground roll at full throttle, from rest to lift-off speed.

Equation of motion on the runway (Raymer, *Aircraft Design*, section 17.8.1):
``m dV/dt = T(1, V) - D_g(V) - mu (W - L_g(V))``. With the airspeed as the
independent variable, ``ds/dV = m V / F(V)`` and ``dt/dV = m / F(V)``, integrated by
CasADi's CVODES from 0 to the lift-off speed (no wind, level runway).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import Aircraft, ground_roll_net_force_n, liftoff_speed_m_s
from tuflexperf.models.thrust import Propulsion, is_extrapolated, total_thrust_n

HISTORY_POINTS = 101
_CHECK_POINTS = 2001
_cache: dict[Any, Any] = {}


def net_force_n(
    aircraft: Aircraft, propulsion: Propulsion, airspeed_m_s: Any, density_kg_m3: float
) -> Any:
    """Accelerating force at full throttle on the runway in N (floats, numpy or CasADi)."""
    thrust = total_thrust_n(propulsion, 1.0, airspeed_m_s, density_kg_m3)
    return ground_roll_net_force_n(aircraft, thrust, airspeed_m_s, density_kg_m3)


@dataclass(frozen=True)
class TakeoffResult:
    """Ground roll in m, lift-off speed in m/s, time in s, and the time history of the roll."""

    ground_roll_m: float
    liftoff_speed_m_s: float
    time_s: float
    history_time_s: np.ndarray = field(repr=False)
    history_airspeed_m_s: np.ndarray = field(repr=False)
    history_distance_m: np.ndarray = field(repr=False)
    extrapolated: bool = False
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {
            "ground_roll_m": self.ground_roll_m,
            "liftoff_speed_m_s": self.liftoff_speed_m_s,
            "time_s": self.time_s,
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
        {"abstol": 1e-12, "reltol": 1e-11, "max_num_steps": 100000},
    )
    v_lo_in = ca.MX.sym("v_lo_in")
    states = integrator(x0=ca.DM.zeros(2), p=v_lo_in)["xf"]
    return ca.Function("ground_roll_history", [v_lo_in], [states])


def _integrator_for(case: Case) -> Any:
    key = (repr(case.aircraft), repr(case.propulsion), case.density_kg_m3)
    if key not in _cache:
        _cache[key] = build_ground_roll_integrator(
            case.aircraft, case.propulsion, case.density_kg_m3
        )
    return _cache[key]


def solve_takeoff(case: Case) -> TakeoffResult:
    """Ground roll at full throttle for ``case``; raises :class:`NotAttainable` with the reason."""
    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3
    v_lo = float(liftoff_speed_m_s(aircraft, rho))
    speeds = np.linspace(0.0, v_lo, _CHECK_POINTS)
    force = np.asarray(net_force_n(aircraft, propulsion, speeds, rho), dtype=float)
    if force[0] <= 0.0:
        raise NotAttainable(
            f"never starts rolling: static thrust does not overcome rolling friction "
            f"(net force {force[0]:.2f} N at rest)"
        )
    if np.any(force <= 0.0):
        stuck = speeds[int(np.argmax(force <= 0.0))]
        raise NotAttainable(
            f"never reaches lift-off: the net force vanishes at {stuck:.1f} m/s, below the "
            f"lift-off speed {v_lo:.1f} m/s"
        )
    try:
        states = np.asarray(_integrator_for(case)(v_lo))
    except RuntimeError:  # CVODES failed: the net force nearly vanishes between check points
        states = np.full((2, HISTORY_POINTS - 1), np.nan)
    if not np.all(np.isfinite(states)):
        raise NotAttainable(
            f"never reaches lift-off: the net force all but vanishes below the lift-off speed "
            f"{v_lo:.1f} m/s (least {force.min():.3g} N)"
        )
    distance = np.concatenate([[0.0], states[0, :]])
    time = np.concatenate([[0.0], states[1, :]])
    history_speed = np.linspace(0.0, v_lo, distance.size)
    warnings: list[str] = []
    extrapolated = is_extrapolated(propulsion, v_lo)
    if extrapolated:
        low, high = propulsion.tested_airspeed_m_s
        warnings.append(
            f"lift-off speed {v_lo:.1f} m/s is outside the thrust model's tested airspeed "
            f"range {low:g}-{high:g} m/s (extrapolated)"
        )
    return TakeoffResult(
        ground_roll_m=float(distance[-1]),
        liftoff_speed_m_s=v_lo,
        time_s=float(time[-1]),
        history_time_s=time,
        history_airspeed_m_s=history_speed,
        history_distance_m=distance,
        extrapolated=extrapolated,
        warnings=tuple(warnings),
    )
