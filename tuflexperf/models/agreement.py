"""Do thrust and electrical power agree? (SPEC 3, "thrust and power agree or the output says so").

Wherever an analysis knows both a fan's thrust and its electrical power at a point, it
carries the momentum-theory ideal power, the figure of merit and (in flight) the overall
efficiency of :mod:`tuflexperf.models.powertrain`, and a warning naming the point when

- the figure of merit exceeds 1 (the thrust needs more power than is drawn), or
- the in-flight overall efficiency ``T V / P_el`` is below 0.2 (the power is several times
  what the thrust needs: a thrust or a power model is wrong).

References
----------
Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed., 2.2-2.8 (momentum theory,
figure of merit); McCormick, *Aerodynamics, Aeronautics and Flight Mechanics*, 6.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from tuflexperf.models.powertrain import (
    MAX_FIGURE_OF_MERIT,
    MIN_OVERALL_EFFICIENCY,
    engine_power_w,
    exit_velocity_m_s,
    figure_of_merit,
    ideal_power_w,
    overall_efficiency,
)
from tuflexperf.models.thrust import Propulsion, density_ratio, engine_thrust_n

# Airspeeds below this are "static" (no overall efficiency: T V / P is 0 by definition).
STATIC_AIRSPEED_M_S = 0.5


@dataclass(frozen=True)
class PowerAgreement:
    """Thrust against electrical power at one point of one fan (SI units)."""

    label: str
    engine: str
    throttle: float
    airspeed_m_s: float
    thrust_n: float
    electrical_power_w: float
    ideal_power_w: float | None
    exit_velocity_m_s: float | None
    figure_of_merit: float | None
    overall_efficiency: float | None
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__, warnings=list(self.warnings))


def _finite(value: Any) -> float | None:
    number = float(value)
    return number if math.isfinite(number) else None


def power_agreement(
    label: str,
    engine: str,
    throttle: float,
    airspeed_m_s: float,
    thrust_n: float,
    electrical_power_w: float,
    density_kg_m3: float,
    fan_area_m2: float | None,
    warn_efficiency: bool = True,
    jet_area_m2: float | None = None,
) -> PowerAgreement:
    """Ideal power, figure of merit and overall efficiency at one point, with warnings.

    Parameters
    ----------
    label : str
        Names the point in warnings (e.g. ``"endurance at throttle 0.50"``).
    engine : str
        The fan's name.
    throttle : float
        Throttle fraction [-].
    airspeed_m_s : float
        True airspeed [m/s].
    thrust_n : float
        The fan's thrust [N] (density-scaled as the analysis uses it).
    electrical_power_w : float
        The fan's electrical power [W].
    density_kg_m3 : float
        Air density [kg/m^3].
    fan_area_m2 : float or None
        The fan's disk area [m^2]: the ideal power and figure of merit are taken on it (the
        least power of any fan of that disk); without it neither.
    warn_efficiency : bool
        Warn on an overall efficiency below 0.2 (flight points). Tunnel test points pass
        False: at low airspeed and high thrust a sound fan's ``T V / P_el`` is that low by
        momentum theory (jet far faster than the stream), so there the figure of merit
        is the check.
    jet_area_m2 : float or None
        The jet (exit) area [m^2] the exit velocity is taken on; None: the disk area's.

    Returns
    -------
    PowerAgreement

    References
    ----------
    SPEC 3; Leishman, *Principles of Helicopter Aerodynamics*, eq. 2.15 and 2.41.
    """
    warnings: list[str] = []
    where = (
        f"{label}: {engine} at throttle {throttle:.2f}, {airspeed_m_s:.1f} m/s "
        f"({thrust_n:.1f} N, {electrical_power_w:.0f} W)"
    )
    if not electrical_power_w > 0:
        warnings.append(f"{where}: the power model gives no positive electrical power")
        return PowerAgreement(label, engine, throttle, airspeed_m_s, thrust_n,
                              electrical_power_w, None, None, None, None, tuple(warnings))
    ideal = exit = merit = None
    if fan_area_m2 is not None and thrust_n > 0:
        ideal = _finite(ideal_power_w(thrust_n, airspeed_m_s, density_kg_m3, fan_area_m2))
        jet = jet_area_m2 if jet_area_m2 is not None else fan_area_m2
        exit = _finite(exit_velocity_m_s(thrust_n, airspeed_m_s, density_kg_m3, jet))
        merit = _finite(figure_of_merit(thrust_n, airspeed_m_s, density_kg_m3, fan_area_m2,
                                        electrical_power_w))
        if merit is not None and merit > MAX_FIGURE_OF_MERIT:
            warnings.append(
                f"{where}: figure of merit {merit:.2f} above 1 - the thrust needs at least "
                f"{ideal:.0f} W (momentum theory), more than the power model's"
            )
    efficiency = None
    if airspeed_m_s > STATIC_AIRSPEED_M_S:
        efficiency = _finite(overall_efficiency(thrust_n, airspeed_m_s, electrical_power_w))
        if warn_efficiency and efficiency is not None and efficiency < MIN_OVERALL_EFFICIENCY:
            warnings.append(
                f"{where}: overall efficiency T V / P_el = {efficiency:.2f}, below "
                f"{MIN_OVERALL_EFFICIENCY:g} - thrust and power models disagree"
            )
    return PowerAgreement(label, engine, throttle, airspeed_m_s, thrust_n, electrical_power_w,
                          ideal, exit, merit, efficiency, tuple(warnings))


def agreement_at(
    label: str,
    propulsion: Propulsion,
    throttle: float,
    airspeed_m_s: float,
    density_kg_m3: float,
    power_w: float | None = None,
) -> tuple[PowerAgreement, ...]:
    """:func:`power_agreement` for every engine of ``propulsion`` at one operating point.

    The power is the engine's own power surface (scaled by ``rho / rho_ref`` like the
    thrust), else ``power_w`` (a per-fan power from elsewhere, e.g. the battery file's
    fan-power law); engines with neither are skipped.

    References
    ----------
    SPEC 3 ("thrust and power agree").
    """
    scale = density_ratio(propulsion, density_kg_m3)
    out = []
    for engine in propulsion.engines:
        surface = engine_power_w(engine, throttle, airspeed_m_s)
        # a fitted surface holds at the test day's density: scaled like the thrust
        power = scale * surface if surface is not None else power_w
        if power is None:
            continue
        thrust = float(engine_thrust_n(engine, throttle, airspeed_m_s, scale))
        out.append(power_agreement(label, engine.name, throttle, airspeed_m_s, thrust,
                                   float(power), density_kg_m3, propulsion.fan_area_m2,
                                   jet_area_m2=propulsion.jet_area_m2))
    return tuple(out)
