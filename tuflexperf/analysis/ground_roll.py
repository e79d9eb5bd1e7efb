"""The take-off's ground roll: full-throttle force on the runway, its integrator, the release.

The roll's right-hand side is :func:`tuflexperf.models.aircraft.ground_roll_net_force_n` at
the full-throttle thrust (:func:`net_force_n`); :func:`build_ground_roll_integrator`
integrates it in CasADi from rest to the lift-off speed, built once per content hash of
the models; :func:`release_acceleration` is the catapult's release.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tuflexperf.analysis.cache import BoundedCache, fingerprint
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    Aircraft,
    ground_roll_net_force_n,
)
from tuflexperf.models.battery import SECONDS_PER_HOUR
from tuflexperf.models.thrust import (
    Propulsion,
    thrust_part,
    total_thrust_n,
)

HISTORY_POINTS = 101

CHECK_POINTS = 2001

TAKEOFF_CACHE: BoundedCache[Any] = BoundedCache()


def net_force_n(
    aircraft: Aircraft, propulsion: Propulsion, airspeed_m_s: Any, density_kg_m3: float
) -> Any:
    """Accelerating force at full throttle on the runway in N (floats, numpy or CasADi)."""
    thrust = total_thrust_n(propulsion, 1.0, airspeed_m_s, density_kg_m3)
    return ground_roll_net_force_n(aircraft, thrust, airspeed_m_s, density_kg_m3)


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


def integrator_for(case: Case) -> Any:
    return TAKEOFF_CACHE.get(
        # the roll reads the thrust alone (a reading that moves the power shares it)
        fingerprint(case.aircraft, thrust_part(case.propulsion), case.density_kg_m3),
        lambda: build_ground_roll_integrator(case.aircraft, case.propulsion, case.density_kg_m3),
    )

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
