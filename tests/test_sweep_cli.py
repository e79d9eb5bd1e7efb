"""`tuflexperf sweep`: grid values equal the single-case analyses; CSV, JSON, carpet plot."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.sweep import parse_vary, run_sweep
from tuflexperf.cli import app
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values

runner = CliRunner()


def test_sweep_json_rows_equal_the_deterministic_check(tmp_path) -> None:
    csv = tmp_path / "grid.csv"
    png = tmp_path / "carpet.png"
    result = runner.invoke(app, [
        "sweep", "--vary", "aircraft.mass_kg=18:30:4", "--vary", "atmosphere.altitude_m=0:2000:3",
        "--json", "--csv", str(csv), "--plot", str(png)])
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["parameters"] == ["aircraft.mass_kg", "atmosphere.altitude_m"]
    assert len(data["rows"]) == 12
    case = load_case(SHIPPED_CASE)
    for row in data["rows"][::5]:
        single = with_values(case, {k: row[k] for k in data["parameters"]})
        for verdict in check_case(single):
            got = row[verdict.name]
            assert got["passed"] == verdict.passed
            if verdict.value is None:
                assert got["value"] is None
            else:
                assert got["value"] == pytest.approx(verdict.value, rel=1e-6)
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("aircraft.mass_kg,atmosphere.altitude_m,takeoff_ground_roll_value")
    assert len(lines) == 13
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging debris


def test_one_point_is_start_equal_to_stop() -> None:
    result = runner.invoke(app, ["sweep", "--vary", "aircraft.mass_kg=30:30:1"])
    assert result.exit_code == 0 and "1 grid points" in result.stdout
    assert "FAIL" in result.stdout  # 30 kg fails trim


def test_one_axis_human_output_and_workers_equal(tmp_path) -> None:
    result = runner.invoke(app, ["sweep", "--vary", "aircraft.cd0=0.015:0.04:6",
                                 "--plot", str(tmp_path / "line.png")])
    assert result.exit_code == 0, result.stderr
    assert "6 grid points" in result.stdout and "PASS" in result.stdout
    case = load_case(SHIPPED_CASE)
    axes = [parse_vary(case, "aircraft.mass_kg=15:60:3000")]
    here = run_sweep(case, axes)
    there = run_sweep(case, axes, workers=2)
    for name in here.values:
        np.testing.assert_array_equal(here.values[name], there.values[name])
    assert (~here.met["takeoff_ground_roll"]).any() and here.met["takeoff_ground_roll"].any()


@pytest.mark.parametrize("args, message", [
    (["--vary", "aircraft.mass_kg=18:30"], "--vary"),
    (["--vary", "aircraft.mass_kgg=18:30:3"], "aircraft.mass_kg"),
    (["--vary", "aircraft.mass_kg=-5:30:3"], "aircraft.mass_kg"),
    (["--vary", "aircraft.mass_kg=18:30:3", "--plot", "x.pdf"], "--plot"),
    # one point at 18 kg PASSed, 30 kg (where trim fails) never flown (outside audit)
    (["--vary", "aircraft.mass_kg=18:30:1"], "N = 1 flies START alone"),
    # refused before the grid is made: 1e23 points was numpy's traceback, 1e9 ate 7.5 GiB
    (["--vary", "aircraft.mass_kg=20:25:99999999999999999999999"], "at most 1000000"),
    (["--vary", "aircraft.mass_kg=20:25:1000000000"], "at most 1000000"),
    # four axes of 1e6: 1e24 points, beyond numpy's int64 (its product wrapped)
    ([arg for key in ("mass_kg=20:25", "cd0=0.02:0.03", "k=0.05:0.06", "cl_max=1.4:1.5")
      for arg in ("--vary", f"aircraft.{key}:1000000")], "at most 1000000"),
])
def test_bad_vary_is_exit_2_one_line(args: list[str], message: str) -> None:
    result = runner.invoke(app, ["sweep", *args])
    assert result.exit_code == 2
    assert message in result.stderr and result.stderr.count("\n") == 1


def test_an_input_file_is_never_overwritten(tmp_path) -> None:
    target = SHIPPED_CASE.parent.parent / "data" / "tuflex" / "aircraft.yaml"
    before = target.read_bytes()
    result = runner.invoke(app, ["sweep", "--vary", "aircraft.mass_kg=18:30:3", "--csv",
                                 str(target)])
    assert result.exit_code == 2 and "input" in result.stderr
    assert target.read_bytes() == before


def test_a_set_the_grid_replaces_does_not_refuse_a_valid_grid() -> None:
    """A --set value of a varied key is not used (a note says so), so it cannot make the
    sweep bad input; nor can a --set that only the grid's own key crosses. Both were
    refused though every grid point was valid."""
    own = runner.invoke(app, ["sweep", "--set", "aircraft.mass_kg=0.001", "--vary",
                              "aircraft.mass_kg=20:30:3", "--json"])
    assert own.exit_code == 0, own.stderr
    plain = runner.invoke(app, ["sweep", "--vary", "aircraft.mass_kg=20:30:3", "--json"])
    assert json.loads(own.stdout)["rows"] == json.loads(plain.stdout)["rows"]
    crossed = runner.invoke(app, [
        "sweep", "--set", "requirements.envelope.max_airspeed_m_s=40", "--set",
        "requirements.envelope.min_airspeed_m_s=41", "--vary",
        "requirements.envelope.min_airspeed_m_s=16:20:2", "--json"])
    assert crossed.exit_code == 0, crossed.stderr
    single = check_case(with_values(load_case(SHIPPED_CASE), {
        "requirements.envelope.max_airspeed_m_s": 40.0,
        "requirements.envelope.min_airspeed_m_s": 20.0}))
    row = json.loads(crossed.stdout)["rows"][1]
    for verdict in single:
        value = row[verdict.name]["value"]
        assert (value is None) == (verdict.value is None)
        if value is not None:
            assert value == pytest.approx(verdict.value, rel=1e-6)
    # a --set that is bad input whatever the grid still is, naming the flag
    bad = runner.invoke(app, ["sweep", "--set", "aircraft.mass_kg=-1", "--vary",
                              "aircraft.cd0=0.03:0.04:2"])
    assert bad.exit_code == 2
    assert bad.stderr.startswith("tuflexperf: error: --set: aircraft.mass_kg")


def test_sweep_refuses_what_check_refuses_an_oei_on_one_engine(tmp_path) -> None:
    """One engine and an OEI requirement: check, oei, margins and --samples refuse it; the
    sweep tabulated 'not attainable FAIL' at every point and exited 0 (outside audit)."""
    from tests.conftest import MADE_UP_PROPULSION, write_case

    one = {**MADE_UP_PROPULSION, "engines": MADE_UP_PROPULSION["engines"][:1]}
    case = write_case(tmp_path, propulsion=one,
                      requirements={"oei": {"dead_engine": "zero", "max_throttle": 1.0}})
    for argv in (["check", str(case)],
                 ["sweep", "--case", str(case), "--vary", "aircraft.mass_kg=8:12:3"]):
        result = runner.invoke(app, argv)
        assert result.exit_code == 2, (argv, result.stdout)
        assert result.stderr.strip().endswith("engines: OEI needs at least two engines")
