"""Carpet plot of a sweep: each requirement's value over the grid with its limit line.

Draws a :class:`tuflexperf.analysis.sweep.SweepResult`; computes nothing of its own. Two
varied parameters: filled contours of the value, the limit as a thick black contour and the
not-met side hatched; one parameter: the value against it with the limit as a dashed line.

References
----------
Raymer, *Aircraft Design*, 19.5 (carpet plots).
"""

from __future__ import annotations

import io
import math
from typing import Any

import numpy as np

# a parameter key's unit from its suffix (SPEC 4 names every numeric key with its unit)
_SUFFIX_UNITS = (("_m_s", "m/s"), ("_kg_m3", "kg/m\u00b3"), ("_m2", "m\u00b2"), ("_kg", "kg"),
                 ("_min", "min"), ("_m", "m"), ("_k", "K"), ("_s", "s"), ("_v", "V"),
                 ("_n", "N"), ("_w", "W"), ("_a", "A"), ("_fraction", "fraction"))


def axis_label(key: str) -> str:
    """``aircraft.mass_kg`` -> ``aircraft.mass_kg (kg)``; ``(-)`` for a key without a unit."""
    leaf = key.rsplit(".", 1)[-1]
    unit = next((u for suffix, u in _SUFFIX_UNITS if leaf.endswith(suffix)), "-")
    return f"{key} ({unit})"


def carpet_png(result: Any, title: str) -> bytes:
    """PNG bytes (150 dpi) of the sweep's carpet plot, one panel per requirement."""
    import warnings

    # axes over values near the float limit (a cd0 swept to 1e308) overflow in matplotlib's
    # tick arithmetic: a warning on stderr for a figure it still draws (outside audit)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return _carpet_png(result, title)


def _carpet_png(result: Any, title: str) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(result.values)
    columns = min(2, len(names))
    rows = math.ceil(len(names) / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(6.0 * columns, 4.4 * rows), squeeze=False)
    keys = result.parameters
    for ax, name in zip(axes.ravel(), names, strict=False):
        value = result.values[name]
        limit = float(result.limits[name][0])
        unit = result.units.get(name, "")
        if len(keys) == 1:
            ax.plot(result.points[:, 0], value, "o-", ms=3, label=name)
            ax.axhline(limit, color="k", ls="--", lw=1.5, label=f"limit {limit:g} {unit}")
            bad = ~result.met[name]
            if bad.any():
                ax.plot(result.points[bad, 0], np.where(np.isfinite(value[bad]), value[bad],
                                                        limit), "x", color="C3",
                        label="not met / not attainable")
            ax.set_xlabel(axis_label(keys[0]))
            ax.set_ylabel(f"{name} ({unit})")
            ax.legend(fontsize=8)
        else:
            x_axis, y_axis = result.axes[0], result.axes[1]
            shape = (x_axis.size, y_axis.size, -1)
            grid = value.reshape(shape)[:, :, 0].T  # first varied axis on x
            met = result.met[name].reshape(shape)[:, :, 0].T
            filled = ax.contourf(x_axis, y_axis, np.ma.masked_invalid(grid), levels=14,
                                 cmap="viridis")
            fig.colorbar(filled, ax=ax, label=f"{name} ({unit})")
            if np.nanmin(grid) < limit < np.nanmax(grid):
                line = ax.contour(x_axis, y_axis, grid, levels=[limit], colors="k",
                                  linewidths=2.0)
                ax.clabel(line, fmt=f"limit {limit:g}", fontsize=8)
            ax.contourf(x_axis, y_axis, (~met).astype(float), levels=[0.5, 1.5],
                        colors="none", hatches=["//"])
            ax.set_xlabel(axis_label(keys[0]))
            ax.set_ylabel(axis_label(keys[1]))
        more = f"\nat the first value of {', '.join(keys[2:])}" if len(keys) > 2 else ""
        ax.set_title(f"{name} (hatched/x: not met){more}", fontsize=10)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    buffer = io.BytesIO()
    from tuflexperf.io.files import SWEEP_PNG_SOFTWARE

    # 'Software: tuflexperf sweep' marks the PNG as a sweep's: a later sweep may replace it
    # (SPEC 5), nothing else
    fig.savefig(buffer, format="png", dpi=150, metadata={"Software": SWEEP_PNG_SOFTWARE})
    plt.close(fig)
    return buffer.getvalue()
