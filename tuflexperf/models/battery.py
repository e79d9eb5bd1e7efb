"""LiPo pack discharge model, its least-squares fit to discharge runs, and the fan's power.

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
floats, numpy arrays and CasADi symbols alike. The fit is a CasADi/IPOPT least-squares
problem.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.models._math import exp, fmin, is_symbolic, sqrt

SECONDS_PER_HOUR = 3600.0
RUN_COLUMNS: tuple[str, ...] = (
    "time_s",
    "force_n",
    "airspeed_m_s",
    "throttle",
    "voltage_v",
    "current_a",
)
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


def open_circuit_voltage_v(p: Any, charge_ah: Any, packs: int = 1) -> Any:
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


def terminal_voltage_v(p: Any, charge_ah: Any, current_a: Any, packs: int = 1) -> Any:
    """Terminal voltage in V under ``current_a`` (A, total of the parallel packs)."""
    return open_circuit_voltage_v(p, charge_ah, packs) - p.resistance_ohm / packs * current_a


def current_at_power_a(p: Any, charge_ah: Any, power_w: Any, packs: int = 1) -> Any:
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


def cutoff_residual_v(p: Any, charge_ah: Any, power_w: Any, cutoff_v: float, packs: int = 1) -> Any:
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
    p: Any, power_w: Any, start_ah: Any, end_ah: Any, packs: int = 1
) -> Any:
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
    total: Any = 0.0
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


# --- discharge runs -------------------------------------------------------------------------
@dataclass(frozen=True)
class DischargeRun:
    """One endurance run (SPEC run format) with the charge drawn, integrated from the current."""

    path: Path
    time_s: np.ndarray
    force_n: np.ndarray
    airspeed_m_s: np.ndarray
    throttle: np.ndarray
    voltage_v: np.ndarray
    current_a: np.ndarray
    charge_ah: np.ndarray

    @property
    def loaded(self) -> np.ndarray:
        """Mask of the samples under load (throttle above zero)."""
        return self.throttle > 1e-6

    @property
    def load_window_s(self) -> tuple[float, float]:
        """Start and end time in s of the loaded segment (throttle on until the cut-off)."""
        t = self.time_s[self.loaded]
        return float(t[0]), float(t[-1])

    @property
    def time_to_cutoff_s(self) -> float:
        """Observed time under load from the throttle step to the cut-off, in s."""
        start, end = self.load_window_s
        return end - start

    def _settled(self) -> np.ndarray:
        start, _ = self.load_window_s
        return self.loaded & (self.time_s >= start + SETTLE_S)

    @property
    def throttle_setting(self) -> float:
        """Median throttle (fraction) under load."""
        return float(np.median(self.throttle[self._settled()]))

    @property
    def airspeed_setting_m_s(self) -> float:
        """Mean tunnel airspeed in m/s under load."""
        return float(np.mean(self.airspeed_m_s[self._settled()]))

    @property
    def mean_power_w(self) -> float:
        """Mean electrical power ``V I`` in W under load (spool-up left out)."""
        mask = self._settled()
        return float(np.mean(self.voltage_v[mask] * self.current_a[mask]))

    @property
    def start_charge_ah(self) -> float:
        """Charge in Ah drawn before the throttle step (idle current of the ESC)."""
        start, _ = self.load_window_s
        return float(np.interp(start, self.time_s, self.charge_ah))


def _read_columns(path: Path) -> dict[str, np.ndarray]:
    if path.suffix.lower() == ".mat":
        from scipy.io import loadmat  # lazy: only .mat runs need SciPy

        try:
            raw = loadmat(path, squeeze_me=True)
        except Exception as exc:  # noqa: BLE001 - any reader failure is bad input
            raise InputError(f"{path}: cannot read MATLAB file: {exc}") from None
        return {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in raw.items()
                if not k.startswith("__") and k in RUN_COLUMNS}
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            header = next(csv.reader(handle), None)
            if header is None:
                raise InputError(f"{path}: empty file, expected a header row")
            data = np.loadtxt(handle, delimiter=",", ndmin=2)
    except InputError:
        raise
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read run data: {str(exc).splitlines()[0]}") from None
    names = [h.strip() for h in header]
    if data.shape[1] != len(names):
        raise InputError(f"{path}: {data.shape[1]} columns of data for {len(names)} header names")
    return {name: data[:, j] for j, name in enumerate(names)}


def read_discharge_run(path: Path | str) -> DischargeRun:
    """Read an endurance run (CSV or MATLAB v5) and integrate the charge drawn (trapezoid).

    Raises :class:`InputError` naming the file and column on missing columns, non-finite
    values, a time that does not increase, or a run with no loaded segment.
    """
    from tuflexperf.io.files import MAX_RUN_BYTES, check_input_file

    path = check_input_file(path, "run file", MAX_RUN_BYTES)
    columns = _read_columns(path)
    missing = [c for c in RUN_COLUMNS if c not in columns]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)} (endurance run)")
    n = columns["time_s"].size
    for name in RUN_COLUMNS:
        values = columns[name]
        if values.size != n:
            raise InputError(f"{path}: {name}: {values.size} values for {n} times")
        if not np.all(np.isfinite(values)):
            raise InputError(f"{path}: {name}: contains NaN or infinite values")
    if n < 10:
        raise InputError(f"{path}: only {n} samples; an endurance run needs more")
    t = columns["time_s"]
    if np.any(np.diff(t) <= 0):
        raise InputError(f"{path}: time_s: must increase strictly")
    throttle = columns["throttle"]
    if np.any((throttle < 0) | (throttle > 1)):
        raise InputError(f"{path}: throttle: values outside [0, 1] (fractions expected)")
    if not np.any(throttle > 1e-6):
        raise InputError(f"{path}: throttle: never above zero, no discharge under load")
    if np.any(columns["voltage_v"] <= 0):
        raise InputError(f"{path}: voltage_v: must be positive")
    current = columns["current_a"]
    charge = np.concatenate(
        [[0.0], np.cumsum(0.5 * (current[1:] + current[:-1]) * np.diff(t))]
    ) / SECONDS_PER_HOUR
    return DischargeRun(
        path=path,
        time_s=t,
        force_n=columns["force_n"],
        airspeed_m_s=columns["airspeed_m_s"],
        throttle=throttle,
        voltage_v=columns["voltage_v"],
        current_a=current,
        charge_ah=charge,
    )


# --- least-squares fit ----------------------------------------------------------------------
@dataclass(frozen=True)
class DischargeFit:
    """Fitted pack parameters and the fit error over the runs they were fitted to."""

    parameters: DischargeParameters
    rms_v: float
    max_abs_v: float
    n_points: int
    runs: tuple[str, ...]


def _initial_guess(cells: int, capacity_ah: float) -> np.ndarray:
    # Typical LiPo cell values (4.2 V full, ~3.7 V nominal, a few milliohm), times cells.
    return np.array(
        [4.0 * cells, 0.01 * cells * 5.0 / capacity_ah, 0.15 * cells, 15.0 / capacity_ah,
         0.02 * cells, 1.05 * capacity_ah, 0.003 * cells]
    )


def block_means(run: DischargeRun, block_s: float = FIT_BLOCK_S) -> tuple[np.ndarray, ...]:
    """Charge (Ah), current (A) and voltage (V) averaged over ``block_s``-long time blocks.

    Blocks are set in seconds, not samples (SPEC 4: the sample rate is what ``time_s``
    says). Averaging cuts the fit's size tenfold at 10 Hz and the noise with it.
    """
    index = np.floor((run.time_s - run.time_s[0]) / block_s).astype(int)
    counts = np.bincount(index)
    keep = counts > 0
    return tuple(
        np.bincount(index, weights=values)[keep] / counts[keep]
        for values in (run.charge_ah, run.current_a, run.voltage_v)
    )


def _fit_setup(
    runs: Sequence[DischargeRun], cells_in_series: int, capacity_ah: float
) -> tuple[np.ndarray, ...]:
    """Block-mean data, parameter scale, bounds and start point shared by both fit methods."""
    blocks = [block_means(r) for r in runs]
    q, i, v = (np.concatenate([b[k] for b in blocks]) for k in range(3))
    scale = _initial_guess(cells_in_series, capacity_ah)
    q_max = max(float(r.charge_ah.max()) for r in runs)
    lower = np.array([0.7, 0.0, 0.0, 0.05, 1e-6, 0.0, 0.0])
    upper = np.array([1.2, 50.0, 5.0, 20.0, 50.0, 3.0, 20.0])
    lower[5] = max(q_max * 1.001, 0.5 * capacity_ah) / scale[5]
    z0 = np.ones(len(PARAMETER_NAMES))
    z0[5] = max(z0[5], lower[5] * 1.02)
    return q, i, v, scale, lower, upper, z0


def _residual_function(scale: np.ndarray) -> Any:
    """CasADi function ``(z, q, i, v) -> (r, dr/dz)`` for one sample, in scaled parameters."""
    import casadi as ca

    z = ca.SX.sym("z", len(PARAMETER_NAMES))
    theta = z * ca.DM(scale)
    sym = SimpleNamespace(**{name: theta[k] for k, name in enumerate(PARAMETER_NAMES)})
    q, i, v = ca.SX.sym("q"), ca.SX.sym("i"), ca.SX.sym("v")
    residual = terminal_voltage_v(sym, q, i) - v
    return ca.Function("discharge_residual", [z, q, i, v], [residual, ca.jacobian(residual, z)])


def _finish_fit(
    runs: Sequence[DischargeRun], params: DischargeParameters, converged: bool, why: str
) -> DischargeFit:
    errors = np.concatenate([
        np.asarray(terminal_voltage_v(params, r.charge_ah, r.current_a), dtype=float) - r.voltage_v
        for r in runs
    ])
    if not np.all(np.isfinite(errors)) or not converged:
        names = ", ".join(r.path.name for r in runs)
        raise InputError(f"{names}: the discharge model could not be fitted ({why})")
    return DischargeFit(
        parameters=params,
        rms_v=float(np.sqrt(np.mean(errors**2))),
        max_abs_v=float(np.max(np.abs(errors))),
        n_points=int(errors.size),
        runs=tuple(r.path.name for r in runs),
    )


def fit_discharge(
    runs: Sequence[DischargeRun], cells_in_series: int, capacity_ah: float
) -> DischargeFit:
    """Fit :class:`DischargeParameters` to the runs' terminal voltage by least squares.

    ``min sum_k (V(q_k, i_k) - V_k)^2`` over 1-s block means of every run, by
    Levenberg-Marquardt (Nocedal & Wright, *Numerical Optimization*, 10.3) on scaled
    variables (each parameter over a typical LiPo value). The residual and its exact
    Jacobian are one CasADi function mapped over the samples, built once per fit; a step
    that leaves the bounds (``Q`` above the largest charge drawn, so the knee's pole stays
    outside the data; signs) is rejected like one that raises the cost. It reaches the
    same optimum as :func:`fit_discharge_ipopt` (tested) in a fraction of the time, which
    keeps ``tuflexperf check`` fast. The reported error (rms and max, volts) is over every
    raw sample. Raises :class:`InputError` if the runs cannot be fitted.
    """
    q, i, v, scale, lower, upper, z = _fit_setup(runs, cells_in_series, capacity_ah)
    mapped = _residual_function(scale).map(q.size)
    data = [column[None, :] for column in (q, i, v)]

    def evaluate(point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r, jac = mapped(point, *data)
        return np.asarray(r).ravel(), np.asarray(jac).reshape(len(point), q.size, order="F").T

    residual, jacobian = evaluate(z)
    cost = float(residual @ residual)
    damping, converged = 1e-3, False
    for _ in range(500):
        normal = jacobian.T @ jacobian
        gradient = jacobian.T @ residual
        if np.max(np.abs(gradient)) <= 1e-13 * max(cost, 1e-300) ** 0.5 * q.size**0.5:
            converged = True
            break
        try:
            step = np.linalg.solve(normal + damping * np.diag(np.diag(normal)), -gradient)
        except np.linalg.LinAlgError:
            damping *= 10.0
            continue
        trial = z + step
        inside = bool(np.all(trial >= lower) and np.all(trial <= upper))
        trial_residual, trial_jacobian = evaluate(trial) if inside else (residual, jacobian)
        trial_cost = float(trial_residual @ trial_residual) if inside else np.inf
        if np.isfinite(trial_cost) and trial_cost <= cost:
            small = cost - trial_cost <= 1e-15 * cost and np.max(np.abs(step)) < 1e-10
            z, residual, jacobian, cost = trial, trial_residual, trial_jacobian, trial_cost
            damping = max(damping / 3.0, 1e-12)
            if small:
                converged = True
                break
        else:
            damping *= 4.0
            if damping > 1e12:  # no descent left: stationary to working precision
                converged = True
                break
    params = DischargeParameters.from_vector(z * scale)
    return _finish_fit(runs, params, converged, "Levenberg-Marquardt did not converge")


def fit_discharge_ipopt(
    runs: Sequence[DischargeRun], cells_in_series: int, capacity_ah: float
) -> DischargeFit:
    """The same least-squares fit as :func:`fit_discharge`, solved by CasADi's IPOPT.

    Kept as the reference the Levenberg-Marquardt fit is verified against (and for
    problems where a general NLP solver is wanted); about ten times slower.
    """
    import casadi as ca

    q, i, v, scale, lower, upper, z0 = _fit_setup(runs, cells_in_series, capacity_ah)
    residual = _residual_function(scale)
    z = ca.MX.sym("z", len(PARAMETER_NAMES))
    data = [ca.DM(column).T for column in (q, i, v)]
    r = residual.map(q.size, "serial")(z, *data)[0]
    objective = 0.5 * ca.sumsqr(r) / q.size
    solver = ca.nlpsol(
        "discharge_fit",
        "ipopt",
        {"x": z, "f": objective},
        {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
         "ipopt.tol": 1e-12, "ipopt.max_iter": 500},
    )
    solution = solver(x0=z0, lbx=lower, ubx=upper)
    status = solver.stats()["return_status"]
    params = DischargeParameters.from_vector(np.asarray(solution["x"]).ravel() * scale)
    ok = status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    return _finish_fit(runs, params, ok, status)


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

    def airspeed_factor(self, airspeed_m_s: Any) -> Any:
        """``1 - (V / V_j)^2`` (dimensionless)."""
        ratio = airspeed_m_s / self.jet_velocity_m_s
        return 1.0 - ratio * ratio

    def electrical_power_w(self, throttle: Any, airspeed_m_s: Any) -> Any:
        """Electrical input power of one fan in W at ``throttle`` (fraction) and airspeed (m/s)."""
        return self.static_full_throttle_w * throttle**self.exponent * self.airspeed_factor(
            airspeed_m_s
        )

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


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


@dataclass(frozen=True)
class PowerFit:
    """The fan power model and how well it matches the points it was fitted to."""

    model: FanPowerModel
    points: tuple[dict[str, float], ...]
    rms_log_error: float


def fit_fan_power(
    runs: Sequence[DischargeRun], static_full_throttle_w: float, jet_velocity_m_s: float
) -> PowerFit:
    """Fit ``ln P = ln P_s + n ln x + ln(1 - (V/V_j)^2)`` to the runs and the published point.

    Points: each run's mean ``V I`` at its throttle and airspeed, and the published
    full-throttle static power (``x = 1``, ``V = 0``). Linear least squares in
    ``(ln P_s, n)``, equal weights.
    """
    xs = [1.0] + [r.throttle_setting for r in runs]
    vs = [0.0] + [r.airspeed_setting_m_s for r in runs]
    ps = [static_full_throttle_w] + [r.mean_power_w for r in runs]
    labels = ["published full-throttle static"] + [r.path.name for r in runs]
    x, v, p = np.array(xs), np.array(vs), np.array(ps)
    if np.any(x <= 0) or np.any(v >= jet_velocity_m_s) or np.any(p <= 0):
        raise InputError("fan power fit: runs need throttle > 0, power > 0, airspeed below jet")
    factor = 1.0 - (v / jet_velocity_m_s) ** 2
    design = np.column_stack([np.ones_like(x), np.log(x)])
    target = np.log(p) - np.log(factor)
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    model = FanPowerModel(float(np.exp(coef[0])), float(coef[1]), jet_velocity_m_s)
    predicted = np.asarray(model.electrical_power_w(x, v), dtype=float)
    points = tuple(
        {"source": label, "throttle": float(xi), "airspeed_m_s": float(vi),
         "power_w": float(pi), "model_w": float(mi)}
        for label, xi, vi, pi, mi in zip(labels, x, v, p, predicted, strict=True)
    )
    return PowerFit(model, points, float(np.sqrt(np.mean(np.log(predicted / p) ** 2))))
