"""Lack of fit of a thrust surface: is the scatter of the holds about it their own noise?

The classical test (Montgomery, *Design and Analysis of Experiments*, sec. 10.x; Draper &
Smith, *Applied Regression Analysis*, 3rd ed., sec. 2.1): with ``m`` distinct conditions,
``n`` points and ``p`` coefficients, the residual sum of squares splits into pure error
(the replicates about their own condition's mean, ``n - m`` degrees of freedom) and lack of
fit (the condition means about the surface, ``m - p``); ``F = MS_LOF / MS_PE`` follows
``F(m - p, n - m)`` when the form is right.

A wind-tunnel campaign seldom repeats a hold. Then the pure error of each hold's mean comes
from inside the hold: the variance of its mean by non-overlapping batch means (batches of
:data:`BATCH_S`, long against the rig's vibration and the 0.1 s median filter, so the
autocorrelation of the samples is inside a batch; Flegal & Jones 2010), with
``sum(batches - 1)`` degrees of freedom. The test is then the residual mean square against the
mean square the holds' own noise alone would give, ``sum((1 - h_ii) var_i) / (n - p)`` (``h``
the hat matrix's diagonal: the expectation of the residual sum of squares for independent
holds of variances ``var_i``). Which basis was used is always said: a hold's inside misses
what changes only from hold to hold (a pack's charge, the tunnel's slow drift), which makes the
test stricter, while a drift within a hold's few batches counts as its noise, which makes it
milder (on the shipped campaign the two nearly balance: F 0.90 and 0.45 for 71 and 153 dof).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

# p below this: the surface does not fit its data (issue 43 item 4)
LACK_OF_FIT_P = 0.01
# Batch length [s] of the batch-means variance: ten times the 0.1 s median window and the
# spool lag, so that neighbouring batches' means are nearly independent
BATCH_S = 1.0
# Fewest replicate degrees of freedom that make a pure error of their own; fewer: the holds'
# inside gives it (two repeats of one hold measure one difference)
MIN_REPLICATE_DOF = 3
# Throttles closer than this are one set point [fraction]
THROTTLE_SET_POINT = 0.01


@dataclass(frozen=True)
class LackOfFit:
    """One surface's lack-of-fit test (module docstring); forces in N, airspeed in m/s."""

    form: str
    f_statistic: float
    p_value: float
    model_form_rms_n: float  # rms over the holds of the surface's bias, beyond their noise
    pure_error_rms_n: float  # repeatability of one hold's mean
    dof_lack_of_fit: int
    dof_pure_error: int
    worst_throttle: float
    worst_airspeed_m_s: float
    worst_residual_n: float  # measured minus surface at the worst hold (condition)
    basis: str  # "replicate_holds" or "within_hold"
    terms: int
    # where the surface errs: the shares of its mean square along MODEL_FORM_TERMS (None:
    # no structure found, or not estimated)
    model_form_shares: tuple[float, ...] | None = None
    # the residual surface where the test finds structure: per set point (throttle [file
    # units], airspeed [m/s], mean residual [N], holds) (None: no structure found)
    residuals: tuple[tuple[float, float, float, int], ...] | None = None

    @property
    def fits(self) -> bool:
        """Whether the form fits its data: not shown otherwise (p below :data:`LACK_OF_FIT_P`;
        a NaN p, e.g. holds without scatter, shows nothing)."""
        return not self.p_value < LACK_OF_FIT_P

    def as_dict(self) -> dict[str, Any]:
        return {
            "f_statistic": self.f_statistic,
            "p_value": self.p_value,
            "model_form_rms_n": self.model_form_rms_n,
            "pure_error_rms_n": self.pure_error_rms_n,
            "dof_lack_of_fit": self.dof_lack_of_fit,
            "dof_pure_error": self.dof_pure_error,
            "worst_throttle": self.worst_throttle,
            "worst_airspeed_m_s": self.worst_airspeed_m_s,
            "worst_residual_n": self.worst_residual_n,
            "pure_error_basis": self.basis,
            **({} if self.model_form_shares is None
               else {"model_form_shares": list(self.model_form_shares)}),
            **({} if self.residuals is None
               else {"residuals": [list(row) for row in self.residuals]}),
        }


def batch_mean_variance(samples: ArrayLike, batch: int) -> tuple[float, int]:
    """Variance [N^2] of the mean of autocorrelated ``samples`` by non-overlapping batch means
    of ``batch`` samples (at least two batches: a shorter stretch is halved), and its degrees
    of freedom (batches - 1)."""
    x = np.asarray(samples, dtype=float)
    count = max(2, x.size // max(int(batch), 1))
    length = x.size // count
    if length < 1:
        return math.nan, 0
    means = x[: count * length].reshape(count, length).mean(axis=1)
    return float(means.var(ddof=1) / count), count - 1


def polynomial_terms(degree_x: int, degree_v: int) -> list[tuple[int, int]]:
    """MATLAB's ``polyMN`` terms ``x^i v^j``: ``i <= M``, ``j <= N``, ``i + j <= max(M, N)``."""
    top = max(degree_x, degree_v)
    return [(i, j) for total in range(top + 1) for i in range(total, -1, -1)
            for j in [total - i] if i <= degree_x and j <= degree_v]


def polynomial_design(throttle: ArrayLike, airspeed_m_s: ArrayLike,
                      terms: Sequence[tuple[int, int]]) -> NDArray[np.float64]:
    """Design matrix of ``terms`` (``x^i v^j``) at the points; columns scaled later."""
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    return np.column_stack([x**i * v**j for i, j in terms])


def _least_squares(design: NDArray[np.float64], y: NDArray[np.float64]) -> tuple[
        NDArray[np.float64], NDArray[np.float64]]:
    """Residuals and hat-matrix diagonal of the OLS fit (columns scaled: airspeed^3 ~ 3e4)."""
    scale = np.maximum(np.abs(design).max(axis=0), 1e-300)
    u, s, _ = np.linalg.svd(design / scale, full_matrices=False)
    keep = s > s[0] * max(design.shape) * np.finfo(float).eps
    u = u[:, keep]
    return y - u @ (u.T @ y), np.einsum("ij,ij->i", u, u)


MODEL_FORM_TERMS = ("offset", "throttle", "airspeed", "throttle_airspeed", "airspeed_squared")
"""The model-form error's shapes over the tested domain (``u = 2 x - 1`` the throttle,
``t`` the airspeed's place in the tested range mapped to [-1, 1]), Legendre polynomials each
scaled to a mean square of 1 there: ``1``, ``sqrt 3 u``, ``sqrt 3 t``, ``3 u t``,
``sqrt 5 (3 t^2 - 1) / 2``. The poly22's sixth, the quadratic in throttle, is not among
them: the surface is itself quadratic in throttle, so its misfit along the throttle is a
cubic or higher, small at mid-throttle and large at the ends as the slope's square is,
while the quadratic's square is large at mid-throttle too (with it, the calibration study's
bands at the mid-throttle cruises came out twice as wide as the truth's error; its
airspeed quadratic changes sign between a loiter and a cruise as their true errors do)."""


def model_form_basis(throttle: ArrayLike, airspeed_m_s: ArrayLike,
                     tested_airspeed_m_s: tuple[float, float]) -> NDArray[np.float64]:
    """The :data:`MODEL_FORM_TERMS` at the points ``(n, 5)`` [-]: throttle a fraction."""
    u = 2.0 * np.asarray(throttle, dtype=float) - 1.0
    low, high = tested_airspeed_m_s
    span = high - low if high > low else 1.0
    t = 2.0 * (np.asarray(airspeed_m_s, dtype=float) - low) / span - 1.0
    return np.column_stack([np.ones_like(u), math.sqrt(3.0) * u, math.sqrt(3.0) * t,
                            3.0 * u * t, math.sqrt(5.0) * 0.5 * (3.0 * t * t - 1.0)])


def model_form_shares(throttle: ArrayLike, airspeed_m_s: ArrayLike, residual_n: ArrayLike,
                      noise_n2: ArrayLike) -> tuple[float, ...] | None:
    """Where the surface errs: the shares of its mean square along :data:`MODEL_FORM_TERMS`.

    Each hold's squared residual less its noise's expectation [N^2] is fitted by
    ``sum_k w_k phi_k^2`` with ``w >= 0`` (the variance profile of a random sum of the
    terms; every subset of the five tried, the best non-negative kept), the shares
    ``w / sum w``. The residuals of a least-squares poly22 hold no poly22 shape, so it is
    their size along throttle and airspeed that says which of the terms' profiles the
    error follows, not their sign. None where nothing is left above the noise.
    """
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    target = np.asarray(residual_n, dtype=float) ** 2 - np.asarray(noise_n2, dtype=float)
    if x.size < 8 or not np.all(np.isfinite(target)):
        return None
    scale = 100.0 if float(np.max(x)) > 1.5 else 1.0  # a throttle in percent
    profile = model_form_basis(x / scale, v, (float(v.min()), float(v.max()))) ** 2
    count = profile.shape[1]
    best, best_sse = None, math.inf
    for mask in range(1, 2 ** count):
        keep = [k for k in range(count) if mask >> k & 1]
        w = np.linalg.lstsq(profile[:, keep], target, rcond=None)[0]
        if np.any(w < 0.0):
            continue
        sse = float(np.sum((profile[:, keep] @ w - target) ** 2))
        if sse < best_sse:
            best, best_sse = np.zeros(count), sse
            best[keep] = w
    if best is None or best.sum() <= 0.0:
        return None
    shares = best / best.sum()
    return tuple(float(round(c, 4)) for c in shares)


def hold_residuals(throttle: ArrayLike, airspeed_m_s: ArrayLike, residual_n: ArrayLike,
                   groups: ArrayLike) -> tuple[tuple[float, float, float, int], ...]:
    """The residual surface as the sampler reads it: per set point (``groups`` labels) the
    mean throttle [file units], mean airspeed [m/s], mean residual [N] and its count of
    holds, rounded to what a file needs (1e-4 throttle, 1e-3 m/s, 1e-4 N)."""
    _, label = np.unique(np.asarray(groups), return_inverse=True)
    label = label.ravel()
    counts = np.bincount(label)
    means = [np.bincount(label, np.asarray(a, dtype=float)) / counts
             for a in (throttle, airspeed_m_s, residual_n)]
    return tuple((round(float(x), 4), round(float(v), 3), round(float(r), 4), int(n))
                 for x, v, r, n in zip(*means, counts, strict=True))


def _p_value(f: float, dof1: int, dof2: float) -> float:
    # stats.f.sf's kernel (scipy.stats takes ~1 s to import), here only: the sampler reads
    # this module's model-form shapes and imports no scipy
    from scipy.special import fdtrc

    return float(fdtrc(dof1, dof2, f)) if math.isfinite(f) else math.nan


def replicate_test(design: ArrayLike, y: ArrayLike, groups: ArrayLike, throttle: ArrayLike,
                   airspeed_m_s: ArrayLike, form: str = "poly22") -> LackOfFit:
    """The textbook test on replicates: ``groups`` labels the points of one condition.

    ``SS_PE = sum (y_ij - ybar_i)^2`` on ``n - m`` dof, ``SS_LOF = SSE - SS_PE`` on ``m - p``;
    the model-form rms is ``sqrt(max(SS_LOF - (m - p) MS_PE, 0) / n)`` (the expectation of
    ``SS_LOF`` is ``(m - p) sigma^2 + sum n_i bias_i^2``). A tunnel's repeat is a near
    replicate (its airspeed a few 0.01 m/s off the other's): the pure error is then the
    residual of the surface *plus* one mean per condition, so that the surface's own slope
    between the repeats is not counted as their scatter (the extra-sum-of-squares form of the
    same test, Draper & Smith sec. 6.1; for exact replicates it is the textbook split).
    """
    X = np.asarray(design, dtype=float)
    y = np.asarray(y, dtype=float)
    _, label = np.unique(np.asarray(groups), return_inverse=True)
    residual, hat = _least_squares(X, y)
    p = int(round(hat.sum()))  # the fit's rank
    m = int(label.max()) + 1
    indicators = (label[:, None] == np.arange(m)).astype(float)
    pure, full_hat = _least_squares(np.column_stack([X, indicators]), y)
    rank = int(round(full_hat.sum()))
    ss_pe = float(pure @ pure)
    sse = float(residual @ residual)
    ss_lof = max(sse - ss_pe, 0.0)
    dof_lof, dof_pe = rank - p, y.size - rank
    ms_pe = ss_pe / dof_pe if dof_pe > 0 else math.nan
    f = (ss_lof / dof_lof) / ms_pe if dof_lof > 0 and ms_pe > 0 else math.nan
    counts = np.bincount(label)
    group_residual = np.bincount(label, residual) / counts  # condition mean minus surface
    worst = int(np.argmax(np.abs(group_residual)))
    first = np.argmax(indicators, axis=0)  # a point of each condition
    return LackOfFit(
        form=form, f_statistic=f, p_value=_p_value(f, dof_lof, dof_pe),
        model_form_rms_n=math.sqrt(max(ss_lof - dof_lof * ms_pe, 0.0) / y.size)
        if dof_pe > 0 else math.nan,
        pure_error_rms_n=math.sqrt(ms_pe) if dof_pe > 0 else math.nan,
        dof_lack_of_fit=dof_lof, dof_pure_error=dof_pe,
        worst_throttle=float(np.asarray(throttle, dtype=float)[first[worst]]),
        worst_airspeed_m_s=float(np.asarray(airspeed_m_s, dtype=float)[first[worst]]),
        worst_residual_n=float(group_residual[worst]), basis="replicate_holds", terms=p,
    )


def within_hold_test(design: ArrayLike, y: ArrayLike, hold_variance_n2: ArrayLike,
                     dof_pure_error: int, throttle: ArrayLike, airspeed_m_s: ArrayLike,
                     form: str = "poly22") -> LackOfFit:
    """The test against each hold's own noise (module docstring): ``F = SSE / sum((1 - h_ii)
    var_i)`` on ``(n - p, dof_pure_error)`` dof; model-form rms ``sqrt(max(SSE - sum((1 -
    h_ii) var_i), 0) / n)``."""
    X = np.asarray(design, dtype=float)
    y = np.asarray(y, dtype=float)
    var = np.asarray(hold_variance_n2, dtype=float)
    residual, hat = _least_squares(X, y)
    p = int(round(hat.sum()))
    sse = float(residual @ residual)
    expected = float(np.sum((1.0 - hat) * var))  # SSE's expectation from the holds' noise
    dof_lof = y.size - p
    f = sse / expected if expected > 0 and dof_lof > 0 else math.nan
    worst = int(np.argmax(np.abs(residual)))
    return LackOfFit(
        form=form, f_statistic=f, p_value=_p_value(f, dof_lof, dof_pure_error),
        model_form_rms_n=math.sqrt(max(sse - expected, 0.0) / y.size),
        pure_error_rms_n=math.sqrt(float(var.mean())),
        dof_lack_of_fit=dof_lof, dof_pure_error=int(dof_pure_error),
        worst_throttle=float(np.asarray(throttle, dtype=float)[worst]),
        worst_airspeed_m_s=float(np.asarray(airspeed_m_s, dtype=float)[worst]),
        worst_residual_n=float(residual[worst]), basis="within_hold", terms=p,
    )


# The forms compared with poly22: MATLAB's polynomial surfaces one degree up in throttle, in
# airspeed or both (the propulsion file holds poly22 only: they say what form the data want)
ALTERNATIVE_FORMS = {"poly32": (3, 2), "poly23": (2, 3), "poly33": (3, 3)}


@dataclass(frozen=True)
class EngineLackOfFit:
    """poly22's test and, where it fails, the best of the other forms by the same test."""

    poly22: LackOfFit
    alternatives: tuple[LackOfFit, ...]
    largest_thrust_n: float = math.nan  # of the holds: the error's size in proportion

    @property
    def best_alternative(self) -> LackOfFit | None:
        """The form that fits with the fewest terms, else the one with the smallest F; None
        where poly22 fits."""
        if self.poly22.fits or not self.alternatives:
            return None
        fitting = [a for a in self.alternatives if a.fits]
        if fitting:
            return min(fitting, key=lambda a: (a.terms, -a.p_value))
        return min(self.alternatives, key=lambda a: a.f_statistic)

    def as_dict(self) -> dict[str, Any]:
        best = self.best_alternative
        return {
            **self.poly22.as_dict(),
            "best_alternative": None if best is None else {
                "form": best.form,
                "f_statistic": best.f_statistic,
                "p_value": best.p_value,
                "model_form_rms_n": best.model_form_rms_n,
                "in_propulsion_file": False,  # the file holds poly22 only
            },
        }


def set_point_groups(throttle: ArrayLike, airspeed_set_point_m_s: ArrayLike) -> NDArray[Any]:
    """One label per (throttle, airspeed) set point: holds with one label replicate."""
    x = np.round(np.asarray(throttle, dtype=float) / THROTTLE_SET_POINT).astype(np.int64)
    v = np.round(np.asarray(airspeed_set_point_m_s, dtype=float) * 1000.0).astype(np.int64)
    return np.unique(np.column_stack([x, v]), axis=0, return_inverse=True)[1].ravel()


def engine_lack_of_fit(
    throttle: ArrayLike, airspeed_m_s: ArrayLike, thrust_n: ArrayLike,
    set_points: ArrayLike, hold_variance_n2: ArrayLike | None = None, hold_dof: int = 0,
) -> EngineLackOfFit | None:
    """poly22's lack of fit and the alternatives' (module docstring) for one engine's holds.

    Replicate holds (same throttle and airspeed set point) give the pure error where they have
    :data:`MIN_REPLICATE_DOF` or more; else each hold's variance of its mean
    ``hold_variance_n2`` [N^2] with ``hold_dof`` dof. None: neither (a table without repeats).
    """
    x = np.asarray(throttle, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    y = np.asarray(thrust_n, dtype=float)
    # the worst hold is named by its set point (a static hold's mean may read -0.0003 m/s)
    where = np.asarray(set_points, dtype=float) + 0.0
    groups = set_point_groups(x, where)
    replicated = y.size - (int(groups.max()) + 1) >= MIN_REPLICATE_DOF
    if not replicated and (hold_variance_n2 is None or hold_dof < 1
                           or not np.all(np.isfinite(hold_variance_n2))):
        return None

    def test(form: str, degrees: tuple[int, int]) -> LackOfFit | None:
        design = polynomial_design(x, v, polynomial_terms(*degrees))
        if y.size <= design.shape[1]:
            return None
        if replicated:
            return replicate_test(design, y, groups, x, where, form)
        return within_hold_test(design, y, hold_variance_n2, hold_dof, x, where, form)

    base = test("poly22", (2, 2))
    if base is None:
        return None
    if not base.fits:
        # the structure the test found: where along throttle and airspeed it lies
        design = polynomial_design(x, v, polynomial_terms(2, 2))
        residual, hat = _least_squares(design, y)
        if replicated:
            noise = np.full(y.size, base.pure_error_rms_n ** 2) * (1.0 - hat)
        else:
            noise = (1.0 - hat) * np.asarray(hold_variance_n2, dtype=float)
        base = replace(base, model_form_shares=model_form_shares(x, v, residual, noise),
                       residuals=hold_residuals(x, v, residual, groups))
    others = tuple(t for t in (test(f, d) for f, d in ALTERNATIVE_FORMS.items())
                   if t is not None and t.dof_lack_of_fit > 0)
    return EngineLackOfFit(base, others, float(np.max(np.abs(y))))


def lack_of_fit_note(engine: str, result: EngineLackOfFit) -> str | None:
    """The plain sentence where the surface does not fit (None where it does)."""
    lof = result.poly22
    if lof.fits or not math.isfinite(lof.p_value):
        return None
    ratio = lof.model_form_rms_n / lof.pure_error_rms_n if lof.pure_error_rms_n > 0 else math.inf
    p = "p < 1e-16" if lof.p_value < 1e-16 else f"p = {lof.p_value:.2g}"
    basis = ("replicate holds" if lof.basis == "replicate_holds"
             else "each hold's own scatter, autocorrelation-corrected")
    text = (f"{engine}: the poly22 surface does not fit its data (lack of fit F = "
            f"{lof.f_statistic:.3g}, {p}): model-form error {lof.model_form_rms_n:.3g} N rms "
            f"against {lof.pure_error_rms_n:.2g} N pure error ({basis}), {ratio:.3g}x, "
            f"{100 * lof.model_form_rms_n / result.largest_thrust_n:.2g} % of the largest "
            f"thrust; worst "
            f"at throttle {lof.worst_throttle:.2f}, {lof.worst_airspeed_m_s:.1f} m/s "
            f"({lof.worst_residual_n:+.3g} N measured minus surface)")
    best = result.best_alternative
    if best is not None:
        verdict = "fits" if best.fits else "does not fit either"
        text += (f"; best form compared: {best.form} ({best.model_form_rms_n:.2g} N rms, F = "
                 f"{best.f_statistic:.3g}, {verdict}), which the propulsion file cannot hold")
    return text
