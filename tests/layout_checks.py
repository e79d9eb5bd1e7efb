"""Layout checks on drawn matplotlib figures (issue 15): what a reviewer sees, measured.

Each check draws the figure on the Agg canvas and compares window extents in display
pixels; each returns a list of problems (empty when the figure is clean), so a test
can both assert a clean figure and assert that a bad one is caught.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

UNIT = re.compile(r"[(\[][^()\[\]]+[)\]]")  # "(m/s)", "[N]", "(fraction)", "(-)"
DENSIFY = 24  # points per segment: a line crossing a legend between two vertices is caught


def renderer_of(fig: Any) -> Any:
    """Draw ``fig`` on an Agg canvas (as the PNG writer does) and return the renderer.

    A figure unchanged since this drew it (matplotlib marks every change ``stale``) is not
    drawn again: each check asks, and a draw of a page is ~0.1 s.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    if fig.stale or getattr(fig, "_layout_checks_drawn", None) is not fig.canvas:
        fig.canvas.draw()
        fig._layout_checks_drawn = fig.canvas
    return fig.canvas.get_renderer()


def _inside(points: np.ndarray, box: Any, shrink: float = 1.0) -> np.ndarray:
    return ((points[:, 0] > box.x0 + shrink) & (points[:, 0] < box.x1 - shrink)
            & (points[:, 1] > box.y0 + shrink) & (points[:, 1] < box.y1 - shrink))


def _line_pixels(line: Any) -> np.ndarray:
    """A line's vertices in display pixels, each segment filled in with ``DENSIFY`` points."""
    xy = np.asarray(line.get_xydata(), dtype=float)
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if xy.shape[0] == 0:
        return np.zeros((0, 2))
    pts = line.get_transform().transform(xy)
    if pts.shape[0] < 2 or line.get_linestyle() in ("None", "none", " ", ""):
        return pts  # markers only: the points themselves
    t = np.linspace(0.0, 1.0, DENSIFY)
    seg = pts[:-1, None, :] + (pts[1:] - pts[:-1])[:, None, :] * t[None, :, None]
    return seg.reshape(-1, 2)


def _data_pixels(ax: Any) -> list[tuple[str, np.ndarray]]:
    """(label, visible pixels) of every line and scatter of an axes, clipped to the axes."""
    out = []
    box = ax.bbox
    for line in ax.get_lines():
        if line.get_visible():
            pts = _line_pixels(line)
            out.append((str(line.get_label()), pts[_inside(pts, box, shrink=0.0)]))
    for coll in ax.collections:
        offsets = np.asarray(coll.get_offsets(), dtype=float)
        if coll.get_visible() and offsets.ndim == 2 and offsets.shape[0] > 1:
            pts = coll.get_offset_transform().transform(offsets)
            out.append((str(coll.get_label()), pts[_inside(pts, box, shrink=0.0)]))
    return out


def legend_overlaps(fig: Any) -> list[str]:
    """Legends (of axes and of the figure) that cover a plotted line or point of any axes."""
    renderer = renderer_of(fig)
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    legends += list(fig.legends)
    problems = []
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for ax in fig.axes:
            if ax.name == "3d":
                continue  # projected data: the 3-D panel's legend is checked by eye
            for label, pts in _data_pixels(ax):
                hit = int(np.count_nonzero(_inside(pts, box)))
                if hit:
                    problems.append(f"legend {box.bounds!r} covers {hit} pixels of {label!r}")
    return problems


def _drawn_ticks(labels: list[Any], limits: tuple[float, float], k: int) -> list[Any]:
    """Tick labels inside the view limits (the locator also returns ones never drawn)."""
    low, high = sorted(limits)
    span = 1e-9 * max(abs(low), abs(high), 1.0)
    return [t for t in labels if low - span <= t.get_position()[k] <= high + span]


def text_over_data(fig: Any) -> list[str]:
    """Texts and annotations drawn on an axes that cover one of its lines or points."""
    renderer = renderer_of(fig)
    problems = []
    for ax in fig.axes:
        if ax.name == "3d":
            continue
        data = _data_pixels(ax)
        for text in ax.texts:
            if not (text.get_visible() and text.get_text().strip()):
                continue
            box = text.get_window_extent(renderer)
            for label, pts in data:
                hit = int(np.count_nonzero(_inside(pts, box)))
                if hit:
                    problems.append(f"text {text.get_text()!r} covers {hit} pixels of {label!r}")
    return problems


def _texts(fig: Any) -> list[Any]:
    """Titles, axis labels, tick labels, annotations and legend texts a reader reads."""
    texts: list[Any] = []
    if fig._suptitle is not None:
        texts.append(fig._suptitle)
    texts.extend(fig.texts)
    for legend in fig.legends:
        texts.extend(legend.get_texts())
    axes = list(fig.axes)
    for ax in list(axes):
        axes.extend(getattr(ax, "child_axes", []))
    for ax in axes:
        texts.extend([ax.title, ax._left_title, ax._right_title])
        if ax.name == "3d":
            continue  # projected labels and ticks: checked by eye
        if ax.axison:
            texts.extend([ax.xaxis.label, ax.yaxis.label])
            texts.extend(_drawn_ticks(ax.get_xticklabels(), ax.get_xlim(), 0))
            texts.extend(_drawn_ticks(ax.get_yticklabels(), ax.get_ylim(), 1))
        texts.extend(t for t in ax.texts)
        if ax.get_legend() is not None:
            texts.extend(ax.get_legend().get_texts())
    unique = list({id(t): t for t in texts}.values())  # the suptitle is in fig.texts too
    return [t for t in unique if t.get_visible() and t.get_text().strip()]


def text_overlaps(fig: Any, tolerance_px: float = 1.0) -> list[str]:
    """Pairs of texts whose window extents overlap (by more than ``tolerance_px``)."""
    renderer = renderer_of(fig)
    texts = _texts(fig)
    boxes = np.array([t.get_window_extent(renderer).bounds for t in texts]).reshape(-1, 4)
    if boxes.shape[0] < 2:
        return []
    x0, y0 = boxes[:, 0], boxes[:, 1]
    x1, y1 = x0 + boxes[:, 2], y0 + boxes[:, 3]
    overlap_x = np.minimum(x1[:, None], x1[None, :]) - np.maximum(x0[:, None], x0[None, :])
    overlap_y = np.minimum(y1[:, None], y1[None, :]) - np.maximum(y0[:, None], y0[None, :])
    clash = (overlap_x > tolerance_px) & (overlap_y > tolerance_px)
    i, j = np.nonzero(np.triu(clash, k=1))
    return [f"{texts[a].get_text()!r} overlaps {texts[b].get_text()!r}"
            for a, b in zip(i, j, strict=True)]


def texts_off_the_page(fig: Any, tolerance_px: float = 1.0) -> list[str]:
    """Texts cut off by the page's edge (a title wider than its axes, a label pushed out)."""
    renderer = renderer_of(fig)
    page = fig.bbox
    problems = []
    for text in _texts(fig):
        box = text.get_window_extent(renderer)
        if (box.x0 < page.x0 - tolerance_px or box.x1 > page.x1 + tolerance_px
                or box.y0 < page.y0 - tolerance_px or box.y1 > page.y1 + tolerance_px):
            problems.append(f"{text.get_text()!r} runs off the page ({box.bounds!r})")
    return problems


def missing_units(fig: Any) -> list[str]:
    """Axes whose x or y axis (with ticks) has no label with a unit in brackets."""
    problems = []
    axes = list(fig.axes)
    for ax in list(axes):
        axes.extend(getattr(ax, "child_axes", []))
    for ax in axes:
        if not ax.axison:
            continue
        if ax.get_label() == "<colorbar>":
            if not (UNIT.search(ax.get_xlabel()) or UNIT.search(ax.get_ylabel())):
                problems.append(f"colorbar without a unit: {ax.get_ylabel()!r}")
            continue
        checks = []
        if len(ax.get_xticks()) and any(t.get_visible() for t in ax.get_xticklabels()):
            siblings = ax.get_shared_x_axes().get_siblings(ax)
            checks.append(("x", [a.get_xlabel() for a in siblings]))
        if len(ax.get_yticks()) and any(t.get_visible() for t in ax.get_yticklabels()):
            checks.append(("y", [ax.get_ylabel()]))
        if ax.name == "3d":
            checks.append(("z", [ax.get_zlabel()]))
        for which, labels in checks:
            if not any(UNIT.search(label) for label in labels):
                problems.append(f"{which} axis without a unit: {labels!r}")
    return problems
