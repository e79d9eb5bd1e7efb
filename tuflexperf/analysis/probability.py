"""Probability helpers without SciPy (``check`` must not import it): normal, beta, binomial CI.

References
----------
Abramowitz & Stegun, *Handbook of Mathematical Functions*, 26.2 (normal), 26.5 (incomplete
beta); Press et al., *Numerical Recipes*, 3rd ed., 6.4 (continued fraction of the
incomplete beta); Acklam (2003), "An algorithm for computing the inverse normal
cumulative distribution function"; Clopper & Pearson (1934), Biometrika 26, 404-413.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

_ERF = np.frompyfunc(math.erf, 1, 1)
_ERFC = np.frompyfunc(math.erfc, 1, 1)

# Acklam's rational approximation, refined below by Newton steps to full precision.
_A = (-3.969683028665376e01, 2.209460984245205e02, -2.759285104469687e02,
      1.383577518672690e02, -3.066479806614716e01, 2.506628277459239e00)
_B = (-5.447609879822406e01, 1.615858368580409e02, -1.556989798598866e02,
      6.680131188771972e01, -1.328068155288572e01)
_C = (-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e00,
      -2.549732539343734e00, 4.374664141464968e00, 2.938163982698783e00)
_D = (7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e00,
      3.754408661907416e00)


def normal_cdf(x: ArrayLike) -> NDArray[np.float64]:
    """Standard normal CDF ``Phi(x) = erfc(-x / sqrt 2) / 2`` (A&S 26.2.2), element-wise."""
    return 0.5 * np.asarray(_ERFC(-np.asarray(x, dtype=float) / math.sqrt(2.0)), dtype=float)


_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)
_SERIES_BELOW = -30.0  # erfc keeps full precision above; the series' next term is 2e-14 here
_DIRECT_LOG_P = -690.0  # exp(-690) = 1.3e-300, a normal double: normal_ppf takes it directly


def normal_logcdf(x: ArrayLike) -> NDArray[np.float64]:
    """``log Phi(x)``, finite far below where ``Phi`` underflows (x < -38.5).

    Above -30 the log of :func:`normal_cdf`; below, the asymptotic series of the Mills ratio,
    ``log Phi(x) = -x^2/2 - log(-x) - log sqrt(2 pi) + log(1 - 1/x^2 + 3/x^4 - ...)``
    (A&S 26.2.12), to six terms.
    """
    x = np.asarray(x, dtype=float)
    with np.errstate(divide="ignore"):
        direct = np.log(normal_cdf(np.maximum(x, _SERIES_BELOW)))
    z = np.minimum(x, _SERIES_BELOW)
    w = 1.0 / (z * z)
    series = 1.0 + w * (-1.0 + w * (3.0 + w * (-15.0 + w * (105.0 - 945.0 * w))))
    tail = -0.5 * z * z - np.log(-z) - _LOG_SQRT_2PI + np.log(series)
    return np.where(x < _SERIES_BELOW, tail, direct)


def normal_ppf_of_log(log_p: ArrayLike) -> NDArray[np.float64]:
    """The ``x`` with ``log Phi(x) = log_p`` (the inverse of :func:`normal_logcdf`).

    :func:`normal_ppf` of ``exp(log_p)`` where that is a normal double; below, Newton's
    method on ``log Phi`` (slope ``phi / Phi``) from ``-sqrt(-2 log_p)``, eight steps.
    """
    log_p = np.asarray(log_p, dtype=float)
    direct = normal_ppf(np.exp(np.maximum(log_p, _DIRECT_LOG_P)))
    deep = np.minimum(log_p, _DIRECT_LOG_P)
    x = -np.sqrt(-2.0 * deep)
    for _ in range(8):
        log_cdf = normal_logcdf(x)
        x = x - (log_cdf - deep) / np.exp(-0.5 * x * x - _LOG_SQRT_2PI - log_cdf)
    return np.where(log_p > _DIRECT_LOG_P, direct, x)


def normal_ppf(p: ArrayLike) -> NDArray[np.float64]:
    """Inverse standard normal CDF for ``p`` in (0, 1): Acklam's start + 2 Newton steps."""
    p = np.asarray(p, dtype=float)
    q = np.minimum(p, 1.0 - p)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.sqrt(-2.0 * np.log(q))
        tail = (((((_C[0] * t + _C[1]) * t + _C[2]) * t + _C[3]) * t + _C[4]) * t + _C[5]) / (
            (((_D[0] * t + _D[1]) * t + _D[2]) * t + _D[3]) * t + 1.0)
        r = (q - 0.5) ** 2
        centre = (q - 0.5) * (((((_A[0] * r + _A[1]) * r + _A[2]) * r + _A[3]) * r + _A[4]) * r
                              + _A[5]) / (((((_B[0] * r + _B[1]) * r + _B[2]) * r + _B[3]) * r
                                           + _B[4]) * r + 1.0)
    x = np.where(q < 0.02425, tail, centre)  # lower-half value, for q = min(p, 1 - p)
    for _ in range(2):
        pdf = np.exp(-0.5 * x * x) / math.sqrt(2.0 * math.pi)
        x = x - (normal_cdf(x) - q) / np.where(pdf > 0, pdf, np.inf)
    x = np.where(p > 0.5, -x, x)
    return np.where(p <= 0.0, -np.inf, np.where(p >= 1.0, np.inf, x))


def _beta_cf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta (Numerical Recipes 6.4, modified Lentz)."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 10000):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c
        c = c if abs(c) > tiny else tiny
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c
        c = c if abs(c) > tiny else tiny
        step = d * c
        h *= step
        if abs(step - 1.0) < 1e-15:
            break
    return h


def beta_cdf(x: float, a: float, b: float) -> float:
    """Regularised incomplete beta ``I_x(a, b)`` (A&S 26.5.8 via NR 6.4)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    log_front = (math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
                 + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _beta_cf(a, b, x) / a
    return 1.0 - math.exp(log_front) * _beta_cf(b, a, 1.0 - x) / b


def beta_ppf(p: float, a: float, b: float) -> float:
    """Quantile of the Beta(a, b) distribution by bisection on :func:`beta_cdf`."""
    low, high = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        if beta_cdf(mid, a, b) < p:
            low = mid
        else:
            high = mid
        if high - low < 1e-15:
            break
    return 0.5 * (low + high)


def clopper_pearson(successes: int, trials: int, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper-Pearson) two-sided confidence interval of a binomial proportion.

    Lower ``B(alpha/2; k, n-k+1)`` (0 when k = 0), upper ``B(1-alpha/2; k+1, n-k)`` (1 when
    k = n), ``alpha = 1 - confidence``.

    References
    ----------
    Clopper & Pearson (1934), Biometrika 26, 404-413.
    """
    if trials <= 0:
        return 0.0, 1.0
    alpha = 1.0 - confidence
    k, n = int(successes), int(trials)
    low = 0.0 if k == 0 else beta_ppf(alpha / 2.0, k, n - k + 1)
    high = 1.0 if k == n else beta_ppf(1.0 - alpha / 2.0, k + 1, n - k)
    return low, high
