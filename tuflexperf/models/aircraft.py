"""Aircraft aerodynamics: parabolic drag polar, level flight, stall and lift-off speed.

Drag polar ``CD = cd0 + k CL^2`` (Anderson, *Aircraft Performance and Design*,
eq. 2.47); level flight ``L = W`` (SPEC 3). Every function takes floats, numpy
arrays or CasADi symbols.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tuflexperf.models._math import sqrt
from tuflexperf.models.atmosphere import G0_M_S2


@dataclass(frozen=True)
class TakeoffConfig:
    """Ground-roll configuration; ``None`` fields fall back to the clean polar."""

    cl_ground: float
    rolling_friction: float = 0.04
    liftoff_speed_m_s: float | None = None
    cd0_ground: float | None = None
    k_ground: float | None = None


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

    @property
    def weight_n(self) -> float:
        """Weight ``m g0`` in N."""
        return self.mass_kg * G0_M_S2


def dynamic_pressure_pa(density_kg_m3: Any, airspeed_m_s: Any) -> Any:
    """``q = rho V^2 / 2`` in Pa."""
    return 0.5 * density_kg_m3 * airspeed_m_s * airspeed_m_s


def polar_drag_coefficient(cl: Any, cd0: float, k: float) -> Any:
    """Parabolic polar ``CD = cd0 + k CL^2``."""
    return cd0 + k * cl * cl


def level_flight_cl(aircraft: Aircraft, airspeed_m_s: Any, density_kg_m3: Any) -> Any:
    """Lift coefficient for ``L = W`` at ``airspeed_m_s``."""
    return aircraft.weight_n / (
        dynamic_pressure_pa(density_kg_m3, airspeed_m_s) * aircraft.wing_area_m2
    )


def level_flight_drag_n(aircraft: Aircraft, airspeed_m_s: Any, density_kg_m3: Any) -> Any:
    """Drag in N in steady level flight: ``q S cd0 + k W^2 / (q S)``."""
    q_s = dynamic_pressure_pa(density_kg_m3, airspeed_m_s) * aircraft.wing_area_m2
    return q_s * aircraft.cd0 + aircraft.k * aircraft.weight_n**2 / q_s


def stall_speed_m_s(aircraft: Aircraft, density_kg_m3: Any) -> Any:
    """1-g stall speed ``sqrt(2 W / (rho S CL_max))`` in m/s."""
    return sqrt(2.0 * aircraft.weight_n / (density_kg_m3 * aircraft.wing_area_m2 * aircraft.cl_max))


def liftoff_speed_m_s(aircraft: Aircraft, density_kg_m3: Any) -> Any:
    """Lift-off speed in m/s: the given one, else 1.1 x stall speed (Raymer 17.8.2)."""
    if aircraft.takeoff.liftoff_speed_m_s is not None:
        return aircraft.takeoff.liftoff_speed_m_s
    return 1.1 * stall_speed_m_s(aircraft, density_kg_m3)


def minimum_drag_speed_m_s(aircraft: Aircraft, density_kg_m3: Any) -> Any:
    """Airspeed of least level-flight drag, ``sqrt(2W/(rho S) sqrt(k/cd0))`` (Anderson eq. 5.34)."""
    return sqrt(
        2.0
        * aircraft.weight_n
        / (density_kg_m3 * aircraft.wing_area_m2)
        * sqrt(aircraft.k / aircraft.cd0)
    )


def minimum_drag_n(aircraft: Aircraft) -> float:
    """Least level-flight drag ``2 W sqrt(cd0 k)`` in N (independent of density)."""
    return 2.0 * aircraft.weight_n * (aircraft.cd0 * aircraft.k) ** 0.5


def ground_roll_net_force_n(
    aircraft: Aircraft, thrust_n: Any, airspeed_m_s: Any, density_kg_m3: Any
) -> Any:
    """Accelerating force on the ground roll, ``T - D - mu (W - L)`` in N (Raymer eq. 17.97).

    Uses the ground configuration's ``cl_ground`` and, where given, ``cd0_ground``/``k_ground``.
    """
    to = aircraft.takeoff
    cd0 = aircraft.cd0 if to.cd0_ground is None else to.cd0_ground
    k = aircraft.k if to.k_ground is None else to.k_ground
    q_s = dynamic_pressure_pa(density_kg_m3, airspeed_m_s) * aircraft.wing_area_m2
    lift = q_s * to.cl_ground
    drag = q_s * polar_drag_coefficient(to.cl_ground, cd0, k)
    return thrust_n - drag - to.rolling_friction * (aircraft.weight_n - lift)
