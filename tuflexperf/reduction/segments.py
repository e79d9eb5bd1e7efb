"""Steady segments of a throttle-step run and their mean force (paper section 4).

After each throttle step the force first waits for the rig's dead time, then
moves towards its new level as the fan spools (a first-order-like transient).
Only the part after the transient may enter the thrust table. How long that
takes is measured, not assumed: the transients of all steps of a run are fitted
together as ``F(t) = L_k + A_k exp(-(t - s_k) / tau)`` (one time constant per
run, one level and amplitude per step, ``s_k`` the step time plus the delay),
and step ``k`` is taken as settled once ``|A_k| exp(-t / tau)`` has fallen below
:data:`SETTLED_N`.

Within the steady part the paper's filters run again on the raw samples of that
part alone (outliers against a 2 s moving mean, then the moving median), so no
window straddles a step: a 2 s window across a 10 % step would pull the samples
near the step towards the neighbouring level.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tuflexperf.reduction.filters import (
    block_mean,
    filloutliers_movmean,
    movmedians,
    window_samples,
)

SETTLED_N = 0.01
"""Transient amplitude (N) below which a step counts as settled."""
MIN_STEADY_SHARE = 0.3
"""At least this share of a plateau (after the delay) is kept, however slow the transient."""


@dataclass(frozen=True)
class TransientFit:
    """The run's spool time constant and each step's fitted amplitude and settling time."""

    tau_s: float
    amplitude_n: NDArray[np.float64]
    settle_s: NDArray[np.float64]


def _segment_sse(
    y: NDArray[np.float64], e: NDArray[np.float64], starts: NDArray[np.intp]
) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Least squares of ``y ~ L + A e`` separately in each segment (closed-form 2x2).

    Returns total SSE, and the per-segment ``L`` and ``A``. ``e`` may carry leading
    axes (one regressor per row, e.g. a grid of time constants); the SSE then is one
    total per row.
    """
    n, sy, syy = (np.add.reduceat(v, starts) for v in (np.ones_like(y), y, y * y))
    se, see, sye = (np.add.reduceat(v, starts, axis=-1) for v in (e, e * e, y * e))
    det = n * see - se * se
    ok = det > 1e-12 * np.maximum(n * see, 1e-300)
    with np.errstate(invalid="ignore", divide="ignore"):
        level = np.where(ok, (see * sy - se * sye) / det, sy / n)
        amplitude = np.where(ok, (n * sye - se * sy) / det, 0.0)
    sse = np.sum(np.maximum(syy - level * sy - amplitude * sye, 0.0), axis=-1)
    return sse, level, amplitude  # type: ignore[return-value]


GRID_BLOCK_VALUES = 1 << 16
"""Regressor values per block of the time-constant grid (:func:`_grid_sse`)."""


def _grid_sse(
    t: NDArray[np.float64], y: NDArray[np.float64], taus: NDArray[np.float64],
    starts: NDArray[np.intp],
) -> NDArray[np.float64]:
    """Total SSE of :func:`_segment_sse` for the regressor ``exp(-t / tau)``, per ``tau``.

    Equal to the bit to ``_segment_sse(y, np.exp(-t / taus[:, None]), starts)[0]``, computed
    a few time constants at a time: the whole grid at once (40 rows of the run's block means,
    a few MB per temporary) spent most of its time faulting in fresh pages.

    Parameters
    ----------
    t : ndarray
        Time since each segment's onset [s].
    y : ndarray
        Force [N], one value per ``t``.
    taus : ndarray
        Time constants [s].
    starts : ndarray of int
        First index of each segment in ``t`` and ``y``.

    Returns
    -------
    ndarray
        SSE [N^2], one per time constant.
    """
    rows = max(1, GRID_BLOCK_VALUES // max(t.size, 1))
    neg = -t
    sse = np.empty(taus.size)
    for first in range(0, taus.size, rows):
        block = taus[first : first + rows, None]
        sse[first : first + rows] = _segment_sse(y, np.exp(neg / block), starts)[0]
    return sse


def fit_transients(
    time_s: NDArray[np.float64],
    force_n: NDArray[np.float64],
    onsets: Sequence[int],
    stops: Sequence[int],
    sample_rate_hz: float,
) -> TransientFit:
    """Fit one first-order time constant to every step of a run (see the module docstring).

    Parameters
    ----------
    time_s, force_n : ndarray
        The run (force median-smoothed against spikes), in s and N.
    onsets, stops : sequence of int
        Per step, the first sample after the step plus delay, and the plateau's end.
    sample_rate_hz : float
        Log rate in Hz; the fit runs on block means of about 5 ms.

    Returns
    -------
    TransientFit
        ``tau_s`` (0 when no transient is seen), per-step amplitude and settling time in s.
    """
    from scipy.optimize import minimize_scalar

    block = max(1, window_samples(0.005, sample_rate_hz))
    pieces_t, pieces_y, starts = [], [], []
    count = 0
    for onset, stop in zip(onsets, stops, strict=True):
        tb = block_mean(time_s[onset:stop], block)
        yb = block_mean(force_n[onset:stop], block)
        if tb.size < 4:
            tb, yb = time_s[onset:stop], force_n[onset:stop]
        starts.append(count)
        pieces_t.append(tb - time_s[onset])
        pieces_y.append(yb)
        count += tb.size
    n_steps = len(starts)
    if n_steps == 0 or count < 4 * n_steps:
        return TransientFit(0.0, np.zeros(n_steps), np.zeros(n_steps))
    t = np.concatenate(pieces_t)
    y = np.concatenate(pieces_y)
    index = np.asarray(starts, dtype=np.intp)
    durations = np.array([p[-1] for p in pieces_t if p.size])
    tau_min = max(2.0 / sample_rate_hz, 1e-3)
    tau_max = max(0.25 * float(np.median(durations)), 2 * tau_min)

    def objective(log_tau: float) -> float:
        return float(_segment_sse(y, np.exp(-t / np.exp(log_tau)), index)[0])

    grid = np.linspace(np.log(tau_min), np.log(tau_max), 40)
    values = _grid_sse(t, y, np.exp(grid), index)
    best = int(np.argmin(values))
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    result = minimize_scalar(objective, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    tau = float(np.exp(result.x)) if result.fun <= values[best] else float(np.exp(grid[best]))
    _, _, amplitude = _segment_sse(y, np.exp(-t / tau), index)
    magnitude = np.abs(amplitude)
    ratio = np.maximum(magnitude, SETTLED_N) / SETTLED_N
    settle = tau * np.log(ratio)  # time for |A| exp(-t/tau) to fall to SETTLED_N
    return TransientFit(tau, amplitude, settle)


@dataclass(frozen=True)
class SteadyMean:
    """One steady segment: its throttle, mean airspeed and mean force (filtered)."""

    throttle: float
    airspeed_m_s: float
    force_n: float
    force_std_n: float
    n_samples: int
    start: int
    stop: int
    outliers_replaced: int
    filtered_force_n: NDArray[np.float64]


def steady_means(
    force_n: NDArray[np.float64],
    airspeed_m_s: NDArray[np.float64],
    throttle: NDArray[np.float64],
    spans: Sequence[tuple[int, int]],
    outlier_window: int,
    outlier_threshold: float,
    median_window: int,
) -> list[SteadyMean]:
    """Mean force over each ``(start, stop)`` in ``spans`` (a run's steady stretches) after
    the paper's two filters.

    Each stretch is filtered on its own (shrinking windows at its ends), so a mean never sees
    a neighbouring step; the moving medians of all of them run together
    (:func:`~tuflexperf.reduction.filters.movmedians`, equal to the bit to one call per
    stretch). Airspeed is averaged as logged; the throttle is the median of the command.

    Parameters
    ----------
    force_n, airspeed_m_s, throttle : ndarray
        The run: force [N], airspeed [m/s], throttle [fraction].
    spans : sequence of (int, int)
        Sample ranges ``[start, stop)``.
    outlier_window, median_window : int
        The two filters' windows [samples].
    outlier_threshold : float
        Outlier threshold in local standard deviations [-].

    Returns
    -------
    list of SteadyMean
        One per span, in order.
    """
    fills = [
        filloutliers_movmean(force_n[start:stop], outlier_window, outlier_threshold)
        for start, stop in spans
    ]
    smooths = movmedians([filled for filled, _ in fills], median_window)
    return [
        SteadyMean(
            throttle=float(np.median(throttle[start:stop])),
            airspeed_m_s=float(np.mean(airspeed_m_s[start:stop])),
            force_n=float(np.mean(smooth)),
            force_std_n=float(np.std(filled, ddof=1)) if smooth.size > 1 else 0.0,
            n_samples=int(stop - start),
            start=start,
            stop=stop,
            outliers_replaced=replaced,
            filtered_force_n=smooth,
        )
        for (start, stop), (filled, replaced), smooth in zip(spans, fills, smooths, strict=True)
    ]


THROTTLE_MATCH = 0.005
"""Steady segments of one run whose throttles differ by less than this are one test point."""


@dataclass(frozen=True)
class TestPoint:
    """One cell of the paper's thrust matrix: a run's steady segments at one throttle."""

    throttle: float
    airspeed_m_s: float
    force_n: float
    force_std_n: float
    n_samples: int
    members: tuple[int, ...]


def merge_test_points(segments: Sequence[SteadyMean]) -> list[TestPoint]:
    """Combine a run's segments at the same throttle (e.g. idle before and after the steps).

    The paper transfers each run's segment means into a thrust *matrix*, one value
    per throttle and airspeed (section 4); a throttle visited twice in a run is one
    cell, its value the sample-weighted mean, so no condition weighs double in the fit.
    """
    cells: list[list[int]] = []
    for i, segment in enumerate(segments):
        for cell in cells:
            if abs(segments[cell[0]].throttle - segment.throttle) < THROTTLE_MATCH:
                cell.append(i)
                break
        else:
            cells.append([i])
    points = []
    for cell in cells:
        members = [segments[i] for i in cell]
        weights = np.array([m.n_samples for m in members], dtype=float)
        force = np.array([m.force_n for m in members])
        mean_force = float(np.average(force, weights=weights))
        spread = np.array([m.force_std_n for m in members])
        # pooled standard deviation, including the spread between the segments' means
        pooled = np.average(spread**2 + (force - mean_force) ** 2, weights=weights)
        points.append(
            TestPoint(
                throttle=float(np.average([m.throttle for m in members], weights=weights)),
                airspeed_m_s=float(np.average([m.airspeed_m_s for m in members], weights=weights)),
                force_n=mean_force,
                force_std_n=float(np.sqrt(pooled)),
                n_samples=int(weights.sum()),
                members=tuple(cell),
            )
        )
    return points
