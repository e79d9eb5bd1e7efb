"""Take-off at full throttle: ground roll, rotation, transition arc and climb to the obstacle.

Equation of motion on the runway (Raymer, *Aircraft Design*, section 17.8.1):
``m dV/dt = T(1, V) - D_g(V) - mu max(W - L_g(V), 0)``. With the airspeed as the
independent variable, ``ds/dV = m V / F(V)`` and ``dt/dV = m / F(V)``, integrated from 0
to the lift-off true airspeed (no wind, level runway) by the batch's quadrature on one row
(:class:`~tuflexperf.analysis.ground_roll.GroundRollRows`); on sagging packs by the batch's
RK4 with the charge drawn per engine beside them (:mod:`.batch_takeoff_packs`, one row).
Rotation adds ``V_LO t_R`` (Raymer 17.8.2);
the airborne part is an arc at ``1.15 V_stall`` and load factor ``n`` followed by the
full-throttle straight climb (Anderson, *Aircraft Performance and Design*, 6.7.2).

The roll lives in :mod:`.ground_roll`, the rotation and the arc (on sagging packs too) in
:mod:`.airborne`; this module holds the result and the catapult and puts the three
together in :func:`solve_takeoff`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.analysis.airborne import (
    ON_PACKS,
    airborne_result,
    obstacle_height_of,
    on_packs_force,
    packs_note,
)
from tuflexperf.analysis.attainable import BEYOND_THE_BATTERY, stall_margin_of
from tuflexperf.analysis.ground_roll import (
    CHECK_POINTS,
    HISTORY_POINTS,
    GroundRollRows,
    net_force_n,
)
from tuflexperf.analysis.pack_limits import limit_reason, pack_rows, pack_side, sagging_packs
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    DEFAULT_OBSTACLE_HEIGHT_M,
    TRANSITION_SPEED_OVER_STALL,
    catapult_energy_shortfall,
    ground_roll_resistance_n,
    liftoff_speed_eas_m_s,
    liftoff_speed_m_s,
    stall_speed_eas_m_s,
    stall_speed_m_s,
    transition_speed_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.powertrain import beyond_jet_velocity, static_jet_velocity_m_s
from tuflexperf.models.thrust import (
    Propulsion,
    outside_tested_span,
    reference_voltage_note,
    total_thrust_n,
    unlapsed_density_warning,
)


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
    packs = packs_of(case)
    if packs is not None:  # full packs give full throttle at all (else no voltage to fly on)
        _refuse_beyond_battery(case, np.array([release, v_tr]), 0.0, known)
    # the batch's release on one row (on full packs where they sag)
    accelerate, seconds, charge, accelerates = (
        GroundRollRows(aircraft, case.propulsion, rho, None, 1).release_run() if packs is None
        else packs.release())
    if not accelerates[0]:
        raise NotAttainable(
            f"after the release at {release:.1f} m/s full throttle does not accelerate to the "
            f"transition speed {v_tr:.1f} m/s ({TRANSITION_SPEED_OVER_STALL:g} x stall): "
            "thrust below the level-flight drag on the way", known)
    air = _airborne(case, height, packs, None if charge is None
                    else np.broadcast_to(charge[:, 0], (packs.n,)))
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
        warnings.append(packs_note(case, packs.point(np.zeros(packs.n), np.array([release]))[2],
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


def _airborne(case: Case, height: float, packs: Any, charge_ah: np.ndarray | None) -> Any:
    """The arc and climb to the obstacle ``height`` [m]: the batch's path on one row, at the
    model's thrust or on the sagging ``packs`` from ``charge_ah`` per engine [Ah]."""
    if packs is None:
        path = GroundRollRows(case.aircraft, case.propulsion, case.density_kg_m3, None,
                              1).obstacle_path(height)
        return airborne_result(case, height, path)
    return airborne_result(case, height, packs.obstacle_path(charge_ah, height), packs.cutoff_v)


def takeoff_beyond_battery(case: Case, side: Any, speeds: np.ndarray,
                           seconds: float) -> str | None:
    """Why full packs (``side``, a :class:`~.pack_limits.PackSide`) cannot give full throttle
    over these take-off airspeeds [m/s] for ``seconds`` [s] (None: they can): the batch's
    :meth:`~.ground_roll.GroundRollRows.launch_on_packs` on one row, every point solved.

    The reason names the point that fails, the earliest in the take-off first: on full
    packs (the brake release's) the first failing airspeed of ``speeds`` [m/s]; after the
    charge, which the aircraft has drawn by the take-off's end at the last of ``speeds``
    (the climb's airspeed), an engine failing there, else the last airspeed that fails,
    said to be the bound's (there the charge is drawn only in the bound), never the brake
    release with the whole take-off's charge drawn.

    References
    ----------
    SPEC 3 (thrust and pack voltage); SPEC 5 (not attainable, with the reason)."""
    v = np.asarray(speeds, dtype=float)
    launch = GroundRollRows(case.aircraft, case.propulsion, case.density_kg_m3, None, 1
                            ).launch_on_packs(side, pack_rows(side.battery), v[None, :],
                                              np.array([seconds]), each_point=True)
    burst = None if launch.burst_a is None else float(launch.burst_a[0])
    engines = case.propulsion.engines
    for after in (False, True):
        failing = []  # (engine, failing airspeeds' indices, voltage, current)
        for j in range(len(launch.power_w)):
            u, current = (x[0] for x in launch.points[2 * j + after])
            beyond = np.flatnonzero(~launch.within[2 * j + after][0])
            if beyond.size:
                failing.append((j, beyond, u, current))
        if not failing:
            continue
        at_end = [f for f in failing if f[1][-1] == v.size - 1]
        j, beyond, u, current = at_end[0] if after and at_end else failing[0]
        n = int(beyond[-1] if after else beyond[0])
        why = limit_reason(side, float(u[n]), float(current[n]),
                           float(launch.power_w[j][0, n]), burst, "burst")
        charge = float(launch.charge_ah[j][0])
        if not after:
            when = "on full packs"
        elif n == v.size - 1:
            when = f"after the take-off's {charge:.3f} Ah"
        else:
            when = (f"with the take-off's {charge:.3f} Ah drawn (an upper bound: the most "
                    f"current for its {seconds:.1f} s; at the last airspeed {v[-1]:.1f} m/s "
                    "the packs hold)")
        return (f"full throttle at {v[n]:.1f} m/s {when}: {engines[j].name}: {why}: "
                f"not attainable, {BEYOND_THE_BATTERY}")
    return None


def _refuse_beyond_battery(case: Case, speeds: np.ndarray, seconds: float,
                           known: dict[str, Any]) -> None:
    """Full throttle on the packs over these airspeeds [m/s] for ``seconds``, or not
    attainable (:func:`takeoff_beyond_battery`; no battery:
    nothing)."""
    side = pack_side(case)
    why = None if side is None else takeoff_beyond_battery(case, side, speeds, seconds)
    if why is not None:
        raise NotAttainable(why, known)



def packs_of(case: Case) -> Any:
    """The sagging packs the take-off flies on
    (:class:`~tuflexperf.analysis.batch_takeoff_packs.TakeoffPacks`), or None (no battery,
    or no reference voltage: the thrust model's own thrust)."""
    if not sagging_packs(case):
        return None
    side = pack_side(case)
    if side is None:
        return None
    # the packs' flight module: only a case on sagging packs needs it
    from tuflexperf.analysis.batch_takeoff_packs import TakeoffPacks

    return TakeoffPacks(case, side)


def ground_roll_of(case: Case, packs: Any
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """The ground roll's distance [m] and time [s] at the :data:`HISTORY_POINTS` airspeeds
    from rest to lift-off (NaN where it never lifts off), and on sagging ``packs``
    (:func:`packs_of`) the charge per engine there [Ah] ``(engines, 101)`` and after the
    rotation ``(engines,)`` (else empty and None): the batch's roll on one row
    (:class:`~tuflexperf.analysis.ground_roll.GroundRollRows`,
    :func:`~tuflexperf.analysis.batch_takeoff_packs.roll_on_packs`)."""
    if packs is None:
        rows = GroundRollRows(case.aircraft, case.propulsion, case.density_kg_m3, None, 1)
        time, distance = (h[0] for h in rows.roll_histories())
        if rows.ground_roll()[3][0] < 0.5:
            distance = time = np.full(HISTORY_POINTS, np.nan)
        return distance, time, np.zeros((0, HISTORY_POINTS)), None
    flown = packs.roll()
    # a shared power surface: every engine draws the one fan's charge
    return (flown.history_distance[0], flown.history_time[0],
            np.broadcast_to(flown.history_charge_ah[:, 0, :], (packs.n, HISTORY_POINTS)),
            np.broadcast_to(flown.charge_ah[:, 0], (packs.n,)))


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
    speeds = np.linspace(0.0, v_lo, CHECK_POINTS)
    known = {"liftoff_speed_m_s": v_lo, "stall_speed_m_s": stall}
    packs = packs_of(case)
    if packs is None:
        force = np.asarray(net_force_n(aircraft, propulsion, speeds, rho), dtype=float)
    else:
        # full packs give full throttle over the roll at all (else no voltage to fly on)
        _refuse_beyond_battery(case, speeds[::(CHECK_POINTS - 1) // (HISTORY_POINTS - 1)],
                               0.0, known)
        force = on_packs_force(case, packs, np.zeros((packs.n, 1)), speeds)
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
            f"(momentum theory, full-throttle static thrust on jet_area_m2, else fan_area_m2), "
            f"where they make no thrust; the thrust model is extrapolated there (tested "
            f"{propulsion.tested_airspeed_m_s[0]:g}-{propulsion.tested_airspeed_m_s[1]:g} m/s)",
            known,
        )
    distance, time, charge, rotated = ground_roll_of(case, packs)
    if not (np.all(np.isfinite(distance)) and np.all(np.isfinite(time))):
        raise NotAttainable(
            f"never reaches lift-off: the net force all but vanishes below the lift-off speed "
            f"{v_lo:.2f} m/s (least {force.min():.3g} N{ON_PACKS if packs else ''})", known
        )
    history_speed = np.linspace(0.0, v_lo, distance.size)
    rotation_m = v_lo * to.rotation_time_s  # Raymer 17.8.2: rotation at the lift-off speed
    ground_roll = float(distance[-1]) + rotation_m
    total_s = float(time[-1]) + to.rotation_time_s
    if packs is None:
        history_thrust = np.asarray(total_thrust_n(propulsion, 1.0, history_speed, rho),
                                    dtype=float)
    else:
        history_thrust, _, history_volts = packs.point(charge, history_speed)
        # the force where the packs have sagged (between the history's nodes, its charge
        # interpolated): a roll that stalls as they sag never lifts off
        along = np.stack([np.interp(speeds, history_speed, q) for q in charge])
        sagged = on_packs_force(case, packs, along, speeds)
        if np.any(sagged <= 0.0):
            stuck = float(speeds[int(np.argmax(sagged <= 0.0))])
            raise NotAttainable(
                f"never reaches lift-off: the net force vanishes at {stuck:.2f} m/s as the "
                f"packs sag{ON_PACKS}, below the lift-off speed {v_lo:.2f} m/s", known)
    history_drag, history_friction = (
        np.broadcast_to(np.asarray(f, dtype=float), history_speed.shape).copy()
        for f in ground_roll_resistance_n(aircraft, history_speed, rho)
    )
    air = _airborne(case, height, packs, rotated)
    airborne_s = (air.distance_m or 0.0) / air.speed_m_s
    _refuse_beyond_battery(case, np.append(history_speed, air.speed_m_s),
                           total_s + airborne_s, known)
    if air.beyond_battery:  # the packs give out in the climb, before the obstacle
        raise NotAttainable(air.reason, known)

    # the roll flies every airspeed from rest up to the lift-off's, the arc its own
    extrapolated, warnings = flown_span_note(propulsion, 0.0, max(v_lo, air.speed_m_s))
    if packs is None:
        voltage_note = reference_voltage_note(propulsion, "the take-off")
        if voltage_note:
            warnings.append(voltage_note)
    else:
        warnings.append(packs_note(case, history_volts[:, 0], history_volts[:, -1], air))
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
            f"after lift-off the full-throttle climb gradient sin(gamma) at "
            f"{air.speed_m_s:.1f} m/s "
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
        time_s=total_s,
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
