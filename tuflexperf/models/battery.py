"""LiPo pack discharge model (equivalent circuit) and the fan's electrical power.

Equivalent circuit (open-circuit voltage of the drawn charge plus a series resistance),
in the Shepherd form with Tremblay's exponential zone:

``V(q, i) = E0 - G q + A exp(-B q) - K q / (Q - q) - R i``

* ``q`` charge drawn from one pack in Ah, ``i`` pack current in A, ``V`` terminal volts;
* ``E0 - G q`` the plateau (linear in charge), ``A exp(-B q)`` the exponential zone of a
  freshly charged pack, ``K q/(Q - q)`` the knee near empty, ``R`` the internal resistance.

Shepherd, C. M. (1965), "Design of primary and secondary cells II", J. Electrochem. Soc.
112(7); Tremblay, O. and Dessaint, L.-A. (2009), "Experimental validation of a battery
dynamic model for EV applications", World Electric Vehicle Journal 3 (also the MATLAB
Simscape "Battery" block). Unlike Tremblay, the knee has no current-dependent term and a
linear plateau slope ``G`` is added: LiPo open-circuit voltage falls ~0.35 V per cell over
the plateau, which a flat ``E0`` cannot follow.

``n`` identical packs in parallel share the current and charge equally:
``V = OCV(q/n) - (R/n) i``.

At constant electrical power ``P`` the current solves ``(R/n) i^2 - OCV i + P = 0``;
the smaller root, written cancellation-free, is ``i = 2P / (OCV + sqrt(OCV^2 - 4 (R/n) P))``.
The pack reaches the cut-off voltage ``Vc`` under that load when
``OCV(q/n) - (R/n) P / Vc - Vc = 0``.

All model functions use plain arithmetic and :mod:`tuflexperf.models._math`, so they take
floats, numpy arrays and CasADi symbols alike. This module is physics only: the discharge
runs are read by :mod:`tuflexperf.io.discharge` and fitted by
:mod:`tuflexperf.reduction.battery`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from tuflexperf.models._math import (
    Vectorizable,
    exp,
    fmax,
    fmin,
    interp_rows,
    is_symbolic,
    sqrt,
    where,
)
from tuflexperf.models.power_correction import PowerCorrection, corrected

SECONDS_PER_HOUR = 3600.0
PARAMETER_NAMES: tuple[str, ...] = (
    "e0_v",
    "slope_v_per_ah",
    "exp_amplitude_v",
    "exp_rate_per_ah",
    "knee_v",
    "max_capacity_ah",
    "resistance_ohm",
)
# Samples this long after a throttle step are left out of the mean power: the ESC and
# the fan spool up in well under a second (paper: 0.05 s delay), 2 s is ample.
SETTLE_S = 2.0
FIT_BLOCK_S = 1.0  # the fit uses 1-s block means (see block_means)
_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(48)


# --- the equivalent circuit ---------------------------------------------------------------
@dataclass(frozen=True)
class DischargeParameters:
    """One pack's parameters (V, Ohm, Ah) of ``V = E0 - G q + A e^{-Bq} - K q/(Q-q) - R i``."""

    e0_v: float
    slope_v_per_ah: float
    exp_amplitude_v: float
    exp_rate_per_ah: float
    knee_v: float
    max_capacity_ah: float
    resistance_ohm: float

    def as_vector(self) -> np.ndarray:
        return np.array([getattr(self, name) for name in PARAMETER_NAMES], dtype=float)

    @classmethod
    def from_vector(cls, values: Sequence[float]) -> DischargeParameters:
        return cls(**{name: float(v) for name, v in zip(PARAMETER_NAMES, values, strict=True)})

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def equivalent_packs(
    packs: Vectorizable, capacity_ah: Vectorizable, measured_capacity_ah: float
) -> Vectorizable:
    """Parallel packs of the measured one that make a pack of another rated capacity [-].

    A pack of the same cells at ``capacity_ah`` holds ``s = capacity_ah /
    measured_capacity_ah`` times the charge at every state of charge and, its cells that
    much larger (or more in parallel), ``1/s`` of the resistance: its circuit is
    ``OCV(q/s) - (R/s) i``, which is ``s`` measured packs in parallel. So ``packs`` packs of
    ``capacity_ah`` behave as ``packs * s`` measured packs, and the rating (C x capacity per
    pack) and the landing reserve (a fraction of ``packs * capacity_ah``) follow alike.

    Parameters
    ----------
    packs : float or array or CasADi expression
        Packs in parallel per engine [-].
    capacity_ah : float or array or CasADi expression
        Rated capacity of the pack flown [Ah].
    measured_capacity_ah : float
        Rated capacity of the pack whose discharge runs the circuit was fitted to [Ah].

    Returns
    -------
    float or array or CasADi expression
        The equivalent number of measured packs in parallel [-].

    References
    ----------
    Tremblay, O. and Dessaint, L.-A. (2009), section 2: the model's parameters for a
    battery of ``Np`` cells in parallel (charge x ``Np``, resistance / ``Np``).
    """
    return packs * (capacity_ah / measured_capacity_ah)


def open_circuit_voltage_v(
    p: Vectorizable, charge_ah: Vectorizable, packs: int = 1
) -> Vectorizable:
    """Open-circuit voltage in V of ``packs`` parallel packs after drawing ``charge_ah`` (Ah).

    ``p`` is a :class:`DischargeParameters` (or anything with the same attributes,
    e.g. CasADi symbols). Shepherd (1965) with Tremblay & Dessaint (2009) exponential zone.
    """
    q = charge_ah / packs
    return (
        p.e0_v
        - p.slope_v_per_ah * q
        + p.exp_amplitude_v * exp(-p.exp_rate_per_ah * q)
        - p.knee_v * q / (p.max_capacity_ah - q)
    )


def terminal_voltage_v(
    p: Vectorizable, charge_ah: Vectorizable, current_a: Vectorizable, packs: int = 1
) -> Vectorizable:
    """Terminal voltage in V under ``current_a`` (A, total of the parallel packs)."""
    return open_circuit_voltage_v(p, charge_ah, packs) - p.resistance_ohm / packs * current_a


def current_at_power_a(
    p: Vectorizable, charge_ah: Vectorizable, power_w: Vectorizable, packs: int = 1
) -> Vectorizable:
    """Current in A that delivers ``power_w`` (W) at the terminals: ``V(q, i) i = P``.

    The smaller root of ``(R/n) i^2 - OCV i + P = 0`` in the cancellation-free form
    ``2P / (OCV + sqrt(OCV^2 - 4 (R/n) P))``. Beyond the maximum power point
    (``OCV^2 < 4 (R/n) P``) the root is clamped at ``OCV / (2 R/n)``.
    """
    ocv = open_circuit_voltage_v(p, charge_ah, packs)
    r = p.resistance_ohm / packs
    disc = ocv * ocv - 4.0 * r * power_w
    disc = disc - fmin(disc, 0.0)  # max(disc, 0) with the backend-neutral helpers
    return 2.0 * power_w / (ocv + sqrt(disc))


def loaded_voltage_at_power_v(
    p: Vectorizable,
    charge_ah: Vectorizable,
    power_w: Vectorizable,
    packs: Vectorizable = 1,
    reference_voltage_v: float | None = None,
    power_exponent: float = 0.0,
) -> Vectorizable:
    """Terminal voltage [V] of ``packs`` parallel packs delivering ``power_w`` [W]; NaN where
    the packs cannot deliver it (beyond their maximum power).

    Without a reference voltage the power is fixed: ``U = (OCV + sqrt(OCV^2 - 4 (R/n) P)) / 2``
    (the larger root of ``U^2 - OCV U + (R/n) P = 0``, the normal branch; the current is
    ``P / U``, :func:`current_at_power_a`). With ``reference_voltage_v`` the fan draws
    ``P (U / U_ref)^m`` (``m = power_exponent``; the fan laws give ``1.5 x`` the thrust's
    voltage exponent), so ``g(U) = U - OCV + (R/n) P U^(m-1) / U_ref^m = 0``: increasing in
    ``U`` for ``m > 1``, negative near 0 and not negative at ``OCV``, one root, found by
    Newton from the fixed-power root (monotone for a convex ``g``, ``m >= 2``; from one
    side after one step for a concave one) and NaN where it did not converge.

    Parameters
    ----------
    p : DischargeParameters
        The fitted circuit of one measured pack.
    charge_ah : float or array
        Charge drawn from the ``packs`` together [Ah].
    power_w : float or array
        Electrical power at the terminals [W] (at the reference voltage, with one).
    packs : float or array
        Measured packs in parallel [-].
    reference_voltage_v : float, optional
        The voltage ``power_w`` was measured at [V].
    power_exponent : float
        ``m`` [-].

    References
    ----------
    Tremblay & Dessaint (2009) (the circuit); SPEC 3 (thrust and pack voltage).
    """
    ocv = open_circuit_voltage_v(p, charge_ah, packs)
    r = p.resistance_ohm / packs
    # past the knee's pole (q = n Q) the circuit is no pack: its knee term changes sign and
    # the "voltage" rises above a full pack's (61 V from 48 V let a take-off drain 11.35 Ah
    # of 10 Ah and pass; outside audit)
    drained = charge_ah >= packs * p.max_capacity_ah
    if reference_voltage_v is None or power_exponent == 0.0:
        disc = ocv * ocv - 4.0 * r * power_w
        return where(drained, math.nan,
                     where(disc >= 0.0, 0.5 * (ocv + sqrt(fmax(disc, 0.0))), math.nan))
    m = float(power_exponent)
    c = r * power_w / float(reference_voltage_v) ** m
    # from the fixed-power root at the reference voltage's power (close: a few steps), or
    # from the open-circuit voltage beyond that power
    disc = ocv * ocv - 4.0 * r * power_w * fmin(ocv / float(reference_voltage_v), 1.0) ** m
    u = where(disc >= 0.0, 0.5 * (ocv + sqrt(fmax(disc, 0.0))), ocv)
    floor = 1e-6 * ocv
    numeric = not is_symbolic(u, c)
    for _ in range(NEWTON_STEPS):
        power = u ** (m - 2.0)  # one fractional power per step: u^(m-1) is u times it
        g = u - ocv + c * u * power
        step = fmin(fmax(u - g / (1.0 + c * (m - 1.0) * power), floor), ocv)
        moved, u = step - u, step
        # Newton converges quadratically: after a move of 1e-12 the next is round-off, so
        # numbers stop there (3-4 steps, within 2 ulp of all 8; a CasADi graph keeps them)
        if numeric and not (np.abs(moved) > 1e-12 * ocv).any():
            break
    g = u - ocv + c * u ** (m - 1.0)
    return where(drained, math.nan, where(fmax(g, -g) <= 1e-9 * ocv, u, math.nan))


NEWTON_STEPS = 8  # loaded_voltage_at_power_v: from a root a few % off, rounding in ~4


def cutoff_residual_v(
    p: Vectorizable, charge_ah: Vectorizable, power_w: Vectorizable, cutoff_v: float, packs: int = 1
) -> Vectorizable:
    """``OCV(q/n) - (R/n) P/Vc - Vc`` in V: positive before, zero at the cut-off under ``P``.

    At cut-off the terminal voltage is ``Vc`` and so the current is ``P / Vc``.
    """
    return (
        open_circuit_voltage_v(p, charge_ah, packs)
        - p.resistance_ohm / packs * power_w / cutoff_v
        - cutoff_v
    )


# --- numeric helpers on floats/numpy (cross-validation, tests, benchmarks) -----------------
def cutoff_charge_ah(
    p: DischargeParameters, power_w: float, cutoff_v: float, packs: int = 1
) -> float:
    """Charge in Ah drawn when the terminal voltage under ``power_w`` reaches ``cutoff_v``.

    Bisection on :func:`cutoff_residual_v` over ``[0, n Q)`` (it decreases in ``q``).
    Returns 0 if the pack is already below the cut-off when full.
    """
    low, high = 0.0, packs * p.max_capacity_ah * (1.0 - 1e-12)
    if cutoff_residual_v(p, low, power_w, cutoff_v, packs) <= 0.0:
        return 0.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        if cutoff_residual_v(p, mid, power_w, cutoff_v, packs) > 0.0:
            low = mid
        else:
            high = mid
        if high - low < 1e-13:
            break
    return 0.5 * (low + high)


def discharge_time_s(
    p: Vectorizable,
    power_w: Vectorizable,
    start_ah: Vectorizable,
    end_ah: Vectorizable,
    packs: int = 1,
) -> Vectorizable:
    """Time in s to draw the charge from ``start_ah`` to ``end_ah`` at constant power.

    ``t = 3600 * integral dq / i(q, P)`` by 48-point Gauss-Legendre quadrature (the
    integrand is smooth between full and cut-off); plain arithmetic, so it also builds
    CasADi expressions.
    """
    half = 0.5 * (end_ah - start_ah)
    mid = 0.5 * (end_ah + start_ah)
    if is_symbolic(p, power_w, start_ah, end_ah):
        import casadi as ca

        # One vector expression over the nodes: a 48-term Python loop of CasADi
        # operations costs tens of milliseconds to build.
        charge = mid + half * ca.DM(_GAUSS_NODES)
        inverse = 1.0 / current_at_power_a(p, charge, power_w, packs)
        return SECONDS_PER_HOUR * half * ca.dot(ca.DM(_GAUSS_WEIGHTS), inverse)
    total: Vectorizable = 0.0
    for node, weight in zip(_GAUSS_NODES, _GAUSS_WEIGHTS, strict=True):
        charge = mid + half * float(node)
        total = total + float(weight) / current_at_power_a(p, charge, power_w, packs)
    return SECONDS_PER_HOUR * half * total


def time_to_cutoff_s(
    p: DischargeParameters, power_w: float, cutoff_v: float, packs: int = 1, start_ah: float = 0.0
) -> float:
    """Time in s from ``start_ah`` drawn to the cut-off at constant ``power_w`` (floats)."""
    end = cutoff_charge_ah(p, power_w, cutoff_v, packs)
    if end <= start_ah:
        return 0.0
    return float(discharge_time_s(p, power_w, start_ah, end, packs))


# --- the pack's continuous rating over a flight ----------------------------------------
def first_window_beyond(
    time_s: np.ndarray, charge_ah: np.ndarray, limit_a: np.ndarray | float, window_s: float,
    block: int = 256,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The earliest-ending stretch of ``window_s`` or longer whose mean current exceeds a limit.

    The pack does not see where a mission's segments begin and end: a continuous rating
    holds over any stretch of the flight (eight 27 s cruises at 1.85 x the rating passed
    when only each segment's mean was bounded; outside audit).

    Parameters
    ----------
    time_s : ndarray
        Node times [s], ``(rows, nodes)``, non-decreasing along each row.
    charge_ah : ndarray
        Charge drawn from each pack [Ah] at the nodes, ``(rows, packs, nodes)``; linear in
        time between nodes (the current constant there).
    limit_a : float or ndarray
        The current [A] no stretch may exceed on average, per row.
    window_s : float
        The shortest stretch [s] the limit applies to.
    block : int
        Start nodes handled at once (bounds the memory to ``rows x block x nodes``).

    Returns
    -------
    end_s, start_s, mean_a : ndarray
        Per row: the end and start [s] of the earliest-ending stretch beyond the limit and its
        mean current [A] (the largest pack's); ``end_s`` is +inf where none exceeds it.

    Notes
    -----
    With the charge piecewise linear in time the mean over ``[s, e]`` is a ratio of
    linear functions on each pair of node intervals, largest on their edges: a stretch
    from node to node, or one of exactly ``window_s`` from or to a node. A stretch beyond
    the limit longer than twice ``window_s`` holds a shorter one that is (one of its
    halves), ending no later, so node-to-node stretches of up to twice ``window_s`` do for
    one history. Every such stretch is a candidate (all, not only the heaviest, so the
    earliest end is found, to the node).
    """
    t = np.asarray(time_s, dtype=float)
    q = np.asarray(charge_ah, dtype=float)
    rows, nodes = t.shape
    limit = np.broadcast_to(np.asarray(limit_a, dtype=float), (rows,))
    end = np.full(rows, np.inf)
    start, mean = np.full(rows, np.nan), np.full(rows, np.nan)

    def take(s: np.ndarray, e: np.ndarray, qs: np.ndarray, qe: np.ndarray) -> None:
        # s, e (rows, m); qs, qe (rows, packs, m): keep each row's earliest violating end
        with np.errstate(invalid="ignore", divide="ignore"):
            drawn = np.max(qe - qs, axis=1) * SECONDS_PER_HOUR / (e - s)
        over = (e - s >= window_s * (1.0 - 1e-12)) & (drawn > limit[:, None] * (1.0 + 1e-9))
        e_over = np.where(over, e, np.inf)
        k = np.argmin(e_over, axis=1)
        at = np.arange(rows)
        better = e_over[at, k] < end
        end[better] = e_over[at, k][better]
        start[better] = s[at, k][better]
        mean[better] = drawn[at, k][better]

    if nodes < 2:
        return end, start, mean
    # a row whose times are not all finite (a batch row the flight refuses anyway) would
    # spoil the other rows' interpolation: it is searched on 0, 1, 2, ... instead
    t = np.where(np.isfinite(t).all(axis=1, keepdims=True), t, np.arange(nodes, dtype=float))
    first, last = t[:, :1], t[:, -1:]

    def charge_at(x: np.ndarray) -> np.ndarray:
        return np.stack([interp_rows(x, t, q[:, p]) for p in range(q.shape[1])], axis=1)

    # exactly window_s from each node, and to each node (inside the flight)
    ahead = np.minimum(t + window_s, last)
    take(t, ahead, q, charge_at(ahead))
    behind = np.maximum(t - window_s, first)
    take(behind, t, charge_at(behind), q)
    # node to node, of window_s to twice it for one history (see Notes); all pairs for a
    # batch of short rows
    packs = q.shape[1]
    for i0 in range(0, nodes, block):
        i1 = min(i0 + block, nodes)
        j0, j1 = 0, nodes
        if rows == 1:
            j0 = int(np.searchsorted(t[0], t[0, i0] + window_s * (1 - 1e-12)))
            j1 = int(np.searchsorted(t[0], t[0, i1 - 1] + 2.0 * window_s, side="right"))
        if j1 <= j0:
            continue
        width = j1 - j0
        s = np.broadcast_to(t[:, i0:i1, None], (rows, i1 - i0, width)).reshape(rows, -1)
        e = np.broadcast_to(t[:, None, j0:j1], (rows, i1 - i0, width)).reshape(rows, -1)
        qs = np.broadcast_to(q[:, :, i0:i1, None], (rows, packs, i1 - i0, width))
        qe = np.broadcast_to(q[:, :, None, j0:j1], (rows, packs, i1 - i0, width))
        take(s, e, qs.reshape(rows, packs, -1), qe.reshape(rows, packs, -1))
    return end, start, mean


# --- electrical power of a fan --------------------------------------------------------------
@dataclass(frozen=True)
class FanPowerModel:
    """Electrical power of one fan: ``P(x, V) = P_s x^n (1 - (V / V_j)^2)`` in W.

    ``P_s`` full-throttle static power (W), ``n`` the throttle exponent, ``V_j`` the fan's
    jet (exit) velocity (m/s). The airspeed factor is ideal momentum theory at a fixed jet
    velocity: the power to accelerate the stream from ``V`` to ``V_j``,
    ``mdot (V_j^2 - V^2) / 2``, relative to its static value (McCormick, *Aerodynamics,
    Aeronautics and Flight Mechanics*, ch. 6 momentum theory).
    """

    static_full_throttle_w: float
    exponent: float
    jet_velocity_m_s: float
    # measured over modelled power (the discharge runs' reading); None: the law as fitted
    power_correction: PowerCorrection | None = None

    def airspeed_factor(self, airspeed_m_s: Vectorizable) -> Vectorizable:
        """``1 - (V / V_j)^2`` (dimensionless)."""
        ratio = airspeed_m_s / self.jet_velocity_m_s
        return 1.0 - ratio * ratio

    def electrical_power_w(
        self, throttle: Vectorizable, airspeed_m_s: Vectorizable
    ) -> Vectorizable:
        """Electrical input power of one fan in W at ``throttle`` (fraction) and airspeed (m/s),
        times ``power_correction`` where there is one."""
        law = (
            self.static_full_throttle_w
            * throttle**self.exponent
            * self.airspeed_factor(airspeed_m_s)
        )
        return corrected(law, self.power_correction, throttle, airspeed_m_s)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = asdict(self)
        if self.power_correction is None:  # the law as fitted: its keys as ever
            out.pop("power_correction")
        return out


def published_static_power_w(
    static_thrust_n: float,
    power_range_w: tuple[float, float],
    thrust_range_n: tuple[float, float],
) -> float:
    """Full-throttle static power in W of a fan with ``static_thrust_n`` (N).

    Interpolates the published power and static-thrust ranges (paper Table 1: 2.4-4.1 kW
    for 41-59 N) with momentum theory's hover law ``P ~ T^(3/2)`` (McCormick ch. 6),
    fitted through both published ends in log space.
    """
    (p_low, p_high), (t_low, t_high) = power_range_w, thrust_range_n
    slope = math.log(p_high / p_low) / math.log(t_high / t_low)
    return p_low * (static_thrust_n / t_low) ** slope
