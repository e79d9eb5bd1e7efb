"""``report --compare`` on the page "predicted vs flown": every configuration that lists
validation flights has them drawn and tabled under its own label, and one that lists none
is said to. Read from the PDF by PDFium, each table held against its own summary.

A: the shipped case with a made-up flight; B: a heavier copy (its model gives other power at
the same bins) with another made-up flight; C: a copy with no flight.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case
from tests.made_up_flight import LEGS_M_S, write_flight
from tests.test_report_flown import ROW, TITLE, _page, _pdf_pages
from tuflexperf.cli import app

runner = CliRunner()
HEAVY, BARE = "TU-Flex heavy copy", "TU-Flex unflown copy"


def _configuration(root: Path, name: str | None, mass_kg: float | None,
                   seed: int | None) -> tuple[Path, dict | None]:
    case = copy_shipped_case(root)
    if name is not None:
        case.write_text(re.sub(r"(?m)^name: .*$", f"name: {name}", case.read_text()))
    if mass_kg is not None:
        aircraft = root / "data" / "tuflex" / "aircraft.yaml"
        aircraft.write_text(re.sub(r"(?m)^mass_kg: .*$", f"mass_kg: {mass_kg}",
                                   aircraft.read_text()))
    if seed is None:
        return case, None
    log = write_flight(root / f"log{seed}", seed=seed)
    summary = case.parent / f"flight{seed}.yaml"
    done = runner.invoke(app, ["flightlog", str(log), "--case", str(case), "--summary",
                               str(summary)])
    assert done.exit_code == 0, done.output
    case.write_text(case.read_text() + f"validation: {{flights: [flight{seed}.yaml]}}\n")
    return case, yaml.safe_load(summary.read_text())


@pytest.fixture(scope="module")
def compared(tmp_path_factory: pytest.TempPathFactory) -> dict:
    root = tmp_path_factory.mktemp("flown_compare")
    a, first = _configuration(root / "a", None, None, 7)
    b, second = _configuration(root / "b", HEAVY, 28.0, 11)
    c, _ = _configuration(root / "c", BARE, None, None)
    done = runner.invoke(app, ["report", "--case", str(a), "--out", str(root / "review"),
                               "--json", "--compare", str(b), "--compare", str(c)])
    assert done.exit_code == 0, done.output
    pages = _pdf_pages(Path(json.loads(done.stdout)["pdf"]))
    return {"page": _page(pages, TITLE), "summaries": {"A": first, "B": second}}


def _tables(page: str) -> dict[str, list[re.Match]]:
    """The bin rows under each configuration's label, by its letter."""
    tables: dict[str, list[re.Match]] = {}
    letter = None
    for line in page.splitlines():
        head = re.match(r"^([A-Z]): ", line)
        if head and not ROW.match(line):
            letter = head[1]
        elif (row := ROW.match(line)) and letter is not None:
            tables.setdefault(letter, []).append(row)
    return tables


def test_each_configurations_flights_are_on_the_page_under_its_label(compared: dict) -> None:
    page = compared["page"]
    flat = " ".join(page.split())
    assert "(validation.flights: A flight7.yaml; B flight11.yaml; C none)" in flat
    assert f"B: {HEAVY}, log11: mean U I per 1 m/s bin" in flat  # B's own legend entry
    assert f"C: {BARE}: lists no validation.flights" in flat
    tables = _tables(page)
    assert sorted(tables) == ["A", "B"]
    for letter, rows in tables.items():
        summary = {b["airspeed_m_s"]: b for b in compared["summaries"][letter]["bins"]}
        assert [float(r[1]) for r in rows] == list(LEGS_M_S)
        for row in rows:
            b = summary[float(row[1])]
            assert float(row[3]) == pytest.approx(b["flown_power_w"], abs=0.5)
            # each configuration's own model: the heavier B needs more power at each bin
            assert float(row[4]) == pytest.approx(b["predicted_power_w"], abs=0.5)
    a = {float(r[1]): float(r[4]) for r in tables["A"]}
    assert all(float(r[4]) > a[float(r[1])] for r in tables["B"])
