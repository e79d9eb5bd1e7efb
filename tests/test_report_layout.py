"""The review's layout (issue 15): A4 pages, verdicts on the first page, a failing aircraft."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

from typer.testing import CliRunner

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
    return json.loads(result.stdout)


def test_every_page_is_a4_and_the_first_page_carries_every_verdict(tmp_path: Path) -> None:
    from tuflexperf.analysis.requirements import check_case
    from tuflexperf.io.case import load_case
    from tuflexperf.report.build import title_lines
    from tuflexperf.report.data import load_measured, run_analyses

    data = _report(None, tmp_path / "review")
    boxes = _media_boxes(Path(data["pdf"]))
    assert len(boxes) == data["pages"]
    for width, height in boxes:
        assert abs(width - A4_PT[0]) < 1.5 and abs(height - A4_PT[1]) < 1.5
    case = load_case(None)
    analyses = run_analyses(case)
    text = "\n".join(title_lines(case, load_measured(case, None), analyses))
    for verdict in check_case(case):
        assert re.search(rf"{verdict.name}\s.*\s(PASS|FAIL)", text), verdict.name
    assert "sha256" not in text.split("every input file")[0]  # hashes live on the last page
    assert "reconstructed" in text and "synthetic" in text  # provenance classes stated


def test_a_failing_aircraft_still_gets_its_review(tmp_path: Path) -> None:
    for folder in ("requirements", "data"):
        shutil.copytree(ROOT / folder, tmp_path / folder)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    lines = [("mass_kg: 200" if line.startswith("mass_kg:") else line)
             for line in aircraft.read_text().splitlines()]
    aircraft.write_text("\n".join(lines) + "\n")
    data = _report(tmp_path / "requirements" / "tuflex.yaml", tmp_path / "review")
    assert data["passed"] is False
    assert Path(data["pdf"]).is_file()
    assert (tmp_path / "review" / "01_requirements.png").is_file()
