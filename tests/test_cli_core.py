"""check/takeoff/trim/oei through typer's CliRunner and one real subprocess run."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tests.conftest import write_case
from tuflexperf.cli import app

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, list(args))


def test_check_json_keys_and_exit_code():
    result = run("check", "--json")
    data = json.loads(result.stdout)
    assert result.exit_code == (0 if data["passed"] else 1)
    assert set(data) >= {"passed", "results"}
    for item in data["results"]:
        assert set(item) >= {"name", "value", "limit", "unit", "margin", "passed"}


def test_check_human_table_names_each_requirement():
    result = run("check")
    assert "takeoff_ground_roll" in result.stdout and "PASS" in result.stdout


def test_takeoff_trim_oei_json_keys():
    takeoff = json.loads(run("takeoff", "--json").stdout)
    assert set(takeoff) >= {"ground_roll_m", "liftoff_speed_m_s", "time_s"}
    trim = json.loads(run("trim", "--json").stdout)
    assert set(trim) >= {"airspeed_m_s", "throttle", "min_throttle", "max_throttle", "all_feasible"}
    assert len(trim["airspeed_m_s"]) == len(trim["throttle"]) == 61
    oei = json.loads(run("oei", "--json").stdout)
    assert set(oei) >= {
        "min_throttle",
        "airspeed_at_min_throttle_m_s",
        "level_flight_airspeed_range_m_s",
    }


def test_trim_exit_1_when_full_throttle_is_not_enough(tmp_path):
    case = write_case(
        tmp_path, requirements={"envelope": {"min_airspeed_m_s": 14, "max_airspeed_m_s": 48}}
    )
    result = run("trim", "--case", str(case), "--json")
    assert result.exit_code == 1
    data = json.loads(result.stdout)
    assert data["all_feasible"] is False and data["throttle"][-1] is None


def test_check_fails_with_exit_1_and_reason(tmp_path):
    requirements = {"takeoff": {"max_ground_roll_m": 5}}
    case = write_case(tmp_path, requirements=requirements)
    result = run("check", str(case), "--json")
    assert result.exit_code == 1
    item = json.loads(result.stdout)["results"][0]
    assert item["passed"] is False and item["margin"] < 0


def test_takeoff_not_attainable_is_exit_1_with_reason(tmp_path):
    from tests.conftest import MADE_UP_AIRCRAFT

    heavy = {**MADE_UP_AIRCRAFT, "mass_kg": 200.0}
    case = write_case(tmp_path, aircraft=heavy)
    result = run("takeoff", "--case", str(case))
    assert result.exit_code == 1
    assert "never" in result.stderr and "Traceback" not in result.output
    # --json on exit 1: the SPEC's keys are there (null: no roll), the lift-off speed known
    out = run("takeoff", "--case", str(case), "--json")
    assert out.exit_code == 1
    payload = json.loads(out.stdout)
    assert payload["ground_roll_m"] is None and payload["time_s"] is None
    assert payload["liftoff_speed_m_s"] > 0 and payload["passed"] is False
    endurance = json.loads(run("endurance", "--throttle", "0.05", "--json").stdout)
    assert endurance["throttle"] == 0.05 and endurance["flight_endurance_min"] is None
    check = run("check", str(case), "--json")
    assert check.exit_code == 1
    item = json.loads(check.stdout)["results"][0]
    assert item["value"] is None and item["passed"] is False and "never" in item["reason"]


def test_an_arc_beyond_cl_max_prints_no_nan():
    """Load factor 1.5 at 1.15 V_stall needs CL beyond cl_max: no arc, said as n/a ('nan m'
    before), and the obstacle distance FAILs with the reason."""
    result = run("takeoff", "--set", "aircraft.takeoff.transition_load_factor=1.5",
                 "--set", "requirements.takeoff.max_distance_to_obstacle_m=200")
    assert result.exit_code == 1
    assert "nan" not in result.stdout.lower()
    assert "transition arc          n/a m" in result.stdout
    assert "beyond cl_max" in result.stdout


def test_set_gives_an_optional_key_the_case_leaves_unset():
    # the shipped aircraft has no lift-off speed (it uses the factor); --set may give one,
    # as the file could, and the take-off then lifts off at it (an EAS, sea level: = TAS)
    plain = json.loads(run("takeoff", "--json").stdout)
    given = run("takeoff", "--json", "--set", "aircraft.takeoff.liftoff_speed_m_s=18.5")
    assert given.exit_code in (0, 1), given.output
    out = json.loads(given.stdout)
    assert out["liftoff_speed_m_s"] == pytest.approx(18.5, rel=1e-9)
    assert out["ground_roll_m"] > plain["ground_roll_m"]
    # below the stall speed: bad input naming the key, one line
    low = run("takeoff", "--set", "aircraft.takeoff.liftoff_speed_m_s=5")
    assert low.exit_code == 2 and "liftoff_speed_m_s" in low.stderr
    assert len(low.stderr.strip().splitlines()) == 1 and "Value error" not in low.stderr
    typo = run("check", "--set", "aircraft.takeoff.liftof_speed_m_s=18")
    assert typo.exit_code == 2 and "did you mean aircraft.takeoff.liftoff_speed_m_s" in typo.stderr


def test_oei_dead_engine_flag(tmp_path):
    case = write_case(tmp_path)
    zero = json.loads(run("oei", "--case", str(case), "--dead-engine", "zero", "--json").stdout)
    wind = json.loads(run("oei", "--case", str(case), "--json").stdout)
    assert zero["min_throttle"] < wind["min_throttle"]
    bad = run("oei", "--dead-engine", "sleepy")
    assert bad.exit_code == 2 and "--dead-engine" in bad.stderr


def test_installed_script_runs_from_any_directory(tmp_path):
    script = shutil.which("tuflexperf", path=str(Path(sys.executable).parent)) or shutil.which(
        "tuflexperf"
    )
    if script is None:
        pytest.skip("console script not installed")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [script, "check", "--json"], cwd=tmp_path, capture_output=True, text=True, env=env
    )
    assert done.returncode in (0, 1), done.stderr
    assert json.loads(done.stdout)["results"]
    bad = subprocess.run(
        [script, "check", "nope.yaml"], cwd=tmp_path, capture_output=True, text=True, env=env
    )
    assert bad.returncode == 2
    assert bad.stderr.strip().count("\n") == 0 and "nope.yaml" in bad.stderr
    assert bad.stdout == ""


def test_check_does_not_import_plotting_or_dataframes():
    code = (
        "import sys\n"
        "from tuflexperf.cli import main\n"
        "try:\n    main(['check', '--json'])\n"
        "except SystemExit:\n    pass\n"
        "bad = [m for m in ('matplotlib', 'pandas', 'scipy') if m in sys.modules]\n"
        "sys.stderr.write(','.join(bad))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stderr == "", f"check imported: {done.stderr}"


def test_an_error_raised_by_an_interrupt_is_the_interrupt(monkeypatch):
    """A SIGTERM landing inside an import or a C extension comes out as that code's error
    (RuntimeError, SystemError): exit 130 "aborted", not a traceback (hostile audit)."""
    import signal
    import sys as _sys

    import tuflexperf.analysis.requirements as requirements
    from tuflexperf.cli import main
    from tuflexperf.io import files

    def broken(case):
        files._signals_received.append(signal.SIGTERM)
        raise RuntimeError("error return without exception set")

    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    hook = _sys.unraisablehook
    monkeypatch.setattr(files, "_signals_received", [])
    monkeypatch.setattr(requirements, "check_case", broken)
    try:
        with pytest.raises(SystemExit) as done:
            main(["check"])
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
        _sys.unraisablehook = hook
    assert done.value.code == 130
    # without an interrupt the same error is a real failure and is not hidden
    monkeypatch.setattr(files, "_signals_received", [])
    monkeypatch.setattr(requirements, "check_case",
                        lambda case: (_ for _ in ()).throw(RuntimeError("a real bug")))
    try:
        with pytest.raises(RuntimeError, match="a real bug"):
            main(["check"])
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
        _sys.unraisablehook = hook


def test_unreadable_numbers_and_unflyable_climbs_are_one_line(tmp_path):
    """Found by a hostile audit: a 5000-digit integer in a case (Python refuses to read it)
    and a wing so small that the best climb is beyond Mach 1 gave tracebacks."""
    case = tmp_path / "huge.yaml"
    case.write_text("name: huge\naircraft: a.yaml\npropulsion: p.yaml\nrequirements:\n"
                    "  takeoff: {max_ground_roll_m: 1" + "0" * 5000 + "}\n")
    out = run("check", str(case))
    assert out.exit_code == 2 and "huge.yaml" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    tiny = run("endurance", "--throttle", "0.5", "--json", "--set", "aircraft.wing_area_m2=0.01")
    assert tiny.exit_code == 1 and "Traceback" not in tiny.output
    assert json.loads(tiny.stdout)["flight_endurance_min"] is None
    check = run("check", "--json", "--set", "aircraft.wing_area_m2=0.01")
    assert check.exit_code == 1
    assert not any(r["passed"] for r in json.loads(check.stdout)["results"])


def test_set_moves_the_envelope_bounds_of_one_case():
    """SPEC 5: --set takes the case's numeric keys; the envelope's bounds were refused (they
    fix a batch's grid, not one case's; outside audit). Both bounds may move together."""
    narrow = json.loads(run("trim", "--json", "--set",
                            "requirements.envelope.max_airspeed_m_s=30").stdout)
    assert narrow["airspeed_m_s"][0] == 15.0 and narrow["airspeed_m_s"][-1] == 30.0
    assert len(narrow["airspeed_m_s"]) == 31  # 0.5 m/s steps, both ends
    # at P(met) >= 0.6 the thrust's bound at 45 m/s still trims (at 0.9 it does not)
    bound = ("--set", "requirements.extrapolation.required_probability=0.6")
    shipped = json.loads(run("trim", "--json", *bound).stdout)
    assert narrow["max_throttle"] < shipped["max_throttle"]
    moved = run("trim", "--json", "--set", "requirements.envelope.min_airspeed_m_s=50",
                "--set", "requirements.envelope.max_airspeed_m_s=60")
    speeds = json.loads(moved.stdout)["airspeed_m_s"]
    assert speeds[0] == 50.0 and speeds[-1] == 60.0
    crossed = run("trim", "--set", "requirements.envelope.min_airspeed_m_s=50")
    assert crossed.exit_code == 2 and "must be below max_airspeed_m_s" in crossed.stderr
    # a batch varies them too, each row on its own grid (tests/verification/
    # test_batch_envelope_bounds.py holds the rows to the single cases)
    batch = run("sweep", "--json", "--vary", "requirements.envelope.max_airspeed_m_s=30:45:2",
                *bound)
    assert batch.exit_code == 0, batch.stderr
    rows = json.loads(batch.stdout)["rows"]
    assert rows[0]["trim_throttle_max"]["value"] == pytest.approx(narrow["max_throttle"],
                                                                  rel=1e-9)
    # the requirement's value is the worse reading's (the thrust beyond the tested 30 m/s at
    # its bound), as check's and trim's verdict shows it
    assert rows[1]["trim_throttle_max"]["value"] == pytest.approx(shipped["result"]["value"],
                                                                  rel=1e-9)
    assert shipped["result"]["readings"][0]["value"] == shipped["max_throttle"]


def test_sweep_says_where_it_extrapolates_the_thrust_model() -> None:
    """SPEC: extrapolation is said. An envelope to 30 m/s stays within the tested 0-30 m/s,
    one to 45 m/s does not; the single case says the same of each (`extrapolated`)."""
    batch = run("sweep", "--json", "--vary", "requirements.envelope.max_airspeed_m_s=30:45:2")
    rows = json.loads(batch.stdout)["rows"]
    flags = [r["trim_throttle_max"]["extrapolated"] for r in rows]
    singles = [json.loads(run("trim", "--json", "--set",
                              f"requirements.envelope.max_airspeed_m_s={top}").stdout)
               ["extrapolated"] for top in (30, 45)]
    assert flags == singles == [False, True]
    text = run("sweep", "--vary", "requirements.envelope.max_airspeed_m_s=30:45:2").stdout
    assert ("note: trim_throttle_max: thrust model extrapolated beyond its tested 0-30 m/s at "
            "1 of 2 grid points") in text
    assert "takeoff_ground_roll: thrust model" not in text  # lift-off at 16.6 m/s
