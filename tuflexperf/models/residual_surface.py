"""The poly22's residual surface as a Gaussian process: where the fit's holds say it errs.

``fit`` writes, where the lack-of-fit test finds structure, each set point's mean residual
(measured minus surface) into the propulsion file (``lack_of_fit.residuals``). Between and
near them the surface's error is the posterior of a Gaussian process over (throttle,
airspeed) conditioned on them (Rasmussen & Williams, *Gaussian Processes for Machine
Learning*, 2006, eq. 2.25-2.26): its mean is the error the holds show there (0 far from
them), its variance what they leave open. The hyperparameters, by a stated rule:

- the signal variance: the lack of fit's model-form mean square (``model_form_rms_n^2``);
- the length scales: a fraction of the tested span in throttle and in airspeed, one of
  :data:`LENGTH_FRACTIONS`;
- the noise of a set point's mean: the pure error's square over its count of holds, plus a
  fraction of the signal variance, one of :data:`NUGGET_FRACTIONS` (a hold's mean errs from
  hold to hold by more than its own scatter says: a pack's charge, the tunnel's drift);
- the fraction of each the pair of largest marginal likelihood (eq. 2.30) on that grid.

The mean is tabulated on a grid (:data:`THROTTLE_NODES` x :data:`AIRSPEED_NODES` over the
tested domain and three length scales beyond it, 0 past the grid's edge as the posterior
is) and read by bilinear interpolation, vectorised over any shapes of throttle and airspeed.
What the mean leaves open (``ResidualSurface.sd_n``) is the posterior's own variance over the
tested domain plus the mean square of its leave-one-out errors at the set points (eq. 5.12):
the posterior alone trusts the holds' means as the truth wherever they are dense.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

LENGTH_FRACTIONS = (0.15, 0.25, 0.4)
"""The length scales tried, as fractions of the tested span in throttle and airspeed."""
NUGGET_FRACTIONS = (0.0, 1e-3, 1e-2, 3e-2, 0.1, 0.3)
"""The hold-to-hold noise tried, as fractions of the signal variance."""
THROTTLE_NODES = 41
AIRSPEED_NODES = 31
BEYOND_LENGTHS = 3.0  # the grid's reach past the holds [length scales]: the mean is ~0 there


@dataclass(frozen=True)
class ResidualSurface:
    """The posterior mean of the residual surface [N] on a grid, and what the rule chose.

    ``throttle`` ``(nx,)`` [fraction] and ``airspeed`` ``(nv,)`` [m/s] the nodes, ``mean``
    ``(nx, nv)`` [N]; ``sd_n`` [N] what the mean leaves open: the posterior variance's mean
    over the tested domain and the mean square of the mean's leave-one-out errors at the set
    points (how well it predicts a set point it was not given), their sum's root;
    ``length_fraction`` and ``nugget_fraction`` the hyperparameters taken; ``points`` the
    set points conditioned on.
    """

    throttle: Array
    airspeed: Array
    mean: Array
    sd_n: float
    length_fraction: float
    nugget_fraction: float
    points: int

    def __call__(self, throttle: Any, airspeed_m_s: Any) -> Array:
        """The mean [N] at ``throttle`` [fraction] and ``airspeed_m_s`` (broadcast together);
        0 beyond the grid."""
        gx, gv = self.throttle, self.airspeed
        if np.ndim(throttle) == 0:  # one throttle (the roll's, a node): its column, 1-D
            fx = min(max((float(throttle) - gx[0]) / (gx[1] - gx[0]), 0.0), gx.size - 1.0)
            if float(throttle) < gx[0] or float(throttle) > gx[-1]:
                return np.zeros(np.shape(airspeed_m_s))
            i = min(int(fx), gx.size - 2)
            column = (1.0 - (fx - i)) * self.mean[i] + (fx - i) * self.mean[i + 1]
            return np.interp(np.asarray(airspeed_m_s, dtype=float), gv, column, left=0.0,
                             right=0.0)
        x, v = np.broadcast_arrays(np.asarray(throttle, dtype=float),
                                   np.asarray(airspeed_m_s, dtype=float))
        fx = (x - gx[0]) / (gx[1] - gx[0])
        fv = (v - gv[0]) / (gv[1] - gv[0])
        inside = (fx >= 0.0) & (fx <= gx.size - 1) & (fv >= 0.0) & (fv <= gv.size - 1)
        i = np.clip(np.floor(fx).astype(np.intp), 0, gx.size - 2)
        j = np.clip(np.floor(fv).astype(np.intp), 0, gv.size - 2)
        tx = np.clip(fx - i, 0.0, 1.0)
        tv = np.clip(fv - j, 0.0, 1.0)
        m = self.mean
        value = ((1.0 - tx) * ((1.0 - tv) * m[i, j] + tv * m[i, j + 1])
                 + tx * ((1.0 - tv) * m[i + 1, j] + tv * m[i + 1, j + 1]))
        return np.where(inside, value, 0.0)


def _kernel(xa: Array, va: Array, xb: Array, vb: Array, lx: float, lv: float,
            s2: float) -> Array:
    return s2 * np.exp(-0.5 * (((xa[:, None] - xb[None]) / lx) ** 2
                               + ((va[:, None] - vb[None]) / lv) ** 2))


def residual_surface(rows: Sequence[Sequence[float]], throttle_scale: float,
                     tested_airspeed_m_s: tuple[float, float], signal_sd_n: float,
                     noise_sd_n: float) -> ResidualSurface | None:
    """The residual surface's posterior (module docstring) from ``rows`` (throttle [file
    units], airspeed [m/s], mean residual [N], count); None without a signal or points.

    Parameters
    ----------
    rows : sequence of (throttle, airspeed, residual, count)
        ``lack_of_fit.residuals`` [file units, m/s, N, -].
    throttle_scale : float
        File throttle per fraction (100 for percent) [-].
    tested_airspeed_m_s : (float, float)
        The tested range [m/s].
    signal_sd_n : float
        The lack of fit's model-form RMS [N].
    noise_sd_n : float
        One hold mean's pure error [N].
    """
    table = np.asarray(rows, dtype=float).reshape(-1, 4)
    if table.shape[0] < 2 or not signal_sd_n > 0.0:
        return None
    x = table[:, 0] / throttle_scale
    v, r, count = table[:, 1], table[:, 2], np.maximum(table[:, 3], 1.0)
    s2 = float(signal_sd_n) ** 2
    low, high = tested_airspeed_m_s
    span_x = max(float(x.max() - x.min()), 1e-6)
    span_v = max(float(high - low), 1e-6)
    pure = (float(noise_sd_n) if noise_sd_n and math.isfinite(noise_sd_n) else 0.0) ** 2 / count
    best: tuple[float, float, float, Array, Array] | None = None
    for frac in LENGTH_FRACTIONS:
        k = _kernel(x, v, x, v, frac * span_x, frac * span_v, s2)
        for nugget in NUGGET_FRACTIONS:
            try:
                chol = np.linalg.cholesky(k + np.diag(pure + nugget * s2 + 1e-10 * s2))
            except np.linalg.LinAlgError:
                continue
            alpha = np.linalg.solve(chol.T, np.linalg.solve(chol, r))
            likelihood = -0.5 * float(r @ alpha) - float(np.log(np.diag(chol)).sum())
            if best is None or likelihood > best[0]:
                best = (likelihood, frac, nugget, chol, alpha)
    if best is None:
        return None
    _, frac, nugget, chol, alpha = best
    lx, lv = frac * span_x, frac * span_v
    gx = np.linspace(0.0, 1.0, THROTTLE_NODES)
    gv = np.linspace(low - BEYOND_LENGTHS * lv, high + BEYOND_LENGTHS * lv, AIRSPEED_NODES)
    px, pv = (a.ravel() for a in np.meshgrid(gx, gv, indexing="ij"))
    mean = (_kernel(px, pv, x, v, lx, lv, s2) @ alpha).reshape(gx.size, gv.size)
    # the posterior sd's RMS over the tested domain (11 x 11 points)
    dx, dv = (a.ravel() for a in np.meshgrid(np.linspace(0.0, 1.0, 11),
                                            np.linspace(low, high, 11), indexing="ij"))
    w = np.linalg.solve(chol, _kernel(dx, dv, x, v, lx, lv, s2).T)
    posterior = float(np.mean(np.maximum(s2 - np.sum(w * w, axis=0), 0.0)))
    # leave-one-out residuals in closed form (eq. 5.12): alpha_i / [K^-1]_ii
    inverse = np.linalg.inv(chol)
    loo = alpha / np.sum(inverse * inverse, axis=0)
    sd = math.sqrt(posterior + float(np.mean(loo * loo)))
    return ResidualSurface(gx, gv, mean, sd, frac, nugget, int(table.shape[0]))
