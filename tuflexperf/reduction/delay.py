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

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tuflexperf.models.thrust import MAX_DELAY_S
from tuflexperf.reduction.filters import block_mean, movmedian, window_samples

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
    """Block means [unit of ``u``] of the lag ``tau dy/dt = u - y`` driven by block means ``u``.

    Each block of ``dt`` [s] holds its input; within it ``y`` relaxes from its value at the
    block's start towards ``u``, so its mean is ``u + (y_start - u) (tau/dt) (1 - a)`` with
    ``a = exp(-dt/tau)``, and its end ``a y_start + (1 - a) u`` starts the next block. The
    recursion's end value alone (``first_order_lag``) runs half a block ahead of the block
    means it is compared with, and the dead time would take up that half block (+2.5 ms at
    200 Hz). Starts at rest at ``u[0]``.
    """
    if tau <= 0:
        return u
    from scipy.signal import lfilter

    a = float(np.exp(-dt / tau))
    c = tau / dt * (1.0 - a)
    # mean = (1 - c) u[n] + c end[n - 1], end[n] = a end[n - 1] + (1 - a) u[n]: one filter
    # (1 - c + (c (1 - a) - a (1 - c)) z^-1) / (1 - a z^-1), at rest at u[0] (gain 1)
    b0, b1 = 1.0 - c, c * (1.0 - a) - a * (1.0 - c)
    return lfilter([b0, b1], [1.0, -a], u, axis=-1, zi=(b1 + a) * u[..., :1])[0]


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
) -> Callable[[float | NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]:
    """``(delay, taus) -> residual sum of squares per tau`` of the variable-projection fit
    on one sampling ``t`` [s] of throttle ``x`` [-] and force ``y`` [N] (step ``dt`` [s]).

    ``delay`` [s] may be an array of dead times: the result is then one row per dead time,
    each equal to the bit to a call with that dead time alone (the dead times share one lag
    filter call and one batch of normal equations per lag: the refinement's stencil).
    """
    # constant and trend columns do not depend on (d, tau): project them out once
    _, basis, _, y_free, yy = _without_trend(y)

    def sse_of_taus(
        delay: float | NDArray[np.float64], taus: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        delays = np.atleast_1d(np.asarray(delay, dtype=float))
        inputs = [np.interp(t - d, t, x) for d in delays]
        both = np.stack([column for u in inputs for column in (u, u * u)])
        rows = np.empty((6, t.size))
        rows[3:5], rows[5] = basis.T, y_free
        grams = np.empty((delays.size, taus.size, 3, 3))
        rhs = np.empty((delays.size, taus.size, 3))
        for m, tau in enumerate(taus):
            lagged = _lag_filter(both, float(tau), dt)  # row by row: L[u], L[u^2] per delay
            for a in range(delays.size):
                rows[0], rows[2] = lagged[2 * a], lagged[2 * a + 1]
                np.multiply(rows[0], rows[0], out=rows[1])
                # one product gives every dot product of the fan columns L[u], L[u]^2,
                # L[u^2] with each other, the constant/trend basis and the data
                dots = np.einsum("an,bn->ab", rows[:3], rows)  # no BLAS: its threads
                cross = dots[:, 3:5]
                grams[a, m] = dots[:, :3] - cross @ cross.T  # basis projected out
                rhs[a, m] = dots[:, 5]  # y_free is orthogonal to the basis already
        # 3 x 3 normal equations, rank-deficient at tau = 0 (where L[u^2] = L[u]^2): the
        # least-squares residual is ||y||^2 - b' G^+ b
        sse = yy - _explained(grams.reshape(-1, 3, 3), rhs.reshape(-1, 3))
        return sse.reshape(delays.size, taus.size) if np.ndim(delay) else sse

    return sse_of_taus


Array = NDArray[np.float64]


def _without_trend(y: Array) -> tuple[Array, Array, Array, Array, float]:
    """The fit's constant and trend columns projected out of the force ``y`` [N].

    Returns the trend ``tn`` (0 .. 1, linear in the sample), the orthonormal ``basis`` of
    ``[1, tn]`` with ``r`` (``[1, tn] = basis r``), ``y_free`` (``y`` less its projection on
    the basis) and ``yy = y_free . y_free`` [N^2].
    """
    tn = np.linspace(0.0, 1.0, y.size) if y.size > 1 else np.zeros(y.size)
    basis, r = np.linalg.qr(np.column_stack([np.ones_like(tn), tn]))
    y_free = y - basis @ (basis.T @ y)
    return tn, basis, r, y_free, float(y_free @ y_free)


def _shifted_grid_sse(
    t: NDArray[np.float64], x: NDArray[np.float64], y: NDArray[np.float64], dt: float,
    taus: NDArray[np.float64], shifts: int,
) -> NDArray[np.float64]:
    """Residual sum of squares of the variable-projection fit for every lag in ``taus`` [s]
    and every dead time of ``k`` whole samples, ``k = 0 .. shifts``: shape
    ``(taus.size, shifts + 1)``, equal to :func:`_projected_sse` at those dead times.

    A whole-sample dead time shifts the lagged columns (the lag is time-invariant and starts
    at rest on the first throttle, as the shifted throttle does), so every dot product of the
    fit is one of the unshifted columns: products of columns with themselves are prefix sums,
    their products with the trend and the data one matrix product over all shifts. The grid
    costs two lag filters per lag instead of two per (dead time, lag).
    """
    from numpy.lib.stride_tricks import sliding_window_view

    n = t.size
    tn, _, r, y_free, yy = _without_trend(y)
    step = tn[1] - tn[0] if n > 1 else 0.0
    to_basis = np.linalg.inv(r)  # [1, tn] @ to_basis = basis
    k = np.arange(shifts + 1)
    # row k: y_free from sample k on, zero-padded to n (its products with a column shifted
    # by k samples); the trend's are prefix sums, the trend being linear in the sample
    y_windows = np.ascontiguousarray(
        sliding_window_view(np.concatenate([y_free, np.zeros(shifts)]), n)[: shifts + 1])
    # before the shift a column holds its first value: those k samples' share
    head_t, head_y = (np.concatenate([[0.0], np.cumsum(z[:shifts])]) for z in (tn, y_free))
    pairs = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
    out = np.empty((taus.size, shifts + 1))
    for j, tau in enumerate(taus):
        lagged, lagged_square = _lag_filter(np.stack([x, x * x]), float(tau), dt)
        cols = np.stack([lagged, lagged * lagged, lagged_square])  # L[u], L[u]^2, L[u^2]
        first = cols[:, 0]
        # sums over the first n - k samples: the whole sum less the last k samples'
        end = cols[:, n - shifts:][:, ::-1]
        gram = np.empty((shifts + 1, 3, 3))
        for a, b in pairs:
            dropped = np.concatenate([[0.0], np.cumsum(end[a] * end[b])])
            whole = float(np.einsum("n,n->", cols[a], cols[b]))  # no BLAS: its threads
            gram[:, a, b] = gram[:, b, a] = k * first[a] * first[b] + whole - dropped
        dropped = np.concatenate([np.zeros((3, 1)), np.cumsum(end, axis=1)], axis=1).T
        kept = cols.sum(axis=1) - dropped  # sum over the first n - k samples
        with_one = k[:, None] * first + kept
        # sum_m col[m] tn[m + k] = sum_m col[m] tn[m] + k step sum_m col[m]
        weighted = np.einsum("cn,n->c", cols, tn)
        dropped_t = np.concatenate([np.zeros((3, 1)),
                                    np.cumsum(end * tn[n - shifts:][::-1], axis=1)], axis=1).T
        with_t = (head_t[:, None] * first + weighted - dropped_t
                  + (k * step)[:, None] * kept)
        with_y = np.einsum("kn,cn->kc", y_windows, cols) + head_y[:, None] * first
        cross = np.einsum("kcb,bq->kcq", np.stack([with_one, with_t], axis=-1), to_basis)
        grams = gram - np.einsum("kaq,kbq->kab", cross, cross)
        out[j] = yy - _explained(grams, with_y)
    return out


def _explained(grams: NDArray[np.float64], rhs: NDArray[np.float64]) -> NDArray[np.float64]:
    """``b' G^+ b`` per row of 3 x 3 normal equations (columns scaled to unit norm; the
    pseudo-inverse drops singular values below 1e-12 of the largest, as lstsq does)."""
    scale = np.sqrt(np.maximum(np.einsum("mii->mi", grams), 0.0))
    scale[scale == 0.0] = 1.0
    grams = grams / (scale[:, :, None] * scale[:, None, :])
    rhs = rhs / scale
    coef = np.einsum("mij,mj->mi", np.linalg.pinv(grams, rcond=1e-12), rhs)
    return np.einsum("mi,mi->m", coef, rhs)


MIN_FIT_SAMPLES = 16
"""Block means a sweep must give for a fit (the grid needs them)."""
TRUST = 4.0
"""The stencil's quadratic model is trusted this many stencil widths away."""
MAX_REFINEMENTS = 60
"""Stencil rounds at most (a round either moves the stencil or shrinks it fourfold)."""



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
    fan columns solved by a 3 x 3 least squares); ``(d, tau)`` is found on a grid of
    every whole-sample dead time against 13 lags (:func:`_shifted_grid_sse`, two lag
    filters per lag) and refined by a 3 x 3 stencil that jumps to its quadratic's minimum,
    travels along the valley ``d + tau ~ const`` and shrinks where its centre stays best,
    to 0.1 ms; no general-purpose optimiser runs. Against a rig simulated at 20 kHz both
    come out within 3 ms (tests/verification/test_reduction_delay_drag.py).

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
    if t.size < MIN_FIT_SAMPLES:  # too short to say anything: the caller leaves it out
        return DelayEstimate(delay_s=0.0, lag_s=0.0, r2=float("nan"), xcorr_lag_s=0.0)
    sse_of_taus = _projected_sse(t, x, y, dt)

    max_lag = min(int(round(max_delay_s / dt)), t.size // 4)
    xcorr = _xcorr_lag(x, y, dt, max_lag)
    top = min(max_delay_s, xcorr + 0.1)
    # every whole-sample dead time up to ``top`` against 13 lags: a coarser grid (20 ms on
    # 20 ms block means) picks the wrong side of the valley d + tau = const, where a pure
    # 50 ms delay comes out as 41 ms + a 12 ms lag
    shifts = min(int(math.floor(top / dt + 1e-9)), t.size // 4)
    delays = np.arange(shifts + 1) * dt
    taus = np.concatenate(([0.0], np.geomspace(dt / 4, max(2 * top, 4 * dt), 12)))
    grid = _shifted_grid_sse(t, x, y, dt, taus, shifts).T  # (delay, tau)
    i, j = np.unravel_index(int(np.argmin(grid)), grid.shape)
    best = float(grid[i, j])
    delay, tau = float(delays[i]), float(taus[j])

    # refine on a 3 x 3 stencil: try the minimum of the quadratic through it (trusted up to
    # TRUST stencil widths) and its points, move to the best; the stencil shrinks only where its
    # centre stays best, so it can travel along the narrow valley d + tau ~ const (shrinking
    # every round stopped it a lag grid step from the optimum: 0.048 + 0.085 s for the
    # shipped campaign's 0.050 + 0.080 s)
    h_d = dt / 2
    h_tau = max(float(taus[min(j + 1, taus.size - 1)] - taus[j]), dt) / 2
    offsets = np.array([-1.0, 0.0, 1.0])
    for _ in range(MAX_REFINEMENTS):
        if h_d <= 1e-4 and h_tau <= 1e-4:
            break
        d_pts = np.clip(delay + h_d * offsets, 0.0, max_delay_s)
        tau_pts = np.maximum(tau + h_tau * offsets, 0.0)
        values = sse_of_taus(d_pts, tau_pts)  # (delay, tau)
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
            # along the valley the quadratic's minimum may lie beyond the stencil: trust it
            # up to TRUST stencil widths
            step = step / max(1.0, abs(step[0]) / (TRUST * h_d), abs(step[1]) / (TRUST * h_tau))
            d_new = float(np.clip(delay + step[0], 0.0, max_delay_s))
            tau_new = max(tau + float(step[1]), 0.0)
            candidates.append((d_new, tau_new))
            scores.append(float(sse_of_taus(d_new, np.array([tau_new]))[0]))
        k_best = int(np.argmin(scores))
        if scores[k_best] < best * (1.0 - 1e-12):
            moved = abs(candidates[k_best][0] - delay), abs(candidates[k_best][1] - tau)
            (delay, tau), best = candidates[k_best], float(scores[k_best])
            if k_best == 9:  # the quadratic's minimum: the optimum is near, close in
                if max(moved) <= 1e-4:  # a step under the tolerance: converged
                    break
                h_d, h_tau = h_d / 2, h_tau / 2
        else:
            h_d, h_tau = h_d / 4, h_tau / 4
    r2 = 1.0 - best / sst if sst > 0 else float("nan")
    return DelayEstimate(delay_s=delay, lag_s=tau, r2=float(r2), xcorr_lag_s=xcorr)


@dataclass(frozen=True)
class SweepAmplitude:
    """First-harmonic force amplitude of a sine sweep per frequency band, measured and per
    model, and each model's error against the measurement."""

    frequency_hz: NDArray[np.float64]  # band centres [Hz]
    measured_n: NDArray[np.float64]  # measured amplitude per band [N]
    model_n: NDArray[np.float64]  # (model, band) amplitude [N]

    @property
    def error(self) -> NDArray[np.float64]:
        """(model, band) amplitude error ``model / measured - 1`` [-]."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.model_n / self.measured_n - 1.0


AMPLITUDE_BANDS_HZ = (0.5, 1.0, 2.0, 3.0, 4.0, 5.0)
"""Frequencies the amplitude is reported at: a sweep's cycles nearest each (paper: to 5 Hz)."""


def sweep_amplitudes(
    time_s: NDArray[np.float64],
    throttle: NDArray[np.float64],
    forces_n: NDArray[np.float64],
    bands_hz: tuple[float, ...] = AMPLITUDE_BANDS_HZ,
) -> SweepAmplitude:
    """First-harmonic amplitude of each force over each cycle of a sine sweep, by band.

    A cycle runs from one upward crossing of the throttle's mid value to the next; its
    frequency is one over its length. Over each cycle the force's first harmonic at that
    frequency is projected out (``2 |mean(F e^(-i w t))|``): noise and the fan's rpm^2
    harmonic do not enter it, as they would a peak-to-peak. The cycles nearest each band
    centre (within 15 %) are averaged; a band the sweep does not reach is NaN.

    Parameters
    ----------
    time_s : ndarray
        Sample times [s].
    throttle : ndarray
        Throttle command [fraction].
    forces_n : ndarray
        (signals, samples) forces [N]: the measured force first, then each model's.
    bands_hz : tuple of float
        Band centres [Hz].

    Returns
    -------
    SweepAmplitude
        ``measured_n`` from the first row of ``forces_n``, ``model_n`` from the others.
    """
    t = np.asarray(time_s, dtype=float)
    x = np.asarray(throttle, dtype=float)
    f = np.atleast_2d(np.asarray(forces_n, dtype=float))
    moving = np.flatnonzero(np.abs(x - x[-1]) > 0.01)
    bands = np.asarray(bands_hz, dtype=float)
    empty = np.full(bands.size, np.nan)
    if moving.size < 4:
        return SweepAmplitude(bands, empty, np.tile(empty, (f.shape[0] - 1, 1)))
    mid = 0.5 * (np.max(x[moving]) + np.min(x[moving]))
    up = np.flatnonzero((x[:-1] < mid) & (x[1:] >= mid)) + 1
    up = up[(up >= moving[0]) & (up <= moving[-1])]
    if up.size < 2:
        return SweepAmplitude(bands, empty, np.tile(empty, (f.shape[0] - 1, 1)))
    starts, stops = up[:-1], up[1:]
    period = t[stops] - t[starts]
    # each sample's phase in its cycle; samples outside every cycle are dropped
    cycle = np.searchsorted(up, np.arange(t.size), side="right") - 1
    inside = (cycle >= 0) & (cycle < starts.size)
    idx = np.flatnonzero(inside)
    c = cycle[idx]
    phase = 2.0 * np.pi * (t[idx] - t[starts[c]]) / period[c]
    counts = np.bincount(c, minlength=starts.size).astype(float)
    re = np.stack([np.bincount(c, weights=row[idx] * np.cos(phase), minlength=starts.size)
                   for row in f])
    im = np.stack([np.bincount(c, weights=row[idx] * np.sin(phase), minlength=starts.size)
                   for row in f])
    amplitude = 2.0 * np.hypot(re, im) / np.maximum(counts, 1.0)  # (signals, cycles)
    freq = 1.0 / period
    # each cycle to its nearest band, if within 15 % of the band's frequency
    nearest = np.argmin(np.abs(freq[:, None] - bands[None, :]), axis=1)
    ok = np.abs(freq - bands[nearest]) <= 0.15 * bands[nearest]
    sums = np.stack([np.bincount(nearest[ok], weights=a[ok], minlength=bands.size)
                     for a in amplitude])
    n = np.bincount(nearest[ok], minlength=bands.size).astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = np.where(n > 0, sums / n, np.nan)
    return SweepAmplitude(bands, mean[0], mean[1:])
