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
from numpy.typing import NDArray

from tuflexperf.analysis.mission_equations import (
    SECONDS_PER_HOUR,
)
from tuflexperf.analysis.mission_results import MissionResult
from tuflexperf.errors import NotAttainable
from tuflexperf.models.aircraft import (
    true_airspeed_m_s,
)

Array = NDArray[np.float64]


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
        to the landing; then, if the packs are below their cut-off voltage on the way, on the
        least loaded voltage instead: :func:`longest_rows`, a batch of one (Newton from
        ``guess_s``, e.g. a closed form, else from the segment's own duration). Returns the
        duration and what ends it: ``"landing reserve"`` or ``"cut-off"``. Raises
        :class:`NotAttainable` when no positive duration does.

        References
        ----------
        Issue 13 item 3 (``solve_for``); Press et al., *Numerical Recipes*, 3rd ed., 9.2
        (regula falsi, the Illinois variant) and 9.4 (Newton-Raphson).
        """
        d = (self.durations if durations is None else np.asarray(durations, float)).copy()
        th = self.theta if theta is None else np.asarray(theta, dtype=float)
        plan = self.plans[k]
        x0 = self.start_state(k, d, th) if start is None else start
        guess = d.copy()
        if guess_s is not None:  # Newton from it (else from the segment's own duration)
            guess[k] = guess_s
        suffix = self._suffix_function(k)
        zeros = np.zeros(self.tk.shape)  # the suffix flies no take-off

        def flown(start: Array, d: Array, theta: Array, par: Array) -> tuple[Array, ...]:
            return tuple(np.asarray(x, dtype=float)
                         for x in suffix(start, d, theta, par, zeros))

        found, cut = longest_rows(
            self, k, np.asarray(x0, dtype=float).reshape(-1, 1), guess[:, None], th[:, None],
            np.asarray(self.par, dtype=float).reshape(-1, 1), np.array([self.reserve]),
            np.array([self.cutoff_v]), np.array([self.capacity_ah]),
            np.array([self.packs * self.params.max_capacity_ah]), flown)
        tau = float(found[0])
        ends = "cut-off" if cut[0] else "landing reserve"
        if not math.isfinite(tau):
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


def longest_rows(model: Any, k: int, start: Array, durations: Array, theta: Array,
                 par: Array, reserve: Array, cutoff: Array, capacity_ah: Array, pole_ah: Array,
                 suffix: Any) -> tuple[Array, NDArray[np.bool_]]:
    """Per row the longest duration [s] of segment ``k`` that lands on the reserve without a
    cut-off (NaN where none does), and where the cut-off ends it: from where segment ``k``
    begins (``start``, ``(state, B)``), per row the ``reserve`` [-], the packs' ``cutoff``
    [V], the charge per engine the landing fraction counts and the pole of the circuit's
    knee [Ah]. ``suffix(start, durations, theta, par)`` flies the mission from segment ``k``
    on for columns of rows, as :meth:`SolveFor._suffix_function` (landing state, aux at
    segment ``k``'s end, most charge per pack, least loaded voltage): the single case's
    CasADi function (a batch of one, :meth:`SolveFor.longest`) or the numpy rows
    (:func:`tuflexperf.analysis.mission_rows.suffix_rows`).

    Vectorised over the rows, never a loop of them: each step evaluates the rows not yet
    converged at once. Newton with the state
    equations' slope ``-i_j / (3600 Q)`` (exact for the last segment, a close guess before
    it) from the file's duration, safeguarded by the bracket it keeps (regula falsi,
    Illinois, where a step leaves it); then, where the packs cut off first, regula falsi on
    the least loaded voltage over ``[0, T]``: to 1e-12 (fraction) and 1e-10 V.

    References
    ----------
    Press et al., *Numerical Recipes*, 3rd ed., 9.2 (Illinois), 9.4 (safeguarded Newton).
    """
    size = start.shape[1]
    n = model.n

    def at(rows: Array, tau: Array) -> tuple[Array, Array, Array]:
        if not rows.size:  # no row left to fly
            return np.zeros(0), np.zeros(0), np.zeros(0)
        d = durations[:, rows].copy()
        d[k] = tau
        end, aux, most, least = suffix(start[:, rows], d, theta[:, rows], par[:, rows])
        least = np.reshape(least, (1, -1))
        with np.errstate(invalid="ignore"):
            valid = (np.all(np.isfinite(end), axis=0) & np.all(most <= end[:n] + 1e-12, axis=0)
                     & np.all(most < pole_ah[rows], axis=0))
            frac = 1.0 - end[:n] / capacity_ah[rows]
            j = np.argmin(np.where(np.isfinite(frac), frac, np.inf), axis=0)
            cols = np.arange(rows.size)
            g = np.where(valid, frac[j, cols] - reserve[rows], -1.0)
            slope = np.where(valid, -aux[6 + j, cols] / SECONDS_PER_HOUR
                             / capacity_ah[rows], np.nan)
            volt = np.where(valid, least[0] - cutoff[rows], -1.0)
        return g, slope, volt

    every = np.flatnonzero(np.all(np.isfinite(start), axis=0))
    tau, g0, v0 = np.full(size, np.nan), np.full(size, np.nan), np.full(size, np.nan)
    g0[every], _, v0[every] = at(every, np.zeros(every.size))
    # landing short with none of it, or cut off: no duration lands
    every = every[(g0[every] >= 0) & (v0[every] >= 0)]
    tau[every] = _root(lambda rows, x: at(rows, x)[:2], every, g0, durations[k], 1e-12)
    volts = np.full(size, np.nan)
    found = every[np.isfinite(tau[every])]
    volts[found] = at(found, tau[found])[2]
    cut = found[volts[found] < 0]  # the packs cut off before the reserve: on the voltage
    if cut.size:
        tau[cut] = _root(lambda rows, x: (at(rows, x)[2], np.full(rows.size, np.nan)), cut,
                         v0, tau, 1e-10, high=(tau.copy(), volts))
    good = np.isfinite(tau) & (tau > 0)
    checked = np.flatnonzero(good)
    if checked.size:
        good[checked] &= at(checked, tau[checked])[0] >= -1e-8
    cut_off = np.zeros(size, dtype=bool)
    cut_off[cut] = True
    return np.where(good, tau, np.nan), cut_off


def _root(f: Any, rows: Array, at_zero: Array, guess: Array, tolerance: float,
          high: tuple[Array, Array] | None = None) -> Array:
    """Per row of ``rows``, the root ``x > 0`` of a falling ``f(rows, x) -> (value, slope)``
    with ``f(0) = at_zero >= 0``: safeguarded Newton from ``guess`` (slope NaN: regula falsi,
    Illinois) inside the bracket it keeps, to ``0 <= f <= tolerance`` or a bracket of 1e-12
    relative (its end with ``f >= 0``); ``high`` a known point and its value ``f < 0`` per
    row. Arrays over all rows; NaN where none is found in 200 steps."""
    size = at_zero.size
    low, f_low = np.zeros(size), np.array(at_zero, dtype=float)
    top = np.full(size, np.inf) if high is None else np.array(high[0], dtype=float)
    f_top = np.full(size, np.nan) if high is None else np.array(high[1], dtype=float)
    side = np.zeros(size)
    x = np.maximum(np.asarray(guess, dtype=float) * np.ones(size), 1.0)
    if high is not None:  # regula falsi on the bracket from the start
        with np.errstate(invalid="ignore", divide="ignore"):
            x = top - f_top * top / (f_top - f_low)
    answer = np.full(size, np.nan)
    active = np.array(rows)
    for _ in range(200):
        if not active.size:
            break
        value, slope = f(active, x[active])
        # on the safe side only: a duration a hair past the root lands 1e-12 short of the
        # reserve, and a verdict that compares the landing with it then fails
        done = (value >= 0.0) & (value <= tolerance)
        above = ~done & (value > 0)
        below = ~done & ~above
        a, b = active[above], active[below]
        # Illinois: halve the kept end's value when the same end moves twice
        f_top[a] = np.where(side[a] == 1, 0.5 * f_top[a], f_top[a])
        f_low[b] = np.where(side[b] == -1, 0.5 * f_low[b], f_low[b])
        low[a], f_low[a], side[a] = x[a], value[above], 1
        top[b], f_top[b], side[b] = x[b], value[below], -1
        narrow = np.isfinite(top[active]) & (top[active] - low[active] <= 1e-12 * top[active])
        answer[active[done]] = x[active[done]]
        answer[active[narrow & ~done]] = low[active[narrow & ~done]]  # its safe end
        active, value, slope = (active[~(done | narrow)], value[~(done | narrow)],
                                slope[~(done | narrow)])
        with np.errstate(invalid="ignore", divide="ignore"):
            newton = x[active] - value / slope
            falsi = top[active] - f_top[active] * (top[active] - low[active]) / (
                f_top[active] - f_low[active])
            bounded = np.isfinite(top[active])
            inside = np.isfinite(newton) & (newton > low[active]) & (
                newton < np.where(bounded, top[active], np.inf))
            unbracketed = np.where(np.isfinite(newton) & (newton > low[active]), newton,
                                   2.0 * np.maximum(x[active], 60.0))
            step = np.where(inside, newton, np.where(
                bounded, np.where(np.isfinite(falsi) & (falsi > low[active])
                                  & (falsi < top[active]), falsi,
                                  0.5 * (low[active] + top[active])), unbracketed))
        x[active] = step
    return answer[rows]
