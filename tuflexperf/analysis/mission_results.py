"""A flown mission's results: per segment and the whole flight (SI units; SPEC 5 JSON keys)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class SegmentResult:
    """One flown segment (SI units; per-engine lists in the propulsion file's order)."""

    index: int
    type: str
    time_s: float
    distance_m: float
    start_altitude_m: float
    end_altitude_m: float
    airspeed_eas_m_s: float | None
    charge_ah: tuple[float, ...]
    energy_wh: tuple[float, ...]
    min_voltage_v: float
    max_throttle: float | None
    dead_engine: str | None

    @property
    def throttle_margin(self) -> float | None:
        """Least ``1 - throttle`` over the segment (``None`` where no engine runs)."""
        return None if self.max_throttle is None else 1.0 - self.max_throttle

    def to_dict(self) -> dict[str, Any]:
        return {
            "type": self.type,
            "index": self.index,
            "time_s": self.time_s,
            "time_min": self.time_s / 60.0,
            "distance_m": self.distance_m,
            "start_altitude_m": self.start_altitude_m,
            "altitude_m": self.end_altitude_m,
            "airspeed_eas_m_s": self.airspeed_eas_m_s,
            "charge_ah": sum(self.charge_ah),
            "charge_ah_per_engine": list(self.charge_ah),
            "energy_wh": sum(self.energy_wh),
            "energy_wh_per_engine": list(self.energy_wh),
            "min_voltage_v": self.min_voltage_v,
            "max_throttle": self.max_throttle,
            "min_throttle_margin": self.throttle_margin,
            "dead_engine": self.dead_engine,
        }


@dataclass(frozen=True)
class MissionResult:
    """A flown mission: per-segment results, the landing charge and the time history.

    ``history`` (one value per integration node, in time order; a flight that ended early
    stops at its event) holds ``time_s`` [s], ``segment`` (index into ``segments``),
    ``altitude_m`` [m above the field], ``distance_m`` [m flown], ``airspeed_m_s`` (true)
    and ``airspeed_eas_m_s`` [m/s], ``throttle`` [-], ``climb_rate_m_s`` [m/s], and per
    engine ``current_a_<name>`` [A], ``voltage_v_<name>`` (loaded, [V]),
    ``charge_ah_<name>`` (drawn, [Ah]), ``charge_fraction_<name>`` (left, [-]),
    ``power_w_<name>`` [W] and ``energy_wh_<name>`` (drawn, [Wh]). A dead engine's current
    and power are 0, its voltage the open-circuit value.
    """

    name: str
    segments: tuple[SegmentResult, ...]
    landing_charge_fraction: float
    min_landing_charge_fraction: float
    attainable: bool
    reason: str
    engines: tuple[str, ...]
    history: dict[str, np.ndarray] = field(repr=False)
    solved: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()
    # when the flight ended early (cut-off, not attainable): the time of that event [s]
    ended_at_s: float | None = None
    # the packs' cut-off voltage [V] flown to (a --set of it, not the battery file's)
    cutoff_voltage_v: float | None = None
    # a catapult's m V^2 / 2 at release [Wh]: energy the flight starts with that no pack gave
    # (a runway take-off draws its own from the packs, in the take-off segment's energy)
    launch_kinetic_energy_wh: float = 0.0

    @property
    def passed(self) -> bool:
        """Every verdict of the flight holds (:func:`~tuflexperf.analysis.requirements.
        mission_verdicts`: the landing charge, and with ``solve_for`` the file's own time)."""
        from tuflexperf.analysis.verdict import mission_verdicts

        return all(v.passed for v in mission_verdicts(self))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mission": self.name,
            "passed": self.passed,
            "attainable": self.attainable,
            "reason": self.reason,
            "landing_charge_fraction": self.landing_charge_fraction,
            "min_landing_charge_fraction": self.min_landing_charge_fraction,
            "total_time_min": float(self.history["time_s"][-1]) / 60.0,
            "packs_energy_wh": float(sum(sum(s.energy_wh) for s in self.segments)),
            "launch_kinetic_energy_wh": self.launch_kinetic_energy_wh,
            "energy_wh": float(sum(sum(s.energy_wh) for s in self.segments))
            + self.launch_kinetic_energy_wh,
            "engines": list(self.engines),
            "segments": [s.to_dict() for s in self.segments],
            "warnings": list(self.warnings),
        }
        if self.solved is not None:
            out["solved"] = self.solved
        if self.ended_at_s is not None:
            out["ended_at_s"] = self.ended_at_s
        return out


AIRBORNE_AT_END_M = 1.0
"""A mission that ends this high above the field [m] or more has not landed."""


def _said_if_airborne(flown: MissionResult) -> MissionResult:
    """A mission whose last segment ends in the air says that its descent and landing are
    not flown: the charge it 'lands' with is the one up there (a take-off and a climb to
    100 m 'landed with 93.4 %' and PASSed, unsaid; outside audit)."""
    import dataclasses

    height = np.asarray(flown.history.get("altitude_m", ()), dtype=float)
    if not flown.attainable or height.size == 0 or not height[-1] >= AIRBORNE_AT_END_M:
        return flown
    note = (f"mission {flown.name!r} ends {height[-1]:.0f} m above the field: its descent and "
            "landing are not flown, the landing charge is the one at the last segment's end "
            "(add {type: descent, to_altitude_m: 0, ...} to fly them)")
    return dataclasses.replace(flown, warnings=(*flown.warnings, note))
