"""The report's figures, one function each, drawn from :mod:`tuflexperf.report.data`.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot
(no global figure state; the Agg canvas renders it headless). Axes carry SI units,
titles say what is shown and which of the paper's figures it corresponds to,
requirement limits are drawn where one applies, and the thrust model's
extrapolated airspeeds (beyond ``tested_airspeed_m_s``) are shaded.

One meaning, one look (:mod:`tuflexperf.report.style`): a red dashed line is a
requirement's limit on every page, grey dashes the envelope's edges, a black dotted
line the stall speed, blue the all-engine analysis or the measurement, orange one
engine out, purple a fitted model. Legends sit outside the axes, so they never cover
data; long time series are drawn through :func:`tuflexperf.report.decimate.envelope`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import (
    BELOW_STALL,
    BEYOND_JET_VELOCITY,
    BEYOND_THE_BATTERY,
    NEEDS_MORE_THAN_FULL_THROTTLE,
)
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.thrust import (
    density_ratio,
    engine_thrust_n,
    total_thrust_n,
)
from tuflexperf.report.data import (  # noqa: F401 - dynamic_thrust_n, model_force_n: API
    Analyses,
    Measured,
    ProcessedRun,
    dynamic_thrust_n,
    model_dynamics,
    model_force_n,
)
from tuflexperf.report.decimate import envelope as decimated
from tuflexperf.report.style import (
    EXTRAPOLATED_FILL,
    FAIL_FILL,
    PASS_FILL,
    POINT,
    STYLE,
    legend_outside,
    unit,
)

LANDSCAPE_IN = (11.69, 8.27)  # A4 landscape (297 x 210 mm)
TEXT_PAGE_MARGIN_IN = 0.6  # about 15 mm: a printer's unprintable edge plus room to staple
# the earlier names of the style's colours, for pages built on them (style.py is the source)
PASS_COLOUR, FAIL_COLOUR = PASS_FILL, FAIL_FILL
LIMIT_COLOUR = STYLE["limit"]["color"]
EXTRAPOLATED_COLOUR = EXTRAPOLATED_FILL
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


def _page_margins(fig: Any) -> None:
    """Margins of a printed page for text and table pages (an axes without decorations
    would otherwise reach the paper's edge)."""
    fig.get_layout_engine().set(w_pad=TEXT_PAGE_MARGIN_IN, h_pad=TEXT_PAGE_MARGIN_IN / 2)


def _style(meaning: str, **override: Any) -> dict[str, Any]:
    """``STYLE[meaning]`` with a few keys changed (a second curve of the same meaning)."""
    return {**STYLE[meaning], **override}


def _legend(ax: Any, **kwargs: Any) -> Any:
    """The report's legend: right of the axes (:func:`legend_outside`), never over data."""
    return legend_outside(ax, **kwargs)


# characters per line of the requirements page's text (monospace, 9 pt, landscape A4)
_REQUIREMENT_TEXT_COLUMNS = 128

# hatch of a stretch not attainable, by reason (full throttle not enough: the plain band)
_REASON_HATCH = {BELOW_STALL: "..", BEYOND_JET_VELOCITY: "xx", BEYOND_THE_BATTERY: "\\\\"}


def _reason_runs(reasons: Sequence[str | None], throttle: Any) -> list[tuple[int, int, str]]:
    """(first, last, reason) of each stretch of grid airspeeds not attainable for one reason;
    a missing throttle without a stated reason needs more than full throttle."""
    values = np.asarray(throttle, dtype=float)
    stated = list(reasons) if len(reasons) == values.size else [None] * values.size
    why = [r if r is not None else (None if np.isfinite(v) else NEEDS_MORE_THAN_FULL_THROTTLE)
           for r, v in zip(stated, values, strict=True)]
    runs: list[tuple[int, int, str]] = []
    for k, w in enumerate(why):
        if w is None:
            continue
        if runs and runs[-1][1] == k - 1 and runs[-1][2] == w:
            runs[-1] = (runs[-1][0], k, w)
        else:
            runs.append((k, k, w))
    return runs


def _shade_extrapolated(ax: Any, case: Case, right: float, label: bool = True) -> None:
    """Grey band over airspeeds beyond the thrust model's tested range."""
    low, high = case.propulsion.tested_airspeed_m_s
    if right > high:
        ax.axvspan(
            high,
            right,
            color=EXTRAPOLATED_FILL,
            zorder=0,
            label=f"thrust model extrapolated (tested {low:g}-{high:g} m/s)" if label else None,
        )


def _envelope_lines(ax: Any, case: Case) -> None:
    envelope = case.requirements.envelope
    if envelope is None:
        return
    low, high = envelope.bounds_m_s(case.density_kg_m3)
    for k, v in enumerate((low, high)):
        ax.axvline(
            v,
            **STYLE["envelope"],
            label=f"envelope {low:.4g}-{high:.4g} m/s" if k == 0 else None,
        )


def _max_airspeed(case: Case) -> float:
    envelope = case.requirements.envelope
    top = case.propulsion.tested_airspeed_m_s[1]
    if envelope is not None:
        top = max(top, envelope.bounds_m_s(case.density_kg_m3)[1])
    return 1.05 * top


def _min_airspeed(case: Case, stall: float) -> float:
    """Left edge of an airspeed axis: just below the stall speed or the envelope, not 0."""
    envelope = case.requirements.envelope
    low = stall if envelope is None else min(stall, envelope.bounds_m_s(case.density_kg_m3)[0])
    return max(0.0, 0.9 * low)


def _note(ax: Any, text: str) -> None:
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


def _wrap(text: str, width: int) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width))


def _label_line_ends(ax: Any, ends: list[tuple[float, str, Any]], fontsize: float = 8.0) -> None:
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


# --- 2. requirement table -----------------------------------------------------------------------
def requirement_table(case: Case, analyses: Analyses) -> Any:
    """The verdicts of ``check``: value, limit, margin, PASS/FAIL, colour-coded."""
    fig = new_figure()
    _page_margins(fig)
    ax = fig.add_subplot()
    ax.axis("off")
    verdicts = analyses.verdicts
    passed = all(v.passed for v in verdicts)
    fig.suptitle(
        f"Requirements of {case.name}: "
        + ("none stated" if not verdicts else "all met" if passed else "NOT all met"),
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
            "PASS" if v.passed else "FAIL",
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
                cell.set_facecolor(PASS_FILL if verdicts[r - 1].passed else FAIL_FILL)
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


# --- 3. required vs available thrust (paper Fig. 18) --------------------------------------------
def thrust_required_available(case: Case, analyses: Analyses) -> Any:
    """Level-flight drag against total available thrust for throttle 0.3-1.0, trim and OEI."""
    import matplotlib as mpl

    aircraft, propulsion, rho = case.aircraft, case.propulsion, case.density_kg_m3
    right = _max_airspeed(case)
    v = np.linspace(0.0, right, 400)
    fig = new_figure()
    ax = fig.add_subplot()
    _shade_extrapolated(ax, case, right)
    # available thrust: the teal-to-yellow part of viridis (clear of the trim blue, the OEI
    # orange, the required black and the limit red)
    cmap = mpl.colormaps["viridis"]
    throttles = np.round(np.arange(0.3, 1.0001, 0.1), 2)
    ends: list[tuple[float, str, Any]] = []
    full = np.asarray(total_thrust_n(propulsion, 1.0, v, rho), dtype=float)
    for k, x in enumerate(throttles):
        t = np.asarray(total_thrust_n(propulsion, float(x), v, rho), dtype=float)
        colour = cmap(0.45 + 0.43 * (x - 0.3) / 0.7)
        ax.plot(
            v,
            t,
            color=colour,
            linewidth=1.0,
            label="available, all engines (throttle at the right edge)" if k == 0 else None,
        )
        ends.append((float(t[-1]), f"{100 * x:.0f} %", colour))
    stall = float(stall_speed_m_s(aircraft, rho))
    vd = v[v >= stall]
    drag = np.asarray(level_flight_drag_n(aircraft, vd, rho), dtype=float)
    ax.plot(vd, drag, **STYLE["required"], label="required (level-flight drag)")
    ax.axvline(stall, **STYLE["stall"], label=f"stall speed {stall:.1f} m/s")
    trim = analyses.trim
    if trim is not None and trim.min_throttle is not None:
        x = trim.min_throttle
        t = np.asarray(total_thrust_n(propulsion, x, v, rho), dtype=float)
        va = trim.airspeed_at_min_throttle_m_s
        ax.plot(v, t, **_style("trim", linestyle="-."),
                label=f"least trim throttle {100 * x:.1f} %, all engines (dot: {va:.1f} m/s)")
        ax.plot([va], [float(level_flight_drag_n(aircraft, va, rho))], **POINT["least"],
                markerfacecolor=STYLE["trim"]["color"])
    oei = analyses.oei
    if oei is not None:
        worst = oei.critical
        index = [e.name for e in propulsion.engines].index(worst.dead_engine)
        one = np.asarray(
            total_thrust_n(propulsion, 1.0, v, rho, index, oei.dead_engine_mode), dtype=float
        )
        ax.plot(v, one, **STYLE["oei"],
                label=f"OEI: {worst.dead_engine} dead ({oei.dead_engine_mode}), others 100 %")
        if worst.min_throttle is not None:
            x = worst.min_throttle
            t = np.asarray(
                total_thrust_n(propulsion, x, v, rho, index, oei.dead_engine_mode), dtype=float
            )
            va = worst.airspeed_at_min_throttle_m_s
            ax.plot(v, t, **_style("oei", linestyle="-."),
                    label=f"OEI least throttle {100 * x:.1f} % (dot: {va:.1f} m/s)")
            ax.plot([va], [float(level_flight_drag_n(aircraft, va, rho))], **POINT["least"],
                    markerfacecolor=STYLE["oei"]["color"])
    _envelope_lines(ax, case)
    ax.set_xlim(0, right)
    top = 1.08 * float(np.max(full))
    if drag.size:
        top = max(top, 1.08 * float(drag.max()))
    ax.set_ylim(0, top)
    _label_line_ends(ax, ends)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("thrust, drag (N)")
    fig.suptitle(
        "Required and available thrust in level flight (paper Fig. 18)\n"
        f"{case.name}, {unit(f'rho = {rho:.3f} kg/m^3')}"
    )
    ax.grid(alpha=0.3)
    # right of the throttle labels in the margin, so neither covers the other
    ax.legend(loc="upper left", bbox_to_anchor=(1.07, 1.0), borderaxespad=0.0,
              fontsize=LEGEND_FONT)
    return fig


# --- 4. thrust surfaces (paper Figs. 11-12) -----------------------------------------------------
def thrust_surface(case: Case, measured: Measured, engine_index: int) -> Any:
    """One fan's poly22 surface with the measured points, and the points' residuals."""
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401 - registers the 3d projection

    propulsion = case.propulsion
    engine = propulsion.engines[engine_index]
    rho_test = measured.density_kg_m3
    scale = 1.0 if rho_test is None else float(density_ratio(propulsion, rho_test))
    low, high = propulsion.tested_airspeed_m_s
    x = np.linspace(0.0, 1.0, 21)
    v = np.linspace(max(low, 0.0), high, 31)
    xx, vv = np.meshgrid(x, v)
    tt = np.asarray(engine_thrust_n(engine, xx, vv, scale), dtype=float)

    fig = new_figure()
    grid = fig.add_gridspec(1, 2, width_ratios=[1.6, 1.0])
    ax3 = fig.add_subplot(grid[0], projection="3d")
    # the scatter is drawn after the surface (no depth sort), so no point hides behind it
    ax3.computed_zorder = False
    ax3.plot_surface(xx, vv, tt, cmap="viridis", alpha=0.7, linewidth=0, antialiased=True,
                     zorder=1)
    ax3.set_xlabel("throttle x (fraction)")
    ax3.set_ylabel("airspeed V (m/s)")
    ax3.set_zlabel("thrust T (N)")
    ax3.view_init(elev=22, azim=-130)
    ax3.set_box_aspect(None, zoom=0.88)  # as large as the z label allows
    ax_r = fig.add_subplot(grid[1])
    points = measured.points.select(engine.name) if measured.points is not None else None
    title = f"Thrust model of {engine.name}: poly22 surface"
    if points is None or points[0].size == 0:
        reason = measured.notes[0] if measured.notes else "no measured points"
        if measured.points is not None:
            reason = f"the measured data name no engine {engine.name!r}"
        _note(ax_r, "No measured points for this engine:\n" + _wrap(reason, 38))
        ax_r.axis("off")  # a note, not an empty plot
        ax3.set_title(title + " (model alone)")
        fig.suptitle(f"{title}; no measured data to compare (paper Figs. 11-12)")
        return fig
    px, pv, pt = points
    model = np.asarray(engine_thrust_n(engine, px, pv, scale), dtype=float)
    residual = pt - model
    measured_colour = "#d62728"  # points on a viridis surface: the one colour it lacks
    ax3.scatter(px, pv, pt, color=measured_colour, s=16, depthshade=False, zorder=5,
                edgecolors="white", linewidths=0.4)
    what = "segment means" if measured.kind == "campaign" else "table points"
    ax3.set_title(f"surface and measured points (red: {what}, n = {pt.size})",
                  fontsize=10)
    sc = ax_r.scatter(px, residual, c=pv, cmap="plasma", s=22, zorder=3)
    fig.colorbar(sc, ax=ax_r, location="bottom", label="airspeed V (m/s)", shrink=0.8,
                 aspect=40)
    ax_r.axhline(0.0, color="black", linewidth=0.8)
    for sign in (-1, 1):
        ax_r.axhline(
            sign * ACCURACY_GOAL_N,
            **STYLE["goal"],
            label=f"accuracy goal ±{ACCURACY_GOAL_N:g} N (paper)" if sign > 0 else None,
        )
    rmse = float(np.sqrt(np.mean(residual**2)))
    sst = float(np.sum((pt - pt.mean()) ** 2))
    r2 = 1.0 - float(np.sum(residual**2)) / sst if sst > 0 else math.nan
    text = f"against this model: R² = {r2:.5f}, RMSE = {rmse:.3f} N"
    refit = _refit(measured, engine.name)
    if refit is not None:
        text += (
            f"\ncampaign re-fit (tuflexperf fit): R² = {refit['r2']:.5f}, "
            f"RMSE = {refit['rmse_n']:.3f} N"
        )
    # the statistics are the panel's title: inside, a box would sit on a goal line or a point
    ax_r.set_title(f"residuals of the measured points\n{text}", fontsize=9)
    ax_r.set_xlabel("throttle x (fraction)")
    ax_r.set_ylabel("measured - model thrust (N)")
    ax_r.grid(alpha=0.3)
    span = max(float(np.max(np.abs(residual))), ACCURACY_GOAL_N)
    ax_r.set_ylim(-1.15 * span, 1.15 * span)
    _legend(ax_r)
    source = measured.source.name if measured.source is not None else "?"
    fig.suptitle(f"{title} with the measured points from {source} (paper Figs. 11-12)")
    return fig


def _refit(measured: Measured, name: str) -> dict[str, Any] | None:
    if measured.fit_summary is None:
        return None
    for entry in measured.fit_summary.get("engines", []):
        if entry["name"] == name and entry.get("r2") is not None and entry.get("rmse_n"):
            return entry
    return None


# --- 5. one run, raw and processed (paper Fig. 10) ----------------------------------------------
def run_processing(run: ProcessedRun) -> Any:
    """Raw and cleaned force of one throttle-step run, change points and steady segments."""
    fig = new_figure()
    gs = fig.add_gridspec(2, 1, height_ratios=[3, 1])
    ax = fig.add_subplot(gs[0])
    axt = fig.add_subplot(gs[1], sharex=ax)
    t = run.time_s
    tr, raw = decimated(t, run.force_raw_n)
    tc, clean = decimated(t, run.force_clean_n)
    ax.plot(tr, raw, **STYLE["measured_raw"], label="raw force")
    ax.plot(
        tc,
        clean,
        **STYLE["measured"],
        label=f"processed (outliers filled: {run.outliers_replaced}, moving median)",
    )
    for k, (start, stop, mean) in enumerate(run.segments):
        ax.plot(
            [t[start], t[stop - 1]],
            [mean, mean],
            **STYLE["segment"],
            solid_capstyle="butt",
            label="steady segment mean" if k == 0 else None,
        )
    for k, c in enumerate(run.changepoints):
        ax.axvline(t[c], **STYLE["changepoint"],
                   label="detected change point" if k == 0 else None)
    ax.set_ylabel("balance force F (N)")
    ax.grid(alpha=0.3)
    _legend(ax)
    ax.tick_params(labelbottom=False)
    ts, x = decimated(t, run.throttle)
    axt.plot(ts, x, **STYLE["command"], label="throttle command")
    axt.set_ylabel("throttle x (fraction)")
    axt.set_xlabel("time t (s)")
    axt.grid(alpha=0.3)
    fig.suptitle(
        f"{run.engine} at {run.mean_airspeed_m_s:.1f} m/s ({run.file}): raw and processed "
        f"force, {len(run.changepoints)} change points, {len(run.segments)} steady segments "
        "(paper Fig. 10)"
    )
    return fig


def _dynamics_label(label: str, delay_s: float, lag_s: float) -> str:
    lag = f"{1000 * lag_s:.0f} ms spool lag" if lag_s > 0 else "no spool lag"
    return f"model ({label} dynamics): {1000 * delay_s:.0f} ms dead time + {lag}"


def _model_styles(dynamics: list[tuple[str, float, float]]) -> list[dict[str, Any]]:
    """Purple for every model; the one with a spool lag solid, the others dashed."""
    lagged = [k for k, (_, _, lag) in enumerate(dynamics) if lag > 0]
    main = lagged[-1] if lagged else 0
    return [STYLE["model"] if k == main else _style("model", linestyle="--", linewidth=1.1)
            for k in range(len(dynamics))]


# --- 6. sine sweep and delay (paper Figs. 13-14) ------------------------------------------------
def sine_sweep(measured: Measured, case: Case) -> Any:
    """Measured force of a sine sweep against the fitted dynamic model (dead time + spool lag)
    in newtons, the whole sweep and its fastest end."""
    sweep = measured.sweep
    fig = new_figure()
    gs = fig.add_gridspec(3, 1, height_ratios=[2.2, 2.2, 1.0])
    ax = fig.add_subplot(gs[0])
    az = fig.add_subplot(gs[1])
    ac = fig.add_subplot(gs[2], sharex=az)
    t = sweep.time_s
    force = sweep.force_median_n
    dynamics = model_dynamics(case, measured)
    styles = _model_styles(dynamics)
    models = [model_force_n(case, measured, sweep, delay, lag) for _, delay, lag in dynamics]
    # the sweep ends where the throttle last leaves the value it holds at the end of the log
    moving = np.flatnonzero(np.abs(sweep.throttle - sweep.throttle[-1]) > 0.01)
    t_end = t[moving[-1]] if moving.size else t[-1]
    end = (t >= t_end - 1.5) & (t <= t_end + 0.3)
    tw, fw = decimated(t, force)
    ax.plot(tw, fw, **STYLE["measured"], label="measured force (20 ms moving median)")
    az.plot(t[end], sweep.force_n[end], **STYLE["measured_raw"], label="measured force (raw)")
    az.plot(t[end], force[end], **STYLE["measured"], label="measured force (20 ms median)")
    for (label, delay, lag), style, model in zip(dynamics, styles, models, strict=True):
        if model is None:
            continue
        if style is STYLE["model"]:  # the whole sweep shows the fitted model alone
            tm, fm = decimated(t, model)
            ax.plot(tm, fm, **style, label=_dynamics_label(label, delay, lag), zorder=1)
        az.plot(t[end], model[end], **style, label=_dynamics_label(label, delay, lag))
    if all(m is None for m in models):
        ax.set_title(f"whole sweep ({sweep.file}); the case's propulsion has no engine "
                     f"{sweep.engine!r}: no model drawn", fontsize=10)
    else:
        ax.set_title(f"whole sweep ({sweep.file}); model: poly22 thrust, dead time, spool lag, "
                     "minus structure drag", fontsize=9)
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("balance force F (N)")
    ax.grid(alpha=0.3)
    _legend(ax)
    az.set_ylabel("balance force F (N)")
    az.set_title("end of the sweep (highest frequency)", fontsize=10)
    az.grid(alpha=0.3)
    az.tick_params(labelbottom=False)
    _legend(az)
    ac.plot(t[end], sweep.throttle[end], **STYLE["command"], label="throttle command")
    ac.set_xlabel("time t (s)")
    ac.set_ylabel("throttle x (fraction)")
    ac.grid(alpha=0.3)
    _legend(ac)
    parts = [f"this sweep: dead time {1000 * sweep.delay_s:.0f} ms, spool lag "
             f"{1000 * sweep.lag_s:.0f} ms" if math.isfinite(sweep.delay_s)
             else "this sweep: delay not estimated"]
    parts += [f"{label}: {1000 * delay:.0f} ms + {1000 * lag:.0f} ms"
              for label, delay, lag in dynamics]
    fig.suptitle(
        f"Sine sweep of {sweep.engine} at {sweep.airspeed_m_s:.1f} m/s: measured force against "
        f"the fitted dynamic model (paper Figs. 13-14)\n" + "; ".join(parts)
    )
    return fig


# --- 7. model against measured force (paper Figs. 16-17) ----------------------------------------
def model_vs_measured(case: Case, measured: Measured) -> Any:
    """The case's thrust model driven by the logged throttle against the measured force."""
    runs = measured.comparisons
    fig = new_figure()
    gs = fig.add_gridspec(2, len(runs), height_ratios=[3, 1])
    dynamics = model_dynamics(case, measured)
    styles = _model_styles(dynamics)
    handles: dict[str, Any] = {}
    for k, run in enumerate(runs):
        ax = fig.add_subplot(gs[0, k])
        ae = fig.add_subplot(gs[1, k], sharex=ax)
        t = run.time_s
        tr, raw = decimated(t, run.force_raw_n)
        tc, clean = decimated(t, run.force_clean_n)
        ax.plot(tr, raw, **STYLE["measured_raw"], label="measured (raw)")
        ax.plot(tc, clean, **STYLE["measured"], label="measured (processed)")
        ax.set_title(f"{run.engine} at {run.mean_airspeed_m_s:.1f} m/s ({run.file})", fontsize=10)
        ax.set_ylabel("balance force F (N)")
        ax.grid(alpha=0.3)
        ax.tick_params(labelbottom=False)
        ae.set_xlabel("time t (s)")
        ae.set_ylabel("model - measured (N)")
        ae.grid(alpha=0.3)
        models = [model_force_n(case, measured, run, delay, lag) for _, delay, lag in dynamics]
        if models[0] is None:
            _note(ae, f"the case's propulsion has no engine {run.engine!r}")
            handles.update(zip(*reversed(ax.get_legend_handles_labels()), strict=True))
            continue
        for (label, delay, lag), style, model in zip(dynamics, styles, models, strict=True):
            tm, fm = decimated(t, model)
            ax.plot(tm, fm, **style,
                    label=_dynamics_label(label, delay, lag) + ", minus structure drag")
        main = next(k for k, st in enumerate(styles) if st is STYLE["model"])
        error = models[main] - run.force_clean_n
        steady = np.zeros(t.size, dtype=bool)
        for start, stop, _ in run.segments:
            steady[start:stop] = True
        te, ee = decimated(t, error)
        ae.plot(te, ee, **STYLE["error"], label=f"model ({dynamics[main][0]} dynamics) - processed")
        for sign in (-1, 1):
            ae.axhline(sign * ACCURACY_GOAL_N, **STYLE["goal"],
                       label=f"accuracy goal ±{ACCURACY_GOAL_N:g} N" if sign > 0 else None)
        e = error[steady]
        neg = e[e < 0].mean() if np.any(e < 0) else 0.0
        pos = e[e > 0].mean() if np.any(e > 0) else 0.0
        # the statistics are the panel's title: inside, they would cross the error spikes
        ae.set_title(f"steady segments: mean error {neg:+.2f} N / {pos:+.2f} N", fontsize=9)
        ae.set_ylim(-3, 3)
        for a in (ax, ae):
            handles.update(zip(*reversed(a.get_legend_handles_labels()), strict=True))
    # one legend for both columns, below them: it covers no trace
    fig.legend(list(handles.values()), list(handles.keys()), loc="outside lower center",
               ncols=3, fontsize=LEGEND_FONT)
    fig.suptitle(
        "Thrust model driven by the logged throttle against the measured force "
        "(paper Figs. 16-17)\nerror panels clipped at ±3 N"
    )
    return fig


# --- 8. take-off ----------------------------------------------------------------------------
def _verdict_passed(analyses: Analyses, name: str) -> bool:
    """PASS/FAIL as ``check`` decided it (analysis/requirements.py), never re-judged here."""
    return any(v.name == name and v.passed for v in analyses.verdicts)


def _takeoff_not_attainable(case: Case, analyses: Analyses) -> Any:
    from tuflexperf.analysis.ground_roll import net_force_n
    from tuflexperf.models.aircraft import liftoff_speed_m_s

    fig = new_figure()
    gs = fig.add_gridspec(1, 2, width_ratios=[1.0, 2.0])
    an = fig.add_subplot(gs[0])
    ad = fig.add_subplot(gs[1])
    an.axis("off")
    an.text(0.0, 0.5, _wrap(f"take-off not attainable: {analyses.takeoff_note}", 50),
            transform=an.transAxes, ha="left", va="center", fontsize=11, color="0.3")
    rho = case.density_kg_m3
    v_lo = float(liftoff_speed_m_s(case.aircraft, rho))
    v = np.linspace(0.0, 1.05 * v_lo, 300)
    force = np.asarray(net_force_n(case.aircraft, case.propulsion, v, rho), dtype=float)
    ad.plot(v, force, **STYLE["takeoff"], label="accelerating force at full throttle")
    ad.axhline(0.0, color="black", linewidth=0.8)
    ad.axvline(v_lo, **STYLE["stall"], label=f"lift-off speed {v_lo:.1f} m/s")
    ad.set_xlabel("airspeed V (m/s)")
    ad.set_ylabel("net force on the runway (N)")
    ad.set_title("why: the net force on the runway", fontsize=10)
    ad.grid(alpha=0.3)
    _legend(ad)
    fig.suptitle(f"Take-off of {case.name}: not attainable")
    return fig


def takeoff_history(case: Case, analyses: Analyses) -> Any:
    """Take-off at full throttle along the runway: airspeed against distance (roll, rotation,
    airborne part to the obstacle) with the runway limit, and the forces along the roll."""
    result = analyses.takeoff
    if result is None:
        return _takeoff_not_attainable(case, analyses)
    fig = new_figure()
    gs = fig.add_gridspec(2, 1, height_ratios=[1.0, 1.0])
    av = fig.add_subplot(gs[0])
    af = fig.add_subplot(gs[1])
    s, v, t = result.history_distance_m, result.history_airspeed_m_s, result.history_time_s
    v_lo, roll = result.liftoff_speed_m_s, result.ground_roll_m
    s_acc = result.acceleration_distance_m
    catapult = result.launch == "catapult"  # released airborne: no ground run to draw
    if not catapult:
        av.plot(s, v, **STYLE["takeoff"], label=f"ground run, full throttle ({t[-1]:.1f} s)")
    if result.rotation_distance_m > 0:
        av.plot([s_acc, roll], [v_lo, v_lo], **_style("takeoff", linestyle="-.", linewidth=3.0),
                label=f"rotation at the lift-off speed ({result.rotation_time_s:.2f} s)")
    av.plot([roll], [v_lo], **POINT["least"],
            label=f"catapult release at {v_lo:.1f} m/s (no runway)" if catapult else
            f"lift-off: {roll:.1f} m after {result.time_s:.1f} s at {v_lo:.1f} m/s")
    right = roll
    obstacle = result.distance_to_obstacle_m
    if obstacle is not None:
        # the airborne part flies the transition speed (Anderson 6.7.2): a level line to
        # the obstacle, so the page shows how much of the take-off distance is in the air
        av.plot([roll, obstacle], [result.transition_speed_m_s] * 2, **STYLE["airborne"],
                label=f"airborne: arc and climb at {result.transition_speed_m_s:.1f} m/s")
        av.plot([obstacle], [result.transition_speed_m_s], marker="^", markersize=8,
                color=STYLE["airborne"]["color"], linestyle="none",
                label=f"{result.obstacle_height_m:g} m obstacle cleared at {obstacle:.1f} m")
        right = obstacle
    av.axhline(result.stall_speed_m_s, **STYLE["stall"],
               label=f"stall speed {result.stall_speed_m_s:.1f} m/s")
    high = case.propulsion.tested_airspeed_m_s[1]
    top = 1.12 * max(v_lo, result.transition_speed_m_s)
    if top > high:
        av.axhspan(high, top, color=EXTRAPOLATED_FILL, zorder=0,
                   label="thrust model extrapolated")
    requirement = case.requirements.takeoff
    limit = requirement.max_ground_roll_m if requirement is not None else None
    for ax in (av, af):
        if limit is not None:
            met = _verdict_passed(analyses, "takeoff_ground_roll")
            ax.axvline(limit, **STYLE["limit"],
                       label=f"runway limit {limit:g} m ({'PASS' if met else 'FAIL'})")
            right = max(right, limit)
    av.set_xlim(0, 1.04 * right)
    # the forces end at lift-off: their panel spans the runway, not the airborne part
    af.set_xlim(0, 1.1 * (roll if limit is None else max(roll, limit)))
    for ax in (av, af):
        ax.grid(alpha=0.3)
    av.set_ylim(0, top)
    av.set_ylabel("true airspeed V (m/s)")
    av.set_title("airspeed along the take-off", fontsize=10)
    av.set_xlabel("distance from brake release s (m)")
    # the forces along the roll; rotation holds the lift-off speed, so its forces too
    s_f = np.append(s, roll)
    forces = [
        ("thrust, all engines at full throttle", result.history_thrust_n,
         {"color": AVAILABLE_COLOUR, "linestyle": "-", "linewidth": 1.8}),
        ("aerodynamic drag (ground run)", result.history_drag_n,
         {"color": STYLE["required"]["color"], "linestyle": "--", "linewidth": 1.4}),
        ("rolling friction", result.history_friction_n,
         {"color": STYLE["error"]["color"], "linestyle": ":", "linewidth": 1.8}),
    ]
    if result.history_thrust_n.size:
        for label, values, style in forces:
            af.plot(s_f, np.append(values, values[-1]), **style, label=label)
        net = result.history_thrust_n - result.history_drag_n - result.history_friction_n
        af.plot(s_f, np.append(net, net[-1]), **STYLE["takeoff"], label="net accelerating force")
        af.axvspan(s_acc, roll, color="0.93", zorder=0, label="rotation")
    af.axhline(0.0, color="black", linewidth=0.8)
    af.set_ylim(bottom=0.0)
    af.set_xlabel("distance from brake release s (m)")
    af.set_ylabel("force (N)")
    af.set_title("forces on the ground run", fontsize=10)
    if catapult:
        af.text(0.5, 0.5, "catapult launch: no ground run (the catapult's energy, not the "
                "battery's, brings the aircraft to its release speed)", transform=af.transAxes,
                ha="center", va="center", fontsize=10)
    _legend(av)
    _legend(af)
    start = (f"catapult release at {v_lo:.1f} m/s, no ground roll" if catapult else
             f"ground roll {roll:.1f} m to lift-off at {v_lo:.1f} m/s")
    # the obstacle's reason may be long (never cleared, and why): wrapped, not cut at the edges
    fig.suptitle(_wrap(
        f"Take-off of {case.name} at full throttle: {start}"
        + (f", {obstacle:.1f} m to the {result.obstacle_height_m:g} m obstacle"
           if obstacle is not None else f"; {result.obstacle_reason}"), 140))
    return fig


# --- 9. trim and OEI throttle -----------------------------------------------------------------
def trim_oei_throttle(case: Case, analyses: Analyses) -> Any:
    """Least level-flight throttle against airspeed, all engines and one engine out."""
    fig = new_figure()
    ax = fig.add_subplot()
    trim, oei = analyses.trim, analyses.oei
    right = _max_airspeed(case)
    stall = float(stall_speed_m_s(case.aircraft, case.density_kg_m3))
    left = _min_airspeed(case, stall)
    _shade_extrapolated(ax, case, right)
    envelope = case.requirements.envelope
    ax.plot(trim.airspeed_m_s, trim.throttle, **STYLE["trim"], label="trim, all engines")
    if trim.min_throttle is not None:
        ax.plot([trim.airspeed_at_min_throttle_m_s], [trim.min_throttle], **POINT["least"],
                markerfacecolor=STYLE["trim"]["color"],
                label=f"least trim throttle {100 * trim.min_throttle:.1f} % at "
                f"{trim.airspeed_at_min_throttle_m_s:.1f} m/s")
    if trim.max_throttle is not None:
        k = int(np.nanargmax(trim.throttle))
        ax.plot([trim.airspeed_m_s[k]], [trim.max_throttle], **POINT["verdict"],
                label=f"highest trim throttle {100 * trim.max_throttle:.1f} % at "
                f"{trim.airspeed_m_s[k]:.1f} m/s (the verdict)")
    ax.axhline(envelope.max_trim_throttle, **STYLE["limit"],
               label=f"limit: max trim throttle {envelope.max_trim_throttle:g}")
    if oei is not None:
        for c in oei.cases:
            critical = c is oei.critical
            ax.plot(c.airspeed_m_s, c.throttle, **STYLE["oei" if critical else "oei_other"],
                    label=f"OEI, {c.dead_engine} dead ({oei.dead_engine_mode})"
                    + (", the worse case" if critical else ""))
        worst = oei.critical
        speeds = np.asarray(worst.airspeed_m_s, dtype=float)
        # not attainable: one hatched band per stretch of airspeeds and reason (the OEI
        # result's own), each reason once in the legend; above full throttle (y 1 to 1.08)
        # where the curve would have to go
        oei_runs = _reason_runs(worst.reasons, worst.throttle)
        for k, (a, b, why) in enumerate(oei_runs):
            lo = speeds[a - 1] if a > 0 else speeds[a]
            hi = speeds[b + 1] if b + 1 < speeds.size else speeds[b]
            ax.axvspan(0.5 * (lo + speeds[a]), 0.5 * (hi + speeds[b]), ymin=1.0 / 1.08,
                       ymax=1.0, facecolor="none", edgecolor=STYLE["oei"]["color"],
                       hatch=_REASON_HATCH.get(why, "//"), linewidth=0.0, alpha=0.9,
                       zorder=0, label=f"OEI ({worst.dead_engine} dead) not attainable: {why}"
                       if all(w != why for _, _, w in oei_runs[:k]) else None)
        if worst.min_throttle is not None:
            ax.plot([worst.airspeed_at_min_throttle_m_s], [worst.min_throttle], **POINT["least"],
                    markerfacecolor=STYLE["oei"]["color"],
                    label=f"OEI least throttle {100 * worst.min_throttle:.1f} % at "
                    f"{worst.airspeed_at_min_throttle_m_s:.1f} m/s")
        requirement = case.requirements.oei
        if (
            requirement is not None
            and abs(requirement.max_throttle - envelope.max_trim_throttle) > 1e-9
        ):
            ax.axhline(requirement.max_throttle, **_style("limit", linewidth=2.2),
                       label=f"limit: OEI max throttle {requirement.max_throttle:g}")
    runs = _reason_runs(trim.reasons, trim.throttle)
    for k, (a, b, why) in enumerate(runs):
        ax.axvspan(trim.airspeed_m_s[a], trim.airspeed_m_s[b], color=FAIL_FILL, alpha=0.6,
                   hatch=_REASON_HATCH.get(why), zorder=0,
                   label=f"trim not attainable: {why}"
                   if all(w != why for _, _, w in runs[:k]) else None)
    ax.axvline(stall, **STYLE["stall"], label=f"stall speed {stall:.1f} m/s")
    _envelope_lines(ax, case)
    ax.set_xlim(left, right)
    ax.set_ylim(0, 1.08)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("least throttle for level flight x (fraction)")
    fig.suptitle(f"Trim and one-engine-inoperative throttle over the envelope, {case.name}")
    ax.grid(alpha=0.3)
    _legend(ax)
    return fig


# --- 10. endurance --------------------------------------------------------------------------
def endurance(case: Case, analyses: Analyses) -> Any:
    """Pack voltage of the discharge runs, model and data; flight time against throttle
    with the level-flight airspeed on a second axis and the best-endurance point."""
    from tuflexperf.models.battery import terminal_voltage_v

    ch = analyses.characterisation
    fig = new_figure()
    gs = fig.add_gridspec(2, 1, height_ratios=[1.0, 1.15])
    av = fig.add_subplot(gs[0])
    af = fig.add_subplot(gs[1])
    colours = [STYLE["measured"]["color"], "#17becf", "#8c564b", "#e377c2"]
    for k, run in enumerate(ch.discharge_runs()):
        colour = colours[k % len(colours)]
        minutes = (run.time_s - run.time_s[0]) / 60.0
        model = np.asarray(
            terminal_voltage_v(ch.fit.parameters, run.charge_ah, run.current_a), dtype=float
        )
        m_t, data_v, model_v = decimated(minutes, run.voltage_v, model)
        label = f"{run.path.name} (throttle {run.throttle_setting:.2f})"
        av.plot(m_t, data_v, color=colour, linewidth=3.0, alpha=0.35, label=f"data: {label}")
        av.plot(m_t, model_v, **_style("model", linestyle="--", linewidth=1.0),
                label="model (fitted equivalent circuit)" if k == 0 else None)
    flown = analyses.battery if analyses.battery is not None else ch.battery
    runs_to = ("" if flown.cutoff_voltage_v == ch.battery.cutoff_voltage_v
               else f" flown (the runs' {ch.battery.cutoff_voltage_v:.1f} V)")
    av.axhline(flown.cutoff_voltage_v, **STYLE["limit"],
               label=f"cut-off {flown.cutoff_voltage_v:.1f} V{runs_to}")
    av.set_xlabel("time t (min)")
    av.set_ylabel("pack terminal voltage U (V)")
    av.set_title(f"discharge runs, one pack; model rms error {ch.fit.rms_v:.3f} V", fontsize=10)
    av.grid(alpha=0.3)
    _legend(av)
    curve = analyses.endurance_curve
    if curve:
        x = np.array([c[0] for c in curve])
        flight = np.array([c[1].flight_endurance_min for c in curve])
        pack = np.array([c[1].battery_endurance_min for c in curve])
        speeds = np.array([c[1].airspeed_m_s for c in curve])
        af.plot(x, flight, **_style("mission", linewidth=2.0),
                label=f"flight ({ch.battery.packs_in_parallel_per_engine} packs per fan, "
                "launch and landing reserve)")
        af.plot(x, pack, **_style("full_throttle", linestyle="-", linewidth=1.4),
                label="one pack on one fan, full to cut-off")
        tested_high = case.propulsion.tested_airspeed_m_s[1]
        envelope = case.requirements.envelope
        for limit, alpha, what in (
            (tested_high, 0.12, f"level flight faster than the tested {tested_high:g} m/s"),
            (
                envelope.bounds_m_s(case.density_kg_m3)[1] if envelope is not None else None,
                0.22,
                "... and beyond the envelope",
            ),
        ):
            beyond = x[speeds > limit] if limit is not None else x[:0]
            if beyond.size and beyond.min() < x.max():  # a band, not a zero-width sliver
                af.axvspan(beyond.min(), x.max(), color="0.5", alpha=alpha, linewidth=0, label=what)
        if x.size >= 2 and np.all(np.diff(speeds) > 0):
            # level-flight airspeed at each throttle (the endurance results'), on top
            # straight on past the ends: a clamped map would squeeze the axis (the axes' limits
            # reach beyond the curve)
            xe = np.concatenate([[x[0] - 1.0], x, [x[-1] + 1.0]])
            se = np.concatenate([[speeds[0] - (speeds[1] - speeds[0]) / (x[1] - x[0])], speeds,
                                 [speeds[-1] + (speeds[-1] - speeds[-2]) / (x[-1] - x[-2])]])
            top = af.secondary_xaxis(
                "top",
                functions=(lambda u: np.interp(u, xe, se), lambda w: np.interp(w, se, xe)),
            )
            from matplotlib.ticker import MaxNLocator

            # ticks inside the curve's airspeeds only (np.interp clamps beyond them)
            ticks = MaxNLocator(nbins=8).tick_values(float(speeds[0]), float(speeds[-1]))
            top.set_xticks(ticks[(ticks >= speeds[0]) & (ticks <= speeds[-1])])
            top.set_xlabel("level-flight true airspeed V (m/s)")
    best = analyses.best_endurance
    if best is not None:
        b = best.endurance
        af.plot([b.throttle], [b.flight_endurance_min], **POINT["best"],
                label=f"best endurance {b.flight_endurance_min:.1f} min at throttle "
                f"{b.throttle:.3f}, {b.airspeed_m_s:.1f} m/s")
    requirement = case.requirements.endurance
    result = analyses.endurance_at_requirement
    if requirement is not None:
        af.axhline(requirement.min_flight_time_min, **STYLE["limit"],
                   label=f"limit: flight time ≥ {requirement.min_flight_time_min:g} min")
        af.axvline(requirement.throttle, **_style("limit", linestyle=":"),
                   label=f"at the required throttle {requirement.throttle:g}")
        if result is not None:
            met = _verdict_passed(analyses, "flight_endurance")
            af.plot([requirement.throttle], [result.flight_endurance_min], **POINT["verdict"],
                    label=f"{result.flight_endurance_min:.1f} min at "
                    f"{result.airspeed_m_s:.1f} m/s ({'PASS' if met else 'FAIL'})")
    af.set_xlabel("throttle, all engines x (fraction)")
    af.set_ylabel("endurance (min)")
    af.set_title("level flight: endurance against throttle", fontsize=10)
    af.set_ylim(bottom=0)
    af.grid(alpha=0.3)
    _legend(af)
    fig.suptitle(f"Endurance of {case.name} with {flown.title}")
    return fig


# --- pages without a figure -----------------------------------------------------------------
def text_page(
    title: str, lines: list[str], size: tuple[float, float] = LANDSCAPE_IN,
    font_size: float = 7.5,
) -> Any:
    """A page of text (title page, notes); a line longer than the page is wrapped."""
    import textwrap

    fig = new_figure(size)
    _page_margins(fig)
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
