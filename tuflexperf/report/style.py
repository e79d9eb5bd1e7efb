"""One colour and line style per meaning, across every page of the report (issue 15).

A figure asks for a meaning (``STYLE["limit"]``), never for a colour: the same red
dashed line is a requirement limit on every page, and nothing else is drawn that way.
Each entry is a dict of matplotlib line keywords, so ``ax.plot(x, y, **STYLE["trim"])``
and ``ax.axhline(y, **STYLE["limit"])`` both work.
"""

from __future__ import annotations

from typing import Any

# Colours: matplotlib's tab10, chosen so that no two meanings on one page share one.
BLUE, ORANGE, GREEN, RED, PURPLE = "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd"
BROWN, PINK, GREY, OLIVE, CYAN = "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"

STYLE: dict[str, dict[str, Any]] = {
    # requirements and boundaries
    "limit": {"color": "#c62828", "linestyle": "--", "linewidth": 1.4},  # a requirement's limit
    "envelope": {"color": GREY, "linestyle": (0, (6, 3)), "linewidth": 1.1},  # envelope edges
    "stall": {"color": "black", "linestyle": ":", "linewidth": 1.3},  # stall speed
    "full_throttle": {"color": "0.35", "linestyle": "-.", "linewidth": 1.0},
    # analyses
    "required": {"color": "black", "linestyle": "-", "linewidth": 2.4},  # drag / power required
    "trim": {"color": BLUE, "linestyle": "-", "linewidth": 2.0},  # all engines
    "oei": {"color": ORANGE, "linestyle": "-", "linewidth": 2.0},  # one engine inoperative
    "oei_other": {"color": ORANGE, "linestyle": "--", "linewidth": 1.2},  # the milder OEI case
    "takeoff": {"color": BLUE, "linestyle": "-", "linewidth": 2.0},
    "mission": {"color": BLUE, "linestyle": "-", "linewidth": 1.8},
    # measurements and models of them
    "measured": {"color": BLUE, "linestyle": "-", "linewidth": 1.0},
    "measured_raw": {"color": "0.72", "linestyle": "-", "linewidth": 0.5},
    "model": {"color": PURPLE, "linestyle": "-", "linewidth": 1.4},  # a fitted model's prediction
    "command": {"color": "black", "linestyle": "-", "linewidth": 0.9},  # throttle command
    "error": {"color": BROWN, "linestyle": "-", "linewidth": 0.8},  # model minus measured
    "goal": {"color": GREEN, "linestyle": "--", "linewidth": 1.1},  # accuracy goal (+-0.5 N)
    "segment": {"color": PINK, "linestyle": "-", "linewidth": 3.0},  # a steady segment's mean
    "changepoint": {"color": OLIVE, "linestyle": ":", "linewidth": 0.9},  # detected change
    "airborne": {"color": CYAN, "linestyle": "--", "linewidth": 1.6},  # after lift-off
}

POINT: dict[str, dict[str, Any]] = {
    "verdict": {"color": "#c62828", "marker": "s", "markersize": 7, "linestyle": "none"},
    "best": {"color": GREEN, "marker": "D", "markersize": 8, "linestyle": "none"},
    "least": {"color": "black", "marker": "o", "markersize": 6, "linestyle": "none"},
    "not_attainable": {"color": "#c62828", "marker": "x", "markersize": 6, "linestyle": "none"},
}

# report --compare: one colour per configuration, the first in the report's blue
CONFIG_COLOURS = (BLUE, GREEN, BROWN, PINK)

EXTRAPOLATED_FILL = "0.90"  # airspeeds beyond the tested range
PASS_FILL, FAIL_FILL = "#c8e6c9", "#ffcdd2"
UNITS = {"kg/m^3": "kg/m\u00b3", "m/s^2": "m/s\u00b2", "m^2": "m\u00b2"}


def unit(text: str) -> str:
    """``kg/m^3`` -> ``kg/m³``: units typeset with superscripts, never a caret."""
    for plain, typeset in UNITS.items():
        text = text.replace(plain, typeset)
    return text


def legend_outside(ax: Any, **kwargs: Any) -> Any:
    """A legend right of the axes, so it can never cover data."""
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                     fontsize="small", **kwargs)
