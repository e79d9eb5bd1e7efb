"""Least throttle for steady level flight, ``T(x, V) >= D(V)``, over airspeed grids of rows.

Written once, on arrays of rows: :class:`LevelFlightRows` holds one aircraft, propulsion
and density per row (floats for one case, ``(B, 1)`` columns for a batch) and gives the
least throttle at each airspeed of each row's grid. ``trim`` and ``oei`` fly one row (the
case), ``--samples``, ``sweep`` and ``margins`` fly ``B``
(:class:`tuflexperf.analysis.batch_model.BatchModel` extends this class). The thrust
excess ``E(x, V) = T(x, V) - D(V)`` is quadratic in the throttle ``x`` (poly22 thrust), so
the least throttle is the least root in [0, 1] of a quadratic, in closed form
(:func:`tuflexperf.models.thrust.least_throttle_reaching`) on the model functions
(:func:`~tuflexperf.models.thrust.engine_thrust_n`,
:func:`~tuflexperf.models.thrust.windmilling_thrust_n`,
:func:`~tuflexperf.models.aircraft.level_flight_drag_n`); nothing iterates.

References
----------
Anderson, *Aircraft Performance and Design*, 5.3-5.4 (level flight, thrust required);
Press et al., *Numerical Recipes*, 3rd ed., 5.6 (the quadratic's roots).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.models.aircraft import Aircraft, level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.powertrain import beyond_jet_velocity
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    Propulsion,
    beyond_tested_m_s,
    density_ratio,
    engine_thrust_n,
    extrapolation_offset_n,
    least_throttle_reaching,
    poly22,
    total_thrust_n,
    windmilling_thrust_n,
)

Array = NDArray[np.float64]
Terms = tuple[list[tuple[Array, Array, Array]], list[Array]]

MAX_GRID_STEP_M_S = 0.5


def airspeed_grid(min_airspeed_m_s: float, max_airspeed_m_s: float) -> np.ndarray:
    """Airspeeds from min to max, both included, at most 0.5 m/s apart (SPEC 3)."""
    return airspeed_grids(np.array([min_airspeed_m_s]), np.array([max_airspeed_m_s]))[0]


def airspeed_grids(min_airspeed_m_s: np.ndarray, max_airspeed_m_s: np.ndarray) -> np.ndarray:
    """One :func:`airspeed_grid` per pair of bounds, as rows of one array.

    Parameters
    ----------
    min_airspeed_m_s, max_airspeed_m_s : ndarray of shape ``(R,)``
        Each row's bounds [m/s], the least below the greatest.

    Returns
    -------
    ndarray of shape ``(R, K)``
        Row ``i`` holds the ``n_i + 1`` airspeeds of its own grid, numbers identical to
        ``numpy.linspace(min_i, max_i, n_i + 1)``, then its greatest airspeed repeated up
        to the longest row's ``K``: a repeated airspeed changes no highest or least value
        over the row, so a batch whose bounds vary per row answers as each case alone.
    """
    low = np.asarray(min_airspeed_m_s, dtype=float).reshape(-1)
    high = np.asarray(max_airspeed_m_s, dtype=float).reshape(-1)
    steps = np.maximum(1, np.ceil((high - low) / MAX_GRID_STEP_M_S - 1e-9)).astype(np.intp)
    index = np.arange(int(steps.max()) + 1, dtype=float)[None, :]
    # numpy.linspace's own arithmetic (j * step + start, the end set exactly), so one case's
    # grid and its row of a batch are the same numbers
    grids = index * ((high - low) / steps)[:, None] + low[:, None]
    return np.where(index >= steps[:, None], high[:, None], grids)


@dataclass
class LevelFlightRows:
    """Level flight of ``size`` rows: the least throttle per airspeed, trim's highest and the
    worse dead engine's least over an envelope grid.

    Parameters
    ----------
    aircraft : Aircraft
        Fields floats (shared by every row) or ``(B, 1)`` columns [SI].
    propulsion : Propulsion
        Engine coefficients floats or ``(B, 1)`` columns (sampled thrust models).
    density : float or ndarray ``(B, 1)``
        Air density [kg/m^3].
    extrapolation_n : ndarray ``(E, B)`` or None
        Thrust error [N per m/s] per engine and row, added times the distance beyond the
        tested airspeed range [m/s].
    size : int
        ``B``, the number of rows (1 for one case).
    stall_margin : float or ndarray ``(B, 1)``
        The envelope's ``stall_margin`` [-]: level flight from ``margin x V_stall`` up.
    """

    aircraft: Aircraft
    propulsion: Propulsion
    density: Any
    extrapolation_n: Array | None
    size: int
    stall_margin: Any = 1.0
    _drag: Any = None  # (airspeeds, level-flight drag there) of the last grid
    _terms: Any = None  # (grid, _engine_thrusts there) of the last grid

    def least_airspeed(self) -> Array:
        """Least level-flight airspeed [m/s] per row: stall x the envelope's margin (SPEC 3)."""
        stall = np.asarray(stall_speed_m_s(self.aircraft, self.density), dtype=float)
        return np.asarray(self.stall_margin, dtype=float).reshape(-1) \
            * (stall.reshape(-1) * np.ones(self.size))

    def _flyable(self, grid: Array) -> Array:
        """Where level flight may be attainable per row: at or above the least airspeed and
        short of the fans' jet velocity (the single-case ``stall_bounded``); ``grid`` is
        ``(1, K)`` or one row of airspeeds [m/s] per row of the batch."""
        above = grid >= self.least_airspeed()[:, None] * (1.0 - 1e-12)
        density = np.asarray(self.density, dtype=float).reshape(-1, 1)
        return above & ~beyond_jet_velocity(self.propulsion, grid, density)

    def extrapolation_errors_n(self, speed: Array) -> list[Array] | None:
        """Per engine, the row's sampled thrust error [N] at ``speed``: its draw per m/s
        beyond the tested range times the distance beyond it, scaled to the row's density as
        the thrust is; ``None`` without draws."""
        if self.extrapolation_n is None:
            return None
        beyond = density_ratio(self.propulsion, self.density) \
            * beyond_tested_m_s(self.propulsion, speed)
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

    def _engine_thrusts(self, speed: Array) -> Terms:
        """Per engine: its thrust [N] as ``a x^2 + b x + c`` in throttle at these airspeeds
        (:meth:`_live_thrusts`), and its dead-engine contribution (:meth:`_dead_drags`), as
        :func:`~tuflexperf.models.thrust.total_thrust_n` sums them."""
        return self._live_thrusts(speed), self._dead_drags(speed)

    def _live_thrusts(self, speed: Array) -> list[tuple[Array, Array, Array]]:
        """Per engine: its thrust [N] as ``a x^2 + b x + c`` in throttle at these airspeeds
        (the extrapolation error in ``c``).

        poly22 is quadratic in throttle: ``a, b, c`` from its values at throttle 0, 1/2
        and 1. Sampled coefficients against airspeeds common to all rows: poly22 is linear
        in its coefficients, so the three values are each row's coefficients times
        poly22's basis functions, one matrix product per coefficient.
        """
        scale = density_ratio(self.propulsion, self.density)
        errors = self.extrapolation_errors_n(speed)
        live = []
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
                # the offset beyond the tested range, as engine_thrust_n adds it
                c_j = c_j + scale * extrapolation_offset_n(engine, speed)
                if engine.thrust_offset is not None:  # the sampled mean model-form error
                    o0, oh, o1 = (engine.thrust_offset(x, speed) for x in (0.0, 0.5, 1.0))
                    o_a = 2.0 * (o1 - 2.0 * oh + o0)
                    a_j, b_j, c_j = (a_j + scale * o_a, b_j + scale * (o1 - o0 - o_a),
                                     c_j + scale * o0)
            else:
                t0, th, t1 = (engine_thrust_n(engine, x, speed, scale) for x in (0.0, 0.5, 1.0))
                a_j = 2.0 * (t1 - 2.0 * th + t0)
                b_j, c_j = t1 - t0 - a_j, t0
            live.append((a_j, b_j, c_j + error))
        return live

    def _dead_drags(self, speed: Array) -> list[Array]:
        """Per engine: its thrust [N] when dead and windmilling at these airspeeds."""
        scale = density_ratio(self.propulsion, self.density)
        return [windmilling_thrust_n(engine, speed, scale, self.density,
                                     self.propulsion.fan_area_m2)
                for engine in self.propulsion.engines]

    def _grid_terms(self, grid: Array) -> Terms:
        """:meth:`_engine_thrusts` on the grid, shared by trim and OEI (keyed on the object)."""
        if self._terms is None or self._terms[0] is not grid:
            self._terms = (grid, self._engine_thrusts(grid))
        return self._terms[1]

    def _excess_quadratic(self, speed: Array, dead: int | None, mode: str,
                          terms: Terms) -> tuple[Array, Array, Array]:
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

    def _offsets(self) -> bool:
        """Whether a sampled engine's thrust adds a mean model-form error (not quadratic in
        throttle: the quadratics' roots are refined by :meth:`_refined`)."""
        return any(e.thrust_offset is not None for e in self.propulsion.engines)

    def _refined(self, a: Array, b: Array, c: Array, speed: Array, rows: Array,
                 dead: int | None) -> Array:
        """:meth:`_roots`, then twice again with ``c`` moved by the live engines' mean
        model-form error at the root less its quadratic through throttle 0, 1/2 and 1 (which
        ``a, b, c`` hold): the error varies over a throttle's fraction, the quadratic does
        not follow it there."""
        throttle = self._roots(a, b, c)
        if not self._offsets():
            return throttle
        scale = np.asarray(density_ratio(self.propulsion, self.density), dtype=float)
        scale = scale[rows] if scale.ndim and scale.shape[0] == self.size else scale
        v = speed if np.shape(speed)[0] == 1 else speed[rows]
        for _ in range(2):
            x = np.clip(np.nan_to_num(throttle, nan=0.5), 0.0, 1.0)
            gap = 0.0
            for j, engine in enumerate(self.propulsion.engines):
                if j == dead or engine.thrust_offset is None:
                    continue
                o0, oh, o1 = (engine.thrust_offset(node, v) for node in (0.0, 0.5, 1.0))
                o_a = 2.0 * (o1 - 2.0 * oh + o0)
                quadratic = (o_a * x + (o1 - o0 - o_a)) * x + o0
                gap = gap + scale * (engine.thrust_offset(x, v) - quadratic)
            throttle = self._roots(a, b, c + gap)
        return throttle

    def least_throttle(self, speed: Array, dead: int | None = None,
                       mode: str = "windmilling", terms: Terms | None = None) -> Array:
        """Least throttle [fraction] for level flight at each airspeed; NaN where none.

        Parameters
        ----------
        speed : ndarray ``(1, K)`` or ``(B, K)``
            True airspeeds [m/s], shared by every row or one row each.
        dead : int, optional
            The inoperative engine; ``mode`` its drag (``windmilling`` or ``zero``).
        terms : optional
            The engines' thrusts at these airspeeds (:meth:`_grid_terms`), reused across
            dead-engine cases.

        Returns
        -------
        ndarray ``(B, K)``
            Not bounded by stall or the jet velocity (:meth:`_flyable` says where those hold).
        """
        terms = terms if terms is not None else self._engine_thrusts(speed)
        return self._refined(*self._excess_quadratic(speed, dead, mode, terms), speed,
                             np.arange(self.size), dead)

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
        # the shortcut's test holds for quadratics only
        candidates = None if self._offsets() else _within(candidates, grid)
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
            throttle = self._refined(a[rows], b[rows], c[rows], grid, rows, None)
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
            picked = None if candidates is None or self._offsets() \
                else _within(candidates.get(dead), grid)
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
                throttle = self._refined(a[rows], b[rows], c[rows], grid, rows, dead)
                throttle = np.where(above[rows] & np.isfinite(throttle), throttle, np.inf)
                best[rows] = np.min(throttle, axis=1)
            worst = np.maximum(worst, best)
        return np.where(np.isfinite(worst), worst, np.nan)


_UNIT = {t: {u: float(u == t) for u in POLY22_TERMS} for t in POLY22_TERMS}  # basis picks


def _within(candidates: Array | None, grid: Array) -> Array | None:
    """The nominal grid's candidate indices that exist on ``grid`` (rows of its own bounds
    may be shorter); only where to look first, so any index is as exact as another."""
    if candidates is None:
        return None
    # sorted(set()), not np.unique: numpy >= 2.3's unique imports numpy.ma (~20 ms)
    last = grid.shape[1] - 1
    return np.array(sorted({min(int(i), last) for i in candidates}), dtype=np.intp)


@dataclass(frozen=True)
class ThrottleSweep:
    """Least level-flight throttle at each airspeed of a grid; NaN where not attainable."""

    airspeed_m_s: np.ndarray
    throttle: np.ndarray

    @property
    def all_feasible(self) -> bool:
        return bool(np.all(np.isfinite(self.throttle)))

    @property
    def min_throttle(self) -> float | None:
        finite = self.throttle[np.isfinite(self.throttle)]
        return float(finite.min()) if finite.size else None

    @property
    def airspeed_at_min_throttle_m_s(self) -> float | None:
        if self.min_throttle is None:
            return None
        return float(self.airspeed_m_s[np.nanargmin(self.throttle)])

    @property
    def level_flight_airspeed_range_m_s(self) -> list[float] | None:
        """Lowest and highest grid airspeed where level flight is attainable."""
        feasible = self.airspeed_m_s[np.isfinite(self.throttle)]
        return [float(feasible.min()), float(feasible.max())] if feasible.size else None

    def lists(self) -> dict[str, list[float | None]]:
        """The grid as JSON lists (``None`` where not attainable)."""
        return {
            "airspeed_m_s": [float(v) for v in self.airspeed_m_s],
            "throttle": [float(x) if np.isfinite(x) else None for x in self.throttle],
        }
