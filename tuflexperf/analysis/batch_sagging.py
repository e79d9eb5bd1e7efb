"""The batch's endurance flight on sagging packs: the propulsion's ``reference_voltage_v``.

With a reference voltage the single case flies its endurance mission with each fan's
thrust ``T (U/U_ref)^k`` and power ``P (U/U_ref)^(1.5 k)`` at its packs' loaded voltage
``U`` (:class:`tuflexperf.analysis.mission.MissionModel`): the roll follows the take-off
on the sagging packs, the climb's rate follows the loaded thrust, and the cruise's airspeed
falls as the packs sag. The constant-power batch (:mod:`.batch_endurance`) took the
reference voltage's figures throughout, so its endurance differed from the single case's
(18.5 against 16.2 min for a reference of 44 V; P(met) 1.0 where the case FAILed).

Here the same flight is flown per row, vectorised: the roll (the take-off's on the packs,
:mod:`.batch_takeoff_packs`, its 101 nodes), the rotation (8 RK4 steps), the climb
(64 steps over height) and the cruise (RK4 in time, steps of 1/64 of the constant-power
estimate, until the first fan's packs reach the landing reserve or the cut-off, the end
between two nodes by cubic Hermite interpolation of the charges). Every stage solves each
fan's loaded voltage (:func:`tuflexperf.analysis.pack_limits.operating_point`) and, in
the cruise, the fast level-flight airspeed at it (secant from the stage before). The
flight is not attainable where the single case's is not: a node below the cut-off, below
stall, off level flight, beyond the jet velocity, a climb that does not climb, or a pack
beyond its rating.

References
----------
SPEC 3 (thrust and pack voltage); paper section 4 (endurance estimate); Hairer, Norsett &
Wanner, *Solving Ordinary Differential Equations I*, II.6 (dense output by Hermite
interpolation).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.airborne import ROTATION_STEPS
from tuflexperf.analysis.batch_kernels import best_climb, fan_power_rows, illinois
from tuflexperf.analysis.constants import BURST_OVER_CONTINUOUS, RATING_SEGMENT_S, STEPS
from tuflexperf.analysis.pack_limits import PackRows, operating_point
from tuflexperf.models.aircraft import level_flight_drag_n
from tuflexperf.models.battery import SECONDS_PER_HOUR, first_window_beyond
from tuflexperf.models.powertrain import beyond_jet_velocity

Array = NDArray[np.float64]

_BRACKET = 2e-3  # about the stage before's airspeed: a cruise step changes it less
_WIDENINGS = 40
_ILLINOIS_STEPS = 100
_SECANT_STEPS = 8
_LEVEL = 1e-9  # (T - D)/W of level flight, the mission's test
_NEAR_STEP = 0.05  # a guess this near a tested end (relative) looks for the step there
# the airspeeds just inside and just beyond a tested end's step (outside_tested_range's slack)
_STEP_BELOW, _STEP_ABOVE = 0.5e-9, 2e-9
_MAX_CRUISE_STEPS = 16 * STEPS  # a sag that lengthens the cruise 16-fold is no cruise here
_END_STEPS = 40  # Illinois steps on the cut-off within the last cruise step
_CUTOFF_SLACK_V = 1e-9  # a node this near its cut-off [V] holds (the mission integrator's)


@dataclass(frozen=True)
class _Step:
    """The thrust's step at a tested end: the airspeeds [m/s] just inside and beyond it, the
    level-flight residuals there, and per row where the fast root lies (the fast root is the
    greatest: beyond the step wherever the excess is still positive there)."""

    below: float
    above: float
    f_below: Array
    f_above: Array
    beyond: NDArray[np.bool_]
    here: NDArray[np.bool_]
    under: NDArray[np.bool_]


@dataclass
class _Nodes:
    """The flight's history per row: times [s], charge per fan [Ah], current per fan [A]."""

    time: list[Array]
    charge: list[Array]
    current: list[Array]

    def add(self, t: Array, q: Array, current: Array) -> None:
        self.time.append(t.copy())
        self.charge.append(q.copy())
        self.current.append(current.copy())


class SaggingFlight:
    """Launch and cruise of a batch's rows with each fan at its packs' loaded voltage.

    ``m`` the batch's physics (``analysis.batch_model.BatchModel``), ``model`` its battery side
    (``batch_endurance.battery_side``), ``rows`` the rows' packs, ``engines`` the fans
    flown (``(None,)``: one power model for all, so one set of packs stands for each).
    """

    def __init__(self, m: Any, model: Any, rows: PackRows, engines: tuple[Any, ...]) -> None:
        self.m, self.model, self.rows, self.engines = m, model, rows, engines
        prop = m.propulsion
        self.u_ref, self.k = prop.reference_voltage_v, prop.voltage_exponent
        self.weight = np.asarray(m.aircraft.weight_n, dtype=float).reshape(-1) * np.ones(m.size)
        self.mass = np.asarray(m.aircraft.mass_kg, dtype=float).reshape(-1) * np.ones(m.size)
        self.pole = rows.circuit_packs * model.params.max_capacity_ah
        self.active = np.ones(m.size, dtype=bool)  # the rows still flown (the cruise's)
        self.cut_first = np.zeros(m.size, dtype=bool)  # the cut-off before the reserve

    # -- one point --------------------------------------------------------------------------
    def _above_cutoff(self, u: Array) -> NDArray[np.bool_]:
        """Per row: every fan's loaded voltage ``u`` [V] ``(fans, rows)`` at or above its
        cut-off, within the mission's slack (NaN: beyond the packs' power, not above)."""
        with np.errstate(invalid="ignore"):
            return np.all(u >= self.rows.cutoff_v - _CUTOFF_SLACK_V, axis=0)

    def reference(self, throttle: Any, speeds: Array) -> tuple[Array, Array]:
        """The packs' power [W] and the thrust [N] per fan flown (for ``(None,)`` the total
        of all engines) at the reference voltage at ``throttle`` [-] and ``speeds`` [m/s]
        ``(B, K)``, ``(fans, B, K)`` each: they depend on the airspeed alone, so a roll's
        stages or an arc's iterations take them once (:meth:`loaded`)."""
        m = self.m
        power = np.stack([np.asarray(fan_power_rows(self.model, m, throttle, speeds, e),
                                     dtype=float) * np.ones_like(speeds) for e in self.engines])
        # each fan's own thrust (the total less the others' took three totals for two fans)
        thrusts = (m.thrust(throttle, speeds)[None] if self.engines == (None,) else np.stack(
            [m.engine_thrust(j, throttle, speeds) for j in range(len(self.engines))]))
        return power, thrusts * np.ones_like(speeds)

    def loaded(self, power: Array, thrusts: Array, charge: Array
               ) -> tuple[Array, Array, Array, Array]:
        """At :meth:`reference`'s ``power`` and ``thrusts`` after ``charge`` [Ah] drawn per
        fan: the live thrust [N], and per fan the loaded voltage [V], the current through its
        packs [A] and the thrust factor ``(U/U_ref)^k`` [-] (``(fans, B)`` or ``(fans, B, K)``)."""
        rows = self.rows
        circuit = rows.circuit_packs.reshape(-1, *([1] * (np.ndim(power) - 2)))  # per row
        u, per_pack, factor = operating_point(self.model.params, charge, power, circuit,
                                              rows.packs_per_engine, self.u_ref, self.k)
        return np.sum(factor * thrusts, axis=0), u, per_pack * rows.packs_per_engine, factor

    def point(self, throttle: Any, speed: Array, charge: Array
              ) -> tuple[Array, Array, Array, Array]:
        """At ``throttle`` [-] and true airspeed ``speed`` [m/s] per row with ``charge`` [Ah]
        drawn per fan ``(fans, rows)``: the live thrust [N] per row, and per fan the loaded
        voltage [V], the current through its packs [A] and the electrical power [W]."""
        # one throttle per row: a column against the rows' airspeeds
        x = np.reshape(throttle, (-1, 1)) if np.ndim(throttle) else throttle
        power, thrusts = (a[..., 0] for a in self.reference(x, speed.reshape(-1, 1)))
        thrust, u, current, factor = self.loaded(power, thrusts, charge)
        return thrust, u, current, power * factor ** 1.5

    def _drag(self, speed: Array) -> Array:
        return np.asarray(level_flight_drag_n(self.m.aircraft, speed.reshape(-1, 1),
                                              self.m.density), dtype=float).reshape(-1) \
            * np.ones(self.m.size)

    def level_speed(self, throttle: Array, charge: Array, guess: Array) -> tuple[Array, Array]:
        """The fast level-flight airspeed [m/s] at the packs' loaded voltage and whether it
        is level flight (a residual ``(T - D)/W`` within 1e-9, or a bracket closed on a step
        of the thrust: the batch's extrapolation error begins at the tested range's end,
        where no airspeed gives ``T = D`` exactly).

        Secant steps from ``guess`` (the root of the stage before: a cruise step moves it by
        ~0.1 %, rounding in 3-5 steps); rows it leaves unconverged are bracketed about the
        guess and refined by the Illinois variant of regula falsi.
        """
        def residual(v: Array) -> Array:
            return (self.point(throttle, v, charge)[0] - self._drag(v)) / self.weight

        floor, ceiling = np.zeros_like(guess), np.full_like(guess, np.inf)
        on_step = np.zeros(guess.shape, dtype=bool)
        step_v = np.zeros_like(guess)
        if self.m.extrapolation_n is not None:
            # near a step of the thrust the root is on it, or the secant keeps to its side
            for end in self.m.propulsion.tested_airspeed_m_s:
                near = self.active & (np.abs(guess - end) < _NEAR_STEP * max(end, 1.0))
                if not near.any():
                    continue
                step = self._thrust_step(residual, end, near)
                step_v = np.where(step.here, np.where(np.abs(step.f_below)
                                                      <= np.abs(step.f_above),
                                                      step.below, step.above), step_v)
                on_step |= step.here
                floor = np.where(step.beyond, step.above, floor)
                ceiling = np.where(step.under, step.below, ceiling)
        start = np.clip(guess, floor, ceiling)
        v0, v1 = start, np.clip(start * (1.0 + 1e-7), floor, ceiling)
        v1 = np.where(v1 == v0, start * (1.0 - 1e-7), v1)
        r0, r1 = residual(v0), residual(v1)
        for _ in range(_SECANT_STEPS):
            with np.errstate(divide="ignore", invalid="ignore"):
                v2 = np.clip(v1 - r1 * (v1 - v0) / (r1 - r0), floor, ceiling)
            moving = (np.isfinite(v2) & (r1 != r0) & (v2 > 0.0) & ~(np.abs(r1) < 1e-15)
                      & ~on_step)
            if not (moving & self.active).any():
                break
            v0, r0 = v1, r1
            v1 = np.where(moving, v2, v1)
            r1 = np.where(moving, residual(v1), r1)
        v1 = np.where(on_step, step_v, v1)
        with np.errstate(invalid="ignore"):
            done = (np.abs(r1) < _LEVEL) | on_step
        if not (~done & self.active).any():
            return v1, done
        # only the rows the secant left matter (the others keep v1): a row without level
        # flight no longer holds every row's bracket to its 40 widenings and 100 steps
        v, level = self._bracketed_level_speed(residual, guess, ~done & self.active)
        return np.where(done, v1, v), done | level

    def _thrust_step(self, residual: Any, end: float, rows: NDArray[np.bool_]) -> _Step:
        """:class:`_Step` at the tested end ``end`` [m/s] for ``rows``: the samples'
        extrapolation error begins there, and no airspeed may give ``T = D`` exactly."""
        below, above = end + _STEP_BELOW, end + _STEP_ABOVE
        f_below = residual(np.full(self.m.size, below))
        f_above = residual(np.full(self.m.size, above))
        beyond = rows & (f_above >= 0.0)
        here = rows & ~beyond & (f_below >= 0.0)
        return _Step(below, above, f_below, f_above, beyond, here, rows & ~beyond & ~here)

    def _bracketed_level_speed(self, residual: Any, guess: Array,
                               need: NDArray[np.bool_]) -> tuple[Array, Array]:
        """:meth:`level_speed` by bracket and Illinois (the secant's fallback) for the rows
        ``need``; the other rows' answers are not used."""
        low, high = guess * (1.0 - _BRACKET), guess * (1.0 + _BRACKET)
        f_low, f_high = residual(low), residual(high)
        for _ in range(_WIDENINGS):  # the fast root: excess above it falls below zero
            short = (~(f_low >= 0.0) | ~(f_high < 0.0)) & need
            if not short.any():
                break
            width = high - low
            wider = np.where(f_low >= 0.0, low, np.maximum(low - width, 1e-3 * guess))
            higher = np.where(f_high < 0.0, high, high + width)
            lower, upper = (need & (wider != low)).any(), (need & (higher != high)).any()
            if not (lower or upper):
                break  # low at its floor, high past the root: every further widening the same
            if lower:  # an end no row needed moved keeps its residual
                low, f_low = wider, residual(wider)
            if upper:
                high, f_high = higher, residual(higher)
        bracketed = (f_low >= 0.0) & (f_high < 0.0)
        if self.m.extrapolation_n is not None:
            # a bracket across a step of the thrust: narrowed to the root's side, or closed on
            # the step where the root is there
            for end in self.m.propulsion.tested_airspeed_m_s:
                across = bracketed & (low < end + _STEP_BELOW) & (high > end + _STEP_ABOVE)
                if not across.any():
                    continue
                step = self._thrust_step(residual, end, across)
                low = np.where(step.beyond, step.above, np.where(step.here, step.below, low))
                f_low = np.where(step.beyond, step.f_above,
                                 np.where(step.here, step.f_below, f_low))
                high = np.where(step.here, step.above, np.where(step.under, step.below, high))
                f_high = np.where(step.here, step.f_above,
                                  np.where(step.under, step.f_below, f_high))
        low, high, f_low, f_high = illinois(residual, low, high, f_low, f_high,
                                            bracketed & need & ~(high - low <= 1e-9 * high),
                                            _ILLINOIS_STEPS)
        nearer = np.abs(f_low) <= np.abs(f_high)
        v = np.where(nearer, low, high)
        level = bracketed & ((np.where(nearer, np.abs(f_low), np.abs(f_high)) < _LEVEL)
                             | (high - low <= 1e-9 * high))
        return v, level

    # -- the launch -----------------------------------------------------------------------
    def launch(self, roll: tuple[Array, Array, Array, Array], climb_speed: Array,
               height: Array, ok: NDArray[np.bool_], catapult: bool
               ) -> tuple[Array, Array, NDArray[np.bool_], _Nodes]:
        """Roll, rotation and full-throttle climb to ``height`` [m] at ``climb_speed`` [m/s]:
        the charge per fan after it [Ah], the climb time [s], where it held, its nodes."""
        m, fans = self.m, len(self.engines)
        q = np.zeros((fans, m.size))
        t = np.zeros(m.size)
        nodes = _Nodes([], [], [])
        _, roll_time, v_lo, _ = roll
        v_lo = np.where(ok, v_lo, 1.0)
        held = ok.copy()

        def check(u: Array, current: Array, charge: Array) -> None:
            nonlocal held
            with np.errstate(invalid="ignore"):
                held &= self._above_cutoff(u)
                held &= np.all(np.isfinite(charge) & (charge < self.pole), axis=0)
                held &= np.all(np.isfinite(current) & (current >= 0.0), axis=0)

        if not catapult:
            rotation = np.asarray(m.aircraft.takeoff.rotation_time_s, dtype=float).reshape(-1) \
                * np.ones(m.size)
            # the roll as the take-off flew it on the sagging packs (batch_takeoff_packs: its
            # charge within 1e-13 of solve_ivp's, where 64 RK4 steps in time along its airspeed
            # history were 3e-8 off): its 101 nodes, each node's current at its airspeed
            flown = m.packs_roll
            t_hist = np.where(ok[:, None], np.nan_to_num(flown.history_time), 0.0)
            q_hist = np.where(ok[None, :, None], np.nan_to_num(flown.history_charge_ah), 0.0)
            v_hist = v_lo[:, None] * np.linspace(0.0, 1.0, t_hist.shape[1])[None, :]
            for k in range(t_hist.shape[1]):
                _, u, current, _ = self.point(1.0, v_hist[:, k], q_hist[:, :, k])
                nodes.add(t_hist[:, k], q_hist[:, :, k], current)
                check(u, current, q_hist[:, :, k])
            q, t = q_hist[:, :, -1], t_hist[:, -1]

            def full_throttle(charge: Array, v: Array) -> tuple[Array, Array, Array]:
                """The rotation's rates in time: dq/dt [Ah/s], dt/dt, U [V]."""
                _, u, current, _ = self.point(1.0, v, charge)
                return current / SECONDS_PER_HOUR, np.ones(m.size), u

            # the rotation at the lift-off speed, in time
            constant = [np.stack([v_lo] * 3)] * ROTATION_STEPS
            q, t = self._rk4(q, t, np.where(ok, rotation, 0.0) / ROTATION_STEPS, constant,
                             full_throttle, nodes, check, first_speed=v_lo)
        # the climb over height at the full-throttle rate of the loaded packs
        climbing_rows = ok & (height > 0)
        dh = np.where(climbing_rows, height, 0.0) / STEPS
        climb_v = np.where(ok, climb_speed, 1.0)
        t_climb0 = t.copy()

        def climbing(charge: Array, v: Array) -> tuple[Array, Array, Array]:
            nonlocal held
            thrust, u, current, _ = self.point(1.0, v, charge)
            rate = (thrust - self._drag(v)) * v / self.weight
            held &= ~(climbing_rows & ~(rate > 0.0))
            dt_dh = 1.0 / np.maximum(rate, 1e-6)
            return current / SECONDS_PER_HOUR * dt_dh, dt_dh, u

        q, t = self._rk4(q, t, dh, [np.stack([climb_v] * 3)] * STEPS, climbing, nodes,
                         check, first_speed=climb_v)
        return q, np.where(height > 0, t - t_climb0, 0.0), held, nodes

    def _rk4(self, q: Array, t: Array, step: Array, speeds: list[Array], rate: Any,
             nodes: _Nodes, check: Any, first_speed: Array) -> tuple[Array, Array]:
        """RK4 of ``dq/ds = rate(q, v)[0]``, ``dt/ds = rate(q, v)[1]`` over steps ``step``
        of the variable ``s`` (time, the analysis's time, height), each step's airspeeds
        (start, middle, end) in ``speeds``; the nodes are recorded and ``check``ed (the
        flight's first node where the history is empty, at ``first_speed``)."""
        if not nodes.time:
            k1, dt1, u = rate(q, first_speed)
            nodes.add(t, q, k1 * SECONDS_PER_HOUR / np.where(dt1 > 0, dt1, 1.0))
            check(u, k1, q)
        for v0, vm, v1 in speeds:
            k1, dt1, _ = rate(q, v0)
            k2, dt2, _ = rate(q + 0.5 * step * k1, vm)
            k3, dt3, _ = rate(q + 0.5 * step * k2, vm)
            k4, dt4, _ = rate(q + step * k3, v1)
            q = q + step / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            t = t + step / 6.0 * (dt1 + 2 * dt2 + 2 * dt3 + dt4)
            k_end, dt_end, u = rate(q, v1)
            nodes.add(t, q, k_end * SECONDS_PER_HOUR / dt_end)
            check(u, k_end, q)
        return q, t

    # -- the cruise -----------------------------------------------------------------------
    def cruise(self, throttle: Array, start: Array, t0: Array, speed: Array,
               estimate_s: Array, ok: NDArray[np.bool_], nodes: _Nodes
               ) -> tuple[Array, NDArray[np.bool_]]:
        """The cruise at ``throttle`` from ``start`` [Ah per fan] at time ``t0`` [s] until
        the first fan reaches the landing reserve or the cut-off: its time [s] and where it
        is attainable. ``speed`` [m/s] starts the airspeed's secant, ``estimate_s`` [s] (the
        constant-power cruise) sizes the steps."""
        m, rows = self.m, self.rows
        least = m.least_airspeed()
        density = np.asarray(m.density, dtype=float).reshape(-1, 1)
        h = np.where(ok, np.maximum(np.nan_to_num(estimate_s), 1.0), 1.0) / STEPS
        going, held = ok.copy(), ok.copy()
        q, t, v = start.copy(), t0.copy(), np.where(ok, speed, 1.0)

        def state(charge: Array, guess: Array) -> tuple[Array, ...]:
            v_here, level = self.level_speed(throttle, charge, guess)
            thrust, u, current, _ = self.point(throttle, v_here, charge)
            return v_here, level, u, current, thrust

        def flyable(v_here: Array, level: Array, thrust: Array) -> NDArray[np.bool_]:
            with np.errstate(invalid="ignore"):
                return (level & (v_here >= least * (1.0 - 1e-12))
                        & ~beyond_jet_velocity(m.propulsion, v_here[:, None], density)[:, 0]
                        & (thrust > 0.0))

        self.active = ok
        v, level, u, current, thrust = state(q, v)
        held &= flyable(v, level, thrust) & self._above_cutoff(u)
        going &= held
        end_s = np.full(m.size, np.nan)
        # per row, the last step's two nodes (charge, rate) for the end's interpolation
        qa, qb, ka, kb, va = (np.zeros_like(q), np.zeros_like(q), np.zeros_like(q),
                              np.zeros_like(q), v.copy())
        ended = np.zeros(m.size, dtype=bool)
        k_here = current / SECONDS_PER_HOUR

        def stage(charge: Array, guess: Array) -> tuple[Array, Array]:
            v_here, _, _, current, _ = state(charge, guess)
            return v_here, current / SECONDS_PER_HOUR

        for _ in range(_MAX_CRUISE_STEPS):
            if not going.any():
                break
            k1 = k_here
            v2, k2 = stage(q + 0.5 * h * k1, v)
            v3, k3 = stage(q + 0.5 * h * k2, v2)
            v4, k4 = stage(q + h * k3, v3)
            q_next = q + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            v_next, level, u, current, thrust = state(q_next, v4)
            k_next = current / SECONDS_PER_HOUR
            with np.errstate(invalid="ignore"):
                at_reserve = np.any(q_next >= rows.reserve_charge_ah, axis=0)
                cut = ~self._above_cutoff(u)
                emptied = ~np.all(np.isfinite(q_next) & (q_next < self.pole), axis=0)
            finishing = going & (at_reserve | cut | emptied)
            # a node before the end that the single case cannot fly ends the row unflown
            bad = going & ~finishing & ~flyable(v_next, level, thrust)
            held &= ~bad
            for array, value in ((qa, q), (qb, q_next), (ka, k1), (kb, k_next)):
                array[:, finishing] = value[:, finishing]
            va = np.where(finishing, v, va)
            end_s = np.where(finishing, t, end_s)
            ended |= finishing
            stepping = going & ~finishing & ~bad
            for array, value in ((q, q_next), (k_here, k_next)):
                array[:, stepping] = value[:, stepping]
            v = np.where(stepping, v_next, v)
            t = np.where(stepping, t + h, t)
            if stepping.any():
                nodes.add(np.where(stepping, t, np.nan), q, k_here * SECONDS_PER_HOUR)
            going = stepping
            self.active = going | (self.active & finishing)
        self.active = held & ended
        held &= ended
        tau = self._end_within(throttle, qa, qb, ka, kb, va, h, held)
        held &= np.isfinite(tau)
        end_t = end_s + tau
        # the end node closes the history (the rating's windows end there); the airspeed
        # falls as the packs sag, so level flight lost within the last step is lost there
        q_end = self._hermite(qa, qb, ka, kb, h, tau)
        v_end, level, _, _, thrust = state(np.where(held, q_end, qa), va)
        held &= flyable(v_end, level, thrust)
        share = np.clip(np.nan_to_num(tau) / h, 0.0, 1.0)
        nodes.add(np.where(held, end_t, np.nan), np.where(held, q_end, np.nan),
                  np.where(held, (ka + share * (kb - ka)) * SECONDS_PER_HOUR, np.nan))
        return np.where(held, end_t - t0, np.nan), held

    @staticmethod
    def _hermite(qa: Array, qb: Array, ka: Array, kb: Array, h: Array, tau: Array) -> Array:
        s = np.clip(np.nan_to_num(tau) / h, 0.0, 1.0)
        return ((2 * s ** 3 - 3 * s ** 2 + 1) * qa + (s ** 3 - 2 * s ** 2 + s) * h * ka
                + (-2 * s ** 3 + 3 * s ** 2) * qb + (s ** 3 - s ** 2) * h * kb)

    def _end_within(self, throttle: Array, qa: Array, qb: Array, ka: Array, kb: Array,
                    va: Array, h: Array, rows_ended: NDArray[np.bool_]) -> Array:
        """Time [s] into the last step at which the first fan reaches the landing reserve or
        the packs their cut-off, whichever is first (NaN where neither lies in it)."""
        reserve, cutoff = self.rows.reserve_charge_ah, self.rows.cutoff_v

        def margin(tau: Array) -> tuple[Array, Array]:
            charge = self._hermite(qa, qb, ka, kb, h, tau)
            v_here = self.level_speed(throttle, charge, va)[0]
            u = self.point(throttle, v_here, charge)[1]
            return (np.min(reserve - charge, axis=0),
                    np.min(u, axis=0) - (cutoff - _CUTOFF_SLACK_V))

        def illinois(which: int) -> Array:
            low, high = np.zeros_like(h), h.copy()
            f_low, f_high = margin(low)[which], margin(high)[which]
            inside = rows_ended & (f_low >= 0.0) & (f_high < 0.0)
            for _ in range(_END_STEPS):
                with np.errstate(divide="ignore", invalid="ignore"):
                    c = high - f_high * (high - low) / (f_high - f_low)
                c = np.where(np.isfinite(c) & (c > low) & (c < high), c, 0.5 * (low + high))
                fc = margin(c)[which]
                up = fc >= 0.0
                f_high = np.where(up, 0.5 * f_high, f_high)
                f_low = np.where(up, f_low, 0.5 * f_low)
                low, f_low = np.where(up, c, low), np.where(up, fc, f_low)
                high, f_high = np.where(up, high, c), np.where(up, f_high, fc)
                if np.all(~inside | (high - low <= 1e-12 * np.maximum(h, 1.0))):
                    break
            return np.where(inside, np.where(np.abs(f_low) <= np.abs(f_high), low, high),
                            np.inf)

        to_reserve, to_cut = illinois(0), illinois(1)
        # the packs' cut-off before the landing reserve: no reserve is kept at the cruise's
        # power, and the endurance is not attainable (issue 43; as endurance_verdict)
        self.cut_first = rows_ended & (to_cut < to_reserve)
        first = np.minimum(to_reserve, to_cut)
        return np.where(rows_ended & np.isfinite(first), first, np.nan)

    # -- the packs' rating --------------------------------------------------------------------
    def within_rating(self, nodes: _Nodes, ok: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """The mission's two rules over the flight's nodes: no node beyond the burst rating,
        no stretch of 30 s or more beyond the continuous one (``MissionModel._beyond_rating``)."""
        rating = self.rows.rating_a
        if rating is None:
            return ok
        per_pack = self.rows.packs_per_engine
        times = np.stack(nodes.time, axis=-1)  # (rows, nodes), NaN past a row's end
        charges = np.stack(nodes.charge, axis=-1) / per_pack  # (fans, rows, nodes)
        currents = np.stack(nodes.current, axis=-1) / per_pack
        with np.errstate(invalid="ignore"):
            peak = np.nanmax(np.where(np.isfinite(currents), currents, -np.inf), axis=(0, 2))
            ok = ok & ~(peak > BURST_OVER_CONTINUOUS * rating * (1.0 + 1e-9))
        # a row's nodes in time order (a row that ended has NaN where others still flew,
        # its end node last)
        filled = np.isfinite(times)
        order = np.argsort(np.where(filled, times, np.inf), axis=1, kind="stable")
        times = np.take_along_axis(times, order, axis=1)
        filled = np.take_along_axis(filled, order, axis=1)
        charges = np.take_along_axis(charges, np.broadcast_to(order, charges.shape), axis=2)
        # no stretch between nodes draws more than the steepest chord: only rows with a chord
        # beyond the continuous rating can have a 30 s stretch beyond it
        with np.errstate(invalid="ignore", divide="ignore"):
            chord = np.diff(charges, axis=2) * SECONDS_PER_HOUR / np.diff(times, axis=1)
            steep = np.nanmax(np.where(np.isfinite(chord), chord, -np.inf), axis=(0, 2))
        suspect = np.flatnonzero(ok & (steep > rating * (1.0 - 1e-9)))
        if not suspect.size:
            return ok
        times, filled, charges = times[suspect], filled[suspect], charges[:, suspect]
        # past its end a row's last node repeats at rest, an instant apart
        count = np.maximum(filled.sum(axis=1), 1)
        last = np.minimum(np.arange(times.shape[1])[None, :], count[:, None] - 1)
        last_t = np.take_along_axis(times, count[:, None] - 1, axis=1)
        times = np.where(filled, times, last_t + 1e-6 * (np.arange(times.shape[1])[None, :]
                                                         - count[:, None] + 1))
        charges = np.take_along_axis(charges, np.broadcast_to(last, charges.shape), axis=2)
        end, _, _ = first_window_beyond(times, charges.transpose(1, 0, 2),
                                        np.broadcast_to(rating, ok.shape)[suspect],
                                        RATING_SEGMENT_S)
        ok = ok.copy()
        ok[suspect] &= end == np.inf
        return ok


@dataclass(frozen=True)
class SaggingRows:
    """The flight on sagging packs per row: its endurance [min] (NaN: not attainable; where
    the cut-off comes before the landing reserve, ``cut_first``, the time to it), the
    cruise's and the climb's times [s] and the greatest charge drawn per fan at its end [Ah]."""

    minutes: Array
    cut_first: NDArray[np.bool_]
    cruise_s: Array
    climb_s: Array
    end_charge_ah: Array


def flight_on_sagging_packs(m: Any, model: Any, rows: PackRows, throttle: Array,
                            roll: tuple[Array, Array, Array, Array], stall: Array,
                            height: Array, speed: Array, ok: NDArray[np.bool_],
                            estimate_s: Array) -> SaggingRows:
    """The endurance flight per row on sagging packs (:class:`SaggingRows`).

    ``ok`` the rows whose throttle holds level flight at the reference voltage (the single
    case's check before its mission), ``speed`` [m/s] their level-flight airspeed there,
    ``estimate_s`` [s] the constant-power cruise (it sizes the cruise's steps).
    """
    from tuflexperf.models.powertrain import PowerSurfaces

    engines: tuple[Any, ...] = (None,)
    if isinstance(model.power, PowerSurfaces) and len(m.propulsion.engines) > 1:
        engines = m.propulsion.engines  # each fan on its own packs, at its own voltage
    _, _, v_lo, rolled = roll
    climb_speed, climb_rate = best_climb(m, v_lo, stall)
    ok = ok & (rolled > 0.5) & ~((height > 0) & (climb_rate <= 0))
    ok &= ~((height > 0) & (climb_speed < m.least_airspeed() * (1.0 - 1e-12)))
    flight = SaggingFlight(m, model, rows, engines)
    start, climb_s, held, nodes = flight.launch(roll, climb_speed, height, ok,
                                                m.aircraft.launch == "catapult")
    with np.errstate(invalid="ignore"):
        ok &= held & np.all(start < rows.reserve_charge_ah, axis=0)
    cruise_s, ok = flight.cruise(throttle, start, nodes.time[-1], speed,
                                 np.where(np.isfinite(estimate_s), estimate_s, 600.0), ok, nodes)
    ok = flight.within_rating(nodes, ok)
    minutes = (cruise_s + climb_s) / 60.0
    flown = ok & np.isfinite(minutes)
    return SaggingRows(np.where(flown, minutes, np.nan), flown & flight.cut_first,
                       np.where(flown, cruise_s, np.nan), np.where(flown, climb_s, np.nan),
                       np.where(flown, np.max(nodes.charge[-1], axis=0), np.nan))
