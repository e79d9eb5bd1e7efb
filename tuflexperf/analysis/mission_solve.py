"""``solve_for``: the longest duration of one segment that lands on the reserve.

References
----------
Issue 13 item 3 (``solve_for``); Press et al., *Numerical Recipes*, 3rd ed., 9.2 (regula
falsi, the Illinois variant) and 9.4 (Newton-Raphson).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tuflexperf.analysis.mission_equations import (
    SECONDS_PER_HOUR,
)
from tuflexperf.analysis.mission_results import MissionResult
from tuflexperf.errors import NotAttainable
from tuflexperf.models.aircraft import (
    true_airspeed_m_s,
)


class SolveFor:
    """``solve_for`` of :class:`tuflexperf.analysis.mission.MissionModel` (a mixin)."""

    n: int

    def _suffix_function(self, k: int) -> Any:
        """``(start, durations, theta) -> (landing state, aux at segment k's end, most charge
        per pack, least loaded voltage of a live engine [V])``.

        The mission from where segment ``k`` begins (``start``, its state) to the landing:
        what the duration of segment ``k`` changes, without the part before it. The least
        voltage is segment ``k``'s at its end and every later segment's at each of its nodes,
        each segment's live engines only (as :meth:`fly` checks the cut-off): a longer cruise
        before a one-engine loiter cuts off in the loiter, which segment ``k``'s end alone
        did not see (outside audit: ``solve_for`` answered a cruise the loiter then refused).
        """
        import casadi as ca

        if k not in self._suffixes:
            n = self.n
            start = ca.MX.sym("start", 2 * n + 3)
            durations, theta, par, tk = self._symbols()
            state, at_k, nodes, least = start, None, [start], []
            for plan in self.plans[k:]:
                if plan.kind == "event":
                    continue
                both, auxes, state = self._segment_graph(plan, state, durations, theta, par,
                                                         tk, nodes_aux=plan.index != k)
                nodes.extend(both)
                if plan.index == k:
                    at_k = auxes[-1][:, -1]
                aux = ca.horzcat(*auxes)
                least.extend(aux[6 + n + i, :].T for i in range(n) if i != plan.dead)
            # the most charge each pack gave at any node: beyond the model's knee (the pole of
            # the discharge curve) the charge stops rising and the answer means nothing
            drawn = ca.horzcat(*nodes)
            most = ca.vertcat(*(ca.mmax(drawn[i, :]) for i in range(n)))
            self._suffixes[k] = ca.Function(f"from_segment_{k}",
                                            [start, durations, theta, par, tk],
                                            [state, at_k, most, ca.mmin(ca.vertcat(*least))])
        return self._suffixes[k]

    def start_state(self, k: int, durations: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The state where segment ``k`` begins: charges [Ah], energies [Wh] per engine,
        height [m], distance [m], time [s], for ``durations`` [s] and ``theta``.

        References
        ----------
        SPEC 4 ("Mission file"): segments flown in order from full packs.
        """
        states = np.asarray(self._history(durations, theta, self.par, self.tk)[0], dtype=float)
        a = self.bounds[k][0]
        return states[:, a] if a < states.shape[1] else states[:, -1]

    def longest(self, k: int, durations: np.ndarray | None = None,
                theta: np.ndarray | None = None, guess_s: float | None = None,
                start: np.ndarray | None = None) -> tuple[float, str]:
        """Longest duration [s] of segment ``k`` that lands on the reserve without a cut-off.

        A rootfinder on ``g(T) = min_i landing_fraction_i(T) - reserve`` (it falls
        monotonically with the segment's duration ``T``), each evaluation one integration of
        the mission from where segment ``k`` begins (``start``, computed once if not given)
        to the landing. For the last segment, Newton with the slope from the state equations,
        ``dg/dT = -i_j / (3600 Q)`` at the landing for the engine ``j`` that lands with
        least charge (from ``guess_s``, e.g. a closed form); otherwise regula falsi
        (Illinois) on a bracket from ``T = 0``. If the packs are then below their cut-off
        voltage on the way to the landing, the same on ``min U(T) - U_cutoff`` instead (the
        least loaded voltage of a live engine from segment ``k``'s end on).
        Both to 1e-12 (fraction) and 1e-9 V. Returns the duration and what ends it:
        ``"landing reserve"`` or ``"cut-off"``. Raises :class:`NotAttainable` when no
        positive duration does.

        References
        ----------
        Issue 13 item 3 (``solve_for``); Press et al., *Numerical Recipes*, 3rd ed., 9.2
        (regula falsi, the Illinois variant) and 9.4 (Newton-Raphson).
        """
        n = self.n
        d = (self.durations if durations is None else np.asarray(durations, float)).copy()
        th = self.theta if theta is None else np.asarray(theta, dtype=float)
        plan = self.plans[k]
        f = self._suffix_function(k)
        x0 = self.start_state(k, d, th) if start is None else start
        last = all(p.kind == "event" for p in self.plans[k + 1:])

        pole = self.packs * self.params.max_capacity_ah
        memo: dict[float, tuple[float, float, float]] = {}

        def at(tau: float) -> tuple[float, float, float]:
            if tau not in memo:
                memo[tau] = evaluate(tau)
            return memo[tau]

        def evaluate(tau: float) -> tuple[float, float, float]:
            d[k] = tau
            end, aux, most, least = (np.asarray(v, dtype=float).ravel()
                                     for v in f(x0, d, th, self.par, self.tk))
            if not (np.all(np.isfinite(end)) and np.all(most <= end[:n] + 1e-12)
                    and np.all(most < pole)):
                return -1.0, math.nan, -1.0  # the packs were emptied on the way: beyond
            frac = 1.0 - end[:n] / self.capacity_ah
            j = int(np.argmin(frac))
            volt = float(least[0])  # a live engine's, to the landing (_suffix_function)
            slope = -aux[6 + j] / SECONDS_PER_HOUR / self.capacity_ah
            return float(frac[j] - self.reserve), float(slope), float(volt - self.cutoff_v)

        def illinois(which: int, low: float, high: float, f_low: float, f_high: float
                     ) -> float | None:
            side = 0
            for _ in range(200):
                c = high - f_high * (high - low) / (f_high - f_low)
                fc = at(c)[which]
                if not math.isfinite(fc):
                    c, fc = 0.5 * (low + high), at(0.5 * (low + high))[which]
                if abs(fc) <= (1e-12 if which == 0 else 1e-10) or high - low <= 1e-9 * high:
                    return c
                if fc > 0:
                    low, f_low = c, fc
                    f_high = 0.5 * f_high if side == 1 else f_high
                    side = 1
                else:
                    high, f_high = c, fc
                    f_low = 0.5 * f_low if side == -1 else f_low
                    side = -1
            return None

        def bracket(which: int, tau: float, f_tau: float
                    ) -> tuple[float, float, float, float] | None:
            # from a point with f > 0 forwards until f < 0 (finite), by doubling the step
            step = max(tau, 60.0)
            for _ in range(40):
                high = tau + step
                f_high = at(high)[which]
                if math.isfinite(f_high) and f_high < 0:
                    return tau, f_tau, high, f_high
                if not math.isfinite(f_high):
                    step *= 0.5
                else:
                    tau, f_tau, step = high, f_high, 2 * step
            return None

        tau: float | None = None
        if last and guess_s is not None:  # Newton from the guess
            tau = max(guess_s, 1.0)
            g, slope, _ = at(tau)
            for _ in range(50):
                if not (math.isfinite(g) and slope < 0):
                    tau = None
                    break
                step = -g / slope
                tau = max(tau + step, 0.5 * tau)
                g, slope, _ = at(tau)
                if abs(g) <= 1e-12 and abs(step) <= 1e-6 * max(tau, 1.0):
                    break
            else:
                tau = None
        if tau is None:  # regula falsi on a bracket from a segment of no duration
            zero = at(0.0)
            if zero[0] >= 0 and zero[2] >= 0:
                found = bracket(0, 0.0, zero[0])
                tau = None if found is None else illinois(0, found[0], found[2], found[1],
                                                          found[3])
        ends = "landing reserve"
        if tau is not None and at(tau)[2] < 0:  # the pack cuts off before the reserve
            ends = "cut-off"
            zero = at(0.0)
            tau = illinois(2, 0.0, tau, zero[2], at(tau)[2]) if zero[2] >= 0 else None
        if tau is None or not tau > 0 or at(tau)[0] < -1e-8:
            # the rest of the mission flown as it is: a segment before this one that empties
            # the packs is named with its own time, not blamed on this one with "-80 %" left
            # (the marker of an emptied pack; outside audit)
            d[k] = 0.0
            rest = self.fly(d)
            label = f"segment {k + 1} ({plan.type})"
            if not rest.attainable:
                raise NotAttainable(f"{rest.reason} (flown with {label}, the one solved for, "
                                    "of no duration: no duration of it lands)")
            raise NotAttainable(
                f"{label}: no duration lands with the reserve {100 * self.reserve:g} % before "
                f"the cut-off (the rest of the mission alone leaves "
                f"{100 * rest.landing_charge_fraction:.1f} %)"
            )
        return tau, ends

    def solve_for(self) -> MissionResult:
        """Longest duration of the ``solve_for`` segment that lands exactly on the reserve.

        See :meth:`longest`; the answer is then flown as a plain mission.
        """
        k = self.mission.solve_for
        assert k is not None
        plan = self.plans[k]
        answer, ends = self.longest(k)
        final = self.durations.copy()
        final[k] = answer
        # the file's own time (or distance) of the segment: the plan the verdict holds it to
        # (a PASS "landing on the reserve" of a 0.47 min cruise planned at 8 min; outside audit)
        solved = {"segment": plan.type, "index": k, "time_min": answer / 60.0,
                  "ends_at": ends, "written_time_min": float(self.durations[k]) / 60.0}
        if plan.eas is not None:
            v_true = float(true_airspeed_m_s(plan.eas, self._rho(plan.start_h)))
            solved["distance_km"] = answer * v_true / 1000.0
            if self.mission.segments[k].distance_km is not None:
                solved["written_distance_km"] = self.mission.segments[k].distance_km
        return self.fly(final, solved)
