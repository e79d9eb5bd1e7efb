"""The review's flown pages (issue 45 item 3, issue 47 item 4): a case that lists a validation
flight gets the page "predicted vs flown", its predicted-against-measured page draws the
flown bins, and ``check`` prints the flown/predicted power beside the endurance verdict.

Everything is read from the PDF by PDFium, and the numbers are held against an independent
few-line numpy reduction of the log's own CSVs (no public, permissively licensed fixed-wing
log with airspeed and current was found to ship: the flight is made up, tests/made_up_flight.py).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case
from tests.made_up_flight import LEGS_M_S, write_flight
from tuflexperf.cli import app

runner = CliRunner()
TITLE = "predicted vs flown (validation.flights:"  # the page's title, not page 1's caveat
ROW = re.compile(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+\.\d{3})\s+(\S+)\s+(\S+)\s+(\S+)\s*$")


def _pdf_pages(pdf: Path) -> list[str]:
    import pypdfium2

    document = pypdfium2.PdfDocument(str(pdf))
    try:
        return [document[k].get_textpage().get_text_range() for k in range(len(document))]
    finally:
        document.close()


def _page(pages: list[str], title: str) -> str:
    found = [text for text in pages if title in text]
    assert len(found) == 1, [text[:80] for text in pages]
    return found[0]


def independent_reduction(folder: Path) -> dict:
    """The flight reduced by hand: the land detector's window, the energy (trapezoid of U I
    over the window), and per 1 m/s bin of calibrated airspeed the time and the mean U I and
    I, each airspeed sample standing for the time to the next one."""
    air = pd.read_csv(next(folder.glob("*_airspeed_validated_0.csv")))
    bat = pd.read_csv(next(folder.glob("*_battery_status_0.csv")))
    land = pd.read_csv(next(folder.glob("*_vehicle_land_detected_0.csv")))
    start, end = land["timestamp"].iloc[1] / 1e6, land["timestamp"].iloc[2] / 1e6
    tb = bat["timestamp"].to_numpy() / 1e6
    power = bat["voltage_v"].to_numpy() * bat["current_a"].to_numpy()
    inside = (tb >= start) & (tb <= end)
    grid = np.concatenate([[start], tb[inside], [end]])
    energy_wh = np.trapezoid(np.interp(grid, tb, power), grid) / 3600.0
    ta = air["timestamp"].to_numpy() / 1e6
    v = air["calibrated_airspeed_m_s"].to_numpy()
    dt = np.where((ta >= start) & (ta < end), np.diff(ta, append=ta[-1]), 0.0)
    label = np.floor(v + 0.5)
    bins = {}
    for b in np.unique(label[dt > 0]):
        w = np.where(label == b, dt, 0.0)
        if w.sum() >= 10.0:
            bins[float(b)] = {"time_s": w.sum(),
                              "power_w": np.sum(w * np.interp(ta, tb, power)) / w.sum(),
                              "current_a": np.sum(w * np.interp(ta, tb, bat["current_a"]))
                              / w.sum()}
    return {"airborne_s": end - start, "energy_wh": energy_wh, "bins": bins}


@pytest.fixture(scope="module")
def flown(tmp_path_factory: pytest.TempPathFactory) -> dict:
    root = tmp_path_factory.mktemp("flown")
    log = write_flight(root / "log")
    case_file = copy_shipped_case(root / "case")
    summary = root / "flight.yaml"
    done = runner.invoke(app, ["flightlog", str(log), "--case", str(case_file), "--summary",
                               str(summary), "--json"])
    assert done.exit_code == 0, done.output
    (case_file.parent / "flight.yaml").write_text(summary.read_text())
    case_file.write_text(case_file.read_text() + "validation: {flights: [flight.yaml]}\n")
    report = runner.invoke(app, ["report", "--case", str(case_file), "--out",
                                 str(root / "review"), "--json"])
    assert report.exit_code == 0, report.output
    check = runner.invoke(app, ["check", "--case", str(case_file), "--json"])
    text = runner.invoke(app, ["check", "--case", str(case_file)])
    return {"case": case_file, "log": log, "flightlog": json.loads(done.stdout),
            "summary": yaml.safe_load(summary.read_text()),
            "report": json.loads(report.stdout), "pages": _pdf_pages(
                Path(json.loads(report.stdout)["pdf"])),
            "check": json.loads(check.stdout), "check_text": text.stdout,
            "hand": independent_reduction(log)}


def test_the_flown_page_holds_every_bin_as_the_log_reduces_by_hand(flown: dict) -> None:
    page = _page(flown["pages"], TITLE)
    rows = {float(m[1]): m for m in (ROW.match(line) for line in page.splitlines()) if m}
    hand = flown["hand"]["bins"]
    summary = {b["airspeed_m_s"]: b for b in flown["summary"]["bins"]}
    assert flown["summary"]["bins_kind"] == "level-flight"
    assert sorted(rows) == sorted(summary) == list(LEGS_M_S)  # one row per leg flown
    for v, row in rows.items():
        flown_w, model_w, ratio = float(row[3]), float(row[4]), float(row[5])
        # the level bins leave out the second or two of climb at each leg's ends (+-1 s)
        assert float(row[2]) == pytest.approx(hand[v]["time_s"], abs=2.5)
        assert flown_w == pytest.approx(hand[v]["power_w"], rel=0.01)
        assert model_w == pytest.approx(summary[v]["predicted_power_w"], abs=0.5)
        assert ratio == pytest.approx(summary[v]["flown_power_w"]
                                      / summary[v]["predicted_power_w"], abs=6e-4)
        assert float(row[7]) == pytest.approx(summary[v]["flown_throttle"], abs=6e-4)
        assert float(row[8]) == pytest.approx(hand[v]["current_a"], rel=0.01)


def test_the_endurance_on_the_flown_energy_against_the_time_flown(flown: dict) -> None:
    page = " ".join(_page(flown["pages"], TITLE).split())
    hand, summary = flown["hand"], flown["summary"]
    assert summary["airborne_s"] == pytest.approx(hand["airborne_s"], abs=1e-6)
    assert summary["energy_wh"] == pytest.approx(hand["energy_wh"], rel=0.005)
    time = np.array([b["time_s"] for b in summary["bins"]])
    model = np.array([b["predicted_power_w"] for b in summary["bins"]])
    predicted = summary["energy_wh"] * 3600.0 / (np.sum(time * model) / np.sum(time))
    match = re.search(r"power: (\d+) s predicted, (\d+) s flown", page)
    assert match, page
    assert float(match[1]) == pytest.approx(predicted, abs=0.5)
    assert float(match[2]) == pytest.approx(hand["airborne_s"], abs=0.5)
    assert f"airborne {hand['airborne_s']:.0f} s, {summary['energy_wh']:.1f} Wh" in page


def test_the_autopilot_hand_off_is_the_models_best_and_the_flown_bin(flown: dict) -> None:
    page = " ".join(_page(flown["pages"], TITLE).split())
    best = json.loads(runner.invoke(app, ["endurance", "--best", "--json"]).stdout)
    point = best["best"]["best_endurance"]
    handoff = flown["flightlog"]["comparison"]["autopilot_handoff"]
    assert f"{2 * point['electrical_power_w']:.0f} W, {handoff['model_current_a']:.1f} A " \
           "(full packs)" in page
    label = float(np.floor(handoff["airspeed_eas_m_s"] + 0.5))
    assert label in flown["hand"]["bins"]  # the made-up flight holds the endurance airspeed
    match = re.search(rf"log, {label:g} m/s bin: (\d+) W, ([\d.]+) A", page)
    assert match, page
    assert float(match[1]) == pytest.approx(flown["hand"]["bins"][label]["power_w"], rel=0.01)
    assert float(match[2]) == pytest.approx(flown["hand"]["bins"][label]["current_a"],
                                            rel=0.01)


def test_predicted_against_measured_draws_the_flown_power(flown: dict) -> None:
    page = " ".join(_page(flown["pages"], "predicted against measured").split())
    assert "model against the validation flights" in page
    assert "no flight log is given" not in page
    first = " ".join(flown["pages"][0].split())
    assert "flights flight.yaml (flight summaries)" in first
    assert "no flight log" not in first


def test_check_prints_the_flown_power_beside_the_endurance_verdict(flown: dict) -> None:
    bins = flown["summary"]["bins"]
    time = np.array([b["time_s"] for b in bins])
    ratio = (np.sum(time * [b["flown_power_w"] for b in bins])
             / np.sum(time * [b["predicted_power_w"] for b in bins]))
    (endurance,) = [r for r in flown["check"]["results"] if r["name"] == "flight_endurance"]
    said = endurance["flown_power"]
    assert said["ratio"] == pytest.approx(ratio, rel=1e-9)
    assert said["bins"] == len(bins) and said["flights"] == ["flight.yaml"]
    assert said["within_tolerance"] is bool(abs(1 / ratio - 1) <= 0.1)
    lines = flown["check_text"].splitlines()
    at = next(k for k, line in enumerate(lines) if line.startswith("flight_endurance"))
    rest = lines[at + 1:]
    block = rest[:next((k for k, line in enumerate(rest) if not line.startswith("  ")),
                       len(rest))]
    assert any(f"flown/predicted power x{ratio:.3f}" in line for line in block), block
    # the two power readings share their nominal: the power model is named once
    (reason,) = [line for line in block if line.lstrip().startswith("UNPROVEN:")]
    assert reason.count("on the power model") == 1, reason


def test_endurance_says_the_flown_power_as_check_does(flown: dict) -> None:
    """At the requirement's throttle its verdict is check's, flown power and note alike; at
    any other throttle the flights' ratio is still said (it is the flown bins')."""
    (judged,) = [r for r in flown["check"]["results"] if r["name"] == "flight_endurance"]
    said = judged["flown_power"]
    case = str(flown["case"])
    throttle = yaml.safe_load(flown["case"].read_text())["requirements"]["endurance"]["throttle"]
    at = json.loads(runner.invoke(app, ["endurance", "--case", case, "--throttle",
                                        str(throttle), "--json"]).stdout)
    assert at["flown_power"] == said
    assert at["result"] == judged
    other = runner.invoke(app, ["endurance", "--case", case, "--throttle",
                                str(throttle + 0.1), "--json"])
    assert "result" not in json.loads(other.stdout)  # not the requirement's throttle
    assert json.loads(other.stdout)["flown_power"] == said
    text = runner.invoke(app, ["endurance", "--case", case, "--throttle",
                               str(throttle + 0.1)]).stdout
    notes = [line for line in text.splitlines() if "flown/predicted power" in line]
    checks = [line for line in flown["check_text"].splitlines() if "flown/predicted" in line]
    assert len(checks) == 1 and notes == checks, text
    assert f"x{said['ratio']:.3f} time-weighted over {said['bins']} airspeed bins" in notes[0]


def test_endurance_without_flights_says_no_flown_power() -> None:
    done = runner.invoke(app, ["endurance", "--throttle", "0.6", "--json"])
    assert "flown_power" not in json.loads(done.stdout)
    text = runner.invoke(app, ["endurance", "--throttle", "0.6"]).stdout
    assert "flown/predicted" not in text and "validation flights" not in text


def test_without_flights_page_one_says_so_and_there_is_no_flown_page(shipped_report) -> None:
    pages = _pdf_pages(Path(shipped_report.data["pdf"]))
    assert not [text for text in pages if TITLE in text]
    first = " ".join(pages[0].split())
    assert "no flight log: the case lists no validation.flights" in first
    assert "flights none" in first
    page = " ".join(_page(pages, "predicted against measured").split())
    assert "no flight log is given" in page
