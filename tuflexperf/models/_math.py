"""Backend-neutral helpers: one physics code path for floats, numpy arrays and CasADi symbols."""

from __future__ import annotations

from typing import Any

import numpy as np


def is_symbolic(*values: Any) -> bool:
    """True if any value is a CasADi SX/MX/DM (checked by type name, so casadi stays optional)."""
    return any(type(v).__name__ in ("SX", "MX", "DM") for v in values)


def where(condition: Any, if_true: Any, if_false: Any) -> Any:
    """Element-wise ``condition ? if_true : if_false`` for numpy or CasADi operands."""
    if is_symbolic(condition, if_true, if_false):
        import casadi as ca

        return ca.if_else(condition, if_true, if_false)
    return np.where(condition, if_true, if_false)


def fmin(a: Any, b: Any) -> Any:
    """Element-wise minimum for numpy or CasADi operands."""
    if is_symbolic(a, b):
        import casadi as ca

        return ca.fmin(a, b)
    return np.minimum(a, b)


def fmax(a: Any, b: Any) -> Any:
    """Element-wise maximum for numpy or CasADi operands."""
    if is_symbolic(a, b):
        import casadi as ca

        return ca.fmax(a, b)
    return np.maximum(a, b)


def sqrt(a: Any) -> Any:
    """Square root for numpy or CasADi operands."""
    if is_symbolic(a):
        import casadi as ca

        return ca.sqrt(a)
    return np.sqrt(a)


def exp(a: Any) -> Any:
    """Exponential for numpy or CasADi operands."""
    if is_symbolic(a):
        import casadi as ca

        return ca.exp(a)
    return np.exp(a)
