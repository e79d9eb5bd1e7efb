"""The review as a board reads it (issue 47): page 1 states every verdict, reason and caveat
that the terminal's ``check`` prints; every page carries a traceable footer.

Everything is read from the PDF by a PDF engine (PDFium's text extraction), never from the
writer's state, and compared with what ``check`` prints for the same case. One report of
the shipped case and one of a failing case (30 kg) per module: a report takes ~15 s.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

import tuflexperf
from tuflexperf.cli import app

runner = CliRunner()
FAILING = ["--set", "aircraft.mass_kg=30"]  # the take-off and trim fail at 30 kg
ROW = re.compile(r"^(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(PASS|FAIL|UNPROVEN)$")


def _report(parent: Path, extra: list[str]) -> dict:
    out = parent / "review"
    result = runner.invoke(app, ["report", "--out", str(out), "--json", *extra])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    import pypdfium2

    document = pypdfium2.PdfDocument(data["pdf"])
    try:
        data["text"] = [document[k].get_textpage().get_text_range() for k in range(len(document))]
    finally:
        document.close()
    return data


def _check(extra: list[str]) -> dict:
    """What the terminal's ``check`` prints: rows (name -> tokens), reasons and notes."""
    result = runner.invoke(app, ["check", *extra])
    assert result.exit_code in (0, 1), result.output
    rows: dict[str, list[str]] = {}
    reasons: dict[str, str] = {}
    notes: list[str] = []
    name = None
    for line in result.stdout.splitlines():
        match = ROW.match(line)
        if match:
            name = match.group(1)
            rows[name] = list(match.groups())
        elif line.startswith("  note: "):
            notes.append(line[len("  note: "):])
        elif line.startswith("  ") and name is not None and name not in reasons:
            reasons[name] = line.strip()
    assert rows, result.stdout  # the parse found the table: the test can fail
    return {"rows": rows, "reasons": reasons, "notes": notes, "output": result.stdout}


@pytest.fixture(scope="module")
def shipped(tmp_path_factory):
    return _report(tmp_path_factory.mktemp("shipped"), []), _check([])


@pytest.fixture(scope="module")
def failing(tmp_path_factory):
    return _report(tmp_path_factory.mktemp("failing"), FAILING), _check(FAILING)


def _flat(text: str) -> str:
    """Whitespace collapsed: a note wrapped over two lines reads as the terminal's one."""
    return " ".join(text.split())


def _page_rows(text: str) -> dict[str, list[str]]:
    """Page 1's verdict rows: name -> [name, value, limit, unit, margin, verdict] (the
    P(meet) column left out; the terminal prints it in a table of its own)."""
    rows = {}
    for line in text.splitlines():
        tokens = line.split()
        if len(tokens) == 7 and tokens[-1] in ("PASS", "FAIL", "UNPROVEN"):
            rows[tokens[0]] = tokens[:5] + tokens[6:]
    return rows


@pytest.mark.parametrize("which", ["shipped", "failing"])
def test_page_one_holds_every_verdict_reason_and_note_that_check_prints(which, request):
    report, check = request.getfixturevalue(which)
    first = report["text"][0]
    assert _page_rows(first) == check["rows"]  # name, value, limit, unit, margin, verdict
    flat = _flat(first)
    for name, reason in check["reasons"].items():
        assert _flat(reason) in flat, (name, reason)
    assert check["notes"], check["output"]  # the shipped case has caveats: the loop runs
    for note in check["notes"]:
        assert _flat(note) in flat, note
    # the disagreeing data and the extrapolation, in words
    assert "thrust and power data disagree" in flat and "extrapolated" in flat
    # inputs whose own header says they are not measured
    assert "reconstructed" in flat and "synthetic" in flat
    assert "P(meet)" in flat and "not sampled" in flat  # no sampling: said, no number made up


def test_a_failing_case_shows_fail_and_why_on_page_one(failing, shipped):
    report, check = failing
    flat = _flat(report["text"][0])
    failed = [name for name, row in check["rows"].items() if row[-1] == "FAIL"]
    assert {"takeoff_ground_roll", "trim_throttle_max"} <= set(failed)
    assert "REQUIREMENTS NOT MET" in flat
    for name in failed:
        assert _page_rows(report["text"][0])[name][-1] == "FAIL"
        assert f"reason: {_flat(check['reasons'][name])}" in flat or (
            _flat(check["reasons"][name]) in flat and "reason:" in flat)
    assert "not attainable: below stall" in flat  # the trim's reason, not the bare words
    assert "70.322 m is above the maximum 60.000 m" in flat
    assert "with --set aircraft.mass_kg=30" in flat
    assert "NOT MET" not in _flat(shipped[0]["text"][0])  # and the passing case says so not


@pytest.mark.parametrize("which", ["shipped", "failing"])
def test_every_page_carries_the_footer(which, request):
    report, _ = request.getfixturevalue(which)
    pages = report["text"]
    assert len(pages) == report["pages"] >= 10
    name = "TU-Flex, two Schuebeler DS-51-DIA HST"
    digests = set()
    for k, text in enumerate(pages, start=1):
        flat = _flat(text)
        assert name in flat, k
        assert f"page {k} of {len(pages)}" in flat, k
        assert f"tuflexperf {tuflexperf.__version__}" in flat, k
        assert re.search(r"\d{4}-\d{2}-\d{2} \d{2}:\d{2} UTC", flat), k
        digests.update(re.findall(r"inputs ([0-9a-f]{8})\b", flat))
        if which == "failing":
            assert "--set aircraft.mass_kg=30" in flat, k
    # one short hash, and it is the first 8 hex of the sha256 of the last page's hashes
    assert len(digests) == 1
    listed = re.findall(r"\b([0-9a-f]{64})\b", pages[-1])
    assert len(listed) >= 5
    expected = hashlib.sha256("".join(f"{h}\n" for h in listed).encode()).hexdigest()[:8]
    assert digests == {expected}
    assert not any(re.search(r"\b[0-9a-f]{64}\b", page) for page in pages[:-1])


def test_each_png_carries_its_page_footer(shipped):
    """The PNGs are the PDF's pages, footer and all: a figure pasted into a slide deck
    stays traceable."""
    import numpy as np
    import pypdfium2
    from PIL import Image

    report, _ = shipped
    pngs = sorted(Path(f) for f in report["figures"])
    document = pypdfium2.PdfDocument(report["pdf"])
    try:
        for k in (1, len(pngs)):
            page = document[k]
            rendered = np.asarray(page.render(scale=150 / 72).to_pil())
            written = np.asarray(Image.open(pngs[k - 1]).convert("RGB"))
            strip = rendered[-45:]  # the footer's strip, 0.3 in at 150 dpi
            assert strip.std() > 0  # is not blank: the footer is drawn there
            np.testing.assert_array_equal(written[-45:], strip)
    finally:
        document.close()


def test_page_one_of_a_crowded_case_keeps_every_note_on_the_page(tmp_path):
    """At a 3.7 V cell cut-off the trim and OEI fail on the battery and the cruise ends at
    the cut-off before the reserve: twelve notes. Page 1 (drawn alone, read back by PDFium)
    holds each of them, every reason, and nothing runs off the page or into the footer."""
    import pypdfium2
    from matplotlib.backends.backend_pdf import PdfPages

    from tuflexperf.analysis.study import Study
    from tuflexperf.io.case import load_case
    from tuflexperf.io.dotted import with_values
    from tuflexperf.report.data import load_measured, run_analyses
    from tuflexperf.report.first_page import first_page, timestamp
    from tuflexperf.report.footer import FOOTER_IN

    sets = ["--set", "battery.cutoff_voltage_per_cell_v=3.7"]
    check = _check(sets)
    assert any("cut-off with" in note and "reserve" in note for note in check["notes"])
    case = with_values(load_case(None), {"battery.cutoff_voltage_per_cell_v": 3.7})
    fig = first_page(case, load_measured(case, None), run_analyses(Study(case)), timestamp())
    with PdfPages(tmp_path / "first.pdf") as pdf:
        pdf.savefig(fig)
    document = pypdfium2.PdfDocument(tmp_path / "first.pdf")
    try:
        page = document[0]
        width, height = page.get_size()
        text = page.get_textpage().get_text_range()
        boxes = [obj.get_bounds() for obj in page.get_objects()
                 if obj.type == pypdfium2.raw.FPDF_PAGEOBJ_TEXT]
    finally:
        document.close()
    assert _page_rows(text) == check["rows"]
    flat = _flat(text)
    for name, reason in check["reasons"].items():
        assert _flat(reason) in flat, (name, reason)
    for note in check["notes"]:
        assert _flat(note) in flat, note
    assert len(boxes) > 40  # each line's text is an object of its own
    for left, bottom, right, top in boxes:
        assert left >= 0 and right <= width and top <= height, (left, right, top)
        assert bottom >= FOOTER_IN * 72, bottom  # clear of the footer's strip
