"""Can the data be physical at all? One rule, applied by every command (issue 43 item 3).

:func:`implausible` scans the operating range once per case (throttle 0..1 x airspeeds from
0 to the envelope's top, at the case's density) and returns what physics forbids:

- **figure of merit above 1**: at a working point of a fan (thrust at least a tenth of its
  static thrust: nearer zero the idle draw and the models' scatter rule the ratio), its
  electrical power below the least power momentum theory needs for its thrust (the ideal
  power on the fan's disk area ``fan_area_m2``, the wake as wide as the disk:
  :func:`tuflexperf.models.powertrain.figure_of_merit`). The power is the
  propulsion file's power surface; an engine without one is flown on the battery file's
  fan-power law, and then the same inequality read from the thrust side says the thrust
  model gives more thrust than momentum theory allows for that power. Either way thrust and
  power cannot both hold: one is wrong, and every requirement flies the thrust, those on
  the packs the power too, so no verdict may PASS on them. A thrust with no positive power
  at all is the limit of the same rule.
- **battery beyond its rated C**: at the highest power any requirement flies (full throttle,
  the worst airspeed of the range: the take-off, a climb), the packs on full charge (their
  highest voltage, so the least current that power can cost) would draw more than their
  burst rating ``2 x max_discharge_c x capacity_ah`` per pack (the rule the take-off's packs
  are judged by: seconds at full throttle), or cannot deliver the power at all. The
  continuous rating over a flight is the analyses' own (pack_limits, the mission).

Each :class:`Implausibility` names the requirement blocks it bears on and carries a one-line
reason naming the file, the key and the worst point; the registry makes those requirements
FAIL with it (:mod:`tuflexperf.analysis.requirements`), the single-analysis commands exit 1
with it. numpy only: ``check`` imports no plotting or fitting library for it.

References
----------
Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed., eq. 2.14-2.15 and 2.41 (momentum
theory, ideal power, figure of merit); Tremblay & Dessaint (2009) (the pack circuit).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.constants import BURST_OVER_CONTINUOUS
from tuflexperf.io.case import Case
from tuflexperf.models.powertrain import (
    MAX_FIGURE_OF_MERIT,
    WORKING_THRUST_SHARE,
    beyond_jet_velocity,
    engine_power_w,
    figure_of_merit,
    ideal_power_w,
)
from tuflexperf.models.thrust import density_ratio, engine_thrust_n

# The requirement blocks of a case (analysis/requirements.py CHECKS, in SPEC order); the
# ``mission`` command's mission file is the mission block's.
BLOCKS = ("takeoff", "envelope", "oei", "endurance", "mission")
# Grid of the scan: throttle steps of 1/40, airspeed steps of at most 0.5 m/s.
_THROTTLES = 41
_AIRSPEED_STEP_M_S = 0.5
# A figure of merit this much above 1 is beyond rounding of the fitted coefficients.
_MERIT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Implausibility:
    """One thing the case's data claim that physics forbids (SI units).

    ``rule`` is ``"figure_of_merit"`` (the power surface below momentum theory's least
    power), ``"thrust_momentum"`` (the thrust model above what momentum theory allows for
    the battery file's fan power) or ``"battery_rating"`` (the packs beyond their rated C).
    ``value`` is the worst figure of merit, or the worst current over the rating [-].
    """

    rule: str
    blocks: tuple[str, ...]
    reason: str
    engine: str | None
    throttle: float
    airspeed_m_s: float
    value: float

    def to_dict(self) -> dict[str, Any]:
        return {"rule": self.rule, "blocks": list(self.blocks), "reason": self.reason,
                "engine": self.engine, "throttle": self.throttle,
                "airspeed_m_s": self.airspeed_m_s, "value": self.value}


def operating_airspeeds_m_s(case: Case) -> np.ndarray:
    """Airspeeds [m/s] of the scan: 0 to the envelope's top true airspeed at the case's
    density (without an envelope, the thrust model's tested top), at most 0.5 m/s apart."""
    top = float(case.propulsion.tested_airspeed_m_s[1])
    envelope = case.requirements.envelope
    if envelope is not None:
        bounds = envelope.bounds_m_s(case.density_kg_m3)
        if bounds is not None:
            top = max(top, float(bounds[1]))
    return np.linspace(0.0, top, max(int(np.ceil(top / _AIRSPEED_STEP_M_S)), 1) + 1)


def implausible(case: Case) -> tuple[Implausibility, ...]:
    """Everything the case's propulsion and battery data claim that physics forbids.

    Parameters
    ----------
    case : Case
        The validated case; its battery file (if any) is read through the cached
        characterisation the analyses share.

    Returns
    -------
    tuple of Implausibility
        Empty when the data are plausible over the whole operating range.

    References
    ----------
    Leishman, eq. 2.15 and 2.41; SPEC 3 ("thrust and power agree", "beyond the battery").
    """
    side = _pack_side(case)
    found = list(_momentum(case, side))
    if side is not None:
        found.extend(_rating(case, side))
    return tuple(found)


def _pack_side(case: Case) -> Any:
    if case.battery_path is None:
        return None
    from tuflexperf.analysis.pack_limits import pack_side

    return pack_side(case)


def _grid(case: Case) -> tuple[np.ndarray, np.ndarray]:
    x, v = np.meshgrid(np.linspace(0.0, 1.0, _THROTTLES), operating_airspeeds_m_s(case),
                       indexing="ij")
    return x, v


def _momentum(case: Case, side: Any) -> list[Implausibility]:
    """Per engine: the worst figure of merit on the disk area over the grid, if above 1."""
    prop = case.propulsion
    if prop.fan_area_m2 is None:
        return []
    rho = case.density_kg_m3
    scale = density_ratio(prop, rho)
    x, v = _grid(case)
    blocks = BLOCKS  # every requirement flies the thrust, and on the packs the power
    # the power the analyses fly: every engine's surface, else (one missing) the battery
    # file's fan-power law for all (pack_limits.pack_side); without packs, what is given
    surfaces = all(e.power_coefficients is not None for e in prop.engines) or side is None
    out = []
    for index, engine in enumerate(prop.engines):
        surface = engine_power_w(engine, x, v) if surfaces else None
        if surface is not None:
            power = scale * np.asarray(surface, dtype=float)
            rule, key = "figure_of_merit", f"engines[{index}] ({engine.name}).power"
        elif side is not None:
            power = np.asarray(side.power.electrical_power_w(x, v), dtype=float) * np.ones_like(x)
            rule, key = "thrust_momentum", f"engines[{index}] ({engine.name}).coefficients"
        else:
            continue
        thrust = np.asarray(engine_thrust_n(engine, x, v, scale), dtype=float) * np.ones_like(x)
        # past the fans' jet velocity every analysis takes no thrust (beyond_jet_velocity)
        thrust = np.where(beyond_jet_velocity(prop, v, rho), 0.0, thrust)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            merit = np.asarray(figure_of_merit(thrust, v, rho, prop.fan_area_m2, power),
                               dtype=float)
        # the fan's working points: near zero thrust the idle draw and the models' scatter
        # rule the ratio (0.1 N "needing" 6 W of a surface at 1 W is no evidence)
        static = float(engine_thrust_n(engine, 1.0, 0.0, scale))
        working = thrust >= WORKING_THRUST_SHARE * static
        # there, thrust with no positive power: no fan makes it (the rule's limit, merit inf)
        merit = np.where(working & ~(power > 0.0), np.inf,
                         np.where(working, np.nan_to_num(merit, nan=0.0), 0.0))
        worst = np.unravel_index(int(np.argmax(merit)), merit.shape)
        value = float(merit[worst])
        if not value > MAX_FIGURE_OF_MERIT + _MERIT_TOLERANCE:
            continue
        xw, vw, tw, pw = (float(a[worst]) for a in (x, v, thrust, power))
        ideal = float(ideal_power_w(tw, vw, rho, prop.fan_area_m2))
        merit_text = "no positive power" if not np.isfinite(value) else \
            f"figure of merit {value:.2f} > 1"
        if rule == "figure_of_merit":
            what = (f"power surface gives {pw:.0f} W where its thrust model's {tw:.1f} N needs at "
                    f"least {ideal:.0f} W by momentum theory")
        else:
            what = (f"thrust {tw:.1f} N is more than momentum theory allows for the battery "
                    f"file's fan power {pw:.0f} W (it needs at least {ideal:.0f} W)")
        out.append(Implausibility(
            rule, blocks,
            f"implausible data: {case.propulsion_path}: {key}: {merit_text} at throttle {xw:.2f}, "
            f"{vw:.1f} m/s: the {what} on fan_area_m2 {prop.fan_area_m2:g} m^2 (the disk): "
            "thrust and power cannot both hold",
            engine.name, xw, vw, value))
    return out


def full_throttle_draw(case: Case, side: Any, capacity_ah: Any
                       ) -> list[tuple[float, float, np.ndarray, np.ndarray]]:
    """Per engine: its highest full-throttle power over the range [W] and where [m/s], and
    the current per pack [A] and loaded voltage [V] (NaN: beyond the packs' power) of packs of
    ``capacity_ah`` [Ah] (float or rows) on full charge drawing it (the least current that
    power can cost: the highest voltage). One kernel for the single case and the batch."""
    from tuflexperf.analysis.pack_limits import fan_power_w, operating_point
    from tuflexperf.models.battery import equivalent_packs

    battery = side.battery
    capacity = np.asarray(capacity_ah, dtype=float)
    circuit = np.asarray(equivalent_packs(battery.packs_in_parallel_per_engine, capacity,
                                          battery.as_read.capacity_ah), dtype=float)
    v = operating_airspeeds_m_s(case)
    out = []
    for index in range(len(case.propulsion.engines)):
        power = np.asarray(fan_power_w(side, case, index, 1.0, v), dtype=float) * np.ones_like(v)
        at = int(np.argmax(power))
        u, current, _ = operating_point(side.params, 0.0, float(power[at]), circuit,
                                        battery.packs_in_parallel_per_engine,
                                        case.propulsion.reference_voltage_v,
                                        case.propulsion.voltage_exponent)
        out.append((float(power[at]), float(v[at]), np.asarray(current, dtype=float),
                    np.asarray(u, dtype=float)))
    return out


def beyond_rating(battery: Any, capacity_ah: Any, current_a: Any, voltage_v: Any) -> Any:
    """True where the current per pack [A] exceeds the burst rating ``BURST_OVER_CONTINUOUS x
    max_discharge_c x capacity_ah`` or the packs cannot deliver the power (NaN voltage);
    arrays broadcast. The burst: a full-throttle take-off lasts seconds, and the analyses'
    own rules (pack_limits, the mission) allow it there; beyond it nothing can fly."""
    rating = _burst_a(battery, capacity_ah)
    with np.errstate(invalid="ignore"):
        return ~np.isfinite(voltage_v) | (current_a > rating * (1.0 + 1e-9))


def _burst_a(battery: Any, capacity_ah: Any) -> Any:
    """A pack's burst rating [A]: twice the continuous ``max_discharge_c x capacity_ah``."""
    return BURST_OVER_CONTINUOUS * float(battery.max_discharge_c) * np.asarray(capacity_ah,
                                                                                 dtype=float)


def _rating(case: Case, side: Any) -> list[Implausibility]:
    """The packs on full charge at each engine's highest full-throttle power of the range."""
    battery = side.battery
    if battery.max_discharge_c is None:
        return []
    rating = float(_burst_a(battery, battery.capacity_ah))
    out = []
    draws = full_throttle_draw(case, side, battery.capacity_ah)
    for engine, (power, speed, current, u) in zip(case.propulsion.engines, draws, strict=True):
        amps, volts = float(current), float(u)
        if not bool(beyond_rating(battery, battery.capacity_ah, amps, volts)):
            continue
        draw = (f"{amps:.1f} A per pack at {volts:.1f} V" if np.isfinite(volts) else
                "more than the packs can deliver (no loaded voltage)")
        out.append(Implausibility(
            "battery_rating", BLOCKS,  # every requirement flies on the packs
            f"implausible data: {case.battery_path}: max_discharge_c x capacity_ah: "
            f"{engine.name} at full throttle, {speed:.1f} m/s, draws {power:.0f} W: {draw} on "
            f"full packs, beyond the battery's burst rating {BURST_OVER_CONTINUOUS:g} x "
            f"{battery.max_discharge_c:g} C x {battery.capacity_ah:g} Ah = {rating:.0f} A",
            engine.name, 1.0, speed, amps / rating if np.isfinite(volts) else float("inf")))
    return out


def rating_rows(case: Case, side: Any, capacity_ah: Any) -> np.ndarray:
    """Per row of ``capacity_ah`` [Ah]: True where :func:`_rating`'s rule finds the packs
    beyond their rated C (the batch's rows that vary the capacity; the nominal density)."""
    capacity = np.asarray(capacity_ah, dtype=float)
    if side is None or side.battery.max_discharge_c is None:
        return np.zeros(capacity.shape, dtype=bool)
    found = np.zeros(capacity.shape, dtype=bool)
    for _, _, current, u in full_throttle_draw(case, side, capacity):
        found |= np.asarray(beyond_rating(side.battery, capacity, current, u), dtype=bool)
    return found
