"""The take-off's airborne part: rotation, the transition arc to the obstacle, on sagging packs.

After lift-off the aircraft rotates (:func:`rotation_charge`) and flies the transition arc
at full throttle to the obstacle height (:func:`obstacle_height_of`), per row an
:class:`ObstaclePath` (one row for ``takeoff``, whose reasons :func:`airborne_result`
words; many for the batch). With a reference voltage the thrust follows the packs' loaded
voltage along the way: :func:`settle_airborne` iterates the charge drawn until the arc and
the packs agree.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import BEYOND_THE_BATTERY
from tuflexperf.analysis.pack_limits import (
    within_limits,
)
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    DEFAULT_OBSTACLE_HEIGHT_M,
    TRANSITION_SPEED_OVER_STALL,
    ground_roll_net_force_n,
    obstacle_distances_m,
    transition_beyond_cl_max,
)
from tuflexperf.models.battery import SECONDS_PER_HOUR

ROTATION_STEPS = 8  # RK4 steps of the rotation's charge at the lift-off speed (the mission's)


def rotation_charge(rate: Any, charge_ah: Any, seconds: Any) -> Any:
    """The charge per engine [Ah] after the rotation's ``seconds`` [s] (one or per row) at
    full throttle at the lift-off speed: :data:`ROTATION_STEPS` RK4 steps of
    ``dq/dt = rate(q)`` [Ah/s] (the single case and the batch alike)."""
    h = seconds / ROTATION_STEPS
    q = charge_ah
    for _ in range(ROTATION_STEPS):
        k1 = rate(q)
        k2 = rate(q + 0.5 * h * k1)
        k3 = rate(q + 0.5 * h * k2)
        k4 = rate(q + h * k3)
        q = q + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return q


# the airborne charge on sagging packs: a settled fixed point, or why not (settle_airborne)
CHARGE_TOLERANCE_AH = 1e-9  # settled: the charge per engine known to within this [Ah]

_INNER_TOLERANCE_AH = 1e-12  # the climb's midpoint charge at a given climb time [Ah]

SETTLE_ITERATIONS = 200  # cap of each iteration and each bisection (then: not settled)

_SCAN_RATIO = 1.1  # growth of the climb times scanned for the obstacle (a bracket)

_SCAN_STEPS = 400  # 1.1^400 ~ 4e16 times the sag-free climb: the packs are long empty

_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)


# per row of :class:`AirborneOnPacks`: the obstacle reached, or why not
REACHED = 0

NO_CLIMB = 1  # the full-throttle gradient at the arc's end is not positive

TOPS_OUT = 2  # the climb stops gaining height below the obstacle as the packs sag

BEYOND_THE_BATTERY_STATUS = 3  # the packs reach their cut-off (or power) before the obstacle

UNSETTLED = 4  # the charge drawn on the way did not settle within SETTLE_ITERATIONS


@dataclass(frozen=True)
class AirborneOnPacks:
    """The airborne part of a take-off on sagging packs, per row (:func:`settle_airborne`).

    Attributes
    ----------
    arc_gradient : ndarray
        Full-throttle climb gradient at the transition arc's end [-] ``(rows,)``: it sets
        the arc's end angle.
    climb_gradient : ndarray
        Full-throttle gradient halfway up the straight climb [-] ``(rows,)``; the arc's
        where the arc clears the obstacle; NaN where the obstacle is not reached (then
        :func:`tuflexperf.models.aircraft.obstacle_distances_m` gives an infinite climb).
    arc_charge_ah, climb_charge_ah, charge_ah : ndarray
        Charge drawn per engine [Ah] ``(engines, rows)`` at the arc's end, halfway up the
        climb and at the obstacle (where it is not reached: the arc's end).
    climb_s : ndarray
        Time of the straight climb [s] ``(rows,)`` (0 where the arc clears the obstacle,
        NaN where it is not reached).
    status : ndarray
        :data:`REACHED`, :data:`NO_CLIMB`, :data:`TOPS_OUT`,
        :data:`BEYOND_THE_BATTERY_STATUS` or :data:`UNSETTLED` per row.
    apex_m : ndarray
        Where the climb tops out (:data:`TOPS_OUT`): the height it reaches [m] ``(rows,)``;
        NaN elsewhere.
    """

    arc_gradient: np.ndarray
    climb_gradient: np.ndarray
    arc_charge_ah: np.ndarray
    climb_charge_ah: np.ndarray
    charge_ah: np.ndarray
    climb_s: np.ndarray
    status: np.ndarray
    apex_m: np.ndarray


def settle_airborne(radius_m: Any, speed_m_s: Any, height_m: Any, charge_ah: Any,
                    point: Callable[[np.ndarray], tuple[Any, Any, Any]],
                    gradient_of: Callable[[Any], Any], cutoff_v: Any) -> AirborneOnPacks:
    """The transition arc and the straight climb to the obstacle on sagging packs, with the
    charge they draw settled; rows broadcast (the single case is one row, the batch's many:
    one code path for both).

    The packs sag as the arc and the climb draw their charge, the thrust and so the
    gradient fall, and the time to the obstacle grows with it. From ``charge_ah``
    ``(engines, rows)`` at the arc's start, two fixed points, each settled to
    :data:`CHARGE_TOLERANCE_AH` per row:

    - the arc: ``q_arc = q0 + I(q_arc) t_arc / 3600``, ``t_arc = R gamma / V`` with
      ``sin(gamma) = G(q_arc)`` (or ``R acos(1 - h/R) / V`` where the arc clears the
      obstacle ``h``); the map is a strong contraction (the arc lasts seconds), so plain
      iteration settles;
    - the straight climb from the arc's top ``h_TR``: ``q_mid = q_arc + I(q_mid) t / 7200``
      with ``t = (h - h_TR) / (V G(q_mid))``, the gradient halfway up standing for the
      climb's (the packs sag almost linearly over these seconds: second order; a test holds
      the distance to an integration with the charge along the path). The charge at the
      obstacle is ``q_arc + I(q_mid) t / 3600``. Near the edge of climbing the gradient
      falls far over the climb and the midpoint stands for it less well: with a 44 V
      reference and k = 0.272 it gives 846 m where an integration in time gives 765 m, and
      at 0.274 it tops out at 13.6 m where the integration clears 15 m at 1084 m (long,
      not short: early in the packs' discharge the gradient falls fastest, convex in the
      charge).

    The climb's map is not a contraction near the edge of climbing: as ``G -> 0`` the time
    to the obstacle goes to infinity, and four plain iterations (the earlier code)
    oscillated there, the obstacle distance jumping up and down in the induced-drag factor
    (outside audit). It is solved in the climb time ``t`` instead: the height reached,
    ``phi(t) = t V G(q_mid(t))``, rises from 0, and the obstacle is reached at its first
    crossing of ``h - h_TR``. More charge lowers the voltage, the thrust and the gradient,
    so ``t0 = (h - h_TR) / (V G(q_arc))`` (the climb without further sag) is a lower bound:
    the scan steps up from it by :data:`_SCAN_RATIO` until the obstacle is reached, or the
    packs' loaded voltage at the obstacle's charge falls below ``cutoff_v`` [V] (or they
    cannot give the power: NaN), or ``phi`` falls (past its peak: a golden-section search
    finds it, and below the obstacle the climb tops out), then bisects the bracket until
    the charge at the obstacle is known to :data:`CHARGE_TOLERANCE_AH`. The returned climb
    is the bracket's upper end: the obstacle is reached there, at a gradient no higher
    than the fixed point's (a distance never short). Each row's iterates depend on that
    row alone, so a batch row gives the single case's numbers.

    Parameters
    ----------
    radius_m : float or ndarray
        Transition arc's radius [m] (one or ``(rows,)``).
    speed_m_s : float or ndarray
        Transition (and climb) true airspeed [m/s].
    height_m : float or ndarray
        Obstacle height [m].
    charge_ah : ndarray
        Charge drawn per engine at the arc's start [Ah] ``(engines, rows)``.
    point : callable
        ``point(q)`` with ``q`` ``(engines, rows)`` [Ah]: the full-throttle thrust [N]
        ``(rows,)``, the current per engine [A] and the packs' loaded voltage per engine [V]
        ``(engines, rows)`` (NaN: beyond their power) at the transition speed.
    gradient_of : callable
        ``gradient_of(thrust)``: the climb gradient [-] ``(rows,)`` at that thrust [N].
    cutoff_v : float or ndarray
        The packs' cut-off voltage [V] (one or per row).

    Returns
    -------
    AirborneOnPacks

    References
    ----------
    Anderson, *Aircraft Performance and Design*, 6.7.2 (the arc and the climb); SPEC 3
    (thrust and pack voltage; take-off to the obstacle); Press et al., *Numerical
    Recipes*, 9.1 and 10.2 (bisection, golden-section search).
    """
    q0 = np.asarray(charge_ah, dtype=float)
    rows = q0.shape[1]
    radius = np.asarray(radius_m, dtype=float) * np.ones(rows)
    speed = np.asarray(speed_m_s, dtype=float) * np.ones(rows)
    height = np.asarray(height_m, dtype=float) * np.ones(rows)

    def evaluate(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        thrust, current, volts = point(q)
        current = np.asarray(current, dtype=float).reshape(q.shape)
        volts = np.asarray(volts, dtype=float).reshape(q.shape)
        gradient = np.asarray(gradient_of(thrust), dtype=float).reshape(-1) * np.ones(rows)
        holds = np.all(within_limits(volts, current, cutoff_v, None), axis=0)
        return gradient, current, volts, holds & np.isfinite(gradient)

    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        cleared_at = np.arccos(np.clip(1.0 - height / radius, -1.0, 1.0))

        def arc(gradient: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            angle = np.arcsin(np.clip(gradient, 0.0, 1.0))
            top = radius * (1.0 - np.cos(angle))
            cleared = top >= height
            return (np.nan_to_num(radius * np.where(cleared, cleared_at, angle) / speed),
                    top, cleared)

        # the arc: a contraction (its seconds are few); each row frozen once settled
        q_arc, arc_settled = q0, np.zeros(rows, dtype=bool)
        for _ in range(SETTLE_ITERATIONS):
            gradient, current = evaluate(q_arc)[:2]
            new = q0 + current * arc(gradient)[0] / SECONDS_PER_HOUR
            moved = np.max(np.abs(new - q_arc), axis=0)
            q_arc = np.where(arc_settled, q_arc, new)
            arc_settled |= moved < CHARGE_TOLERANCE_AH
            if arc_settled.all():
                break
        g_arc, current_arc, _, holds_arc = evaluate(q_arc)
        top, cleared = arc(g_arc)[1:]
        need = height - top
        status = np.full(rows, REACHED)
        status[~holds_arc] = BEYOND_THE_BATTERY_STATUS
        status[holds_arc & ~cleared & ~(g_arc > 0.0)] = NO_CLIMB
        status[~arc_settled] = UNSETTLED
        climbing = (status == REACHED) & ~cleared

        def at(seconds: np.ndarray, guess: np.ndarray, active: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
            """Halfway up a climb of ``seconds`` [s] (the ``active`` rows; the others at no
            climb): the charge [Ah], the gradient, the height reached above the arc's top
            ``phi`` [m], whether the packs hold at the obstacle's charge and whether the
            charge settled."""
            seconds = np.where(active, seconds, 0.0)
            q, settled = np.where(active, guess, q_arc), np.zeros(rows, dtype=bool)
            for _ in range(SETTLE_ITERATIONS):
                new = q_arc + evaluate(q)[1] * seconds / (2.0 * SECONDS_PER_HOUR)
                moved = np.max(np.abs(new - q), axis=0)
                q = np.where(settled, q, new)
                # a charge beyond the packs' power is NaN: no fixed point, the packs are out
                settled |= (moved < _INNER_TOLERANCE_AH) | ~np.all(np.isfinite(new), axis=0)
                if settled.all():
                    break
            gradient = evaluate(q)[0]
            holds = evaluate(2.0 * q - q_arc)[3] & np.isfinite(gradient)
            return q, gradient, seconds * speed * gradient, holds, settled

        def event(phi: np.ndarray, holds: np.ndarray) -> np.ndarray:
            return (phi >= need) | ~holds  # the obstacle reached, or the packs out first

        # the scan: from the sag-free climb time (a lower bound) up, until an event or phi
        # falls; each row keeps its own bracket [low, high] (and the point before low)
        before, low, phi_low = np.zeros(rows), np.zeros(rows), np.zeros(rows)
        q_before, q_low = q_arc, q_arc
        high = np.where(climbing, need / (speed * np.where(climbing, g_arc, 1.0)), 0.0)
        q_high, g_high = q_arc, g_arc
        holds_high = np.ones(rows, dtype=bool)
        scanning = climbing.copy()
        bracketed, peaked = np.zeros(rows, dtype=bool), np.zeros(rows, dtype=bool)
        for _ in range(_SCAN_STEPS):
            if not scanning.any():
                break
            q, g, phi, holds, settled = at(high, q_low, scanning)
            status[scanning & ~settled] = UNSETTLED
            live = scanning & settled
            found = live & event(phi, holds)
            fell = live & ~found & ~(phi > phi_low)
            keep = live & ~found & ~fell
            q_high = np.where(found, q, q_high)
            g_high = np.where(found, g, g_high)
            holds_high = np.where(found, holds, holds_high)
            bracketed |= found
            peaked |= fell
            before, q_before = np.where(keep, low, before), np.where(keep, q_low, q_before)
            low, q_low = np.where(keep, high, low), np.where(keep, q, q_low)
            phi_low = np.where(keep, phi, phi_low)
            high = np.where(keep, high * _SCAN_RATIO, high)
            scanning &= keep
        status[scanning] = UNSETTLED

        # the packs out at the scan's point (the obstacle maybe reached there too): where do
        # they give out? (their charge only grows: a bisection); the climb may have topped
        # out before, or reached the obstacle in between: the peak's search below decides
        out = bracketed & ~holds_high
        bracketed &= ~out
        end, q_end_low, phi_end = high.copy(), q_low, phi_low.copy()
        if out.any():
            gone, q_gone, onset = high.copy(), q_high, out.copy()
            end = np.where(out, low, end)
            for _ in range(SETTLE_ITERATIONS):
                onset &= ~(2.0 * np.max(np.abs(q_gone - q_end_low), axis=0)
                           < CHARGE_TOLERANCE_AH)
                if not onset.any():
                    break
                middle = 0.5 * (end + gone)
                q, _, phi, holds, settled = at(middle, q_end_low, onset)
                status[onset & ~settled] = UNSETTLED
                onset &= settled
                held, lost = onset & holds, onset & ~holds
                end, q_end_low = np.where(held, middle, end), np.where(held, q, q_end_low)
                phi_end = np.where(held, phi, phi_end)
                gone, q_gone = np.where(lost, middle, gone), np.where(lost, q, q_gone)
            status[onset] = UNSETTLED
            peaked |= out & (status == REACHED)

        # past phi's peak below the obstacle, or the packs out: golden section for the peak
        # on [before, end] (phi rose up to low; it fell at high, or the packs give out at
        # end); high enough, the crossing is before it; a peak at end is the packs' limit
        apex = np.full(rows, np.nan)
        if peaked.any():
            a, b = before.copy(), end.copy()
            c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
            q_c, _, phi_c, _, ok_c = at(c, q_low, peaked)
            q_d, _, phi_d, _, ok_d = at(d, q_low, peaked)
            searching = peaked & ok_c & ok_d
            status[peaked & ~searching] = UNSETTLED
            for _ in range(SETTLE_ITERATIONS):
                # settled where the peak's time is known to a charge within the tolerance
                width = np.max(np.abs(evaluate(q_c)[1]), axis=0) * (b - a) / SECONDS_PER_HOUR
                searching &= ~(width < CHARGE_TOLERANCE_AH)
                if not searching.any():
                    break
                left = searching & (phi_c >= phi_d)  # the peak in [a, d]: d <- c, a new c
                right = searching & ~left  # the peak in [c, b]: c <- d, a new d
                b, a = np.where(left, d, b), np.where(right, c, a)
                q_d, phi_d, q_c, phi_c = (np.where(left, q_c, q_d), np.where(left, phi_c, phi_d),
                                          np.where(right, q_d, q_c), np.where(right, phi_d, phi_c))
                c, d = (np.where(left, b - _GOLDEN * (b - a), np.where(right, d, c)),
                        np.where(left, c, np.where(right, a + _GOLDEN * (b - a), d)))
                q_new, _, phi_new, _, ok_new = at(np.where(left, c, d), q_low, searching)
                q_c, phi_c = np.where(left, q_new, q_c), np.where(left, phi_new, phi_c)
                q_d, phi_d = np.where(right, q_new, q_d), np.where(right, phi_new, phi_d)
                status[searching & ~ok_new] = UNSETTLED
                searching &= ok_new
            status[searching] = UNSETTLED
            peak_s = np.where(phi_c >= phi_d, c, d)
            q_p, g_p, phi_p, holds_p, ok_p = at(peak_s, q_low, peaked)
            candidate = peaked & (status == REACHED) & ok_p
            high_enough = candidate & event(phi_p, holds_p)
            highest = np.fmax(phi_p, np.fmax(phi_c, phi_d))
            # the packs out while the climb still gains height: beyond the battery; where it
            # stopped gaining before (the peak inside), it topped out first
            gave_out = candidate & ~high_enough & out & ~(highest > phi_end)
            tops = candidate & ~high_enough & ~gave_out
            status[tops] = TOPS_OUT
            status[gave_out] = BEYOND_THE_BATTERY_STATUS
            apex = np.where(tops, top + highest, np.nan)
            low, q_low = np.where(high_enough, before, low), np.where(high_enough, q_before,
                                                                       q_low)
            high, q_high = np.where(high_enough, peak_s, high), np.where(high_enough, q_p,
                                                                         q_high)
            g_high = np.where(high_enough, g_p, g_high)
            holds_high = np.where(high_enough, holds_p, holds_high)
            bracketed |= high_enough

        # bisection of each bracket for the first event: the charge at the obstacle settled
        bracketed &= status == REACHED
        bisecting = bracketed.copy()
        for _ in range(SETTLE_ITERATIONS):
            # the obstacle's charge is 2 q_mid - q_arc: known to within 2 |dq_mid|
            spread = 2.0 * np.max(np.abs(q_high - q_low), axis=0)
            bisecting &= ~(spread < CHARGE_TOLERANCE_AH)
            if not bisecting.any():
                break
            middle = 0.5 * (low + high)
            q, g, phi, holds, settled = at(middle, q_low, bisecting)
            status[bisecting & ~settled] = UNSETTLED
            bisecting &= settled
            up = bisecting & event(phi, holds)
            down = bisecting & ~up
            high, q_high = np.where(up, middle, high), np.where(up, q, q_high)
            g_high = np.where(up, g, g_high)
            holds_high = np.where(up, holds, holds_high)
            low, q_low = np.where(down, middle, low), np.where(down, q, q_low)
        status[bisecting] = UNSETTLED
        status[bracketed & (status == REACHED) & ~holds_high] = BEYOND_THE_BATTERY_STATUS

        reached = status == REACHED
        climbed = reached & ~cleared
        climb_s = np.where(climbed, high, np.where(reached, 0.0, np.nan))
        q_mid = np.where(climbed, q_high, q_arc)
        q_end = np.where(climbed, 2.0 * q_high - q_arc, q_arc)
        straight = np.where(climbed, g_high, np.where(reached, g_arc, np.nan))
    return AirborneOnPacks(g_arc, straight, q_arc, q_mid, q_end, climb_s, status, apex)

ON_PACKS = " at the packs' loaded voltage"


def on_packs_force(case: Case, packs: Any, charge_ah: np.ndarray,
                    speeds: np.ndarray) -> np.ndarray:
    """Full-throttle net force on the runway [N] at ``speeds`` on the sagging ``packs``
    (:class:`~tuflexperf.analysis.batch_takeoff_packs.TakeoffPacks`)."""
    thrust = packs.point(charge_ah, speeds)[0]
    return np.asarray(ground_roll_net_force_n(case.aircraft, thrust, speeds,
                                              case.density_kg_m3), dtype=float)


def packs_note(case: Case, start_v: np.ndarray, liftoff_v: np.ndarray | None,
                air: _Airborne) -> str:
    """What the take-off flew on: the packs' least loaded voltage [V] at the brake release
    (a catapult's release), at lift-off and at the obstacle."""
    prop = case.propulsion
    start = "the release" if liftoff_v is None else "the brake release"
    return (f"the take-off at the packs' loaded voltage: thrust x (U/"
            f"{prop.reference_voltage_v:g} V)^{prop.voltage_exponent:g}, U "
            f"{float(np.min(start_v)):.1f} V at {start}"
            + ("" if liftoff_v is None else f", {float(np.min(liftoff_v)):.1f} V at lift-off")
            + (f", {air.least_voltage_v:.1f} V at the obstacle" if air.distance_m is not None
               else ""))


def obstacle_height_of(case: Case) -> float:
    """The case's obstacle height [m] (requirements.takeoff.obstacle_height_m, default 15 m)."""
    requirement = case.requirements.takeoff
    if requirement is None or requirement.obstacle_height_m is None:
        return DEFAULT_OBSTACLE_HEIGHT_M
    return float(requirement.obstacle_height_m)


@dataclass(frozen=True)
class _Airborne:
    """The airborne part of a take-off: the arc at 1.15 V_stall, then the straight climb."""

    speed_m_s: float
    radius_m: float
    gradient: float
    arc_m: float
    climb_m: float
    arc_top_m: float
    reason: str
    least_voltage_v: float = math.nan  # the packs' at the obstacle (sagging packs only)
    arc_gradient: float = math.nan  # sets the arc's end angle (the climb's, but on sagging packs)
    # the packs reach their cut-off before the obstacle: the take-off is not attainable
    beyond_battery: bool = False

    @property
    def distance_m(self) -> float | None:
        total = self.arc_m + self.climb_m
        return total if math.isfinite(total) else None

    def fields(self, ground_roll_m: float, load_factor: float, height_m: float) -> dict[str, Any]:
        """The :class:`TakeoffResult` fields after a ground roll (or none) of ``ground_roll_m``."""
        airborne = self.distance_m
        return {
            "transition_speed_m_s": self.speed_m_s,
            "transition_load_factor": load_factor,
            "transition_radius_m": self.radius_m,
            "climb_gradient": self.gradient,
            "transition_gradient": (self.arc_gradient if math.isfinite(self.arc_gradient)
                                    else self.gradient),
            "transition_distance_m": self.arc_m,
            "transition_height_m": self.arc_top_m,
            "climb_distance_m": self.climb_m if math.isfinite(self.climb_m) else None,
            "airborne_distance_m": airborne,
            "distance_to_obstacle_m": None if airborne is None else ground_roll_m + airborne,
            "obstacle_height_m": height_m,
            # a vertical climb (gradient >= 1) also covers no ground: the arc's top says it
            "obstacle_cleared_in_transition": bool(self.arc_top_m >= height_m),
            "obstacle_reason": self.reason,
        }


@dataclass(frozen=True)
class ObstaclePath:
    """From lift-off to the obstacle per row ``(rows,)`` (one row for ``takeoff``, many for
    the batch): the transition speed [m/s], the arc's radius [m], the full-throttle gradient
    [-] at the arc's end and along the straight climb (on sagging packs NaN where the
    obstacle is not reached), the horizontal arc and climb [m] (climb ``inf``: never
    cleared) and the arc's top [m]; on sagging packs the settled path
    (:func:`settle_airborne`) and the least loaded voltage at the obstacle [V]."""

    speed_m_s: np.ndarray
    radius_m: np.ndarray
    arc_gradient: np.ndarray
    climb_gradient: np.ndarray
    arc_m: np.ndarray
    climb_m: np.ndarray
    top_m: np.ndarray
    settled: AirborneOnPacks | None = None
    least_voltage_v: np.ndarray | None = None

    @property
    def distance_m(self) -> np.ndarray:
        """Arc + climb to the obstacle [m] (``inf`` where never cleared)."""
        return self.arc_m + self.climb_m


def obstacle_path(speed_m_s: Any, radius_m: Any, height_m: Any, arc_gradient: Any,
                  climb_gradient_: Any = None, settled: AirborneOnPacks | None = None,
                  least_voltage_v: Any = None) -> ObstaclePath:
    """:class:`ObstaclePath` of rows flying the arc at ``arc_gradient`` and the straight
    climb at ``climb_gradient_`` (None: the arc's) to ``height_m`` [m]
    (:func:`~tuflexperf.models.aircraft.obstacle_distances_m`; Anderson 6.7.2)."""
    straight = arc_gradient if climb_gradient_ is None else climb_gradient_
    distances = obstacle_distances_m(radius_m, arc_gradient, height_m, climb_gradient_)
    columns = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (
        speed_m_s, radius_m, arc_gradient, straight, *distances)))
    return ObstaclePath(*(c.reshape(-1) for c in columns), settled, least_voltage_v)


def airborne_result(case: Case, height: float, path: ObstaclePath,
                    cutoff_v: float = math.nan) -> _Airborne:
    """The single case's airborne part from its one-row ``path`` (the batch's, at the
    model's thrust or on sagging packs of cut-off ``cutoff_v`` [V]), with the reason where
    the obstacle is not reached."""
    aircraft = case.aircraft
    v_tr, radius = float(path.speed_m_s[0]), float(path.radius_m[0])
    gradient, straight = float(path.arc_gradient[0]), float(path.climb_gradient[0])
    # where the obstacle is not reached on the packs the climb's gradient is NaN (an infinite
    # climb): the result reports the gradient the climb starts at
    reported = straight if math.isfinite(straight) else gradient
    air = path.settled
    why, beyond, least_voltage = "", False, math.nan
    if air is not None:
        least_voltage = float(path.least_voltage_v[0])
        beyond = bool(air.status[0] == BEYOND_THE_BATTERY_STATUS)
        why = _not_reached(int(air.status[0]), height, v_tr, gradient, float(air.apex_m[0]),
                           cutoff_v)
    arc_m, climb_m, arc_top_m = (float(x[0]) for x in (path.arc_m, path.climb_m, path.top_m))
    reason = "" if math.isfinite(arc_m + climb_m) else why or (
        f"the {height:g} m obstacle is never cleared: the arc tops out at {arc_top_m:.1f} m "
        f"and the full-throttle climb gradient sin(gamma) at {v_tr:.1f} m/s is {reported:.3f} "
        "(no climb)"
    )
    n = aircraft.takeoff.transition_load_factor
    if transition_beyond_cl_max(n):
        arc_m = climb_m = math.nan
        reason = (f"the transition arc at {v_tr:.1f} m/s ({TRANSITION_SPEED_OVER_STALL:g} "
                  f"V_stall) with load factor {n:g} needs CL = "
                  f"{n / TRANSITION_SPEED_OVER_STALL ** 2:.2f} cl_max, beyond cl_max (at most "
                  f"n = {TRANSITION_SPEED_OVER_STALL ** 2:.5g})")
    return _Airborne(v_tr, radius, reported, arc_m, climb_m, arc_top_m, reason, least_voltage,
                     gradient, beyond)


def _not_reached(status: int, height: float, speed: float, gradient: float, apex: float,
                 cutoff_v: float) -> str:
    """Why the climb on sagging packs does not reach the obstacle (:func:`settle_airborne`'s
    status; "" where it does, or no climb at all: the caller says that), the obstacle height
    and the apex [m], the airspeed [m/s], the arc's gradient [-], the cut-off [V]."""
    if status == TOPS_OUT:
        return (f"the {height:g} m obstacle is never cleared: the full-throttle climb gradient "
                f"at {speed:.1f} m/s falls from {gradient:.3f} at the arc's end as the packs "
                f"sag, and the climb tops out at {apex:.2f} m")
    if status == BEYOND_THE_BATTERY_STATUS:
        return (f"full throttle in the climb to the {height:g} m obstacle at {speed:.1f} m/s "
                f"takes the packs below their cut-off {cutoff_v:.2f} V (or beyond their "
                f"power) before they reach it: not attainable, {BEYOND_THE_BATTERY}")
    if status == UNSETTLED:
        return (f"the {height:g} m obstacle is not attainable: the charge drawn in the arc and "
                f"the climb at {speed:.1f} m/s did not settle to {CHARGE_TOLERANCE_AH:g} Ah "
                f"in {SETTLE_ITERATIONS} iterations")
    return ""
