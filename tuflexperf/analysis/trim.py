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
from tuflexperf.analysis.level_flight import LevelFlightRows, ThrottleSweep, airspeed_grid
from tuflexperf.analysis.pack_limits import with_packs
from tuflexperf.errors import InputError
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import MAX_AIRSPEED_M_S, level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.thrust import (
    DeadEngineMode,
    outside_tested_range,
    total_thrust_n,
    unlapsed_density_warning,
)


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


def level_flight_rows(case: Case) -> LevelFlightRows:
    """The case as one row of :class:`LevelFlightRows`: the batch's least level-flight
    throttle, which ``--samples``, ``sweep`` and ``margins`` run on many rows."""
    return LevelFlightRows(case.aircraft, case.propulsion, case.density_kg_m3, None, 1,
                           stall_margin_of(case))


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


def level_flight_over(case: Case, rows: LevelFlightRows, grid: np.ndarray, what: str,
                      dead: int | None = None, mode: DeadEngineMode = "windmilling"
                      ) -> tuple[np.ndarray, tuple[str | None, ...], AttainableRange, list[str]]:
    """Level flight over the case's envelope grid, all engines (``dead`` None) or one dead.

    Parameters
    ----------
    rows : LevelFlightRows
        The case as one row (:func:`level_flight_rows`).
    grid : ndarray ``(1, K)``
        The envelope's airspeeds [m/s] (:func:`airspeed_grid`), the same object for every
        dead engine (the engines' thrusts there are computed once).
    what : str
        What the pack notes call it (``trim``, ``OEI (fan 1 dead)``).
    dead, mode
        The inoperative engine and its drag (``windmilling`` or ``zero``).

    Returns
    -------
    throttle, reasons, attainable, notes
        The least throttle per airspeed [fraction] (NaN where not attainable, with the
        reason), the exact attainable range [m/s] and the packs' notes
        (:func:`~tuflexperf.analysis.pack_limits.with_packs`).
    """
    speeds = grid[0]
    least = least_airspeed_m_s(case)
    throttle = rows.least_throttle(grid, dead, mode, rows._grid_terms(grid))[0]
    throttle, reasons = stall_bounded(speeds, throttle, least, case)
    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3

    def full_throttle_excess(v: np.ndarray) -> np.ndarray:
        thrust = total_thrust_n(propulsion, 1.0, v, rho, dead, mode)
        return thrust - level_flight_drag_n(aircraft, v, rho)

    # the grid's ends are the envelope's bounds exactly (airspeed_grid)
    attainable = attainable_range(full_throttle_excess, least, float(speeds[0]),
                                  min(float(speeds[-1]), jet_ceiling_m_s(case)))
    return with_packs(case, what, rows, grid, throttle, reasons, attainable, dead, mode)


def solve_trim(case: Case) -> TrimResult:
    """Least level-flight throttle at every airspeed of the case's envelope grid."""
    speeds = airspeed_grid(*envelope_of(case))
    throttle, reasons, attainable, notes = level_flight_over(
        case, level_flight_rows(case), speeds[None, :], "trim")
    extrapolated, warnings = extrapolation_note(case, speeds)
    warnings.extend(jet_ceiling_note(case, speeds))
    warnings.extend(notes)
    density_note = unlapsed_density_warning(case.propulsion, case.density_kg_m3)
    if density_note:
        warnings.append(density_note)
    stall = float(stall_speed_m_s(case.aircraft, case.density_kg_m3))
    return TrimResult(
        speeds, throttle, stall, extrapolated, tuple(warnings), stall_margin_of(case), reasons,
        attainable,
    )
