"""The report's page frame: A4 landscape figures without pyplot, and the helpers every page uses.

Figures are built on the Agg canvas (no global figure state); the colours, legends outside
the axes, notes and wrapped text are drawn the same way on every page
(:mod:`tuflexperf.report.style` holds the meanings).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tuflexperf.report.style import STYLE

LANDSCAPE_IN = (11.69, 8.27)  # A4 landscape (297 x 210 mm)

TEXT_PAGE_MARGIN_IN = 0.6  # about 15 mm: a printer's unprintable edge plus room to staple


LIMIT_COLOUR = STYLE["limit"]["color"]

ACCURACY_GOAL_N = 0.5  # paper section 1 and 2.1: model accuracy aimed for +-0.5 N

LEGEND_FONT = 8

AVAILABLE_COLOUR = "#5ec962"  # available thrust at full throttle (viridis' green, as on Fig. 18)


def use_agg() -> None:
    """Select the headless Agg backend before anything imports pyplot."""
    import matplotlib

    matplotlib.use("Agg")


def preload() -> None:
    """Import the drawing stack and load its fonts once, before the report forks its
    writers: each forked copy then inherits them instead of paying ~0.4 s of its own."""
    from io import BytesIO

    import pypdfium2  # noqa: F401 - rasterises the pages (report.build)
    from matplotlib.backends import backend_pdf  # noqa: F401
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401 - the thrust surfaces

    fig = new_figure((2.0, 1.0))
    ax = fig.add_subplot()
    ax.text(0.5, 0.5, "tuflexperf 0-9", weight="bold")
    ax.set_title("preload", fontsize=9)
    fig.savefig(BytesIO(), format="pdf")


def new_figure(size: tuple[float, float] = LANDSCAPE_IN) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def page_margins(fig: Any) -> None:
    """Margins of a printed page for text and table pages (an axes without decorations
    would otherwise reach the paper's edge)."""
    fig.get_layout_engine().set(w_pad=TEXT_PAGE_MARGIN_IN, h_pad=TEXT_PAGE_MARGIN_IN / 2)


def style_of(meaning: str, **override: Any) -> dict[str, Any]:
    """``STYLE[meaning]`` with a few keys changed (a second curve of the same meaning)."""
    return {**STYLE[meaning], **override}


def note_box(ax: Any, text: str) -> None:
    ax.text(
        0.5,
        0.5,
        text,
        transform=ax.transAxes,
        ha="center",
        va="center",
        wrap=True,
        fontsize=11,
        color="0.3",
    )
    ax.set_xticks([])
    ax.set_yticks([])


def wrap_text(text: str, width: int) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width))


def label_line_ends(ax: Any, ends: list[tuple[float, str, Any]], fontsize: float = 8.0) -> None:
    """Label lines in the margin right of the axes, spread so no two labels touch.

    ``ends`` holds (y at the right edge [data], text, colour). A label outside the axes
    can never sit on another curve (the "40 %" on the trim line of issue 15); a short
    leader joins it to its line's end when it had to move.
    """
    low, high = ax.get_ylim()
    fig = ax.get_figure()
    # the axes' height before the layout is solved: the figure's, less titles and ticks
    height_pt = 0.8 * fig.get_size_inches()[1] * 72.0 * ax.get_position().height
    gap = 1.25 * fontsize / max(height_pt, 1.0)  # one text line, in axes fraction
    items = sorted(
        ((float(np.clip((y - low) / (high - low), 0.0, 1.0)), text, colour)
         for y, text, colour in ends if math.isfinite(y) and low <= y <= high),
        key=lambda item: item[0],
    )
    placed: list[float] = []
    for frac, _, _ in items:  # bottom up, each at least a line above the one below
        placed.append(frac if not placed else max(frac, placed[-1] + gap))
    overshoot = (placed[-1] - (1.0 - gap / 2)) if placed else 0.0
    if overshoot > 0:  # pushed off the top: shift down, then keep the spacing from the top
        placed = [p - overshoot for p in placed]
        for k in range(len(placed) - 2, -1, -1):
            placed[k] = min(placed[k], placed[k + 1] - gap)
    transform = ax.transAxes
    for (frac, text, colour), y in zip(items, placed, strict=True):
        ax.annotate(
            text,
            xy=(1.0, frac),
            xycoords=transform,
            xytext=(1.012, y),
            textcoords=transform,
            fontsize=fontsize,
            color=colour,
            va="center",
            ha="left",
            annotation_clip=False,
            arrowprops=(
                {"arrowstyle": "-", "color": colour, "linewidth": 0.6, "shrinkA": 0, "shrinkB": 0}
                if abs(y - frac) > gap / 4
                else None
            ),
        )


# --- pages without a figure -----------------------------------------------------------------
def text_page(
    title: str, lines: list[str], size: tuple[float, float] = LANDSCAPE_IN,
    font_size: float = 7.5,
) -> Any:
    """A page of text (title page, notes); a line longer than the page is wrapped."""
    import textwrap

    fig = new_figure(size)
    page_margins(fig)
    ax = fig.add_subplot()
    ax.axis("off")
    fig.suptitle(title, fontsize=15, weight="bold")
    # monospace glyphs are 0.6 em wide: a 240-character note ran off the page, its reason
    # cut mid-sentence (outside audit)
    usable_in = fig.get_figwidth() - 2.0 * TEXT_PAGE_MARGIN_IN  # the layout's margins
    width = max(40, int(usable_in * 72 / (0.6 * font_size)))
    wrapped = []
    for line in lines:
        indent = " " * (len(line) - len(line.lstrip(" -")))
        wrapped += textwrap.wrap(line, width, subsequent_indent=indent,
                                 break_on_hyphens=False) or [""]
    ax.text(
        0.0,
        1.0,
        "\n".join(wrapped),
        transform=ax.transAxes,
        va="top",
        ha="left",
        fontsize=font_size,
        family="monospace",
    )
    return fig


# --- one basis for every thrust and force (issue 47 item 3) -----------------------------------
DRAG_SIGN = "drag D > 0 rearward"  # the one sign convention: F = T - D on every page


def basis_text(reference_density_kg_m3: float | None) -> str:
    """The thrust figures' basis, for an axis label: the propulsion file's reference density,
    or "as measured" when the file states none."""
    if reference_density_kg_m3 is None:
        return "as measured (no \u03c1ref stated)"
    return f"at \u03c1ref = {reference_density_kg_m3:.3f} kg/m\u00b3"


def basis_note(measured: Any) -> str:
    """How the measured forces were brought onto the basis (one line under a title)."""
    ref, rho = measured.reference_density_kg_m3, measured.density_kg_m3
    if ref is None or rho is None:
        return "measured forces as given"
    return (f"measured at \u03c1 = {rho:.3f} kg/m\u00b3, scaled by \u03c1ref/\u03c1 = "
            f"{measured.basis_scale:.4f} onto the model's \u03c1ref = {ref:.3f} kg/m\u00b3")


def thrust_label(what: str, reference_density_kg_m3: float | None) -> str:
    """An axis label of thrust or force: the quantity, its basis and the drag convention."""
    return f"{what} (N)\n{basis_text(reference_density_kg_m3)}\n{DRAG_SIGN}"


def flight_label(what: str, density_kg_m3: float) -> str:
    """An axis label of a flight page's force: flight is at the case's density, not the
    model's reference (the thrust model's pages are), so the label says which it is; three
    short lines fit a half-height panel."""
    return f"{what} (N)\nin flight, \u03c1 = {density_kg_m3:.3f} kg/m\u00b3\n{DRAG_SIGN}"


def flight_basis(density_kg_m3: float, reference_density_kg_m3: float | None) -> str:
    """How a flight page's thrust relates to the model's basis (for its title)."""
    if reference_density_kg_m3 is None:
        return "thrust as measured (the propulsion file states no reference density)"
    return (f"thrust = model x \u03c1/\u03c1ref = {density_kg_m3 / reference_density_kg_m3:.3f} "
            f"(\u03c1ref {reference_density_kg_m3:.3f} kg/m\u00b3)")
