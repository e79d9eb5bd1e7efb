"""Min-max envelope decimation of long time series for drawing (issue 9: report speed).

A 144 k-sample sweep drawn into a 1,600-pixel-wide axes puts about 90 samples on
each pixel column; Agg still strokes every segment. Keeping, per column, the first,
smallest, largest and last sample draws the same pixels (the line's vertical extent
in each column and its joins to the neighbours) from at most four points a column.
Plain subsampling would not: it drops the spikes the run-processing page exists to show.
"""

from __future__ import annotations

import numpy as np

COLUMNS = 2000  # wider than any axes of the report at 150 dpi (A4 landscape: 1,754 px)


def envelope_indices(length: int, values: np.ndarray, columns: int = COLUMNS) -> np.ndarray:
    """Sorted indices of the first, minimum, maximum and last sample of each column.

    Parameters
    ----------
    length : int
        Number of samples [-].
    values : numpy.ndarray
        The samples, shape (length,) [any unit]; NaN is kept where it is the first or last
        sample of a column (a gap stays a gap).
    columns : int
        Number of equal-count columns [-].

    Returns
    -------
    numpy.ndarray
        Indices into ``values``, ascending, at most ``4 * columns`` of them; all indices
        when ``length <= 4 * columns``.
    """
    if length <= 4 * columns:
        return np.arange(length)
    per = length // columns
    body = columns * per
    blocks = np.asarray(values[:body], dtype=float).reshape(columns, per)
    starts = np.arange(columns) * per
    filled = np.where(np.isnan(blocks), np.inf, blocks)
    low = starts + np.argmin(filled, axis=1)
    high = starts + np.argmax(np.where(np.isnan(blocks), -np.inf, blocks), axis=1)
    first, last = starts, starts + per - 1
    tail = np.arange(body, length)
    return np.unique(np.concatenate([first, low, high, last, tail]))


def envelope(time: np.ndarray, *series: np.ndarray, columns: int = COLUMNS
             ) -> tuple[np.ndarray, ...]:
    """``time`` and each series decimated on the union of their envelope indices.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s], shape (n,).
    *series : numpy.ndarray
        Series to draw against ``time``, each shape (n,).
    columns : int
        Number of columns [-].

    Returns
    -------
    tuple of numpy.ndarray
        ``(time, *series)`` at the kept indices.
    """
    n = len(time)
    if n <= 4 * columns:
        return (np.asarray(time), *(np.asarray(s) for s in series))
    keep = np.unique(np.concatenate([envelope_indices(n, np.asarray(s), columns)
                                     for s in series])) if series else np.arange(n)
    return (np.asarray(time)[keep], *(np.asarray(s)[keep] for s in series))
