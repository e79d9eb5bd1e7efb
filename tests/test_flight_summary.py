"""Validation flights (issue 45 item 3): `flightlog --summary` reduces a log against a case, the
case lists the summary, and its flown power is a reading of the case (no log opened again)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case, files_opened
from tuflexperf.analysis.flown_reading import flown_power_readings, model_power_w
from tuflexperf.analysis.study import Study
from tuflexperf.cli import app
from tuflexperf.errors import InputError
from tuflexperf.io.case import load_case

runner = CliRunner()


def _made_up_log(folder: Path, power_w: float) -> Path:
    """A ulog2csv folder: 65 s at each of 18, 21 and 24 m/s calibrated airspeed at a
    constant ``power_w`` [W], airborne between 2 s and 198 s (land detector)."""
    folder.mkdir(parents=True)
    t = np.arange(0.0, 200.0, 0.1)
    us = (t * 1e6).astype(np.int64)
    v = np.where(t < 70, 18.0, np.where(t < 135, 21.0, 24.0))
    pd.DataFrame({"timestamp": us, "calibrated_airspeed_m_s": v}).to_csv(
        folder / "f_airspeed_validated_0.csv", index=False)
    current = np.full(t.size, power_w / 44.0)
    pd.DataFrame({"timestamp": us, "voltage_v": np.full(t.size, 44.0), "current_a": current,
                  "discharged_mah": np.cumsum(current) * 0.1 / 3.6}).to_csv(
        folder / "f_battery_status_0.csv", index=False)
    pd.DataFrame({"timestamp": np.array([0, 2_000_000, 198_000_000], dtype=np.int64),
                  "landed": [1, 0, 1]}).to_csv(folder / "f_vehicle_land_detected_0.csv",
                                               index=False)
    return folder


def _case_listing(tmp_path: Path, summary: Path) -> Path:
    case_file = copy_shipped_case(tmp_path / "case")
    (case_file.parent / "flight.yaml").write_text(summary.read_text())
    case_file.write_text(case_file.read_text() + "validation: {flights: [flight.yaml]}\n")
    return case_file


def _summary(path: Path, case, flown_over_model: float) -> Path:
    """A summary at three level-flight points of the shipped case, its flown power
    ``flown_over_model`` times the model's."""
    x = np.array([0.36, 0.39, 0.43])
    v = np.array([18.0, 21.0, 24.0])
    model = model_power_w(case, x, v, case.density_kg_m3)
    bins = [{"airspeed_m_s": float(vi), "true_airspeed_m_s": float(vi), "time_s": 60.0,
             "flown_power_w": float(flown_over_model * m), "predicted_power_w": float(m),
             "predicted_throttle": float(xi)} for xi, vi, m in zip(x, v, model, strict=True)]
    path.write_text(yaml.safe_dump({
        "log": "made-up.ulg", "log_sha256": "0" * 64, "power_model": "test",
        "density_kg_m3": case.density_kg_m3, "mass_kg": case.aircraft.mass_kg,
        "airborne_s": 180.0, "energy_wh": 100.0, "bins": bins}, sort_keys=False))
    return path


def test_flightlog_writes_the_summary_a_case_lists(tmp_path: Path) -> None:
    log = _made_up_log(tmp_path / "log", 2600.0)
    out = tmp_path / "flight.yaml"
    shipped = Path(__file__).resolve().parent.parent / "requirements" / "tuflex.yaml"
    done = runner.invoke(app, ["flightlog", str(log), "--case", str(shipped), "--summary",
                               str(out), "--json"])
    assert done.exit_code == 0, done.output
    import json

    comparison = json.loads(done.stdout)["comparison"]
    written = yaml.safe_load(out.read_text())
    assert [b["airspeed_m_s"] for b in written["bins"]] == [18.0, 21.0, 24.0]
    for row, b in zip(comparison["bins"], written["bins"], strict=True):
        assert b["flown_power_w"] == pytest.approx(2600.0, rel=1e-9)
        assert b["predicted_power_w"] == pytest.approx(row["predicted_power_w"], rel=1e-12)
    case = load_case(_case_listing(tmp_path, out))
    assert [p.name for p in case.validation_flights] == ["flight.yaml"]
    (reading,) = flown_power_readings(case)  # about 2x the model's power: a reading
    assert reading.key == "flown_power" and "endurance" in reading.affects
    assert reading.evidence.startswith("validation.flights (flight.yaml;")
    assert "27.6 m/s outside the flown bins' 18.0-24.0 m/s" in reading.evidence
    assert reading.settle == "a flight holding 27.6 m/s"
    # without --case there is no model to set the bins beside: one line, exit 2
    bare = runner.invoke(app, ["flightlog", str(log), "--summary", str(tmp_path / "x.yaml")])
    assert bare.exit_code == 2 and "--summary: needs --case" in bare.output


def test_the_flown_power_reading_flies_the_flown_power(tmp_path: Path) -> None:
    case = load_case(Path(__file__).resolve().parent.parent / "requirements" / "tuflex.yaml")
    case_file = _case_listing(tmp_path, _summary(tmp_path / "s.yaml", case, 1.3))
    listed = load_case(case_file)
    (reading,) = flown_power_readings(listed)
    nominal = Study(listed).endurance(0.5)
    flown = Study(reading.case).endurance(0.5)
    # 1.3 x the model at every flown point: 1.3 x its power at the cruise as well
    assert flown.electrical_power_w == pytest.approx(1.3 * nominal.electrical_power_w, rel=1e-9)
    assert flown.flight_endurance_min < nominal.flight_endurance_min
    assert "x1.300" in reading.evidence


def test_a_flight_within_the_tolerance_makes_no_reading(tmp_path: Path) -> None:
    case = load_case(Path(__file__).resolve().parent.parent / "requirements" / "tuflex.yaml")
    case_file = _case_listing(tmp_path, _summary(tmp_path / "s.yaml", case, 1.05))
    assert flown_power_readings(load_case(case_file)) == ()
    assert flown_power_readings(case) == ()  # no validation block: none


def test_a_missing_or_bad_summary_is_bad_input(tmp_path: Path) -> None:
    case_file = copy_shipped_case(tmp_path / "case")
    case_file.write_text(case_file.read_text() + "validation: {flights: [gone.yaml]}\n")
    with pytest.raises(InputError, match=r"validation.flights\[0\]: .*gone.yaml"):
        load_case(case_file)
    (case_file.parent / "gone.yaml").write_text("log: x.ulg\nbins: []\n")
    with pytest.raises(InputError, match="gone.yaml"):
        load_case(case_file)


def test_check_parses_each_summary_once_and_a_changed_one_again(tmp_path: Path) -> None:
    import json
    import os

    case = load_case(Path(__file__).resolve().parent.parent / "requirements" / "tuflex.yaml")
    case_file = _case_listing(tmp_path, _summary(tmp_path / "s.yaml", case, 1.3))
    listed = case_file.parent / "flight.yaml"
    with files_opened() as opened:
        done = runner.invoke(app, ["check", "--case", str(case_file), "--json"])
    # the case's load, the flown-power reading and the endurance note: one parse
    assert [name for name in opened if name.endswith("flight.yaml")] == [str(listed)]
    (said,) = [r["flown_power"] for r in json.loads(done.stdout)["results"]
               if r["name"] == "flight_endurance"]
    assert said["ratio"] == pytest.approx(1.3, rel=1e-9)

    def rewrite(text: str) -> None:  # a later time: the change is seen on any clock
        later = listed.stat().st_mtime_ns + 2_000_000_000
        listed.write_text(text)
        os.utime(listed, ns=(later, later))

    rewrite(_summary(tmp_path / "t.yaml", case, 1.05).read_text())
    again = json.loads(runner.invoke(app, ["check", "--case", str(case_file), "--json"]).stdout)
    (said,) = [r["flown_power"] for r in again["results"] if r["name"] == "flight_endurance"]
    assert said["ratio"] == pytest.approx(1.05, rel=1e-9)
    # a bad summary is still refused when the case is loaded, one line naming file and key
    rewrite(listed.read_text().replace("mass_kg:", "mass_kgs:"))
    bad = runner.invoke(app, ["check", "--case", str(case_file)])
    assert bad.exit_code == 2
    assert any("flight.yaml" in line and "mass_kgs" in line for line in bad.output.splitlines())


def test_the_reading_opens_no_log(tmp_path: Path) -> None:
    log = _made_up_log(tmp_path / "log", 2600.0)
    out = tmp_path / "flight.yaml"
    shipped = Path(__file__).resolve().parent.parent / "requirements" / "tuflex.yaml"
    assert runner.invoke(app, ["flightlog", str(log), "--case", str(shipped), "--summary",
                               str(out)]).exit_code == 0
    case_file = _case_listing(tmp_path, out)
    with files_opened() as opened:
        (reading,) = flown_power_readings(load_case(case_file))
    assert any(name.endswith("flight.yaml") for name in opened)
    assert not [name for name in opened if str(log) in name]
