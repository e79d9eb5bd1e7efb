"""Throttle-to-force delay from a sine-sweep run (paper section 4: 0.05 s).

A plain cross-correlation of throttle and force measures the dead time *plus*
the fan's spool lag (a first-order lag of time constant ``tau`` shifts a sine of
frequency ``f`` by ``atan(2 pi f tau) / (2 pi f)``, about ``tau`` at low
frequency). The dead time is what the flight-dynamics model adds as a pure delay,
so both are fitted, by least squares, to the measured force:

``F(t) = c0 + c1 t + c2 L[u](t) + c3 L[u]^2(t) + c4 L[u^2](t)``,
``u(t) = x(t - d)``, ``L`` the first-order lag with time constant ``tau``,

linear in ``c`` (solved exactly for each ``(d, tau)``: variable projection) and
searched over ``d`` and ``tau``. The quadratic terms carry the fan's static
nonlinearity (thrust ~ rpm^2), whether the lag acts before or after it; the
``t`` term absorbs battery sag. A sweep that rises in frequency (the paper's
25-75 %, up to 5 Hz) separates ``d`` from ``tau``: the lag's phase saturates
with frequency, the dead time's keeps growing.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tuflexperf.reduction.filters import block_mean, first_order_lag, movmedian, window_samples

FIT_RATE_HZ = 200.0
"""The fit runs on block means at about this rate (both signals averaged alike)."""


@dataclass(frozen=True)
class DelayEstimate:
    """Dead time ``delay_s`` and spool lag ``lag_s`` (s) of one sweep, with the fit's R^2."""

    delay_s: float
    lag_s: float
    r2: float
    xcorr_lag_s: float


def _lag_filter(u: NDArray[np.float64], tau: float, dt: float) -> NDArray[np.float64]:
    """Discrete first-order lag ``tau dy/dt = u - y`` (exact for a sample-and-hold input)."""
    if tau <= 0:
        return u
    return first_order_lag(u, float(np.exp(-dt / tau)))


def _xcorr_lag(x: NDArray[np.float64], y: NDArray[np.float64], dt: float, max_lag: int) -> float:
    """Lag (s) of the cross-correlation peak of ``y`` behind ``x`` in ``[0, max_lag]`` samples."""
    xc = x - x.mean()
    yc = y - y.mean()
    # corr[k] = sum_n yc[n + k] xc[n] for k >= 0, by FFT with zero padding (no wrap-around)
    size = 1 << int(2 * xc.size - 1).bit_length()
    corr = np.fft.irfft(np.fft.rfft(yc, size) * np.conj(np.fft.rfft(xc, size)), size)
    return float(np.argmax(corr[: max_lag + 1])) * dt


def _projected_sse(
    t: NDArray[np.float64], x: NDArray[np.float64], y: NDArray[np.float64], dt: float
) -> Callable[[float, NDArray[np.float64]], NDArray[np.float64]]:
    """``(delay, taus) -> residual sum of squares per tau`` of the variable-projection fit
    on one sampling ``t`` [s] of throttle ``x`` [-] and force ``y`` [N] (step ``dt`` [s])."""
    tn = (t - t[0]) / max(t[-1] - t[0], dt)
    # constant and trend columns do not depend on (d, tau): project them out once
    basis, _ = np.linalg.qr(np.column_stack([np.ones_like(t), tn]))
    y_free = y - basis @ (basis.T @ y)
    yy = float(y_free @ y_free)

    def sse_of_taus(delay: float, taus: NDArray[np.float64]) -> NDArray[np.float64]:
        u = np.interp(t - delay, t, x)
        both = np.stack([u, u * u])
        rows = np.empty((6, t.size))
        rows[3:5], rows[5] = basis.T, y_free
        grams = np.empty((taus.size, 3, 3))
        rhs = np.empty((taus.size, 3))
        for m, tau in enumerate(taus):
            rows[0], rows[2] = _lag_filter(both, float(tau), dt)
            np.multiply(rows[0], rows[0], out=rows[1])
            # one product gives every dot product of the fan columns L[u], L[u]^2, L[u^2]
            # with each other, the constant/trend basis and the data
            dots = rows[:3] @ rows.T
            cross = dots[:, 3:5]
            grams[m] = dots[:, :3] - cross @ cross.T  # fan columns with the basis projected out
            rhs[m] = dots[:, 5]  # y_free is orthogonal to the basis already
        # columns scaled to unit norm; 3 x 3 normal equations (rank-deficient at tau = 0, where
        # L[u^2] = L[u]^2): the pseudo-inverse drops singular values below 1e-12 of the
        # largest, as lstsq does; the least-squares residual is ||y||^2 - b' G^+ b
        scale = np.sqrt(np.maximum(np.einsum("mii->mi", grams), 0.0))
        scale[scale == 0.0] = 1.0
        grams /= scale[:, :, None] * scale[:, None, :]
        rhs /= scale
        coef = np.einsum("mij,mj->mi", np.linalg.pinv(grams, rcond=1e-12), rhs)
        return yy - np.einsum("mi,mi->m", coef, rhs)

    return sse_of_taus


#: The longest dead time the reduction looks for [s]: an EDF answers within tens of ms (the
#: paper's 0.05 s), and the shortest throttle plateau a run may hold is half a second.
MAX_DELAY_S = 1.0


def estimate_delay(
    time_s: NDArray[np.float64],
    throttle: NDArray[np.float64],
    force_n: NDArray[np.float64],
    sample_rate_hz: float,
    max_delay_s: float = MAX_DELAY_S,
) -> DelayEstimate:
    """Fit dead time and spool lag of one sine-sweep run (see the module docstring).

    The linear coefficients are eliminated exactly for each ``(d, tau)`` (variable
    projection: the constant and trend columns are projected out once, the three
    fan columns solved by a 3 x 3 least squares); ``(d, tau)`` is found on a grid
    and refined on shrinking 3 x 3 stencils (each jumping to the local quadratic's
    minimum) to 0.1 ms, so no general-purpose optimiser runs.

    Parameters
    ----------
    time_s, throttle, force_n : ndarray
        The run: time in [s], throttle [fraction], force in [N].
    sample_rate_hz : float
        Log rate [Hz].
    max_delay_s : float
        Largest dead time (and lag) searched [s].

    Returns
    -------
    DelayEstimate

    References
    ----------
    Golub, G. H. and Pereyra, V. (1973), "The differentiation of pseudo-inverses and
    nonlinear least squares problems whose variables separate", SIAM J. Numer. Anal. 10.
    """
    k = window_samples(0.02, sample_rate_hz) | 1  # 20 ms median: spikes out, no phase shift
    force = movmedian(force_n, k) if k >= 3 else np.asarray(force_n, dtype=float)
    block = max(1, int(round(sample_rate_hz / FIT_RATE_HZ)))
    t = block_mean(time_s, block)
    x = block_mean(throttle, block)
    y = block_mean(force, block)
    dt = block / sample_rate_hz
    sst = float(np.sum((y - y.mean()) ** 2))
    sse_of_taus = _projected_sse(t, x, y, dt)
    # the grid on block means four times coarser, its best cell and neighbours again at
    # the fit rate: the grid is where most (d, tau) pairs are tried
    coarse = 4 if t.size >= 256 else 1
    sse_coarse = (
        _projected_sse(block_mean(t, coarse), block_mean(x, coarse), block_mean(y, coarse),
                       dt * coarse)
        if coarse > 1 else sse_of_taus
    )

    max_lag = min(int(round(max_delay_s / dt)), t.size // 4)
    xcorr = _xcorr_lag(x, y, dt, max_lag)
    top = min(max_delay_s, xcorr + 0.1)
    step_d = max(dt, 0.02)
    delays = np.arange(0.0, top + 1e-12, step_d)
    taus = np.concatenate(([0.0], np.geomspace(dt / 2, max(2 * top, 4 * dt), 12)))
    grid = np.array([sse_coarse(float(d), taus) for d in delays])
    i, j = np.unravel_index(int(np.argmin(grid)), grid.shape)
    if coarse > 1:
        near_d = np.arange(max(i - 1, 0), min(i + 2, delays.size))
        near_tau = np.arange(max(j - 1, 0), min(j + 2, taus.size))
        fine = np.array([sse_of_taus(float(delays[a]), taus[near_tau]) for a in near_d])
        a, b = np.unravel_index(int(np.argmin(fine)), fine.shape)
        i, j, best = int(near_d[a]), int(near_tau[b]), float(fine[a, b])
    else:
        best = float(grid[i, j])
    delay, tau = float(delays[i]), float(taus[j])

    # refine on a 3 x 3 stencil: jump to the minimum of the quadratic through it
    # (within the stencil), else to its best point; shrink the stencil each round
    h_d = step_d / 2
    h_tau = max(float(taus[min(j + 1, taus.size - 1)] - taus[j]), dt) / 2
    offsets = np.array([-1.0, 0.0, 1.0])
    while h_d > 1e-4 or h_tau > 1e-4:
        d_pts = np.clip(delay + h_d * offsets, 0.0, max_delay_s)
        tau_pts = np.maximum(tau + h_tau * offsets, 0.0)
        values = np.array([sse_of_taus(float(d), tau_pts) for d in d_pts])
        dd, tt = np.meshgrid(d_pts - delay, tau_pts - tau, indexing="ij")
        design = np.column_stack(
            [np.ones(9), dd.ravel(), tt.ravel(), dd.ravel() ** 2, dd.ravel() * tt.ravel(),
             tt.ravel() ** 2]
        )
        c = np.linalg.lstsq(design, values.ravel(), rcond=None)[0]
        hessian = np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]])
        candidates = [(float(d_pts[a]), float(tau_pts[b])) for a, b in np.ndindex(3, 3)]
        scores = list(values.ravel())
        if np.all(np.linalg.eigvalsh(hessian) > 0):
            step = np.linalg.solve(hessian, -c[1:3])
            if abs(step[0]) <= h_d and abs(step[1]) <= h_tau:
                d_new = float(np.clip(delay + step[0], 0.0, max_delay_s))
                tau_new = max(tau + float(step[1]), 0.0)
                candidates.append((d_new, tau_new))
                scores.append(float(sse_of_taus(d_new, np.array([tau_new]))[0]))
        k_best = int(np.argmin(scores))
        if scores[k_best] < best:
            (delay, tau), best = candidates[k_best], float(scores[k_best])
        h_d, h_tau = h_d / 4, h_tau / 4
    r2 = 1.0 - best / sst if sst > 0 else float("nan")
    return DelayEstimate(delay_s=delay, lag_s=tau, r2=float(r2), xcorr_lag_s=xcorr)
