"""A mission's static plan: each segment's kind, heights, settings, checked at build time.

Segments below stall, climbs that do not climb, a throttle with no level flight, a second
engine failure: refused here, before anything is flown (SPEC 3, SPEC 4 "Mission file").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.level_flight import LevelFlightRows
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.mission import SegmentSchema
from tuflexperf.models.aircraft import (
    MAX_AIRSPEED_M_S,
    level_flight_drag_n,
    stall_speed_eas_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.powertrain import (
    jet_velocity_ceiling_m_s,
)
from tuflexperf.models.thrust import least_throttle_reaching

Array = NDArray[np.float64]


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

    def _case_rows(self) -> Any:
        """The case as one row of the batch's model (its plan is a batch of one)."""
        return LevelFlightRows(aircraft=self.case.aircraft, propulsion=self.case.propulsion,
                               density=self.case.density_kg_m3, extrapolation_n=None, size=1)

    def _level_speed_at_throttle(self, throttle: float, h: float, dead: int | None,
                                 label: str) -> float:
        """Fastest true airspeed [m/s] of level flight at ``throttle`` short of the fans' jet
        velocity (full packs, no sag): :func:`level_speeds_at_throttle`, a batch of one."""
        speed, beyond = level_speeds_at_throttle(self, h, throttle, dead, self._case_rows(),
                                                 np.array([self.field_m]),
                                                 np.array([self.dt_k]))
        if beyond[0]:
            ceiling = float(jet_velocity_ceiling_m_s(self.case.propulsion, float(self._rho(h))))
            raise NotAttainable(
                f"{label}: throttle {throttle:g} flies level only at or beyond the fans' static "
                f"jet velocity {ceiling:.1f} m/s, where they make no thrust (the thrust model "
                "is extrapolated there): not attainable")
        if not np.isfinite(speed[0]):
            raise NotAttainable(f"{label}: throttle {throttle:g} holds level flight at no "
                                "airspeed")
        return float(speed[0])

    def _best_endurance_eas(self, h: float, dead: int | None = None) -> float:
        """EAS of least electrical power in level flight at height ``h`` (full packs):
        :func:`best_endurance_eas_rows`, a batch of one.

        With a ``dead`` engine (after an engine failure) on the live engines alone, the dead
        one windmilling (or not) as in flight.
        """
        eas = best_endurance_eas_rows(self, h, dead, self._case_rows(), np.array([self.field_m]),
                                      np.array([self.dt_k]), np.array([self._stall_factor()]))
        if not np.isfinite(eas[0]):
            raise NotAttainable(f"loiter at {h:g} m: no level flight up to full throttle")
        return float(eas[0])

    def _stall_factor(self) -> float:
        """Least EAS [m/s] of level flight: the stall speed (EAS) x the envelope's margin."""
        envelope = self.case.requirements.envelope
        margin = getattr(envelope, "stall_margin", 1.0) if envelope is not None else 1.0
        return margin * float(stall_speed_eas_m_s(self.case.aircraft))


def _segment_rows(model: Any, h: float, m: Any, field_m: Array, dt_k: Array
                  ) -> tuple[Array, Any]:
    """Per row the density [kg/m^3] at height ``h`` [m] and the batch's model there."""
    rho = (np.full(m.size, model.fixed_density) if model.fixed_density is not None
           else np.asarray(isa_density_kg_m3(field_m + h, dt_k), dtype=float)
           * np.ones(m.size))
    return rho, LevelFlightRows(aircraft=m.aircraft, propulsion=m.propulsion,
                                density=rho[:, None], extrapolation_n=m.extrapolation_n,
                                size=m.size)


def best_endurance_eas_rows(model: Any, h: float, dead: int | None, m: Any, field_m: Array,
                            dt_k: Array, least: Array) -> Array:
    """Per row the EAS [m/s] of least electrical power in level flight at height ``h`` [m]
    with full packs (NaN: no level flight), engine ``dead`` out: over 2001 airspeeds from
    ``least`` (the row's stall x margin [m/s]) to 4 times it, then golden section on the
    best one's neighbours (the power is smooth and unimodal there) to 1e-9 m/s, each row on
    its own bracket. ``m`` the rows' model (``analysis.batch_model.BatchModel``; one row for
    the single case's plan), per row the field [m] and temperature offset [K]."""
    rho, at = _segment_rows(model, h, m, field_m, dt_k)
    live = [i for i in range(model.n) if i != dead]

    def power_at(eas: Array) -> Array:  # eas (B, K) [m/s] -> electrical power [W]
        # rows done with (no bracket: 0 m/s) or far outside the models go NaN, harmlessly
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            v = np.asarray(true_airspeed_m_s(eas, rho[:, None]), dtype=float)
            t = [at.thrust(x, v, dead, model.dead_mode) for x in (0.0, 0.5, 1.0)]
            a = 2.0 * (t[2] - 2.0 * t[1] + t[0])
            b = t[2] - t[0] - a
            c = t[0] - np.asarray(level_flight_drag_n(m.aircraft, v, rho[:, None]),
                                  dtype=float)
            x, reached = least_throttle_reaching(a, b, c)
            x = np.asarray(x, dtype=float)
            total = sum(np.asarray(model._engine_power(i, x, v, rho[:, None]), dtype=float)
                        for i in live)
        return np.where(np.asarray(reached) > 0.5, total, np.inf)

    grid, block, size = 2001, 250, m.size
    start, step = least, (4.0 * least - least) / (grid - 1)  # np.linspace's own terms

    def eas_at(index: Array) -> Array:
        return np.where(index[None, :] == grid - 1, 4.0 * least[:, None],
                        index[None, :] * step[:, None] + start[:, None])

    best, k = np.full(size, np.inf), np.zeros(size, dtype=int)
    for first in range(0, grid, block):  # the grid's least power per row, a block at a time
        index = np.arange(first, min(first + block, grid))
        power = power_at(eas_at(index))
        j = np.argmin(power, axis=1)
        lower = power[np.arange(size), j] < best
        best, k = np.where(lower, power[np.arange(size), j], best), np.where(lower, index[j], k)
    edge = (k == 0) | (k == grid - 1)
    low = np.where(edge, 0.0, (k - 1) * step + start)
    high = np.where(k + 1 == grid - 1, 4.0 * least, (k + 1) * step + start)
    high = np.where(edge, 0.0, high)
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    a, b = high - ratio * (high - low), low + ratio * (high - low)
    f_a, f_b = power_at(a[:, None])[:, 0], power_at(b[:, None])[:, 0]
    active = ~edge & np.isfinite(best) & (high - low > 1e-9)
    while active.any():  # each row stops at its own 1e-9 m/s, as the single case's loop
        left = active & (f_a <= f_b)
        right = active & ~left
        high, b, f_b = np.where(left, b, high), np.where(left, a, b), np.where(left, f_a, f_b)
        low, a, f_a = np.where(right, a, low), np.where(right, b, a), np.where(right, f_b, f_a)
        a = np.where(left, high - ratio * (high - low), a)
        b = np.where(right, low + ratio * (high - low), b)
        fresh = power_at(np.where(left, a, b)[:, None])[:, 0]
        f_a, f_b = np.where(left, fresh, f_a), np.where(right, fresh, f_b)
        active &= high - low > 1e-9
    on_grid = np.where(k == grid - 1, 4.0 * least, k * step + start)
    return np.where(~np.isfinite(best), np.nan, np.where(edge, on_grid, 0.5 * (low + high)))


def level_speeds_at_throttle(model: Any, h: float, throttle: float, dead: int | None, m: Any,
                             field_m: Array, dt_k: Array) -> tuple[Array, Array]:
    """Per row the fastest true airspeed [m/s] of level flight at ``throttle`` at height
    ``h`` [m] with full packs short of the fans' jet velocity (NaN: none), engine ``dead``
    out, and whether the root found lies at or beyond that velocity (then NaN too). The
    rows' aircraft and thrust (with its extrapolation error; ``m`` as for
    :func:`best_endurance_eas_rows`): 4001 airspeeds from half the stall speed to 8 x it,
    the top doubled while the throttle still flies level there (a large ``cl_max`` puts the
    stall far below the cruise) up to the jet velocity or Mach 1, the last one that flies
    level, then 60 bisections."""
    size = m.size
    rho, at = _segment_rows(model, h, m, field_m, dt_k)
    stall = np.asarray(stall_speed_eas_m_s(m.aircraft), dtype=float).reshape(-1) * np.sqrt(
        1.225 / rho)
    ceiling = np.asarray(jet_velocity_ceiling_m_s(m.propulsion, rho[:, None]),
                         dtype=float).reshape(-1) * np.ones(size)

    def excess(speed: Array) -> Array:  # speed (B, K) [m/s]
        return (at.thrust(throttle, speed, dead, model.dead_mode)
                - np.asarray(level_flight_drag_n(m.aircraft, speed, rho[:, None]), dtype=float))

    top = 8.0 * stall
    limit = np.maximum(top, np.minimum(ceiling, MAX_AIRSPEED_M_S))
    for _ in range(64):  # the doubling, each row until it stops (<= log2(340/stall) steps)
        grow = (top < limit) & (excess(top[:, None])[:, 0] >= 0.0)
        if not grow.any():
            break
        top = np.where(grow, np.minimum(2.0 * top, limit), top)
    grid, block = 4001, 250
    start, step = 0.5 * stall, (top - 0.5 * stall) / (grid - 1)  # np.linspace's own terms
    last = np.full(size, -1)
    # the fast root short of the jet velocity: the last grid speed that flies level, found
    # from the top down in blocks of speeds (all rows at once; done rows are not redone)
    for end in range(grid, 0, -block):
        todo = last < 0
        if not todo.any():
            break
        index = np.arange(max(end - block, 0), end)
        v = np.where(index[None, :] == grid - 1, top[:, None],
                     index[None, :] * step[:, None] + start[:, None])
        flies = (excess(v) >= 0) & (v < ceiling[:, None])
        hit = flies.any(axis=1) & todo
        last[hit] = index[v.shape[1] - 1 - np.argmax(flies[hit, ::-1], axis=1)]
    found = (last >= 0) & (last < grid - 1)
    low = np.where(found, last * step + start, np.nan)
    high = np.where(found & (last + 1 == grid - 1), top, (last + 1) * step + start)
    high = np.where(found, high, np.nan)
    for _ in range(60):
        mid = 0.5 * (low + high)
        with np.errstate(invalid="ignore"):
            up = excess(mid[:, None])[:, 0] >= 0
        low, high = np.where(up, mid, low), np.where(up, high, mid)
    with np.errstate(invalid="ignore"):
        beyond = high >= ceiling
        return np.where(beyond, np.nan, 0.5 * (low + high)), beyond
