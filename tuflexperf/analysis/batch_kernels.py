"""Vectorised helpers the batch evaluators share: per-fan power, stall speed, roots and maxima.

Each works per row of a batch (one row per sample or grid point) and stops each row at its
own convergence, so a row's answer does not depend on the rows that share its batch.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.constants import MAX_SPEED_OVER_STALL, SPEED_GRID_POINTS
from tuflexperf.models.aircraft import climb_sine, level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.powertrain import (
    PowerSurfaces,
    engine_power_w,
    jet_velocity_ceiling_m_s,
)
from tuflexperf.models.thrust import POLY22_TERMS, Propulsion, density_ratio

Array = NDArray[np.float64]


def fan_power_rows(model: Any, m: Any, throttle: Any, speed: Any, engine: Any = None) -> Array:
    """Per-fan electrical power [W] per row: the nominal model's power (the largest fan's),
    or ``engine``'s own surface, a propulsion power surface rescaled to the row's density
    (``rho / rho_ref``, as the single case does); times the row's sampled power scale."""
    power = _unscaled_power_rows(model, m, throttle, speed, engine)
    scale = getattr(m, "power_scale", None)
    if scale is None:
        return power
    scale = np.asarray(scale, dtype=float)
    if scale.ndim == 0 or power.ndim == 0:
        return power * scale
    return power * scale.reshape(-1, *([1] * (power.ndim - 1)))


def _unscaled_power_rows(model: Any, m: Any, throttle: Any, speed: Any,
                         engine: Any = None) -> Array:
    if not isinstance(model.power, PowerSurfaces):
        return np.asarray(model.power.electrical_power_w(throttle, speed), dtype=float)
    if engine is None:
        power = np.asarray(model.power.electrical_power_w(throttle, speed), dtype=float)
    else:
        power = model.power.density_scale * np.asarray(engine_power_w(engine, throttle, speed),
                                                       dtype=float)
    ratio = np.asarray(density_ratio(m.propulsion, m.density), dtype=float)
    ratio = ratio / model.power.density_scale
    if ratio.size == 1 or power.ndim == 0:
        return power * ratio.reshape(-1)[0] if ratio.size == 1 else power * ratio.reshape(-1)
    return power * ratio.reshape(-1, *([1] * (power.ndim - 1)))

GOLDEN_STEPS = 25

_BISECTIONS = 60


def golden_section_max(
    f: Callable[[Array], Array], a: Array, b: Array,
    done: Callable[[Array, Array, int], bool],
) -> tuple[Array, Array]:
    """The bracket ``[a, b]`` per row around the maximum of a unimodal ``f`` (vectorised
    golden-section search, one evaluation of ``f`` per step) once ``done(a, b, steps)``.

    References
    ----------
    Kiefer, "Sequential minimax search for a maximum", Proc. AMS 4 (1953).
    """
    golden = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - golden * (b - a), a + golden * (b - a)
    fc, fd = f(c), f(d)
    steps = 0
    while not done(a, b, steps):
        left = fc >= fd
        a, b = np.where(left, a, c), np.where(left, d, b)
        c_new = np.where(left, b - golden * (b - a), d)
        d_new = np.where(left, c, a + golden * (b - a))
        fp = f(np.where(left, c_new, d_new))
        fc, fd = np.where(left, fp, fd), np.where(left, fc, fp)
        c, d = c_new, d_new
        steps += 1
    return a, b


def best_climb(m: Any, v_lo: Array, stall: Array) -> tuple[Array, Array]:
    """Best-rate airspeed [m/s] and rate ``(T - D) V / W`` [m/s] (small angle, ``L = W``:
    Anderson, *Aircraft Performance and Design*, 5.10) per row on the 4001-point grid from
    ``v_lo`` to 8 x ``stall`` [m/s], short of the jet velocity (one row for the endurance's
    mission plan, ``endurance_plan._best_climb``).

    The rate ``(T - D) V / W`` is unimodal in airspeed: a golden-section search over the
    grid index, then the grid points beside it, pick the same grid point as the full scan.
    """
    n = SPEED_GRID_POINTS
    top = MAX_SPEED_OVER_STALL * stall
    ceiling = np.asarray(jet_velocity_ceiling_m_s(m.propulsion, m.density),
                         dtype=float).reshape(-1, 1) * np.ones((m.size, 1))
    weight = np.asarray(m.aircraft.weight_n, dtype=float).reshape(-1, 1)

    def rate_at(index: Array) -> tuple[Array, Array]:
        speed = v_lo[:, None] + (top - v_lo)[:, None] * index / (n - 1)
        excess = m.thrust(1.0, speed) - np.asarray(
            level_flight_drag_n(m.aircraft, speed, m.density), dtype=float)
        # no climb at or beyond the jet velocity (the grid's first point excepted)
        rate = np.where((speed >= ceiling) & (index > 0), -np.inf,
                        np.asarray(climb_sine(excess / weight), dtype=float) * speed)
        return rate, speed

    a, _ = golden_section_max(
        lambda index: rate_at(index[:, None])[0][:, 0],
        np.zeros(m.size), np.full(m.size, float(n - 1)),
        lambda a, b, _: not np.any(b - a > 4.0),
    )
    near = np.clip(np.floor(a)[:, None] + np.arange(-2, 8)[None, :], 0, n - 1)
    rate, speed = rate_at(near)
    best = np.argmax(rate, axis=1)
    rows = np.arange(m.size)
    return speed[rows, best], rate[rows, best]


def bracketed_root(f: Any, low: Array, high: Array) -> Array:
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
    low, high, f_low, f_high = illinois(f, low, high, f_low, f_high,
                                        np.ones(np.shape(low), dtype=bool))
    return np.where(np.abs(f_low) <= np.abs(f_high), low, high)


def illinois(f: Any, low: Array, high: Array, f_low: Array, f_high: Array,
             going: NDArray[np.bool_], steps: int = _BISECTIONS
             ) -> tuple[Array, Array, Array, Array]:
    """The Illinois variant of regula falsi on the brackets ``[low, high]`` with
    ``f(low) >= 0 > f(high)`` of the rows ``going`` (vectorised): the brackets and their
    values once each row has converged (to 1e-13 relative, or a zero) or after ``steps``.

    A row stops at its own convergence: its root is the same whatever rows share its batch.

    References
    ----------
    Dahlquist & Bjorck, *Numerical Methods*, 6.2.
    """
    going = going.copy()
    for _ in range(steps):
        with np.errstate(invalid="ignore", divide="ignore"):
            trial = high - f_high * (high - low) / (f_high - f_low)
        trial = np.where(np.isfinite(trial) & (trial > low) & (trial < high), trial,
                         0.5 * (low + high))
        f_trial = f(trial)
        up = going & (f_trial >= 0.0)
        down = going & ~(f_trial >= 0.0)
        # Illinois: halve the value kept at the end that did not move
        f_high = np.where(up, 0.5 * f_high, f_high)
        f_low = np.where(down, 0.5 * f_low, f_low)
        low, f_low = np.where(up, trial, low), np.where(up, f_trial, f_low)
        high, f_high = np.where(down, trial, high), np.where(down, f_trial, f_high)
        going &= ~((high - low) <= 1e-13 * np.maximum(np.abs(high), 1.0)) & (f_trial != 0)
        if not going.any():
            break
    return low, high, f_low, f_high


def stall_speed(model: Any) -> Array:
    """1-g stall speed [m/s] per row."""
    return np.asarray(stall_speed_m_s(model.aircraft, model.density), dtype=float).reshape(-1) \
        * np.ones(model.size)


def nominal_engines(propulsion: Propulsion) -> Array:
    """The nominal coefficients as ``(E, 6)`` (POLY22_TERMS order)."""
    return np.array([[e.coefficients[t] for t in POLY22_TERMS] for e in propulsion.engines])
