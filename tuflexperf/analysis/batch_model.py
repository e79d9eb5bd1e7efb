"""The batch's physics: array-valued aircraft and engines through the model functions.

:class:`BatchModel` carries one row per sample or grid point and evaluates thrust and the
packs' limits for every row at once; its level flight (the least throttle, trim, OEI) is
:class:`tuflexperf.analysis.level_flight.LevelFlightRows` and its take-off
:class:`tuflexperf.analysis.ground_roll.GroundRollRows`, the very code ``trim``, ``oei`` and
``takeoff`` run on one row.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.batch_kernels import fan_power_rows
from tuflexperf.analysis.ground_roll import GroundRollRows
from tuflexperf.analysis.pack_limits import (
    level_rows_on_packs,
    pack_rows,
    power_limit_w,
)

Array = NDArray[np.float64]
_MISSING = object()


@dataclass(frozen=True)
class SharedRows:
    """What the evaluations of one batch on several readings of a case share: the results
    that read only the thrust, the aircraft and the air (never a fan's electrical power), kept
    in ``memo`` under the fingerprint of what they read (:func:`thrust_identity`).

    A reading that moves only the power (the measured power correction) finds every such
    result there; one that moves a dead engine's drag only (windmilling) finds the live
    engines' thrust and the take-off. The numbers are the ones each evaluation would make.

    Attributes
    ----------
    memo : dict
        ``(identity, method, arguments) -> result``, one per batch of rows.
    live : str
        Fingerprint of what every live engine's thrust reads.
    dead : str
        The same with the dead engines' windmilling drag.
    """

    memo: dict[Hashable, Any]
    live: str
    dead: str


def _digest(value: Any) -> Hashable:
    """A key equal for equal arguments [arrays by shape, type and bytes]."""
    if isinstance(value, np.ndarray):
        return ("array", value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, (tuple, list)):
        return tuple(_digest(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((k, _digest(v)) for k, v in value.items()))
    if isinstance(value, np.generic):
        return value.item()
    return value


def _frozen(value: Any) -> Any:
    """``value`` with its arrays read-only (a shared result is never changed in place)."""
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif isinstance(value, (tuple, list)):
        for v in value:
            _frozen(v)
    return value


@dataclass
class BatchModel(GroundRollRows):
    """The batch's physics: array-valued aircraft/engines through the model functions
    (fields as :class:`LevelFlightRows`: ``aircraft``, ``propulsion``, ``density``,
    ``extrapolation_n``, ``size``, ``stall_margin``; the take-off's as
    :class:`GroundRollRows`)."""

    # per row, the error model's factor on every fan's electrical power [-] (None: 1)
    power_scale: Array | None = None
    packs_air: Any = None  # that airborne part's settled path (airborne.AirborneOnPacks)
    # the results of the batch's other readings that this one may take (SharedRows)
    shared: SharedRows | None = None
    # shared results being made (the thrusts within them are not kept)
    _making: int = dataclasses.field(default=0, init=False, repr=False, compare=False)

    def _shared(self, kind: str, name: str, arguments: tuple[Any, ...],
                compute: Callable[[], Any]) -> Any:
        """``compute()``, or its result from another reading of the batch that reads the
        same thrust (``kind`` "live": every engine running; "dead": a dead one's drag too)."""
        if self.shared is None:
            return compute()
        identity = self.shared.live if kind == "live" else self.shared.dead
        key = (identity, name, _digest(arguments))
        found = self.shared.memo.get(key, _MISSING)
        if found is _MISSING:
            self._making += 1
            try:
                found = self.shared.memo[key] = _frozen(compute())
            finally:
                self._making -= 1
        return found

    def shared_rows(self, name: str, arguments: tuple[Any, ...],
                    compute: Callable[[], Any]) -> Any:
        """``compute()``, a result of these rows that reads only the thrust of every engine
        running, the aircraft and the air (never a fan's power), or the one another reading
        of the batch made with equal ``arguments`` (:class:`SharedRows`); its arrays
        read-only."""
        return self._shared("live", name, arguments, compute)

    # -- the thrust-only results, shared between readings (SharedRows) ----------------------
    def thrust(self, throttle: Any, speed: Array, dead: int | None = None,
               mode: str = "windmilling") -> Array:
        if self._making:
            # within a shared result another reading takes whole: its thrusts are asked
            # for again by nobody (keeping them cost their hashing and their memory)
            return super().thrust(throttle, speed, dead, mode)
        kind = "dead" if dead is not None and mode == "windmilling" else "live"
        return self._shared(kind, "thrust", (throttle, speed, dead, mode),
                            lambda: super(BatchModel, self).thrust(throttle, speed, dead, mode))

    def _live_thrusts(self, speed: Array) -> list[tuple[Array, Array, Array]]:
        return self._shared("live", "live_thrusts", (speed,),
                            lambda: super(BatchModel, self)._live_thrusts(speed))

    def trim_max_throttle(self, grid: Array, candidates: Array | None = None) -> Array:
        return self._shared("live", "trim", (grid, candidates),
                            lambda: super(BatchModel, self).trim_max_throttle(grid, candidates))

    def oei_min_throttle(self, grid: Array, mode: str,
                         candidates: dict[int, Array] | None = None) -> Array:
        return self._shared("dead", "oei", (grid, mode, candidates),
                            lambda: super(BatchModel, self).oei_min_throttle(grid, mode,
                                                                             candidates))

    def _roll_pieces(self) -> Any:
        return self._shared("live", "roll_pieces", (),
                            lambda: super(BatchModel, self)._roll_pieces())

    def uniform_force(self) -> Array:
        return self._shared("live", "uniform_force", (),
                            lambda: super(BatchModel, self).uniform_force())

    def force_range(self) -> tuple[Array, Array]:
        return self._shared("live", "force_range", (),
                            lambda: super(BatchModel, self).force_range())

    def ground_roll(self) -> tuple[Array, Array, Array, Array]:
        return self._shared("live", "ground_roll", (),
                            lambda: super(BatchModel, self).ground_roll())

    def roll_history(self, wanted: NDArray[np.bool_] | None = None) -> Array:
        return self._shared("live", "roll_history", (wanted,),
                            lambda: super(BatchModel, self).roll_history(wanted))

    def packs_never_bind(self, grid: Array, packs: Any, battery: dict[str, Array],
                         top_throttle: Array) -> bool:
        """True when the packs change no row's answer (:meth:`rows_packs_may_bind` in none)."""
        return not bool(np.any(self.rows_packs_may_bind(grid, packs, battery, top_throttle)))

    def rows_packs_may_bind(self, grid: Array, packs: Any, battery: dict[str, Array],
                            top_throttle: Array) -> NDArray[np.bool_]:
        """Per row, False where the packs change nothing, so the candidates' answer stands:
        no reference voltage (the thrust does not depend on the packs) and each fan's
        greatest power over the grid and throttles in ``[0, top_throttle]`` within the
        power its packs give at the landing reserve (``pack_limits.power_limit_w``; power
        is quadratic in throttle for a surface, monotone for the fan law, so the ends and
        the vertex bound it). A row whose answer is NaN binds nothing."""
        if self.propulsion.reference_voltage_v is not None:
            return np.ones(self.size, dtype=bool)
        limit = power_limit_w(packs, battery)[:, None]
        top = np.nan_to_num(np.asarray(top_throttle, dtype=float)).reshape(-1, 1)
        engines = self.propulsion.engines if packs.own_surfaces else (None,)
        may = np.zeros(self.size, dtype=bool)
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
                may |= ~np.broadcast_to(most <= limit * (1.0 - 1e-9), (self.size, 1))[:, 0]
        return may

    def rows(self, index: NDArray[np.intp]) -> BatchModel:
        """The model of the rows ``index`` alone (aircraft, thrust, density, errors, power
        scale): where only some rows need the packs' slower solution, they alone take it."""
        size = self.size

        def take(value: Any) -> Any:
            # a per-row array has the batch's rows first; a shared value is kept
            if isinstance(value, np.ndarray) and value.ndim >= 1 and value.shape[0] == size:
                return value[index]
            return value

        craft = self.aircraft
        skip = ("name", "takeoff", "launch")
        aircraft = dataclasses.replace(
            craft, **{f.name: take(getattr(craft, f.name))
                      for f in dataclasses.fields(craft) if f.name not in skip},
            takeoff=dataclasses.replace(craft.takeoff, **{
                f.name: take(getattr(craft.takeoff, f.name))
                for f in dataclasses.fields(craft.takeoff)}))
        engines = tuple(dataclasses.replace(e, coefficients={k: take(v) for k, v in
                                                             e.coefficients.items()})
                        for e in self.propulsion.engines)
        return BatchModel(
            aircraft=aircraft, propulsion=dataclasses.replace(self.propulsion, engines=engines),
            density=take(self.density),
            extrapolation_n=None if self.extrapolation_n is None
            else self.extrapolation_n[:, index],
            size=int(len(index)), stall_margin=take(self.stall_margin),
            power_scale=take(self.power_scale))

    def over_grid_on_packs(self, grid: Array, dead: int | None, mode: str, packs: Any,
                           battery: dict[str, Array]) -> Array:
        """Trim's highest (``dead`` None) or one dead engine's least throttle over the grid,
        flown on the packs at the landing reserve
        (:func:`tuflexperf.analysis.pack_limits.level_rows_on_packs`, the single case's on
        one row); NaN where not attainable (trim: at some airspeed; OEI: at every one).

        Every airspeed of every row is solved (no candidates): where the packs bind depends
        on the power, not only on the throttle.
        """
        x = level_rows_on_packs(self, grid, dead, mode, packs,
                                pack_rows(packs.battery, battery)).flown
        ok = np.isfinite(x)
        if dead is None:
            return np.where(np.all(ok, axis=1), np.max(x, axis=1), np.nan)
        least = np.min(np.where(ok, x, np.inf), axis=1)
        return np.where(np.isfinite(least), least, np.nan)

    # -- endurance ----------------------------------------------------------------------------
    def flight_endurance_min(self, model: Any, throttle: Array,
                             roll: tuple[Array, Array, Array, Array],
                             battery: dict[str, Array]) -> tuple[Array, Array, Array]:
        """Flight endurance [min] at ``throttle`` per row (see :class:`EnduranceModel`), the
        level-flight airspeed [m/s] on full packs and the launch's climb airspeed [m/s]."""
        from tuflexperf.analysis import batch_endurance

        return batch_endurance.flight_endurance_min(self, model, throttle, roll, battery)

