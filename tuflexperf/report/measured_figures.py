"""The measurement's pages: thrust surface, a run's processing, the sine sweeps, model vs measured.

Paper section 4 and Fig. 10-14: what the wind-tunnel campaign measured and how the fitted
poly22 surface and the delay-and-lag dynamics reproduce it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tuflexperf.io.case import Case
from tuflexperf.models.thrust import engine_thrust_n
from tuflexperf.report.canvas import (
    ACCURACY_GOAL_N,
    LEGEND_FONT,
    basis_note,
    basis_text,
    new_figure,
    note_box,
    style_of,
    thrust_label,
    wrap_text,
)
from tuflexperf.report.data import (
    Measured,
    ProcessedRun,
    model_dynamics,
    model_force_n,
)
from tuflexperf.report.decimate import envelope as decimated
from tuflexperf.report.style import STYLE, legend_outside


# --- 4. thrust surfaces (paper Figs. 11-12) -----------------------------------------------------
def thrust_surface(case: Case, measured: Measured, engine_index: int) -> Any:
    """One fan's poly22 surface with the measured points, and the points' residuals."""
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401 - registers the 3d projection

    propulsion = case.propulsion
    engine = propulsion.engines[engine_index]
    ref = propulsion.reference_density_kg_m3
    scale = 1.0  # the model's own basis; the measured points were scaled onto it (data.py)
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
    ax3.set_zlabel(f"thrust T (N) {basis_text(ref)}", fontsize=9)
    ax3.view_init(elev=22, azim=-130)
    ax3.set_box_aspect(None, zoom=0.88)  # as large as the z label allows
    ax_r = fig.add_subplot(grid[1])
    points = measured.points.select(engine.name) if measured.points is not None else None
    title = f"Thrust model of {engine.name}: poly22 surface"
    if points is None or points[0].size == 0:
        reason = measured.notes[0] if measured.notes else "no measured points"
        if measured.points is not None:
            reason = f"the measured data name no engine {engine.name!r}"
        note_box(ax_r, "No measured points for this engine:\n" + wrap_text(reason, 38))
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
    ax_r.set_ylabel(thrust_label("measured - model thrust", ref))
    ax_r.grid(alpha=0.3)
    span = max(float(np.max(np.abs(residual))), ACCURACY_GOAL_N)
    ax_r.set_ylim(-1.15 * span, 1.15 * span)
    legend_outside(ax_r)
    source = measured.source.name if measured.source is not None else "?"
    fig.suptitle(f"{title} with the measured points from {source} (paper Figs. 11-12)\n"
                 f"{basis_note(measured)}", fontsize=11)
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
    ax.set_ylabel(thrust_label("balance force F = T - D", run.reference_density_kg_m3))
    ax.grid(alpha=0.3)
    legend_outside(ax)
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
    """Purple for every model; the sweeps' fit (what ``fit`` writes) solid where drawn, else
    the last one with a spool lag; the propulsion file's dashed, the steps' fit dotted."""
    labels = [label for label, _, _ in dynamics]
    lagged = [k for k, (_, _, lag) in enumerate(dynamics) if lag > 0]
    main = (labels.index("sine-sweep fit") if "sine-sweep fit" in labels
            else lagged[-1] if lagged else 0)
    return [STYLE["model"] if k == main
            else style_of("model", linestyle=":", linewidth=1.5)
            if label == "throttle-step fit"
            else style_of("model", linestyle="--", linewidth=1.1)
            for k, label in enumerate(labels)]


# --- 6. sine sweep and delay (paper Figs. 13-14) ------------------------------------------------
AMPLITUDE_TOLERANCE = 0.20  # issue 47: a dynamic model off by more than this is said to be


def amplitude_verdicts(measured: Measured) -> list[tuple[str, bool, str]]:
    """Per dynamic model drawn on the sweep: (label, within the tolerance at every frequency,
    the words for the page), from :attr:`Measured.sweep_amplitude`."""
    amp = measured.sweep_amplitude
    if amp is None:
        return []
    out = []
    bands = np.isfinite(amp.measured_n)
    for (label, delay, lag), error in zip(measured.sweep_amplitude_labels, amp.error,
                                          strict=True):
        worst = int(np.nanargmax(np.where(bands, np.abs(error), -1.0)))
        ok = bool(np.all(np.abs(error[bands]) <= AMPLITUDE_TOLERANCE))
        what = f"{label} ({1000 * delay:.0f} ms dead time + {1000 * lag:.0f} ms lag)"
        if ok:
            text = (f"{what} reproduces the measured amplitude within "
                    f"{100 * AMPLITUDE_TOLERANCE:.0f} % at every frequency (worst "
                    f"{100 * error[worst]:+.0f} % at {amp.frequency_hz[worst]:g} Hz)")
        else:
            text = (f"{what} does NOT reproduce the measured amplitude within "
                    f"{100 * AMPLITUDE_TOLERANCE:.0f} %: {100 * error[worst]:+.0f} % at "
                    f"{amp.frequency_hz[worst]:g} Hz (x{1 + error[worst]:.1f})")
        out.append((label, ok, text))
    return out


def sine_sweep(measured: Measured, case: Case) -> Any:
    """Measured force of a sine sweep against each dynamic model (dead time + spool lag) as
    fitted, the whole sweep and its fastest end, and the first-harmonic amplitude per
    frequency with each model's error (issue 47 item 6)."""
    sweep = measured.sweep
    fig = new_figure()
    gs = fig.add_gridspec(4, 2, height_ratios=[2.0, 2.0, 0.9, 0.6], width_ratios=[1.4, 1.0])
    ax = fig.add_subplot(gs[0, 0])
    az = fig.add_subplot(gs[1, 0])
    ac = fig.add_subplot(gs[2, 0], sharex=az)
    aa = fig.add_subplot(gs[0:2, 1])
    at = fig.add_subplot(gs[2:4, 1])
    lax = fig.add_subplot(gs[3, 0])
    at.axis("off")
    at.set_xticks([])  # a text panel: no axis to label
    at.set_yticks([])
    lax.axis("off")
    lax.set_xticks([])  # a text panel: no axis to label
    lax.set_yticks([])
    ref = measured.reference_density_kg_m3
    t = sweep.time_s
    force = sweep.force_median_n
    dynamics = model_dynamics(case, measured, steps=True)
    styles = _model_styles(dynamics)
    models = [model_force_n(case, measured, sweep, delay, lag) for _, delay, lag in dynamics]
    # the sweep ends where the throttle last leaves the value it holds at the end of the log
    moving = np.flatnonzero(np.abs(sweep.throttle - sweep.throttle[-1]) > 0.01)
    t_end = t[moving[-1]] if moving.size else t[-1]
    end = (t >= t_end - 1.5) & (t <= t_end + 0.3)
    tw, fw = decimated(t, force)
    ax.plot(tw, fw, **STYLE["measured"], label="measured (20 ms moving median)")
    az.plot(t[end], sweep.force_n[end], **STYLE["measured_raw"], label="measured (raw)")
    az.plot(t[end], force[end], **STYLE["measured"])
    for (label, delay, lag), style, model in zip(dynamics, styles, models, strict=True):
        if model is None:
            continue
        if style is STYLE["model"]:  # the whole sweep shows the fitted model alone
            tm, fm = decimated(t, model)
            ax.plot(tm, fm, **style, zorder=1)
        lagged = f"{1000 * lag:.0f} ms lag" if lag > 0 else "no lag"
        az.plot(t[end], model[end], **style,
                label=f"model, {label}: {1000 * delay:.0f} ms dead time + {lagged}")
    if all(m is None for m in models):
        ax.set_title(f"whole sweep ({sweep.file}); the case's propulsion has no engine "
                     f"{sweep.engine!r}: no model drawn", fontsize=9)
    else:
        ax.set_title(f"whole sweep ({sweep.file}): measured and the solid model", fontsize=9)
    ax.set_xlabel("time t (s)")
    ax.set_ylabel(thrust_label("balance force F = T - D", ref), fontsize=8)
    ax.grid(alpha=0.3)
    az.set_ylabel(thrust_label("balance force F", ref), fontsize=8)
    az.set_title("end of the sweep (highest frequency)", fontsize=9)
    az.grid(alpha=0.3)
    az.tick_params(labelbottom=False)
    ac.plot(t[end], sweep.throttle[end], **STYLE["command"], label="throttle command")
    ac.set_xlabel("time t (s)")
    ac.set_ylabel("throttle x\n(fraction)", fontsize=8)
    ac.grid(alpha=0.3)
    _amplitude_panel(aa, at, measured, styles)
    handles: dict[str, Any] = {}
    for a in (ax, az, ac):
        handles.update(zip(*reversed(a.get_legend_handles_labels()), strict=True))
    lax.legend(list(handles.values()), list(handles.keys()), loc="center", ncols=2,
               fontsize=7, frameon=False)
    parts = [f"this sweep: {1000 * sweep.delay_s:.0f} ms + {1000 * sweep.lag_s:.0f} ms"
             if math.isfinite(sweep.delay_s) else "this sweep: delay not estimated"]
    parts += [f"{label}: {1000 * delay:.0f} ms + {1000 * lag:.0f} ms"
              for label, delay, lag in dynamics]
    fig.suptitle(
        f"Sine sweep of {sweep.engine} at {sweep.airspeed_m_s:.1f} m/s: measured force against "
        "each dynamic model (dead time + spool lag) as fitted (paper Figs. 13-14)\n"
        + "; ".join(parts), fontsize=11,
    )
    return fig


def _amplitude_panel(aa: Any, at: Any, measured: Measured, styles: list[dict[str, Any]]) -> None:
    """First-harmonic amplitude against frequency, measured and per model, and the verdict
    of each model against the 20 % tolerance, in words (red where it fails)."""
    amp = measured.sweep_amplitude
    if amp is None:
        note_box(aa, "no amplitude: the case's propulsion has no model of this engine")
        return
    bands = np.isfinite(amp.measured_n)
    f = amp.frequency_hz
    aa.plot(f[bands], amp.measured_n[bands], "o-", color=STYLE["measured"]["color"],
            label="measured")
    aa.fill_between(f[bands], (1 - AMPLITUDE_TOLERANCE) * amp.measured_n[bands],
                    (1 + AMPLITUDE_TOLERANCE) * amp.measured_n[bands],
                    color=STYLE["measured"]["color"], alpha=0.12, linewidth=0,
                    label=f"measured \u00b1{100 * AMPLITUDE_TOLERANCE:.0f} %")
    for (label, _, _), style, values in zip(measured.sweep_amplitude_labels, styles,
                                            amp.model_n, strict=True):
        aa.plot(f[bands], values[bands], marker="s", markersize=3.5, **style, label=label)
    aa.set_xlabel("sweep frequency f (Hz)")
    aa.set_ylabel("first-harmonic force amplitude (N)", fontsize=9)
    aa.set_ylim(bottom=0.0)
    aa.grid(alpha=0.3)
    aa.set_title("amplitude per frequency", fontsize=9)
    aa.legend(loc="lower left", fontsize=7)
    rows = ["f (Hz)       " + "".join(f"{x:>5g} " for x in f[bands])]
    for (label, _, _), error in zip(measured.sweep_amplitude_labels, amp.error, strict=True):
        short = label.replace(" fit", "").replace("propulsion file", "prop. file")
        rows.append(f"{short:<13}" + "".join(f"{100 * e:>+5.0f}%" for e in error[bands]))
    blocks = [("amplitude error, model / measured - 1:\n" + "\n".join(rows), "black", True)]
    blocks += [(wrap_text(text, 58), "0.2" if ok else "#c62828", False)
               for _, ok, text in amplitude_verdicts(measured)]
    down = 0.0  # points below the panel's top: each block under the one before
    for text, colour, mono in blocks:
        at.annotate(text, xy=(0.0, 1.0), xycoords="axes fraction", xytext=(0.0, -down),
                    textcoords="offset points", va="top", ha="left", fontsize=7,
                    color=colour, family="monospace" if mono else None,
                    weight="normal" if colour != "#c62828" else "bold")
        down += 8.6 * (text.count("\n") + 1) + 4.0


# --- 7. model against measured force (paper Figs. 16-17) ----------------------------------------
def model_vs_measured(case: Case, measured: Measured) -> Any:
    """The case's thrust model driven by the logged throttle against the measured force."""
    runs = measured.comparisons
    fig = new_figure()
    gs = fig.add_gridspec(3, len(runs), height_ratios=[3, 1, 0.32])
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
        ax.set_ylabel(thrust_label("balance force F = T - D", measured.reference_density_kg_m3))
        ax.grid(alpha=0.3)
        ax.tick_params(labelbottom=False)
        ae.set_xlabel("time t (s)")
        ae.set_ylabel("model - measured F (N)")
        ae.grid(alpha=0.3)
        models = [model_force_n(case, measured, run, delay, lag) for _, delay, lag in dynamics]
        if models[0] is None:
            note_box(ae, f"the case's propulsion has no engine {run.engine!r}")
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
    # one legend for both columns, below them in a row of its own: it covers no trace, and
    # the footer's strip stays free (a figure legend sat on the footer)
    lax = fig.add_subplot(gs[2, :])
    lax.axis("off")
    lax.set_xticks([])  # a text panel: no axis to label
    lax.set_yticks([])
    lax.legend(list(handles.values()), list(handles.keys()), loc="center", ncols=3,
               fontsize=LEGEND_FONT, frameon=False)
    fig.suptitle(
        "Thrust model driven by the logged throttle against the measured force "
        f"(paper Figs. 16-17)\nerror panels clipped at ±3 N; {basis_note(measured)}",
        fontsize=11,
    )
    return fig
