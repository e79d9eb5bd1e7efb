"""The report's figures, one function each, drawn from :mod:`tuflexperf.report.data`.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot
(no global figure state; the Agg canvas renders it headless). Axes carry SI units,
titles say what is shown and which of the paper's figures it corresponds to,
requirement limits are drawn where one applies, and the thrust model's
extrapolated airspeeds (beyond ``tested_airspeed_m_s``) are shaded.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import level_flight_drag_n, stall_speed_m_s
from tuflexperf.models.thrust import density_ratio, engine_thrust_n, total_thrust_n
from tuflexperf.report.data import Analyses, Measured, ProcessedRun

LANDSCAPE_IN = (11.69, 8.27)  # A4 landscape (297 x 210 mm)
PASS_COLOUR = "#c8e6c9"
FAIL_COLOUR = "#ffcdd2"
LIMIT_COLOUR = "#c62828"
EXTRAPOLATED_COLOUR = "0.88"
ACCURACY_GOAL_N = 0.5  # paper section 1 and 2.1: model accuracy aimed for +-0.5 N


def use_agg() -> None:
    """Select the headless Agg backend before anything imports pyplot."""
    import matplotlib

    matplotlib.use("Agg")


def new_figure(size: tuple[float, float] = LANDSCAPE_IN) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def _shade_extrapolated(ax: Any, case: Case, right: float, label: bool = True) -> None:
    """Grey band over airspeeds beyond the thrust model's tested range."""
    low, high = case.propulsion.tested_airspeed_m_s
    if right > high:
        ax.axvspan(
            high,
            right,
            color=EXTRAPOLATED_COLOUR,
            zorder=0,
            label=f"thrust model extrapolated (tested {low:g}-{high:g} m/s)" if label else None,
        )


def _envelope_lines(ax: Any, case: Case) -> None:
    envelope = case.requirements.envelope
    if envelope is None:
        return
    for k, v in enumerate((envelope.min_airspeed_m_s, envelope.max_airspeed_m_s)):
        ax.axvline(
            v,
            color=LIMIT_COLOUR,
            linestyle="--",
            linewidth=1.2,
            label=(
                f"envelope {envelope.min_airspeed_m_s:g}-{envelope.max_airspeed_m_s:g} m/s"
                if k == 0
                else None
            ),
        )


def _max_airspeed(case: Case) -> float:
    envelope = case.requirements.envelope
    top = case.propulsion.tested_airspeed_m_s[1]
    if envelope is not None:
        top = max(top, envelope.max_airspeed_m_s)
    return 1.05 * top


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


# --- 2. requirement table -----------------------------------------------------------------------
def requirement_table(case: Case, analyses: Analyses) -> Any:
    """The verdicts of ``check``: value, limit, margin, PASS/FAIL, colour-coded."""
    fig = new_figure()
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
            v.unit,
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
                cell.set_facecolor(PASS_COLOUR if verdicts[r - 1].passed else FAIL_COLOUR)
    lines = [
        "Margin: positive when met (limit - value for a maximum, value - limit for a minimum)."
    ]
    for v in verdicts:
        lines.append(f"{v.name}: {v.reason}")
        lines.extend(f"    note: {w}" for w in v.details.get("warnings", []))
    ax.text(
        0.0,
        0.5,
        "\n".join(lines),
        transform=ax.transAxes,
        va="top",
        ha="left",
        fontsize=9,
        family="monospace",
        wrap=True,
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
    cmap = mpl.colormaps["viridis"]
    throttles = np.round(np.arange(0.3, 1.0001, 0.1), 2)
    for k, x in enumerate(throttles):
        t = np.asarray(total_thrust_n(propulsion, float(x), v, rho), dtype=float)
        colour = cmap(0.9 * (x - 0.3) / 0.7)
        ax.plot(
            v,
            t,
            color=colour,
            linewidth=1.0,
            label="available, all engines (throttle at the line's end)" if k == 0 else None,
        )
        # label each line where it ends (or where it leaves the plot at zero thrust)
        inside = np.flatnonzero(t >= 0.0)
        if inside.size:
            j = inside[-1]
            ax.annotate(
                f"{100 * x:.0f} %",
                (v[j], t[j]),
                textcoords="offset points",
                xytext=(2, 2),
                fontsize=8,
                color=colour,
                ha="right" if j < v.size - 1 else "left",
                va="bottom",
            )
    stall = float(stall_speed_m_s(aircraft, rho))
    vd = v[v >= stall]
    drag = np.asarray(level_flight_drag_n(aircraft, vd, rho), dtype=float)
    ax.plot(vd, drag, color="black", linewidth=2.5, label="required (level-flight drag)")
    ax.axvline(stall, color="0.4", linestyle=":", label=f"stall speed {stall:.1f} m/s")
    trim = analyses.trim
    if trim is not None and trim.min_throttle is not None:
        x = trim.min_throttle
        t = np.asarray(total_thrust_n(propulsion, x, v, rho), dtype=float)
        ax.plot(
            v,
            t,
            color="tab:blue",
            linewidth=2.2,
            linestyle="-.",
            label=f"least trim throttle {100 * x:.1f} % (all engines)",
        )
        va = trim.airspeed_at_min_throttle_m_s
        ax.plot([va], [float(level_flight_drag_n(aircraft, va, rho))], "o", color="tab:blue")
    oei = analyses.oei
    if oei is not None:
        worst = oei.critical
        index = [e.name for e in propulsion.engines].index(worst.dead_engine)
        full = np.asarray(
            total_thrust_n(propulsion, 1.0, v, rho, index, oei.dead_engine_mode), dtype=float
        )
        ax.plot(
            v,
            full,
            color="tab:red",
            linewidth=2.0,
            label=f"OEI: {worst.dead_engine} dead ({oei.dead_engine_mode}), others 100 %",
        )
        if worst.min_throttle is not None:
            x = worst.min_throttle
            t = np.asarray(
                total_thrust_n(propulsion, x, v, rho, index, oei.dead_engine_mode), dtype=float
            )
            ax.plot(
                v,
                t,
                color="tab:red",
                linewidth=2.0,
                linestyle="-.",
                label=f"OEI least throttle {100 * x:.1f} %",
            )
            va = worst.airspeed_at_min_throttle_m_s
            ax.plot([va], [float(level_flight_drag_n(aircraft, va, rho))], "o", color="tab:red")
    _envelope_lines(ax, case)
    ax.set_xlim(0, right)
    top = 1.3 * float(np.max(total_thrust_n(propulsion, 1.0, v, rho)))  # room for the legend
    if drag.size:
        top = max(top, 1.1 * float(drag.max()))
    ax.set_ylim(0, top)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("thrust, drag (N)")
    fig.suptitle(
        "Required and available thrust in level flight (paper Fig. 18)\n"
        f"{case.name}, rho = {rho:.3f} kg/m³"
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right", ncols=2, framealpha=0.95)
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
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax3.plot_surface(xx, vv, tt, cmap="viridis", alpha=0.75, linewidth=0, antialiased=True)
    ax3.set_xlabel("throttle (fraction)")
    ax3.set_ylabel("airspeed V (m/s)")
    ax3.set_zlabel("thrust T (N)")
    ax3.view_init(elev=22, azim=-130)
    ax3.set_box_aspect(None, zoom=0.85)  # room for the z label
    ax_r = fig.add_subplot(1, 2, 2)
    points = measured.points.select(engine.name) if measured.points is not None else None
    title = f"Thrust model of {engine.name}: poly22 surface"
    if points is None or points[0].size == 0:
        reason = measured.notes[0] if measured.notes else "no measured points"
        if measured.points is not None:
            reason = f"the measured data name no engine {engine.name!r}"
        _note(ax_r, "No measured points for this engine:\n" + _wrap(reason, 60))
        ax3.set_title(title + " (model alone)")
        fig.suptitle(f"{title}; no measured data to compare (paper Figs. 11-12)")
        return fig
    px, pv, pt = points
    model = np.asarray(engine_thrust_n(engine, px, pv, scale), dtype=float)
    residual = pt - model
    ax3.scatter(px, pv, pt, color="red", s=14, depthshade=False, label="measured (segment means)")
    ax3.legend(loc="upper left", fontsize=8)
    ax3.set_title("surface and measured points")
    sc = ax_r.scatter(px, residual, c=pv, cmap="plasma", s=22)
    fig.colorbar(sc, ax=ax_r, label="airspeed V (m/s)")
    ax_r.axhline(0.0, color="black", linewidth=0.8)
    for sign in (-1, 1):
        ax_r.axhline(
            sign * ACCURACY_GOAL_N,
            color=LIMIT_COLOUR,
            linestyle="--",
            label="accuracy goal +-0.5 N (paper)" if sign > 0 else None,
        )
    rmse = float(np.sqrt(np.mean(residual**2)))
    sst = float(np.sum((pt - pt.mean()) ** 2))
    r2 = 1.0 - float(np.sum(residual**2)) / sst if sst > 0 else math.nan
    text = f"against this model: R^2 = {r2:.5f}, RMSE = {rmse:.3f} N, n = {pt.size}"
    refit = _refit(measured, engine.name)
    if refit is not None:
        text += (
            f"\ncampaign re-fit (tuflexperf fit): R^2 = {refit['r2']:.5f}, "
            f"RMSE = {refit['rmse_n']:.3f} N"
        )
    ax_r.text(
        0.02,
        0.02,
        text,
        transform=ax_r.transAxes,
        fontsize=8,
        va="bottom",
        bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.7"},
    )
    ax_r.set_xlabel("throttle (fraction)")
    ax_r.set_ylabel("measured - model thrust (N)")
    ax_r.set_title("residuals of the measured points")
    ax_r.grid(alpha=0.3)
    ax_r.legend(fontsize=8, loc="upper right")
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


def _wrap(text: str, width: int) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width))


# --- 5. one run, raw and processed (paper Fig. 10) ----------------------------------------------
def run_processing(run: ProcessedRun) -> Any:
    """Raw and cleaned force of one throttle-step run, change points and steady segment means."""
    fig = new_figure()
    gs = fig.add_gridspec(2, 1, height_ratios=[3, 1])
    ax = fig.add_subplot(gs[0])
    axt = fig.add_subplot(gs[1], sharex=ax)
    t = run.time_s
    ax.plot(t, run.force_raw_n, color="0.7", linewidth=0.4, label="raw force")
    ax.plot(
        t,
        run.force_clean_n,
        color="tab:blue",
        linewidth=1.0,
        label=f"processed (outliers filled: {run.outliers_replaced}, moving median)",
    )
    for k, (start, stop, mean) in enumerate(run.segments):
        ax.plot(
            [t[start], t[stop - 1]],
            [mean, mean],
            color="tab:red",
            linewidth=3,
            solid_capstyle="butt",
            label="steady segment mean" if k == 0 else None,
        )
    for k, c in enumerate(run.changepoints):
        ax.axvline(
            t[c],
            color="tab:green",
            linestyle=":",
            linewidth=0.9,
            label="detected change point" if k == 0 else None,
        )
    ax.set_ylabel("balance force (N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    ax.tick_params(labelbottom=False)
    axt.plot(t, run.throttle, color="black", linewidth=1.0, label="throttle command")
    axt.set_ylabel("throttle (fraction)")
    axt.set_xlabel("time t (s)")
    axt.grid(alpha=0.3)
    fig.suptitle(
        f"{run.engine} at {run.mean_airspeed_m_s:.1f} m/s ({run.file}): raw and processed "
        f"force, {len(run.changepoints)} change points, {len(run.segments)} steady segments "
        "(paper Fig. 10)"
    )
    return fig


# --- 6. sine sweep and delay (paper Figs. 13-14) ------------------------------------------------
def sine_sweep(measured: Measured) -> Any:
    """Normalised throttle and force of a sine sweep, and its end with the measured delay."""
    from tuflexperf.reduction.filters import movmedian, window_samples

    sweep = measured.sweep
    fig = new_figure()
    ax = fig.add_subplot(2, 1, 1)
    az = fig.add_subplot(2, 1, 2)
    t = sweep.time_s
    rate = (t.size - 1) / (t[-1] - t[0])
    # a 20 ms moving median takes the balance's spikes out without shifting the phase
    force = movmedian(sweep.force_n, window_samples(0.02, rate) | 1)
    x = sweep.throttle / np.max(np.abs(sweep.throttle))
    f = force / np.max(np.abs(force))
    ax.plot(t, f, color="tab:orange", linewidth=0.5, label="force / max force (20 ms median)")
    ax.plot(t, x, color="black", linewidth=0.7, label="throttle / max throttle")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("normalised (-)")
    ax.set_title(f"whole sweep ({sweep.file})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))  # off the traces
    # the sweep ends where the throttle last leaves the value it holds at the end of the log
    moving = np.flatnonzero(np.abs(sweep.throttle - sweep.throttle[-1]) > 0.01)
    t_end = t[moving[-1]] if moving.size else t[-1]
    end = (t >= t_end - 1.5) & (t <= t_end + 0.3)
    az.plot(t[end], f[end], color="tab:orange", linewidth=0.8, label="force / max force")
    az.plot(t[end], x[end], color="black", linewidth=1.0, label="throttle / max throttle")
    if math.isfinite(sweep.delay_s):
        from scipy.signal import lfilter

        from tuflexperf.models.thrust import lag_factor

        # the dynamic model as fitted: dead time, then the first-order spool lag (exact
        # discretisation, the exports' recursion), driven by the logged throttle
        delayed = np.interp(t - sweep.delay_s, t, x)
        lag = sweep.lag_s if math.isfinite(sweep.lag_s) else 0.0
        a = lag_factor(lag, 1.0 / rate)
        modelled = lfilter([1.0 - a], [1.0, -a], delayed, zi=[a * delayed[0]])[0]
        az.plot(
            t[end],
            modelled[end],
            color="tab:blue",
            linestyle="--",
            linewidth=1.2,
            label=f"model: throttle after {1000 * sweep.delay_s:.0f} ms dead time and "
            f"{1000 * lag:.0f} ms spool lag",
        )
    az.set_xlabel("time t (s)")
    az.set_ylabel("normalised (-)")
    az.set_title(
        "end of the sweep (highest frequency): the force lags by the dead time plus "
        "the fan's spool lag"
    )
    az.grid(alpha=0.3)
    # below the axes: inside, it would cover the traces it explains
    az.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncols=3)
    delay = (
        f"dead time {1000 * sweep.delay_s:.0f} ms, spool lag {1000 * sweep.lag_s:.0f} ms"
        if math.isfinite(sweep.delay_s)
        else "delay not estimated"
    )
    model = measured.fit_summary.get("delay_s") if measured.fit_summary else None
    if model is not None:
        delay += f"; campaign mean delay {1000 * model:.0f} ms"
    fig.suptitle(
        f"Sine sweep of {sweep.engine} at {sweep.airspeed_m_s:.1f} m/s, normalised by each "
        f"maximum (paper Figs. 13-14)\n{delay}"
    )
    return fig


# --- 7. model against measured force (paper Figs. 16-17) ----------------------------------------
def model_force_n(case: Case, measured: Measured, run: ProcessedRun) -> np.ndarray | None:
    """The model's balance force over a run: ``T(x(t - d), V(t)) - D_structure(V(t))`` in N.

    ``d`` is the propulsion model's delay, ``D`` the structure drag fitted from the
    campaign (the paper compared a model "without the drag correction", section 4).
    """
    names = [e.name for e in case.propulsion.engines]
    if run.engine not in names:
        return None
    engine = case.propulsion.engines[names.index(run.engine)]
    rho = measured.density_kg_m3
    scale = 1.0 if rho is None else float(density_ratio(case.propulsion, rho))
    t = run.time_s
    x = np.interp(t - case.propulsion.delay_s, t, run.throttle)
    force = np.asarray(engine_thrust_n(engine, x, run.airspeed_m_s, scale), dtype=float)
    if measured.drag_c1_c2 is not None:
        c1, c2 = measured.drag_c1_c2
        force = force - (c1 * run.airspeed_m_s + c2 * run.airspeed_m_s**2)
    return force


def model_vs_measured(case: Case, measured: Measured) -> Any:
    """The case's thrust model driven by the logged throttle against the measured force."""
    runs = measured.comparisons
    fig = new_figure()
    gs = fig.add_gridspec(2, len(runs), height_ratios=[3, 1])
    for k, run in enumerate(runs):
        ax = fig.add_subplot(gs[0, k])
        ae = fig.add_subplot(gs[1, k], sharex=ax)
        model = model_force_n(case, measured, run)
        t = run.time_s
        ax.plot(t, run.force_raw_n, color="0.75", linewidth=0.4, label="measured (raw)")
        ax.plot(t, run.force_clean_n, color="tab:blue", linewidth=1.0, label="measured (processed)")
        ax.set_title(f"{run.engine} at {run.mean_airspeed_m_s:.1f} m/s ({run.file})", fontsize=10)
        ax.set_ylabel("balance force (N)")
        ax.grid(alpha=0.3)
        ax.tick_params(labelbottom=False)
        ae.set_xlabel("time t (s)")
        ae.set_ylabel("model - measured (N)")
        ae.grid(alpha=0.3)
        if model is None:
            _note(ae, f"the case's propulsion has no engine {run.engine!r}")
            ax.legend(fontsize=8)
            continue
        ax.plot(
            t,
            model,
            color="tab:red",
            linewidth=1.2,
            label=f"model (delay {1000 * case.propulsion.delay_s:.0f} ms, minus structure drag)",
        )
        ax.legend(fontsize=8, loc="upper right")
        error = model - run.force_clean_n
        steady = np.zeros(t.size, dtype=bool)
        for start, stop, _ in run.segments:
            steady[start:stop] = True
        ae.plot(t, error, color="tab:red", linewidth=0.6)
        for sign in (-1, 1):
            ae.axhline(sign * ACCURACY_GOAL_N, color=LIMIT_COLOUR, linestyle="--", linewidth=0.9)
        e = error[steady]
        neg = e[e < 0].mean() if np.any(e < 0) else 0.0
        pos = e[e > 0].mean() if np.any(e > 0) else 0.0
        ae.text(
            0.01,
            0.95,
            f"steady segments: mean error {neg:+.2f} / {pos:+.2f} N; dashed: +-0.5 N goal",
            transform=ae.transAxes,
            fontsize=8,
            va="top",
        )
        ae.set_ylim(-3, 3)
    fig.suptitle(
        "Thrust model driven by the logged throttle against the measured force (paper Figs. 16-17)"
    )
    return fig


# --- 8. take-off ----------------------------------------------------------------------------
def _verdict_passed(analyses: Analyses, name: str) -> bool:
    """PASS/FAIL as ``check`` decided it (analysis/requirements.py), never re-judged here."""
    return any(v.name == name and v.passed for v in analyses.verdicts)


def takeoff_history(case: Case, analyses: Analyses) -> Any:
    """Ground roll at full throttle: airspeed and distance against time, runway limit."""
    fig = new_figure()
    av = fig.add_subplot(1, 2, 1)
    ad = fig.add_subplot(1, 2, 2)
    result = analyses.takeoff
    if result is None:
        from tuflexperf.analysis.takeoff import net_force_n
        from tuflexperf.models.aircraft import liftoff_speed_m_s

        _note(av, _wrap(f"take-off not attainable: {analyses.takeoff_note}", 50))
        rho = case.density_kg_m3
        v_lo = float(liftoff_speed_m_s(case.aircraft, rho))
        v = np.linspace(0.0, 1.05 * v_lo, 300)
        force = np.asarray(net_force_n(case.aircraft, case.propulsion, v, rho), dtype=float)
        ad.plot(v, force, color="tab:blue", label="accelerating force at full throttle")
        ad.axhline(0.0, color="black", linewidth=0.8)
        ad.axvline(v_lo, color=LIMIT_COLOUR, linestyle="--", label=f"lift-off speed {v_lo:.1f} m/s")
        ad.set_xlabel("airspeed V (m/s)")
        ad.set_ylabel("net force on the runway (N)")
        ad.set_title("why: the net force on the runway")
        ad.grid(alpha=0.3)
        ad.legend(fontsize=8)
        fig.suptitle(f"Take-off of {case.name}: not attainable")
        return fig
    t = result.history_time_s
    high = case.propulsion.tested_airspeed_m_s[1]
    av.plot(t, result.history_airspeed_m_s, color="tab:blue", label="airspeed")
    av.axhline(
        result.liftoff_speed_m_s,
        color="black",
        linestyle=":",
        label=f"lift-off speed {result.liftoff_speed_m_s:.1f} m/s",
    )
    if result.liftoff_speed_m_s > high:
        av.axhspan(
            high,
            result.liftoff_speed_m_s * 1.05,
            color=EXTRAPOLATED_COLOUR,
            zorder=0,
            label="thrust model extrapolated",
        )
    av.set_xlabel("time t (s)")
    av.set_ylabel("airspeed V (m/s)")
    av.set_title("airspeed")
    av.grid(alpha=0.3)
    av.legend(fontsize=8, loc="lower right")
    ad.plot(t, result.history_distance_m, color="tab:blue", label="distance rolled")
    ad.plot(
        [result.time_s],
        [result.ground_roll_m],
        "o",
        color="tab:blue",
        label=f"lift-off: {result.ground_roll_m:.1f} m after {result.time_s:.1f} s",
    )
    requirement = case.requirements.takeoff
    if requirement is not None:
        limit = requirement.max_ground_roll_m
        met = _verdict_passed(analyses, "takeoff_ground_roll")
        ad.axhline(
            limit,
            color=LIMIT_COLOUR,
            linestyle="--",
            label=f"runway limit {limit:g} m ({'PASS' if met else 'FAIL'})",
        )
        ad.set_ylim(0, 1.1 * max(limit, result.ground_roll_m))
    ad.set_xlabel("time t (s)")
    ad.set_ylabel("ground roll distance s (m)")
    ad.set_title("distance")
    ad.grid(alpha=0.3)
    ad.legend(fontsize=8, loc="upper left")
    fig.suptitle(
        f"Take-off of {case.name} at full throttle: ground roll {result.ground_roll_m:.1f} m "
        f"to lift-off at {result.liftoff_speed_m_s:.1f} m/s"
    )
    return fig


# --- 9. trim and OEI throttle -----------------------------------------------------------------
def trim_oei_throttle(case: Case, analyses: Analyses) -> Any:
    """Least level-flight throttle against airspeed, all engines and one engine out."""
    fig = new_figure()
    ax = fig.add_subplot()
    trim, oei = analyses.trim, analyses.oei
    right = _max_airspeed(case)
    _shade_extrapolated(ax, case, right)
    envelope = case.requirements.envelope
    ax.plot(
        trim.airspeed_m_s, trim.throttle, color="tab:blue", linewidth=2, label="trim, all engines"
    )
    if trim.min_throttle is not None:
        ax.plot([trim.airspeed_at_min_throttle_m_s], [trim.min_throttle], "o", color="tab:blue")
        ax.annotate(
            f"least {100 * trim.min_throttle:.1f} %",
            (trim.airspeed_at_min_throttle_m_s, trim.min_throttle),
            textcoords="offset points",
            xytext=(8, -14),
            color="tab:blue",
        )
    if trim.max_throttle is not None:
        k = int(np.argmax(trim.throttle))
        ax.plot([trim.airspeed_m_s[k]], [trim.max_throttle], "s", color="tab:blue")
        ax.annotate(
            f"highest {100 * trim.max_throttle:.1f} % (the verdict)",
            (trim.airspeed_m_s[k], trim.max_throttle),
            textcoords="offset points",
            xytext=(-10, -16),
            ha="right",
            color="tab:blue",
        )
    ax.axhline(
        envelope.max_trim_throttle,
        color=LIMIT_COLOUR,
        linestyle="--",
        label=f"max trim throttle {envelope.max_trim_throttle:g}",
    )
    styles = ["-", "--", ":", "-."]
    if oei is not None:
        for k, c in enumerate(oei.cases):
            critical = c is oei.critical
            ax.plot(
                c.airspeed_m_s,
                c.throttle,
                color="tab:red",
                linestyle=styles[k % 4],
                linewidth=2 if critical else 1.2,
                label=f"OEI, {c.dead_engine} dead ({oei.dead_engine_mode})"
                + (" - worse case" if critical else ""),
            )
        worst = oei.critical
        missing = ~np.isfinite(worst.throttle)
        if missing.any():
            ax.plot(
                worst.airspeed_m_s[missing],
                np.ones(int(missing.sum())),
                "x",
                color="tab:red",
                label=f"OEI ({worst.dead_engine} dead) not attainable: needs > full throttle",
            )
        if worst.min_throttle is not None:
            ax.plot(
                [worst.airspeed_at_min_throttle_m_s], [worst.min_throttle], "o", color="tab:red"
            )
            ax.annotate(
                f"least {100 * worst.min_throttle:.1f} %",
                (worst.airspeed_at_min_throttle_m_s, worst.min_throttle),
                textcoords="offset points",
                xytext=(8, 8),
                color="tab:red",
            )
        requirement = case.requirements.oei
        if (
            requirement is not None
            and abs(requirement.max_throttle - envelope.max_trim_throttle) > 1e-9
        ):
            ax.axhline(
                requirement.max_throttle,
                color=LIMIT_COLOUR,
                linestyle=":",
                label=f"OEI max throttle {requirement.max_throttle:g}",
            )
    bad = trim.unattainable_airspeed_m_s
    if bad:
        ax.axvspan(
            min(bad),
            max(bad),
            color=FAIL_COLOUR,
            alpha=0.6,
            zorder=0,
            label="trim not attainable (> full throttle)",
        )
    _envelope_lines(ax, case)
    ax.set_xlim(0, right)
    ax.set_ylim(0, 1.08)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("least throttle for level flight (fraction)")
    ax.set_title(f"Trim and one-engine-inoperative throttle over the envelope, {case.name}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    return fig


# --- 10. endurance --------------------------------------------------------------------------
def endurance(case: Case, analyses: Analyses) -> Any:
    """Pack voltage of the discharge runs, model and data; flight time against throttle."""
    from tuflexperf.models.battery import terminal_voltage_v

    ch = analyses.characterisation
    fig = new_figure()
    av = fig.add_subplot(1, 2, 1)
    af = fig.add_subplot(1, 2, 2)
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:purple"]
    for k, run in enumerate(ch.discharge_runs()):
        colour = colours[k % len(colours)]
        minutes = (run.time_s - run.time_s[0]) / 60.0
        model = np.asarray(
            terminal_voltage_v(ch.fit.parameters, run.charge_ah, run.current_a), dtype=float
        )
        label = f"{run.path.name} (throttle {run.throttle_setting:.2f})"
        av.plot(
            minutes, run.voltage_v, color=colour, linewidth=3.0, alpha=0.35, label=f"data: {label}"
        )
        av.plot(
            minutes,
            model,
            color="black",
            linestyle="--",
            linewidth=0.9,
            label="model (fitted equivalent circuit)" if k == 0 else None,
        )
    av.axhline(
        ch.battery.cutoff_voltage_v,
        color=LIMIT_COLOUR,
        linestyle="--",
        label=f"cut-off {ch.battery.cutoff_voltage_v:.1f} V",
    )
    av.set_xlabel("time t (min)")
    av.set_ylabel("pack terminal voltage (V)")
    av.set_title(f"discharge runs, one pack; model rms error {ch.fit.rms_v:.3f} V", fontsize=10)
    av.grid(alpha=0.3)
    av.legend(fontsize=7, loc="upper right")
    curve = analyses.endurance_curve
    if curve:
        x = np.array([c[0] for c in curve])
        flight = np.array([c[1].flight_endurance_min for c in curve])
        pack = np.array([c[1].battery_endurance_min for c in curve])
        af.plot(
            x,
            flight,
            "o-",
            color="tab:blue",
            markersize=3,
            label=f"flight ({ch.battery.packs_in_parallel_per_engine} packs per fan, "
            "launch and landing reserve)",
        )
        af.plot(
            x,
            pack,
            "s-",
            color="tab:gray",
            markersize=3,
            label="one pack on one fan, full to cut-off",
        )
        speeds = np.array([c[1].airspeed_m_s for c in curve])
        tested_high = case.propulsion.tested_airspeed_m_s[1]
        envelope = case.requirements.envelope
        for limit, alpha, what in (
            (tested_high, 0.12, f"level flight faster than the tested {tested_high:g} m/s"),
            (
                envelope.max_airspeed_m_s if envelope is not None else None,
                0.22,
                "... and beyond the envelope",
            ),
        ):
            beyond = x[speeds > limit] if limit is not None else x[:0]
            if beyond.size:
                af.axvspan(beyond.min(), x.max(), color="0.5", alpha=alpha, linewidth=0, label=what)
    requirement = case.requirements.endurance
    result = analyses.endurance_at_requirement
    if requirement is not None:
        af.axhline(
            requirement.min_flight_time_min,
            color=LIMIT_COLOUR,
            linestyle="--",
            label=f"required >= {requirement.min_flight_time_min:g} min",
        )
        af.axvline(
            requirement.throttle,
            color=LIMIT_COLOUR,
            linestyle=":",
            label=f"at throttle {requirement.throttle:g}",
        )
        if result is not None:
            met = _verdict_passed(analyses, "flight_endurance")
            af.plot(
                [requirement.throttle],
                [result.flight_endurance_min],
                "D",
                color="tab:green" if met else LIMIT_COLOUR,
                markersize=8,
                label=f"{result.flight_endurance_min:.1f} min at "
                f"{result.airspeed_m_s:.1f} m/s ({'PASS' if met else 'FAIL'})",
            )
    af.set_xlabel("throttle, all engines (fraction)")
    af.set_ylabel("endurance (min)")
    af.set_title("level flight: endurance against throttle", fontsize=10)
    af.set_ylim(bottom=0)
    af.grid(alpha=0.3)
    af.legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Endurance of {case.name} with {ch.battery.name}")
    return fig


# --- pages without a figure -----------------------------------------------------------------
def text_page(
    title: str, lines: list[str], size: tuple[float, float] = LANDSCAPE_IN,
    font_size: float = 7.5,
) -> Any:
    """A page of text (title page, notes)."""
    fig = new_figure(size)
    ax = fig.add_subplot()
    ax.axis("off")
    fig.suptitle(title, fontsize=15, weight="bold")
    ax.text(
        0.0,
        1.0,
        "\n".join(lines),
        transform=ax.transAxes,
        va="top",
        ha="left",
        fontsize=font_size,
        family="monospace",
    )
    return fig
