"""`tuflexperf init`: a starter case check runs at once, from typical values or a datasheet."""

from __future__ import annotations

import json
import math

import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import SHIPPED_CASE
from tuflexperf.cli import app

runner = CliRunner()
SHEET = ["--static-thrust-n", "55", "--max-power-w", "3500", "--fan-diameter-m", "0.12",
         "--cells", "12", "--capacity-ah", "5", "--c-rating", "40"]


def run(*args: str):
    return runner.invoke(app, list(args))


def poly22(c: dict[str, float], x: float, v: float) -> float:
    return (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x * x + c["p11"] * x * v
            + c["p02"] * v * v)


def test_init_writes_a_starter_that_check_runs(tmp_path):
    made = run("init", str(tmp_path / "mine"), "--json")
    assert made.exit_code == 0, made.stderr
    written = json.loads(made.stdout)
    names = {p.removeprefix(str(tmp_path / "mine") + "/") for p in written["files"]}
    assert {"case.yaml", "aircraft.yaml", "propulsion.yaml", "battery.yaml"} <= names
    case = yaml.safe_load((tmp_path / "mine" / "case.yaml").read_text())
    assert "endurance" in case["requirements"]
    checked = run("check", written["case"], "--json")
    assert checked.exit_code in (0, 1), checked.stderr
    results = {r["name"] for r in json.loads(checked.stdout)["results"]}
    assert "flight_endurance" in results


def test_datasheet_surfaces_reproduce_the_datasheet_at_full_static_throttle(tmp_path):
    made = run("init", str(tmp_path / "ds"), "--from-datasheet", *SHEET)
    assert made.exit_code == 0, made.stderr
    prop = yaml.safe_load((tmp_path / "ds" / "propulsion.yaml").read_text())
    area = math.pi * 0.12**2 / 4
    assert prop["fan_area_m2"] == pytest.approx(area, rel=1e-5)
    jet = math.sqrt(55.0 / (1.225 * area))  # momentum theory, T0 = rho A V_j^2
    assert len(prop["engines"]) == 2
    for engine in prop["engines"]:
        thrust, power = engine["coefficients"], engine["power"]["coefficients"]
        tolerance = engine["residual_sd_n"]  # the stated uncertainty
        assert 0 < tolerance <= 0.2 * 55
        assert poly22(thrust, 1.0, 0.0) == pytest.approx(55.0, abs=tolerance)
        assert poly22(power, 1.0, 0.0) == pytest.approx(3500.0, abs=engine["power"]["rmse_w"])
        # the ram drag of momentum theory: half the static thrust left at half the jet speed
        assert poly22(thrust, 1.0, jet / 2) == pytest.approx(27.5, rel=1e-4)
        assert poly22(thrust, 0.5, 0.0) == pytest.approx(55.0 / 4, rel=1e-6)
    checked = run("check", str(tmp_path / "ds" / "case.yaml"))
    assert checked.exit_code in (0, 1), checked.stderr


def test_datasheet_file_with_a_flag_replacing_one_key(tmp_path):
    sheet = {"name": "big fan", "static_thrust_n": 40, "max_power_w": 2600,
             "fan_diameter_m": 0.1, "engines": 1, "cells": 10, "capacity_ah": 4,
             "c_rating": 30, "internal_resistance_ohm_per_cell": 0.004}
    path = tmp_path / "sheet.yaml"
    path.write_text(yaml.safe_dump(sheet))
    made = run("init", str(tmp_path / "f"), "--from-datasheet", "--datasheet", str(path),
               "--capacity-ah", "6", "--json")
    assert made.exit_code == 0, made.stderr
    given = json.loads(made.stdout)["datasheet"]
    assert given["capacity_ah"] == 6 and given["resistance_source"] == "datasheet"
    battery = yaml.safe_load((tmp_path / "f" / "battery.yaml").read_text())
    assert battery["capacity_ah"] == 6 and battery["cells_in_series"] == 10
    assert battery["fit"]["parameters"]["resistance_ohm"] == pytest.approx(0.04, rel=0.05)
    assert run("check", str(tmp_path / "f" / "case.yaml")).exit_code in (0, 1)


def test_init_never_replaces_a_file(tmp_path):
    folder = tmp_path / "taken"
    folder.mkdir()
    (folder / "aircraft.yaml").write_text("mine\n")
    refused = run("init", str(folder))
    assert refused.exit_code == 2
    assert str(folder / "aircraft.yaml") in refused.stderr and "exists" in refused.stderr
    assert (folder / "aircraft.yaml").read_text() == "mine\n"
    assert sorted(p.name for p in folder.iterdir()) == ["aircraft.yaml"]


@pytest.mark.parametrize("args, named", [
    (["--from-datasheet", "--cells", "6"], "--static-thrust-n"),
    (["--from-datasheet", *SHEET[:-2], "--c-rating", "-3"], "c_rating"),
    (["--cells", "6"], "--from-datasheet"),
    (["--example", "nosuch"], "--example"),
])
def test_bad_init_input_is_exit_2_naming_it(tmp_path, args, named):
    result = run("init", str(tmp_path / "x"), *args)
    assert result.exit_code == 2 and named in result.stderr
    assert not (tmp_path / "x").exists()


def test_example_copies_the_shipped_case(tmp_path):
    made = run("init", str(tmp_path / "ex"), "--example", "tuflex")
    assert made.exit_code == 0, made.stderr
    copied = tmp_path / "ex" / "requirements" / "tuflex.yaml"
    assert copied.read_text() == SHIPPED_CASE.read_text()
    ours = json.loads(run("check", str(copied), "--json").stdout)
    shipped = json.loads(run("check", "--json").stdout)
    assert ours["results"] == shipped["results"]
