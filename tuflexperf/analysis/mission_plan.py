"""A mission's static plan: each segment's kind, heights, settings, checked at build time.

Segments below stall, climbs that do not climb, a throttle with no level flight, a second
engine failure: refused here, before anything is flown (SPEC 3, SPEC 4 "Mission file").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.mission import SegmentSchema
from tuflexperf.models.aircraft import (
    MAX_AIRSPEED_M_S,
    level_flight_drag_n,
    stall_speed_eas_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.powertrain import (
    jet_velocity_ceiling_m_s,
)
from tuflexperf.models.thrust import (
    least_throttle_reaching,
    total_thrust_n,
)


@dataclass(frozen=True)
class _Plan:
    """A segment's static data, fixed at build time."""

    index: int
    type: str
    kind: str  # "time", "height", "takeoff" or "event"
    start_h: float
    end_h: float
    eas: float | None
    solve_x: bool
    throttle: float
    rate: float  # commanded rate of climb [m/s] (negative: descent)
    rate_from_excess: bool
    duration_s: float
    dead: int | None
    solve_v: bool = False  # level at a fixed throttle: the airspeed is solved
    v_guess: float = 0.0  # true airspeed [m/s] of that level flight with full packs


class MissionPlanning:
    """The plan of :class:`tuflexperf.analysis.mission.MissionModel` (a mixin)."""

    case: Any
    mission: Any
    engines: tuple[str, ...]
    n: int

    def _plan(self, segments: tuple[SegmentSchema, ...]) -> tuple[_Plan, ...]:
        plans: list[_Plan] = []
        h, dead = 0.0, None
        stall_eas = float(stall_speed_eas_m_s(self.case.aircraft))
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        where = f"{self.mission.path}: segments"
        i = 0
        try:
            for i, s in enumerate(segments):
                label = f"segment {i + 1} ({s.type})"
                if s.type == "engine_failure":
                    if s.engine not in self.engines:
                        raise InputError(
                            f"{where}[{i}].engine: {s.engine!r} is not an engine of the propulsion "
                            f"file ({', '.join(self.engines)})"
                        )
                    if dead is not None:  # SPEC 3: one engine inoperative, not two
                        raise InputError(
                            f"{where}[{i}]: a second engine_failure ({s.engine}): "
                            f"{self.engines[dead]} has already failed and the OEI rule "
                            "flies on one engine inoperative"
                        )
                    if self.n < 2:
                        raise InputError(f"{where}[{i}]: engine_failure on a single-engine "
                                         "aircraft leaves no engine to fly on")
                    dead = self.engines.index(s.engine)
                    plans.append(_Plan(i, s.type, "event", h, h, None, False, 0.0, 0.0, False, 0.0,
                                       dead))
                    continue
                if s.type == "takeoff":
                    if i != 0:
                        raise InputError(f"{where}[{i}]: takeoff must be the first segment")
                    from tuflexperf.analysis.takeoff import obstacle_height_of

                    if self.case.aircraft.launch == "catapult":  # airborne at release, 0 m
                        from tuflexperf.analysis.takeoff import solve_takeoff

                        try:  # the catapult must give the mass its release speed
                            solve_takeoff(self.case)
                        except NotAttainable as exc:
                            raise NotAttainable(f"{label}: {exc}") from None
                        plans.append(_Plan(i, s.type, "event", 0.0, 0.0, None, False, 0.0, 0.0,
                                           False, 0.0, dead))
                        continue
                    # the take-off ends over the obstacle (or, for the endurance launch, at
                    # the lift-off: its climb starts from the runway)
                    h = obstacle_height_of(self.case) if self.takeoff_to_obstacle else 0.0
                    plans.append(_Plan(i, s.type, "takeoff", 0.0, h, None, False, 1.0, 0.0,
                                       False, 0.0, dead))
                    continue
                if s.type in ("cruise", "loiter") and s.throttle is not None:
                    # level at a fixed throttle: the airspeed follows (the fast root)
                    v_guess = self._level_speed_at_throttle(s.throttle, h, dead, label)
                    plans.append(_Plan(i, s.type, "time", h, h, None, False, s.throttle, 0.0,
                                       False, 60.0 * float(s.time_min), dead,  # type: ignore[arg-type]
                                       True, v_guess))
                    continue
                eas = (s.airspeed_m_s if s.airspeed_m_s is not None
                       else self._best_endurance_eas(h, dead))
                if eas < margin * stall_eas * (1 - 1e-12):
                    raise NotAttainable(
                        f"{label}: {eas:.1f} m/s EAS is below stall ({margin:g} x "
                        f"{stall_eas:.1f} m/s EAS): not attainable, below stall"
                    )
                if s.type in ("climb", "descent"):
                    target = float(s.to_altitude_m)  # type: ignore[arg-type]
                    # a descent to its own height is no descent, as a climb to it is no climb
                    if not (target > h if s.type == "climb" else target < h):
                        raise InputError(
                            f"{where}[{i}].to_altitude_m: a {s.type} from {h:g} m must go "
                            f"{'up' if s.type == 'climb' else 'down'}, got {target:g} m"
                        )
                    if s.throttle is not None:
                        plans.append(_Plan(i, s.type, "height", h, target, eas, False, s.throttle,
                                           0.0, True, 0.0, dead))
                    else:
                        rate = s.climb_rate_m_s if s.type == "climb" else -s.descent_rate_m_s
                        plans.append(_Plan(i, s.type, "height", h, target, eas, True, 0.0,
                                           float(rate), False, 0.0, dead))
                    h = target
                    continue
                # cruise / loiter: level at constant height
                if s.time_min is not None:
                    duration = 60.0 * s.time_min
                else:
                    v_true = float(true_airspeed_m_s(eas, self._rho(h)))
                    duration = 1000.0 * s.distance_km / v_true  # type: ignore[operator]
                plans.append(_Plan(i, s.type, "time", h, h, eas, True, 0.0, 0.0, False, duration,
                                   dead))
        except NotAttainable as exc:
            # the segments before it can still be flown (solve_mission reports them)
            exc.segment_index = i  # type: ignore[attr-defined]
            raise
        return tuple(plans)

    def _level_speed_at_throttle(self, throttle: float, h: float, dead: int | None,
                                 label: str) -> float:
        """Fastest true airspeed [m/s] of level flight at ``throttle`` short of the fans' jet
        velocity (full packs, no sag)."""
        aircraft, prop = self.case.aircraft, self.case.propulsion
        rho = float(self._rho(h))
        stall = float(stall_speed_eas_m_s(aircraft)) * math.sqrt(1.225 / rho)
        ceiling = float(jet_velocity_ceiling_m_s(prop, rho))

        def excess(speed: Any) -> Any:
            return np.asarray(total_thrust_n(prop, throttle, speed, rho, dead, self.dead_mode)
                              - level_flight_drag_n(aircraft, speed, rho), dtype=float)

        # up to 8 x stall, further while the throttle still flies level at the top (a large
        # cl_max puts the stall far below the cruise), to the jet velocity or Mach 1 at most
        top = 8.0 * stall
        limit = max(top, min(ceiling, MAX_AIRSPEED_M_S))
        while top < limit and float(excess(top)) >= 0.0:
            top = min(2.0 * top, limit)
        v = np.linspace(0.5 * stall, top, 4001)
        # the fast root short of the jet velocity: past it a fan makes no thrust, so the
        # extrapolated polynomial's rise there (a near-zero cd0) is no level flight
        ok = np.flatnonzero((excess(v) >= 0) & (v < ceiling))
        if not ok.size or ok[-1] == v.size - 1:
            raise NotAttainable(f"{label}: throttle {throttle:g} holds level flight at no "
                                "airspeed")
        low, high = float(v[ok[-1]]), float(v[ok[-1] + 1])
        for _ in range(60):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if excess(mid) >= 0 else (low, mid)
        if high >= ceiling:
            raise NotAttainable(
                f"{label}: throttle {throttle:g} flies level only at or beyond the fans' static "
                f"jet velocity {ceiling:.1f} m/s, where they make no thrust (the thrust model "
                "is extrapolated there): not attainable")
        return 0.5 * (low + high)

    def _best_endurance_eas(self, h: float, dead: int | None = None) -> float:
        """EAS of least electrical power in level flight at height ``h`` (full packs).

        With a ``dead`` engine (after an engine failure) on the live engines alone, the dead
        one windmilling (or not) as in flight.
        """
        aircraft = self.case.aircraft
        rho = float(self._rho(h))
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        stall = margin * float(stall_speed_eas_m_s(aircraft))
        eas = np.linspace(stall, 4.0 * stall, 2001)

        def power_at(speeds_eas: np.ndarray) -> np.ndarray:
            v = np.asarray(true_airspeed_m_s(speeds_eas, rho), dtype=float)
            x, ok = self._level_throttle_numpy(v, rho, dead)
            return np.where(ok, self._power_numpy(x, v, rho, dead), np.inf)

        power = power_at(eas)
        k = int(np.argmin(power))
        if not np.isfinite(power[k]):
            raise NotAttainable(f"loiter at {h:g} m: no level flight up to full throttle")
        if k == 0 or k == eas.size - 1:
            return float(eas[k])
        # the grid's best point is up to half a step off the minimum: golden section on
        # its neighbours (the power is smooth and unimodal there) to 1e-9 m/s
        low, high = float(eas[k - 1]), float(eas[k + 1])
        ratio = 0.5 * (math.sqrt(5.0) - 1.0)
        a, b = high - ratio * (high - low), low + ratio * (high - low)
        f_a, f_b = power_at(np.array([a, b]))
        while high - low > 1e-9:
            if f_a <= f_b:
                high, b, f_b = b, a, f_a
                a = high - ratio * (high - low)
                f_a = float(power_at(np.array([a]))[0])
            else:
                low, a, f_a = a, b, f_b
                b = low + ratio * (high - low)
                f_b = float(power_at(np.array([b]))[0])
        return 0.5 * (low + high)

    def _level_throttle_numpy(self, v: np.ndarray, rho: float, dead: int | None = None
                              ) -> tuple[np.ndarray, np.ndarray]:
        prop = self.case.propulsion
        t = [np.asarray(total_thrust_n(prop, x, v, rho, dead, self.dead_mode), dtype=float)
             for x in (0.0, 0.5, 1.0)]
        a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
        b = t[2] - t[0] - a
        c = t[0] - np.asarray(level_flight_drag_n(self.case.aircraft, v, rho), dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            x, reached = least_throttle_reaching(a, b, c)
        return np.asarray(x, dtype=float), np.asarray(reached) > 0.5

    def _power_numpy(self, x: np.ndarray, v: np.ndarray, rho: float, dead: int | None = None
                     ) -> np.ndarray:
        total = sum(np.asarray(self._engine_power(i, x, v, rho), dtype=float)
                    for i in range(self.n) if i != dead)
        return np.asarray(total, dtype=float)

    def _stall_factor(self) -> float:
        """Least EAS [m/s] of level flight: the stall speed (EAS) x the envelope's margin."""
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        return margin * float(stall_speed_eas_m_s(self.case.aircraft))
