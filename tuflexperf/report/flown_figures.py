"""The review's flown pages (issue 45 item 3): the case's model beside its validation flights.

Drawn from the flight summaries a case lists under ``validation: {flights: [...]}``
(:func:`tuflexperf.analysis.flown_reading.flown_flights`, read once into
``Analyses.flights``): per 1 m/s airspeed bin the flown electrical power beside the model's
at the bin's true airspeed, level-flight throttle, the log's density and the summary's mass;
their ratio; the predicted endurance on the flown energy against the flown time; the
throttle the model needs against the throttle flown; and the autopilot hand-off at the
model's best-endurance airspeed. No log is opened and nothing is solved here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tuflexperf.report.canvas import new_figure, note_box, wrap_text
from tuflexperf.report.style import CONFIG_COLOURS, STYLE

MARKERS = ("o", "s", "^", "D")


def _colour(k: int) -> str:
    return CONFIG_COLOURS[k % len(CONFIG_COLOURS)]


def draw_flown_against_model(ax: Any, flights: tuple[Any, ...], tolerance: float) -> None:
    """Flown power (x) against the model's (y) per bin, each flight its own marker, the 1:1
    line and the tolerance band: the predicted-against-measured page's flown panel."""
    from tuflexperf.analysis.flown_reading import flown_power_ratio

    flown = np.concatenate([f.flown_power_w for f in flights])
    model = np.concatenate([f.model_power_w for f in flights])
    top = 1.25 * float(max(flown.max(), model.max()))  # room for the labels right of a point
    span = np.array([0.0, top])
    ax.plot(span, span, color="black", linewidth=0.8, label="model = flown")
    ax.fill_between(span, (1 - tolerance) * span, (1 + tolerance) * span,
                    color=STYLE["goal"]["color"], alpha=0.15, linewidth=0,
                    label=f"\u00b1{100 * tolerance:.0f} % (the check's tolerance)")
    outside = 0
    for k, f in enumerate(flights):
        bad = np.abs(1.0 / f.ratio - 1.0) > tolerance
        outside += int(bad.sum())
        ax.plot(f.flown_power_w, f.model_power_w, MARKERS[k % 4], color=_colour(k),
                markersize=5, label=f"{f.log}: {f.time_s.size} bins, flown/model "
                f"x{f.mean_ratio:.3f}")
        for v, x, y, off in zip(f.airspeed_m_s, f.flown_power_w, f.model_power_w, bad,
                                strict=True):
            ax.annotate(f"{v:g} m/s", (x, y), textcoords="offset points", xytext=(6, -10),
                        fontsize=7, color=STYLE["limit"]["color"] if off else "0.2")
    ratio = flown_power_ratio(flights)
    ax.set_xlim(0.0, top)
    ax.set_ylim(0.0, top)
    ax.set_xlabel("flown power P (W), mean U I per 1 m/s bin", fontsize=9)
    ax.set_ylabel("model power P (W), level flight at the bin", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize=7, ncols=1)
    judged = ratio is not None and not ratio["within_tolerance"]
    # three short lines: the panel is as narrow as the discharge runs' beside it
    ax.set_title("electrical power: model against the validation flights\n"
                 f"{outside} of {sum(f.time_s.size for f in flights)} bins outside the "
                 "tolerance" + (f"; x{ratio['ratio']:.3f} overall:\nthe power verdicts are "
                                "judged on both" if judged else ""),
                 fontsize=8, color=STYLE["limit"]["color"] if judged else "black")


def flown_configurations(case: Any, analyses: Any) -> list[tuple[str | None, tuple[Any, ...]]]:
    """(label, validation flights) of each configuration drawn: this case's, then each
    ``--compare`` configuration's (label None: no comparison, the case alone)."""
    if not analyses.compare:
        return [(None, tuple(analyses.flights))]
    return [(f"A: {case.name}", tuple(analyses.flights)), *analyses.compared_flights]


def _drawn(case: Any, analyses: Any) -> list[tuple[str, str, str, Any]]:
    """(legend name, short name, colour, flight) of every flight drawn: coloured by flight
    for the case alone, by configuration (its colour on every compared page) otherwise."""
    groups = flown_configurations(case, analyses)
    several = sum(len(flights) for _, flights in groups) > 1
    out = []
    for k, (label, flights) in enumerate(groups):
        for f in flights:
            if label is None:
                name = f.log if several else "flown"
                out.append((name, name, _colour(len(out)), f))
            else:
                out.append((f"{label}, {f.log}", f"{label.split(':')[0]}, {f.log}",
                            _colour(k), f))
    return out


def predicted_vs_flown(case: Any, analyses: Any) -> Any:
    """The page "predicted vs flown": power, ratio and throttle against airspeed per bin, and
    per flight the endurance on its energy and the autopilot hand-off in words; with
    ``--compare`` every configuration's flights, each labelled by its configuration."""
    from tuflexperf.analysis.battery_fit import RUN_POWER_TOLERANCE

    drawn = _drawn(case, analyses)
    fig = new_figure()
    grid = fig.add_gridspec(2, 3, width_ratios=[1.0, 1.0, 1.05], height_ratios=[1.15, 1.0])
    ap = fig.add_subplot(grid[0, 0:2])
    ar = fig.add_subplot(grid[1, 0])
    ax = fig.add_subplot(grid[1, 1])
    at = fig.add_subplot(grid[:, 2])
    if not drawn:  # the page is drawn only with flights; a direct call says why it is empty
        note_box(ap, "no flight log is given (the case lists no validation.flights)")
        return fig
    one = len(drawn) == 1
    for k, (name, short, colour, f) in enumerate(drawn):
        marker = MARKERS[k % 4]
        order = np.argsort(f.airspeed_m_s)
        v = f.airspeed_m_s[order]
        ap.plot(v, f.flown_power_w[order], marker, color=colour, markersize=6,
                label=f"{name}: mean U I per 1 m/s bin ({f.bins_kind or 'bins'})")
        # several flights: each its own model line (its density and mass), in its colour
        model = {**STYLE["model"], "marker": "x"} if one else {
            "color": colour, "linestyle": "--", "linewidth": 1.2, "marker": "x"}
        ap.plot(v, f.model_power_w[order], **model,
                label=f"model at the bins ({short if not one else f.log}: \u03c1 "
                f"{f.density_kg_m3:.3f} kg/m\u00b3, {f.mass_kg:g} kg)")
        if one:  # several flights' labels would sit on each other (the table)
            for vi, p, t in zip(v, f.flown_power_w[order], f.time_s[order], strict=True):
                ap.annotate(f"{t:.0f} s", (vi, p), textcoords="offset points", xytext=(0, 7),
                            ha="center", fontsize=6.5, color="0.35")
        ar.plot(v, f.ratio[order], marker, color=colour, markersize=6, linestyle="-",
                linewidth=0.8, label=f"{short}: x{f.mean_ratio:.3f} time-weighted")
        ax.plot(v, f.model_throttle[order], **model,
                label="throttle the model needs (level flight)" + ("" if one else f", {short}"))
        if np.any(np.isfinite(f.flown_throttle)):
            ax.plot(v, f.flown_throttle[order], marker, color=colour, markersize=6,
                    linestyle="none", label=f"{short}: throttle flown (bin mean)")
    ap.set_ylabel("electrical power P (W), all packs")
    ap.set_xlabel("calibrated airspeed (m/s), 1 m/s bins" + (" (label: time flown)" if one else ""))
    ap.set_ylim(bottom=0.0, top=1.15 * ap.get_ylim()[1])
    ap.grid(alpha=0.3)
    ap.legend(loc="lower right", fontsize=7)
    ap.set_title("flown power against the model's at the bin's true airspeed, level-flight "
                 "throttle, the log's density and the mass", fontsize=9)
    ar.axhline(1.0, color="black", linewidth=0.8)
    ar.axhspan(1.0 - RUN_POWER_TOLERANCE, 1.0 + RUN_POWER_TOLERANCE,
               color=STYLE["goal"]["color"], alpha=0.15, linewidth=0,
               label=f"\u00b1{100 * RUN_POWER_TOLERANCE:.0f} % (the check's tolerance)")
    low, high = ar.get_ylim()
    ar.set_ylim(min(low, 0.8), max(high, 1.2))
    ar.set_xlabel("calibrated airspeed (m/s)")
    ar.set_ylabel("flown / predicted power (-)")
    ar.grid(alpha=0.3)
    ar.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), fontsize=7)
    ar.set_title("ratio per bin", fontsize=9)
    ax.set_ylim(0.0, 1.05)
    ax.set_xlabel("calibrated airspeed (m/s)")
    ax.set_ylabel("throttle (fraction)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), fontsize=7)
    ax.set_title("throttle: the model's against the flown"
                 + ("" if any(np.any(np.isfinite(d[3].flown_throttle)) for d in drawn)
                    else "\n(no flight logged its throttle)"), fontsize=9)
    at.axis("off")
    at.text(0.0, 1.0, "\n".join(flight_lines(case, analyses)), transform=at.transAxes,
            va="top", ha="left", fontsize=7, family="monospace")
    files = "; ".join(
        (f"{label.split(':')[0]} " if label else "")
        + (", ".join(f.path.name for f in flights) if flights else "none")
        for label, flights in flown_configurations(case, analyses))
    fig.suptitle(f"{case.name}: predicted vs flown (validation.flights: {files})", fontsize=11)
    return fig


def flight_lines(case: Any, analyses: Any, width: int = 54) -> list[str]:
    """Per flight its numbers in words (airborne time, energy, endurance predicted on its
    energy against the time flown), then the autopilot hand-off, wrapped to ``width``; with
    ``--compare`` under each configuration's label, a configuration without flights said."""
    lines: list[str] = []

    def say(text: str, indent: str = "") -> None:
        lines.extend(indent + part for part in wrap_text(text, width - len(indent)).split("\n"))

    groups = flown_configurations(case, analyses)
    for label, flights in groups:
        if label is not None:
            say(label if flights else f"{label}: lists no validation.flights")
            if not flights:
                lines.append("")
        for f in flights:
            lines.append(f"{f.path.name}: log {f.log}")
            say(f"sha256 {f.log_sha256[:16]}...", "  ")
            say(f"\u03c1 {f.density_kg_m3:.4f} kg/m\u00b3, mass {f.mass_kg:g} kg, "
                f"{f.time_s.size} {f.bins_kind or ''} bins over {f.time_s.sum():.0f} s", "  ")
            energy = ("energy not logged" if f.energy_wh is None else
                      f"{f.energy_wh:.1f} Wh, mean {f.mean_power_w:.0f} W")
            say(f"airborne {f.airborne_s:.0f} s, {energy}", "  ")
            say(f"flown/predicted power x{f.mean_ratio:.3f} (time-weighted; x"
                f"{float(np.min(f.ratio)):.2f} to x{float(np.max(f.ratio)):.2f} per bin)", "  ")
            predicted = f.predicted_endurance_s
            if predicted is not None:
                say(f"endurance on the flown {f.energy_wh:.1f} Wh at the model's power: "
                    f"{predicted:.0f} s predicted, {f.airborne_s:.0f} s flown "
                    f"({100 * (predicted / f.airborne_s - 1):+.0f} %)", "  ")
            if f.stale:
                say("the case's model gives other power than when the summary was written: "
                    "drawn as it is today", "  ")
            lines += [""] + bin_table(f) + [""]
    lines.append("AUTOPILOT HAND-OFF (cruise at best endurance)")
    if len(groups) > 1:  # each configuration's best endurance is its own report's
        say(f"of {groups[0][0]} only: each compared configuration's is on its own report",
            "  ")
    for text in handoff_lines(case, analyses):
        say(text, "  ")
    return lines


def bin_table(flight: Any, most: int = 24) -> list[str]:
    """The flight's bins as rows of numbers (53 characters): airspeed, time, flown and model
    power, their ratio, the model's and the flown throttle, the flown current; at most
    ``most`` rows, the fastest bins said to be left out."""

    def cell(value: float, width: int, digits: int) -> str:
        return f"{value:>{width}.{digits}f}" if np.isfinite(value) else "n/a".rjust(width)

    rows = [f"{'V':>5}{'t':>5}{'flown':>8}{'model':>8}{'ratio':>7}{'throttle':>11}{'I':>9}",
            f"{'m/s':>5}{'s':>5}{'W':>8}{'W':>8}{'':>7}{'model':>7}{'flown':>7}{'A':>6}",
            " " + "-" * 52]
    order = np.argsort(flight.airspeed_m_s)
    for k in order[:most]:
        rows.append(f"{flight.airspeed_m_s[k]:>5.0f}{flight.time_s[k]:>5.0f}"
                    f"{flight.flown_power_w[k]:>8.0f}{flight.model_power_w[k]:>8.0f}"
                    f"{flight.ratio[k]:>7.3f}{cell(flight.model_throttle[k], 7, 3)}"
                    f"{cell(flight.flown_throttle[k], 7, 3)}"
                    f"{cell(flight.flown_current_a[k], 6, 1)}")
    if order.size > most:
        rows.append(f"  ... {order.size - most} faster bins left out of this table")
    return rows


def handoff_lines(case: Any, analyses: Any) -> list[str]:
    """The cruise power and current an autopilot's average-current setting and a ground
    station's flight-time estimate need: the model's at its best-endurance airspeed, and each
    flight's in the bin holding that airspeed."""
    from tuflexperf.analysis.flown_compare import handoff_point

    best = getattr(analyses, "best_endurance", None)
    if best is None:
        return ["no best-endurance point (the case has no battery file, or none is "
                "attainable): no hand-off"]
    point = handoff_point(case, best)
    out = [f"model: {point['airspeed_eas_m_s']:.1f} m/s EAS ({point['airspeed_true_m_s']:.1f} "
           f"m/s true), throttle {point['throttle']:.2f}: {point['model_power_w']:.0f} W, "
           f"{point['model_current_a']:.1f} A (full packs)"]
    for f in analyses.flights:
        held = np.flatnonzero(f.airspeed_m_s == point["bin_m_s"])
        if held.size == 0:
            out.append(f"{f.log}: no bin holds {point['bin_m_s']:g} m/s (flown "
                       f"{f.airspeed_m_s.min():g}-{f.airspeed_m_s.max():g} m/s)")
            continue
        k = int(held[0])
        current = f.flown_current_a[k]
        out.append(f"{f.log}, {point['bin_m_s']:g} m/s bin: {f.flown_power_w[k]:.0f} W, "
                   + (f"{current:.1f} A" if np.isfinite(current) else "current not in the "
                      "summary"))
    return out
