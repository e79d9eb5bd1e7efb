"""Backend-neutral helpers: one physics code path for floats, numpy arrays and CasADi symbols.

The physics in :mod:`tuflexperf.models` is written once against these functions and runs
on Python floats, numpy arrays (vectorised batches) and CasADi ``SX``/``MX`` (the problems
the analyses build), as AeroSandbox's ``aerosandbox.numpy`` does. CasADi is never imported
here unless a symbol is actually passed in.

Type aliases
------------
``Vectorizable``
    What the physics accepts and returns: a float, a numpy array or a CasADi symbol.
``Array``
    A concrete numpy array of floats (results, grids): never symbolic.

:func:`interp_rows` alone is numpy only: the batches' row-wise interpolation.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TypeAlias, Union

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    import casadi

    Symbolic: TypeAlias = casadi.SX | casadi.MX | casadi.DM
else:
    Symbolic = object  # casadi stays optional at run time

Array: TypeAlias = NDArray[np.float64]
Vectorizable: TypeAlias = Union[float, Array, "Symbolic"]


def is_symbolic(*values: object) -> bool:
    """True if any value is a CasADi SX/MX/DM (no CasADi loaded: nothing can be symbolic)."""
    ca = sys.modules.get("casadi")
    if ca is None:
        return False
    kinds = (ca.SX, ca.MX, ca.DM)
    # a plain loop: the batches call this millions of times, a generator costs 3x
    for value in values:
        if isinstance(value, kinds):
            return True
    return False


def where(condition: Vectorizable, if_true: Vectorizable, if_false: Vectorizable) -> Vectorizable:
    """Element-wise ``condition ? if_true : if_false`` for numpy or CasADi operands."""
    if is_symbolic(condition, if_true, if_false):
        import casadi as ca

        return ca.if_else(condition, if_true, if_false)
    return np.where(condition, if_true, if_false)


def fmin(a: Vectorizable, b: Vectorizable) -> Vectorizable:
    """Element-wise minimum for numpy or CasADi operands."""
    if is_symbolic(a, b):
        import casadi as ca

        return ca.fmin(a, b)
    return np.minimum(a, b)


def fmax(a: Vectorizable, b: Vectorizable) -> Vectorizable:
    """Element-wise maximum for numpy or CasADi operands."""
    if is_symbolic(a, b):
        import casadi as ca

        return ca.fmax(a, b)
    return np.maximum(a, b)


def sqrt(a: Vectorizable) -> Vectorizable:
    """Square root for numpy or CasADi operands."""
    if is_symbolic(a):
        import casadi as ca

        return ca.sqrt(a)
    return np.sqrt(a)


def exp(a: Vectorizable) -> Vectorizable:
    """Exponential for numpy or CasADi operands."""
    if is_symbolic(a):
        import casadi as ca

        return ca.exp(a)
    return np.exp(a)


def interp_rows(t: Array, t_hist: Array, v_hist: Array) -> Array:
    """``np.interp(t[i, j], t_hist[i], v_hist[i])`` for every row ``i`` and column ``j``.

    numpy only (no CasADi). One ``np.searchsorted`` over all rows at once: each row's
    history (finite, non-decreasing: one row that is not spoils the others) and queries are
    shifted by the row's index times a span longer than any history, so the rows follow one
    another in one sorted array (seven vectorised halvings of a binary search per query took
    as long as the rest of the launch).
    """
    rows, width = t_hist.shape
    # a non-decreasing row's least and greatest are its ends (a pass over two columns, not
    # over every history)
    low_t = min(float(t_hist[:, 0].min()), float(t.min()))
    high_t = max(float(t_hist[:, -1].max()), float(t.max()))
    offset = (np.arange(rows, dtype=float) * (high_t - low_t + 1.0))[:, None]
    flat = (t_hist + offset).ravel()
    at = np.searchsorted(flat, (t + offset).ravel(), side="right").reshape(t.shape) - 1
    at = np.clip(at - width * np.arange(rows)[:, None], 0, width - 2) \
        + width * np.arange(rows)[:, None]
    flat_t, flat_v = t_hist.ravel(), v_hist.ravel()
    t0, t1 = np.take(flat_t, at), np.take(flat_t, at + 1)
    v0, v1 = np.take(flat_v, at), np.take(flat_v, at + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        value = v0 + (t - t0) * (v1 - v0) / (t1 - t0)
    return np.where(t >= t_hist[:, -1:], v_hist[:, -1:], value)
