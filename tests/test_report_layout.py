"""The review's layout (issue 15): A4 pages, verdicts on the first page, a failing aircraft."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case
from tests.layout_checks import (
    legend_overlaps,
    missing_units,
    text_over_data,
    text_overlaps,
    texts_off_the_page,
)
from tuflexperf.cli import app

ROOT = Path(__file__).resolve().parents[1]
A4_PT = (841.89, 595.28)  # landscape, 297 x 210 mm


def _media_boxes(pdf: Path) -> list[tuple[float, float]]:
    boxes = re.findall(rb"/MediaBox\s*\[\s*([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s*\]",
                       pdf.read_bytes())
    return [(float(x1) - float(x0), float(y1) - float(y0)) for x0, y0, x1, y1 in boxes]


def _report(case: Path | None, out: Path) -> dict:
    args = ["report", "--out", str(out), "--json"]
    if case is not None:
        args += ["--case", str(case)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output
    return json.loads(result.stdout)


def test_every_page_is_a4_and_the_first_page_carries_every_verdict(shipped_report) -> None:
    from tests.conftest import title_lines
    from tuflexperf.analysis.requirements import check_case
    from tuflexperf.io.case import load_case
    from tuflexperf.report.data import load_measured, run_analyses

    data = shipped_report.data
    boxes = _media_boxes(Path(data["pdf"]))
    assert len(boxes) == data["pages"]
    for width, height in boxes:
        assert abs(width - A4_PT[0]) < 1.5 and abs(height - A4_PT[1]) < 1.5
    case = load_case(None)
    analyses = run_analyses(case)
    text = "\n".join(title_lines(case, load_measured(case, None), analyses))
    for verdict in check_case(case):
        assert re.search(rf"{verdict.name}\s.*\s(PASS|FAIL|UNPROVEN)", text), verdict.name
    assert "sha256" not in text.split("every input file")[0]  # hashes live on the last page
    assert "reconstructed" in text and "synthetic" in text  # provenance classes stated


def test_a_failing_aircraft_still_gets_its_review(tmp_path: Path) -> None:
    data = _report(_failing_copy(tmp_path), tmp_path / "review")
    assert data["passed"] is False
    assert Path(data["pdf"]).is_file()
    assert (tmp_path / "review" / "01_requirements.png").is_file()


# --- layout of every figure: legends off the data, no text on text, units on every axis ---------
def _drawn_inputs(case_path: Path | None) -> tuple:
    """What build.py draws from: the case, its analyses (one Study) and the measured runs."""
    from tuflexperf.analysis.study import Study
    from tuflexperf.io.case import load_case
    from tuflexperf.report import figures as fg
    from tuflexperf.report.data import load_measured, run_analyses

    fg.use_agg()
    case = load_case(case_path)
    return case, run_analyses(Study(case)), load_measured(case, None)


def _all_figures(case_path: Path | None) -> dict[str, object]:
    """Every figure of the report for a case, drawn in-process (as build.py draws them)."""
    from tuflexperf.report import figures as fg

    case, analyses, measured = _drawn_inputs(case_path)
    figures = {
        "requirements": fg.requirement_table(case, analyses),
        "thrust_required_available": fg.thrust_required_available(case, analyses),
        "takeoff": fg.takeoff_history(case, analyses),
    }
    for index, engine in enumerate(case.propulsion.engines):
        figures[f"surface_{engine.name}"] = fg.thrust_surface(case, measured, index)
    if analyses.trim is not None:
        figures["trim_oei"] = fg.trim_oei_throttle(case, analyses)
    if analyses.characterisation is not None:
        figures["endurance"] = fg.endurance(case, analyses)
    if measured.processed is not None:
        figures["run_processing"] = fg.run_processing(measured.processed)
    if measured.sweep is not None:
        figures["sine_sweep"] = fg.sine_sweep(measured, case)
    if measured.comparisons:
        figures["model_vs_measured"] = fg.model_vs_measured(case, measured)
    from tuflexperf.report import review_figures as rf  # issue 47 item 4's pages

    figures["predicted_measured"] = rf.predicted_vs_measured(case, analyses, measured)
    figures["takeoff_profile"] = rf.takeoff_profile(case, analyses)
    figures["flight_envelope"] = rf.flight_envelope(case, analyses)
    if case.battery_path is not None:
        figures["mass_trade"] = rf.mass_trade(case, analyses)
    return figures


def _failing_copy(folder: Path) -> Path:
    """The shipped case with a 200 kg aircraft: take-off, trim and endurance all fail."""
    copy_shipped_case(folder)
    aircraft = folder / "data" / "tuflex" / "aircraft.yaml"
    lines = [("mass_kg: 200" if line.startswith("mass_kg:") else line)
             for line in aircraft.read_text().splitlines()]
    aircraft.write_text("\n".join(lines) + "\n")
    return folder / "requirements" / "tuflex.yaml"


@pytest.fixture(scope="module")
def report_figures(tmp_path_factory) -> dict[str, dict[str, object]]:
    from tests.conftest import write_case

    folder = tmp_path_factory.mktemp("layout")
    return {
        "shipped": _all_figures(None),
        "failing": _all_figures(_failing_copy(folder / "failing")),
        "made_up": _all_figures(write_case(folder / "made_up")),
    }


def _every(report_figures):
    for case, figures in report_figures.items():
        for name, fig in figures.items():
            yield f"{case}/{name}", fig


def test_the_failing_case_draws_its_failures(report_figures):
    """The made-up failing case is really failing: the layout tests see the FAIL pages."""
    from tuflexperf.io.case import load_case

    figures = report_figures["failing"]
    assert "NOT all met" in figures["requirements"]._suptitle.get_text()
    assert "not attainable" in figures["takeoff"]._suptitle.get_text()
    assert load_case(None).aircraft.mass_kg < 200


def test_no_legend_or_label_covers_plotted_data(report_figures):
    problems = [f"{name}: {p}" for name, fig in _every(report_figures)
                for p in legend_overlaps(fig) + text_over_data(fig)]
    assert not problems, "\n".join(problems)


def test_no_text_overlaps_other_text_or_runs_off_the_page(report_figures):
    problems = [f"{name}: {p}" for name, fig in _every(report_figures)
                for p in text_overlaps(fig) + texts_off_the_page(fig)]
    assert not problems, "\n".join(problems)


def test_every_axis_has_a_label_with_a_unit(report_figures):
    problems = [f"{name}: {p}" for name, fig in _every(report_figures)
                for p in missing_units(fig)]
    assert not problems, "\n".join(problems)


def test_the_checks_catch_a_bad_figure():
    """A legend over a line, two labels on top of each other and an axis without a unit
    are each flagged: the layout tests above can fail."""
    import numpy as np

    from tuflexperf.report import figures as fg

    fg.use_agg()
    fig = fg.new_figure()
    ax = fig.add_subplot()
    x = np.linspace(0.0, 10.0, 50)
    ax.plot(x, np.full_like(x, 9.5), label="a line through the upper right corner")
    ax.plot(x, x, label="a diagonal")
    ax.axhline(9.8, label="a horizontal of two points")
    ax.set_ylim(0, 10)
    ax.legend(loc="upper right")
    ax.annotate("label one", (5.0, 5.0))
    ax.annotate("label two", (5.05, 5.0))
    ax.set_xlabel("time (s)")
    ax.set_ylabel("no unit here")
    covered = legend_overlaps(fig)
    assert any("upper right corner" in p for p in covered)
    assert any("horizontal of two points" in p for p in covered)  # between its two vertices
    assert any("'label one' overlaps 'label two'" in p for p in text_overlaps(fig))
    assert any("'label one' covers" in p and "diagonal" in p for p in text_over_data(fig))
    assert missing_units(fig) == ["y axis without a unit: ['no unit here']"]
    ax.set_title("a title far too long for its axes " * 6)
    assert any("runs off the page" in p for p in texts_off_the_page(fig))

    good = fg.new_figure()
    ax = good.add_subplot()
    ax.plot(x, np.full_like(x, 9.5), label="a line through the upper right corner")
    fg.legend_outside(ax)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("force (N)")
    assert legend_overlaps(good) == text_overlaps(good) == text_over_data(good) == []
    assert texts_off_the_page(good) == []
    assert missing_units(good) == []


@pytest.mark.parametrize(("delay_s", "lag_s"), [(0.04, 0.08), (0.0, 0.05), (0.03, 0.0)])
def test_the_figures_dynamic_model_is_the_exported_step(tmp_path: Path, delay_s: float,
                                                        lag_s: float) -> None:
    """The sweep and model-vs-measured pages draw the model the exports carry: the CasADi
    ``tfp_thrust_step`` stepped over the same logged throttle gives the same thrust."""
    import copy

    import numpy as np
    import yaml

    from tests.conftest import MADE_UP_PROPULSION, model_from_propulsion_file
    from tuflexperf.export.model import thrust_step_function
    from tuflexperf.models.thrust import engine_thrust_n
    from tuflexperf.report.figures import dynamic_thrust_n

    data = copy.deepcopy(MADE_UP_PROPULSION)
    data.update(delay_s=delay_s, lag_s=lag_s)
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(data))
    prop = model_from_propulsion_file(path).propulsion
    dt, v, n = 0.005, 12.0, 150
    time = np.arange(n) * dt
    throttle = np.clip(0.5 + 0.4 * np.sin(2 * np.pi * 3.0 * time)
                       + np.random.default_rng(3).normal(0, 0.05, n), 0, 1)
    step = thrust_step_function(prop, dt)
    commands = np.tile(throttle[:, None], (1, len(prop.engines)))
    width = max(int(np.floor(delay_s / dt + 0.5)), 1)
    delay_state = np.full((len(prop.engines), width), throttle[0])
    lag_state = np.array([float(engine_thrust_n(e, throttle[0], v, 1.0)) for e in prop.engines])
    stepped = []
    for command in commands:
        thrust, _, delay_state, lag_state = step(delay_state, lag_state, command, v, 1.0)
        stepped.append(np.array(thrust).ravel())
    stepped = np.array(stepped)
    for k, engine in enumerate(prop.engines):
        drawn = dynamic_thrust_n(engine, time, throttle, v, 1.0, delay_s, lag_s)
        np.testing.assert_allclose(drawn, stepped[:, k], rtol=1e-12, atol=1e-12)


def test_a_long_take_off_title_stays_on_the_page(tmp_path: Path) -> None:
    """A lift-off that cannot climb away puts the obstacle's whole reason in the take-off
    page's title (~190 characters): it ran off both edges of the page."""
    from tuflexperf.report import figures as fg

    copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    aircraft.write_text("\n".join(("k: 0.3" if line.startswith("k:") else line)
                                  for line in aircraft.read_text().splitlines()) + "\n")
    case, analyses, _ = _drawn_inputs(tmp_path / "requirements" / "tuflex.yaml")
    fig = fg.takeoff_history(case, analyses)
    assert "is never" in fig._suptitle.get_text()  # wrapped: its words on two lines
    assert texts_off_the_page(fig) == []
