"""Where the thrust model's uncertainty comes from: fit covariance and leave-one-airspeed-out.

Three numbers per engine go into the propulsion file (SPEC 4):

- ``covariance``: of the six poly22 coefficients, ``s^2 (X^T X)^-1`` with
  ``s^2 = SSE / (n - 6)`` (least squares with its correct degrees of freedom), or, for a
  model reconstructed from published values, ``sigma^2 (X^T X)^-1`` on the published test
  grid with the published measurement accuracy ``sigma`` (:func:`design_covariance`);
- ``residual_sd_n``: the points' scatter about the fit, ``s``;
- ``extrapolation_sd_n``: each tested airspeed in turn is left out, the surface refitted
  on the others and its error measured at the left-out points; the RMS error at the
  highest tested airspeed is what a model extrapolated beyond its tunnel carries
  (:func:`leave_one_airspeed_out`);
- ``extrapolation_bias_n_per_m_s`` and its standard error: the signed mean of that left-out
  error (measured minus extrapolated) over the top airspeed's upper throttles, per m/s of
  the distance it was extrapolated (a fan family that loses thrust faster at speed errs
  with one sign; :attr:`LeaveOneAirspeedOut.extrapolation_bias_n_per_m_s`).

References
----------
Montgomery, D. C. & Runger, G. C., *Applied Statistics and Probability for Engineers*,
section 12-2 (covariance of least-squares estimates). Hastie, Tibshirani & Friedman,
*The Elements of Statistical Learning*, 7.10 (cross-validation by left-out groups).
Paper section 4: test airspeeds 0-30 m/s, throttle 10-100 % in 10 % steps, +-0.5 N aim.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tuflexperf.reduction.poly22fit import N_TERMS, Poly22Fit, fit_poly22, poly22_design

# Points whose airspeeds differ by less than this belong to one tunnel set point [m/s].
AIRSPEED_GROUP_GAP_M_S = 1.0
# The paper's test grid (section 4): airspeeds [m/s] and throttles [fraction].
PAPER_TEST_AIRSPEEDS_M_S: tuple[float, ...] = (0.0, 15.0, 20.0, 22.5, 25.0, 27.5, 30.0)
PAPER_TEST_THROTTLES: tuple[float, ...] = tuple(round(0.1 * k, 1) for k in range(1, 11))
PAPER_ACCURACY_N = 0.5


def design_covariance(
    throttle: ArrayLike, airspeed_m_s: ArrayLike, sigma_n: float
) -> NDArray[np.float64]:
    """Covariance [N^2 in the coefficients' units] of a poly22 fit on these points.

    ``sigma^2 (X^T X)^-1`` for independent measurement errors of standard deviation
    ``sigma_n`` [N] at the points ``(throttle [fraction], airspeed_m_s [m/s])``.

    References
    ----------
    Montgomery & Runger, *Applied Statistics and Probability for Engineers*, 12-2.
    """
    design = poly22_design(throttle, airspeed_m_s)
    _, s, vt = np.linalg.svd(design, full_matrices=False)
    scaled = vt.T / s
    covariance = float(sigma_n) ** 2 * (scaled @ scaled.T)
    return 0.5 * (covariance + covariance.T)  # exactly symmetric for the file


def paper_grid() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The paper's test grid as flat (throttle [fraction], airspeed [m/s]) arrays.

    References
    ----------
    Paper section 4: airspeeds 0, 15, 20, 22.5, 25, 27.5, 30 m/s; throttle 100 % down in
    10 % steps.
    """
    x, v = np.meshgrid(PAPER_TEST_THROTTLES, PAPER_TEST_AIRSPEEDS_M_S)
    return x.ravel(), v.ravel()


def airspeed_groups(airspeed_m_s: ArrayLike) -> list[NDArray[np.bool_]]:
    """Masks of the points per tunnel set point (airspeeds closer than 1 m/s), ascending."""
    v = np.asarray(airspeed_m_s, dtype=float)
    order = np.sort(np.unique(v))
    edges = [order[0]]
    for low, high in zip(order[:-1], order[1:], strict=True):
        if high - low > AIRSPEED_GROUP_GAP_M_S:
            edges.append(high)
    bounds = [*edges[1:], np.inf]
    return [(v >= low) & (v < high) for low, high in zip(edges, bounds, strict=True)]


@dataclass(frozen=True)
class LeaveOneAirspeedOut:
    """RMS error [N] at each tested airspeed when that airspeed is left out of the fit."""

    airspeed_m_s: tuple[float, ...]
    rms_error_n: tuple[float | None, ...]  # None where the rest cannot determine a surface
    # the largest |error| among each left-out airspeed's points [N] (its worst throttle)
    worst_error_n: tuple[float | None, ...] = ()
    # at the top airspeed: the mean of measured minus extrapolated over its upper throttles
    # [N] and that mean's standard error [N] (the holds' scatter and the refit's own error)
    top_mean_error_n: float | None = None
    top_mean_error_se_n: float | None = None

    @property
    def extrapolation_sd_n(self) -> float | None:
        """The error at the highest tested airspeed [N] (what extrapolation carries)."""
        return self.rms_error_n[-1] if self.rms_error_n else None

    @property
    def extrapolation_worst_n(self) -> float | None:
        """The largest error [N] at the highest tested airspeed, over its throttles: a
        requirement flown beyond the range flies a high throttle, where it is largest."""
        return self.worst_error_n[-1] if self.worst_error_n else None

    @property
    def extrapolation_distance_m_s(self) -> float | None:
        """How far [m/s] the left-out top airspeed lies beyond the rest: the distance
        :attr:`extrapolation_sd_n` is the error at (the sampler grows it with distance)."""
        if len(self.airspeed_m_s) < 2:
            return None
        return float(self.airspeed_m_s[-1] - self.airspeed_m_s[-2])

    @property
    def extrapolation_bias_n_per_m_s(self) -> float | None:
        """The thrust the extrapolated surface misses per m/s beyond the rest [N per m/s]:
        measured minus extrapolated at the left-out top airspeed, over the distance."""
        distance = self.extrapolation_distance_m_s
        if self.top_mean_error_n is None or not distance or distance <= 0.0:
            return None
        return self.top_mean_error_n / distance

    @property
    def extrapolation_bias_se_n_per_m_s(self) -> float | None:
        """The standard error of :attr:`extrapolation_bias_n_per_m_s` [N per m/s]."""
        distance = self.extrapolation_distance_m_s
        if self.top_mean_error_se_n is None or not distance or distance <= 0.0:
            return None
        return self.top_mean_error_se_n / distance


def leave_one_airspeed_out(
    throttle: ArrayLike, airspeed_m_s: ArrayLike, thrust_n: ArrayLike
) -> LeaveOneAirspeedOut:
    """Leave each tested airspeed out in turn, refit poly22, and measure the error there.

    Parameters
    ----------
    throttle : array
        Throttle of each point [fraction, or the file's unit].
    airspeed_m_s : array
        Airspeed of each point [m/s]; points within 1 m/s are one set point.
    thrust_n : array
        Measured thrust [N].

    Returns
    -------
    LeaveOneAirspeedOut
        Mean airspeed [m/s] and RMS prediction error [N] per set point; ``None`` where the
        remaining points cannot determine the six coefficients.

    References
    ----------
    Hastie, Tibshirani & Friedman, *The Elements of Statistical Learning*, 7.10.
    """
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    y = np.asarray(thrust_n, dtype=float)
    speeds: list[float] = []
    errors: list[float | None] = []
    worst: list[float | None] = []
    mean_se: tuple[float | None, float | None] = (None, None)
    for mask in airspeed_groups(v):
        speeds.append(float(v[mask].mean()))
        mean_se = (None, None)  # the top airspeed's (the last group's) is kept
        rest = ~mask
        if rest.sum() <= N_TERMS or np.unique(np.round(v[rest])).size < 3:
            errors.append(None)
            worst.append(None)
            continue
        try:
            refit = fit_poly22(x[rest], v[rest], y[rest])
        except Exception:  # noqa: BLE001 - a degenerate remainder has no prediction
            errors.append(None)
            worst.append(None)
            continue
        error = refit.predict(x[mask], v[mask]) - y[mask]
        errors.append(float(np.sqrt(np.mean(error**2))))
        worst.append(float(np.max(np.abs(error))))
        mean_se = _upper_mean_error(refit, x[mask], v[mask], y[mask])
    return LeaveOneAirspeedOut(tuple(speeds), tuple(errors), tuple(worst), *mean_se)


def _upper_mean_error(refit: Poly22Fit, x: NDArray[np.float64], v: NDArray[np.float64],
                      y: NDArray[np.float64]) -> tuple[float | None, float | None]:
    """Measured minus ``refit`` [N] averaged over the left-out points at throttles of at least
    half their largest (beyond the tested airspeeds a flight flies a high throttle, where a
    fan's misfit is largest), and its standard error [N]: ``sqrt(g^T C g + s^2 / n)``, ``g``
    their mean design row, ``C`` the refit's covariance and ``s`` its residual scatter (the
    lack of fit counted as noise: an upper bound)."""
    upper = x >= 0.5 * float(np.max(x)) if x.size else x.astype(bool)
    if not upper.any() or not np.all(np.isfinite(refit.covariance)):
        return None, None
    mean = float(np.mean(y[upper] - refit.predict(x[upper], v[upper])))
    g = poly22_design(x[upper], v[upper]).mean(axis=0)
    variance = float(g @ refit.covariance @ g) + refit.residual_sd_n**2 / int(upper.sum())
    return mean, math.sqrt(max(variance, 0.0))


def expected_extrapolation_sd_n(
    throttle: ArrayLike, airspeed_m_s: ArrayLike, sigma_n: float
) -> float:
    """Expected leave-highest-airspeed-out RMS error [N] from measurement noise alone.

    With the highest set point left out, a new point there differs from the refit's
    prediction by ``sigma^2 (1 + g^T (X_-^T X_-)^-1 g)`` in variance, ``g`` its design row;
    the RMS over that set point's throttles is returned.

    References
    ----------
    Montgomery & Runger, *Applied Statistics and Probability for Engineers*, 12-4
    (prediction interval of a new observation).
    """
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    top = airspeed_groups(v)[-1]
    covariance = design_covariance(x[~top], v[~top], sigma_n)
    rows = poly22_design(x[top], v[top])
    variance = sigma_n**2 + np.einsum("ij,jk,ik->i", rows, covariance, rows)
    return float(np.sqrt(np.mean(variance)))


@dataclass(frozen=True)
class PublishedGridUncertainty:
    """Uncertainty of a model reconstructed from published values (no raw points)."""

    covariance: NDArray[np.float64]  # 6x6 [N^2 in the coefficients' units]
    residual_sd_n: float  # [N]
    extrapolation_sd_n: float  # [N]


def published_grid_uncertainty(
    accuracy_n: float = PAPER_ACCURACY_N, edge_error_n: float = 0.0
) -> PublishedGridUncertainty:
    """Covariance and extrapolation error of a poly22 fitted on the paper's test grid.

    Parameters
    ----------
    accuracy_n : float
        Measurement accuracy [N], taken as one standard deviation (paper: +-0.5 N).
    edge_error_n : float
        Largest published model error at the highest tested airspeed [N] (paper: 0.73 N
        for EDF1, 0.50 N for EDF2 at 30 m/s); the extrapolation error is at least this.

    Returns
    -------
    PublishedGridUncertainty
        ``sigma^2 (X^T X)^-1`` on the 7 x 10 grid, ``residual_sd_n = sigma``, and
        ``extrapolation_sd_n = max(expected leave-30-m/s-out error, edge_error_n)``.

    References
    ----------
    Paper section 4 (test grid, +-0.5 N, errors at 30 m/s); Montgomery & Runger 12-2, 12-4.
    """
    x, v = paper_grid()
    expected = expected_extrapolation_sd_n(x, v, accuracy_n)
    return PublishedGridUncertainty(
        covariance=design_covariance(x, v, accuracy_n),
        residual_sd_n=float(accuracy_n),
        extrapolation_sd_n=max(expected, float(edge_error_n)),
    )
