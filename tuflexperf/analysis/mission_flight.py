"""A flown mission's checks and result: cut-off, full throttle, the pack's ratings, stall,
the fans' jet velocity, climbs that climb; the flight ends at the first failure (SPEC 3, 5).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tuflexperf.analysis.mission_equations import (
    BURST_OVER_CONTINUOUS,
    RATING_SEGMENT_S,
)
from tuflexperf.analysis.mission_plan import _Plan
from tuflexperf.analysis.mission_results import MissionResult, SegmentResult
from tuflexperf.models.battery import (
    first_window_beyond,
)
from tuflexperf.models.powertrain import (
    beyond_jet_velocity,
    static_jet_velocity_m_s,
)
from tuflexperf.models.thrust import (
    density_ratio,
    engine_thrust_n,
    outside_tested_range,
)


class FlightChecks:
    """The checks of :class:`tuflexperf.analysis.mission.MissionModel` (a mixin)."""

    case: Any
    n: int

    def _charge_valid(self, q: np.ndarray, current: np.ndarray) -> np.ndarray:
        """Per node: the packs' state is on the discharge curve (else they were emptied).

        Charges finite, never falling, short of the pole of the model's knee (``n Q_max``),
        currents finite and not negative: past the pole the equivalent circuit means nothing
        (its voltage rises again), so such a node counts as beyond the cut-off.
        """
        pole = self.packs * self.params.max_capacity_ah
        rising = np.ones(q.shape[1], dtype=bool)
        rising[1:] = np.all(np.diff(q, axis=1) >= -1e-12, axis=0)
        with np.errstate(invalid="ignore"):
            return (np.all(np.isfinite(q), axis=0) & np.all(q < pole, axis=0)
                    & np.all(np.isfinite(current), axis=0) & np.all(current >= 0.0, axis=0)
                    & np.logical_and.accumulate(rising))

    def _cutoff_within(self, plan: _Plan, start: np.ndarray, durations: np.ndarray,
                       theta: np.ndarray, low: float, high: float
                       ) -> tuple[float, np.ndarray, np.ndarray]:
        """Time [s] into a timed segment at which the loaded voltage meets the cut-off.

        Bisection on the segment flown from ``start`` for ``tau`` in ``[low, high]`` (the
        voltage is above the cut-off at ``low``, below at ``high``) to 1e-6 s, each ``tau``
        judged by the least voltage over its nodes (and the charge staying on the discharge
        curve); a bracket wider than a minute is first narrowed by doubling steps from
        ``low``. Returns the time and the state and aux outputs there.
        """
        f = self._segment_function(plan.index)
        d = np.array(durations, dtype=float)
        pole = self.packs * self.params.max_capacity_ah

        def margin(tau: float) -> float:
            d[plan.index] = tau
            end, aux, least_v, fall, most = (np.asarray(v, dtype=float).ravel()
                                             for v in f(start, d, theta, self.par, self.tk))
            q = np.stack([start[:self.n], end[:self.n]], axis=1)
            if not (self._charge_valid(q, aux[6:6 + self.n, None] * np.ones((1, 2))).all()
                    and fall[0] >= -1e-12 and most[0] < pole):
                return -1.0
            value = float(least_v[0]) - self.cutoff_v
            return value if math.isfinite(value) else -1.0

        # a bracket far wider than the discharge (a segment of months): march out from
        # ``low`` by doubling, so that every integration tried spans at most twice the time
        # to the cut-off and its nodes see the voltage cross before the knee
        span = high - low
        if span > 60.0:
            step = 60.0
            while step < span:
                if margin(low + step) < 0:
                    high = low + step
                    break
                low, span = low + step, span - step
                step *= 2.0
        for _ in range(200):
            if high - low <= 1e-6:
                break
            mid = 0.5 * (low + high)
            low, high = (mid, high) if margin(mid) >= 0 else (low, mid)
        d[plan.index] = low  # the last time still on the right side of the cut-off
        end, aux = (np.asarray(v_, dtype=float).ravel()
                    for v_ in f(start, d, theta, self.par, self.tk)[:2])
        return low, end, aux

    def _pack_rating_a(self) -> float | None:
        """The pack's continuous rating [A]: ``max_discharge_c x capacity_ah`` (None without
        a rating in the battery file)."""
        c_rate = self.battery.max_discharge_c
        return None if c_rate is None else float(c_rate) * float(self.battery.capacity_ah)

    def _beyond_rating(self, rating: float | None, t: np.ndarray, current: np.ndarray,
                       a: int, b: int, live: list[int], heavy: tuple[float, float, float]
                       ) -> tuple[int, str, float] | None:
        """Where segment ``[a, b)`` draws a pack beyond its rating: the node, why, and the
        time [s] it happens (None: within).

        No current may exceed :data:`BURST_OVER_CONTINUOUS` times the continuous rating
        (:meth:`_pack_rating_a`; the usual burst rating), and the mean current over any
        :data:`RATING_SEGMENT_S` or more of the flight, ``heavy`` = (end, start [s], mean
        [A]) of the earliest such stretch beyond it (:func:`first_window_beyond`), stays
        within the rating: when that stretch ends in this segment the flight ends there. A
        pack asked for 9 C against a 5 C rating 'flew' (outside audit); a take-off a few per
        cent above the continuous rating for seconds is within the burst; a long cruise cut
        into segments under 30 s each passed when the mean was bounded per segment (outside
        audit). The batch applies the same two rules (analysis.batch_endurance).
        """
        if rating is None or not live or b - a < 1:
            return None
        what = (f"(max_discharge_c {self.battery.max_discharge_c:g} C x "
                f"{self.battery.capacity_ah:g} Ah): not attainable, beyond the battery")
        per_pack = self.battery.packs_in_parallel_per_engine
        peak = np.max(current[live, a:b], axis=0) / per_pack
        burst = np.flatnonzero(peak > BURST_OVER_CONTINUOUS * rating * (1.0 + 1e-9))
        found: list[tuple[int, str, float]] = []
        if burst.size:
            k = int(burst[0])
            found.append((k, f"draws {peak[k]:.1f} A per pack, beyond its burst rating "
                          f"{BURST_OVER_CONTINUOUS * rating:.1f} A {what}", float(t[a + k])))
        end, begin, mean = heavy
        if t[a] - 1e-9 <= end <= t[b - 1] + 1e-9:
            k = min(int(np.searchsorted(t[a:b], end - 1e-9)), b - 1 - a)
            # the flight ends where the stretch ends, not at the node after it
            found.append((k, (
                f"draws {mean:.1f} A per pack on average over {end - begin:.0f} s "
                f"({begin:.0f}-{end:.0f} s into the mission{self._spanned(t, begin, end)}), "
                f"beyond its continuous rating {rating:.1f} A {what}"),
                min(float(t[a + k]), end)))
        return min(found, key=lambda item: item[:2]) if found else None

    def _spanned(self, t: np.ndarray, begin: float, end: float) -> str:
        """``, over segments 1-3 (takeoff, climb, cruise)`` where the stretch ``[begin,
        end]`` [s] covers more than the segment it ends in: the flight ends in that one, but
        the current was drawn over all of them (a take-off and climb read as the cruise's)."""
        covered = [plan for plan, (a, b) in zip(self.plans, self.bounds, strict=True)
                   if b > a and t[a] < end - 1e-9 and t[b - 1] > begin + 1e-9]
        if len(covered) < 2:
            return ""
        return (f", over segments {covered[0].index + 1}-{covered[-1].index + 1} "
                f"({', '.join(plan.type for plan in covered)})")

    def _result(self, states: np.ndarray, aux: np.ndarray, solved: dict[str, Any] | None,
                theta: np.ndarray, durations: np.ndarray) -> MissionResult:
        n = self.n
        q, e = states[:n], states[n:2 * n]
        h, dist, t = states[2 * n], states[2 * n + 1], states[2 * n + 2]
        x, v, rate, reached, idle, level_residual = (aux[k] for k in range(6))
        current, voltage = aux[6:6 + n], aux[6 + n:6 + 2 * n]
        power = aux[6 + 2 * n:6 + 3 * n]
        segment_of = np.full(t.size, -1, dtype=int)
        stall_factor = self._stall_factor()
        rating = self._pack_rating_a()
        heavy = (math.inf, math.nan, math.nan)
        if rating is not None and t.size > 1:
            per_pack = self.battery.packs_in_parallel_per_engine
            # the pack does not see the segments: the rating holds over any 30 s or more
            heavy = tuple(float(v[0]) for v in first_window_beyond(  # type: ignore[assignment]
                t[None, :], q[None, :, :] / per_pack, rating, RATING_SEGMENT_S))
        reason = ""
        first_bad, ended_at = None, None
        segments: list[SegmentResult] = []
        vertical: list[str] = []  # climbs whose thrust exceeds weight plus drag
        for plan, (a, b) in zip(self.plans, self.bounds, strict=True):
            label = f"segment {plan.index + 1} ({plan.type})"
            if plan.kind == "event":
                k = max(a - 1, 0)
                segments.append(SegmentResult(plan.index, plan.type, 0.0, 0.0, float(h[k]),
                                              float(h[k]), None, (0.0,) * n, (0.0,) * n,
                                              float(np.nanmin(voltage[:, k])) if states.size
                                              else math.nan, None,
                                              None if plan.dead is None
                                              else self.engines[plan.dead]))
                continue
            sl = slice(a, b)
            live = [i for i in range(n) if i != plan.dead]
            volt_live = voltage[live, sl]
            problems: list[tuple[int, str]] = []
            exact_at: dict[str, float] = {}  # a problem's time where it is not its node's
            cut = np.flatnonzero(~(np.min(volt_live, axis=0) >= self.cutoff_v - 1e-9)
                                 | ~self._charge_valid(q[:, sl], current[:, sl]))
            if cut.size:
                problems.append((int(cut[0]), "the pack reaches its cut-off voltage "
                                 f"{self.cutoff_v:.1f} V"))
            bad = np.flatnonzero(reached[sl] < 0.5)
            if bad.size:
                problems.append((int(bad[0]), "needs more than full throttle"))
            beyond = self._beyond_rating(rating, t, current, a, b, live, heavy)
            if beyond is not None:
                problems.append(beyond[:2])
                exact_at[beyond[1]] = beyond[2]
            segment_of[sl] = plan.index
            if plan.solve_v:
                throttle = float(theta[3 * plan.index])
                off = np.flatnonzero(~(np.abs(level_residual[sl]) < 1e-9))
                if off.size:
                    problems.append((int(off[0]), f"throttle {throttle:g} no longer holds "
                                     "level flight"))
                # the airspeed is an outcome here: stall bounds it (SPEC 3)
                stall_v = stall_factor * np.sqrt(1.225 / np.asarray(self._rho(h[sl]),
                                                                      dtype=float))
                slow = np.flatnonzero(v[sl] < stall_v * (1 - 1e-12))
                if slow.size:
                    k0 = int(slow[0])
                    problems.append((k0, f"throttle {throttle:g} flies level at "
                                     f"{v[a + k0]:.1f} m/s, below stall ({stall_v[k0]:.1f} m/s):"
                                     " not attainable, below stall"))
                braking = self._braking_engine(throttle, v[sl], h[sl], live)
                if braking is not None:
                    problems.append(braking)
            if plan.kind != "takeoff":  # the take-off analysis holds its own lift-off to it
                rho_sl = np.asarray(self._rho(h[sl]), dtype=float)
                # only thrust the fans cannot make counts: an idle dive past the jet velocity
                # needs none (the live engines' thrust is the aux's last row)
                pushing = aux[6 + 3 * n, sl] > 0.0
                fast = np.flatnonzero(beyond_jet_velocity(self.case.propulsion, v[sl], rho_sl)
                                      & pushing)
                if fast.size:
                    k0 = int(fast[0])
                    jet = float(static_jet_velocity_m_s(self.case.propulsion, rho_sl[k0]))
                    problems.append((k0, f"{v[a + k0]:.1f} m/s is beyond the fans' static jet "
                                     f"velocity {jet:.1f} m/s, where they make no thrust "
                                     "(the thrust model is extrapolated there): not attainable"))
            if plan.kind == "height":
                climbing = plan.end_h > plan.start_h
                wrong = np.flatnonzero((rate[sl] <= 0) if climbing else (rate[sl] >= 0))
                if wrong.size:
                    verb = "climb" if climbing else "descend"
                    what = ("the rate of climb is not attainable" if plan.solve_x
                            else f"cannot {verb} at throttle {plan.throttle:g}")
                    problems.append((int(wrong[0]), what))
                if plan.solve_x and np.any(np.abs(plan.rate) >= v[sl]):
                    k0 = int(np.argmax(np.abs(plan.rate) >= v[sl]))
                    problems.append((k0, f"a {'climb' if climbing else 'descent'} at "
                                     f"{abs(plan.rate):g} m/s is steeper than vertical at "
                                     f"{v[a + k0]:.1f} m/s true airspeed: not attainable"))
                if plan.solve_x and not climbing:
                    steep = np.flatnonzero(idle[sl] > 1e-9)
                    if steep.size:
                        problems.append((int(steep[0]), f"needs less than idle thrust to descend "
                                         f"at {-plan.rate:g} m/s"))
                # only the nodes flown: past a failure the integration runs on unphysical states
                flown = level_residual[sl][:min(problems)[0] if problems else None]
                if plan.rate_from_excess and np.any(flown > 1.0):
                    vertical.append(
                        f"{label}: thrust at throttle {plan.throttle:g} exceeds weight plus "
                        "drag: flown as a vertical climb (rate of climb at the airspeed); the "
                        "steady-climb model (L = W) does not hold there, the excess would "
                        "accelerate it")
            if problems and first_bad is None:
                k, why = min(problems)
                at = exact_at.get(why, float(t[a + k]))
                b = a + max(k, 1)  # the flight ends there: nothing after the event is flown
                if why.startswith("the pack reaches") and plan.kind == "time" and k > 0:
                    # the event between two nodes, exactly (the nodes are 1/64 segment apart),
                    # and the state there becomes the flight's last node
                    tau, end_s, end_a = self._cutoff_within(
                        plan, states[:, a], durations, theta, float(t[a + k - 1] - t[a]),
                        float(t[a + k] - t[a]))
                    at = float(t[a]) + tau

                    def put(arr: np.ndarray, value: Any, b: int = b) -> np.ndarray:
                        return np.concatenate(
                            [arr[..., :b], np.reshape(value, arr.shape[:-1] + (1,))], axis=-1)

                    q, e = put(q, end_s[:n]), put(e, end_s[n:2 * n])
                    h, dist = put(h, end_s[2 * n]), put(dist, end_s[2 * n + 1])
                    t, x, v, rate = (put(t, end_s[2 * n + 2]), put(x, end_a[0]),
                                     put(v, end_a[1]), put(rate, end_a[2]))
                    current, voltage = put(current, end_a[6:6 + n]), put(voltage,
                                                                         end_a[6 + n:6 + 2 * n])
                    power, segment_of = put(power, end_a[6 + 2 * n:6 + 3 * n]), put(
                        segment_of, plan.index)
                    b += 1
                first_bad, ended_at = a + k, at
                reason = f"{label}: {why} at {at:.1f} s ({at / 60:.2f} min into the mission)"
                if why.startswith("the pack reaches") and plan.kind != "time" and k > 0:
                    # between two nodes of a climb or descent (integrated over height, 1/64 of
                    # it apart): the flight, its history and ended_at_s end at the last node
                    # before the cut-off, and the reason says so (it named the node after,
                    # past the history's end)
                    ended_at = float(t[a + k - 1])
                    reason = (f"{label}: {why} between {ended_at:.1f} and {at:.1f} s "
                              f"({ended_at / 60:.2f}-{at / 60:.2f} min into the mission)")
                sl = slice(a, b)
                volt_live = voltage[live, sl]
            xs = x[sl]
            eas_flown = plan.eas
            if plan.solve_v:  # the mean EAS the throttle gave
                eas_flown = float(np.mean(v[sl] * np.sqrt(np.asarray(self._rho(h[sl]), dtype=float)
                                                          / 1.225)))
            segments.append(SegmentResult(
                index=plan.index, type=plan.type,
                time_s=float(t[b - 1] - t[a]), distance_m=float(dist[b - 1] - dist[a]),
                start_altitude_m=float(h[a]), end_altitude_m=float(h[b - 1]),
                airspeed_eas_m_s=eas_flown,
                charge_ah=tuple(float(q[i, b - 1] - q[i, a]) for i in range(n)),
                energy_wh=tuple(float(e[i, b - 1] - e[i, a]) for i in range(n)),
                min_voltage_v=float(np.nanmin(volt_live)) if volt_live.size else math.nan,
                max_throttle=float(np.nanmax(xs)) if live else None,
                dead_engine=self.engines[plan.dead] if plan.dead is not None else None,
            ))
            if first_bad is not None:
                end = b
                q, e, h, dist, t = q[:, :end], e[:, :end], h[:end], dist[:end], t[:end]
                x, v, rate, segment_of = x[:end], v[:end], rate[:end], segment_of[:end]
                current, voltage, power = current[:, :end], voltage[:, :end], power[:, :end]
                break
        landing = float(np.min(1.0 - q[:, -1] / self.capacity_ah))
        rho_h = np.asarray(self._rho(h), dtype=float) * np.ones_like(h)
        history = {"time_s": t, "segment": segment_of, "altitude_m": h, "distance_m": dist,
                   "airspeed_m_s": v, "airspeed_eas_m_s": v * np.sqrt(rho_h / 1.225),
                   "throttle": x, "climb_rate_m_s": rate}
        for i, name in enumerate(self.engines):
            history[f"current_a_{name}"] = current[i]
            history[f"voltage_v_{name}"] = voltage[i]
            history[f"charge_ah_{name}"] = q[i]
            history[f"charge_fraction_{name}"] = 1.0 - q[i] / self.capacity_ah
            history[f"power_w_{name}"] = power[i]
            history[f"energy_wh_{name}"] = e[i]
        return MissionResult(
            name=self.mission.name, segments=tuple(segments),
            landing_charge_fraction=landing if first_bad is None else math.nan,
            min_landing_charge_fraction=self.reserve, attainable=first_bad is None,
            reason=reason or (f"lands with {100 * landing:.1f} % charge (reserve "
                              f"{100 * self.reserve:g} %)"),
            engines=self.engines, history=history, solved=solved, ended_at_s=ended_at,
            cutoff_voltage_v=self.cutoff_v,
            warnings=(*self.start_notes, *self.battery.scaled_notes, *vertical,
                      *self._extrapolation_notes(v, segment_of)),
        )

    def _extrapolation_notes(self, v: np.ndarray, segment_of: np.ndarray) -> list[str]:
        """Per segment flown outside the thrust model's tested airspeeds: a note saying so
        (SPEC: extrapolation is said; a mission at 40 m/s said nothing; outside audit)."""
        low, high = self.case.propulsion.tested_airspeed_m_s
        outside = outside_tested_range(self.case.propulsion, v)
        notes = []
        # a set, not np.unique: numpy >= 2.3's unique imports numpy.ma (~20 ms of `check`)
        for k in sorted(set(np.asarray(segment_of)[outside].astype(int).tolist())):
            speeds = v[outside & (segment_of == k)]
            segment = self.mission.segments[k]
            span = (f"{speeds.min():.1f}" if round(speeds.min(), 1) == round(speeds.max(), 1)
                    else f"{speeds.min():.1f}-{speeds.max():.1f}")
            notes.append(f"segment {k + 1} ({segment.type}): thrust model extrapolated at "
                         f"{span} m/s true (tested {low:g}-{high:g} m/s)")
        return notes

    def _braking_engine(self, throttle: float, v: np.ndarray, h: np.ndarray,
                        live: list[int]) -> tuple[int, str] | None:
        """The first node of a level flight at a fixed ``throttle`` where a live engine's
        models give no thrust, or thrust on no power, and why (``None`` if none does).

        The other fan's extrapolated thrust can still balance the drag there, and the ESC
        clamp hides the power the pack would be "given back": a cruise at 99 m/s on one fan
        at -3.6 N and -448 W flew 66.9 min (outside audit). Unflown (NaN) nodes are skipped.
        """
        prop = self.case.propulsion
        rho = np.asarray(self._rho(h), dtype=float) * np.ones_like(v)
        sigma = density_ratio(prop, rho)
        for i in live:
            thrust = np.asarray(engine_thrust_n(prop.engines[i], throttle, v, sigma), dtype=float)
            power = np.asarray(self._modelled_power(i, throttle, v, rho), dtype=float)
            power = power * np.ones_like(v)
            bad = np.flatnonzero((thrust <= 0.0) | (power <= 0.0))
            if bad.size:
                k = int(bad[0])
                return k, (f"{self.engines[i]}'s models give {thrust[k]:.1f} N on "
                           f"{power[k]:.0f} W at throttle {throttle:g}, {v[k]:.1f} m/s "
                           "(extrapolated): a fan that makes no thrust, or thrust on no power, "
                           "flies no cruise")
        return None
