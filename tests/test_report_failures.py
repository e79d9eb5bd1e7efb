"""A failing requirement has a marked, labelled point on its own page (issue 47): trim's
unattainable airspeeds and throttles above the limit, the ground roll beyond the runway."""

from __future__ import annotations

import numpy as np
import pytest

from tests.layout_checks import text_overlaps, texts_off_the_page

RED = "#c62828"  # the limit's colour (report/style.py)


def _drawn(sets: dict[str, float]):
    from tuflexperf.analysis.study import Study
    from tuflexperf.io.case import load_case
    from tuflexperf.io.dotted import with_values
    from tuflexperf.report import figures as fg
    from tuflexperf.report.data import run_analyses

    fg.use_agg()
    case = with_values(load_case(None), sets)
    return case, run_analyses(Study(case)), fg


def _red_points(fig) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(label, x, y) of every red marker set drawn without a line."""
    return [(line.get_label(), np.asarray(line.get_xdata(), float),
             np.asarray(line.get_ydata(), float))
            for ax in fig.axes for line in ax.get_lines()
            if line.get_color() == RED and line.get_linestyle() == "None"
            and line.get_marker() not in (None, "None", "")]


def _texts(fig) -> str:
    return " ".join(t.get_text() for ax in fig.axes for t in ax.texts)


@pytest.fixture(scope="module")
def heavy():
    return _drawn({"aircraft.mass_kg": 30.0})


def test_trim_unattainable_airspeeds_are_marked_in_red_with_a_label(heavy) -> None:
    case, analyses, fg = heavy
    trim = analyses.trim
    missing = np.asarray(trim.airspeed_m_s)[[r is not None for r in trim.reasons]]
    assert missing.size, "the 30 kg case no longer fails trim: choose another"
    fig = fg.trim_oei_throttle(case, analyses)
    marked = [(label, x) for label, x, y in _red_points(fig) if "not attainable" in label]
    assert marked and all(label.startswith("FAIL") for label, _ in marked)
    assert np.allclose(np.sort(np.concatenate([x for _, x in marked])), np.sort(missing))
    title = fig.axes[0].get_title()
    assert f"at {missing[0]:.1f}" in title and "trim FAIL" in title
    assert text_overlaps(fig) == [] and texts_off_the_page(fig) == []


def test_a_trim_throttle_above_the_limit_is_marked_where_it_is() -> None:
    case, analyses, fg = _drawn({"requirements.envelope.max_trim_throttle": 0.9})
    throttle = np.asarray(analyses.trim.throttle, dtype=float)
    over = np.asarray(analyses.trim.airspeed_m_s)[np.isfinite(throttle) & (throttle > 0.9)]
    assert over.size
    fig = fg.trim_oei_throttle(case, analyses)
    marked = [x for label, x, _ in _red_points(fig) if "above the limit" in label]
    assert len(marked) == 1 and np.allclose(marked[0], over)
    assert "trim FAIL: throttle up to" in fig.axes[0].get_title()


def test_a_ground_roll_beyond_the_runway_is_marked_at_lift_off(heavy) -> None:
    case, analyses, fg = heavy
    roll, limit = analyses.takeoff.ground_roll_m, case.requirements.takeoff.max_ground_roll_m
    assert roll > limit
    fig = fg.takeoff_history(case, analyses)
    marked = [(label, x) for label, x, _ in _red_points(fig) if "ground roll" in label]
    assert len(marked) == 1 and marked[0][1][0] == pytest.approx(roll)
    assert f"{roll - limit:.1f} m beyond the {limit:g} m limit" in _texts(fig)
    assert text_overlaps(fig) == [] and texts_off_the_page(fig) == []


def test_a_passing_case_marks_no_failure() -> None:
    case, analyses, fg = _drawn({})
    for fig in (fg.trim_oei_throttle(case, analyses), fg.takeoff_history(case, analyses)):
        assert not [label for label, _, _ in _red_points(fig) if "FAIL" in label]
        assert "FAIL" not in _texts(fig) + " ".join(ax.get_title() for ax in fig.axes)
