"""Fan power and momentum theory: electrical power surface, ideal power, efficiencies, windmilling.

A ducted fan that makes thrust ``T`` at airspeed ``V`` accelerates the air through its jet
area ``A`` to the exit velocity ``v_e`` with ``T = rho A v_e (v_e - V)`` (momentum theory,
actuator disc with the wake at the exit). The least (ideal) power that thrust can cost is
``P_i = T (V + v_e) / 2``; the electrical power ``P_el`` a real fan draws is larger.

Two areas, two keys of the propulsion file (issue 43: one meaning per key):

- ``fan_area_m2``, the fan's **disk** area: the ideal power and figure of merit are taken on
  it (a wake as wide as the disk: the least power any fan of that disk needs, unless its duct
  diffuses; an open rotor's wake contracts, a nozzle's jet is narrower, both need more), and
  the windmilling drag ``C_d q A`` refers to it (a dead fan is a porous disk);
- ``jet_area_m2``, the jet (exit) area: the jet velocity (:func:`jet_area_m2`; without it the
  disk area, a jet no wider than the disk and so the least jet velocity).

So

- the figure of merit ``P_i / P_el`` on the disk area is at most 1 (above 1 the thrust is
  more than the power can make: :mod:`tuflexperf.analysis.plausibility`), and
- the overall efficiency ``T V / P_el`` in flight is the share of electrical power turned
  into useful work (SPEC 3, "thrust and power agree").

The electrical power surface is a poly22 in throttle and airspeed like the thrust
(``q00 + q10 x + q01 v + q20 x^2 + q11 x v + q02 v^2``, W), fitted by ``fit`` from runs that
log ``voltage_v`` and ``current_a``. Every function takes floats, numpy arrays or CasADi
symbols.

References
----------
Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed., sections 2.2-2.8 (momentum
theory, ideal power, figure of merit). Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 3
(drag of a disc/windmilling rotor, ``C_D = D / (q A)``). Paper section 2.1, Table 1
(DS-51-DIA HST: exit velocity 82-98 m/s, power 2.4-4.1 kW, efficiency 70-71 %).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from tuflexperf.models._math import Vectorizable, fmax, fmin, sqrt, where
from tuflexperf.models.power_correction import corrected
from tuflexperf.models.thrust import Engine, Propulsion, density_ratio, engine_thrust_n, poly22

# In-flight overall efficiency below this is implausible for a working fan (SPEC 3).
MIN_OVERALL_EFFICIENCY = 0.2
# A figure of merit above this means the thrust needs more power than is drawn (SPEC 3).
MAX_FIGURE_OF_MERIT = 1.0
# A working point of a fan makes at least this share of its largest thrust: near zero thrust
# the ESC's idle draw and the models' own scatter rule T/P (fit's check, the plausibility rule)
WORKING_THRUST_SHARE = 0.1


def electrical_power_w(
    throttle: Vectorizable, airspeed_m_s: Vectorizable, coefficients: Mapping[str, float]
) -> Vectorizable:
    """Electrical power of one fan from its fitted poly22 power surface.

    Parameters
    ----------
    throttle : float or array or CasADi
        Throttle fraction [-], the variable the surface was fitted against.
    airspeed_m_s : float or array or CasADi
        True airspeed [m/s].
    coefficients : mapping
        ``p00 .. p02`` of the power surface [W, W/(m/s), ...].

    Returns
    -------
    Electrical power [W] (``V I`` at the pack).

    References
    ----------
    SPEC 4, propulsion file ``power: {model: poly22}``; paper section 4 (poly22 form).
    """
    return poly22(throttle, airspeed_m_s, coefficients)


def engine_power_w(
    engine: Engine, throttle: Vectorizable, airspeed_m_s: Vectorizable
) -> Vectorizable:
    """Electrical power [W] of ``engine`` from its fitted power surface (``None`` if none).

    Parameters
    ----------
    engine : Engine
        The fan; its surface shares the thrust's throttle variable (``throttle_scale``).
    throttle : float or array or CasADi
        Throttle fraction [-].
    airspeed_m_s : float or array or CasADi
        True airspeed [m/s].

    Returns
    -------
    The surface's power [W], times the engine's ``power_correction`` where it has one (the
    measured power of the discharge runs: :mod:`tuflexperf.models.power_correction`).

    References
    ----------
    SPEC 4 (``power: {model: poly22}``); issue 43 item 2.
    """
    if engine.power_coefficients is None:
        return None
    surface = electrical_power_w(
        throttle * engine.throttle_scale, airspeed_m_s, engine.power_coefficients
    )
    return corrected(surface, engine.power_correction, throttle, airspeed_m_s)


def exit_velocity_m_s(
    thrust_n: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
    area_m2: Vectorizable,
) -> Vectorizable:
    """Jet exit velocity of a fan making ``thrust_n``: the root of ``T = rho A v_e (v_e - V)``.

    Parameters
    ----------
    thrust_n : float or array or CasADi
        Thrust of the fan [N]; a drag (``T <= 0``) gives ``v_e = V`` (no jet).
    airspeed_m_s : float or array or CasADi
        Free-stream airspeed ``V`` [m/s].
    density_kg_m3 : float or array or CasADi
        Air density [kg/m^3].
    area_m2 : float
        Jet area ``A`` [m^2] (:func:`jet_area_m2`; the disk area for the ideal power).

    Returns
    -------
    ``v_e = (V + sqrt(V^2 + 4 T / (rho A))) / 2`` [m/s].

    References
    ----------
    Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.10-2.14 (momentum theory in
    axial flight).
    """
    t = fmax(thrust_n, 0.0)
    return 0.5 * (
        airspeed_m_s + sqrt(airspeed_m_s * airspeed_m_s + 4.0 * t / (density_kg_m3 * area_m2))
    )


def jet_area_m2(propulsion: Propulsion) -> float | None:
    """The area the jet velocity is taken on [m^2]: ``jet_area_m2``, else the disk area
    ``fan_area_m2`` (a jet no wider than the disk: the least jet velocity, the lower airspeed
    bound of :func:`beyond_jet_velocity`); ``None`` without either.

    References
    ----------
    Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.14 (the exit area fixes a ducted
    fan's wake).
    """
    return propulsion.jet_area_m2 if propulsion.jet_area_m2 is not None else propulsion.fan_area_m2


def static_jet_velocity_m_s(propulsion: Propulsion, density_kg_m3: Vectorizable) -> Vectorizable:
    """The least jet velocity of the engines at full throttle at rest [m/s] (momentum theory).

    A fixed-pitch fan's jet velocity stays near its static value as the airspeed rises, so
    its thrust ``rho A v_j (v_j - V)`` falls to nothing as ``V`` reaches ``v_j``: beyond it
    a thrust model extrapolated from lower airspeeds has no physics behind it (the paper's
    DS-51 data, 0-30 m/s, follow this line to within ~7 %). ``inf`` without the
    propulsion's ``jet_area_m2`` or ``fan_area_m2`` (:func:`jet_area_m2`).

    Parameters
    ----------
    propulsion : Propulsion
        The engines (their coefficients may be arrays of samples) and the areas.
    density_kg_m3 : float or array
        Air density [kg/m^3] (the static thrust scales with it as the model says).

    Returns
    -------
    ``min_i sqrt(T0_i / (rho A))`` [m/s], ``T0_i`` engine ``i``'s full-throttle static thrust.

    References
    ----------
    Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.14 (hover: ``v = sqrt(T/(rho A))``
    across the far wake for a ducted fan, whose exit area fixes the contraction).
    """
    area = jet_area_m2(propulsion)
    if area is None:
        return float("inf")
    scale = density_ratio(propulsion, density_kg_m3)
    speeds = [exit_velocity_m_s(engine_thrust_n(engine, 1.0, 0.0, scale), 0.0, density_kg_m3,
                                area) for engine in propulsion.engines]
    least = speeds[0]
    for speed in speeds[1:]:
        least = fmin(least, speed)
    return least


def beyond_jet_velocity(propulsion: Propulsion, airspeed_m_s: Any, density_kg_m3: Any) -> Any:
    """True where the airspeed is past the thrust model's tested range and at or beyond the
    fans' static jet velocity (:func:`static_jet_velocity_m_s`): no thrust a fan makes,
    whatever the extrapolated polynomial gives (floats or numpy arrays, broadcast).

    The one rule for every analysis: the take-off's lift-off, the trim and OEI grid
    airspeeds, the endurance cruise and climb, a mission's flown airspeeds, and the
    point-performance scans (:func:`jet_velocity_ceiling_m_s`).
    """
    import numpy as np

    v = np.asarray(airspeed_m_s, dtype=float)
    jet = np.asarray(static_jet_velocity_m_s(propulsion, density_kg_m3), dtype=float)
    return (v > propulsion.tested_airspeed_m_s[1] + 1e-9) & (v >= jet)


def jet_velocity_ceiling_m_s(propulsion: Propulsion, density_kg_m3: Vectorizable) -> Vectorizable:
    """The airspeed [m/s] from which :func:`beyond_jet_velocity` holds: the fans' static jet
    velocity, never below the top tested airspeed (up to there the model is measured, not
    extrapolated); ``inf`` without an area (:func:`jet_area_m2`).

    Parameters
    ----------
    propulsion : Propulsion
        The engines and their areas.
    density_kg_m3 : float or array
        Air density [kg/m^3].

    Returns
    -------
    ``max(v_j, V_tested_max)`` [m/s].

    References
    ----------
    Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.14; paper section 4 (tested
    0-30 m/s).
    """
    return fmax(static_jet_velocity_m_s(propulsion, density_kg_m3),
                float(propulsion.tested_airspeed_m_s[1]))


def ideal_power_w(
    thrust_n: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
    area_m2: Vectorizable,
) -> Vectorizable:
    """Momentum-theory (ideal) power of a fan: ``P_i = T (V + v_e) / 2``.

    Parameters
    ----------
    thrust_n : float or array or CasADi
        Thrust [N]; no ideal power for a drag (``T <= 0`` gives 0).
    airspeed_m_s : float or array or CasADi
        Airspeed [m/s].
    density_kg_m3 : float or array or CasADi
        Air density [kg/m^3].
    area_m2 : float
        Area of the wake [m^2]: the disk area ``fan_area_m2`` for the least power any fan of
        that disk needs (the figure of merit, the plausibility rule).

    Returns
    -------
    Ideal power [W]: the least power any fan whose wake is ``area_m2`` wide needs for that thrust.

    References
    ----------
    Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.15 (``P = T (V + v_i)``,
    ``v_e = V + 2 v_i``).
    """
    t = fmax(thrust_n, 0.0)
    return t * (airspeed_m_s + exit_velocity_m_s(t, airspeed_m_s, density_kg_m3, area_m2)) / 2.0


def figure_of_merit(
    thrust_n: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
    area_m2: Vectorizable,
    power_w: Vectorizable,
) -> Vectorizable:
    """Ideal over electrical power, ``P_i / P_el`` [-]; above 1 the power cannot make the thrust.

    ``nan`` where the electrical power is not positive.

    References
    ----------
    Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.41 (figure of merit), extended
    to axial flight with the momentum-theory ideal power.
    """
    ideal = ideal_power_w(thrust_n, airspeed_m_s, density_kg_m3, area_m2)
    return where(power_w > 0.0, ideal / where(power_w > 0.0, power_w, 1.0), float("nan"))


def overall_efficiency(
    thrust_n: Vectorizable, airspeed_m_s: Vectorizable, power_w: Vectorizable
) -> Vectorizable:
    """Useful over electrical power in flight, ``T V / P_el`` [-] (``nan`` if ``P_el <= 0``).

    References
    ----------
    McCormick, *Aerodynamics, Aeronautics and Flight Mechanics*, 2nd ed., 6.2 (propulsive
    efficiency ``T V / P``).
    """
    return where(
        power_w > 0.0, thrust_n * airspeed_m_s / where(power_w > 0.0, power_w, 1.0), float("nan")
    )


def windmilling_drag_n(
    drag_coefficient: float, airspeed_m_s: Vectorizable, density_kg_m3: Vectorizable, area_m2: float
) -> Vectorizable:
    """A dead fan's contribution to thrust: ``-C_d,wm q A_fan`` [N], always a drag.

    Parameters
    ----------
    drag_coefficient : float
        ``C_d,wm`` on the fan area [-] (``fit`` estimates it from the idle points).
    airspeed_m_s : float or array or CasADi
        Airspeed [m/s].
    density_kg_m3 : float or array or CasADi
        Air density [kg/m^3].
    area_m2 : float
        The propulsion file's ``fan_area_m2``, the fan's disk area [m^2].

    References
    ----------
    SPEC 3 (windmilling drag); Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 3 (disc drag on
    its frontal area).
    """
    return -abs(drag_coefficient) * 0.5 * density_kg_m3 * airspeed_m_s * airspeed_m_s * area_m2


@dataclass(frozen=True)
class PowerSurfaces:
    """Per-fan electrical power from the propulsion file's power surfaces (all engines).

    ``electrical_power_w`` is the largest engine's power at the throttle and airspeed (the
    fan that empties its packs first sets the endurance), scaled by ``rho / rho_ref`` like
    the thrust (at a fixed rpm a fan's thrust and power both go with density).
    """

    engines: tuple[Engine, ...]
    density_scale: float = 1.0

    def electrical_power_w(
        self, throttle: Vectorizable, airspeed_m_s: Vectorizable
    ) -> Vectorizable:
        """Per-fan electrical power [W] at ``throttle`` [-] and true airspeed [m/s].

        References
        ----------
        SPEC 4 (``power: {model: poly22}``); SPEC 3 (thrust and density).
        """
        power: Vectorizable = None
        for engine in self.engines:
            p = engine_power_w(engine, throttle, airspeed_m_s)
            power = p if power is None else fmax(power, p)
        return self.density_scale * power

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": "propulsion power surfaces (poly22 per engine, the largest per fan)",
            "density_scale": self.density_scale,
            "engines": {e.name: dict(e.power_coefficients or {}) for e in self.engines},
            **({"power_correction": self.engines[0].power_correction.to_dict()}
               if self.engines and self.engines[0].power_correction is not None else {}),
        }


def power_surfaces(propulsion: Propulsion, density_kg_m3: float) -> PowerSurfaces | None:
    """The propulsion's power surfaces as one per-fan power model, or ``None`` if any is missing.

    References
    ----------
    SPEC 4 (propulsion file, ``power``).
    """
    if not propulsion.engines or any(e.power_coefficients is None for e in propulsion.engines):
        return None
    return PowerSurfaces(propulsion.engines, float(density_ratio(propulsion, density_kg_m3)))
