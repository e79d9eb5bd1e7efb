"""Every problem of a case in one run, and the --aircraft/--propulsion/--battery overrides."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import MADE_UP_AIRCRAFT, MADE_UP_PROPULSION, SHIPPED_CASE, write_case
from tuflexperf.cli import app

runner = CliRunner()
DATA = SHIPPED_CASE.parent.parent / "data" / "tuflex"


def run(*args: str):
    return runner.invoke(app, list(args))


def error_lines(stderr: str) -> list[str]:
    lines = stderr.strip().splitlines()
    assert all(line.startswith("tuflexperf: error: ") for line in lines), stderr
    return [line.removeprefix("tuflexperf: error: ") for line in lines]


def test_three_typos_in_one_file_and_errors_in_two_more_are_all_said_at_once(tmp_path):
    aircraft = dict(MADE_UP_AIRCRAFT)
    aircraft["mas_kg"] = aircraft.pop("mass_kg")
    aircraft["cdo"] = aircraft.pop("cd0")
    aircraft["takeoff"] = {"cl_ground": 0.4, "roling_friction": 0.05}
    propulsion = json.loads(json.dumps(MADE_UP_PROPULSION))
    propulsion["delay_s"] = "soon"
    case = write_case(tmp_path, aircraft=aircraft, propulsion=propulsion,
                      requirements={"takeof": {"max_ground_roll_m": 60}})
    result = run("check", str(case))
    assert result.exit_code == 2
    lines = error_lines(result.stderr)
    assert "more problem" not in result.stderr
    expected = {  # (file, key) -> the key it meant
        ("case.yaml", "requirements.takeof"): "takeoff",
        ("aircraft.yaml", "mas_kg"): "mass_kg",
        ("aircraft.yaml", "cdo"): "cd0",
        ("aircraft.yaml", "takeoff.roling_friction"): "rolling_friction",
    }
    for (name, key), meant in expected.items():
        hits = [line for line in lines if re.match(rf"\S*{name}: {re.escape(key)}: ", line)]
        assert len(hits) == 1, (name, key, lines)
        assert f"unknown key '{key.split('.')[-1]}' (did you mean '{meant}'?)" in hits[0]
    delay = [line for line in lines if "propulsion.yaml: delay_s: " in line]
    assert len(delay) == 1 and "'soon'" in delay[0]
    # a misspelt required key is said once, by its misspelling, never also as missing
    assert not any("required key is missing" in line for line in lines), lines
    assert len(lines) == 5


def test_a_missing_key_and_a_bad_value_in_one_file_are_two_lines(tmp_path):
    aircraft = dict(MADE_UP_AIRCRAFT, cl_max=-1.0)
    del aircraft["wing_area_m2"]
    result = run("check", str(write_case(tmp_path, aircraft=aircraft)))
    assert result.exit_code == 2
    lines = error_lines(result.stderr)
    assert len(lines) == 2, lines
    assert any(line.endswith("aircraft.yaml: wing_area_m2: required key is missing")
               for line in lines)
    assert any("aircraft.yaml: cl_max: " in line and "-1.0" in line for line in lines)


def _shipped_copy(tmp_path: Path, **files: Path) -> Path:
    """The shipped case written again with some of its files replaced (as the flags would)."""
    case = yaml.safe_load(SHIPPED_CASE.read_text())
    for key in ("aircraft", "propulsion", "battery"):
        case[key] = str(files.get(key, (SHIPPED_CASE.parent / case[key]).resolve()))
    path = tmp_path / "edited.yaml"
    path.write_text(yaml.safe_dump(case, sort_keys=False))
    return path


def _stronger_fans(tmp_path: Path) -> Path:
    propulsion = yaml.safe_load((DATA / "propulsion.yaml").read_text())
    for engine in propulsion["engines"]:
        # 1.3 x made the thrust at 0.33 throttle, 43.5 m/s more than the shipped power surface
        # can make (figure of merit 1.23: FAIL by the plausibility rule, issue 43)
        engine["coefficients"]["p10"] *= 1.2
    path = tmp_path / "stronger.yaml"
    path.write_text(yaml.safe_dump(propulsion, sort_keys=False))
    return path


def test_propulsion_flag_flies_that_file_as_a_case_naming_it_does(tmp_path):
    stronger = _stronger_fans(tmp_path)
    flagged = json.loads(run("takeoff", "--propulsion", str(stronger), "--json").stdout)
    edited = json.loads(run("takeoff", "--case", str(_shipped_copy(tmp_path, propulsion=stronger)),
                            "--json").stdout)
    shipped = json.loads(run("takeoff", "--json").stdout)
    assert flagged["ground_roll_m"] == pytest.approx(edited["ground_roll_m"], rel=1e-12)
    assert flagged["ground_roll_m"] < 0.95 * shipped["ground_roll_m"]  # it did change


def test_aircraft_and_battery_flags_replace_those_files(tmp_path):
    aircraft = yaml.safe_load((DATA / "aircraft.yaml").read_text())
    aircraft["mass_kg"] = 22.0
    lighter = tmp_path / "lighter.yaml"
    lighter.write_text(yaml.safe_dump(aircraft, sort_keys=False))
    battery = tmp_path / "battery.yaml"  # with its discharge runs, which it names relative
    battery.write_text((DATA / "battery.yaml").read_text())
    shutil.copytree(DATA / "endurance", tmp_path / "endurance")
    args = ["--aircraft", str(lighter), "--battery", str(battery), "--json"]
    flagged = json.loads(run("check", *args).stdout)
    edited = json.loads(run("check", str(_shipped_copy(tmp_path, aircraft=lighter)),
                            "--json").stdout)
    shipped = json.loads(run("check", "--json").stdout)
    assert flagged["files_replaced"] == {"battery": str(battery.resolve()),
                                         "aircraft": str(lighter.resolve())}
    assert "files_replaced" not in edited
    values = {r["name"]: r["value"] for r in flagged["results"]}
    assert values == {r["name"]: r["value"] for r in edited["results"]}
    assert values != {r["name"]: r["value"] for r in shipped["results"]}


CASE_COMMANDS = [
    ["check"], ["takeoff"], ["trim"], ["oei"], ["endurance", "--throttle", "0.5"],
    ["performance"], ["mission"], ["sweep", "--vary", "aircraft.mass_kg=20:30:2"], ["margins"],
    ["report", "--out", "OUT"], ["export", "--out", "OUT"],
]


@pytest.mark.parametrize("command", CASE_COMMANDS, ids=lambda c: c[0])
@pytest.mark.parametrize("flag", ["--aircraft", "--propulsion", "--battery"])
def test_every_case_command_takes_the_flags_and_names_a_bad_one(tmp_path, command, flag):
    args = [str(tmp_path / "out") if a == "OUT" else a for a in command]
    result = run(*args, flag, str(tmp_path / "no-such.yaml"))
    assert result.exit_code == 2
    assert error_lines(result.stderr) == [f"{flag}: file not found: {tmp_path / 'no-such.yaml'}"]
    assert not (tmp_path / "out").exists()


def test_a_bad_override_file_is_named_by_its_flag_with_all_its_problems(tmp_path):
    propulsion = json.loads(json.dumps(MADE_UP_PROPULSION))
    propulsion["modle"] = propulsion.pop("model")
    propulsion["engines"][0]["coefficients"]["p2O"] = propulsion["engines"][0][
        "coefficients"].pop("p20")
    bad = tmp_path / "fans.yaml"
    bad.write_text(yaml.safe_dump(propulsion))
    result = run("check", "--propulsion", str(bad))
    assert result.exit_code == 2
    lines = error_lines(result.stderr)
    assert len(lines) == 2 and all(line.startswith(f"--propulsion: {bad}: ") for line in lines)
    assert any("(did you mean 'model'?)" in line for line in lines)
    assert any("(did you mean 'p20'?)" in line for line in lines)
