"""The review's pages that no requirement asks for (issue 47 item 4), each drawn from the
study's results (:func:`tuflexperf.report.data.views`), nothing solved here:

- predicted against measured on one basis: the thrust model at the tunnel's points and the
  power model at the discharge runs;
- the altitude-airspeed envelope of level flight, all engines and one engine out;
- endurance and range against take-off mass;
- the take-off's height over distance to the obstacle.

With ``report --compare`` every configuration is drawn over the first (``Analyses.others``),
one colour per configuration (:data:`CONFIG_COLOURS`), the first in the report's blue.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tuflexperf.io.case import Case
from tuflexperf.messages import ceiling_text
from tuflexperf.report.canvas import (
    ACCURACY_GOAL_N,
    basis_note,
    basis_text,
    new_figure,
    note_box,
    wrap_text,
)
from tuflexperf.report.data import Analyses, Measured, views
from tuflexperf.report.style import CONFIG_COLOURS, EXTRAPOLATED_FILL, POINT, STYLE, legend_outside


def configurations(case: Case, analyses: Analyses) -> list[tuple[str, Case, Analyses, str]]:
    """(label, case, analyses, colour) of the configurations drawn: this one, then each
    ``--compare``; each one's views filled."""
    first = [(case.name, case, analyses)] if not analyses.compare else [
        (f"A: {case.name}", case, analyses)]
    rows = first + list(analyses.others)
    return [(label, c, views(a), CONFIG_COLOURS[k % len(CONFIG_COLOURS)])
            for k, (label, c, a) in enumerate(rows)]


def _shade_tested(ax: Any, case: Case, right: float, vertical: bool = True) -> None:
    """Airspeeds beyond the thrust model's tested range, shaded (as every page does)."""
    high = case.propulsion.tested_airspeed_m_s[1]
    if right > high and vertical:
        ax.axvspan(high, right, color=EXTRAPOLATED_FILL, zorder=0, linewidth=0,
                   label=f"thrust model extrapolated (tested to {high:g} m/s)")


# --- predicted against measured ------------------------------------------------------------
def predicted_vs_measured(case: Case, analyses: Analyses, measured: Measured) -> Any:
    """The thrust model against the tunnel's points and the power model against the
    discharge runs, each on its model's basis, the 1:1 line and the tolerance drawn."""
    from tuflexperf.analysis.battery_fit import RUN_POWER_TOLERANCE

    views(analyses)
    fig = new_figure()
    at, ap, af = fig.subplots(1, 3, width_ratios=[1.0, 1.0, 1.0 if analyses.flights else 0.55])
    ref = case.propulsion.reference_density_kg_m3
    points, model = measured.points, measured.points_model_n
    if points is None or model is None or points.thrust_n.size == 0:
        note_box(at, "no measured thrust points:\n" + wrap_text(
            measured.notes[0] if measured.notes else "no measured data", 40))
    else:
        markers = ["o", "s", "^", "D"]
        lines = []
        for k, name in enumerate(dict.fromkeys(points.engine)):
            mine = np.array([e == name for e in points.engine])
            error = model[mine] - points.thrust_n[mine]
            at.plot(points.thrust_n[mine], model[mine], markers[k % 4], markersize=4,
                    color=CONFIG_COLOURS[k % len(CONFIG_COLOURS)], alpha=0.8,
                    label=f"{name} ({mine.sum()} points)")
            if np.all(np.isfinite(error)):
                lines.append(f"{name}: mean {np.mean(error):+.2f} N, rms "
                             f"{np.sqrt(np.mean(error ** 2)):.2f} N, worst {_worst(error):+.2f} N")
        top = 1.05 * float(np.nanmax(np.concatenate([points.thrust_n, model])))
        low = min(0.0, float(np.nanmin(np.concatenate([points.thrust_n, model]))))
        span = np.array([low, top])
        at.plot(span, span, color="black", linewidth=0.8, label="model = measured")
        at.fill_between(span, span - ACCURACY_GOAL_N, span + ACCURACY_GOAL_N,
                        color=STYLE["goal"]["color"], alpha=0.15, linewidth=0,
                        label=f"\u00b1{ACCURACY_GOAL_N:g} N (paper's accuracy goal)")
        at.set_xlim(low, top)
        at.set_ylim(low, top)
        at.set_title("thrust: model against the tunnel's points\n" + "\n".join(lines),
                     fontsize=8)
        _legend_below(at)
    at.set_xlabel(f"measured thrust T (N)\n{basis_text(ref)}", fontsize=9)
    at.set_ylabel(f"model thrust T (N)\n{basis_text(ref)}", fontsize=9)
    at.grid(alpha=0.3)
    runs = analyses.run_powers
    if not runs:
        note_box(ap, "no discharge runs against the power model:\n" + wrap_text(
            analyses.view_notes.get("mass", "the case names no battery file"), 40))
    else:
        measured_w = np.array([r[4] for r in runs])
        model_w = np.array([r[5] for r in runs])
        top = 1.15 * float(max(measured_w.max(), model_w.max()))
        span = np.array([0.0, top])
        ap.plot(span, span, color="black", linewidth=0.8, label="model = measured")
        ap.fill_between(span, (1 - RUN_POWER_TOLERANCE) * span, (1 + RUN_POWER_TOLERANCE) * span,
                        color=STYLE["goal"]["color"], alpha=0.15, linewidth=0,
                        label=f"\u00b1{100 * RUN_POWER_TOLERANCE:.0f} % (the check's tolerance)")
        worst = []
        for (name, engine, x, v, got, said), colour in zip(
                runs, CONFIG_COLOURS * len(runs), strict=False):
            off = said / got - 1.0
            bad = abs(off) > RUN_POWER_TOLERANCE
            ap.plot([got], [said], "o", color=STYLE["limit"]["color"] if bad else colour,
                    markersize=7, label=f"{name}: {engine}, throttle {x:.2f}, {v:.0f} m/s")
            ap.annotate(f"{100 * off:+.0f} %", (got, said), textcoords="offset points",
                        xytext=(6, -10), fontsize=8,
                        color=STYLE["limit"]["color"] if bad else "0.2")
            worst.append(abs(off))
        ap.set_xlim(0.0, top)
        ap.set_ylim(0.0, top)
        outside = sum(w > RUN_POWER_TOLERANCE for w in worst)
        ap.set_title("electrical power: model against the discharge runs (mean U I under load)"
                     + (f"\n{outside} of {len(runs)} runs outside the tolerance: the power "
                        "verdicts are judged on both" if outside
                        else "\nevery run within the tolerance"),
                     fontsize=8, color=STYLE["limit"]["color"] if outside else "black")
        _legend_below(ap)
    ap.set_xlabel("measured power P (W), in the tunnel (as measured)", fontsize=9)
    ap.set_ylabel("model power P (W), same throttle and airspeed", fontsize=9)
    ap.grid(alpha=0.3)
    if analyses.flights:
        from tuflexperf.report.flown_figures import draw_flown_against_model

        draw_flown_against_model(af, analyses.flights, RUN_POWER_TOLERANCE)
    else:
        af.axis("off")
        af.set_xticks([])  # a text panel: no axis to label
        af.set_yticks([])
        af.text(0.0, 1.0, wrap_text(
            "flown power: no flight log is given (the case lists no validation.flights; "
            "flightlog LOG --case CASE --summary FILE writes one)", 34),
            transform=af.transAxes, va="top", ha="left", fontsize=9, color="0.3")
    fig.suptitle(f"{case.name}: predicted against measured, on one basis\n"
                 f"{basis_note(measured)}", fontsize=11)
    return fig


def _legend_below(ax: Any) -> None:
    """A legend under the axes (its x label above it): never over the data."""
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize=7, ncols=1)


def _worst(error: np.ndarray) -> float:
    return float(error[int(np.argmax(np.abs(error)))])


# --- altitude-airspeed envelope ------------------------------------------------------------
def flight_envelope(case: Case, analyses: Analyses) -> Any:
    """Altitude against true airspeed of level flight at full throttle: each configuration's
    all-engine region (filled) and its one-engine-out boundaries, the stall bound and the
    required envelope at the case's altitude."""
    fig = new_figure()
    ax = fig.add_subplot()
    drawn = configurations(case, analyses)
    right = 0.0
    texts = []
    for label, _c, a, colour in drawn:
        env = a.envelope
        if env is None:
            texts.append(f"{label}: no envelope ({a.view_notes.get('envelope', '')})")
            continue
        h = env.altitude_m
        for k, state in enumerate(env.states):
            low, high = env.low_m_s[k], env.high_m_s[k]
            ok = np.isfinite(low)
            if not ok.any():
                texts.append(f"{label}, {state}: no level flight at any altitude drawn")
                continue
            # the boundary: up the least speeds, down the greatest
            xs = np.concatenate([low[ok], high[ok][::-1]])
            ys = np.concatenate([h[ok], h[ok][::-1]])
            name = f"{label}: {state}" if len(drawn) > 1 else state
            if k == 0:
                ax.fill(xs, ys, color=colour, alpha=0.12, linewidth=0)
                ax.plot(xs, ys, color=colour, linewidth=2.0, label=name)
            else:
                ax.plot(xs, ys, color=colour, linewidth=1.2,
                        linestyle="--" if k == 1 else ":", label=name)
            right = max(right, float(np.nanmax(high)))
            ceiling = env.ceiling_m[k]
            texts.append(f"{name}: ceiling of level flight "
                         + (f"{ceiling_text(ceiling)} m (grid {h[1] - h[0]:.0f} m)"
                            if ceiling is not None else f"above the {h[-1]:.0f} m drawn"))
        ax.plot(env.least_airspeed_m_s, h, **STYLE["stall"],
                label="least airspeed (stall x margin)" if colour == drawn[0][3] else None)
        right = max(right, float(np.nanmin(env.least_airspeed_m_s)))
    if case.requirements.envelope is not None:  # the required band stays on the page
        right = max(right, case.requirements.envelope.bounds_m_s(case.density_kg_m3)[1])
    right = max(right * 1.08, 1.0)
    _shade_tested(ax, case, right)
    envelope = case.requirements.envelope
    if envelope is not None:
        lo, hi = envelope.bounds_m_s(case.density_kg_m3)
        alt = float(case.atmosphere.altitude_m)
        ax.plot([lo, hi], [alt, alt], color=STYLE["limit"]["color"], linewidth=3.0,
                solid_capstyle="butt", label=f"required envelope {lo:.0f}-{hi:.0f} m/s at "
                f"{alt:.0f} m")
    ax.set_xlim(0.0, right)
    foot = min(0.0, float(case.atmosphere.altitude_m))
    ax.set_ylim(bottom=foot - 0.02 * (ax.get_ylim()[1] - foot))  # the required band shows
    ax.set_xlabel("true airspeed V (m/s)")
    ax.set_ylabel("altitude h (m, ISA"
                  + (f" {case.atmosphere.temperature_offset_k:+g} K" if
                     case.atmosphere.temperature_offset_k else "") + ")")
    ax.grid(alpha=0.3)
    legend_outside(ax)
    ax.set_title("\n".join(texts), fontsize=8, loc="left")
    fig.suptitle("Altitude-airspeed envelope: level flight at full throttle, all engines and "
                 "one engine out (thrust x \u03c1/\u03c1ref)", fontsize=12)
    return fig


# --- endurance and range against take-off mass --------------------------------------------
def mass_trade(case: Case, analyses: Analyses) -> Any:
    """Best flight endurance and best range against take-off mass, per configuration, with
    the endurance at the requirement's throttle and its limit."""
    fig = new_figure()
    ae, ar = fig.subplots(1, 2)
    drawn = configurations(case, analyses)
    notes = []
    for label, c, a, colour in drawn:
        sweep = a.mass_sweep
        if sweep is None:
            notes.append(f"{label}: {a.view_notes.get('mass', 'no endurance')}")
            continue
        name = label if len(drawn) > 1 else "best throttle per mass"
        ae.plot(sweep.mass_kg, sweep.best_endurance_min, color=colour, linewidth=2.0,
                label=f"{name}" if len(drawn) > 1 else "longest flight (best throttle per mass)")
        ar.plot(sweep.mass_kg, sweep.best_range_km, color=colour, linewidth=2.0,
                label=name if len(drawn) > 1 else "farthest (best throttle per mass)")
        requirement = c.requirements.endurance
        if requirement is not None:
            k = int(np.argmin(np.abs(sweep.throttle - requirement.throttle)))
            ae.plot(sweep.mass_kg, sweep.endurance_min[:, k], color=colour, linewidth=1.2,
                    linestyle="--", label=f"at the requirement's throttle "
                    f"{sweep.throttle[k]:.2f}" + (f" ({label[:2]})" if len(drawn) > 1 else ""))
            ae.axhline(requirement.min_flight_time_min, **STYLE["limit"],
                       label=f"limit: min flight time {requirement.min_flight_time_min:g} min"
                       if colour == drawn[0][3] else None)
        if not np.any(np.isfinite(sweep.best_endurance_min)):
            notes.append(f"{label}: no flight at any take-off mass from {sweep.mass_kg[0]:.1f} "
                         f"to {sweep.mass_kg[-1]:.1f} kg: no throttle gives one (not attainable)")
            for axis in (ae, ar):
                axis.set_xlim(sweep.mass_kg[0], sweep.mass_kg[-1])
            continue
        for axis, values in ((ae, sweep.best_endurance_min), (ar, sweep.best_range_km)):
            at = float(np.interp(sweep.nominal_mass_kg, sweep.mass_kg, values))
            axis.plot([sweep.nominal_mass_kg], [at], "o", color=colour, markeredgecolor="black",
                      markersize=7, label=f"take-off mass {sweep.nominal_mass_kg:.2f} kg: "
                      f"{at:.1f} {'min' if axis is ae else 'km'}")
    ae.set_xlabel("take-off mass m (kg)")
    ae.set_ylabel("flight endurance (min), climb and cruise to the reserve")
    ar.set_xlabel("take-off mass m (kg)")
    ar.set_ylabel("range (km): cruise airspeed x flight endurance")
    for axis in (ae, ar):
        axis.grid(alpha=0.3)
        axis.set_ylim(bottom=0.0)
        _legend_below(axis)
    if notes:  # in the title: a note box would sit on a curve of another configuration
        ae.set_title("\n".join(wrap_text(n, 70) for n in notes), fontsize=9,
                     color=STYLE["limit"]["color"])
    fig.suptitle("Endurance and range against take-off mass (batch endurance on a mass x "
                 "throttle grid; the battery and its packs as the case's)", fontsize=12)
    return fig


# --- the take-off's height profile ---------------------------------------------------------
def takeoff_profile(case: Case, analyses: Analyses) -> Any:
    """Height over distance from brake release: ground roll, transition arc, climb to the
    obstacle, per configuration, with the requirements' distances."""
    fig = new_figure()
    ax = fig.add_subplot()
    drawn = configurations(case, analyses)
    right = 0.0
    titles = []
    for label, _c, a, colour in drawn:
        profile = a.height_profile
        prefix = f"{label}: " if len(drawn) > 1 else ""
        if profile is None:
            titles.append(f"{prefix}take-off not attainable: "
                          f"{a.view_notes.get('takeoff', '')}")
            continue
        ax.plot(profile.distance_m, profile.height_m, color=colour, linewidth=2.0,
                label=f"{prefix}height above the runway")
        ax.plot([profile.liftoff_m], [0.0], **{**POINT["least"], "color": colour},
                label=f"{prefix}lift-off after {profile.liftoff_m:.1f} m (end of rotation)")
        if profile.obstacle_m is not None:
            ax.plot([profile.obstacle_m], [profile.obstacle_height_m], "^", color=colour,
                    markersize=10, markeredgecolor="black",
                    label=f"{prefix}{profile.obstacle_height_m:g} m obstacle cleared at "
                    f"{profile.obstacle_m:.1f} m")
            titles.append(f"{prefix}obstacle {profile.obstacle_height_m:g} m at "
                          f"{profile.obstacle_m:.1f} m, lift-off at {profile.liftoff_m:.1f} m, "
                          f"arc to {profile.arc_end_m:.1f} m")
        else:
            titles.append(f"{prefix}the obstacle is not reached: "
                          f"{a.takeoff.obstacle_reason}")
        right = max(right, float(profile.distance_m[-1]))
    requirement = case.requirements.takeoff
    if requirement is not None:
        for value, what in ((requirement.max_ground_roll_m, "ground roll"),
                            (requirement.max_distance_to_obstacle_m, "distance to the obstacle")):
            if value is not None:
                ax.axvline(value, **STYLE["limit"], label=f"limit: max {what} {value:g} m")
                right = max(right, value)
        ax.axhline(requirement.obstacle_height_m, color="0.5", linewidth=0.8, linestyle=":",
                   label=f"obstacle height {requirement.obstacle_height_m:g} m")
    ax.set_xlim(0.0, 1.08 * right if right > 0 else 1.0)
    ax.set_ylim(bottom=-0.03 * ax.get_ylim()[1])  # the runway and the lift-off mark show
    ax.set_xlabel("distance from brake release s (m)")
    ax.set_ylabel("height above the runway h (m)")
    ax.grid(alpha=0.3)
    legend_outside(ax)
    ax.set_title("\n".join(titles), fontsize=9)
    fig.suptitle("Take-off height profile to the obstacle at full throttle: ground roll, "
                 "transition arc, straight climb", fontsize=12)
    return fig


# --- report --compare: the verdicts side by side -------------------------------------------
def compare_verdicts(case: Case, analyses: Analyses) -> Any:
    """Every requirement of every configuration side by side: value and verdict per
    configuration, and for each after the first what changed against the first (value and
    margin, in the unit and in per cent)."""
    from tuflexperf.report.canvas import page_margins
    from tuflexperf.report.style import FAIL_FILL, PASS_FILL

    drawn = configurations(case, analyses)
    fig = new_figure()
    page_margins(fig)
    ax = fig.add_subplot()
    ax.axis("off")
    names = list(dict.fromkeys(v.name for _, _, a, _ in drawn for v in a.verdicts))
    by = [{v.name: v for v in a.verdicts} for _, _, a, _ in drawn]
    letters = [label.split(":", 1)[0] for label, _, _, _ in drawn]
    columns = ["requirement", "limit"]
    for k, letter in enumerate(letters):
        columns += [f"{letter} value", f"{letter} verdict"]
        if k:
            columns += [f"{letter} - A", f"{letter} margin - A"]
    rows, fills = [], []
    for name in names:
        row, fill = [name, ""], ["white", "white"]
        first = by[0].get(name)
        for k, table in enumerate(by):
            v = table.get(name)
            if v is not None and not row[1]:
                row[1] = f"{'<=' if v.kind == 'max' else '>='} {v.limit:g}{_unit(v)}"
            value = "not stated" if v is None else (
                "not attainable" if v.value is None else f"{v.value:.4g}{_unit(v)}")
            word = "" if v is None else v.verdict
            row += [value, word]
            fill += ["white", PASS_FILL if word == "PASS" else FAIL_FILL if word == "FAIL"
                     else "#ffe0b2" if word else "white"]
            if k:
                row += list(_change(first, v))
                changed = word != ("" if first is None else first.verdict)
                fill += ["#fff3c4" if changed else "white"] * 2
        rows.append(row)
        fills.append(fill)
    if rows:
        weights = {"requirement": 2.2, "limit": 1.0}
        widths = [weights.get(c, 1.5 if " - A" in c else 0.75 if "verdict" in c else 1.0)
                  for c in columns]
        widths = [w / sum(widths) for w in widths]
        table = ax.table(cellText=rows, colLabels=columns, cellColours=fills, loc="upper center",
                         cellLoc="center", bbox=[0.0, 0.32, 1.0, 0.6], colWidths=widths)
        table.auto_set_font_size(False)
        table.set_fontsize(7.5 if len(drawn) > 2 else 9)
        for (r, _), cell in table.get_celld().items():
            if r == 0:
                cell.set_facecolor("0.85")
                cell.set_text_props(weight="bold")
    lines = [f"{label}: {c.path}" + _overrides(c) for label, c, _, _ in drawn]
    lines += ["", "change = value of the configuration less A's; margin change likewise "
              "(positive: more margin than A); the changes of a verdict that differs from A's "
              "are shaded yellow."]
    # monospace 8.5 pt: 110 characters fit the page's text width (longer ones widened the
    # layout and squeezed the table)
    ax.text(0.0, 0.28, "\n".join(wrap_text(line, 110) for line in lines),
            transform=ax.transAxes, va="top", ha="left", fontsize=8.5, family="monospace")
    passed = [all(v.passed for v in a.verdicts) for _, _, a, _ in drawn]
    # one line per configuration: two long case names on one line ran off the page
    fig.suptitle("Configurations compared\n"
                 + "\n".join(wrap_text(f"{label}: {'all met' if ok else 'NOT all met'}", 110)
                             for (label, _, _, _), ok in zip(drawn, passed, strict=True)),
                 fontsize=11)
    return fig


def _overrides(case: Case) -> str:
    given = getattr(case, "overrides", ())
    return (" with --set " + ", ".join(f"{k}={v:g}" for k, v in given)) if given else ""


def _change(first: Any, other: Any) -> tuple[str, str]:
    """(value change, margin change) of ``other`` against ``first``, each with its per cent
    of the first's value where both exist."""
    if first is None or other is None or first.value is None or other.value is None:
        return "-", "-"
    delta = other.value - first.value
    share = f" ({100 * delta / first.value:+.1f} %)" if first.value else ""
    margin = other.margin - first.margin
    return f"{delta:+.3g}{_unit(other)}{share}", f"{margin:+.3g}{_unit(other)}"


def _unit(verdict: Any) -> str:
    """`` m``, `` min``; a fraction goes without a word (its limit says 1)."""
    return "" if verdict.unit == "fraction" else f" {verdict.unit}"
