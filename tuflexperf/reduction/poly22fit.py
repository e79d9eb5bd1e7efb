"""Least-squares fit of the paper's 2x2 polynomial (MATLAB ``fit(..., 'poly22')``).

``T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2`` by ordinary least
squares on the scattered points (x throttle fraction, v airspeed m/s, T N), with
MATLAB's goodness-of-fit: ``R^2 = 1 - SSE/SST``, ``RMSE = sqrt(SSE / (n - p))``
(p = 6 coefficients), and the coefficients' standard errors
``sqrt(diag((X^T X)^-1) SSE / (n - p))``, and their full covariance
``(X^T X)^-1 SSE / (n - p)`` (the unbiased residual variance, n - p degrees of freedom;
Montgomery & Runger, *Applied Statistics and Probability for Engineers*, 12-2).
Solved through the SVD of the design matrix, so an ill-conditioned table (throttle ~1,
airspeed ~30) loses no digits and a rank-deficient one is caught instead of returning arbitrary
numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tuflexperf.errors import InputError
from tuflexperf.models.thrust import POLY22_TERMS

N_TERMS = len(POLY22_TERMS)


def poly22_design(throttle: ArrayLike, airspeed_m_s: ArrayLike) -> NDArray[np.float64]:
    """Design matrix with columns in :data:`POLY22_TERMS` order: 1, x, v, x^2, x v, v^2."""
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    return np.column_stack([np.ones_like(x), x, v, x * x, x * v, v * v])


@dataclass(frozen=True)
class Poly22Fit:
    """Coefficients (N, per unit throttle / per m/s as the term says) and goodness of fit."""

    coefficients: dict[str, float]
    standard_errors: dict[str, float]
    r2: float
    rmse_n: float
    sse: float
    n_points: int
    residuals_n: NDArray[np.float64]
    covariance: NDArray[np.float64]  # 6x6, POLY22_TERMS order; NaN when n <= 6
    # the fitted (throttle, airspeed, thrust) points, for leave-one-airspeed-out
    points: tuple[NDArray[np.float64], ...] = field(default=(), repr=False)

    @property
    def residual_sd_n(self) -> float:
        """Scatter of the points about the fit, ``sqrt(SSE / (n - 6))`` in N."""
        return self.rmse_n

    def predict(self, throttle: ArrayLike, airspeed_m_s: ArrayLike) -> NDArray[np.float64]:
        """Thrust in N at ``throttle`` (fraction) and ``airspeed_m_s`` (m/s)."""
        beta = np.array([self.coefficients[t] for t in POLY22_TERMS])
        return poly22_design(throttle, airspeed_m_s) @ beta


def fit_poly22(
    throttle: ArrayLike, airspeed_m_s: ArrayLike, thrust_n: ArrayLike, label: str = "engine"
) -> Poly22Fit:
    """Ordinary least-squares poly22 fit (see the module docstring).

    Raises
    ------
    InputError
        When the points cannot determine six coefficients (fewer than 6 points, or
        fewer than 3 distinct throttles or airspeeds: a rank-deficient design).
    """
    y = np.asarray(thrust_n, dtype=float)
    design = poly22_design(throttle, airspeed_m_s)
    n = y.size
    if n < N_TERMS:
        raise InputError(f"{label}: {n} points, a poly22 fit needs at least {N_TERMS}")
    u, s, vt = np.linalg.svd(design, full_matrices=False)
    tol = s[0] * max(design.shape) * np.finfo(float).eps
    if np.count_nonzero(s > tol) < N_TERMS:
        nx = np.unique(design[:, 1]).size
        nv = np.unique(design[:, 2]).size
        raise InputError(
            f"{label}: the points do not determine a poly22 surface "
            f"({nx} distinct throttles, {nv} distinct airspeeds; need at least 3 of each "
            "in a non-degenerate pattern)"
        )
    beta = vt.T @ ((u.T @ y) / s)
    residuals = y - design @ beta
    sse = float(residuals @ residuals)
    sst = float(np.sum((y - y.mean()) ** 2))
    dfe = n - N_TERMS
    mse = sse / dfe if dfe > 0 else float("nan")
    covariance_diag = np.sum((vt.T / s) ** 2, axis=1)  # diag((X^T X)^-1) from the SVD
    errors = np.sqrt(covariance_diag * mse) if dfe > 0 else np.full(N_TERMS, np.nan)
    unscaled = (vt.T / s) @ (vt.T / s).T  # (X^T X)^-1 from the SVD
    unscaled = 0.5 * (unscaled + unscaled.T)
    covariance = unscaled * mse if dfe > 0 else np.full((N_TERMS, N_TERMS), np.nan)
    return Poly22Fit(
        coefficients={t: float(b) for t, b in zip(POLY22_TERMS, beta, strict=True)},
        standard_errors={t: float(e) for t, e in zip(POLY22_TERMS, errors, strict=True)},
        r2=1.0 - sse / sst if sst > 0 else float("nan"),
        rmse_n=float(np.sqrt(mse)) if dfe > 0 else float("nan"),
        sse=sse,
        n_points=n,
        residuals_n=residuals,
        covariance=covariance,
        points=(design[:, 1].copy(), design[:, 2].copy(), y.copy()),
    )
