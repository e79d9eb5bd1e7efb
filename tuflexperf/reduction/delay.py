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

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

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
    """Discrete first-order lag ``tau dy/dt = u - y`` (exact for a sample-and-hold input)."""
    from scipy.signal import lfilter

    if tau <= 0:
        return u
    a = np.exp(-dt / tau)
    return lfilter([1.0 - a], [1.0, -a], u, zi=[a * u[0]])[0]


def _xcorr_lag(x: NDArray[np.float64], y: NDArray[np.float64], dt: float, max_lag: int) -> float:
    """Lag (s) of the cross-correlation peak of ``y`` behind ``x`` in ``[0, max_lag]`` samples."""
    from scipy.signal import correlate

    xc = x - x.mean()
    yc = y - y.mean()
    corr = correlate(yc, xc, mode="full", method="fft")
    zero = xc.size - 1
    window = corr[zero : zero + max_lag + 1]
    return float(np.argmax(window)) * dt


def estimate_delay(
    time_s: NDArray[np.float64],
    throttle: NDArray[np.float64],
    force_n: NDArray[np.float64],
    sample_rate_hz: float,
    max_delay_s: float = 1.0,
) -> DelayEstimate:
    """Fit dead time and spool lag of one sine-sweep run (see the module docstring).

    Parameters
    ----------
    time_s, throttle, force_n : ndarray
        The run: time in s, throttle fraction, force in N.
    sample_rate_hz : float
        Log rate in Hz.
    max_delay_s : float
        Largest dead time (and lag) searched, in s.

    Returns
    -------
    DelayEstimate
    """
    from scipy.optimize import minimize

    k = window_samples(0.02, sample_rate_hz) | 1  # 20 ms median: spikes out, no phase shift
    force = movmedian(force_n, k) if k >= 3 else np.asarray(force_n, dtype=float)
    block = max(1, int(round(sample_rate_hz / FIT_RATE_HZ)))
    t = block_mean(time_s, block)
    x = block_mean(throttle, block)
    y = block_mean(force, block)
    dt = block / sample_rate_hz
    tn = (t - t[0]) / max(t[-1] - t[0], dt)
    sst = float(np.sum((y - y.mean()) ** 2))

    def sse(delay: float, tau: float) -> float:
        u = np.interp(t - delay, t, x)
        lu = _lag_filter(u, tau, dt)
        lu2 = _lag_filter(u * u, tau, dt)
        design = np.column_stack([np.ones_like(t), tn, lu, lu * lu, lu2])
        coef, *_ = np.linalg.lstsq(design, y, rcond=None)
        residual = y - design @ coef
        return float(residual @ residual)

    max_lag = min(int(round(max_delay_s / dt)), t.size // 4)
    xcorr = _xcorr_lag(x, y, dt, max_lag)
    top = min(max_delay_s, xcorr + 0.1)
    delays = np.arange(0.0, top + 1e-12, max(dt, 0.005))
    taus = np.concatenate(([0.0], np.geomspace(dt / 2, max(2 * top, 4 * dt), 12)))
    grid = np.array([[sse(d, tau) for tau in taus] for d in delays])
    i, j = np.unravel_index(int(np.argmin(grid)), grid.shape)

    def objective(p: NDArray[np.float64]) -> float:
        d = float(np.clip(p[0], 0.0, max_delay_s))
        return sse(d, abs(float(p[1])))

    step_d = max(dt, 0.005)
    step_tau = max(taus[min(j + 1, taus.size - 1)] - taus[j], dt)
    result = minimize(
        objective,
        x0=np.array([delays[i], taus[j]]),
        method="Nelder-Mead",
        options={
            "initial_simplex": np.array(
                [
                    [delays[i], taus[j]],
                    [delays[i] + step_d, taus[j]],
                    [delays[i], taus[j] + step_tau],
                ]
            ),
            "xatol": 1e-4,
            "fatol": 1e-9 * max(sst, 1.0),
            "maxiter": 200,
        },
    )
    if result.fun <= grid[i, j]:
        delay, tau, best = float(np.clip(result.x[0], 0, max_delay_s)), abs(result.x[1]), result.fun
    else:
        delay, tau, best = float(delays[i]), float(taus[j]), float(grid[i, j])
    r2 = 1.0 - best / sst if sst > 0 else float("nan")
    return DelayEstimate(delay_s=delay, lag_s=float(tau), r2=float(r2), xcorr_lag_s=xcorr)
