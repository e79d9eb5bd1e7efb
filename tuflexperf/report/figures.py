"""The report's figures, one function each, drawn from :mod:`tuflexperf.report.data`.

The requirement table is drawn here; the measurement's pages live in
:mod:`.measured_figures`, the flight analyses' in :mod:`.flight_figures`, the page frame
(A4 canvas, notes, legends, text pages) in :mod:`.canvas`: this module names them all.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot (the Agg
canvas renders it headless). Axes carry SI units, requirement limits are drawn where one
applies, the thrust model's extrapolated airspeeds are shaded, one meaning has one look
(:mod:`tuflexperf.report.style`), legends sit outside the axes, and long time series are
drawn through :func:`tuflexperf.report.decimate.envelope`.
"""

from __future__ import annotations

from typing import Any

from tuflexperf.io.case import Case
from tuflexperf.report.canvas import (
    LIMIT_COLOUR,
    new_figure,
    page_margins,
    preload,
    text_page,
    use_agg,
)
from tuflexperf.report.data import Analyses, dynamic_thrust_n, model_force_n
from tuflexperf.report.flight_figures import (
    endurance,
    takeoff_history,
    thrust_required_available,
    trim_oei_throttle,
)
from tuflexperf.report.measured_figures import (
    model_vs_measured,
    run_processing,
    sine_sweep,
    thrust_surface,
)
from tuflexperf.report.style import FAIL_FILL, PASS_FILL, UNPROVEN_FILL, legend_outside, unit

# the report's pages by name: the page frame (canvas), the measurement's, the flight's
__all__ = [
    "dynamic_thrust_n", "endurance", "legend_outside", "model_force_n", "model_vs_measured",
    "new_figure", "preload", "requirement_table", "run_processing", "sine_sweep",
    "takeoff_history", "text_page", "thrust_required_available", "thrust_surface",
    "trim_oei_throttle", "use_agg",
]

# characters per line of the requirements page's text (monospace, 9 pt, landscape A4)
_REQUIREMENT_TEXT_COLUMNS = 128


# --- 2. requirement table -----------------------------------------------------------------------
def requirement_table(case: Case, analyses: Analyses) -> Any:
    """The verdicts of ``check``: value, limit, margin, PASS/FAIL, colour-coded."""
    fig = new_figure()
    page_margins(fig)
    ax = fig.add_subplot()
    ax.axis("off")
    verdicts = analyses.verdicts
    passed = all(v.passed for v in verdicts)
    unproven = not passed and all(v.verdict != "FAIL" for v in verdicts)
    fig.suptitle(
        f"Requirements of {case.name}: "
        + ("none stated" if not verdicts else "all met" if passed else
           "NOT all shown met (UNPROVEN)" if unproven else "NOT all met"),
        fontsize=14,
        color="black" if passed else LIMIT_COLOUR,
    )

    def fmt(value: float | None) -> str:
        return "not attainable" if value is None else f"{value:.3f}"

    rows = [
        [
            v.name,
            fmt(v.value),
            f"{v.limit:g}",
            unit(v.unit),
            fmt(v.margin),
            "max" if v.kind == "max" else "min",
            v.verdict,
        ]
        for v in verdicts
    ]
    if rows:
        table = ax.table(
            cellText=rows,
            colLabels=["requirement", "value", "limit", "unit", "margin", "limit is", "verdict"],
            colWidths=[0.22, 0.15, 0.1, 0.1, 0.15, 0.1, 0.1],  # the names are the longest
            cellLoc="center",
            loc="upper center",
            bbox=[0.0, 0.55, 1.0, 0.4],
        )
        table.auto_set_font_size(False)
        table.set_fontsize(11)
        for (r, _c), cell in table.get_celld().items():
            if r == 0:
                cell.set_facecolor("0.85")
                cell.set_text_props(weight="bold")
            else:
                word = verdicts[r - 1].verdict
                cell.set_facecolor(PASS_FILL if word == "PASS" else FAIL_FILL
                                   if word == "FAIL" else UNPROVEN_FILL)
    lines = [
        "Margin: positive when met (limit - value for a maximum, value - limit for a minimum)."
    ]
    for v in verdicts:
        lines.append(f"{v.name}: {v.reason}")
        lines.extend(f"    note: {w}" for w in v.details.get("warnings", []))
    import textwrap

    # monospace at 9 pt: the page holds ~130 characters; matplotlib's own wrap cut at the
    # figure's edge, past the table's right side
    wrapped = [textwrap.fill(line, width=_REQUIREMENT_TEXT_COLUMNS,
                             subsequent_indent=" " * (len(line) - len(line.lstrip()) + 4))
               for line in lines]
    ax.text(
        0.0,
        0.5,
        "\n".join(wrapped),
        transform=ax.transAxes,
        va="top",
        ha="left",
        fontsize=9,
        family="monospace",
    )
    return fig


