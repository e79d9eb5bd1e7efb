"""The report pages of the newer analyses: point performance, the thrust model's
confidence band, the tornado of every requirement, and the flown mission.

Each function returns one A4-landscape :class:`matplotlib.figure.Figure` drawn from
results already in :class:`tuflexperf.report.data.Analyses` (solved once by the case's
:class:`~tuflexperf.analysis.study.Study`); nothing is solved here. Styling comes from
:mod:`tuflexperf.report.style` (one colour and line style per meaning across the report;
legends outside the axes). A result that is missing or not attainable is drawn as far as
it exists, and the page says why the rest is missing, never a traceback.
"""

from __future__ import annotations

import math
import re
import textwrap
from typing import Any

import numpy as np

from tuflexperf.io.case import Case
from tuflexperf.messages import CEILING_RULE, ceiling_text
from tuflexperf.report.canvas import basis_note, new_figure, thrust_label
from tuflexperf.report.data import Analyses, Measured
from tuflexperf.report.style import (
    CYAN,
    EXTRAPOLATED_FILL,
    FAIL_FILL,
    PASS_FILL,
    PINK,
    POINT,
    STYLE,
    legend_outside,
    unit,
)

# Markers of the characteristic speeds (one shape per speed, colour per engine state).
_MARK = {
    "vy": {"marker": "D", "markersize": 8, "linestyle": "none"},
    "vx": {"marker": "^", "markersize": 9, "linestyle": "none"},
    "vmd": {"marker": "s", "markersize": 7, "linestyle": "none"},
    "vmax": {"marker": "v", "markersize": 9, "linestyle": "none"},
}
_DECREASED, _INCREASED = CYAN, PINK  # tornado: parameter lowered / raised
_SEGMENT_LINE = {"color": "0.6", "linestyle": "-", "linewidth": 0.7}
_ENGINE_DASHES = ("-", "--", ":", "-.")


def _note(ax: Any, text: str, width: int = 80) -> None:
    """A panel that says why there is nothing to draw (no ticks: not a data axes)."""
    ax.text(0.5, 0.5, textwrap.fill(text, width), transform=ax.transAxes, ha="center",
            va="center", fontsize=10, color="0.3")
    ax.set_xticks([])
    ax.set_yticks([])
    for spine in ax.spines.values():  # no frame: a long note must not seem to cross a box
        spine.set_visible(False)


def _fmt(value: float | None, unit_text: str = "", digits: int = 2) -> str:
    if value is None or not math.isfinite(value):
        return "none"
    return f"{value:.{digits}f}" + (f" {unit_text}" if unit_text else "")


def _table(ax: Any, rows: list[list[str]], columns: list[str], bbox: list[float],
           widths: list[float], font_size: float = 9.5) -> Any:
    ax.axis("off")
    table = ax.table(cellText=rows, colLabels=columns, cellLoc="left", colLoc="left",
                     bbox=bbox, colWidths=widths)
    table.auto_set_font_size(False)
    table.set_fontsize(font_size)
    for (r, _c), cell in table.get_celld().items():
        cell.set_edgecolor("0.8")
        if r == 0:
            cell.set_facecolor("0.9")
            cell.set_text_props(weight="bold")
    return table


def _verdict(analyses: Analyses, name: str) -> Any | None:
    return next((v for v in analyses.verdicts if v.name == name), None)


# --- point performance (issue 11) ------------------------------------------------------------
def performance(case: Case, analyses: Analyses) -> Any:
    """Rate of climb at full throttle against airspeed, all engines and one engine out,
    with the characteristic speeds, and a table of the ceilings and the OEI gradient."""
    fig = new_figure()
    perf = analyses.performance
    if perf is None:
        ax = fig.add_subplot()
        _note(ax, f"Point performance not attainable: {analyses.performance_note}")
        fig.suptitle(f"Point performance of {case.name}: not attainable")
        return fig
    grid = fig.add_gridspec(2, 1, height_ratios=[2.3, 1.0])
    ax = fig.add_subplot(grid[0])
    low_t, high_t = case.propulsion.tested_airspeed_m_s
    v = perf.climb_airspeed_m_s
    right = float(v[-1]) * 1.04 if v.size else 1.5 * high_t
    left = 0.85 * perf.stall_speed_m_s
    if right > high_t:
        ax.axvspan(max(high_t, left), right, color=EXTRAPOLATED_FILL, zorder=0, linewidth=0,
                   label=f"thrust model extrapolated (tested {low_t:g}-{high_t:g} m/s)")
    ax.axhline(0.0, color="black", linewidth=0.8)
    ax.plot(v, perf.climb_rate_curve_m_s, **STYLE["trim"], label="all engines, full throttle")
    worst = perf.oei_critical
    for c in perf.oei:
        if c.climb_rate_curve_m_s.size != v.size:
            continue
        critical = c is worst
        ax.plot(v, c.climb_rate_curve_m_s, **STYLE["oei" if critical else "oei_other"],
                label=f"{c.dead_engine} dead ({perf.oei_dead_engine_mode}), others full"
                + (" - worse case" if critical and len(perf.oei) > 1 else ""))
    ax.axvline(perf.stall_speed_m_s, **STYLE["stall"],
               label=f"stall speed {perf.stall_speed_m_s:.1f} m/s (TAS)")
    if perf.stall_margin != 1.0:
        ax.axvline(perf.least_airspeed_m_s, **{**STYLE["stall"], "linestyle": "-."},
                   label=f"least airspeed {perf.least_airspeed_m_s:.1f} m/s "
                   f"(stall x {perf.stall_margin:g})")
    blue, orange = STYLE["trim"]["color"], STYLE["oei"]["color"]
    ax.plot([perf.best_climb_rate_speed_m_s], [perf.max_climb_rate_m_s], **_MARK["vy"],
            color=blue, label=f"Vy {perf.best_climb_rate_speed_m_s:.1f} m/s: best rate of "
            f"climb {perf.max_climb_rate_m_s:.2f} m/s")
    vx = perf.best_climb_angle_speed_m_s
    ax.plot([vx], [perf.max_climb_gradient * vx], **_MARK["vx"], color=blue,
            label=f"Vx {vx:.1f} m/s: best climb gradient {100 * perf.max_climb_gradient:.1f} %")
    if v.size:
        vmd = perf.minimum_drag_speed_m_s
        # placed on the drawn curve (interpolation of the result's own array)
        ax.plot([vmd], [float(np.interp(vmd, v, perf.climb_rate_curve_m_s))], **_MARK["vmd"],
                color=blue, markerfacecolor="white", markeredgewidth=1.5,
                label=f"minimum-drag speed {vmd:.1f} m/s")
    if perf.max_level_speed_m_s is not None:
        ax.plot([perf.max_level_speed_m_s], [0.0], **_MARK["vmax"], color=blue,
                label=f"max level speed {perf.max_level_speed_m_s:.1f} m/s")
    if worst is not None:
        speed = worst.max_climb_gradient_speed_m_s
        ax.plot([speed], [worst.max_climb_gradient * speed], **_MARK["vx"], color=orange,
                label=f"OEI best gradient {100 * worst.max_climb_gradient:.1f} % at "
                f"{speed:.1f} m/s")
        if worst.max_level_speed_m_s is not None:
            ax.plot([worst.max_level_speed_m_s], [0.0], **_MARK["vmax"], color=orange,
                    label=f"OEI max level speed {worst.max_level_speed_m_s:.1f} m/s")
    curves = [perf.climb_rate_curve_m_s] + [c.climb_rate_curve_m_s for c in perf.oei]
    finite = np.concatenate([np.asarray(c, dtype=float).ravel() for c in curves])
    finite = finite[np.isfinite(finite)]
    if finite.size:
        span = float(finite.max() - min(finite.min(), 0.0)) or 1.0
        ax.set_ylim(min(finite.min(), 0.0) - 0.05 * span, max(finite.max(), 0.0) + 0.1 * span)
    ax.set_xlim(left, right)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("rate of climb at full throttle (m/s)")
    ax.grid(alpha=0.3)
    legend_outside(ax)
    table_ax = fig.add_subplot(grid[1])
    _performance_table(table_ax, perf)
    fig.suptitle(
        f"Point performance of {case.name} (Anderson 5.10-5.11)\n"
        f"ISA {perf.altitude_m:g} m, dT {case.atmosphere.temperature_offset_k:+g} K, "
        + unit(f"rho = {perf.density_kg_m3:.3f} kg/m^3")
    )
    return fig


def _performance_table(ax: Any, perf: Any) -> None:
    worst = perf.oei_critical
    level = ("none at full throttle" if perf.min_level_speed_m_s is None
             else f"{perf.min_level_speed_m_s:.2f}-"
             + (f"{perf.max_level_speed_m_s:.2f} m/s" if perf.max_level_speed_m_s is not None
                else "(no maximum in the model)"))
    if worst is None:
        oei_level = oei_grad = "one engine only"
    else:
        oei_level = ("no level flight" if worst.max_level_speed_m_s is None
                     else f"up to {worst.max_level_speed_m_s:.2f} m/s")
        oei_grad = (f"{100 * worst.max_climb_gradient:.1f} % at "
                    f"{worst.max_climb_gradient_speed_m_s:.2f} m/s")
    ceiling = "not reached (see notes)"
    rows = [
        ["stall speed (TAS), least airspeed",
         f"{perf.stall_speed_m_s:.2f} m/s, {perf.least_airspeed_m_s:.2f} m/s", "the same"],
        ["level flight at full throttle", level, oei_level],
        ["minimum-drag speed", f"{perf.minimum_drag_speed_m_s:.2f} m/s", ""],
        ["best rate of climb (at Vy)",
         f"{perf.max_climb_rate_m_s:.2f} m/s at {perf.best_climb_rate_speed_m_s:.2f} m/s", ""],
        ["best climb gradient (at Vx)",
         f"{100 * perf.max_climb_gradient:.1f} % at {perf.best_climb_angle_speed_m_s:.2f} m/s",
         oei_grad],
        [f"service ceiling (0.5 m/s) / absolute ceiling ({CEILING_RULE})",
         (f"{ceiling_text(perf.service_ceiling_m)} m" if perf.service_ceiling_m is not None
          else ceiling) + " / "
         + (f"{ceiling_text(perf.absolute_ceiling_m)} m" if perf.absolute_ceiling_m is not None
            else ceiling), ""],
        [f"take-off distance to the {perf.takeoff_obstacle_height_m:g} m obstacle",
         _fmt(perf.takeoff_distance_to_obstacle_m, "m", 1), ""],
    ]
    oei_head = ("one engine inoperative" if worst is None
                else f"one engine out: {worst.dead_engine} dead ({perf.oei_dead_engine_mode})")
    remarks = [*perf.notes, *perf.warnings]
    bottom = 0.0 if not remarks else 0.3
    # as wide as the plot and its legend together (the legend column is empty down here)
    _table(ax, rows, ["quantity", "all engines", oei_head], [0.0, bottom, 1.3, 1.0 - bottom],
           [0.32, 0.30, 0.38])
    if remarks:
        text = "; ".join(remarks)
        lines = textwrap.wrap("notes: " + text, 170)
        if len(lines) > 3:  # the page has room for three; the rest is in the JSON
            lines = [*lines[:2], textwrap.shorten(" ".join(lines[2:]), 140,
                                                  placeholder=" ... (all in performance --json)")]
        ax.text(0.0, bottom - 0.04, "\n".join(lines), transform=ax.transAxes, va="top",
                ha="left", fontsize=8, color="0.25")


# --- thrust model confidence band (issue 12) --------------------------------------------------
def thrust_band(case: Case, analyses: Analyses, measured: Measured | None = None) -> Any:
    """Each engine's thrust against airspeed at a few throttles with the fit's 95 % band,
    the tested airspeeds marked, the extrapolated ones shaded, and the measured points."""
    import matplotlib as mpl
    from matplotlib.patches import Patch

    fig = new_figure()
    bands = analyses.thrust_bands
    names = list(dict.fromkeys(b.engine for b in bands))
    if not bands:
        _note(fig.add_subplot(), "no thrust band: the case's propulsion has no engine")
        fig.suptitle("Thrust model confidence band: nothing to draw")
        return fig
    axes = fig.subplots(1, len(names), sharey=True, squeeze=False)[0]
    throttles = sorted({b.throttle for b in bands})
    cmap = mpl.colormaps["viridis"]
    colour = {x: cmap(0.9 * (x - 0.3) / 0.7) for x in throttles}  # as page 02's throttles
    low_t, high_t = case.propulsion.tested_airspeed_m_s
    envelope = case.requirements.envelope
    points = measured.points if measured is not None else None
    for ax, name in zip(axes, names, strict=True):
        engine = next(e for e in case.propulsion.engines if e.name == name)
        mine = [b for b in bands if b.engine == name]
        v = mine[0].airspeed_m_s
        right = float(v[-1])
        if right > high_t:
            ax.axvspan(high_t, right, color=EXTRAPOLATED_FILL, zorder=0, linewidth=0)
        if envelope is not None:
            for edge in envelope.bounds_m_s(case.density_kg_m3):
                ax.axvline(edge, **STYLE["envelope"])
        for band in mine:
            c = colour[band.throttle]
            if band.has_covariance or np.any(band.sd_n > 0):
                ax.fill_between(v, band.low_n, band.high_n, color=c, alpha=0.25, linewidth=0)
            ax.plot(v, band.thrust_n, color=c, linewidth=1.8)
            if points is not None:
                x, speed, thrust = points.select(name)
                near = np.abs(x - band.throttle) < 5e-3
                ax.plot(speed[near], thrust[near], "o", color=c, markeredgecolor="black",
                        markeredgewidth=0.6, markersize=4.5)
        full = max(mine, key=lambda b: b.throttle)
        half_width = 0.5 * (full.high_n - full.low_n)
        half = [f"\u00b1{float(np.interp(s, v, half_width)):.2f} N at {s:g} m/s"
                for s in (high_t, right) if s <= right]
        sd = [f"residual sd {engine.residual_sd_n:.2f} N"] if engine.residual_sd_n else []
        if engine.extrapolation_sd_n is not None:
            sd.append(f"extrapolation sd {engine.extrapolation_sd_n:.2f} N")
        band_text = (f"95 % band at {100 * full.throttle:.0f} % throttle:\n" + ", ".join(half)
                     if full.has_covariance else "no covariance in the propulsion file")
        ax.set_title(f"{name}" + (f": {', '.join(sd)}" if sd else "") + f"\n{band_text}",
                     fontsize=9)
        ax.set_xlim(0.0, 1.02 * right)  # the envelope's top edge stays visible
        ax.set_xlabel("airspeed V (m/s)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(thrust_label("thrust per engine T",
                                    case.propulsion.reference_density_kg_m3))
    axes[0].set_ylim(bottom=min(0.0, *(float(np.min(b.low_n)) for b in bands)))
    handles: list[Any] = []
    from matplotlib.lines import Line2D

    for x in reversed(throttles):
        handles.append(Line2D([], [], color=colour[x], linewidth=1.8,
                              label=f"model, throttle {100 * x:.0f} %"))
    if any(np.any(b.sd_n > 0) for b in bands):
        handles.append(Patch(color="0.5", alpha=0.35, linewidth=0,
                             label="95 % confidence band of the\nmodel (fit covariance, +\n"
                             "extrapolation error beyond\nthe tested range); single\n"
                             f"points scatter more (sd {_residual_text(case)})"))
    if points is not None:
        handles.append(Line2D([], [], marker="o", linestyle="none", color="0.5",
                              markeredgecolor="black", markeredgewidth=0.6,
                              label="measured (campaign points)"))
    handles.append(Patch(color=EXTRAPOLATED_FILL,
                         label=f"extrapolated: beyond the\ntested {low_t:g}-{high_t:g} m/s"))
    if envelope is not None:
        handles.append(Line2D([], [], **STYLE["envelope"],
                              label="envelope {:.4g}-{:.4g} m/s".format(
                                  *envelope.bounds_m_s(case.density_kg_m3))))
    legend_outside(axes[-1], handles=handles)
    fig.suptitle(f"Thrust model {case.propulsion.name}: 95 % confidence band over the "
                 "envelope (delta method, Montgomery & Runger 12-4)"
                 + (f"\n{basis_note(measured)}" if points is not None else ""), fontsize=11)
    return fig


def _residual_text(case: Case) -> str:
    values = [e.residual_sd_n for e in case.propulsion.engines if e.residual_sd_n is not None]
    return f"{max(values):.2f} N" if values else "not stated"


# --- tornado (issue 12) ------------------------------------------------------------------------
_KEY_UNITS = (("_m_s", "m/s"), ("_m2", "m^2"), ("_kg", "kg"), ("_m", "m"), ("_k", "K"),
              ("_s", "s"), ("_v", "V"), ("_j", "J"))


def _key_unit(key: str) -> str:
    """The unit a key's name states (``mass_kg`` -> kg), '' for dimensionless keys."""
    leaf = key.rsplit(".", 1)[-1]
    for suffix, text in _KEY_UNITS:
        if leaf.endswith(suffix):
            return unit(text)
    return ""


def _short(key: str) -> str:
    return re.sub(r"^(aircraft|atmosphere|requirements)\.", "", key)


def _limit_label(key: str, limit: tuple[Any, str, Any] | None) -> str:
    """The parameter's value where the requirement just holds, or "none in range"."""
    if limit is None or limit[0] is None:
        return "none in range"
    u = _key_unit(key)
    how = {"limit": "", "envelope ends": ", where the envelope ends",
           "aircraft refused": ", where check refuses the aircraft"}.get(
        limit[1], ", then not attainable")
    return f"{limit[0]:.4g}{(' ' + u) if u else ''}{how}"


def tornado(case: Case, analyses: Analyses) -> Any:
    """Per requirement: each parameter moved -/+ 10 % (altitude -/+ 500 m, temperature
    -/+ 10 K), bars ranked by the change of the requirement's value, each labelled with
    the parameter's value at which the requirement just holds."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from tuflexperf.report.data import margins

    fig = new_figure()
    tornadoes = margins(analyses).tornadoes
    if not tornadoes:
        _note(fig.add_subplot(), analyses.margins_note or "no requirement to vary")
        fig.suptitle(f"Tornado of {case.name}: nothing to draw")
        return fig
    n = len(tornadoes)
    # two columns at most: each panel needs room for its parameter names on the left and the
    # limit values on the right
    cols = 1 if n == 1 else 2
    rows = math.ceil(n / cols)
    # the legend has a row of its own: a figure legend "outside" is placed by the figure's
    # edge, not the layout's rectangle, and ran over the footer's strip
    grid = fig.add_gridspec(rows + 1, cols, height_ratios=[1.0] * rows + [0.1])
    axes = np.array([fig.add_subplot(grid[r, c]) for r in range(rows) for c in range(cols)])
    key = fig.add_subplot(grid[rows, :])
    key.axis("off")
    key.set_label("legend")  # no tornado panel: the page's key
    limits = analyses.limit_values or {}
    for ax, t in zip(axes, tornadoes, strict=False):
        verdict = _verdict(analyses, t.requirement)
        kind = getattr(verdict, "kind", "max")
        bars = list(t.bars)
        base = t.nominal_value
        u = unit(t.unit) if t.unit != "fraction" else ""
        head = t.requirement
        if verdict is not None:
            head += f": {'PASS' if verdict.passed else 'FAIL'}"
        head += f"\nnominal {_fmt(base, u, 3)}, limit {t.limit:g}{(' ' + u) if u else ''}"
        ax.set_title(head, fontsize=9.5)
        if not bars or base is None:
            why = ("not attainable at the nominal case: no bar to draw" if base is None
                   else "no parameter changes this requirement")
            holds = [f"{_short(k[1])} {_limit_label(k[1], v)}" for k, v in limits.items()
                     if k[0] == t.requirement and v[0] is not None]
            why += ("; it would hold at " + "; ".join(holds) if holds
                    else "; it holds at no parameter value in the searched ranges")
            _note(ax, why, 42)
            continue
        y = np.arange(len(bars))
        ends = [v for b in bars for v in (b.value_at_low, b.value_at_high) if v is not None]
        lo, hi = min([*ends, base, t.limit]), max([*ends, base, t.limit])
        pad = 0.08 * ((hi - lo) or abs(base) or 1.0)
        lo, hi = lo - pad, hi + pad
        # not attainable: a cross in a strip of its own past the bad end, inside the axes
        # (on the edge it sat half across the spine, off its axis)
        if any(v is None for b in bars for v in (b.value_at_low, b.value_at_high)):
            if kind == "max":
                missing_x, hi = hi + pad, hi + 2.0 * pad
            else:
                missing_x, lo = lo - pad, lo - 2.0 * pad
        else:
            missing_x = hi
        for i, bar in enumerate(bars):
            for value, colour in ((bar.value_at_low, _DECREASED),
                                  (bar.value_at_high, _INCREASED)):
                # lowered above raised, each half the slot (they may point the same way)
                offset = -0.19 if colour == _DECREASED else 0.19
                if value is None:
                    ax.plot([missing_x], [i + offset],
                            **{**POINT["not_attainable"], "markersize": 7})
                    continue
                ax.barh(i + offset, value - base, left=base, height=0.38, color=colour,
                        edgecolor="0.3", linewidth=0.5)
        ax.axvline(base, color="black", linewidth=0.9)
        ax.axvline(t.limit, **STYLE["limit"])
        ax.set_yticks(y, [_short(b.parameter) for b in bars], fontsize=7.5)
        ax.set_ylim(len(bars) - 0.4, -0.6)  # the largest effect on top
        # right of the bars: where the requirement just holds (margins' exact root)
        beside = ax.get_yaxis_transform()  # x in axes fractions, y in bar rows
        for i, b in enumerate(bars):
            ax.text(1.02, i, _limit_label(b.parameter, limits.get((t.requirement, b.parameter))),
                    transform=beside, ha="left", va="center", fontsize=7.5, clip_on=False)
        ax.set_xlim(lo, hi)
        ax.set_xlabel(f"{t.requirement} ({u or '-'})", fontsize=9)
        ax.tick_params(axis="x", labelsize=8)
        ax.grid(axis="x", alpha=0.3)
    for ax in axes[n:]:
        ax.set_visible(False)
    handles = [
        Patch(facecolor=_DECREASED, edgecolor="0.3", label="parameter lowered (-10 %; "
              "altitude -500 m, temperature -10 K)"),
        Patch(facecolor=_INCREASED, edgecolor="0.3", label="parameter raised (+10 %; "
              "altitude +500 m, temperature +10 K)"),
        Line2D([], [], color="black", linewidth=0.9, label="nominal value"),
        Line2D([], [], **STYLE["limit"], label="requirement limit"),
        Line2D([], [], **{**POINT["not_attainable"], "markersize": 7},
               label="not attainable there (upper: lowered, lower: raised)"),
    ]
    key.legend(handles=handles, loc="center", ncols=3, fontsize=8)
    missing = [v.name for v in analyses.verdicts
               if v.name not in {t.requirement for t in tornadoes}]
    extra = f"; not varied: {', '.join(missing)}" if missing else ""
    fig.suptitle(f"Tornado of {case.name}: each parameter -/+ 10 %, others nominal\n"
                 "right: the parameter's value at which the requirement just holds "
                 f"(others nominal){extra}", fontsize=11)
    return fig


# --- mission (issue 13) -----------------------------------------------------------------------
def mission(case: Case, analyses: Analyses) -> Any:
    """The flown mission against time: altitude, airspeed, throttle; per engine the pack
    voltage with its cut-off, the charge left with the landing reserve, and the current;
    segment boundaries numbered and tabled."""
    fig = new_figure()
    result = analyses.mission
    if result is None:
        _note(fig.add_subplot(), f"The mission could not be flown: {analyses.mission_note}")
        fig.suptitle(f"Mission of {case.name}: not attainable")
        return fig
    h = result.history
    t = np.asarray(h["time_s"], dtype=float) / 60.0
    grid = fig.add_gridspec(4, 2, height_ratios=[1.0, 1.0, 1.0, 1.05])
    left = [fig.add_subplot(grid[0, 0])]
    left += [fig.add_subplot(grid[k, 0], sharex=left[0]) for k in (1, 2)]
    right = [fig.add_subplot(grid[k, 1], sharex=left[0]) for k in (0, 1, 2)]
    table_ax = fig.add_subplot(grid[3, :])
    style = STYLE["mission"]
    alt, speed, throttle = left
    volt, charge, current = right
    alt.plot(t, h["altitude_m"], **style)
    alt.set_ylabel("height above\nthe field (m)")
    speed.plot(t, h["airspeed_eas_m_s"], **style)
    speed.set_ylabel("airspeed EAS (m/s)")
    throttle.plot(t, h["throttle"], **style)
    throttle.set_ylabel("throttle, live\nengines (fraction)")
    throttle.set_ylim(0.0, 1.08)
    throttle.axhline(1.0, **STYLE["full_throttle"])
    battery = result.cutoff_voltage_v  # flown to (a --set of it), not the file's
    for k, name in enumerate(result.engines):
        dash = _ENGINE_DASHES[k % len(_ENGINE_DASHES)]
        line = {**style, "linestyle": dash}
        volt.plot(t, h[f"voltage_v_{name}"], **line, label=f"{name}")
        charge.plot(t, h[f"charge_fraction_{name}"], **line, label=f"{name}")
        current.plot(t, h[f"current_a_{name}"], **line, label=f"{name}")
    if battery is not None:
        volt.axhline(battery, **STYLE["limit"], label=f"cut-off {battery:.1f} V")
    reserve = result.min_landing_charge_fraction
    charge.axhline(reserve, **STYLE["limit"], label=f"landing reserve {100 * reserve:g} %")
    charge.set_ylim(0.0, 1.03)
    volt.set_ylabel("pack voltage,\nloaded (V)")
    charge.set_ylabel("charge left\n(fraction)")
    current.set_ylabel("current per\nengine (A)")
    _segments(result, [*left, *right], alt, right[0])
    if not result.attainable and t.size:
        for ax, key in ((alt, "altitude_m"), (speed, "airspeed_eas_m_s"),
                        (throttle, "throttle")):
            ax.plot([t[-1]], [h[key][-1]], **POINT["not_attainable"])
    for ax in (*left, *right):
        ax.grid(alpha=0.3)
        if ax not in (throttle, current):
            ax.tick_params(labelbottom=False)
    throttle.set_xlabel("time t (min)")
    current.set_xlabel("time t (min)")
    for ax in right:
        legend_outside(ax)
    _mission_table(table_ax, result)
    verdict = _verdict(analyses, "mission_landing_charge")
    outcome = (f"lands with {100 * result.landing_charge_fraction:.1f} % charge, reserve "
               f"{100 * reserve:g} %" if result.attainable else f"NOT ATTAINABLE: {result.reason}")
    if verdict is not None:
        outcome += f" ({'PASS' if verdict.passed else 'FAIL'})"
    if result.solved is not None:
        solved = _verdict(analyses, "mission_solved_time")
        outcome += (f"; solved: longest {result.solved['segment']} "
                    f"{result.solved['time_min']:.2f} min, planned "
                    f"{result.solved['written_time_min']:.2f} min")
        if solved is not None:
            outcome += f" ({'PASS' if solved.passed else 'FAIL'})"
    fig.suptitle(textwrap.fill(f"Mission '{result.name}' of {case.name}: {outcome}", 150),
                 fontsize=11)
    return fig


def _segments(result: Any, axes: list[Any], *tops: Any) -> None:
    """Segment boundaries in every panel, their numbers above the top panels, and the
    engine failure as a one-engine-inoperative line."""
    t = np.asarray(result.history["time_s"], dtype=float) / 60.0
    seg = np.asarray(result.history["segment"], dtype=int)
    if not t.size:
        return
    starts: dict[int, float] = {}
    ends: dict[int, float] = {}
    for index in np.unique(seg[seg >= 0]):
        times = t[seg == index]
        starts[int(index)], ends[int(index)] = float(times[0]), float(times[-1])
    span = float(t[-1] - t[0]) or 1.0
    for index in sorted(starts)[1:]:
        for ax in axes:
            ax.axvline(starts[index], **_SEGMENT_LINE)
    fail = [s for s in result.segments if s.type == "engine_failure"]
    for s in fail:
        later = [starts[k] for k in starts if k > s.index]
        at = min(later) if later else float(t[-1])
        for k, ax in enumerate(axes):
            ax.axvline(at, **{**STYLE["oei"], "linestyle": "--", "linewidth": 1.3},
                       label=f"{s.dead_engine} fails" if k == len(axes) - 3 else None)
    last = -1.0
    for index in sorted(starts):
        middle = 0.5 * (starts[index] + ends[index])
        fraction = (middle - t[0]) / span
        if fraction - last < 0.03:  # two numbers would touch: the table names both
            continue
        last = fraction
        for ax in tops:
            ax.text(middle, 1.02, str(index + 1), transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=8, color="0.3")


def _mission_table(ax: Any, result: Any) -> None:
    rows = []
    for s in result.segments:
        rows.append([
            str(s.index + 1),
            s.type + (f" ({s.dead_engine} dead)" if s.type == "engine_failure" else ""),
            f"{s.time_s / 60.0:.2f}",
            f"{s.distance_m / 1000.0:.2f}",
            f"{s.start_altitude_m:.0f} -> {s.end_altitude_m:.0f}",
            "" if s.airspeed_eas_m_s is None else f"{s.airspeed_eas_m_s:.1f}",
            f"{sum(s.charge_ah):.2f}",
            f"{sum(s.energy_wh):.0f}",
            _fmt(s.min_voltage_v, "", 1),
            "" if s.max_throttle is None else f"{s.max_throttle:.2f}",
        ])
    table = _table(ax, rows, ["#", "segment", "time (min)", "distance (km)", "height (m)",
                              "EAS (m/s)", "charge, all (Ah)", "energy, all (Wh)",
                              "min voltage (V)", "max throttle"],
                   # under the legends too: that column is empty down here
                   [0.0, 0.0, 1.12, 1.0], [0.03, 0.17, 0.08, 0.1, 0.1, 0.08, 0.12, 0.12, 0.11,
                                           0.09], font_size=8)
    if not result.attainable:
        failed = result.segments[-1].index + 1 if result.segments else None
        for (r, _c), cell in table.get_celld().items():
            if r > 0 and rows[r - 1][0] == str(failed):
                cell.set_facecolor(FAIL_FILL)
    else:
        for (r, c), cell in table.get_celld().items():
            if r > 0 and c == 0:
                cell.set_facecolor(PASS_FILL)
