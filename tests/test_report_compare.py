"""``report --compare`` (issue 47 item 5) and the review's new pages (items 3, 4, 6), read
from the PDF by a PDF engine (PDFium's text extraction), never from the writer's state.

One report of the shipped case compared with a heavier copy of it (28 kg, renamed): its
take-off fails where the shipped one passes, so the side-by-side table must show a change
of verdict.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case
from tuflexperf.cli import app

runner = CliRunner()
HEAVY_NAME = "TU-Flex heavy copy"
HEAVY_KG = 28.0


def _heavy_copy(folder: Path) -> Path:
    case = copy_shipped_case(folder)
    case.write_text(re.sub(r"(?m)^name: .*$", f"name: {HEAVY_NAME}", case.read_text()))
    aircraft = folder / "data" / "tuflex" / "aircraft.yaml"
    aircraft.write_text(re.sub(r"(?m)^mass_kg: .*$", f"mass_kg: {HEAVY_KG}",
                               aircraft.read_text()))
    return case


def _pdf_text(path: str) -> list[str]:
    import pypdfium2

    document = pypdfium2.PdfDocument(path)
    try:
        return [document[k].get_textpage().get_text_range() for k in range(len(document))]
    finally:
        document.close()


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    folder = tmp_path_factory.mktemp("compare")
    heavy = _heavy_copy(folder / "heavy")
    out = folder / "review"
    result = runner.invoke(app, ["report", "--out", str(out), "--json", "--compare", str(heavy)])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    data["text"] = _pdf_text(data["pdf"])
    return data


def _flat(text: str) -> str:
    return " ".join(text.split())


def _page(report: dict, title: str) -> str:
    pages = [_flat(t) for t in report["text"] if title in _flat(t)]
    assert pages, f"no page with {title!r}"
    return pages[0]


def test_the_pdf_names_both_cases_on_every_page(compared):
    from tuflexperf.io.case import load_case

    shipped = load_case(None).name
    for k, text in enumerate(compared["text"], start=1):
        flat = _flat(text)
        assert f"A: {shipped}" in flat and f"B: {HEAVY_NAME}" in flat, f"page {k}"
    assert [c["name"] for c in compared["compared"]] == [HEAVY_NAME]


def test_the_verdicts_stand_side_by_side_with_what_changed(compared):
    page = _page(compared, "Configurations compared")
    for column in ("A value", "A verdict", "B value", "B verdict", "B - A", "B margin - A"):
        assert column in page
    row = re.search(r"takeoff_ground_roll <= 60 m (\S+) m (PASS|FAIL) (\S+) m (PASS|FAIL) "
                    r"(\S+) m \(([-+][\d.]+) %\)", page)
    assert row, page
    a, a_word, b, b_word, change, share = row.groups()
    assert (a_word, b_word) == ("PASS", "FAIL")  # the heavy copy fails its runway
    assert float(change) == pytest.approx(float(b) - float(a), abs=0.02)
    assert float(share) == pytest.approx(100 * (float(b) / float(a) - 1), abs=0.1)
    assert "NOT all met" in page and HEAVY_NAME in page


def test_comparable_figures_draw_every_configuration(compared):
    """Each overlay's own legend entry (the footer names B on every page: not that)."""
    b = f"B: {HEAVY_NAME}"
    for title, entry in (("Trim and one-engine-inoperative", f"{b}: trim, all engines"),
                         ("Altitude-airspeed envelope", f"{b}: all engines"),
                         ("Endurance and range against take-off mass",
                          f"take-off mass {HEAVY_KG:.2f} kg"),
                         ("Take-off height profile", f"{b}: height above the runway"),
                         ("Take-off of", f"{b}: ground run, lift-off at"),
                         ("Endurance of", f"{b}: flight endurance")):
        assert entry in _page(compared, title), title


def test_the_new_pages_are_there_with_their_numbers(compared):
    envelope = _page(compared, "Altitude-airspeed envelope")
    assert "ceiling of level flight" in envelope and "dead (windmilling)" in envelope
    profile = _page(compared, "Take-off height profile")
    assert re.search(r"obstacle cleared at [\d.]+ m", profile)
    predicted = _page(compared, "predicted against measured, on one basis")
    assert "discharge runs" in predicted and "\u03c1ref = 1.204" in predicted


def test_every_thrust_page_states_its_basis(compared):
    """Item 3: the model's reference density and the drag convention on every thrust axis."""
    for title in ("poly22 surface", "95 % confidence band", "Sine sweep of",
                  "driven by the logged throttle", "raw and processed force"):
        page = _page(compared, title)
        assert "\u03c1ref = 1.204 kg/m" in page, title
        assert "drag D > 0 rearward" in page, title


def test_the_sweep_page_says_the_shipped_dynamics_miss_the_amplitude(compared):
    page = _page(compared, "Sine sweep of")
    assert re.search(r"propulsion file \(50 ms dead time \+ 0 ms lag\) does NOT reproduce the "
                     r"measured amplitude within 20 %", page), page
    assert "amplitude error, model / measured - 1" in page
    assert "throttle-step fit" in page and "sine-sweep fit" in page


def test_a_missing_compare_file_is_bad_input(tmp_path):
    result = runner.invoke(app, ["report", "--out", str(tmp_path / "r"), "--compare",
                                 str(tmp_path / "nope.yaml")])
    assert result.exit_code == 2
    assert "--compare" in result.output and "Traceback" not in result.output
    assert not (tmp_path / "r").exists()
