"""Flight endurance for a batch of parameter sets: the steps of ``EnduranceModel``, vectorised.

Per row, exactly as :class:`tuflexperf.analysis.endurance.EnduranceModel` does for one
case: the launch (ground-roll time history, best full-throttle climb on the same 4001-point
airspeed grid, RK4 of the constant-power current in strides of 0.25 s steps, the roll
and the steady climb apart as the single case's mission integrates them), the least
throttle of level flight, the fast level-flight root at the throttle,
the pack's cut-off charge, and the Gauss-Legendre discharge time from the launch charge to
the reserve. Newton per case becomes bisection over the batch (same roots, bracketed). The battery's
parameters and the fan's power model are the nominal case's (they come from the battery
file, not from the sampled aircraft). A catapult launch starts airborne at its release
speed: no roll, the battery pays for the climb only.

References
----------
Paper section 4 (endurance estimate); Tremblay & Dessaint (2009) (pack model);
Anderson, *Aircraft Performance and Design*, 5.10 (climb).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.batch_kernels import (
    GOLDEN_STEPS,
    best_climb,
    bracketed_root,
    fan_power_rows,
    golden_section_max,
    stall_speed,
)
from tuflexperf.analysis.constants import (
    BURST_OVER_CONTINUOUS,
    MAX_SPEED_OVER_STALL,
    RATING_SEGMENT_S,
    STEPS,
)
from tuflexperf.models._math import interp_rows
from tuflexperf.models.aircraft import level_flight_drag_n
from tuflexperf.models.battery import (
    SECONDS_PER_HOUR,
    current_at_power_a,
    cutoff_residual_v,
    discharge_time_s,
    first_window_beyond,
)
from tuflexperf.models.powertrain import (
    PowerSurfaces,
    beyond_jet_velocity,
    engine_power_w,
    figure_of_merit,
    jet_velocity_ceiling_m_s,
)
from tuflexperf.models.thrust import density_ratio, engine_thrust_n

Array = NDArray[np.float64]

# A figure of merit beyond this (ideal power over electrical) is no measurement error: the
# power model gives less than half what momentum theory needs for the thrust
IMPOSSIBLE_FIGURE_OF_MERIT = 2.0


def _shared(m: Any, name: str, arguments: tuple[Any, ...], compute: Any) -> Any:
    """``compute()``, or the same thrust-only result of another reading of the batch's rows
    (:meth:`.batch_model.BatchModel.shared_rows`; rows without it compute their own)."""
    share = getattr(m, "shared_rows", None)
    return compute() if share is None else share(name, arguments, compute)


def battery_side(case: Any) -> Any:
    """What the endurance flight takes from the case's battery: the battery, its fitted pack
    model (``params``) and the fan power model (:func:`.pack_limits.pack_side`, cached).

    References
    ----------
    Paper section 4 (endurance estimate); SPEC 4 (battery file).
    """
    from tuflexperf.analysis.pack_limits import pack_side
    from tuflexperf.errors import InputError

    side = pack_side(case)
    if side is None:
        raise InputError(
            f"{case.path}: battery: the case names no battery file; endurance needs one")
    return side


_ROLL_STEPS = 16  # RK4 steps of a roll along its history: 1e-8 of the mission's 64 ...
_DWELL_ROLL_STEPS = STEPS  # ... where the force all but vanishes and 16 were 5e-5 off
_DWELL_FORCE_SHARE = 0.2  # a least net force below this share of the greatest: dwelling
_ROTATION_STEPS = 2
_CLIMB_STEPS = 8  # RK4 steps of a climb drawing at most _LONG_CLIMB_SHARE of the packs
_LONG_CLIMB_SHARE = 0.1  # 8 steps are ~1e-9 of the 64 up to it (a 300 m climb here)


@dataclass(frozen=True)
class _Launch:
    """Per fan and row ``(fans, rows)``: charge [Ah] per fan after the roll and after the
    climb (NaN: impossible), and the largest current [A] on the way (for the pack rating);
    per row: the climb's and the roll's times [s]."""

    charge_ah: Array
    climb_time_s: Array
    roll_charge_ah: Array
    roll_time_s: Array
    peak_current_a: Array
    full_throttle_speeds_m_s: Array  # (rows, points): every airspeed its power was taken at
    climb_power_w: Array  # (fans, rows): the climb's constant electrical power


def _rk4_phase(params: Any, q: Array, h: Array, active: Array,
               powers: list[tuple[Array, Array, Array]], packs: Array,
               cutoff_v: Array) -> tuple[Array, Array, Array]:
    """RK4 of ``dq/dt = i(q, P)/3600`` [Ah/s] from ``q`` in steps of ``h`` [s] where
    ``active``, each step's power [W] at its start, middle and end in ``powers``; with the
    largest current [A] at the nodes and whether the loaded packs stay above their cut-off
    ``cutoff_v`` [V] at every node (the mission's checks; a take-off that cut off passed
    here; outside audit)."""
    peak = np.zeros(np.shape(q))
    above = np.asarray(cutoff_residual_v(params, q, powers[0][0], cutoff_v, packs)) > 0.0
    above |= ~active
    for p0, p_half, p1 in powers:
        k1 = np.asarray(current_at_power_a(params, q, p0, packs)) / 3600.0
        k2 = np.asarray(current_at_power_a(params, q + h / 2 * k1, p_half, packs)) / 3600.0
        k3 = np.asarray(current_at_power_a(params, q + h / 2 * k2, p_half, packs)) / 3600.0
        k4 = np.asarray(current_at_power_a(params, q + h * k3, p1, packs)) / 3600.0
        # the mission checks its nodes' currents (step ends): k1 and k4 are those here
        peak = np.where(active, np.maximum(peak, 3600.0 * np.maximum(k1, k4)), peak)
        after = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        held = np.asarray(cutoff_residual_v(params, after, p1, cutoff_v, packs)) > 0.0
        above = np.where(active, above & held, above)
        q = np.where(active, after, q)
    return q, peak, above


def _launch_path(m: Any, roll: tuple[Array, Array, Array, Array], stall: Array,
                 height: Array) -> tuple[Any, ...]:
    """What of the launch reads only the thrust, the aircraft and the air (the power
    model never): where it is flown, its climb time [s], roll time [s], rotation [s], roll
    before the rotation [s], the roll's row groups with their RK4 steps, the widest group's
    stage count, and every airspeed [m/s] the launch takes power at (:class:`_Launch`)."""
    _, roll_time, v_lo, ok = roll
    climb_speed, climb_rate = best_climb(m, v_lo, stall)
    ok = (ok > 0.5) & ~((height > 0) & (climb_rate <= 0))
    # the mission flies no climb below the envelope's stall margin (its segment is not
    # attainable there): the batch flew it (outside audit, a false PASS)
    ok &= ~((height > 0) & (climb_speed < m.least_airspeed() * (1.0 - 1e-12)))
    with np.errstate(divide="ignore", invalid="ignore"):
        climb_time = np.where(ok, np.where(height > 0, height / climb_rate, 0.0), np.nan)
    roll_time = np.where(ok, roll_time, 0.0)
    # a catapult launch has no roll: its history is never looked up (the roll time is 0)
    t_hist = (np.zeros((m.size, 2)) if m.aircraft.launch == "catapult"
              else m.roll_history(ok))
    v_hist = v_lo[:, None] * np.linspace(0.0, 1.0, t_hist.shape[1])[None, :]
    t_hist = np.where(ok[:, None], t_hist, 0.0)
    # the roll along its airspeed history, as many steps for a roll of hours as of seconds
    # (steps of 0.5 s made one such row stall a whole chunk; outside audit): the mission's 64
    # where the net force all but vanishes (the airspeed dwells, 16 were 5e-5 off), else 16
    catapult = m.aircraft.launch == "catapult"  # released airborne: no roll, no rotation
    rotation = np.where(ok & (not catapult), np.asarray(
        m.aircraft.takeoff.rotation_time_s, dtype=float).reshape(-1) * np.ones(m.size), 0.0)
    roll_only = np.where(ok, np.maximum(roll_time - rotation, 0.0), 0.0)
    least, most = m.force_range() if not catapult else (np.ones(m.size), np.ones(m.size))
    with np.errstate(invalid="ignore"):
        dwelling = least < _DWELL_FORCE_SHARE * most
    groups = [(rows, steps) for rows, steps in ((np.flatnonzero(~dwelling), _ROLL_STEPS),
                                                (np.flatnonzero(dwelling), _DWELL_ROLL_STEPS))
              if rows.size]
    widest = 2 * max((steps for _, steps in groups), default=_ROLL_STEPS) + 1
    # every airspeed of the roll's stages (padded with V_LO), then V_LO and the climb's
    used = np.repeat(v_lo[:, None], widest + 1, axis=1)
    used[:, -1] = climb_speed
    for rows, steps in groups:
        stage_t = 0.5 * (roll_only[rows] / steps)[:, None] * np.arange(2 * steps + 1)[None, :]
        every = rows.size == m.size  # one group: its histories as they are, not copied
        used[rows, :2 * steps + 1] = interp_rows(stage_t, t_hist if every else t_hist[rows],
                                                 v_hist if every else v_hist[rows])
    return ok, climb_time, roll_time, rotation, roll_only, groups, widest, used


def _launch_charge(m: Any, model: Any, roll: tuple[Array, Array, Array, Array],
                   stall: Array, height: Array, packs: Array, cutoff_v: Array,
                   engines: tuple[Any, ...] = (None,)) -> _Launch:
    """Charge [Ah] per fan drawn by roll + climb to ``height`` [m] on ``packs`` measured packs
    in parallel per fan, one row per fan of ``engines`` (each with its own power surface;
    ``None``: the largest fan's power), the climb time [s] and the rest of
    :class:`_Launch`; NaN if impossible, the packs' cut-off ``cutoff_v`` [V] reached on the
    way included. The fans are integrated together, as ``(fans, rows)`` arrays."""
    # the roll's and the climb's airspeeds read only the thrust: one reading's for them all
    ok, climb_time, roll_time, rotation, roll_only, groups, widest, used = _shared(
        m, "launch_path", (roll, stall, height), lambda: _launch_path(m, roll, stall, height))
    v_lo, climb_speed = roll[2], used[:, -1]
    climb_time_safe = np.where(ok, climb_time, 0.0)
    params = model.params

    def power(throttle: float, speed: Array) -> Array:
        return np.stack([fan_power_rows(model, m, throttle, speed, engine) for engine in engines])

    fans = len(engines)
    q, peak = np.zeros((fans, m.size)), np.zeros((fans, m.size))
    above = np.ones((fans, m.size), dtype=bool)

    def rk4_rows(rows: Array, h: Array, active: Array,
                 powers: list[tuple[Array, Array, Array]]) -> None:
        # _rk4_phase on these rows of q, peak and above (each a group of its own step count)
        q[:, rows], group_peak, held = _rk4_phase(params, q[:, rows], h, active, powers,
                                                  packs[rows], cutoff_v[rows])
        peak[:, rows] = np.maximum(peak[:, rows], group_peak)
        above[:, rows] &= held

    rolling = power(1.0, used[:, :widest])
    for rows, steps in groups:
        rk4_rows(rows, roll_only[rows] / steps, roll_only[rows] > 0.0,
                 [(rolling[:, rows, j], rolling[:, rows, j + 1], rolling[:, rows, j + 2])
                  for j in range(0, 2 * steps, 2)])
    # the rotation at the lift-off speed: constant power for a second or two, where 2 steps
    # agree with the mission's 8 to ~1e-15
    every = np.arange(m.size)
    rk4_rows(every, rotation / _ROTATION_STEPS, rotation > 0.0,
             [(power(1.0, v_lo),) * 3] * _ROTATION_STEPS)
    q_roll = q.copy()
    # the steady climb at constant power: the mission's 64 steps where it draws more than
    # _LONG_CLIMB_SHARE of the packs (8 were 5e-6 off on a long climb and PASSed at a
    # reserve's edge), 8 where the current hardly changes over it (~1e-9 of the 64)
    climbing = power(1.0, climb_speed)
    drawn = climb_time_safe * np.asarray(current_at_power_a(params, q, climbing, packs)) / 3600.0
    with np.errstate(invalid="ignore"):
        long = np.any(~(drawn <= _LONG_CLIMB_SHARE * packs * params.max_capacity_ah), axis=0)
    for rows, steps in ((np.flatnonzero(~long), _CLIMB_STEPS), (np.flatnonzero(long), STEPS)):
        if rows.size:
            rk4_rows(rows, climb_time_safe[rows] / steps, climb_time_safe[rows] > 0.0,
                     [(climbing[:, rows],) * 3] * steps)
    ok = ok & np.all(above, axis=0)
    return _Launch(np.where(ok, q, np.nan), climb_time, q_roll, roll_time, peak, used,
                   climbing)


def _one_fan_draws_most(model: Any, m: Any, launch: _Launch, throttle: Array,
                        speed: Array, rows: NDArray[np.bool_]) -> bool:
    """True when in every row of ``rows`` one fan's power surface gives the most power at
    every point the launch and the cruise took power at: that fan's packs end the flight,
    and the largest fan's power (one integration) is exactly its own."""
    def top(x: Any, v: Array) -> Array:
        return np.argmax(np.stack([fan_power_rows(model, m, x, v, e)
                                   for e in m.propulsion.engines]), axis=0)

    at_full = top(1.0, launch.full_throttle_speeds_m_s)
    cruising = top(throttle, speed)
    return bool(np.all((at_full == cruising[:, None]) | ~rows[:, None]))


def _most_excess(m: Any, throttle: Array, least: Array, stall: Array) -> tuple[Array, Array]:
    """Largest level-flight thrust excess [N] at ``throttle`` between the least level-flight
    airspeed ``least`` (stall x the envelope's margin) and 8 x ``stall``, and its airspeed:
    the throttle holds level flight somewhere iff it is >= 0 (the same range and test as
    ``throttle >= least level-flight throttle`` of ``EnduranceModel.check_throttle``).
    Coarse grid, then golden-section search (one evaluation per step)."""
    low = least
    # 8 x the stall, not 8 x the margin's speed: a margin of 2.4 searched to 19 x stall, into
    # an extrapolated rise of thrust the single case never reaches (outside audit)
    high = MAX_SPEED_OVER_STALL * stall
    # short of the fans' jet velocity, as the single case: beyond it a fan makes no thrust,
    # whatever the extrapolated polynomial gives
    ceiling = np.asarray(jet_velocity_ceiling_m_s(m.propulsion, m.density),
                         dtype=float).reshape(-1) * np.ones(m.size)

    def short_of_jet(values: Array, speed: Array) -> Array:
        return np.where(speed < (ceiling if speed.ndim == 1 else ceiling[:, None]), values,
                        -np.inf)

    grid = low[:, None] + (high - low)[:, None] * np.linspace(0.0, 1.0, 21)[None, :]
    values = short_of_jet(_excess_grid(m, throttle, grid), grid)
    k = np.argmax(values, axis=1)
    rows = np.arange(m.size)
    a = grid[rows, np.maximum(k - 1, 0)]
    b = grid[rows, np.minimum(k + 1, grid.shape[1] - 1)]
    a, b = golden_section_max(
        lambda speed: short_of_jet(_excess(m, throttle, speed), speed), a, b,
        lambda _a, _b, steps: steps >= GOLDEN_STEPS)
    speed = 0.5 * (a + b)
    most = short_of_jet(_excess(m, throttle, speed), speed)
    # a maximum at the least airspeed itself (the excess falling from there): golden section
    # stops 1e-5 m/s short of it, 6e-6 N below, and "no level flight" (outside audit)
    at_least = short_of_jet(_excess(m, throttle, low), low)
    better = at_least >= most
    return np.where(better, at_least, most), np.where(better, low, speed)


def _excess_grid(m: Any, throttle: Array, speed: Array) -> Array:
    drag = np.asarray(level_flight_drag_n(m.aircraft, speed, m.density), dtype=float)
    return m.thrust(throttle[:, None], speed) - drag


def _excess(m: Any, throttle: Array, speed: Array) -> Array:
    thrust = m.thrust(throttle[:, None], speed[:, None])[:, 0]
    drag = np.asarray(level_flight_drag_n(m.aircraft, speed[:, None], m.density),
                      dtype=float).reshape(-1) * np.ones(m.size)
    return thrust - drag


@dataclass(frozen=True)
class EnduranceRows:
    """The endurance flight per row (NaN where not flown).

    ``minutes`` the flight endurance [min] (climb + cruise; NaN: not attainable, except
    where the cruise ends at the packs' cut-off before the landing reserve: ``cut_first``,
    the time to it), ``airspeed_m_s`` the level-flight airspeed [m/s] on full packs at the
    reference voltage, ``climb_airspeed_m_s`` the launch's climb airspeed [m/s],
    ``power_w`` the power model's electrical power per fan there [W], ``cruise_s`` and
    ``climb_s`` the cruise's and the climb's times [s], ``end_charge_ah`` the charge drawn
    per fan at the cruise's end from the fan that ends it [Ah], ``level`` where the throttle holds
    level flight (short of the jet velocity, a fan's models possible, the packs above their
    cut-off at the start).
    """

    minutes: Array
    cut_first: NDArray[np.bool_]
    airspeed_m_s: Array
    climb_airspeed_m_s: Array
    power_w: Array
    cruise_s: Array
    climb_s: Array
    end_charge_ah: Array
    level: NDArray[np.bool_]

    def endurance_min(self) -> Array:
        """The requirement's value [min]: NaN where no reserve is kept (the cut-off first)."""
        return np.where(self.cut_first, np.nan, self.minutes)


def level_airspeed(m: Any, throttle: Array, stall: Array) -> tuple[Array, NDArray[np.bool_]]:
    """The fast level-flight airspeed [m/s] per row at ``throttle`` [-] (all engines, the
    reference voltage) and where the throttle holds level flight at or above the least
    level-flight airspeed (``stall`` [m/s] x the envelope's margin)."""
    # thrust only: one reading's for them all (its flags copied, the caller narrows them)
    speed, ok = _shared(m, "level_airspeed", (throttle, stall),
                        lambda: _level_airspeed(m, throttle, stall))
    return speed, ok.copy()


def _level_airspeed(m: Any, throttle: Array, stall: Array) -> tuple[Array, NDArray[np.bool_]]:
    most, least_speed = _most_excess(m, throttle, m.least_airspeed(), stall)
    # a throttle down to the least one less 1e-9 holds it (EnduranceModel.check_throttle)
    ok = (most >= 0.0) | (_excess(m, throttle + 1e-9, least_speed) >= 0.0)
    # an airspeed above the fast level-flight root: the bracket's upper end
    guess = np.maximum(least_speed, stall) * 1.25
    found = np.zeros(m.size, dtype=bool)
    for _ in range(60):
        found |= _excess(m, throttle, guess) < 0.0
        if found[ok].all():
            break
        guess = np.where(found, guess, guess * 1.25)
    ok &= found
    speed = bracketed_root(
        lambda v: _excess(m, throttle, v), np.where(ok, least_speed, 1.0), np.where(ok, guess, 2.0)
    )
    return speed, ok


def flight_endurance_min(m: Any, model: Any, throttle: Array,
                         roll: tuple[Array, Array, Array, Array],
                         battery: dict[str, Array]) -> tuple[Array, Array, Array]:
    """Flight endurance [min] per row, NaN where not attainable, the level-flight airspeed
    [m/s] on full packs (the result's) and the launch's climb airspeed [m/s]
    (:func:`flight_rows`)."""
    rows = flight_rows(m, model, throttle, roll, battery)
    return rows.endurance_min(), rows.airspeed_m_s, rows.climb_airspeed_m_s


def flight_rows(m: Any, model: Any, throttle: Array, roll: tuple[Array, Array, Array, Array],
                battery: dict[str, Array],
                launches: dict[tuple[Any, ...], _Launch] | None = None) -> EnduranceRows:
    """The endurance flight of each row (:class:`EnduranceRows`): ``m`` the rows' physics
    (:class:`.batch_model.BatchModel`), ``model`` the battery side (:func:`battery_side`),
    ``throttle`` [-] per row, ``roll`` the take-off's roll tuple, ``battery`` the rows'
    battery keys (``dotted.BATTERY_KEYS``); ``launches`` the launch per fans flown, kept by
    a caller that flies the same rows at other throttles (the launch is full throttle)."""
    launches = {} if launches is None else launches
    stall = stall_speed(m)
    from tuflexperf.analysis.pack_limits import pack_rows

    # the battery keys that vary without refitting the pack (dotted.BATTERY_KEYS); a pack of
    # another capacity flies as that many measured packs in parallel
    rows = pack_rows(model.battery, battery)
    capacity, packs, cutoff = rows.capacity_ah, rows.circuit_packs, rows.cutoff_v
    reserve_ah = rows.reserve_charge_ah
    # level flight counts from stall x the envelope's margin, as EnduranceModel.least_m_s
    speed, ok = level_airspeed(m, throttle, stall)
    # a cruise at or beyond the fans' jet velocity flies on no thrust (the mission's rule)
    density = np.asarray(m.density, dtype=float).reshape(-1, 1)
    ok &= ~beyond_jet_velocity(m.propulsion, speed[:, None], density)[:, 0]
    power_w = fan_power_rows(model, m, throttle, speed)
    ok &= ~_impossible_cruise(m, throttle, speed, power_w)
    params = model.params
    # the packs in parallel per fan fly, not one of them alone (EnduranceModel.solve)
    ok &= (cutoff_residual_v(params, 0.0, power_w, cutoff, packs) > 0.0)
    level = ok.copy()  # the single case's checks before it flies its mission
    # each fan on its own packs, with its own power surface, as the mission flies them: the
    # flight ends when the first fan's packs do (the largest launch charge with the largest
    # cruise power, of different fans at low throttle, was 2 % short; outside audit). Where
    # one fan draws the most throughout, the largest fan's power is exactly its own
    height = battery["battery.mission.pattern_altitude_m"]
    engines: tuple[Any, ...] = (None,)

    def launched(engines: tuple[Any, ...]) -> _Launch:
        # keyed by which fans fly, not by the engines (an engine may hold unhashable maps)
        key = tuple(None if e is None else e.name for e in engines)
        if key not in launches:
            launches[key] = _launch_charge(m, model, roll, stall, height, packs, cutoff,
                                           engines)
        return launches[key]

    launch = launched(engines)
    if isinstance(model.power, PowerSurfaces) and len(m.propulsion.engines) > 1 \
            and not _one_fan_draws_most(model, m, launch, throttle, speed,
                                        ok & np.all(np.isfinite(launch.charge_ah), axis=0)):
        engines = m.propulsion.engines
        launch = launched(engines)
    climb_time = launch.climb_time_s
    # the climb's airspeed (the last of them), where there is a climb
    climb = np.where(height > 0, launch.full_throttle_speeds_m_s[:, -1], np.nan)
    ok &= np.all(np.isfinite(launch.charge_ah), axis=0)
    # every fan at once, as (fans, rows)
    own = np.stack([fan_power_rows(model, m, throttle, speed, engine) for engine in engines])
    q_cut = bracketed_root(
        lambda q: np.asarray(cutoff_residual_v(params, q, own, cutoff, packs), dtype=float),
        np.zeros(own.shape),
        np.broadcast_to(packs * params.max_capacity_ah * (1.0 - 1e-12), own.shape).copy(),
    )
    start = np.where(ok, launch.charge_ah, 0.0)
    # a launch that leaves no cruise before the reserve or the cut-off is not attainable
    # (the single case's mission): the batch counted the climb alone (outside audit)
    ok &= np.all(np.minimum(q_cut, reserve_ah) > start, axis=0)
    span = np.maximum(np.minimum(q_cut, reserve_ah) - start, 0.0)
    seconds = np.asarray(discharge_time_s(params, np.where(ok, own, 1.0), start, start + span,
                                          packs), dtype=float)
    ok &= np.all(_within_rating(model, launch, own, start, span, seconds, packs, capacity),
                 axis=0)
    cruise_s = np.min(seconds, axis=0)
    # the first fan to end ends at its packs' cut-off before the landing reserve: no reserve
    # is kept at the cruise's power, the endurance is not attainable (as endurance_verdict)
    first = np.argmin(seconds, axis=0)
    columns = np.arange(seconds.shape[1])
    cut_first = ok & np.broadcast_to(q_cut < reserve_ah, seconds.shape)[first, columns]
    if m.propulsion.reference_voltage_v is not None:
        # thrust and power follow the packs' loaded voltage: flown as the single case's
        # mission flies them (the constant-power cruise above only sizes the steps)
        from tuflexperf.analysis.batch_sagging import flight_on_sagging_packs

        sag = flight_on_sagging_packs(m, model, rows, throttle, roll, stall, height, speed,
                                      level, np.where(ok & ~cut_first, cruise_s, np.nan))
        return EnduranceRows(sag.minutes, sag.cut_first, speed, climb, power_w, sag.cruise_s,
                             sag.climb_s, sag.end_charge_ah, level)
    minutes = cruise_s / 60.0 + np.where(ok, climb_time, 0.0) / 60.0
    flown = ok & np.isfinite(minutes)
    end_ah = np.broadcast_to(np.minimum(q_cut, reserve_ah), seconds.shape)[first, columns]
    return EnduranceRows(np.where(flown, minutes, np.nan), flown & cut_first, speed, climb,
                         power_w, np.where(flown, cruise_s, np.nan),
                         np.where(flown, climb_time, np.nan),
                         np.where(flown, end_ah, np.nan), level)


def _impossible_cruise(m: Any, throttle: Array, speed: Array, power_w: Array) -> Array:
    """Rows whose cruise the single case refuses for an engine's models: a fan whose thrust
    or electrical power is not positive there (``MissionModel._braking_engine``), or whose
    power is under 1/``IMPOSSIBLE_FIGURE_OF_MERIT`` of momentum theory's ideal power for its
    thrust (``EnduranceModel._result``: no fan flies on it); each engine's own power surface
    where it has one, else the per-fan ``power_w`` [W], as ``models.agreement.agreement_at``."""
    area = m.propulsion.fan_area_m2
    impossible = np.zeros(m.size, dtype=bool)
    scale = density_ratio(m.propulsion, m.density)
    x, v = throttle.reshape(-1, 1) * np.ones((m.size, 1)), speed.reshape(-1, 1)
    density = np.asarray(m.density, dtype=float).reshape(-1, 1)
    for engine in m.propulsion.engines:
        surface = engine_power_w(engine, x, v)
        power = scale * surface if surface is not None else power_w.reshape(-1, 1)
        thrust = engine_thrust_n(engine, x, v, scale)
        impossible |= ~((thrust > 0.0) & (power > 0.0)).reshape(-1)
        if area is None:
            continue
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            merit = np.asarray(figure_of_merit(thrust, v, density, area, power), dtype=float)
        impossible |= (merit > IMPOSSIBLE_FIGURE_OF_MERIT).reshape(-1)
    return impossible


def _within_rating(model: Any, launch: _Launch, power_w: Array, start: Array,
                   span: Array, cruise_s: Array, packs: Array, capacity_ah: Array) -> Array:
    """Per fan and row ``(fans, rows)``: the packs of ``capacity_ah`` [Ah] (flying as
    ``packs`` measured ones) stay within their rating, by the mission's two rules
    (``MissionModel._beyond_rating``): no current beyond the burst rating, and no stretch of
    30 s or more of the flight beyond the continuous one on average.

    The flight's charge is taken where the phases meet, the roll at its mean current, and
    ``w = min(30 s, phase / 2)`` into and before the end of the climb and of the cruise: each
    at constant power, its current rising as the pack sags (its heaviest 30 s are its last),
    the current over such a stretch the one at the charge halfway through it (midpoint rule).
    """
    battery = model.battery
    if battery.max_discharge_c is None:
        return np.ones(np.shape(power_w), dtype=bool)
    rating = float(battery.max_discharge_c) * capacity_ah
    per_pack = battery.packs_in_parallel_per_engine
    params = model.params
    # the cruise at constant power draws most at its end (the pack sags)
    cruise_end = np.asarray(current_at_power_a(params, start + span, power_w, packs),
                            dtype=float)
    peak = np.maximum(launch.peak_current_a, cruise_end) / per_pack
    ok = ~(peak > BURST_OVER_CONTINUOUS * rating * (1.0 + 1e-9))
    shape = np.shape(start)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):

        def stretch(q0: Array, q1: Array, seconds: Array, power: Array) -> list[Array]:
            # a constant-power phase from charge q0 to q1 [Ah] in ``seconds``: its times
            # and charges w after its start and w before its end
            w = np.minimum(RATING_SEGMENT_S, 0.5 * seconds)

            def mean_current(q: Array, toward: float) -> Array:
                i = np.asarray(current_at_power_a(params, q, power, packs), dtype=float)
                mid = q + toward * i * w / 2.0 / SECONDS_PER_HOUR
                return np.asarray(current_at_power_a(params, mid, power, packs), dtype=float)

            return [w, seconds - w, q0 + mean_current(q0, 1.0) * w / SECONDS_PER_HOUR,
                    q1 - mean_current(q1, -1.0) * w / SECONDS_PER_HOUR]

        roll_s = np.broadcast_to(launch.roll_time_s, shape)
        climb_s = np.broadcast_to(np.nan_to_num(launch.climb_time_s), shape)
        launch_s = roll_s + climb_s
        c_in, c_out, cq_in, cq_out = stretch(launch.roll_charge_ah, start, climb_s,
                                             launch.climb_power_w)
        k_in, k_out, kq_in, kq_out = stretch(start, start + span, cruise_s, power_w)
        zero = np.zeros(shape)
        times = np.stack([zero, roll_s, roll_s + c_in, roll_s + c_out, launch_s,
                          launch_s + k_in, launch_s + k_out, launch_s + cruise_s], axis=-1)
        charges = np.stack([zero, launch.roll_charge_ah, cq_in, cq_out, start, kq_in, kq_out,
                            start + span], axis=-1) / per_pack
        nodes = times.shape[-1]
        end, _, _ = first_window_beyond(
            times.reshape(-1, nodes), charges.reshape(-1, 1, nodes),
            np.broadcast_to(rating, shape).reshape(-1), RATING_SEGMENT_S)
    return ok & (end == np.inf).reshape(shape)
