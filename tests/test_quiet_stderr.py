"""Nothing but the tool's own one-line messages on stderr (outside audit of warnings).

Each command runs in its own process: Python shows a warning once per place and process, so
an earlier test in this one could hide it.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.conftest import copy_shipped_case


def _run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "tuflexperf", *args], capture_output=True,
                          text=True, cwd=cwd)


@pytest.mark.parametrize(("args", "code"), [
    # margins' search range is 0.5x-2x the nominal: 2 x 1e308 overflowed in numpy.linspace
    # (margins explores: exit 0, every requirement failing)
    (("margins", "--set", "aircraft.cd0=1e308", "--json"), 0),
    # matplotlib's tick arithmetic overflowed on axes near the float limit
    (("sweep", "--vary", "aircraft.cd0=1e300:1e308:2", "--plot", "{tmp}/p.png"), 0),
    # a roll whose net force all but vanishes: one line says why (CasADi's CVODES, which
    # integrated it once, printed each try's inputs, 54 lines, before it)
    (("check", "--json", "--set", "aircraft.mass_kg=11.446817162898647",
      "--set", "aircraft.takeoff.cl_ground=2.0", "--set", "aircraft.cl_max=2.0",
      "--set", "aircraft.takeoff.rolling_friction=1.0",
      "--set", "aircraft.takeoff.liftoff_speed_factor=1.1359427930494517"), 1),
])
def test_extreme_values_leave_stderr_to_the_tool(tmp_path, args, code) -> None:
    done = _run(*(a.format(tmp=tmp_path) for a in args))
    assert done.returncode == code, done.stderr
    assert "Warning" not in done.stderr and len(done.stderr.splitlines()) <= 1, done.stderr


def test_a_long_note_is_wrapped_on_its_page() -> None:
    """The report's notes page ran a 240-character note off the page (its reason cut)."""
    from tuflexperf.report import figures as fg

    fg.use_agg()
    note = "- " + "the pack reaches its cut-off in the climb to the pattern altitude " * 6
    page = fg.text_page("What this report leaves out, and why", [note, "- short"])
    text = page.axes[0].texts[0].get_text().splitlines()
    assert len(text) > 2 and text[-1] == "- short"
    assert " ".join(t.strip() for t in text[:-1]) == note.strip()
    assert all(line.startswith("  ") for line in text[1:-1])  # under the bullet's text
    page.canvas.draw()
    box = page.axes[0].texts[0].get_window_extent()
    assert box.x1 <= page.bbox.x1  # inside the page


def test_a_report_of_a_case_that_cannot_cruise_is_quiet(tmp_path) -> None:
    path = copy_shipped_case(tmp_path)
    done = _run("report", "--case", str(path), "--out", str(tmp_path / "review"),
                "--set", "battery.mission.pattern_altitude_m=5000")
    assert done.returncode in (0, 1), done.stderr
    assert "Warning" not in done.stderr, done.stderr
    # the title page says the inputs' sha256 are on the last page: after the notes
    import pypdfium2 as pdfium

    pdf = pdfium.PdfDocument(str(tmp_path / "review" / "review.pdf"))
    pages = [pdf[i].get_textpage().get_text_range() for i in range(len(pdf))]
    assert "on the last page" in pages[0]
    assert "What this report leaves out" in pages[-2] and "no best endurance" in pages[-2]
    assert "sha256" in pages[-1] and "tuflex.yaml" in pages[-1]
