"""Where level flight is attainable: above stall (times the margin), within full throttle,
and short of the fans' jet velocity.

SPEC 3: level flight needs ``CL <= cl_max``; below ``stall_margin x V_stall`` it is
*not attainable, below stall* — never a pass with a note. At or beyond the fans' static jet
velocity (past the tested range) a fan makes no thrust, whatever the extrapolated poly22
gives: not attainable there either (the rule of the take-off, :func:`beyond_jet_velocity`).
Trim, OEI and endurance mark each grid airspeed with why it is not attainable, and report
the exact bounds of the attainable airspeeds (the stall bound, the jet-velocity ceiling,
and the full-throttle roots of ``T(1, V) = D(V)`` refined by bisection to 1e-12 m/s).

References
----------
Anderson, *Aircraft Performance and Design*, sections 5.4 (thrust available and
required) and 5.7 (stall speed, eq. 5.67).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import stall_speed_m_s
from tuflexperf.models.powertrain import beyond_jet_velocity, jet_velocity_ceiling_m_s

BELOW_STALL = "below stall"
BEYOND_JET_VELOCITY = "beyond the fans' jet velocity"
NEEDS_MORE_THAN_FULL_THROTTLE = "needs more than full throttle"
BEYOND_THE_BATTERY = "beyond the battery"  # the packs cannot fly it (analysis.pack_limits)
_SCAN_POINTS = 2001
_BISECTIONS = 100


def stall_margin_of(case: Case) -> float:
    """The envelope's ``stall_margin`` [-] (1.0 without an envelope block)."""
    envelope = case.requirements.envelope
    return 1.0 if envelope is None else float(envelope.stall_margin)


def least_airspeed_m_s(case: Case) -> float:
    """Least airspeed of level flight [m/s] at the case's density: ``stall_margin x V_stall``.

    References
    ----------
    Anderson, *Aircraft Performance and Design*, eq. 5.67.
    """
    return stall_margin_of(case) * float(stall_speed_m_s(case.aircraft, case.density_kg_m3))


def jet_ceiling_m_s(case: Case) -> float:
    """Airspeed [m/s] from which level flight is beyond the fans' jet velocity at the case's
    density (``inf`` without an area; :func:`jet_velocity_ceiling_m_s`)."""
    return float(jet_velocity_ceiling_m_s(case.propulsion, case.density_kg_m3))


def jet_ceiling_note(case: Case, airspeed_m_s: np.ndarray) -> list[str]:
    """The warning that some of these airspeeds are beyond the fans' jet velocity (or none)."""
    beyond = np.asarray(beyond_jet_velocity(case.propulsion, airspeed_m_s, case.density_kg_m3))
    if not beyond.any():
        return []
    return [
        f"at {jet_ceiling_m_s(case):.1f} m/s and above the fans' static jet velocity is reached "
        "(momentum theory on jet_area_m2, else fan_area_m2): a fan makes no thrust there, "
        "whatever the extrapolated thrust model gives, so level flight is not attainable"
    ]


def stall_bounded(
    airspeed_m_s: np.ndarray, throttle: np.ndarray, least_m_s: float, case: Case | None = None
) -> tuple[np.ndarray, tuple[str | None, ...]]:
    """Throttles with points below ``least_m_s`` [m/s] (and, given the ``case``, beyond the
    fans' jet velocity) made NaN, and each point's reason.

    ``throttle`` holds the least throttle per airspeed (NaN where full throttle is not
    enough). The reason is ``None`` where attainable, else ``below stall``, ``beyond the
    fans' jet velocity`` or ``needs more than full throttle``.
    """
    v = np.asarray(airspeed_m_s, dtype=float)
    x = np.asarray(throttle, dtype=float).copy()
    below = v < least_m_s * (1.0 - 1e-12)
    beyond = (np.zeros(v.shape, dtype=bool) if case is None else
              np.asarray(beyond_jet_velocity(case.propulsion, v, case.density_kg_m3)) & ~below)
    x[below | beyond] = np.nan
    reasons = tuple(
        BELOW_STALL if b else BEYOND_JET_VELOCITY if j else (
            None if np.isfinite(t) else NEEDS_MORE_THAN_FULL_THROTTLE)
        for b, j, t in zip(below, beyond, x, strict=True)
    )
    return x, reasons


@dataclass(frozen=True)
class AttainableRange:
    """Exact bounds [m/s] of attainable level flight within an airspeed interval.

    ``low``/``high`` are ``None`` when nothing is attainable; ``contiguous`` is False
    when the attainable set has a gap (then ``low``/``high`` are its outer bounds).
    """

    low: float | None
    high: float | None
    contiguous: bool = True

    def as_list(self) -> list[float] | None:
        return None if self.low is None else [self.low, self.high]


def attainable_range(
    full_throttle_excess: Callable[[np.ndarray], np.ndarray],
    least_m_s: float,
    low_m_s: float,
    high_m_s: float,
) -> AttainableRange:
    """Airspeeds in ``[low_m_s, high_m_s]`` above ``least_m_s`` where ``excess(V) >= 0``.

    ``full_throttle_excess`` is thrust at full throttle minus level-flight drag [N]
    (vectorised over airspeed [m/s]). A scan of 2001 points brackets the boundaries,
    bisection refines each to round-off.
    """
    start = max(low_m_s, least_m_s)
    if start > high_m_s:
        return AttainableRange(None, None)
    grid = np.linspace(start, high_m_s, _SCAN_POINTS)
    ok = np.asarray(full_throttle_excess(grid), dtype=float) >= 0.0
    if not ok.any():
        return AttainableRange(None, None)
    first = int(np.argmax(ok))
    last = int(ok.size - 1 - np.argmax(ok[::-1]))
    contiguous = bool(ok[first : last + 1].all())

    def boundary(inside: float, outside: float) -> float:
        a, b = inside, outside
        for _ in range(_BISECTIONS):  # to round-off: stops when the midpoint is an end
            mid = 0.5 * (a + b)
            if mid in (a, b):
                break
            if float(np.asarray(full_throttle_excess(np.array([mid])))[0]) >= 0.0:
                a = mid
            else:
                b = mid
        return a

    low = float(grid[0]) if first == 0 else boundary(float(grid[first]), float(grid[first - 1]))
    end = ok.size - 1
    high = float(grid[-1]) if last == end else boundary(float(grid[last]), float(grid[last + 1]))
    return AttainableRange(low, high, contiguous)


def describe_unattainable(airspeed_m_s: np.ndarray, reasons: tuple[str | None, ...]) -> list[str]:
    """One phrase per reason: ``below stall at 15-23 m/s (17 of 61 grid airspeeds)``."""
    v = np.asarray(airspeed_m_s, dtype=float)
    phrases = []
    for reason in (BELOW_STALL, BEYOND_JET_VELOCITY, NEEDS_MORE_THAN_FULL_THROTTLE,
                   BEYOND_THE_BATTERY):
        hit = np.array([r == reason for r in reasons], dtype=bool)
        if hit.any():
            low, high = v[hit].min(), v[hit].max()
            span = f"{low:g}" if low == high else f"{low:g}-{high:g}"
            phrases.append(
                f"{reason} at {span} m/s ({int(hit.sum())} of {v.size} grid airspeeds)"
            )
    return phrases
