"""The report pages of issues 11-13 (report/analysis_figures.py): point performance, the
thrust model's confidence band, the tornado and the mission.

Each page is checked present (PNG and PDF page) for the shipped case, with every axis
labelled with a unit, legends off the data and no overlapping text; the mission page for
a case with a mission; and every page for a failing made-up case (no traceback).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case
from tests.test_report_layout import _drawn_inputs, _report
from tuflexperf.cli import app

ROOT = Path(__file__).resolve().parents[1]
NEW_PAGES = ("06b_thrust_band", "08b_performance", "11_tornado")
UNIT = re.compile(r"\((m/s|N|s|m|V|A|min|fraction|-)\)")
MISSION_LINE = ("  mission: {file: ../data/tuflex/missions/test_flight.yaml, "
                "min_landing_charge_fraction: 0.2}")


def _pdf_pages(path: Path) -> int:
    return len(re.findall(rb"/Type\s*/Page(?![a-zA-Z])", path.read_bytes()))


def _shipped_copy(folder: Path, mission: str | None = MISSION_LINE, mass_kg: float | None = None,
                  cruise_min: float | None = None) -> Path:
    """The shipped case and data copied, optionally with the test-flight mission as a
    requirement, a changed mass, or a longer cruise."""
    copy_shipped_case(folder)
    case = folder / "requirements" / "tuflex.yaml"
    if mission is not None:
        case.write_text(case.read_text().rstrip("\n") + "\n" + mission + "\n")
    if mass_kg is not None:
        aircraft = folder / "data" / "tuflex" / "aircraft.yaml"
        lines = [f"mass_kg: {mass_kg}" if line.startswith("mass_kg:") else line
                 for line in aircraft.read_text().splitlines()]
        aircraft.write_text("\n".join(lines) + "\n")
    if cruise_min is not None:
        plan = folder / "data" / "tuflex" / "missions" / "test_flight.yaml"
        plan.write_text(plan.read_text().replace("time_min: 8}", f"time_min: {cruise_min:g}}}"))
    return case


# --- layout checks (display coordinates, after drawing) -----------------------------------
def _drawn(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # as the PNG writer draws it (constrained layout solved)
    canvas.draw()
    return canvas.get_renderer()


def _assert_axes_have_units(name: str, fig) -> None:
    for ax in fig.axes:
        if not ax.get_visible() or (not ax.get_xticks().size and not ax.get_yticks().size):
            continue  # a note or table panel
        if not ax.axison:
            continue
        x_labels = [a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax)]
        assert any(UNIT.search(x) for x in x_labels), f"{name}: x label {x_labels!r}"
        if _categorical(ax.yaxis):
            continue  # rows named by their labels (the tornado's parameters): no unit
        y_labels = [a.get_ylabel() for a in ax.get_shared_y_axes().get_siblings(ax)]
        assert any(UNIT.search(y) for y in y_labels), f"{name}: y label {y_labels!r}"


def _categorical(axis) -> bool:
    labels = [t.get_text() for t in axis.get_ticklabels() if t.get_text()]
    return bool(labels) and not all(re.fullmatch(r"[\u2212\-+0-9.e]+", x) for x in labels)


def _assert_legends_off_data(name: str, fig) -> None:
    renderer = _drawn(fig)
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        box = legend.get_window_extent(renderer)
        for line in ax.get_lines():
            xy = np.column_stack([np.asarray(line.get_xdata(), dtype=float),
                                  np.asarray(line.get_ydata(), dtype=float)])
            xy = xy[np.all(np.isfinite(xy), axis=1)]
            if not xy.size:
                continue
            if line.get_transform() != ax.transData:  # axhline/axvline: span the axes
                continue
            points = ax.transData.transform(xy)
            inside = ((points[:, 0] > box.x0) & (points[:, 0] < box.x1)
                      & (points[:, 1] > box.y0) & (points[:, 1] < box.y1))
            assert not inside.any(), f"{name}: legend covers {line.get_label()!r}"


def _texts(fig, renderer):
    from matplotlib.table import Table
    from matplotlib.text import Text

    skip = {id(t) for table in fig.findobj(Table) for t in table.findobj(Text)}
    for ax in fig.axes:  # tick labels outside the view are never drawn
        for axis in (ax.xaxis, ax.yaxis):
            low, high = sorted(axis.get_view_interval())
            span = high - low
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not low - 1e-9 * span <= tick.get_loc() <= high + 1e-9 * span:
                    skip.update((id(tick.label1), id(tick.label2)))
    for legend in [a.get_legend() for a in fig.axes] + list(fig.legends):
        if legend is not None:
            skip.update(id(t) for t in legend.findobj(Text))
    out = []
    for text in fig.findobj(Text):
        if id(text) in skip or not text.get_visible() or not text.get_text().strip():
            continue
        box = text.get_window_extent(renderer)
        if box.width > 0 and box.height > 0:
            out.append((text.get_text(), box))
    return out


def _assert_no_text_overlap(name: str, fig) -> None:
    renderer = _drawn(fig)
    texts = _texts(fig, renderer)
    for i, (a, box_a) in enumerate(texts):
        for b, box_b in texts[i + 1:]:
            overlap_x = min(box_a.x1, box_b.x1) - max(box_a.x0, box_b.x0)
            overlap_y = min(box_a.y1, box_b.y1) - max(box_a.y0, box_b.y0)
            assert not (overlap_x > 1.0 and overlap_y > 1.0), f"{name}: {a!r} overlaps {b!r}"
    page = fig.bbox
    for text, box in texts:  # nothing cut off at the page's edge
        assert box.x0 >= page.x0 - 1 and box.x1 <= page.x1 + 1, f"{name}: {text!r} cut off"


def _all_text(fig) -> str:
    """Every text of the figure (titles, labels, table cells), one per line."""
    from matplotlib.table import Table
    from matplotlib.text import Text

    cells = [c.get_text().get_text() for t in fig.findobj(Table) for c in t.get_celld().values()]
    return "\n".join([t.get_text() for t in fig.findobj(Text)] + cells)


def _figures(case_path: Path | None):
    from tuflexperf.report import analysis_figures as af

    case, analyses, measured = _drawn_inputs(case_path)
    figures = {
        "performance": af.performance(case, analyses),
        "thrust_band": af.thrust_band(case, analyses, measured),
        "tornado": af.tornado(case, analyses),
    }
    if analyses.mission is not None or analyses.mission_note is not None:
        figures["mission"] = af.mission(case, analyses)
    return case, analyses, figures


# --- the shipped case ---------------------------------------------------------------------
@pytest.fixture(scope="module")
def shipped(shipped_report):
    return shipped_report.out, shipped_report.data  # drawn once per session (conftest)


def test_shipped_report_has_every_new_page_as_png_and_pdf_page(shipped):
    out, data = shipped
    names = {Path(f).stem for f in data["figures"]}
    assert set(NEW_PAGES) <= names
    assert "10_mission" not in names  # the shipped case states no mission
    for name in NEW_PAGES:
        assert (out / f"{name}.png").stat().st_size > 20_000, name
    # title + one page per PNG + hashes (+ notes)
    assert _pdf_pages(out / "review.pdf") == data["pages"] >= len(data["figures"]) + 2
    # the pages sort in review order: model band after the model pages, performance after
    # trim, tornado last
    order = sorted(names)
    assert order.index("06b_thrust_band") > order.index("06_model_vs_measured")
    assert order.index("08b_performance") > order.index("08_trim_oei_throttle")
    assert order[-1] == "11_tornado"
    # the one-page PDFs the report is put together from stay out of it
    assert not list(out.glob("*.pickle*")) and not list(out.glob("*.part"))
    assert [p.name for p in out.glob("*.pdf")] == ["review.pdf"]


@pytest.fixture(scope="module")
def shipped_figures():
    return _figures(None)


def test_shipped_pages_have_units_legends_off_data_and_no_overlapping_text(shipped_figures):
    _, _, figures = shipped_figures
    assert set(figures) == {"performance", "thrust_band", "tornado"}
    for name, fig in figures.items():
        assert fig._suptitle is not None and fig._suptitle.get_text(), name
        w, h = fig.get_size_inches()
        assert abs(w - 11.69) < 0.01 and abs(h - 8.27) < 0.01, name  # A4 landscape
        _assert_axes_have_units(name, fig)
        _assert_legends_off_data(name, fig)
        _assert_no_text_overlap(name, fig)


def test_performance_page_draws_the_results_curves_and_speeds(shipped_figures):
    _, analyses, figures = shipped_figures
    perf = analyses.performance
    ax = figures["performance"].axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    curve = lines["all engines, full throttle"]
    np.testing.assert_array_equal(curve.get_xdata(), perf.climb_airspeed_m_s)
    np.testing.assert_array_equal(curve.get_ydata(), perf.climb_rate_curve_m_s)
    labels = " ".join(lines)
    for speed in (perf.best_climb_rate_speed_m_s, perf.best_climb_angle_speed_m_s,
                  perf.minimum_drag_speed_m_s, perf.max_level_speed_m_s,
                  perf.stall_speed_m_s):
        assert f"{speed:.1f} m/s" in labels
    for c in perf.oei:
        assert any(c.dead_engine in label for label in lines)
    text = _all_text(figures["performance"])
    from tuflexperf.messages import ceiling_text  # to 10 m (issue 47: not to 0.1 m)

    assert (f"{ceiling_text(perf.service_ceiling_m)} m" in text
            and f"{ceiling_text(perf.absolute_ceiling_m)} m" in text)
    # a gradient is sin(gamma), labelled so (not a percent, which reads as the tangent)
    assert f"sin(gamma) {perf.oei_critical.max_climb_gradient:.3f}" in text


def test_oei_climb_curves_agree_with_the_oei_answers(shipped_figures):
    """The dead-engine curves carried by PerformanceResult: their best gradient is the
    solved OEI gradient, and they cross zero at the solved OEI max level speed."""
    _, analyses, _ = shipped_figures
    perf = analyses.performance
    v = perf.climb_airspeed_m_s
    assert perf.oei
    for c in perf.oei:
        gradient = c.climb_rate_curve_m_s / v
        assert gradient.max() <= c.max_climb_gradient + 1e-12
        assert gradient.max() == pytest.approx(c.max_climb_gradient, abs=2e-4)
        crossing = np.flatnonzero(np.diff(np.sign(c.climb_rate_curve_m_s)) < 0)
        assert crossing.size == 1
        k = int(crossing[0])
        root = np.interp(0.0, c.climb_rate_curve_m_s[[k + 1, k]], v[[k + 1, k]])
        assert root == pytest.approx(c.max_level_speed_m_s, abs=0.02)
        assert c.to_dict()["climb_rate_m_s"] == pytest.approx(list(c.climb_rate_curve_m_s))


def test_thrust_band_page_shows_the_band_the_tested_range_and_the_points(shipped_figures):
    case, analyses, figures = shipped_figures
    fig = figures["thrust_band"]
    axes = [a for a in fig.axes if a.get_visible()]
    assert len(axes) == len(case.propulsion.engines)
    high = case.propulsion.tested_airspeed_m_s[1]
    for ax in axes:
        spans = [p for p in ax.patches if abs(p.get_x() - high) < 1e-9]
        assert spans, "extrapolated airspeeds not shaded"
        assert len(ax.collections) >= 3  # one band per throttle
        points = [line for line in ax.get_lines() if line.get_marker() == "o"]
        assert points and sum(len(p.get_xdata()) for p in points) > 10
    # the band is the analysis' own: wider beyond the tested range than inside it
    band = analyses.thrust_bands[-1]
    inside = band.sd_n[band.airspeed_m_s <= high].max()
    assert band.sd_n[band.airspeed_m_s > high].min() > inside


def test_tornado_labels_each_bar_with_the_limit_value_or_none_in_range(shipped_figures):
    _, analyses, figures = shipped_figures
    fig = figures["tornado"]
    limits = analyses.limit_values
    assert limits
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    for t in analyses.tornadoes:
        for bar in t.bars:
            value, binds, _ = limits[(t.requirement, bar.parameter)]
            if value is None:
                assert binds == "none in range"
            elif t.nominal_value is None:  # no bar: the note lists where it would hold
                assert any(f"{value:.4g}" in " ".join(x.split()) for x in texts), (
                    t.requirement, bar.parameter)
            else:
                assert any(x.startswith(f"{value:.4g}") for x in texts), (t.requirement,
                                                                          bar.parameter)
    assert "none in range" in texts
    # the mass limit of the ground roll is the margins' root
    mass = limits[("takeoff_ground_roll", "aircraft.mass_kg")][0]
    assert f"{mass:.4g} kg" in texts


def test_every_png_is_its_page_of_the_pdf_pixel_for_pixel(shipped):
    """Each page is drawn once (a vector PDF page); its PNG is that page rasterised, so the
    PNG shows exactly what the PDF does, in the PDF's page order (title page first)."""
    import pypdfium2
    from PIL import Image

    from tuflexperf.report.build import PNG_DPI

    out, data = shipped
    pngs = sorted(Path(f) for f in data["figures"])
    document = pypdfium2.PdfDocument(out / "review.pdf")
    try:
        assert len(document) == data["pages"]
        for page, png in enumerate(pngs, start=1):  # page 0 is the title page
            rendered = np.asarray(document[page].render(scale=PNG_DPI / 72.0).to_pil())
            written = np.asarray(Image.open(png).convert("RGB"))
            np.testing.assert_array_equal(written, rendered, err_msg=png.name)
        # and no PNG matches a neighbouring page: the comparison can tell pages apart
        other = np.asarray(document[1].render(scale=PNG_DPI / 72.0).to_pil())
        assert not np.array_equal(np.asarray(Image.open(pngs[1]).convert("RGB")), other)
    finally:
        document.close()
    with Image.open(pngs[0]) as image:
        assert image.info.get("Software", "").startswith("tuflexperf")  # ours (SPEC 5)
        assert round(image.info["dpi"][0]) == PNG_DPI


# --- a case with a mission ------------------------------------------------------------------
@pytest.fixture(scope="module")
def mission_case(tmp_path_factory):
    return _shipped_copy(tmp_path_factory.mktemp("mission"))


def test_mission_page_is_in_the_report_of_a_case_with_a_mission(mission_case, tmp_path):
    data = _report(mission_case, tmp_path / "review")
    names = {Path(f).stem for f in data["figures"]}
    assert {"10_mission", *NEW_PAGES} <= names
    assert _pdf_pages(Path(data["pdf"])) == data["pages"]
    # the report's verdict is check's (the shipped endurance is UNPROVEN: the discharge runs)
    checked = json.loads(CliRunner().invoke(app, ["check", "--json", "--case",
                                                  str(mission_case)]).stdout)
    assert data["verdict"] == checked["verdict"] == "UNPROVEN" and data["passed"] is False


def test_mission_page_draws_the_history_reserve_and_cutoff(mission_case):
    case, analyses, figures = _figures(mission_case)
    result = analyses.mission
    assert result is not None and result.attainable
    fig = figures["mission"]
    _assert_axes_have_units("mission", fig)
    _assert_legends_off_data("mission", fig)
    _assert_no_text_overlap("mission", fig)
    minutes = result.history["time_s"] / 60.0
    drawn = {(ax.get_ylabel(), line.get_label()): line for ax in fig.axes
             for line in ax.get_lines()}
    for name in result.engines:
        charge = next(line for (y, label), line in drawn.items()
                      if "charge" in y and label == name)
        np.testing.assert_array_equal(charge.get_xdata(), minutes)
        np.testing.assert_array_equal(charge.get_ydata(),
                                      result.history[f"charge_fraction_{name}"])
    reserve = [line for (y, label), line in drawn.items() if "reserve" in label]
    assert reserve and np.allclose(reserve[0].get_ydata(), 0.2)
    cutoff = [line for (y, label), line in drawn.items() if "cut-off" in label]
    assert cutoff and np.allclose(cutoff[0].get_ydata(),
                                  analyses.characterisation.battery.cutoff_voltage_v)
    failure = [label for (_, label) in drawn if label.endswith("fails")]
    assert failure == ["EDF2 fails"]
    # every segment in the table, with its flown time
    cells = _all_text(fig).split("\n")
    for s in result.segments:
        assert f"{s.time_s / 60.0:.2f}" in cells
    assert "PASS" in fig._suptitle.get_text()


def test_a_mission_ending_at_cutoff_is_drawn_to_its_end_with_the_reason(tmp_path):
    case_path = _shipped_copy(tmp_path / "long", cruise_min=40)
    _, analyses, figures = _figures(case_path)
    result = analyses.mission
    assert result is not None and not result.attainable
    title = figures["mission"]._suptitle.get_text().replace("\n", " ")
    assert "NOT ATTAINABLE" in title and "cut-off" in title
    lines = [line for ax in figures["mission"].axes for line in ax.get_lines()
             if line.get_marker() == "x"]
    assert lines and lines[0].get_xdata()[0] == pytest.approx(result.history["time_s"][-1] / 60)
    _assert_no_text_overlap("mission (cut-off)", figures["mission"])


# --- a failing made-up case -------------------------------------------------------------------
def test_a_failing_case_draws_every_page_and_says_why(tmp_path):
    """Mass 60 kg: stall above the climb speed of the mission, trim below stall at the
    envelope's floor, no OEI level flight: every page drawn, reasons on the pages."""
    case_path = _shipped_copy(tmp_path / "heavy", mass_kg=60)
    data = _report(case_path, tmp_path / "review")
    assert data["passed"] is False
    names = {Path(f).stem for f in data["figures"]}
    assert {"10_mission", *NEW_PAGES} <= names
    assert _pdf_pages(Path(data["pdf"])) == data["pages"]
    _, analyses, figures = _figures(case_path)
    # the take-off is flown, the climb below stall ends the flight: drawn to there, and why
    mission = analyses.mission
    assert mission is not None and not mission.attainable and "below stall" in mission.reason
    assert [s.type for s in mission.segments] == ["takeoff"]
    assert "below stall" in figures["mission"]._suptitle.get_text().replace("\n", " ")
    tornado_text = " ".join(t.get_text() for ax in figures["tornado"].axes for t in ax.texts)
    assert "not attainable at the nominal case" in tornado_text
    assert "no level flight" in _all_text(figures["performance"])
    for name, fig in figures.items():
        _assert_no_text_overlap(f"{name} (failing)", fig)


def test_a_case_without_measured_data_or_battery_draws_the_pages(tmp_path):
    from tests.conftest import write_case

    case_path = write_case(tmp_path / "case")
    data = _report(case_path, tmp_path / "review")
    names = {Path(f).stem for f in data["figures"]}
    assert set(NEW_PAGES) <= names


def test_trim_below_stall_is_drawn_as_below_stall_and_five_tornadoes_stay_on_the_page(tmp_path):
    """34 kg at 500 m, ISA+15: stall 17.2 m/s above the envelope's 15 m/s floor, so trim is
    not attainable there *below stall* (not 'more than full throttle'); with the obstacle
    requirement five tornado panels, every label and note on the page, none over another."""
    from tests.layout_checks import text_overlaps, texts_off_the_page

    case_path = _shipped_copy(tmp_path / "heavy", mission=None, mass_kg=34)
    text = case_path.read_text()
    text = text.replace("takeoff: {max_ground_roll_m: 60}",
                        "takeoff: {max_ground_roll_m: 60, max_distance_to_obstacle_m: 150}")
    text = text.replace("atmosphere: {altitude_m: 0, temperature_offset_k: 0}",
                        "atmosphere: {altitude_m: 500, temperature_offset_k: 15}")
    case_path.write_text(text)
    from tuflexperf.report import figures as fg

    case, analyses, figures = _figures(case_path)
    assert analyses.trim.reasons[0] == "below stall"
    trim = fg.trim_oei_throttle(case, analyses)
    labels = [t.get_text() for legend in trim.legends + [a.get_legend() for a in trim.axes]
              if legend is not None for t in legend.get_texts()]
    assert "trim not attainable: below stall" in labels
    assert not any(label.startswith("trim not attainable: needs") for label in labels)
    tornado = figures["tornado"]
    assert len([ax for ax in tornado.axes if ax.get_visible() and ax.get_label() != "legend"]) == 5
    assert text_overlaps(tornado) == []
    assert texts_off_the_page(tornado) == []
