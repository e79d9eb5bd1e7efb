"""Minimum-throttle trim over the flight envelope (paper section 4, Fig. 18).

At each airspeed of the envelope grid: the least throttle, equal on all engines,
with total thrust >= level-flight drag (SPEC 3). ``None`` where not attainable:
below stall (x the envelope's ``stall_margin``) or needing more than full throttle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import (
    AttainableRange,
    attainable_range,
    jet_ceiling_m_s,
    jet_ceiling_note,
    least_airspeed_m_s,
    stall_bounded,
    stall_margin_of,
)
from tuflexperf.analysis.cache import BoundedCache, fingerprint
from tuflexperf.analysis.level_flight import (
    LeastThrottleSolver,
    ThrottleSweep,
    airspeed_grid,
    least_throttle_solver,
)
from tuflexperf.analysis.pack_limits import with_packs
from tuflexperf.errors import InputError
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import MAX_AIRSPEED_M_S, level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.thrust import (
    outside_tested_range,
    total_thrust_n,
    unlapsed_density_warning,
)

_cache: BoundedCache[LeastThrottleSolver] = BoundedCache()


def envelope_of(case: Case, density_kg_m3: float | None = None) -> tuple[float, float]:
    """The case's envelope as true airspeeds [m/s] (min, max) at ``density_kg_m3`` (default:
    the case's); trim and OEI need it. Equivalent-airspeed bounds (``_eas``) are converted."""
    envelope = case.requirements.envelope
    if envelope is None:
        raise InputError(
            f"{case.path}: requirements.envelope: missing; trim and OEI need "
            "min_airspeed_m_s and max_airspeed_m_s"
        )
    rho = case.density_kg_m3 if density_kg_m3 is None else density_kg_m3
    low, high = envelope.bounds_m_s(rho)
    if not low < high:  # one bound true, the other equivalent: ordered only at a density
        raise InputError(
            f"{case.path}: requirements.envelope: the least airspeed {low:.2f} m/s is not below "
            f"the greatest {high:.2f} m/s (true airspeeds at {rho:.4f} kg/m^3)"
        )
    if high > MAX_AIRSPEED_M_S:
        raise InputError(
            f"{case.path}: requirements.envelope: max_airspeed_eas_m_s is "
            f"{high:.1f} m/s true at {rho:.4f} kg/m^3, beyond the speed of sound"
        )
    return low, high


def extrapolation_note(case: Case, airspeeds_m_s: np.ndarray) -> tuple[bool, list[str]]:
    """Whether airspeeds leave the thrust model's tested range, and the warning saying so."""
    low, high = case.propulsion.tested_airspeed_m_s
    outside = outside_tested_range(case.propulsion, airspeeds_m_s)
    if not outside.any():
        return False, []
    beyond = airspeeds_m_s[outside]
    return True, [
        f"thrust model extrapolated at {beyond.min():g}-{beyond.max():g} m/s "
        f"(tested {low:g}-{high:g} m/s)"
    ]


def trim_solver(case: Case) -> LeastThrottleSolver:
    """Least-throttle solver for level flight on all engines, built once per case."""
    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3

    def build() -> LeastThrottleSolver:
        def excess(throttle: Any, airspeed: Any) -> Any:
            return total_thrust_n(propulsion, throttle, airspeed, rho) - level_flight_drag_n(
                aircraft, airspeed, rho
            )

        return least_throttle_solver(excess)

    return _cache.get(fingerprint(aircraft, propulsion, rho), build)


@dataclass(frozen=True)
class TrimResult(ThrottleSweep):
    """Least trim throttle per envelope airspeed (NaN where not attainable, with the reason).

    ``least_attainable_airspeed_m_s`` and ``attainable_airspeed_range_m_s`` are exact
    (stall x margin, and the full-throttle roots of thrust = drag), clipped to the envelope.
    """

    stall_speed_m_s: float
    extrapolated: bool
    warnings: tuple[str, ...]
    stall_margin: float = 1.0
    reasons: tuple[str | None, ...] = ()
    attainable: AttainableRange = AttainableRange(None, None)

    @property
    def max_throttle(self) -> float | None:
        """Highest trim throttle over the envelope; ``None`` if some airspeed is unattainable."""
        return float(self.throttle.max()) if self.all_feasible else None

    @property
    def unattainable_airspeed_m_s(self) -> list[float]:
        return [float(v) for v in self.airspeed_m_s[~np.isfinite(self.throttle)]]

    def to_dict(self) -> dict[str, Any]:
        return {
            **self.lists(),
            "min_throttle": self.min_throttle,
            "airspeed_at_min_throttle_m_s": self.airspeed_at_min_throttle_m_s,
            "max_throttle": self.max_throttle,
            "all_feasible": self.all_feasible,
            "unattainable_airspeed_m_s": self.unattainable_airspeed_m_s,
            "not_attainable_reason": list(self.reasons),
            "least_attainable_airspeed_m_s": self.attainable.low,
            "attainable_airspeed_range_m_s": self.attainable.as_list(),
            "level_flight_airspeed_range_m_s": self.attainable.as_list(),  # as OEI's key
            "stall_speed_m_s": self.stall_speed_m_s,
            "stall_margin": self.stall_margin,
            "least_airspeed_m_s": self.stall_margin * self.stall_speed_m_s,
            "extrapolated": self.extrapolated,
            "warnings": list(self.warnings),
        }


def solve_trim(case: Case) -> TrimResult:
    """Least level-flight throttle at every airspeed of the case's envelope grid."""
    v_min, v_max = envelope_of(case)
    speeds = airspeed_grid(v_min, v_max)
    least = least_airspeed_m_s(case)
    throttle, reasons = stall_bounded(speeds, trim_solver(case)(speeds), least, case)
    extrapolated, warnings = extrapolation_note(case, speeds)
    stall = float(stall_speed_m_s(case.aircraft, case.density_kg_m3))
    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3

    def full_throttle_excess(v: np.ndarray) -> np.ndarray:
        thrust = total_thrust_n(propulsion, 1.0, v, rho)
        return thrust - level_flight_drag_n(aircraft, v, rho)

    attainable = attainable_range(full_throttle_excess, least, v_min,
                                  min(v_max, jet_ceiling_m_s(case)))
    warnings.extend(jet_ceiling_note(case, speeds))

    throttle, reasons, attainable, notes = with_packs(case, "trim", speeds, throttle, reasons,
                                                      attainable)
    warnings.extend(notes)
    density_note = unlapsed_density_warning(propulsion, rho)
    if density_note:
        warnings.append(density_note)
    return TrimResult(
        speeds, throttle, stall, extrapolated, tuple(warnings), stall_margin_of(case), reasons,
        attainable,
    )
