"""Flight endurance for a batch of parameter sets: the steps of ``EnduranceModel``, vectorised.

Per row, exactly as :class:`tuflexperf.analysis.endurance.EnduranceModel` does for one
case: the launch (ground-roll time history, best full-throttle climb on the same 4001-point
airspeed grid, the same RK4 of the constant-power current in 0.25 s steps), the least
throttle of level flight, the fast level-flight root at the throttle, the pack's cut-off
charge, and the Gauss-Legendre discharge time from the launch charge to the reserve.
Newton per case becomes bisection over the batch (same roots, bracketed). The battery's
parameters and the fan's power model are the nominal case's (they come from the battery
file, not from the sampled aircraft).

References
----------
Paper section 4 (endurance estimate); Tremblay & Dessaint (2009) (pack model);
Anderson, *Aircraft Performance and Design*, 5.10 (climb).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis import endurance as single
from tuflexperf.models.aircraft import level_flight_drag_n
from tuflexperf.models.battery import (
    current_at_power_a,
    cutoff_residual_v,
    discharge_time_s,
)
from tuflexperf.models.powertrain import PowerSurfaces
from tuflexperf.models.thrust import density_ratio

Array = NDArray[np.float64]


def _power_w(model: Any, m: Any, throttle: Any, speed: Any) -> Array:
    """Per-fan electrical power [W] per row: the nominal model's power, a propulsion power
    surface rescaled to the row's density (``rho / rho_ref``, as the single case does)."""
    power = np.asarray(model.power.electrical_power_w(throttle, speed), dtype=float)
    if not isinstance(model.power, PowerSurfaces):
        return power
    ratio = np.asarray(density_ratio(m.propulsion, m.density), dtype=float)
    ratio = ratio / model.power.density_scale
    if ratio.size == 1 or power.ndim == 0:
        return power * ratio.reshape(-1)[0] if ratio.size == 1 else power * ratio.reshape(-1)
    return power * ratio.reshape(-1, *([1] * (power.ndim - 1)))


def battery_side(case: Any) -> Any:
    """What the batch takes from the case's endurance model: the battery, its fitted pack
    model (``params``), the packs per engine and the fan power model.

    The deterministic :func:`endurance_model` (cached, so ``check`` has built it already);
    where the nominal case cannot launch (it never rolls to lift-off) that model does not
    exist, but its battery side does, and the batch's other rows may well launch.

    References
    ----------
    Paper section 4 (endurance estimate); SPEC 4 (battery file).
    """
    from types import SimpleNamespace

    from tuflexperf.errors import NotAttainable

    try:
        return single.endurance_model(case)
    except NotAttainable:
        from tuflexperf.io.battery import load_battery
        from tuflexperf.models.powertrain import power_surfaces

        battery = load_battery(case.battery_path)
        characterised = single.characterise_battery(battery, case)
        # the same choice as EnduranceModel: the propulsion's power surfaces, else the
        # battery file's fan-power law
        surfaces = power_surfaces(case.propulsion, case.density_kg_m3)
        return SimpleNamespace(
            battery=battery, params=characterised.fit.parameters,
            packs=battery.packs_in_parallel_per_engine,
            power=surfaces if surfaces is not None else characterised.power.model)


_GOLDEN_STEPS = 25
_CLIMB_STRIDE = 16  # single-case launch steps per batch RK4 step in the steady climb
_BISECTIONS = 60


def _best_climb(m: Any, v_lo: Array, stall: Array) -> tuple[Array, Array]:
    """Best-rate airspeed and rate per row on the 4001-point grid of ``endurance._best_climb``.

    The rate ``(T - D) V / W`` is unimodal in airspeed: a golden-section search over the
    grid index, then the grid points beside it, pick the same grid point as the full scan.
    """
    n = single._SPEED_GRID_POINTS
    top = single._MAX_SPEED_OVER_STALL * stall
    weight = np.asarray(m.aircraft.weight_n, dtype=float).reshape(-1, 1)

    def rate_at(index: Array) -> tuple[Array, Array]:
        speed = v_lo[:, None] + (top - v_lo)[:, None] * index / (n - 1)
        excess = m.thrust(1.0, speed) - np.asarray(
            level_flight_drag_n(m.aircraft, speed, m.density), dtype=float)
        return excess * speed / weight, speed

    golden = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = np.zeros(m.size), np.full(m.size, float(n - 1))
    c, d = b - golden * (b - a), a + golden * (b - a)
    fc, fd = rate_at(c[:, None])[0][:, 0], rate_at(d[:, None])[0][:, 0]
    while np.any(b - a > 4.0):
        left = fc >= fd
        a, b = np.where(left, a, c), np.where(left, d, b)
        c_new = np.where(left, b - golden * (b - a), d)
        d_new = np.where(left, c, a + golden * (b - a))
        probe = np.where(left, c_new, d_new)
        fp = rate_at(probe[:, None])[0][:, 0]
        fc, fd = np.where(left, fp, fd), np.where(left, fc, fp)
        c, d = c_new, d_new
    near = np.clip(np.floor(a)[:, None] + np.arange(-2, 8)[None, :], 0, n - 1)
    rate, speed = rate_at(near)
    best = np.argmax(rate, axis=1)
    rows = np.arange(m.size)
    return speed[rows, best], rate[rows, best]


def _interp_rows(step: Array, count: int, t_hist: Array, v_hist: Array) -> Array:
    """``np.interp(j step[i], t_hist[i], v_hist[i])`` for every row ``i`` and ``j < count``.

    The query times are uniform per row, so each history time ``t_k`` is counted once, at
    the first query ``j = ceil(t_k / step)`` that reaches it (one ``bincount`` over all
    rows), and a cumulative sum gives every query's interval: no search.
    """
    rows, width = t_hist.shape
    safe = np.where(step > 0, step, 1.0)[:, None]
    first = np.clip(np.ceil(t_hist / safe), 0, count).astype(np.intp)
    # a history time within rounding of a query time counts as reached (side="right")
    first = np.where((first > 0) & ((first - 1) * safe >= t_hist), first - 1, first)
    flat = (first + (count + 1) * np.arange(rows)[:, None]).ravel()
    reached = np.cumsum(np.bincount(flat, minlength=rows * (count + 1)).reshape(
        rows, count + 1)[:, :count], axis=1)
    index = np.clip(reached - 1, 0, width - 2)
    t = safe * np.arange(count)[None, :]
    t0 = np.take_along_axis(t_hist, index, axis=1)
    t1 = np.take_along_axis(t_hist, index + 1, axis=1)
    v0 = np.take_along_axis(v_hist, index, axis=1)
    v1 = np.take_along_axis(v_hist, index + 1, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        value = v0 + (t - t0) * (v1 - v0) / (t1 - t0)
    return np.where(t >= t_hist[:, -1:], v_hist[:, -1:], value)


def _launch_charge(m: Any, model: Any, roll: tuple[Array, Array, Array, Array],
                   stall: Array, height: Array) -> tuple[Array, Array]:
    """Charge [Ah] per fan drawn by roll + climb to ``height`` [m], and the climb time [s];
    NaN if impossible."""
    _, roll_time, v_lo, ok = roll
    packs = model.battery.packs_in_parallel_per_engine
    climb_speed, climb_rate = _best_climb(m, v_lo, stall)
    ok = (ok > 0.5) & ~((height > 0) & (climb_rate <= 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        climb_time = np.where(ok, np.where(height > 0, height / climb_rate, 0.0), np.nan)
    roll_time = np.where(ok, roll_time, 0.0)
    climb_time_safe = np.where(ok, climb_time, 0.0)
    # a catapult launch has no roll: its history is never looked up (the roll time is 0)
    t_hist = (np.zeros((m.size, 2)) if m.aircraft.launch == "catapult" else m.roll_history())
    v_hist = v_lo[:, None] * np.linspace(0.0, 1.0, t_hist.shape[1])[None, :]
    climb_power = _power_w(model, m, 1.0, climb_speed)
    total = roll_time + climb_time_safe
    steps = np.maximum(1, np.ceil(total / single._LAUNCH_STEP_S)).astype(int)
    dt = total / steps
    # RK4 stage times are the half-steps j dt / 2: the power at each, looked up at once
    # where the row is still rolling (the same linear interpolation of the roll history).
    rolling_stages = int(np.max(np.where(ok, np.ceil(2.0 * roll_time / np.where(dt > 0, dt, 1.0)),
                                         0))) + 1
    stage_t = dt[:, None] * 0.5 * np.arange(rolling_stages)[None, :]
    rolling = _power_w(model, m, 1.0, _interp_rows(
        np.where(ok, dt * 0.5, 0.0), rolling_stages, np.where(ok[:, None], t_hist, 0.0), v_hist))
    stage_power = np.where(stage_t < roll_time[:, None], rolling, climb_power[:, None])

    def power_at(j: int) -> Array:
        return stage_power[:, j] if j < rolling_stages else climb_power

    def rate(j: int, charge: Array) -> Array:
        return np.asarray(current_at_power_a(model.params, charge, power_at(j), packs)) / 3600.0

    # the steps that touch the roll: the single case's RK4 step by step (its power lookups
    # along the roll history); k0 is the first step whose stages all lie in the climb
    with np.errstate(divide="ignore", invalid="ignore"):
        k0 = np.ceil(roll_time / dt)
    k0 = np.where(np.isfinite(k0), k0, 0.0)
    k0 = np.where((k0 > 0) & (dt * (k0 - 1) >= roll_time), k0 - 1, k0)
    k0 = np.where(dt * k0 < roll_time, k0 + 1, k0)
    k0 = np.clip(k0, 0, steps).astype(int)
    q = np.zeros(m.size)
    for k in range(int(k0.max()) if k0.size else 0):
        active = k < k0
        k1 = rate(2 * k, q)
        k2 = rate(2 * k + 1, q + dt / 2 * k1)
        k3 = rate(2 * k + 1, q + dt / 2 * k2)
        k4 = rate(2 * k + 2, q + dt * k3)
        q = np.where(active, q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4), q)
    # the rest is the climb at constant power, dq/dt = i(q, P)/3600, smooth and slow (the
    # current changes ~1 % over it): RK4 in strides of _CLIMB_STRIDE of the single case's
    # steps gives the same charge to ~1e-12 Ah in a sixteenth of the evaluations
    left = steps - k0
    strides = np.ceil(left / _CLIMB_STRIDE).astype(int)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(strides > 0, left * dt / np.maximum(strides, 1), 0.0)

    def climb_rate_ah(charge: Array) -> Array:
        return np.asarray(current_at_power_a(model.params, charge, climb_power, packs)) / 3600.0

    for k in range(int(strides.max()) if strides.size else 0):
        active = k < strides
        k1 = climb_rate_ah(q)
        k2 = climb_rate_ah(q + h / 2 * k1)
        k3 = climb_rate_ah(q + h / 2 * k2)
        k4 = climb_rate_ah(q + h * k3)
        q = np.where(active, q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), q)
    return np.where(ok, q, np.nan), climb_time


def _most_excess(m: Any, throttle: Array, stall: Array) -> tuple[Array, Array]:
    """Largest level-flight thrust excess [N] at ``throttle`` between stall and 8 x stall,
    and its airspeed: the throttle holds level flight somewhere iff it is >= 0 (the same
    test as ``throttle >= least level-flight throttle`` of ``EnduranceModel.check_throttle``).
    Coarse grid, then golden-section search (one evaluation per step)."""
    low = stall
    high = single._MAX_SPEED_OVER_STALL * stall
    grid = low[:, None] + (high - low)[:, None] * np.linspace(0.0, 1.0, 21)[None, :]
    values = _excess_grid(m, throttle, grid)
    k = np.argmax(values, axis=1)
    rows = np.arange(m.size)
    a = grid[rows, np.maximum(k - 1, 0)]
    b = grid[rows, np.minimum(k + 1, grid.shape[1] - 1)]
    golden = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - golden * (b - a), a + golden * (b - a)
    fc, fd = _excess(m, throttle, c), _excess(m, throttle, d)
    for _ in range(_GOLDEN_STEPS):
        left = fc >= fd
        a, b = np.where(left, a, c), np.where(left, d, b)
        c_new = np.where(left, b - golden * (b - a), d)
        d_new = np.where(left, c, a + golden * (b - a))
        probe = np.where(left, c_new, d_new)
        fp = _excess(m, throttle, probe)
        fc, fd = np.where(left, fp, fd), np.where(left, fc, fp)
        c, d = c_new, d_new
    speed = 0.5 * (a + b)
    return _excess(m, throttle, speed), speed


def _bracketed_root(f: Any, low: Array, high: Array) -> Array:
    """Root of ``f`` per row in [low, high] with ``f(low) >= 0 > f(high)`` (vectorised).

    Bisection to a 1/4096 bracket, then the Illinois variant of regula falsi, which keeps
    the bracket and converges superlinearly (Dahlquist & Bjorck, *Numerical Methods*, 6.2).
    Rows whose bracket is not one come out somewhere inside it; callers mask them.
    """
    f_low, f_high = f(low), f(high)
    for _ in range(12):
        mid = 0.5 * (low + high)
        f_mid = f(mid)
        up = f_mid >= 0.0
        low, f_low = np.where(up, mid, low), np.where(up, f_mid, f_low)
        high, f_high = np.where(up, high, mid), np.where(up, f_high, f_mid)
    for _ in range(_BISECTIONS):
        with np.errstate(invalid="ignore", divide="ignore"):
            trial = high - f_high * (high - low) / (f_high - f_low)
        trial = np.where(np.isfinite(trial) & (trial > low) & (trial < high), trial,
                         0.5 * (low + high))
        f_trial = f(trial)
        up = f_trial >= 0.0
        # Illinois: halve the value kept at the end that did not move
        f_high = np.where(up, 0.5 * f_high, f_high)
        f_low = np.where(up, f_low, 0.5 * f_low)
        low, f_low = np.where(up, trial, low), np.where(up, f_trial, f_low)
        high, f_high = np.where(up, high, trial), np.where(up, f_high, f_trial)
        if np.all((high - low) <= 1e-13 * np.maximum(np.abs(high), 1.0)) or np.all(f_trial == 0):
            break
    return np.where(np.abs(f_low) <= np.abs(f_high), low, high)


def _excess_grid(m: Any, throttle: Array, speed: Array) -> Array:
    drag = np.asarray(level_flight_drag_n(m.aircraft, speed, m.density), dtype=float)
    return m.thrust(throttle[:, None], speed) - drag


def _excess(m: Any, throttle: Array, speed: Array) -> Array:
    thrust = m.thrust(throttle[:, None], speed[:, None])[:, 0]
    drag = np.asarray(level_flight_drag_n(m.aircraft, speed[:, None], m.density),
                      dtype=float).reshape(-1) * np.ones(m.size)
    return thrust - drag


def flight_endurance_min(m: Any, model: Any, throttle: Array,
                         roll: tuple[Array, Array, Array, Array],
                         battery: dict[str, Array]) -> Array:
    """Flight endurance [min] per row; NaN where the single-case analysis says not attainable."""
    from tuflexperf.analysis.batch import stall_speed

    stall = stall_speed(m)
    q_launch, climb_time = _launch_charge(m, model, roll, stall,
                                          battery["battery.mission.pattern_altitude_m"])
    # the battery keys that vary without refitting the pack (dotted.BATTERY_KEYS)
    cutoff = model.battery.cells_in_series * battery["battery.cutoff_voltage_per_cell_v"]
    reserve_ah = (model.packs * model.battery.capacity_ah
                  * (1.0 - battery["battery.mission.landing_reserve_fraction"]))
    # level flight counts from stall x the envelope's margin, as EnduranceModel.least_m_s
    most, least_speed = _most_excess(m, throttle, m.least_airspeed())
    ok = np.isfinite(q_launch) & (most >= 0.0)
    # an airspeed above the fast level-flight root, as EnduranceModel._speed_guess
    guess = np.maximum(least_speed, stall) * 1.25
    found = np.zeros(m.size, dtype=bool)
    for _ in range(60):
        found |= _excess(m, throttle, guess) < 0.0
        if found[ok].all():
            break
        guess = np.where(found, guess, guess * 1.25)
    ok &= found
    speed = _bracketed_root(
        lambda v: _excess(m, throttle, v), np.where(ok, least_speed, 1.0), np.where(ok, guess, 2.0)
    )
    power_w = _power_w(model, m, throttle, speed)
    params, packs = model.params, model.packs
    ok &= (cutoff_residual_v(params, 0.0, power_w, cutoff, 1) > 0.0)
    ok &= (cutoff_residual_v(params, 0.0, power_w, cutoff, packs) > 0.0)
    q_cut = _bracketed_root(
        lambda q: np.asarray(cutoff_residual_v(params, q, power_w, cutoff, packs), dtype=float),
        np.zeros(m.size),
        np.full(m.size, packs * params.max_capacity_ah * (1.0 - 1e-12)),
    )
    start = np.where(ok, q_launch, 0.0)
    span = np.maximum(np.minimum(q_cut, reserve_ah) - start, 0.0)
    cruise_s = np.asarray(discharge_time_s(params, np.where(ok, power_w, 1.0), start,
                                           start + span, packs), dtype=float)
    minutes = cruise_s / 60.0 + np.where(ok, climb_time, 0.0) / 60.0
    return np.where(ok & np.isfinite(minutes), minutes, np.nan)
