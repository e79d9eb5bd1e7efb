"""Change points: in the logged throttle (plateaus) and in the force (paper section 4).

The paper finds "significant change points" in the cleaned force automatically,
as MATLAB's ``findchangepts(x, 'Statistic', 'mean', 'MinThreshold', beta)`` does:
minimise the within-segment sum of squared deviations plus ``beta`` per change.
That is ruptures' ``l2`` cost with penalty ``beta``; its ``KernelCPD`` with a
linear kernel solves the same problem in C. To stay fast on long 1 kHz logs the
search runs on block means (about 20 Hz) and each change is then refined to the
sample on the full-rate signal, with the same least-squares criterion.

The force change points are cross-checked against the throttle steps that the
rig logged: every step should be followed, within the delay and a tolerance, by a
change in force; a change in force without a step (battery swap, loose fairing)
is reported.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tuflexperf.reduction.filters import block_mean, movmedian, robust_std, window_samples

THROTTLE_MOVE = 0.002
"""A throttle change larger than this (fraction) between samples starts a transition."""
PLATEAU_SPREAD = 0.02
"""A plateau whose throttle spans more than this (fraction) is a ramp, not a steady step."""


@dataclass(frozen=True)
class Plateau:
    """Samples ``[start, stop)`` at one throttle; ``step_index`` is where the command changed.

    ``step_index`` is ``None`` for the plateau the log starts in (no step seen).
    """

    start: int
    stop: int
    throttle: float
    step_index: int | None
    steady: bool


def throttle_plateaus(
    throttle: NDArray[np.float64],
    sample_rate_hz: float,
    min_duration_s: float = 0.5,
) -> list[Plateau]:
    """Split a run at its logged throttle steps.

    The throttle is first median-filtered over 20 ms (isolated logging glitches
    out, steps kept sharp). A sample is *moving* when the throttle differs from
    its value 0.1 s earlier by more than :data:`THROTTLE_MOVE` (or 5 robust
    standard deviations of those differences, if the log is noisy): comparing
    over 0.1 s rather than sample to sample also catches slow ramps. Moving
    stretches closer than 0.1 s merge into one transition; what lies between
    transitions is a plateau. Plateaus shorter than ``min_duration_s`` are
    dropped, and those whose throttle still drifts by more than
    :data:`PLATEAU_SPREAD` are kept but marked not ``steady``.
    """
    x = np.asarray(throttle, dtype=float)
    k = window_samples(0.02, sample_rate_hz)
    if k >= 3:
        x = movmedian(x, k | 1)
    lag = window_samples(0.1, sample_rate_hz)
    if x.size <= lag:
        lag = max(1, x.size // 4)
    moves = np.abs(x[lag:] - x[:-lag])
    tolerance = max(THROTTLE_MOVE, 5.0 * robust_std(moves))
    # moving[i]: the throttle changed between sample i - lag and i
    moving = np.concatenate((np.zeros(lag, dtype=bool), moves > tolerance))
    # a change at sample s makes samples s .. s + lag - 1 "moving"; its first sample is
    # where the command changed (the step), the plateau starts after the last one.
    index = np.flatnonzero(moving)
    transitions: list[tuple[int, int]] = []  # [first moving sample, first settled sample)
    if index.size:
        breaks = np.flatnonzero(np.diff(index) > lag) + 1
        for run in np.split(index, breaks):
            first, last = int(run[0]), int(run[-1])
            # the step is the first sample that differs from the level before it
            before = x[max(first - 1, 0)]
            span = x[first : last + 1]
            moved = np.flatnonzero(np.abs(span - before) > tolerance)
            step = first + int(moved[0]) if moved.size else first
            transitions.append((step, last + 1))
    bounds: list[tuple[int, int | None]] = [(0, None)]
    bounds += [(stop, start) for start, stop in transitions]
    ends = [start for start, _ in transitions] + [x.size]
    minimum = max(3, window_samples(min_duration_s, sample_rate_hz))
    plateaus: list[Plateau] = []
    for (begin, step), end in zip(bounds, ends, strict=True):
        if end - begin < minimum:
            continue
        segment = x[begin:end]
        plateaus.append(
            Plateau(
                start=begin,
                stop=end,
                throttle=float(np.median(np.asarray(throttle)[begin:end])),
                step_index=step,
                steady=bool(np.ptp(segment) <= PLATEAU_SPREAD),
            )
        )
    return plateaus


def _l2_split(csum: NDArray[np.float64], lo: int, hi: int) -> int:
    """Best single split ``s`` of ``[lo, hi)`` into two constant-mean pieces (least squares)."""
    s = np.arange(lo + 1, hi)
    n_left = (s - lo).astype(float)
    n_right = (hi - s).astype(float)
    sum_left = csum[s] - csum[lo]
    sum_right = csum[hi] - csum[s]
    # total SS is constant: minimising cost == maximising the explained part
    explained = sum_left**2 / n_left + sum_right**2 / n_right
    return int(s[np.argmax(explained)])


PELT_WINDOW_BLOCKS = 4000  # block means searched at once (200 s at 20 Hz; see kernel_breaks)
PELT_MARGIN_BLOCKS = 200  # each window's overlap with its neighbours (10 s at 20 Hz)


def kernel_breaks(coarse: NDArray[np.float64], min_size: int, penalty: float) -> list[int]:
    """Change points of ``coarse`` (PELT, ruptures' linear-kernel ``KernelCPD``): the index
    of the first block of each new segment, ascending.

    PELT prunes little where the mean never changes, so its time grows with the square of
    the length (a steady run of 10 million samples would take ten minutes). A run
    longer than :data:`PELT_WINDOW_BLOCKS` is searched in windows of that many blocks, each
    overlapping its neighbours by :data:`PELT_MARGIN_BLOCKS` and keeping the changes in its
    own core (a change is local: the penalty and the segments' least length are the whole
    run's); a change closer than ``min_size`` to the one before is dropped.
    """
    import ruptures

    def search(piece: NDArray[np.float64]) -> list[int]:
        detector = ruptures.KernelCPD(kernel="linear", min_size=min_size, jump=1)
        return [int(b) for b in detector.fit(piece.reshape(-1, 1)).predict(pen=penalty)[:-1]]

    n = coarse.size
    if n <= PELT_WINDOW_BLOCKS:
        return search(coarse)
    margin = max(PELT_MARGIN_BLOCKS, 4 * min_size)
    core = max(PELT_WINDOW_BLOCKS - 2 * margin, 2 * min_size)
    breaks: list[int] = []
    for start in range(0, n, core):
        lo, hi = max(start - margin, 0), min(start + core + margin, n)
        if hi - lo < 2 * min_size:
            continue
        for b in search(coarse[lo:hi]):
            if start <= lo + b < start + core and (not breaks or lo + b - breaks[-1] >= min_size):
                breaks.append(lo + b)
    return breaks


def force_changepoints(
    force: NDArray[np.float64],
    sample_rate_hz: float,
    block_s: float = 0.05,
    min_segment_s: float = 0.5,
    penalty_factor: float = 10.0,
    min_shift_n: float = 0.3,
) -> list[int]:
    """Sample indices where the mean of a (cleaned) force signal changes.

    Parameters
    ----------
    force : ndarray
        Force in N, already outlier-filled and smoothed (paper section 4).
    sample_rate_hz : float
        Log rate in Hz.
    block_s : float
        Decimation block in s for the coarse search (about 20 Hz).
    min_segment_s : float
        Shortest segment in s.
    penalty_factor : float
        Penalty per change in units of ``sigma^2 log(n)`` (``sigma`` the block-mean
        noise, from the median absolute deviation of lagged differences):
        ``findchangepts``' ``MinThreshold``, made independent of the noise level.
    min_shift_n : float
        Smallest change of mean in N worth a change point: the penalty is at least
        the cost reduction such a shift between two minimum-length segments gives
        (the rig's accuracy goal is +-0.5 N, paper section 2.1; slow vibration
        beats and battery sag must not split a steady step).

    Returns
    -------
    list of int
        Index of the first sample of each new segment, ascending.
    """
    y = np.asarray(force, dtype=float)
    block = max(1, window_samples(block_s, sample_rate_hz))
    coarse = block_mean(y, block)
    min_size = max(2, int(round(min_segment_s / (block / sample_rate_hz))))
    if coarse.size < 2 * min_size:
        return []
    # Noise of the block means from differences at a lag of one minimum segment: lag-1
    # differences would miss the noise's correlation (the smoothing spans several
    # blocks); the few differences that straddle a real change are outvoted by the MAD.
    lag = min(min_size, coarse.size - 1)
    sigma = robust_std(coarse[lag:] - coarse[:-lag]) / np.sqrt(2.0)
    sigma = max(sigma, 1e-6 * max(1.0, float(np.max(np.abs(coarse)))))
    penalty = max(
        penalty_factor * sigma**2 * np.log(coarse.size),
        0.5 * min_size * min_shift_n**2,  # two segments of min_size, means min_shift apart
    )
    breaks = kernel_breaks(coarse, min_size, penalty)
    if not breaks:
        return []
    # refine at full rate: best split between the neighbouring coarse change points
    csum = np.concatenate(([0.0], np.cumsum(y - y.mean())))
    edges = [0, *[b * block for b in breaks], y.size]
    refined = []
    for i, b in enumerate(breaks, start=1):
        lo = max(edges[i - 1], (b - min_size // 2) * block, (edges[i - 1] + edges[i]) // 2)
        hi = min(edges[i + 1], (b + min_size // 2) * block, (edges[i] + edges[i + 1]) // 2)
        refined.append(_l2_split(csum, lo, hi) if hi - lo >= 2 else b * block)
    return refined


@dataclass(frozen=True)
class CrossCheck:
    """Force change points sorted against the logged throttle steps.

    ``matched`` maps each throttle step (sample) to the first force change after
    it; further changes inside the same step's transient are ``in_transient``;
    force changes away from every step are ``changes_without_step`` (worth a look:
    a battery swap, a loose fairing, a drifting balance).
    """

    matched: dict[int, int]
    in_transient: list[int]
    steps_without_change: list[int]
    changes_without_step: list[int]


def cross_check(
    steps: Sequence[int],
    changes: Sequence[int],
    before: int,
    after: Sequence[int] | int,
    expected_lag: int = 0,
) -> CrossCheck:
    """Sort force changes into those explained by a throttle step and those that are not.

    A change belongs to step ``s`` when it lies in ``[s - before, s + after]`` (samples;
    ``after`` may differ per step: delay plus that step's settling time). The step's
    match is the change nearest ``s + expected_lag`` (the delay); a smooth transient
    can give a mean-shift detector more than one change, the others are
    ``in_transient``.
    """
    steps = sorted(steps)
    afters = [after] * len(steps) if isinstance(after, int) else list(after)
    matched: dict[int, int] = {}
    in_transient: list[int] = []
    missing: list[int] = []
    explained: set[int] = set()
    for step, tail in zip(steps, afters, strict=True):
        inside = [c for c in changes if step - before <= c <= step + tail]
        if inside:
            best = min(inside, key=lambda c: abs(c - step - expected_lag))
            matched[step] = best
            in_transient.extend(c for c in inside if c != best and c not in explained)
            explained.update(inside)
        else:
            missing.append(step)
    unexplained = [c for c in sorted(changes) if c not in explained]
    return CrossCheck(matched, sorted(set(in_transient)), missing, unexplained)
