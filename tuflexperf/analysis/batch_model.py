"""The batch's physics: array-valued aircraft and engines through the model functions.

:class:`BatchModel` carries one row per sample or grid point and evaluates thrust, the
least throttle for a thrust (the closed-form quadratic root of the thrust surface), trim,
OEI and the packs' limits for every row at once; its take-off comes from
:class:`tuflexperf.analysis.batch_roll.GroundRollRows`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.batch_kernels import fan_power_rows, stall_speed
from tuflexperf.analysis.batch_roll import GroundRollRows
from tuflexperf.analysis.pack_limits import (
    least_throttle_where,
    operating_point,
    pack_rows,
    power_limit_w,
    within_limits,
)
from tuflexperf.models.aircraft import (
    Aircraft,
    ground_roll_net_force_n,
    level_flight_drag_n,
    liftoff_speed_m_s,
    transition_speed_m_s,
)
from tuflexperf.models.powertrain import beyond_jet_velocity
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    Propulsion,
    density_ratio,
    engine_thrust_n,
    least_throttle_reaching,
    outside_tested_range,
    poly22,
    total_thrust_n,
    windmilling_thrust_n,
)

Array = NDArray[np.float64]


@dataclass
class BatchModel(GroundRollRows):
    """The batch's physics: array-valued aircraft/engines through the model functions."""

    aircraft: Aircraft
    propulsion: Propulsion
    density: Any
    extrapolation_n: Array | None
    size: int
    stall_margin: Any = 1.0  # envelope's stall_margin (scalar or per row)
    _uniform: Array | None = None
    _drag: Any = None  # (airspeeds, level-flight drag there) of the last grid
    _pieces: Any = None  # memo of _roll_pieces (False: evaluate node by node)
    _terms: Any = None
    _force_range: tuple[Array, Array] | None = None  # memo of force_range
    # the take-off on sagging packs (batch_takeoff_packs.RollOnPacks), where one is flown
    packs_roll: Any = None
    # a catapult's level acceleration from release to the transition speed (distance [m],
    # time [s], charge per fan [Ah] or None, accelerates): ground_roll.release_acceleration
    release: Any = None
    # the arc and climb to the obstacle on sagging packs [m] (batch_takeoff_packs)
    packs_airborne: Array | None = None
    # where those packs reach their cut-off in the climb, before the obstacle
    packs_beyond: NDArray[np.bool_] | None = None

    def transition_speed(self) -> Array:
        """The take-off arc's true airspeed [m/s] per row ``(B,)``: 1.15 V_stall."""
        return np.asarray(transition_speed_m_s(self.aircraft, self.density),
                          dtype=float).reshape(-1) * np.ones(self.size)

    def least_airspeed(self) -> Array:
        """Least level-flight airspeed [m/s] per row: stall x the envelope's margin (SPEC 3)."""
        return np.asarray(self.stall_margin, dtype=float).reshape(-1) * stall_speed(self)

    def _flyable(self, grid: Array) -> Array:
        """Where level flight may be attainable per row: at or above the least airspeed and
        short of the fans' jet velocity (the single-case ``stall_bounded``); ``grid`` is
        ``(1, K)`` or one row of airspeeds [m/s] per row of the batch."""
        above = grid >= self.least_airspeed()[:, None] * (1.0 - 1e-12)
        density = np.asarray(self.density, dtype=float).reshape(-1, 1)
        return above & ~beyond_jet_velocity(self.propulsion, grid, density)

    def extrapolation_errors_n(self, speed: Array) -> list[Array] | None:
        """Per engine, the row's sampled thrust error [N] at ``speed``: its draw beyond the
        tested range, scaled to the row's density as the thrust is; ``None`` without draws."""
        if self.extrapolation_n is None:
            return None
        beyond = density_ratio(self.propulsion, self.density) \
            * outside_tested_range(self.propulsion, speed).astype(float)
        return [beyond * error[:, None] for error in self.extrapolation_n]

    def _per_row(self, value: Any) -> Array:
        """``value`` [N] as an array with one row per batch row (a view where it is shared)."""
        value = np.asarray(value, dtype=float)
        return np.broadcast_to(value, np.broadcast_shapes(value.shape, (self.size, 1)))

    def thrust(self, throttle: Any, speed: Array, dead: int | None = None,
               mode: str = "windmilling") -> Array:
        """Total thrust [N]; the extrapolation error adds to each live engine beyond the range."""
        total = total_thrust_n(self.propulsion, throttle, speed, self.density, dead, mode)
        errors = self.extrapolation_errors_n(speed)
        for j, error in enumerate(errors or ()):
            if j != dead:
                total = total + error
        return self._per_row(total)

    def engine_thrust(self, index: int, throttle: Any, speed: Array) -> Array:
        """One live engine's thrust [N], as :meth:`thrust` counts it in the total (its model
        at the row's density, its extrapolation error beyond the tested range)."""
        own = engine_thrust_n(self.propulsion.engines[index], throttle, speed,
                              density_ratio(self.propulsion, self.density))
        errors = self.extrapolation_errors_n(speed)
        return self._per_row(own if errors is None else own + errors[index])

    # -- take-off -----------------------------------------------------------------------------
    def net_force(self, speed: Array) -> Array:
        thrust = self.thrust(1.0, speed)
        return np.asarray(
            ground_roll_net_force_n(self.aircraft, thrust, speed, self.density), dtype=float
        ) * np.ones((self.size, 1))

    def liftoff_speed(self) -> Array:
        return np.asarray(liftoff_speed_m_s(self.aircraft, self.density), dtype=float) \
            * np.ones((self.size, 1))

    # -- level flight --------------------------------------------------------------------------
    def _engine_thrusts(self, speed: Array) -> tuple[list[tuple[Array, Array, Array]],
                                                      list[Array]]:
        """Per engine: its thrust [N] as ``a x^2 + b x + c`` in throttle at these airspeeds
        (the extrapolation error in ``c``), and its dead-engine contribution, as
        :func:`total_thrust_n` sums them.

        poly22 is quadratic in throttle: ``a, b, c`` from its values at throttle 0, 1/2
        and 1. Sampled coefficients against airspeeds common to all rows: poly22 is linear
        in its coefficients, so the three values are each row's coefficients times
        poly22's basis functions, one matrix product per coefficient.
        """
        scale = density_ratio(self.propulsion, self.density)
        errors = self.extrapolation_errors_n(speed)
        live, dead = [], []
        for j, engine in enumerate(self.propulsion.engines):
            error = 0.0 if errors is None else errors[j]
            coefficients = engine.coefficients
            if np.shape(speed)[0] == 1 and all(np.ndim(coefficients[t]) == 2
                                               for t in POLY22_TERMS):
                rows = np.concatenate([coefficients[t] for t in POLY22_TERMS], axis=1)
                f0, fh, f1 = (np.stack([
                    np.broadcast_to(poly22(x * engine.throttle_scale, speed[0], _UNIT[t]),
                                    speed[0].shape) for t in POLY22_TERMS])
                    for x in (0.0, 0.5, 1.0))
                basis_a = 2.0 * (f1 - 2.0 * fh + f0)
                a_j, b_j, c_j = (scale * (rows @ basis)
                                 for basis in (basis_a, f1 - f0 - basis_a, f0))
            else:
                t0, th, t1 = (engine_thrust_n(engine, x, speed, scale) for x in (0.0, 0.5, 1.0))
                a_j = 2.0 * (t1 - 2.0 * th + t0)
                b_j, c_j = t1 - t0 - a_j, t0
            live.append((a_j, b_j, c_j + error))
            dead.append(windmilling_thrust_n(engine, speed, scale, self.density,
                                             self.propulsion.fan_area_m2))
        return live, dead

    def _excess_quadratic(self, speed: Array, dead: int | None, mode: str,
                          terms: tuple[list[tuple[Array, Array, Array]], list[Array]]
                          ) -> tuple[Array, Array, Array]:
        """Level-flight thrust excess ``a x^2 + b x + c`` [N] in throttle at each airspeed:
        the live engines' sum (a windmilling dead engine adds its drag to ``c``) less the
        drag."""
        live, windmill = terms
        a, b, c = (sum(live[j][i] for j in range(len(live)) if j != dead) for i in range(3))
        if dead is not None and mode == "windmilling":
            c = c + windmill[dead]
        if self._drag is None or self._drag[0] is not speed:  # shared by trim and OEI
            self._drag = (speed, np.asarray(
                level_flight_drag_n(self.aircraft, speed, self.density), dtype=float))
        drag = self._drag[1]
        shape = np.broadcast_shapes(np.shape(a), np.shape(c), np.shape(drag), (self.size, 1))
        return (np.broadcast_to(a, shape), np.broadcast_to(b, shape),
                np.broadcast_to(c - drag, shape))

    @staticmethod
    def _roots(a: Array, b: Array, c: Array) -> Array:
        """:func:`least_throttle_reaching` (one closed form for trim, OEI, endurance and the
        export), NaN where no throttle in [0, 1] reaches."""
        with np.errstate(invalid="ignore", divide="ignore"):
            throttle, reached = least_throttle_reaching(a, b, c)
        return np.where(np.asarray(reached) > 0.5, np.asarray(throttle, dtype=float), np.nan)

    def least_throttle(self, speed: Array, dead: int | None = None,
                       mode: str = "windmilling",
                       terms: tuple[list[tuple[Array, Array, Array]], list[Array]] | None = None
                       ) -> Array:
        """Least throttle [fraction] for level flight at each airspeed; NaN where none.

        ``terms`` reuses the engines' thrusts at these airspeeds across dead-engine cases.
        """
        terms = terms if terms is not None else self._engine_thrusts(speed)
        return self._roots(*self._excess_quadratic(speed, dead, mode, terms))

    def trim_max_throttle(self, grid: Array, candidates: Array | None = None) -> Array:
        """Highest least throttle over the envelope grid ``(1, K)`` or ``(B, K)`` [m/s]; NaN if
        any airspeed is not attainable.

        ``candidates`` (grid indices where the highest least throttle is expected, from the
        nominal case) make it cheap and leave it exact: the largest least throttle ``m`` over
        the candidates is the answer of every row whose excess at throttle ``m`` is >= 0 at
        all other airspeeds (there the least throttle is <= m); the other rows are solved at
        every airspeed. Each row's answer depends on that row alone.
        """
        above = self._flyable(grid)
        a, b, c = self._excess_quadratic(grid, None, "windmilling", self._grid_terms(grid))
        candidates = _within(candidates, grid)
        everywhere = np.all(above, axis=1)  # below stall somewhere: not attainable there
        if candidates is None:
            rows = np.arange(self.size)
            result = np.full(self.size, np.nan)
        else:
            m = np.max(self._roots(a[:, candidates], b[:, candidates], c[:, candidates]), axis=1)
            with np.errstate(invalid="ignore"):
                excess = (a * m[:, None] + b) * m[:, None] + c
            excess[:, candidates] = 0.0  # the candidates' roots are m or below, computed
            holds = np.all(excess >= 0.0, axis=1)
            # NaN at a candidate: that airspeed is not attainable, so neither is the envelope
            result = np.where(np.isnan(m) | holds, m, np.nan)
            rows = np.flatnonzero(everywhere & ~np.isnan(m) & ~holds)
        if rows.size:
            throttle = self._roots(a[rows], b[rows], c[rows])
            result[rows] = np.where(np.all(np.isfinite(throttle), axis=1),
                                    np.max(throttle, axis=1), np.nan)
        return np.where(everywhere, result, np.nan)

    def oei_min_throttle(self, grid: Array, mode: str,
                         candidates: dict[int, Array] | None = None) -> Array:
        """Worse dead engine's least throttle over the grid; NaN if one has no level flight.

        ``candidates`` per dead engine (grid indices where the least throttle is expected to
        be lowest, from the nominal case): with ``m`` the least over the attainable
        candidates, a row's answer is ``m`` when at every other airspeed above stall the
        excess is < 0 at throttle ``m`` and rising in throttle on [0, m] (so its least
        throttle is above ``m``); the other rows are solved at every airspeed.
        """
        worst = np.full(self.size, -np.inf)
        terms = self._grid_terms(grid)
        above = self._flyable(grid)
        for dead in range(len(self.propulsion.engines)):
            a, b, c = self._excess_quadratic(grid, dead, mode, terms)
            picked = None if candidates is None else _within(candidates.get(dead), grid)
            if picked is None:
                rows = np.arange(self.size)
                best = np.full(self.size, np.inf)
            else:
                roots = self._roots(a[:, picked], b[:, picked], c[:, picked])
                roots = np.where(above[:, picked] & np.isfinite(roots), roots, np.inf)
                m = np.min(roots, axis=1)
                mc = np.where(np.isfinite(m), m, 0.0)[:, None]
                with np.errstate(invalid="ignore"):
                    higher = ((((a * mc + b) * mc + c) < 0.0) & (b >= 0.0)
                              & (2.0 * a * mc + b >= 0.0))
                higher |= ~above  # below stall: no level flight to compare with
                higher[:, picked] = True
                holds = np.isfinite(m) & np.all(higher, axis=1)
                best = np.where(holds, m, np.inf)
                rows = np.flatnonzero(~holds)
            if rows.size:
                throttle = self._roots(a[rows], b[rows], c[rows])
                throttle = np.where(above[rows] & np.isfinite(throttle), throttle, np.inf)
                best[rows] = np.min(throttle, axis=1)
            worst = np.maximum(worst, best)
        return np.where(np.isfinite(worst), worst, np.nan)

    def packs_never_bind(self, grid: Array, packs: Any, battery: dict[str, Array],
                         top_throttle: Array) -> bool:
        """True when the packs change no row's answer, so the candidates' answer stands: no
        reference voltage (the thrust does not depend on the packs) and, in every row, each
        fan's greatest power over the grid and throttles in ``[0, top_throttle]`` within the
        power its packs give at the landing reserve (``pack_limits.power_limit_w``; power
        is quadratic in throttle for a surface, monotone for the fan law, so the ends and
        the vertex bound it). A row whose answer is NaN binds nothing."""
        if self.propulsion.reference_voltage_v is not None:
            return False
        limit = power_limit_w(packs, battery)[:, None]
        top = np.nan_to_num(np.asarray(top_throttle, dtype=float)).reshape(-1, 1)
        engines = self.propulsion.engines if packs.own_surfaces else (None,)
        for engine in engines:
            p0, ph, p1 = (np.maximum(fan_power_rows(packs, self, x, grid, engine), 0.0)
                          for x in (0.0 * top, 0.5 * top, top))
            curvature = 2.0 * (p1 - 2.0 * ph + p0)
            with np.errstate(invalid="ignore", divide="ignore"):
                vertex = np.clip(0.5 - (p1 - p0) / (2.0 * curvature), 0.0, 1.0)
            vertex = np.where(np.isfinite(vertex), vertex, 0.0)
            pv = np.maximum(fan_power_rows(packs, self, vertex * top, grid, engine), 0.0)
            most = np.max(np.maximum(np.maximum(p0, p1), pv), axis=1, keepdims=True)
            with np.errstate(invalid="ignore"):
                if not np.all(most <= limit * (1.0 - 1e-9)):
                    return False
        return True

    def over_grid_on_packs(self, grid: Array, dead: int | None, mode: str, packs: Any,
                           battery: dict[str, Array]) -> Array:
        """Trim's highest (``dead`` None) or one dead engine's least throttle over the grid,
        flown on the packs at the landing reserve as the single case flies it
        (:func:`tuflexperf.analysis.pack_limits.level_flight_on_packs`); NaN where not
        attainable (trim: at some airspeed; OEI: at every one).

        Every airspeed of every row is solved (no candidates): where the packs bind depends
        on the power, not only on the throttle.
        """
        prop = self.propulsion
        terms = self._grid_terms(grid)
        live = [j for j in range(len(prop.engines)) if j != dead]
        # the level-flight excess at idle; its shape is every row's grid
        idle = self._excess_quadratic(grid, dead, mode, terms)[2]
        shape = idle.shape
        flyable = np.broadcast_to(self._flyable(grid), shape)
        rows = pack_rows(packs.battery, battery)
        charge, circuit = rows.reserve_charge_ah[:, None], rows.circuit_packs[:, None]
        rating = None if rows.rating_a is None else rows.rating_a[:, None]

        def on_packs(x: Array) -> list[tuple[Array, Array, Array]]:
            engines = [prop.engines[j] if packs.own_surfaces else None for j in live]
            return [operating_point(packs.params, charge,
                                    np.maximum(fan_power_rows(packs, self, x, grid, engine), 0.0),
                                    circuit, rows.packs_per_engine, prop.reference_voltage_v,
                                    prop.voltage_exponent) for engine in engines]

        if prop.reference_voltage_v is None:
            x = np.where(flyable, self.least_throttle(grid, dead, mode, terms), np.nan)
        else:  # the thrust follows the sagging pack: no closed form (pack_limits)
            # the excess without the live engines: the dead one's drag less the airframe's
            other = idle - sum(terms[0][j][2] for j in live)

            def excess(xs: Array) -> Array:
                total = np.broadcast_to(other, shape)
                for j, (_, _, factor) in zip(live, on_packs(xs), strict=True):
                    a_j, b_j, c_j = terms[0][j]
                    total = total + factor * ((a_j * xs + b_j) * xs + c_j)
                return total

            x = np.where(flyable, least_throttle_where(excess, shape), np.nan)
        ok = np.isfinite(x)
        for u, current, _ in on_packs(np.nan_to_num(x)):
            ok &= within_limits(u, current, rows.cutoff_v[:, None], rating)
        x = np.where(ok, x, np.nan)
        if dead is None:
            return np.where(np.all(ok, axis=1), np.max(x, axis=1), np.nan)
        least = np.min(np.where(ok, x, np.inf), axis=1)
        return np.where(np.isfinite(least), least, np.nan)

    def _grid_terms(self, grid: Array) -> tuple[list[tuple[Array, Array, Array]], list[Array]]:
        """:meth:`_engine_thrusts` on the grid, shared by trim and OEI (keyed on the object)."""
        if self._terms is None or self._terms[0] is not grid:
            self._terms = (grid, self._engine_thrusts(grid))
        return self._terms[1]

    # -- endurance ----------------------------------------------------------------------------
    def flight_endurance_min(self, model: Any, throttle: Array,
                             roll: tuple[Array, Array, Array, Array],
                             battery: dict[str, Array]) -> tuple[Array, Array, Array]:
        """Flight endurance [min] at ``throttle`` per row (see :class:`EnduranceModel`), the
        level-flight airspeed [m/s] on full packs and the launch's climb airspeed [m/s]."""
        from tuflexperf.analysis import batch_endurance

        return batch_endurance.flight_endurance_min(self, model, throttle, roll, battery)

_UNIT = {t: {u: float(u == t) for u in POLY22_TERMS} for t in POLY22_TERMS}  # basis picks


def _within(candidates: Array | None, grid: Array) -> Array | None:
    """The nominal grid's candidate indices that exist on ``grid`` (rows of its own bounds
    may be shorter); only where to look first, so any index is as exact as another."""
    if candidates is None:
        return None
    return np.unique(np.minimum(candidates, grid.shape[1] - 1))
