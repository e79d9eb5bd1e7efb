"""The review's first page: every verdict ``check`` prints, its reason and its caveats.

What the terminal's ``check`` prints for each requirement (name, value, limit, unit, margin,
verdict, the reason line and every ``note:``) is read from the same
:class:`~tuflexperf.analysis.requirements.Verdict` objects (the study's verdicts, their
``details["warnings"]``); nothing is computed here. Failures stand in red, caveats in amber,
passes in green. Below the verdicts: the inputs' own caveats (files whose header says they
are synthetic, reconstructed or estimated; measured data that are not the fit's), the key
figures and the provenance of every input.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any

from tuflexperf.io.inputs import path_text

PAGE_IN = (11.69, 8.27)  # A4 landscape, as every page of the review
MARGIN_IN = 0.6  # left and right: a printer's edge plus room to staple
TOP_IN = 0.45
BOTTOM_IN = 0.6  # above the footer stamped at assembly (build.FOOTER_IN)
FONT_PT, SMALLEST_FONT_PT = 8.0, 5.5
LINE_SPACING = 1.28  # line height in font sizes
CHAR_EM = 0.602  # DejaVu Sans Mono's advance: every glyph 0.602 em wide

PASS_COLOUR, FAIL_COLOUR, CAVEAT_COLOUR = "#2e7d32", "#c62828", "#a15c00"  # green, red, amber
PLAIN, QUIET = "black", "0.30"
NAME_WIDTH = 22


@dataclass(frozen=True)
class Segment:
    """A run of text on one line, starting ``column`` characters in."""

    text: str
    colour: str = PLAIN
    bold: bool = False
    column: int = 0


Line = tuple[Segment, ...]


def fmt(value: float | None, digits: int = 3) -> str:
    """A number as ``check`` prints it: ``n/a`` where there is none."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}f}"


def _word_colour(word: str) -> str:
    return {"PASS": PASS_COLOUR, "FAIL": FAIL_COLOUR}.get(word, CAVEAT_COLOUR)


def _wrapped(text: str, width: int, indent: int, colour: str, bold: bool = False,
             column: int = 0) -> list[Line]:
    """``text`` wrapped to ``width`` characters, continuation lines indented further."""
    # the continuation's deeper indent counts against the width too (it ran 4 characters
    # past the right margin)
    parts = textwrap.wrap(text, max(20 + indent + 4, width), initial_indent=" " * indent,
                          subsequent_indent=" " * (indent + 4),
                          break_on_hyphens=False) or [" " * indent]
    return [(Segment(part, colour, bold, column),) for part in parts]


def verdict_lines(verdicts: list[Any], width: int,
                  probabilities: dict[str, Any] | None = None) -> list[Line]:
    """The verdict table: one row per verdict as ``check`` prints it, then its reason
    (red where it failed) and every note of it as a caveat (amber)."""
    w = max([NAME_WIDTH, *(len(v.name) + 2 for v in verdicts)])
    header = (f"{'requirement':<{w}}{'value':>10}{'limit':>10}{'unit':>10}{'margin':>10}"
              f"{'P(meet)':>9}  verdict")
    lines: list[Line] = [(Segment(header, bold=True),), (Segment("-" * len(header), QUIET),)]
    for k, v in enumerate(verdicts):
        if k:
            lines.append(())
        word = v.verdict
        p = (probabilities or {}).get(v.name)
        chance = "-" if p is None else f"{p.probability:.4f}"
        failed = word == "FAIL"
        row = (f"{v.name:<{w}}{_cell(fmt(v.value))}{_cell(fmt(v.limit))}{_cell(v.unit)}"
               f"{_cell(fmt(v.margin))}{_cell(chance, 9)}  ")
        lines.append((Segment(row, FAIL_COLOUR if failed else PLAIN, failed),
                      Segment(word, _word_colour(word), True, len(row))))
        if failed:
            lines += _wrapped(failure_reason(v), width, 2, FAIL_COLOUR, True)
        elif word == "UNPROVEN":  # the disagreement, both values and what would settle it
            lines += _wrapped(f"UNPROVEN: {v.reason}", width, 2, CAVEAT_COLOUR, True)
            if getattr(v, "settle", ""):
                lines += _wrapped(f"to settle: {v.settle}", width, 2, CAVEAT_COLOUR, True)
        elif v.reason:
            lines += _wrapped(v.reason, width, 2, QUIET)
        for warning in v.details.get("warnings", []):
            lines += _wrapped(f"caveat: {warning}", width, 2, CAVEAT_COLOUR)
    return lines


def failure_reason(verdict: Any) -> str:
    """Why a requirement failed, in the verdict's own words: its value against its limit
    (or "not attainable"), then the reason line ``check`` prints."""
    unit = f" {verdict.unit}" if verdict.unit else ""
    if verdict.value is None:
        said = verdict.reason or "no value"
        return "reason: " + (said if said.startswith("not attainable") else
                             f"not attainable: {said}")
    side = "above the maximum" if verdict.kind == "max" else "below the minimum"
    head = f"reason: {fmt(verdict.value)}{unit} is {side} {fmt(verdict.limit)}{unit}"
    return f"{head}; {verdict.reason}" if verdict.reason else head


def _cell(text: str, width: int = 10) -> str:
    """Right-aligned in ``width``; a longer value keeps a space before it (as ``check``)."""
    return text.rjust(width) if len(text) < width else " " + text


def headline(verdicts: list[Any], caveats: int) -> list[Line]:
    """The overall verdict in one line, red when any requirement is not met."""
    words = [v.verdict for v in verdicts]
    failed = sum(w == "FAIL" for w in words)
    other = sum(w not in ("PASS", "FAIL") for w in words)
    if not verdicts:
        return [(Segment("VERDICT: no requirements stated", CAVEAT_COLOUR, True),)]
    if failed:
        text, colour = f"VERDICT: {failed} OF {len(verdicts)} REQUIREMENTS NOT MET", FAIL_COLOUR
    elif other:
        text, colour = (f"VERDICT: {other} OF {len(verdicts)} REQUIREMENTS NOT SHOWN MET",
                        CAVEAT_COLOUR)
    else:
        text, colour = f"VERDICT: ALL {len(verdicts)} REQUIREMENTS MET", PASS_COLOUR
    line = [Segment(text, colour, True)]
    if caveats:
        line.append(Segment(f"  with {caveats} caveat{'s' if caveats > 1 else ''} (amber)",
                            CAVEAT_COLOUR, True, len(text)))
    return [tuple(line)]


def sampling_lines(case: Any, probabilities: dict[str, Any] | None, width: int) -> list[Line]:
    """Where P(meet) comes from, or why the column is empty (never a number made up)."""
    if probabilities:
        return []
    block = getattr(case, "uncertainty", None) is not None
    why = ("the case's uncertainty block is sampled by `tuflexperf check`, not by this report"
           if block else "the case has no uncertainty block; `tuflexperf check --samples N` "
           "samples one")
    return [()] + _wrapped(f"P(meet): not sampled ({why}): each verdict above is the nominal one",
                    width, 0, QUIET)


def page_lines(case: Any, measured: Any, analyses: Any, width: int, now: str,
               probabilities: dict[str, Any] | None = None,
               notes_page: int | None = None) -> tuple[list[Line], list[Line], list[Line]]:
    """The first page's text: (verdicts and caveats, key figures, inputs), each a list of
    lines of coloured segments; ``width`` is the page's width in characters."""
    from tuflexperf.report.data import input_caveats

    verdicts = list(analyses.verdicts)
    inputs = input_caveats(case, measured)
    notes = sum(len(v.details.get("warnings", [])) for v in verdicts) + len(inputs)
    top = headline(verdicts, notes) + [()]
    top += verdict_lines(verdicts, width, probabilities)
    top += sampling_lines(case, probabilities, width)
    if inputs:
        top += [(), (Segment("CAVEATS OF THE INPUTS", CAVEAT_COLOUR, True),)]
        for caveat in inputs:
            top += _wrapped(caveat, width, 2, CAVEAT_COLOUR)
    if notes_page is not None:
        top += [()] + _wrapped(f"What this report leaves out, and why: page {notes_page}",
                               width, 0, QUIET)
    half = width // 2 - 2
    left = [(Segment("KEY FIGURES (as fitted; verdicts: the worse reading)", bold=True),)]
    for text in key_figures(analyses):
        left += _wrapped(text.strip(), half, 2, PLAIN)
    right = [(Segment("INPUTS AND THEIR PROVENANCE", bold=True),)]
    for text in provenance_lines(case, measured):
        right += _wrapped(text.strip(), half, 2, PLAIN)
    # a folder's bytes that are no UTF-8 as \xfc: the font raised on them (issue 46)
    right += [()] + _wrapped(f"case {path_text(case.path)}", half, 0, QUIET)
    if getattr(case, "overrides", ()):  # the figures are of the changed case, not the files'
        right += _wrapped("with --set " + ", ".join(f"{k}={v:g}" for k, v in case.overrides),
                          half, 2, CAVEAT_COLOUR, True)
    from tuflexperf import __version__

    right += _wrapped(f"tuflexperf {__version__}, {now};", half, 0, QUIET)
    right += _wrapped("every input file with its sha256 on the last page", half, 0, QUIET)
    return top, left, right


def key_figures(analyses: Any) -> list[str]:
    """The numbers a reviewer asks for first, from the analyses already run (no physics)."""
    lines = []
    t = getattr(analyses, "takeoff", None)
    if t is not None:
        lines.append(f"  stall speed          {fmt(t.stall_speed_m_s, 2)} m/s (TAS)")
        lines.append(f"  lift-off speed       {fmt(t.liftoff_speed_m_s, 2)} m/s "
                     f"({fmt(t.liftoff_speed_eas_m_s, 2)} m/s EAS)")
        lines.append(f"  ground roll          {fmt(t.ground_roll_m, 1)} m; to the "
                     f"{t.obstacle_height_m:g} m obstacle {fmt(t.distance_to_obstacle_m, 1)} m")
    else:
        lines.append(f"  take-off             not attainable: {analyses.takeoff_note}")
    if getattr(analyses, "trim", None) is not None:
        lines.append(f"  least trim throttle  {fmt(analyses.trim.min_throttle)}")
    if getattr(analyses, "oei", None) is not None:
        worst = analyses.oei.critical
        lines.append(f"  OEI least throttle   {fmt(worst.min_throttle)} "
                     f"({worst.dead_engine} dead)")
    e = getattr(analyses, "endurance_at_requirement", None)
    if e is not None:
        lines.append(f"  flight endurance     {fmt(e.flight_endurance_min, 1)} min at "
                     f"throttle {e.throttle:g}, {fmt(e.airspeed_m_s, 1)} m/s")
    return lines


def provenance_lines(case: Any, measured: Any) -> list[str]:
    """Each input and what its own header says it is (measured, synthetic, ...)."""
    from tuflexperf.report.data import provenance_class

    lines = [f"  aircraft     {case.aircraft.name}, {case.aircraft.mass_kg:g} kg: "
             f"{provenance_class(case.aircraft_path)}",
             f"  propulsion   {case.propulsion.name}: {provenance_class(case.propulsion_path)}"]
    if case.battery_path is not None:
        lines.append(f"  battery      {provenance_class(case.battery_path)}")
    if measured.source is not None:
        lines.append(f"  test data    {measured.kind} {path_text(measured.source.name)}: "
                     f"{provenance_class(measured.source)}")
    else:
        lines.append("  test data    none (the thrust model is drawn alone)")
    flights = getattr(case, "validation_flights", ())
    lines.append("  flights      " + (", ".join(path_text(p.name) for p in flights)
                                      + " (flight summaries)" if flights else "none"))
    lines.append(f"  atmosphere   ISA {case.atmosphere.altitude_m:g} m, "
                 f"dT {case.atmosphere.temperature_offset_k:+g} K, "
                 f"rho = {case.density_kg_m3:.4f} kg/m\u00b3")
    return lines


def plain_text(lines: list[Line]) -> list[str]:
    """The lines as text (each segment at its column), for a reader without colours."""
    out = []
    for line in lines:
        text = ""
        for seg in line:
            text = text.ljust(seg.column) + seg.text
        out.append(text)
    return out


def timestamp() -> str:
    """The report's date, as the first page and every footer print it."""
    return datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def first_page(case: Any, measured: Any, analyses: Any, now: str,
               probabilities: dict[str, Any] | None = None,
               notes_page: int | None = None) -> Any:
    """The first page as a matplotlib figure: the font shrinks (down to 5.5 pt) until every
    line fits above the footer; no line runs past the page's right margin."""
    from matplotlib.figure import Figure

    width_in, height_in = PAGE_IN
    usable_w = width_in - 2 * MARGIN_IN
    title_in = 0.45
    usable_h = height_in - TOP_IN - title_in - BOTTOM_IN
    size = FONT_PT
    while True:
        chars = int(usable_w * 72 / (CHAR_EM * size))
        top, left, right = page_lines(case, measured, analyses, chars, now, probabilities,
                                      notes_page)
        rows = len(top) + 1 + max(len(left), len(right))
        if rows * size * LINE_SPACING / 72 <= usable_h or size <= SMALLEST_FONT_PT:
            break
        size = max(SMALLEST_FONT_PT, size - 0.25)
    fig = Figure(figsize=PAGE_IN)
    fig.text(0.5, 1 - TOP_IN / height_in, f"Design review: {case.name}", ha="center",
             va="top", fontsize=15, weight="bold")
    step_in = size * LINE_SPACING / 72
    char_in = CHAR_EM * size / 72
    y = height_in - TOP_IN - title_in

    def draw(lines: list[Line], x0_in: float, y_in: float) -> None:
        for k, line in enumerate(lines):
            for seg in line:
                if seg.text.strip():
                    fig.text((x0_in + seg.column * char_in) / width_in,
                             (y_in - k * step_in) / height_in, seg.text, va="top", ha="left",
                             fontsize=size, family="monospace", color=seg.colour,
                             weight="bold" if seg.bold else "normal")

    draw(top, MARGIN_IN, y)
    y -= (len(top) + 1) * step_in
    draw(left, MARGIN_IN, y)
    draw(right, MARGIN_IN + usable_w / 2 + 0.1, y)
    return fig
