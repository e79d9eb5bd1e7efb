"""Electrical side of the fan from runs that log ``voltage_v`` and ``current_a`` (SPEC 4).

Three fits, each on the campaign's steady test points (one per throttle and airspeed):

1. **Voltage effect** ``T = T_ref(x, V) (U / U_ref)^n`` (SPEC 3): the poly22 and ``n`` by
   separable least squares. For a fixed ``n`` the poly22 is linear (OLS on the design scaled by
   ``(U/U_ref)^n``), so ``n`` is found by minimising the profile residual sum of squares, and
   its standard error from the profile's curvature (``Delta RSS = s^2`` at one standard
   error; Bates & Watts, *Nonlinear Regression Analysis*, 1988, 3.5 and 6.1).
   ``n`` is kept only when the data determine it (standard error below
   :data:`MAX_EXPONENT_SE`); otherwise the fit says so and the SPEC default 2 stands.
2. **Power surface** ``P_el = poly22(x, V)`` in W per engine, from the segment means of ``U I``.
3. **Windmilling drag** ``C_d,wm = -T(0, V) / (q A_fan)`` from the zero-throttle points above
   :data:`MIN_WINDMILL_AIRSPEED_M_S`, one coefficient per engine by least squares through
   the origin (Hoerner, *Fluid-Dynamic Drag*, ch. 3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tuflexperf.reduction.poly22fit import Poly22Fit, fit_poly22, poly22_design

# Larger than this the exponent is not determined by the runs (SPEC default 2 kept).
MAX_EXPONENT_SE = 0.25
# Search range of the voltage exponent (rpm ~ duty x voltage, thrust ~ rpm^2 gives 2).
EXPONENT_RANGE = (-2.0, 6.0)
# Zero-throttle points below this airspeed carry no usable windmilling drag.
MIN_WINDMILL_AIRSPEED_M_S = 5.0
# Throttle at or below this is "zero throttle" for the windmilling fit.
IDLE_THROTTLE = 1e-3
# Least relative spread of the pack voltage over the points for the exponent fit.
MIN_VOLTAGE_SPREAD = 0.005


@dataclass(frozen=True)
class VoltageFit:
    """The voltage exponent ``n`` of ``T (U/U_ref)^n`` and how well the runs determine it."""

    reference_voltage_v: float
    exponent: float
    standard_error: float
    identified: bool
    reason: str
    voltage_range_v: tuple[float, float]

    def to_dict(self) -> dict[str, object]:
        return {
            "reference_voltage_v": self.reference_voltage_v,
            "exponent": self.exponent if math.isfinite(self.exponent) else None,
            "standard_error": self.standard_error if math.isfinite(self.standard_error) else None,
            "identified": self.identified,
            "reason": self.reason,
            "voltage_range_v": list(self.voltage_range_v),
        }


@dataclass(frozen=True)
class WindmillingFit:
    """``C_d,wm`` on the fan area from one engine's zero-throttle points."""

    drag_coefficient: float
    rms_n: float
    n_points: int
    airspeed_range_m_s: tuple[float, float]

    def to_dict(self) -> dict[str, object]:
        return {
            "windmilling_drag_coefficient": self.drag_coefficient,
            "rms_n": self.rms_n,
            "n_points": self.n_points,
            "airspeed_range_m_s": list(self.airspeed_range_m_s),
        }


def _profile_rss(
    design: np.ndarray, thrust: np.ndarray, ratio: np.ndarray, exponent: float
) -> float:
    scale = ratio**exponent
    scaled = design * scale[:, None]
    beta, *_ = np.linalg.lstsq(scaled, thrust, rcond=None)
    residual = thrust - scaled @ beta
    return float(residual @ residual)


def fit_voltage_exponent(
    throttle: ArrayLike,
    airspeed_m_s: ArrayLike,
    thrust_n: ArrayLike,
    voltage_v: ArrayLike,
    reference_voltage_v: float,
) -> VoltageFit:
    """Voltage exponent ``n`` of ``T = poly22(x, V) (U / U_ref)^n`` by profile least squares.

    Parameters
    ----------
    throttle, airspeed_m_s, thrust_n, voltage_v : array_like
        One engine's test points: throttle fraction [-], airspeed [m/s], thrust [N] and the
        mean pack voltage over the point's samples [V].
    reference_voltage_v : float
        ``U_ref`` [V]: the voltage at which the poly22 is to hold.

    Returns
    -------
    VoltageFit
        ``identified`` is False (with the reason) when the voltage hardly varies or the
        profile's standard error exceeds :data:`MAX_EXPONENT_SE`.

    References
    ----------
    SPEC 3 ("thrust and pack voltage"); Bates & Watts, *Nonlinear Regression Analysis and
    its Applications*, 1988, sections 3.5 (separable least squares) and 6.1 (profile
    intervals).
    """
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    t = np.asarray(thrust_n, dtype=float)
    u = np.asarray(voltage_v, dtype=float)
    span = (float(np.min(u)), float(np.max(u))) if u.size else (math.nan, math.nan)

    def unidentified(reason: str, exponent: float = math.nan, se: float = math.nan) -> VoltageFit:
        return VoltageFit(reference_voltage_v, exponent, se, False, reason, span)

    if u.size < 8 or not np.all(np.isfinite(u)) or np.any(u <= 0):
        return unidentified("too few points with a valid pack voltage")
    spread = (span[1] - span[0]) / reference_voltage_v
    if spread < MIN_VOLTAGE_SPREAD:
        return unidentified(f"the pack voltage varies by only {100 * spread:.2f} %")
    design = poly22_design(x, v)
    ratio = u / reference_voltage_v
    grid = np.linspace(*EXPONENT_RANGE, 161)
    rss = np.array([_profile_rss(design, t, ratio, n) for n in grid])
    k = int(np.argmin(rss))
    low, high = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    golden = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(60):
        a = high - golden * (high - low)
        b = low + golden * (high - low)
        if _profile_rss(design, t, ratio, a) <= _profile_rss(design, t, ratio, b):
            high = b
        else:
            low = a
    n_hat = 0.5 * (low + high)
    rss_min = _profile_rss(design, t, ratio, n_hat)
    dof = t.size - 7
    if dof <= 0:
        return unidentified("no degrees of freedom left for the exponent", n_hat)
    s2 = rss_min / dof
    h = 0.05
    curvature = (
        _profile_rss(design, t, ratio, n_hat + h) - 2 * rss_min
        + _profile_rss(design, t, ratio, n_hat - h)
    ) / h**2
    se = math.sqrt(2.0 * s2 / curvature) if curvature > 0 else math.inf
    if n_hat <= EXPONENT_RANGE[0] + 0.1 or n_hat >= EXPONENT_RANGE[1] - 0.1:
        return unidentified(f"the best exponent lies at the search bound ({n_hat:.2f})", n_hat, se)
    if not se < MAX_EXPONENT_SE:
        return unidentified(
            f"standard error {se:.2f} exceeds {MAX_EXPONENT_SE} (voltage confounded with "
            "throttle and airspeed)",
            n_hat,
            se,
        )
    return VoltageFit(reference_voltage_v, n_hat, se, True, "", span)


def fit_power_surface(
    throttle: ArrayLike, airspeed_m_s: ArrayLike, power_w: ArrayLike, label: str = "engine"
) -> Poly22Fit:
    """Electrical power surface ``P_el = poly22(x, V)`` [W] by ordinary least squares.

    Parameters
    ----------
    throttle, airspeed_m_s, power_w : array_like
        Test points: throttle fraction [-], airspeed [m/s], mean ``U I`` [W].
    label : str
        Names the engine in errors.

    Returns
    -------
    Poly22Fit
        In W (its ``rmse_n`` field holds the RMSE in W here).

    References
    ----------
    SPEC 4 (``power: {model: poly22}``); paper section 4 (the poly22 form).
    """
    return fit_poly22(throttle, airspeed_m_s, power_w, label=f"{label} (electrical power)")


def fit_windmilling(
    throttle: ArrayLike,
    airspeed_m_s: ArrayLike,
    thrust_n: ArrayLike,
    density_kg_m3: float,
    fan_area_m2: float,
) -> WindmillingFit | None:
    """``C_d,wm`` from the zero-throttle points: ``-T(0, V) = C_d,wm (rho V^2 / 2) A_fan``.

    Least squares through the origin over the points at zero throttle and at least
    :data:`MIN_WINDMILL_AIRSPEED_M_S`. ``None`` when there are fewer than two such points;
    a fan that pushes at zero throttle (fitted ``C_d,wm < 0``) gives 0, never a thrust.

    Parameters
    ----------
    throttle, airspeed_m_s, thrust_n : array_like
        One engine's test points [-, m/s, N] (thrust corrected for the structure drag).
    density_kg_m3 : float
        Air density of the tests [kg/m^3].
    fan_area_m2 : float
        Fan area the coefficient refers to [m^2].

    References
    ----------
    SPEC 3 (windmilling drag); Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 3.
    """
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    t = np.asarray(thrust_n, dtype=float)
    keep = (np.abs(x) <= IDLE_THROTTLE) & (v >= MIN_WINDMILL_AIRSPEED_M_S) & np.isfinite(t)
    if np.count_nonzero(keep) < 2:
        return None
    qa = 0.5 * density_kg_m3 * v[keep] ** 2 * fan_area_m2
    cd = max(float(-(t[keep] @ qa) / (qa @ qa)), 0.0)
    residual = t[keep] + cd * qa
    return WindmillingFit(
        drag_coefficient=cd,
        rms_n=float(np.sqrt(np.mean(residual**2))),
        n_points=int(np.count_nonzero(keep)),
        airspeed_range_m_s=(float(v[keep].min()), float(v[keep].max())),
    )
