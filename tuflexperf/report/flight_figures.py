"""The flight analyses' pages: thrust required and available, take-off, trim and OEI, endurance.

Each draws the study's results (:class:`tuflexperf.report.data.Analyses`) with the
requirement limits, the envelope's edges and the thrust model's extrapolated airspeeds.
"""

from __future__ import annotations

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
    total_thrust_n,
)
from tuflexperf.report.canvas import (
    AVAILABLE_COLOUR,
    LEGEND_FONT,
    flight_basis,
    flight_label,
    label_line_ends,
    new_figure,
    style_of,
    wrap_text,
)
from tuflexperf.report.data import Analyses
from tuflexperf.report.decimate import envelope as decimated
from tuflexperf.report.style import (
    CONFIG_COLOURS,
    EXTRAPOLATED_FILL,
    FAIL_FILL,
    POINT,
    STYLE,
    legend_outside,
    unit,
)

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


def _overlay(ax: Any, analyses: Analyses, what: str) -> None:
    """``report --compare``: each other configuration's curve of ``what`` ("trim", "oei",
    "takeoff", "endurance") on this page, in its colour, labelled with its letter; drawn
    beneath the page's own curves (zorder 1.8), so where they coincide both show."""
    for k, (label, _, other) in enumerate(analyses.others, start=1):
        colour = CONFIG_COLOURS[k % len(CONFIG_COLOURS)]
        if what == "trim" and other.trim is not None:
            ax.plot(other.trim.airspeed_m_s, other.trim.throttle, color=colour, linewidth=1.8,
                    zorder=1.8, label=f"{label}: trim, all engines")
            if other.oei is not None:
                worst = other.oei.critical
                ax.plot(worst.airspeed_m_s, worst.throttle, color=colour, linewidth=1.4,
                        linestyle="--", zorder=1.8, label=f"{label}: OEI, {worst.dead_engine} dead")
        elif what == "takeoff" and other.takeoff is not None:
            r = other.takeoff
            ax.plot(np.append(r.history_distance_m, r.ground_roll_m),
                    np.append(r.history_airspeed_m_s, r.liftoff_speed_m_s), color=colour,
                    linewidth=1.8, zorder=1.8, label=f"{label}: ground run, lift-off at "
                    f"{r.ground_roll_m:.1f} m")
        elif what == "endurance" and other.endurance_curve:
            ax.plot([c[0] for c in other.endurance_curve],
                    [c[1].flight_endurance_min for c in other.endurance_curve], color=colour,
                    linewidth=1.8, zorder=1.8, label=f"{label}: flight endurance")
        elif what in ("trim", "takeoff", "endurance"):
            note = {"trim": "no trim", "takeoff": other.takeoff_note or "no take-off",
                    "endurance": "no endurance curve"}[what]
            ax.plot([], [], color=colour, label=f"{label}: {wrap_text(note, 60)}")


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

    def least(meaning: str, result: Any, label: str, *dead: Any) -> None:
        """The thrust at ``result``'s least throttle, its point on the drag curve a dot."""
        x, va = result.min_throttle, result.airspeed_at_min_throttle_m_s
        engines = "" if dead else ", all engines"
        ax.plot(v, np.asarray(total_thrust_n(propulsion, x, v, rho, *dead), dtype=float),
                **style_of(meaning, linestyle="-."),
                label=f"{label} {100 * x:.1f} %{engines} (dot: {va:.1f} m/s)")
        ax.plot([va], [float(level_flight_drag_n(aircraft, va, rho))], **POINT["least"],
                markerfacecolor=STYLE[meaning]["color"])

    trim = analyses.trim
    if trim is not None and trim.min_throttle is not None:
        least("trim", trim, "least trim throttle")
    oei = analyses.oei
    if oei is not None:
        worst = oei.critical
        dead = ([e.name for e in propulsion.engines].index(worst.dead_engine),
                oei.dead_engine_mode)
        one = np.asarray(total_thrust_n(propulsion, 1.0, v, rho, *dead), dtype=float)
        ax.plot(v, one, **STYLE["oei"],
                label=f"OEI: {worst.dead_engine} dead ({oei.dead_engine_mode}), others 100 %")
        if worst.min_throttle is not None:
            least("oei", worst, "OEI least throttle", *dead)
    _envelope_lines(ax, case)
    ax.set_xlim(0, right)
    top = 1.08 * float(np.max(full))
    if drag.size:
        top = max(top, 1.08 * float(drag.max()))
    ax.set_ylim(0, top)
    label_line_ends(ax, ends)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel(flight_label("thrust T, drag D", rho))
    fig.suptitle(
        "Required and available thrust in level flight (paper Fig. 18)\n"
        f"{case.name}, {unit(f'rho = {rho:.3f} kg/m^3')}; "
        f"{flight_basis(rho, propulsion.reference_density_kg_m3)}"
    )
    ax.grid(alpha=0.3)
    # right of the throttle labels in the margin, so neither covers the other
    ax.legend(loc="upper left", bbox_to_anchor=(1.07, 1.0), borderaxespad=0.0,
              fontsize=LEGEND_FONT)
    return fig


# --- 8. take-off ----------------------------------------------------------------------------
def _verdict_word(analyses: Analyses, name: str) -> str:
    """PASS, FAIL or UNPROVEN as ``check`` decided it (analysis/requirements.py), never
    re-judged here (FAIL where no verdict of that name exists)."""
    return next((v.verdict for v in analyses.verdicts if v.name == name), "FAIL")


def _takeoff_not_attainable(case: Case, analyses: Analyses) -> Any:
    from tuflexperf.analysis.ground_roll import net_force_n
    from tuflexperf.models.aircraft import liftoff_speed_m_s

    fig = new_figure()
    gs = fig.add_gridspec(1, 2, width_ratios=[1.0, 2.0])
    an = fig.add_subplot(gs[0])
    ad = fig.add_subplot(gs[1])
    an.axis("off")
    an.text(0.0, 0.5, wrap_text(f"take-off not attainable: {analyses.takeoff_note}", 50),
            transform=an.transAxes, ha="left", va="center", fontsize=11, color="0.3")
    rho = case.density_kg_m3
    v_lo = float(liftoff_speed_m_s(case.aircraft, rho))
    v = np.linspace(0.0, 1.05 * v_lo, 300)
    force = np.asarray(net_force_n(case.aircraft, case.propulsion, v, rho), dtype=float)
    ad.plot(v, force, **STYLE["takeoff"], label="accelerating force at full throttle")
    ad.axhline(0.0, color="black", linewidth=0.8)
    ad.axvline(v_lo, **STYLE["stall"], label=f"lift-off speed {v_lo:.1f} m/s")
    ad.set_xlabel("airspeed V (m/s)")
    ad.set_ylabel(flight_label("net force T - D - friction", rho))
    ad.set_title("why: the net force on the runway", fontsize=10)
    ad.grid(alpha=0.3)
    legend_outside(ad)
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
        av.plot([s_acc, roll], [v_lo, v_lo], **style_of("takeoff", linestyle="-.", linewidth=3.0),
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
            ax.axvline(limit, **STYLE["limit"], label=f"runway limit {limit:g} m "
                       f"({_verdict_word(analyses, 'takeoff_ground_roll')})")
            right = max(right, limit)
    if limit is not None and not catapult and roll > limit:
        _mark_beyond(av, limit, roll, v_lo, f"ground roll FAIL: {roll:.1f} m, "
                     f"{roll - limit:.1f} m beyond the {limit:g} m limit")
    far = requirement.max_distance_to_obstacle_m if requirement is not None else None
    if far is not None:
        av.axvline(far, **style_of("limit", linestyle="-."),
                   label=f"obstacle distance limit {far:g} m ("
                   + _verdict_word(analyses, "takeoff_distance_to_obstacle") + ")")
        right = max(right, far)
        if obstacle is not None and obstacle > far:
            _mark_beyond(av, far, obstacle, result.transition_speed_m_s,
                         f"obstacle FAIL: {obstacle:.1f} m, {obstacle - far:.1f} m beyond the "
                         f"{far:g} m limit")
    av.set_xlim(0, 1.04 * right)
    # the forces end at lift-off: their panel spans the runway, not the airborne part
    af.set_xlim(0, 1.1 * (roll if limit is None else max(roll, limit)))
    for ax in (av, af):
        ax.grid(alpha=0.3)
    av.set_ylim(0, top)
    _overlay(av, analyses, "takeoff")
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
    af.set_ylabel(flight_label("force", case.density_kg_m3))
    af.set_title("forces on the ground run", fontsize=10)
    if catapult:
        af.text(0.5, 0.5, "catapult launch: no ground run (the catapult's energy, not the "
                "battery's, brings the aircraft to its release speed)", transform=af.transAxes,
                ha="center", va="center", fontsize=10)
    legend_outside(av)
    legend_outside(af)
    start = (f"catapult release at {v_lo:.1f} m/s, no ground roll" if catapult else
             f"ground roll {roll:.1f} m to lift-off at {v_lo:.1f} m/s")
    # the obstacle's reason may be long (never cleared, and why): wrapped, not cut at the edges
    fig.suptitle(wrap_text(
        f"Take-off of {case.name} at full throttle: {start}"
        + (f", {obstacle:.1f} m to the {result.obstacle_height_m:g} m obstacle"
           if obstacle is not None else f"; {result.obstacle_reason}"), 140))
    return fig


def _mark_beyond(ax: Any, limit: float, reached: float, speed: float, text: str) -> None:
    """A distance beyond its limit: the stretch shaded red, a red cross where it ends and
    the words beside it."""
    ax.axvspan(limit, reached, color=FAIL_FILL, alpha=0.6, zorder=0)
    ax.plot([reached], [speed], **style_of("limit", linestyle="none", marker="X",
                                           markersize=12, zorder=6), label=text)
    ax.annotate(text, (reached, speed), xytext=(8, -60), textcoords="offset points",
                color=STYLE["limit"]["color"], fontsize=9, fontweight="bold", ha="left",
                va="top", arrowprops={"arrowstyle": "-", "color": STYLE["limit"]["color"]},
                bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "none"},
                zorder=7)


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
    bound = analyses.trim_bound
    if trim.max_throttle is not None:
        k = int(np.nanargmax(trim.throttle))
        ax.plot([trim.airspeed_m_s[k]], [trim.max_throttle], **POINT["verdict"],
                label=f"highest trim throttle {100 * trim.max_throttle:.1f} % at "
                f"{trim.airspeed_m_s[k]:.1f} m/s "
                + ("(as fitted)" if bound is not None else "(the verdict)"))
    if bound is not None:  # the reading the verdict also reads: where it flies and where not
        throttle = np.asarray(bound.throttle, dtype=float)
        lost = np.asarray(bound.airspeed_m_s, dtype=float)[~np.isfinite(throttle)
                                                           | (throttle > 1.0)]
        top = (f"not attainable at {lost.min():.1f}-{lost.max():.1f} m/s" if lost.size
               else f"highest {100 * bound.max_throttle:.1f} %")
        ax.plot(bound.airspeed_m_s, bound.throttle, **style_of("trim", linestyle=":"),
                label=wrap_text(f"trim on {analyses.trim_bound_label}: {top}", 60))
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
            ax.axhline(requirement.max_throttle, **style_of("limit", linewidth=2.2),
                       label=f"limit: OEI max throttle {requirement.max_throttle:g}")
    runs = _reason_runs(trim.reasons, trim.throttle)
    speeds = np.asarray(trim.airspeed_m_s, dtype=float)
    half = 0.5 * float(np.diff(speeds).min()) if speeds.size > 1 else 0.25
    for k, (a, b, why) in enumerate(runs):
        # half a grid step either side: one unattainable airspeed was a span of no width
        ax.axvspan(speeds[a] - half, speeds[b] + half, color=FAIL_FILL, alpha=0.6,
                   hatch=_REASON_HATCH.get(why), zorder=0,
                   label=f"trim not attainable: {why}"
                   if all(w != why for _, _, w in runs[:k]) else None)
    failures = _mark_trim_failures(ax, trim, envelope.max_trim_throttle, runs)
    if oei is not None:
        failures += _mark_oei_failure(ax, oei.critical, case.requirements.oei)
    if failures:  # above the axes, in red: never over a curve, whatever the case
        ax.set_title("\n".join(wrap_text(f, 80) for f in failures), color=STYLE["limit"]["color"],
                     fontsize=10, fontweight="bold")
    ax.axvline(stall, **STYLE["stall"], label=f"stall speed {stall:.1f} m/s")
    _envelope_lines(ax, case)
    ax.set_xlim(left, right)
    ax.set_ylim(0, 1.08)
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("least throttle for level flight x (fraction)")
    _overlay(ax, analyses, "trim")
    fig.suptitle(f"Trim and one-engine-inoperative throttle over the envelope, {case.name}"
                 + (" (A), compared" if analyses.compare else ""))
    ax.grid(alpha=0.3)
    legend_outside(ax)
    return fig


def _mark_trim_failures(ax: Any, trim: Any, limit: float,
                        runs: list[tuple[int, int, str]]) -> list[str]:
    """Red crosses on the limit at each airspeed trim cannot fly, red dots where its
    throttle is above the limit, each set labelled; returns the failures in words."""
    speeds = np.asarray(trim.airspeed_m_s, dtype=float)
    said = []
    for a, b, why in runs:
        span = (f"{speeds[a]:.1f} m/s" if a == b else f"{speeds[a]:.1f}-{speeds[b]:.1f} m/s")
        ax.plot(speeds[a:b + 1], np.full(b + 1 - a, limit), **style_of(
            "limit", linestyle="none", marker="X", markersize=11, zorder=6, clip_on=False),
            label=f"FAIL: trim not attainable at {span} ({why})")
        said.append(f"trim FAIL: not attainable at {span} ({why})")
    throttle = np.asarray(trim.throttle, dtype=float)
    over = np.isfinite(throttle) & (throttle > limit)
    if over.any():
        span = f"{speeds[over].min():.1f}-{speeds[over].max():.1f} m/s"
        ax.plot(speeds[over], throttle[over], **style_of(
            "limit", linestyle="none", marker="o", markersize=5, zorder=6),
            label=f"FAIL: trim throttle above the limit {limit:g} at {span}")
        said.append(f"trim FAIL: throttle up to {100 * float(throttle[over].max()):.1f} % "
                    f"> {100 * limit:g} % at {span}")
    return said


def _mark_oei_failure(ax: Any, worst: Any, requirement: Any) -> list[str]:
    """The OEI verdict's point in red and labelled when its least throttle is above the
    limit; returns the failure in words (also when nowhere attainable)."""
    if requirement is None:
        return []
    limit = requirement.max_throttle
    if worst.min_throttle is None:
        return ["OEI FAIL: level flight with one engine out attainable nowhere in the envelope"]
    if worst.min_throttle <= limit:
        return []
    ax.plot([worst.airspeed_at_min_throttle_m_s], [worst.min_throttle], **style_of(
        "limit", linestyle="none", marker="X", markersize=11, zorder=6),
        label=f"FAIL: OEI least throttle {100 * worst.min_throttle:.1f} % above the "
        f"limit {limit:g}")
    return [f"OEI FAIL: least throttle {100 * worst.min_throttle:.1f} % > {100 * limit:g} %"]


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
        av.plot(m_t, model_v, **style_of("model", linestyle="--", linewidth=1.0),
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
    legend_outside(av)
    curve = analyses.endurance_curve
    if curve:
        x = np.array([c[0] for c in curve])
        flight = np.array([c[1].flight_endurance_min for c in curve])
        pack = np.array([c[1].battery_endurance_min for c in curve])
        speeds = np.array([c[1].airspeed_m_s for c in curve])
        af.plot(x, flight, **style_of("mission", linewidth=2.0),
                label=f"flight ({ch.battery.packs_in_parallel_per_engine} packs per fan, "
                "launch and landing reserve)")
        af.plot(x, pack, **style_of("full_throttle", linestyle="-", linewidth=1.4),
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
        af.axvline(requirement.throttle, **style_of("limit", linestyle=":"),
                   label=f"at the required throttle {requirement.throttle:g}")
        if result is not None:
            af.plot([requirement.throttle], [result.flight_endurance_min], **POINT["verdict"],
                    label=f"{result.flight_endurance_min:.1f} min at "
                    f"{result.airspeed_m_s:.1f} m/s "
                    f"({_verdict_word(analyses, 'flight_endurance')})")
    af.set_xlabel("throttle, all engines x (fraction)")
    af.set_ylabel("endurance (min)")
    _overlay(af, analyses, "endurance")
    af.set_title("level flight: endurance against throttle", fontsize=10)
    af.set_ylim(bottom=0)
    af.grid(alpha=0.3)
    legend_outside(af)
    fig.suptitle(f"Endurance of {case.name} with {flown.title}")
    return fig
