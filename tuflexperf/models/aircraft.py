"""Aircraft aerodynamics: drag polar, level flight, stall, lift-off, climb and the obstacle.

Drag polar ``CD = cd0 + k CL^2`` (Anderson, *Aircraft Performance and Design*,
eq. 2.47); level flight ``L = W`` (SPEC 3). Airspeeds the pilot sets are
equivalent airspeeds (EAS); physics uses true airspeed (TAS),
``V = EAS sqrt(rho0 / rho)``. Every function takes floats, numpy arrays or CasADi
symbols through one code path (``tuflexperf.models._math``).

References
----------
Anderson, J. D., *Aircraft Performance and Design*, McGraw-Hill, 1999: ch. 5
(steady flight, climb) and 6.7 (take-off). Raymer, D. P., *Aircraft Design: A
Conceptual Approach*, AIAA, section 17.8 (take-off analysis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tuflexperf.models._math import Vectorizable, fmax, sqrt, where
from tuflexperf.models.atmosphere import (
    G0_M_S2,
    GAS_CONSTANT_J_KG_K,
    SEA_LEVEL_PRESSURE_PA,
    SEA_LEVEL_TEMPERATURE_K,
)

DEFAULT_LIFTOFF_SPEED_FACTOR = 1.1
DEFAULT_TRANSITION_LOAD_FACTOR = 1.19
TRANSITION_SPEED_OVER_STALL = 1.15
DEFAULT_OBSTACLE_HEIGHT_M = 15.0
# Mach 1 at sea level, rounded: the top of every airspeed the subsonic drag polar and the
# fans' poly22 are used at (schemas' bounds, stall, envelope, mission speed searches)
MAX_AIRSPEED_M_S = 340.0
# rho0 of EAS: the ISA's own sea-level density (1.2250 kg/m^3 to 8 digits), so EAS = TAS there
EAS_REFERENCE_DENSITY_KG_M3 = SEA_LEVEL_PRESSURE_PA / (
    GAS_CONSTANT_J_KG_K * SEA_LEVEL_TEMPERATURE_K
)


@dataclass(frozen=True)
class TakeoffConfig:
    """Ground-roll and transition configuration; ``None`` fields fall back to the clean polar.

    ``liftoff_speed_m_s`` is an equivalent airspeed [m/s]; when given it replaces
    ``liftoff_speed_factor`` (x stall speed). ``rotation_time_s`` [s] is spent on
    the ground at the lift-off speed (Raymer 17.8.2); ``transition_load_factor``
    [-] is the arc's load factor after lift-off (Anderson 6.7.2).
    """

    cl_ground: float
    rolling_friction: float = 0.04
    liftoff_speed_m_s: float | None = None
    cd0_ground: float | None = None
    k_ground: float | None = None
    liftoff_speed_factor: float = DEFAULT_LIFTOFF_SPEED_FACTOR
    rotation_time_s: float = 0.0
    transition_load_factor: float = DEFAULT_TRANSITION_LOAD_FACTOR


@dataclass(frozen=True)
class Aircraft:
    """Mass and aerodynamic data of the aircraft (SI units)."""

    name: str
    mass_kg: float
    wing_area_m2: float
    cd0: float
    k: float
    cl_max: float
    takeoff: TakeoffConfig
    launch: str = "runway"  # or "catapult": endurance and missions start airborne
    launch_speed_m_s: float | None = None  # catapult: EAS at release
    launch_energy_j: float | None = None  # catapult: from ground equipment, not the battery

    @property
    def weight_n(self) -> float:
        """Weight ``m g0`` in N."""
        return self.mass_kg * G0_M_S2


def dynamic_pressure_pa(density_kg_m3: Vectorizable, airspeed_m_s: Vectorizable) -> Vectorizable:
    """``q = rho V^2 / 2`` [Pa] from density [kg/m^3] and true airspeed [m/s]."""
    return 0.5 * density_kg_m3 * airspeed_m_s * airspeed_m_s


def polar_drag_coefficient(cl: Vectorizable, cd0: float, k: float) -> Vectorizable:
    """Parabolic polar ``CD = cd0 + k CL^2`` [-] (Anderson eq. 2.47)."""
    return cd0 + k * cl * cl


def true_airspeed_m_s(
    equivalent_airspeed_m_s: Vectorizable, density_kg_m3: Vectorizable
) -> Vectorizable:
    """True airspeed [m/s] from an equivalent airspeed [m/s]: ``EAS sqrt(rho0 / rho)``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, section 3.5 (equivalent airspeed),
    with ``rho0 = 1.225 kg/m^3`` (ISA sea level).
    """
    return equivalent_airspeed_m_s * sqrt(EAS_REFERENCE_DENSITY_KG_M3 / density_kg_m3)


def equivalent_airspeed_m_s(
    true_airspeed: Vectorizable, density_kg_m3: Vectorizable
) -> Vectorizable:
    """Equivalent airspeed [m/s] from a true airspeed [m/s]: ``V sqrt(rho / rho0)``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, section 3.5.
    """
    return true_airspeed * sqrt(density_kg_m3 / EAS_REFERENCE_DENSITY_KG_M3)


def level_flight_cl(
    aircraft: Aircraft, airspeed_m_s: Vectorizable, density_kg_m3: Vectorizable
) -> Vectorizable:
    """Lift coefficient [-] for ``L = W`` at true airspeed [m/s] and density [kg/m^3]."""
    return aircraft.weight_n / (
        dynamic_pressure_pa(density_kg_m3, airspeed_m_s) * aircraft.wing_area_m2
    )


def level_flight_drag_n(
    aircraft: Aircraft, airspeed_m_s: Vectorizable, density_kg_m3: Vectorizable
) -> Vectorizable:
    """Drag [N] in steady level flight: ``q S cd0 + k W^2 / (q S)`` (Anderson eq. 5.18)."""
    q_s = dynamic_pressure_pa(density_kg_m3, airspeed_m_s) * aircraft.wing_area_m2
    return q_s * aircraft.cd0 + aircraft.k * aircraft.weight_n**2 / q_s


def stall_speed_m_s(aircraft: Aircraft, density_kg_m3: Vectorizable) -> Vectorizable:
    """1-g stall speed, true airspeed [m/s]: ``sqrt(2 W / (rho S CL_max))``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.67.
    """
    return sqrt(2.0 * aircraft.weight_n / (density_kg_m3 * aircraft.wing_area_m2 * aircraft.cl_max))


def stall_speed_eas_m_s(aircraft: Aircraft) -> Vectorizable:
    """1-g stall speed as an equivalent airspeed [m/s]; the same at every density.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.67 at ``rho0 = 1.225 kg/m^3``.
    """
    return sqrt(  # backend-neutral: the batched analyses pass array-valued aircraft
        2.0
        * aircraft.weight_n
        / (EAS_REFERENCE_DENSITY_KG_M3 * aircraft.wing_area_m2 * aircraft.cl_max)
    )


def liftoff_speed_eas_m_s(aircraft: Aircraft) -> Vectorizable:
    """Lift-off speed as an equivalent airspeed [m/s] (SPEC 3).

    The file's ``liftoff_speed_m_s`` (an EAS) where given, else
    ``liftoff_speed_factor`` (default 1.1) times the stall EAS.

    References
    ----------
    Raymer, *Aircraft Design*, section 17.8.1 (lift-off at about 1.1 V_stall).
    """
    to = aircraft.takeoff
    if to.liftoff_speed_m_s is not None:
        return to.liftoff_speed_m_s
    return to.liftoff_speed_factor * stall_speed_eas_m_s(aircraft)


def liftoff_speed_m_s(aircraft: Aircraft, density_kg_m3: Vectorizable) -> Vectorizable:
    """Lift-off true airspeed [m/s] at density [kg/m^3]: the lift-off EAS times ``sqrt(rho0/rho)``.

    References
    ----------
    Raymer, *Aircraft Design*, section 17.8.1; SPEC 3 (airspeeds the pilot sets are EAS).
    """
    return true_airspeed_m_s(liftoff_speed_eas_m_s(aircraft), density_kg_m3)


def minimum_drag_speed_m_s(aircraft: Aircraft, density_kg_m3: Vectorizable) -> Vectorizable:
    """True airspeed [m/s] of least level-flight drag, ``sqrt(2W/(rho S) sqrt(k/cd0))``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.34.
    """
    return sqrt(
        2.0
        * aircraft.weight_n
        / (density_kg_m3 * aircraft.wing_area_m2)
        * sqrt(aircraft.k / aircraft.cd0)
    )


def minimum_drag_n(aircraft: Aircraft) -> float:
    """Least level-flight drag ``2 W sqrt(cd0 k)`` [N] (independent of density).

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.30 (``(L/D)_max = 1 / (2 sqrt(cd0 k))``).
    """
    return 2.0 * aircraft.weight_n * (aircraft.cd0 * aircraft.k) ** 0.5


def climb_gradient(
    aircraft: Aircraft,
    thrust_n: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
) -> Vectorizable:
    """Steady climb gradient ``sin(gamma) = (T - D) / W`` [-], drag at ``L = W``.

    Thrust [N], true airspeed [m/s], density [kg/m^3]. The small-angle assumption
    (lift equal to weight) is the textbooks'; it overstates drag by under 1 % of
    the induced part at gradients below 0.14.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eqs. 5.77-5.79 (section 5.10).
    """
    return (thrust_n - level_flight_drag_n(aircraft, airspeed_m_s, density_kg_m3)) / (
        aircraft.weight_n
    )


def climb_sine(gradient: Vectorizable) -> Vectorizable:
    """Sine of the steady climb angle [-] from the climb ``gradient`` [-]: at most 1.

    A gradient of 1 or more (thrust above weight plus drag) is a vertical climb: the
    path cannot be steeper, and the excess thrust would accelerate the aircraft, which a
    steady climb does not fly. Below 1 the two are equal.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.78 (``sin gamma = (T - D) / W``).
    """
    return _at_most_one(gradient)


def climb_rate_m_s(
    aircraft: Aircraft,
    thrust_n: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
) -> Vectorizable:
    """Steady rate of climb ``R/C = V sin(gamma)`` [m/s], ``sin(gamma) = (T - D) / W`` (Anderson
    eq. 5.80), drag at ``L = W``; a vertical climb (:func:`climb_sine`) climbs at ``V``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.80.
    """
    return airspeed_m_s * climb_sine(
        climb_gradient(aircraft, thrust_n, airspeed_m_s, density_kg_m3))


def ground_roll_net_force_n(
    aircraft: Aircraft,
    thrust_n: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
) -> Vectorizable:
    """Accelerating force on the ground roll, ``T - D - mu max(W - L, 0)`` [N].

    Thrust [N], true airspeed [m/s], density [kg/m^3]. Uses the ground
    configuration's ``cl_ground`` and, where given, ``cd0_ground``/``k_ground``.
    Friction acts on the wheel load ``max(W - L, 0)``: with more lift than weight
    the runway carries nothing, it never pushes (SPEC 3).

    References
    ----------
    Raymer, *Aircraft Design*, eq. 17.97; Anderson, *Aircraft Performance and Design*, eq. 6.77.
    """
    drag, friction = ground_roll_resistance_n(aircraft, airspeed_m_s, density_kg_m3)
    return thrust_n - drag - friction


def ground_roll_resistance_n(
    aircraft: Aircraft, airspeed_m_s: Vectorizable, density_kg_m3: Vectorizable
) -> tuple[Vectorizable, Vectorizable]:
    """Aerodynamic drag and rolling friction on the ground roll, ``(D_g, mu max(W - L_g, 0))`` [N].

    True airspeed [m/s], density [kg/m^3]; the two forces that
    :func:`ground_roll_net_force_n` subtracts from the thrust (the report draws them).

    References
    ----------
    Raymer, *Aircraft Design*, eq. 17.97.
    """
    to = aircraft.takeoff
    cd0 = aircraft.cd0 if to.cd0_ground is None else to.cd0_ground
    k = aircraft.k if to.k_ground is None else to.k_ground
    q_s = dynamic_pressure_pa(density_kg_m3, airspeed_m_s) * aircraft.wing_area_m2
    lift = q_s * to.cl_ground
    drag = q_s * polar_drag_coefficient(to.cl_ground, cd0, k)
    return drag, to.rolling_friction * fmax(aircraft.weight_n - lift, 0.0)


def transition_speed_m_s(aircraft: Aircraft, density_kg_m3: Vectorizable) -> Vectorizable:
    """Mean true airspeed [m/s] of the transition arc after lift-off, ``1.15 V_stall``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, section 6.7.2 (from 1.1 V_stall at
    lift-off to 1.2 V_stall at the obstacle); Raymer, *Aircraft Design*, section 17.8.3.
    """
    return TRANSITION_SPEED_OVER_STALL * stall_speed_m_s(aircraft, density_kg_m3)


def transition_radius_m(airspeed_m_s: Vectorizable, load_factor: Vectorizable) -> Vectorizable:
    """Radius [m] of the pull-up arc at true airspeed [m/s] and load factor [-]: ``V^2/(g (n-1))``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 6.41 (pull-up) and 6.98.
    """
    return airspeed_m_s * airspeed_m_s / (G0_M_S2 * (load_factor - 1.0))


def obstacle_distances_m(
    radius_m: Vectorizable, climb_gradient_: Vectorizable, obstacle_height_m: Vectorizable,
    straight_gradient: Vectorizable | None = None,
) -> tuple[Vectorizable, Vectorizable, Vectorizable]:
    """Horizontal distances [m] from lift-off to an obstacle: (arc, straight climb, arc top [m]).

    The arc of ``radius_m`` [m] turns the path up to the climb angle ``gamma`` with
    ``sin(gamma) = climb_gradient_`` [-]; it reaches ``h_TR = R (1 - cos gamma)``.
    If the obstacle ``h`` [m] is cleared during the arc (``h_TR >= h``) the airborne
    distance is ``R sin(acos(1 - h/R)) = sqrt(h (2R - h))`` and the climb part is 0;
    otherwise the arc covers ``R sin(gamma)`` and the straight climb
    ``(h - h_TR) / tan(gamma_c)``, ``sin(gamma_c)`` the ``straight_gradient`` [-] (default
    the arc's; packs that sag on the way lower it). With no positive climb gradient an
    obstacle above the arc is never cleared: the climb part is ``inf``; a gradient of 1 or
    more (thrust beyond drag plus weight) climbs vertically, ``gamma = 90 deg``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eqs. 6.99-6.100 (section 6.7.2);
    Raymer, *Aircraft Design*, eqs. 17.108-17.111.
    """
    g = climb_gradient_
    positive = g > 0.0
    # excess thrust beyond the weight (G >= 1) climbs vertically: the path angle ends at 90
    # degrees (sin = G read past 1 gave arcs longer than their radius; outside audit)
    sin_g = where(positive, _at_most_one(g), 0.0)
    cos_g = sqrt(1.0 - _at_most_one(sin_g * sin_g))
    arc_height = radius_m * (1.0 - cos_g)
    cleared_in_arc = arc_height >= obstacle_height_m
    within = sqrt(fmax(obstacle_height_m * (2.0 * radius_m - obstacle_height_m), 0.0))
    if straight_gradient is None:
        straight, sin_c, cos_c = positive, sin_g, cos_g
    else:
        straight = where(positive, straight_gradient, 0.0) > 0.0
        sin_c = where(straight, _at_most_one(straight_gradient), 0.0)
        cos_c = sqrt(1.0 - _at_most_one(sin_c * sin_c))
    safe_sin = where(straight, sin_c, 1.0)
    climb = where(straight, (obstacle_height_m - arc_height) * cos_c / safe_sin, math.inf)
    arc = where(cleared_in_arc, within, radius_m * sin_g)
    climb = where(cleared_in_arc, 0.0, climb)
    # where the obstacle is cleared in the arc, the arc is flown only up to its height
    return arc, climb, where(cleared_in_arc, obstacle_height_m, arc_height)


def _at_most_one(value: Vectorizable) -> Vectorizable:
    """``min(value, 1)`` element-wise: keeps ``sqrt(1 - s^2)`` real when rounding exceeds 1."""
    return where(value < 1.0, value, 1.0)


def catapult_energy_shortfall(
    mass_kg: Vectorizable, release_m_s: Vectorizable, energy_j: Vectorizable | None
) -> Vectorizable:
    """True where the catapult's energy [J] is below the kinetic energy at release
    ``m V^2 / 2`` [J] (``V`` the release true airspeed [m/s], no wind); False without an
    energy (``None``: not checked). Floats or numpy arrays.

    References
    ----------
    SPEC 4 (``launch_energy_j``: the ground equipment's energy, not the battery's).
    """
    kinetic = 0.5 * mass_kg * release_m_s * release_m_s
    if energy_j is None:
        return kinetic < 0.0  # never: the same shape as the kinetic energy
    return energy_j < kinetic


def transition_beyond_cl_max(load_factor: Vectorizable) -> Vectorizable:
    """True where the transition arc, flown at ``1.15 V_stall``, needs more than ``cl_max``:
    a load factor ``n`` needs ``CL = n cl_max / 1.15^2`` (the default 1.19 is 0.9 cl_max).

    References
    ----------
    Raymer, *Aircraft Design*, 17.8.3 (transition at 1.15 V_stall, CL = 0.9 cl_max);
    Anderson, *Aircraft Performance and Design*, 6.7.
    """
    return load_factor > TRANSITION_SPEED_OVER_STALL ** 2 * (1.0 + 1e-12)
