"""`tuflexperf endurance`: JSON keys, exit codes, bad flags, bad battery files."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import copy_shipped_case
from tests.validation.test_endurance_paper import shipped_with_battery
from tuflexperf.cli import app
from tuflexperf.errors import InputError
from tuflexperf.io.battery import load_battery
from tuflexperf.io.case import load_case

ROOT = Path(__file__).resolve().parent.parent
BATTERY = ROOT / "data" / "tuflex" / "battery.yaml"
SPEC_KEYS = ("throttle", "airspeed_m_s", "electrical_power_w", "battery_endurance_min",
             "flight_endurance_min")
runner = CliRunner()


@pytest.fixture(scope="module")
def case_path(tmp_path_factory) -> Path:
    return shipped_with_battery(tmp_path_factory.mktemp("case"))


def run(*args: str):
    return runner.invoke(app, list(args))


def test_json_has_the_spec_keys(case_path):
    result = run("endurance", "--throttle", "0.5", "--case", str(case_path), "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    for key in SPEC_KEYS:
        assert isinstance(data[key], float) and math.isfinite(data[key])
    assert data["throttle"] == 0.5
    assert data["passed"] is True and data["min_flight_time_min"] == 15
    assert {"rms_v", "n_points"} <= set(data["battery_fit"])
    assert data["cross_validation"] and data["launch"]["charge_ah"] > 0


def test_human_table(case_path):
    result = run("endurance", "--throttle", "0.6", "--case", str(case_path))
    assert result.exit_code == 0, result.output
    assert "level-flight airspeed" in result.stdout and "one pack" in result.stdout


def test_best(case_path):
    result = run("endurance", "--best", "--case", str(case_path), "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    best = data["best"]
    # the longest flight is at the least throttle that flies, not above a bit over it
    assert data["min_throttle"] - 1e-6 <= best["best_endurance"]["throttle"]
    assert best["best_endurance"]["throttle"] <= data["min_throttle"] + 0.05
    at_half = json.loads(
        run("endurance", "--throttle", "0.5", "--case", str(case_path), "--json").stdout
    )
    assert best["best_endurance"]["flight_endurance_min"] >= at_half["flight_endurance_min"]
    # best range inside the case's envelope
    assert 15.0 <= best["best_range"]["airspeed_m_s"] <= 45.0 + 1e-6
    assert best["best_range"]["cruise_range_km"] > 0


def test_below_least_throttle_is_not_attainable(case_path):
    result = run("endurance", "--throttle", "0.3", "--case", str(case_path))
    assert result.exit_code == 1
    assert "least throttle" in result.stderr and "throttle 0.3 is below" in result.stderr


@pytest.mark.parametrize("value", ["nan", "1.5", "-0.1", "inf", "abc", ""])
def test_bad_throttle_is_exit_2_naming_the_flag(case_path, value):
    result = run("endurance", "--throttle", value, "--case", str(case_path))
    assert result.exit_code == 2
    assert "--throttle" in result.stderr or "'--throttle'" in result.output


def test_missing_throttle(case_path):
    result = run("endurance", "--case", str(case_path))
    assert result.exit_code == 2 and "--throttle" in result.stderr


def test_case_without_battery_names_the_case_file(tmp_path):
    data = yaml.safe_load((ROOT / "requirements" / "tuflex.yaml").read_text())
    data.pop("battery", None)
    (data.get("requirements") or {}).pop("endurance", None)
    for key in ("aircraft", "propulsion"):
        data[key] = str((ROOT / "requirements" / data[key]).resolve())
    path = tmp_path / "nobattery.yaml"
    path.write_text(yaml.safe_dump(data))
    result = run("endurance", "--throttle", "0.5", "--case", str(path))
    assert result.exit_code == 2
    assert str(path) in result.stderr and "battery" in result.stderr
    assert result.stderr.count("\n") == 1


# --- bad battery files ------------------------------------------------------------------------
def _battery_copy(folder: Path, edit) -> Path:
    """A copy of the shipped battery file with its runs, changed by ``edit(dict)``."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copytree(BATTERY.parent / "endurance", folder / "endurance", dirs_exist_ok=True)
    data = yaml.safe_load(BATTERY.read_text())
    edit(data)
    path = folder / "battery.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _case_with(folder: Path, battery: Path) -> Path:
    """The shipped case with ``battery`` as its battery file (written into ``folder``)."""
    data = yaml.safe_load((ROOT / "requirements" / "tuflex.yaml").read_text())
    for key in ("aircraft", "propulsion"):
        data[key] = str((ROOT / "requirements" / data[key]).resolve())
    data["battery"] = str(battery)
    case = folder / "case.yaml"
    case.write_text(yaml.safe_dump(data))
    return case


def _set(path: tuple, value):
    def edit(data):
        target = data
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
    return edit


def _drop(key):
    return lambda data: data.pop(key)


BAD_BATTERIES = {
    "misspelt key": (lambda d: d.update(capacity_mah=5000), "capacity_mah"),
    "missing key": (_drop("cells_in_series"), "cells_in_series"),
    "negative capacity": (_set(("capacity_ah",), -5.0), "capacity_ah"),
    "nan cut-off": (_set(("cutoff_voltage_per_cell_v",), float("nan")), "cutoff_voltage"),
    "string cells": (_set(("cells_in_series",), "12"), "cells_in_series"),
    "no runs": (_set(("runs",), []), "runs"),
    "missing run file": (_set(("runs",), [{"file": "endurance/nope.csv"}]), "runs[0].file"),
    "misspelt mission key": (_set(("mission",), {"pattern_altitude": 100}), "mission"),
    "reserve of 1": (_set(("mission", "landing_reserve_fraction"), 1.0), "landing_reserve"),
    "inverted power range": (
        _set(("fan_power", "published_power_range_w"), [4100, 2400]), "published_power_range_w"
    ),
    "nominal voltage for 6S": (_set(("nominal_voltage_v",), 22.2), "nominal_voltage_v"),
}


@pytest.mark.parametrize("name", sorted(BAD_BATTERIES))
def test_bad_battery_file_is_one_line_naming_file_and_key(tmp_path, name):
    edit, key = BAD_BATTERIES[name]
    path = _battery_copy(tmp_path, edit)
    with pytest.raises(InputError) as info:
        load_battery(path)
    message = str(info.value)
    assert str(path) in message and key in message and "\n" not in message


def test_bad_battery_fails_at_case_load_with_exit_2(tmp_path):
    battery = _battery_copy(tmp_path / "b", lambda d: d.update(cells=12))
    data = yaml.safe_load((ROOT / "requirements" / "tuflex.yaml").read_text())
    for key in ("aircraft", "propulsion"):
        data[key] = str((ROOT / "requirements" / data[key]).resolve())
    data["battery"] = str(battery)
    case = tmp_path / "case.yaml"
    case.write_text(yaml.safe_dump(data))
    with pytest.raises(InputError, match="cells"):
        load_case(case)
    result = run("check", str(case))
    assert result.exit_code == 2 and "cells" in result.stderr


def test_duplicate_key_in_battery_file(tmp_path):
    path = _battery_copy(tmp_path, lambda d: None)
    path.write_text(path.read_text() + "capacity_ah: 6.0\n")
    with pytest.raises(InputError, match="duplicate key"):
        load_battery(path)


@pytest.mark.parametrize(
    "content, problem",
    [
        ("time_s,force_n,airspeed_m_s,throttle,voltage_v\n0,0,30,0,50\n", "current_a"),
        ("time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a\n"
         + "".join(f"{t},0,30,0.5,nan,20\n" for t in range(20)), "voltage_v"),
        ("time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a\n"
         + "".join(f"{t % 5},0,30,0.5,48,20\n" for t in range(20)), "time_s"),
        ("time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a\n"
         + "".join(f"{t},0,30,50,48,20\n" for t in range(20)), "throttle"),
        ("time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a\n0,0,x,0,1,1\n",
         "column airspeed_m_s: non-numeric value 'x' (line 2)"),
    ],
)
def test_bad_run_file_is_exit_2_naming_the_run(tmp_path, content, problem):
    # the runs are read (and refused) by the fit that writes the pack model; check reads
    # that model only, and refuses a changed run by its sha256 (test below)
    path = _battery_copy(tmp_path, lambda d: d.pop("fit", None))
    run_file = path.parent / "endurance" / "edf1_endurance_75.csv"
    run_file.write_text(content)
    out = tmp_path / "fitted.yaml"
    result = run("fit", str(path), "--out", str(out))
    assert result.exit_code == 2, result.output
    assert not out.exists()
    assert run_file.name in result.stderr and problem in result.stderr
    assert result.stderr.count("\n") == 1


def test_real_subprocess(case_path):
    exe = Path(sys.executable).parent / "tuflexperf"
    proc = subprocess.run(
        [str(exe), "endurance", "--throttle", "0.5", "--case", str(case_path), "--json"],
        capture_output=True, text=True, timeout=120, check=False,
    )
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert set(SPEC_KEYS) <= set(data)
    bad = subprocess.run([str(exe), "endurance", "--throttle", "2"], capture_output=True,
                         text=True, timeout=120, check=False)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--throttle" in bad.stderr


def test_a_run_changed_since_the_fit_is_refused_where_it_is_read(tmp_path):
    """check and endurance fly the battery file's fitted parameters and open no run (issue 43
    item 2): a run edited since the fit leaves their answer as it was; the report, which
    draws the runs, refuses it (sha256), naming the file, key and run."""
    from tuflexperf.analysis.battery_fit import cached_case_battery, characterise_battery

    path = _battery_copy(tmp_path, lambda d: None)
    case_file = _case_with(tmp_path, path)
    before = run("endurance", "--throttle", "0.5", "--case", str(case_file), "--json")
    run_file = path.parent / "endurance" / "edf1_endurance_75.csv"
    run_file.write_text(run_file.read_text().replace("\n1", "\n2", 1))
    after = run("endurance", "--throttle", "0.5", "--case", str(case_file), "--json")
    assert before.exit_code == after.exit_code == 0, after.output
    assert (json.loads(after.stdout)["flight_endurance_min"]
            == json.loads(before.stdout)["flight_endurance_min"])
    case = load_case(case_file)
    with pytest.raises(InputError, match="fit.runs: edf1_endurance_75.csv changed since"):
        characterise_battery(cached_case_battery(case), case).discharge_runs()


def test_a_power_model_far_below_momentum_theory_flies_no_endurance(tmp_path):
    """A power surface at 1 mW: 'flight_endurance 22166939 min PASS' beside a figure-of-merit
    warning of 644970 (outside audit). Above 1 it is no fan's power: FAIL (plausibility)."""

    copy_shipped_case(tmp_path)
    path = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    data = yaml.safe_load(path.read_text())
    for engine in data["engines"]:
        engine["power"]["coefficients"] = dict(p00=1e-3, p10=0, p01=0, p20=0, p11=0, p02=0)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    result = run("check", str(tmp_path / "requirements" / "tuflex.yaml"), "--json")
    assert result.exit_code == 1
    endurance = next(r for r in json.loads(result.stdout)["results"]
                     if r["name"] == "flight_endurance")
    assert endurance["passed"] is False and endurance["value"] is None
    # the one plausibility rule says it (issue 43): the figure of merit on the disk area
    assert "implausible data" in endurance["reason"] and "momentum theory" in endurance["reason"]


def test_best_with_a_pack_too_small_names_the_throttle_asked_for_then_the_search():
    """--best named a throttle from its own search (0.679179) as if the user had asked it."""
    # a pack that takes off (a smaller one is beyond the battery at the take-off itself)
    # but reaches its cut-off in the climb
    pack = "battery.capacity_ah=1.7"
    asked = CliRunner().invoke(app, ["endurance", "--throttle", "0.5", "--best", "--set", pack])
    assert asked.exit_code == 1 and "throttle 0.5: segment 2 (climb)" in asked.stderr
    best = CliRunner().invoke(app, ["endurance", "--best", "--set", pack])
    assert best.exit_code == 1
    assert "no best endurance: its search starts halfway from the least level-flight " \
        "throttle 0.358 to full, and there throttle 0.679" in best.stderr


def test_a_cruise_that_ends_at_the_cutoff_does_not_call_the_charge_left_a_reserve():
    """A cut-off of 3.75 V per cell ends the cruise with 33.7 % left: the flight said "lands
    with 33.7 % charge (reserve 20 %)" as if the reserve were there to draw (outside audit)."""
    result = CliRunner().invoke(app, ["endurance", "--throttle", "0.5", "--json", "--set",
                                      "battery.cutoff_voltage_per_cell_v=3.75"])
    out = json.loads(result.stdout)
    assert out["cruise_ends_at"] == "cut-off"
    left = 100 * out["flight"]["landing_charge_fraction"]
    assert left > 20.0 and out["flight"]["reason"].startswith(
        f"the cruise ends at the packs' cut-off with {left:.1f} % of the charge left")
    assert any("the reserve is charge, not power" in w for w in out["warnings"])
    shipped = json.loads(CliRunner().invoke(app, ["endurance", "--throttle", "0.5",
                                                  "--json"]).stdout)
    assert shipped["cruise_ends_at"] == "landing reserve"
    assert shipped["flight"]["reason"].startswith("lands with")
