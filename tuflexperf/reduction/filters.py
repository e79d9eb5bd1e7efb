"""Moving-window filters with MATLAB semantics, windows given in seconds.

The paper (section 4) cleans every run in two steps: outliers beyond 1.5 local
standard deviations of a 2 s moving mean are replaced by the window's centre
value (MATLAB ``filloutliers(x, 'center', 'movmean', window, 'ThresholdFactor',
1.5)``), then the signal is smoothed by a moving median (``movmedian``).

Window conventions follow MATLAB's ``movmean``/``movstd``/``movmedian``
documentation: a window of ``k`` samples is centred on the current sample when
``k`` is odd; when ``k`` is even it spans ``k/2`` samples before and ``k/2 - 1``
after. At the ends the window shrinks to the samples that exist
(``'Endpoints', 'shrink'``). Every function is O(n) or O(n log k), never O(n k).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def window_samples(window_s: float, sample_rate_hz: float) -> int:
    """Number of samples in a window of ``window_s`` seconds at ``sample_rate_hz`` (at least 1).

    The paper's 2 s window at its 1 kHz log is 2000 samples (section 4).
    """
    if not window_s > 0 or not sample_rate_hz > 0:
        raise ValueError("window and sample rate must be positive")
    return max(1, int(round(window_s * sample_rate_hz)))


def _bounds(n: int, k: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Start (inclusive) and stop (exclusive) index of each sample's shrinking window."""
    before = k // 2
    after = k - 1 - before
    index = np.arange(n)
    return np.maximum(index - before, 0), np.minimum(index + after + 1, n)


def movmean(x: ArrayLike, k: int) -> Array:
    """Moving mean over ``k`` samples with shrinking end windows (MATLAB ``movmean(x, k)``)."""
    return _moving_mean_std(x, k)[0]


def movstd(x: ArrayLike, k: int) -> Array:
    """Moving sample standard deviation (N - 1 normalisation; MATLAB ``movstd(x, k)``).

    A one-sample window has a standard deviation of 0, as in MATLAB.
    """
    return _moving_mean_std(x, k)[1]


def _moving_mean_std(x: ArrayLike, k: int) -> tuple[Array, Array]:
    """:func:`movmean` and :func:`movstd` from one pair of cumulative sums (equal to both)."""
    values = np.asarray(x, dtype=float)
    if values.size == 0:
        return values.copy(), values.copy()
    offset = float(np.mean(values))  # centring keeps the cumulative sums well conditioned
    centred = values - offset
    c1 = np.zeros(values.size + 1)
    np.cumsum(centred, out=c1[1:])
    c2 = np.zeros(values.size + 1)
    np.cumsum(centred * centred, out=c2[1:])
    lo, hi = _bounds(values.size, k)
    count = (hi - lo).astype(float)
    s1 = c1[hi] - c1[lo]
    s2 = c2[hi] - c2[lo]
    mean = s1 / count + offset
    with np.errstate(invalid="ignore", divide="ignore"):
        variance = (s2 - s1 * s1 / count) / (count - 1.0)
    variance = np.where(count > 1, np.maximum(variance, 0.0), 0.0)
    return mean, np.sqrt(variance)


def movmedian(x: ArrayLike, k: int) -> Array:
    """Moving median over ``k`` samples with shrinking end windows (MATLAB ``movmedian(x, k)``).

    The interior uses an O(n log k) running median: SciPy's rank filter for an odd
    window; for an even one, whose median averages the two middle values as MATLAB's
    ``median`` does, Bottleneck's double-heap median, which gives that average in one
    pass where the rank filter needs one per middle value (~1.7x faster, equal to the
    bit). The few end samples whose window is cut short are computed directly.
    """
    from scipy.ndimage import rank_filter

    values = np.asarray(x, dtype=float)
    n = values.size
    if n == 0 or k <= 1:
        return values.copy()
    k = min(k, 2 * n + 1)  # a longer window shrinks to the whole signal everywhere
    before = k // 2
    after = k - 1 - before
    out = np.empty(n)
    if n > k:
        finite = bool(np.isfinite(values).all())
        if k % 2:
            out[:] = rank_filter(values, rank=k // 2, size=k, mode="nearest")
        elif finite:  # Bottleneck skips NaN where the rank filter keeps it: finite only
            import bottleneck

            # its window ends at the sample; the centred one ends ``after`` samples later
            out[before : n - after] = bottleneck.move_median(values, k)[k - 1 :]
        else:
            # scipy's window for an even size spans size//2 before and size//2 - 1 after,
            # the same as MATLAB's: no origin shift is needed.
            upper = rank_filter(values, rank=k // 2, size=k, mode="nearest")
            lower = rank_filter(values, rank=k // 2 - 1, size=k, mode="nearest")
            out[:] = 0.5 * (lower + upper)
        if finite:
            # the cut-short end windows, all at once (one sorted row per end sample)
            out[:before] = _growing_window_medians(values[: before + after], after + 1)
            if after:
                tail = _growing_window_medians(values[::-1][: after + before], before + 1)
                out[n - after :] = tail[::-1]
            return out
        edges = np.r_[0 : min(before, n), max(n - after, 0) : n]
    elif np.isfinite(values).all():
        # a window longer than the signal: each one is a prefix, a suffix or the whole
        # signal (one median per sample takes 53 s for a run logged in microseconds)
        return _clipped_window_medians(values, before, after)
    else:
        edges = np.arange(n)
    for i in edges:
        out[i] = np.median(values[max(i - before, 0) : min(i + after + 1, n)])
    return out


def movmedians(pieces: Sequence[ArrayLike], k: int) -> list[Array]:
    """:func:`movmedian` of each of ``pieces`` (equal to the bit), the common case at once.

    Pieces that take :func:`movmedian`'s Bottleneck path (an even window, finite values,
    longer than the window) share one running median over their concatenation, whose
    windows within a piece hold that piece's samples alone, and one sort for the cut-short
    windows at all their ends; any other piece is filtered on its own. One steady stretch
    after another cost more in calls than in medians (168 stretches of ~3000 samples).

    Parameters
    ----------
    pieces : sequence of array_like
        The signals [any unit], filtered independently.
    k : int
        Window [samples].

    Returns
    -------
    list of ndarray
        One filtered signal per piece, same unit.
    """
    arrays = [np.asarray(x, dtype=float) for x in pieces]
    together = [
        i for i, x in enumerate(arrays)
        if k > 1 and k % 2 == 0 and x.size > k and bool(np.isfinite(x).all())
    ]
    batched = set(together)
    out: list[Array] = [
        np.empty(0) if i in batched else movmedian(x, k) for i, x in enumerate(arrays)
    ]
    if not together:
        return out
    import bottleneck

    before = k // 2
    after = k - 1 - before
    chosen = [arrays[i] for i in together]
    running = bottleneck.move_median(np.concatenate(chosen), k)
    heads = _growing_window_medians_rows(np.stack([x[: before + after] for x in chosen]),
                                         after + 1)
    tails = _growing_window_medians_rows(
        np.stack([x[::-1][: after + before] for x in chosen]), before + 1)
    offset = 0
    for row, (i, x) in enumerate(zip(together, chosen, strict=True)):
        n = x.size
        filtered = np.empty(n)
        filtered[:before] = heads[row]
        # a window ends at its sample in Bottleneck's output: the centred one ``after`` later
        filtered[before : n - after] = running[offset + k - 1 : offset + n]
        filtered[n - after :] = tails[row][::-1]
        out[i] = filtered
        offset += n
    return out


def _growing_window_medians_rows(heads: Array, first: int) -> Array:
    """:func:`_growing_window_medians` of each row of ``heads`` (one sort for all rows
    while the padded cells stay under ``_SORTED_ROWS_MAX``)."""
    rows, width = heads.shape
    counts = np.arange(first, width + 1)
    if rows * counts.size * width > _SORTED_ROWS_MAX:
        return np.stack([_growing_window_medians(head, first) for head in heads])
    cells = np.where(np.arange(width) < counts[:, None], heads[:, None, :], np.inf)
    cells.sort(axis=-1)
    at = np.arange(counts.size)
    return 0.5 * (cells[:, at, (counts - 1) // 2] + cells[:, at, counts // 2])


def _clipped_window_medians(values: Array, before: int, after: int) -> Array:
    """``median(values[max(i - before, 0) : min(i + after + 1, n)])`` for every ``i`` when
    the window is at least as long as the signal (finite values), in O(n log n)."""
    n = values.size
    out = np.full(n, float(np.median(values)))  # the windows that hold every sample
    prefix = np.arange(n)[np.arange(n) + after + 1 < n]  # end cut short: [0, i + after + 1)
    if prefix.size:
        out[prefix] = _growing_window_medians(values, after + 1)[: prefix.size]
    suffix = np.arange(n)[np.arange(n) - before > 0]  # start cut short: [i - before, n)
    if suffix.size:
        tail = _growing_window_medians(values[::-1], n - suffix[-1] + before)
        out[suffix] = tail[: suffix.size][::-1]
    return out


_SORTED_ROWS_MAX = 1 << 22  # cells of the padded matrix below (32 MiB of float64)


def _growing_window_medians(head: Array, first: int) -> Array:
    """Medians of ``head[:first]``, ``head[:first + 1]``, ... up to the whole of ``head``.

    Each row holds one window, padded with +inf past its end; after sorting, the
    median is the mean of the row's two middle values (equal for an odd count). Where
    that matrix would be large (a window of thousands of samples), two heaps instead
    (a max-heap of the lower half, a min-heap of the upper): O(n log n), O(n) memory.
    """
    width = head.size
    counts = np.arange(first, width + 1)
    if counts.size * width > _SORTED_ROWS_MAX:
        return _growing_window_medians_by_heaps(head, first)
    rows = np.where(np.arange(width) < counts[:, None], head, np.inf)
    rows.sort(axis=1)
    at = np.arange(counts.size)
    return 0.5 * (rows[at, (counts - 1) // 2] + rows[at, counts // 2])


def _growing_window_medians_by_heaps(head: Array, first: int) -> Array:
    """:func:`_growing_window_medians` by two heaps (see there)."""
    import heapq

    lower: list[float] = []  # negated
    upper: list[float] = []
    medians = []
    for count, value in enumerate(head.tolist(), start=1):
        if lower and value > -lower[0]:
            heapq.heappush(upper, value)
        else:
            heapq.heappush(lower, -value)
        if len(lower) > len(upper) + 1:
            heapq.heappush(upper, -heapq.heappop(lower))
        elif len(upper) > len(lower):
            heapq.heappush(lower, -heapq.heappop(upper))
        if count >= first:
            medians.append(-lower[0] if count % 2 else 0.5 * (upper[0] - lower[0]))
    return np.asarray(medians, dtype=float)


def filloutliers_movmean(x: ArrayLike, k: int, threshold: float = 3.0) -> tuple[Array, int]:
    """Replace moving-mean outliers by the window's centre value (the local mean).

    MATLAB ``filloutliers(x, 'center', 'movmean', k, 'ThresholdFactor', threshold)``: a
    sample is an outlier when it lies more than ``threshold`` local standard deviations
    from the local mean (strictly), both :func:`movmean` and :func:`movstd` over the same
    window (which includes the sample itself). The paper uses a 2 s window and
    ``threshold = 1.5`` (section 4).

    Returns
    -------
    filled : ndarray
        Copy of ``x`` with the outliers replaced.
    n_replaced : int
        How many samples were replaced.
    """
    values = np.asarray(x, dtype=float)
    centre, spread = _moving_mean_std(values, k)
    outlier = np.abs(values - centre) > threshold * spread
    filled = np.where(outlier, centre, values)
    return filled, int(np.count_nonzero(outlier))


def block_mean(x: ArrayLike, block: int) -> Array:
    """Means of consecutive blocks of ``block`` samples (the last, partial block dropped).

    Decimation by block averaging: used to run change-point detection and
    delay estimation on far fewer samples than the raw log.
    """
    values = np.asarray(x, dtype=float)
    if block <= 1:
        return values.copy()
    m = values.size // block
    return values[: m * block].reshape(m, block).mean(axis=1)


def robust_std(x: ArrayLike) -> float:
    """Standard deviation estimated from the median absolute deviation (1.4826 MAD)."""
    values = np.asarray(x, dtype=float)
    if values.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


def first_order_lag(u: ArrayLike, pole: float) -> Array:
    """Discrete first-order lag ``y[n] = pole y[n-1] + (1 - pole) u[n]`` along the last axis.

    Each row starts at rest at its first value (``y[-1] = u[0]``). With
    ``pole = exp(-dt / tau)`` it is the exact response of ``tau dy/dt = u - y`` to a
    sample-and-hold input (the exports' recursion). SciPy's ``lfilter`` runs the
    recursion in C (its module is imported by the change-point search anyway).

    Parameters
    ----------
    u : array_like
        Input [any unit], one signal per row.
    pole : float
        ``exp(-dt / tau)`` in [0, 1) [-].

    Returns
    -------
    ndarray
        The lagged signal, same shape and unit as ``u``.
    """
    from scipy.signal import lfilter

    values = np.asarray(u, dtype=float)
    if pole <= 0.0:
        return values.copy()
    return lfilter([1.0 - pole], [1.0, -pole], values, axis=-1, zi=pole * values[..., :1])[0]
