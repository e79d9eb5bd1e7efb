"""Malformed files and flags: exit 2, one line on stderr naming the file and key, no traceback."""

from __future__ import annotations

import copy
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import (
    MADE_UP_AIRCRAFT,
    MADE_UP_PROPULSION,
    MADE_UP_REQUIREMENTS,
    copy_shipped_case,
    write_case,
)
from tuflexperf.cli import app

runner = CliRunner()
ROOT = Path(__file__).resolve().parent.parent


def _assert_bad(result, *needles):
    assert result.exit_code == 2, result.output
    message = result.stderr.strip()
    assert message.count("\n") == 0, message
    assert "Traceback" not in result.output
    for needle in needles:
        assert needle in message, message
    assert result.stdout == ""


def _mutated(section, path, value):
    data = copy.deepcopy(
        {
            "aircraft": MADE_UP_AIRCRAFT,
            "propulsion": MADE_UP_PROPULSION,
            "requirements": MADE_UP_REQUIREMENTS,
        }[section]
    )
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is _DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return {section: data}


_DELETE = object()

CASES = [
    # (section, key path, value, file that must be named, key text that must be named)
    ("aircraft", ["mass_kg"], -3.0, "aircraft.yaml", "mass_kg"),
    ("aircraft", ["mass_kg"], "heavy", "aircraft.yaml", "mass_kg"),
    ("aircraft", ["mass_kg"], float("nan"), "aircraft.yaml", "mass_kg"),
    ("aircraft", ["cd0"], _DELETE, "aircraft.yaml", "cd0"),
    ("aircraft", ["wingarea_m2"], 1.0, "aircraft.yaml", "wingarea_m2"),
    (
        "aircraft",
        ["takeoff", "rolling_frcition"],
        0.05,
        "aircraft.yaml",
        "takeoff.rolling_frcition",
    ),
    # physics bounds found by an outside review (each was a PASS before): an obstacle above
    # 100 m was climbed at the field's gradient (15 km "passed"); cl_max 100 gave a 2 m roll
    ("aircraft", ["cl_max"], 100.0, "aircraft.yaml", "cl_max"),
    # an unbounded value overflowed into a message naming no file or key (outside audit)
    ("aircraft", ["takeoff", "cl_ground"], 1e308, "aircraft.yaml", "takeoff.cl_ground"),
    # a ground-roll lift above cl_max held the weight below stall (2.5 on 1.69 "passed" with
    # a note; outside audit)
    ("aircraft", ["takeoff", "cl_ground"], 2.5, "aircraft.yaml", "takeoff.cl_ground"),
    ("propulsion", ["voltage_exponent"], 1000.0, "propulsion.yaml", "voltage_exponent"),
    ("propulsion", ["reference_voltage_v"], 1e300, "propulsion.yaml", "reference_voltage_v"),
    ("requirements", ["takeoff", "obstacle_height_m"], 15000.0, "case.yaml",
     "requirements.takeoff.obstacle_height_m"),
    ("propulsion", ["model"], "poly33", "propulsion.yaml", "model"),
    ("propulsion", ["tested_airspeed_m_s"], [30, 0], "propulsion.yaml", "tested_airspeed_m_s"),
    ("propulsion", ["engines"], [], "propulsion.yaml", "engines"),
    (
        "propulsion",
        ["engines", 0, "coefficients", "p12"],
        1.0,
        "propulsion.yaml",
        "engines[0].coefficients.p12",
    ),
    (
        "propulsion",
        ["engines", 1, "coefficients", "p02"],
        float("inf"),
        "propulsion.yaml",
        "engines[1].coefficients.p02",
    ),
    ("propulsion", ["delay_s"], -0.1, "propulsion.yaml", "delay_s"),
    # names go into comments, CSV headers and XML: a newline in one injected YAML keys into
    # fit's output, an escape made the export's XML malformed, a comma split the mission's
    # CSV columns (outside audit)
    ("aircraft", ["name"], "TU-Flex\ncapacity_ah: 99", "aircraft.yaml", "name"),
    ("propulsion", ["engines", 0, "name"], "E\x1b[31m1", "propulsion.yaml",
     "engines[0].name"),
    ("propulsion", ["engines", 0, "name"], "E\x001", "propulsion.yaml", "engines[0].name"),
    ("propulsion", ["engines", 1, "name"], "EDF,2", "propulsion.yaml", "engines[1].name"),
    # and fills CSV cells, where a spreadsheet runs a leading '=' as a formula
    ("propulsion", ["engines", 1, "name"], "=SUM(A1)", "propulsion.yaml", "engines[1].name"),
    ("propulsion", ["name"], "x" * 201, "propulsion.yaml", "name"),
    ("requirements", ["takeof"], {"max_ground_roll_m": 60}, "case.yaml", "requirements.takeof"),
    ("requirements", ["envelope", "max_airspeed_m_s"], 10, "case.yaml", "envelope"),
    ("requirements", ["oei", "max_throttle"], 1.5, "case.yaml", "requirements.oei.max_throttle"),
    (
        "requirements",
        ["oei", "dead_engine"],
        "feathered",
        "case.yaml",
        "requirements.oei.dead_engine",
    ),
    (
        "requirements",
        ["endurance"],
        {"throttle": -0.1, "min_flight_time_min": 15},
        "case.yaml",
        "throttle",
    ),
]


@pytest.mark.parametrize(("section", "path", "value", "file", "key"), CASES)
def test_malformed_files_exit_2_naming_file_and_key(tmp_path, section, path, value, file, key):
    case = write_case(tmp_path, **_mutated(section, path, value))
    _assert_bad(runner.invoke(app, ["check", str(case)]), file, key)


def test_case_level_problems(tmp_path):
    case = write_case(tmp_path, atmosphere={"altitude_m": 0, "temprature_offset_k": 10})
    _assert_bad(
        runner.invoke(app, ["check", str(case)]), "case.yaml", "atmosphere.temprature_offset_k"
    )
    case = write_case(tmp_path, atmosphere={"altitude_m": 90000})
    _assert_bad(runner.invoke(app, ["trim", "--case", str(case)]), "atmosphere.altitude_m")
    case = write_case(tmp_path, surprise=1)
    _assert_bad(runner.invoke(app, ["check", str(case)]), "surprise")


def test_missing_and_unreadable_files(tmp_path):
    _assert_bad(
        runner.invoke(app, ["check", str(tmp_path / "absent.yaml")]), "absent.yaml", "not found"
    )
    _assert_bad(runner.invoke(app, ["check", str(tmp_path)]), "directory")
    case = write_case(tmp_path)
    text = case.read_text().replace("aircraft.yaml", "nowhere/aircraft.yaml")
    case.write_text(text)
    _assert_bad(
        runner.invoke(app, ["check", str(case)]), "case.yaml", "aircraft", "nowhere/aircraft.yaml"
    )


def test_invalid_yaml_duplicate_keys_and_non_mapping(tmp_path):
    case = write_case(tmp_path)
    (tmp_path / "aircraft.yaml").write_text("name: [unclosed\nmass_kg: 3\n")
    _assert_bad(runner.invoke(app, ["check", str(case)]), "aircraft.yaml", "invalid YAML")
    (tmp_path / "aircraft.yaml").write_text(yaml.safe_dump(MADE_UP_AIRCRAFT) + "mass_kg: 40\n")
    _assert_bad(
        runner.invoke(app, ["check", str(case)]), "aircraft.yaml", "duplicate key 'mass_kg'"
    )
    (tmp_path / "aircraft.yaml").write_text("- just\n- a list\n")
    _assert_bad(runner.invoke(app, ["check", str(case)]), "aircraft.yaml", "mapping")
    # a merge key: "could not determine a constructor for the tag ...:merge" told nothing
    (tmp_path / "aircraft.yaml").write_text(
        "shared: &t {cl_ground: 0.4}\n" + yaml.safe_dump(MADE_UP_AIRCRAFT).replace(
            "takeoff:", "takeoff:\n  <<: *t\nunused_takeoff:", 1))
    _assert_bad(runner.invoke(app, ["check", str(case)]), "aircraft.yaml", "merge key '<<'")


def test_trim_without_envelope_names_the_missing_block(tmp_path):
    case = write_case(tmp_path, requirements={"takeoff": {"max_ground_roll_m": 60}})
    _assert_bad(
        runner.invoke(app, ["trim", "--case", str(case)]), "case.yaml", "requirements.envelope"
    )


def test_check_of_a_case_without_requirements_is_no_pass(tmp_path):
    """Every requirement block commented out: check verified nothing and said "overall:
    PASS" (exit 0). Now bad input naming the file and key; the analyses still run on it."""
    case = write_case(tmp_path, requirements={})
    for args in (["check", str(case)], ["check", str(case), "--json"],
                 ["check", str(case), "--samples", "8"]):
        _assert_bad(runner.invoke(app, args), "case.yaml", "requirements: none stated")
    assert runner.invoke(app, ["takeoff", "--case", str(case)]).exit_code in (0, 1)


def test_bad_flags_give_one_line_and_exit_2():
    from tests.conftest import tuflexperf

    process = subprocess.run(  # one as the console runs it, the rest in this process
        [sys.executable, "-m", "tuflexperf", "check", "--bogus"], capture_output=True, text=True
    )
    for argv, done in ((["check", "--bogus"], process), *((argv, tuflexperf(*argv)) for argv in (
            ["trim", "--case"], ["nosuchcommand"]))):
        assert done.returncode == 2, (argv, done.stderr)
        assert done.stderr.strip().count("\n") == 0, done.stderr
        assert "Traceback" not in done.stderr


def test_a_case_given_by_position_to_a_command_that_takes_case_says_so(capsys):
    """``report case.yaml --out r``: typer's "unexpected extra argument" alone left the user
    guessing; only check and mission take a file by position."""
    from tuflexperf.cli import main

    with pytest.raises(SystemExit) as done:
        main(["report", "my_case.yaml", "--out", "r"])
    assert done.value.code == 2
    line = capsys.readouterr().err
    assert line.count("\n") == 1 and "--case my_case.yaml" in line
    with pytest.raises(SystemExit):
        main(["trim", "--case", "a.yaml", "b.yaml"])  # --case given: no hint
    assert "--case b.yaml" not in capsys.readouterr().err


def test_symbolic_link_loops_are_one_line_not_a_traceback(tmp_path):
    """A link that points at itself, as a campaign's run and as a case's propulsion file:
    pathlib raised RuntimeError("Symlink loop ...") out of fit, report, check, mission and
    export as a traceback (found by an outside audit)."""
    from pathlib import Path

    shipped = Path(__file__).resolve().parents[1] / "data" / "tuflex" / "campaign"
    campaign = tmp_path / "campaign"
    shutil.copytree(shipped, campaign)
    run = campaign / "runs" / "edf1_v15p0.csv.gz"
    run.unlink()
    run.symlink_to(run.name)
    _assert_bad(runner.invoke(app, ["fit", str(campaign / "campaign.yaml"), "--out",
                                    str(tmp_path / "fitted.yaml")]),
                "edf1_v15p0.csv.gz", "symbolic link loop")
    assert not (tmp_path / "fitted.yaml").exists()
    case = write_case(tmp_path / "case")
    propulsion = case.parent / "propulsion.yaml"
    propulsion.unlink()
    propulsion.symlink_to(propulsion.name)
    for args in (["check", str(case)], ["takeoff", "--case", str(case)],
                 ["export", "--case", str(case), "--out", str(tmp_path / "export")]):
        _assert_bad(runner.invoke(app, args), "propulsion.yaml", "symbolic link loop")


def test_a_misspelt_required_key_is_matched_to_the_missing_one(tmp_path):
    """'p12' for 'p11' was answered 'did you mean p20?' (a key that is present); the key
    left missing beside the unknown one is the likelier meaning (outside audit)."""
    from tuflexperf.errors import InputError
    from tuflexperf.io.case import load_case

    copy_shipped_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    original = propulsion.read_text()
    for wrong, meant in (("p12", "p11"), ("p2", "p02")):
        propulsion.write_text(original.replace(f"      {meant}:", f"      {wrong}:", 1))
        with pytest.raises(InputError, match=rf"unknown key '{wrong}' \(did you mean '{meant}'"):
            load_case(tmp_path / "requirements" / "tuflex.yaml")


def test_a_misspelt_key_under_a_named_parameter_gets_the_closest_one(tmp_path):
    """A distribution under ``uncertainty.parameters.<key>`` (a key the user names):
    'normall' had no suggestion, the schema walk stopped at the user's key (outside audit)."""
    from tuflexperf.errors import InputError
    from tuflexperf.io.case import load_case

    copy_shipped_case(tmp_path)
    case = tmp_path / "requirements" / "tuflex.yaml"
    original = case.read_text()
    for wrong, meant in (("normall", "normal"), ("truncated_nomal", "truncated_normal"),
                         ("unifrom", "uniform")):
        case.write_text(original + "uncertainty:\n  parameters:\n    aircraft.mass_kg: {"
                        + wrong + ": [20.0, 0.5]}\n")
        with pytest.raises(InputError, match=rf"aircraft.mass_kg.{wrong}: unknown key "
                                             rf"'{wrong}' \(did you mean '{meant}'"):
            load_case(case)


@pytest.mark.parametrize(("args", "needle"), [
    # --set met none of the files' cross checks: 1e-9 kg passed with 1e10 x thrust/weight
    (["takeoff", "--set", "aircraft.mass_kg=1e-9"], "physically absurd"),
    # the weight's square overflowed into a traceback
    (["check", "--set", "aircraft.mass_kg=1e300"], "less than or equal to 1000000"),
    # a 1e300 m^2 wing lifted off at 0 m/s; a 1e-300 m^2 one stalled at 1e151 m/s
    (["check", "--set", "aircraft.wing_area_m2=1e300"], "aircraft.wing_area_m2"),
    (["performance", "--set", "aircraft.wing_area_m2=1e-300"], "beyond the speed of sound"),
    # the last one won, silently (outside audit)
    (["check", "--set", "aircraft.mass_kg=20", "--set", "aircraft.mass_kg=40"],
     "--set: aircraft.mass_kg given twice (20 and 40)"),
    # read as YAML, a comment or a tag took 020 past the octal check (outside re-audit)
    (["check", "--set", "requirements.endurance.min_flight_time_min=020 # twenty"],
     "not a number"),
    (["check", "--set", "requirements.endurance.min_flight_time_min=!!int 020"],
     "not a number"),
])
def test_absurd_values_set_on_the_command_line_are_bad_input(args, needle):
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert needle in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_a_null_requirement_block_is_bad_input(tmp_path):
    """`takeoff: null` dropped the requirement and check passed without it (outside audit)."""
    copy_shipped_case(tmp_path)
    case = tmp_path / "requirements" / "tuflex.yaml"
    text = case.read_text()
    for empty in ("  takeoff: null\n", "  takeoff:\n"):
        case.write_text(text.replace("  takeoff: {max_ground_roll_m: 60}\n", empty))
        result = runner.invoke(app, ["check", str(case)])
        assert result.exit_code == 2, result.output
        assert "requirements.takeoff: the requirement block is empty (null)" in result.stderr
    # so is a bare `uncertainty:`, which turned the probabilistic check off unsaid (audit)
    case.write_text(text + "uncertainty:\n")
    result = runner.invoke(app, ["check", str(case)])
    assert result.exit_code == 2, result.output
    assert "uncertainty: the uncertainty block is empty (null)" in result.stderr


def test_an_alias_bomb_in_the_propulsion_source_is_refused_at_once(tmp_path):
    """Nine levels of nine aliases in `source:` cost check nothing but ran the exports out
    of memory (outside audit): the expanded provenance is counted, and refused."""
    copy_shipped_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    levels = "".join(f"  {chr(98 + i)}: &{chr(98 + i)} [{','.join(['*' + chr(97 + i)] * 9)}]\n"
                     for i in range(9))
    propulsion.write_text(propulsion.read_text() + "source:\n  a: &a [x,x,x,x,x,x,x,x,x]\n"
                          + levels)
    out = tmp_path / "exp"
    result = runner.invoke(app, ["export", "--case", str(tmp_path / "requirements/tuflex.yaml"),
                                 "--format", "json", "--out", str(out)])
    assert result.exit_code == 2 and "propulsion.yaml: more than 2,000,000 values once its " \
        "anchors and aliases are expanded" in result.stderr
    assert not out.exists()


def test_an_alias_bomb_anywhere_is_refused_before_the_schemas_see_it(tmp_path):
    """A covariance of 2,000 rows, each an alias of one 2,000-value row (40 kB), was expanded
    by the schema before its 6 x 6 check: 20,000 rows took 3.2 GB (outside audit)."""
    copy_shipped_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    text = propulsion.read_text()
    start, end = text.index("    covariance:\n"), text.index("    residual_sd_n")
    rows = "[&r [" + ",".join(["1.0"] * 2000) + "]," + ",".join(["*r"] * 2000) + "]"
    propulsion.write_text(text[:start] + "    covariance: " + rows + "\n" + text[end:])
    _assert_bad(runner.invoke(app, ["check", str(tmp_path / "requirements/tuflex.yaml")]),
                "propulsion.yaml: more than 2,000,000 values")


def test_fits_own_provenance_is_far_below_the_source_bound(tmp_path):
    from tuflexperf.io.case import MAX_SOURCE_VALUES
    from tuflexperf.io.yamlio import count_values
    from tuflexperf.reduction.pipeline import fit_campaign

    source = yaml.safe_load(fit_campaign(ROOT / "data/tuflex/campaign/campaign.yaml")
                            .propulsion_text)["source"]
    assert 10 < count_values(source, MAX_SOURCE_VALUES) < MAX_SOURCE_VALUES / 1000


def test_set_on_a_block_the_case_leaves_out_says_so(tmp_path):
    copy_shipped_case(tmp_path)
    case = tmp_path / "requirements" / "tuflex.yaml"
    case.write_text(case.read_text().replace("  takeoff: {max_ground_roll_m: 60}\n", ""))
    result = runner.invoke(app, ["check", str(case), "--set",
                                 "requirements.takeoff.max_ground_roll_m=0.1"])
    assert result.exit_code == 2
    assert "the case has no requirements.takeoff block" in result.stderr
    assert "did you mean" not in result.stderr


@pytest.mark.parametrize(("value", "hint"), [("1.0000001", False), ("1.5", False), ("50", True)])
def test_a_percent_hint_only_for_what_looks_like_a_percent(value, hint):
    result = runner.invoke(app, ["endurance", "--throttle", value])
    assert result.exit_code == 2 and "must be a fraction in [0, 1]" in result.stderr
    assert ("fraction, not percent" in result.stderr) is hint


@pytest.mark.parametrize("density", ["1e-9", "50.0"])
def test_a_reference_density_no_test_day_has_is_bad_input(tmp_path, density) -> None:
    """1e-9 kg/m^3 scaled every thrust 1e9-fold: take-off, trim and OEI PASSed, a climb of
    1.6e10 m/s (outside audit)."""
    case = copy_shipped_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    text = propulsion.read_text()
    assert "reference_density_kg_m3:" in text
    propulsion.write_text("\n".join(
        f"reference_density_kg_m3: {density}" if line.startswith("reference_density_kg_m3:")
        else line for line in text.splitlines()) + "\n")
    _assert_bad(runner.invoke(app, ["check", str(case)]), "propulsion.yaml",
                "reference_density_kg_m3")


def test_a_newline_in_a_path_or_a_files_garbage_stays_one_line(tmp_path) -> None:
    """A path with a newline made the message two lines, and a binary run file's quoted
    garbage one line of 5,091 characters (outside audit)."""
    _assert_bad(runner.invoke(app, ["check", str(tmp_path / "no\nsuch.yaml")]), "no\\nsuch.yaml")
    junk = tmp_path / "junk.csv"
    junk.write_bytes(bytes(range(256)) * 80)
    result = runner.invoke(app, ["fit", str(junk), "--out", str(tmp_path / "o.yaml")])
    _assert_bad(result)
    assert len(result.stderr) < 1200


@pytest.mark.parametrize(("written", "reading"), [
    ("020", "octal 16"), ("-05", "octal -5"), ("1:00", "base 60 60"), ("0x40", "hex 64"),
    ("0b11", "binary 3"), ("0815", "text"),
])
def test_a_number_yaml_reads_other_than_in_decimal_is_bad_input(tmp_path, written,
                                                                 reading) -> None:
    """``min_flight_time_min: 020`` was a limit of 16 min (octal) and passed 18.5 min; the
    same in ``--set`` and in a mission's ``time_min: 8:30`` (510 min). Outside audit."""
    path = copy_shipped_case(tmp_path)
    text = path.read_text()
    assert "min_flight_time_min: 15" in text
    for tag in ("", "!!int ", "!!float "):  # a tag took it past (outside re-audit)
        path.write_text(text.replace("min_flight_time_min: 15",
                                     f"min_flight_time_min: {tag}{written}"))
        _assert_bad(runner.invoke(app, ["check", str(path)]), "min_flight_time_min",
                    f"'{written}' is no plain decimal number (YAML 1.1 reads it as {reading})")
    path.write_text(text)
    _assert_bad(runner.invoke(app, ["check", str(path), "--set",
                                    f"requirements.endurance.min_flight_time_min={written}"]),
                "--set: requirements.endurance.min_flight_time_min", reading)
    if ":" not in written:  # --vary's own separator
        _assert_bad(runner.invoke(app, [
            "sweep", "--case", str(path), "--vary",
            f"requirements.endurance.min_flight_time_min={written}:30:2"]), "--vary", reading)
    mission = tmp_path / "m.yaml"
    mission.write_text(f"name: m\nsegments:\n  - {{type: cruise, airspeed_m_s: 26, "
                       f"time_min: {written}}}\n")
    _assert_bad(runner.invoke(app, ["mission", str(mission), "--case", str(path)]),
                "m.yaml", "time_min", reading)


def test_text_that_looks_like_such_a_number_stays_text_where_text_is_meant(tmp_path) -> None:
    path = copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    lines = aircraft.read_text().splitlines()
    lines = ["name: 0123" if line.startswith("name:") else line for line in lines]
    aircraft.write_text("\n".join(lines) + "\n")
    result = runner.invoke(app, ["check", str(path), "--json"])
    assert result.exit_code in (0, 1), result.stderr


def test_a_thrust_table_is_checked_like_every_input(tmp_path) -> None:
    """``fit TABLE.csv`` read the file whatever it was: a FIFO hung, /dev/zero filled the
    memory, a 140 kB field and a 3 GB file ended in tracebacks (outside audit)."""
    import os

    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.csv"
    zero.symlink_to("/dev/zero")
    long = tmp_path / "long.csv"
    long.write_text("engine,throttle,airspeed_m_s,thrust_n\n" + "x" * 140_000 + ",0,0,0\n")
    big = tmp_path / "big.csv"
    with big.open("wb") as handle:
        handle.truncate(65 << 20)  # sparse: no disk used
    for path, needle in ((fifo, "not a regular file"), (zero, "not a regular file"),
                         (long, "cannot read as CSV"), (big, "larger than a thrust table")):
        _assert_bad(runner.invoke(app, ["fit", str(path), "--out", str(tmp_path / "p.yaml")]),
                    path.name, needle)
    assert not (tmp_path / "p.yaml").exists()


def test_an_engine_name_a_spreadsheet_would_run_is_refused_in_a_table_and_a_campaign(
        tmp_path) -> None:
    """An engine named ``=HYPERLINK(...)`` in a thrust table or a campaign reached fit's
    propulsion file and thrust table, a formula in every spreadsheet (outside audit)."""
    import shutil

    table = tmp_path / "table.csv"
    table.write_text("engine,throttle,airspeed_m_s,thrust_n\n@cmd,0.5,0,10\n")
    _assert_bad(runner.invoke(app, ["fit", str(table), "--out", str(tmp_path / "p.yaml")]),
                "table.csv: line 2: engine", "cannot start with '@'")
    campaign = tmp_path / "campaign"
    shutil.copytree(ROOT / "data" / "tuflex" / "campaign", campaign)
    manifest = campaign / "campaign.yaml"
    manifest.write_text(manifest.read_text().replace("engine: EDF1", "engine: '=1+1'", 1))
    _assert_bad(runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "p.yaml")]),
                "runs[0].engine", "cannot start with '='")
    assert not (tmp_path / "p.yaml").exists()


@pytest.mark.parametrize(("line", "value", "needle"), [
    ("delay_s: 0.05", "delay_s: 1e9", "delay_s"),
    ("fan_area_m2: 0.006793", "fan_area_m2: 6793", "fan_area_m2"),
])
def test_a_propulsion_value_no_fan_has_is_bad_input(tmp_path, line, value, needle) -> None:
    """A 1e9 s delay ran (fit refuses beyond 1 s); an area in mm^2 gave misleading
    jet-velocity notes and exit 1 (outside audit)."""
    path = copy_shipped_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    text = propulsion.read_text()
    assert line in text
    propulsion.write_text(text.replace(line, value))
    _assert_bad(runner.invoke(app, ["check", str(path)]), "propulsion.yaml", needle)


def test_a_folder_or_device_named_as_an_input_is_said_as_such(tmp_path) -> None:
    """A directory or /dev/zero given as the aircraft file was "file not found" (audit)."""
    path = copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    aircraft.unlink()
    aircraft.mkdir()
    _assert_bad(runner.invoke(app, ["check", str(path)]), "aircraft: a directory, not a file")
    aircraft.rmdir()
    aircraft.symlink_to("/dev/zero")
    _assert_bad(runner.invoke(app, ["check", str(path)]), "aircraft: not a regular file")
    aircraft.unlink()
    _assert_bad(runner.invoke(app, ["check", str(path)]), "aircraft: file not found")


@pytest.mark.parametrize(("file", "old", "new", "message"), [
    # a p02 of 1e300 and a p01 that gives 150 N at idle PASSed trim at throttle 0 (audit)
    ("propulsion.yaml", "p02: 0.0006833333333", "p02: 1e300", "inside the tested range"),
    ("propulsion.yaml", "p01: -0.13", "p01: 100", "inside the tested range"),
    ("propulsion.yaml", "tested_airspeed_m_s: [0, 30]", "tested_airspeed_m_s: [0, 1e308]",
     "tested_airspeed_m_s"),
])
def test_nonsense_models_are_bad_input_not_a_pass(tmp_path, file, old, new, message):
    from tests.conftest import copy_shipped_case

    case = copy_shipped_case(tmp_path)
    path = tmp_path / "data" / "tuflex" / file
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    _assert_bad(runner.invoke(app, ["check", str(case)]), file, message)


def test_a_catapult_release_beyond_mach_1_or_the_jet_velocity_is_no_pass(tmp_path):
    from tests.conftest import copy_shipped_case

    case = copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    shipped = aircraft.read_text()
    aircraft.write_text(shipped + "launch: catapult\nlaunch_speed_m_s: 400\n")
    _assert_bad(runner.invoke(app, ["takeoff", "--case", str(case)]), "aircraft.yaml",
                "launch_speed_m_s")
    aircraft.write_text(shipped + "launch: catapult\nlaunch_speed_m_s: 150\n")
    result = runner.invoke(app, ["takeoff", "--case", str(case)])
    assert result.exit_code == 1 and "beyond the fans' jet velocity" in result.stderr


@pytest.mark.parametrize("args", [
    ["endurance", "--throttle", "0.5", "--throttle", "0.6"],
    ["endurance", "--throttle=0.5", "--throttle", "0.5"],
    ["takeoff", "--case", "a.yaml", "--case=b.yaml"],
])
def test_a_single_valued_option_given_twice_is_refused(args, capsys):
    # click keeps the last value silently: `--throttle 0.5 --throttle 0.6` flew 0.6
    from tuflexperf.cli import main

    with pytest.raises(SystemExit) as done:
        main(args)
    assert done.value.code == 2
    out = capsys.readouterr()
    assert out.out == "" and out.err.count("\n") == 1, out
    flag = args[1].partition("=")[0]
    assert f"'{flag}'" in out.err and "given twice" in out.err and "give it once" in out.err


def test_repeatable_options_and_repeated_flags_are_not_refused():
    result = runner.invoke(app, ["endurance", "--throttle", "0.5", "--set", "aircraft.mass_kg=21",
                                 "--set", "aircraft.cd0=0.02", "--json", "--json"])
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize("named, kind", [
    ("../data/tuflex/aircraft.yaml", "an aircraft file"),
    ("../data/tuflex/battery.yaml", "a battery file"),
    ("../data/tuflex/campaign/campaign.yaml", "a campaign file"),
    ("tuflex.yaml", "a case file"),
])
def test_another_kind_of_file_as_the_mission_is_named_as_such(tmp_path, named, kind):
    # a case's mission naming its aircraft file was told "mass_kg: unknown key"
    case = copy_shipped_case(tmp_path)
    text = case.read_text() + f"  mission: {{file: {named}, min_landing_charge_fraction: 0.2}}\n"
    case.write_text(text)
    result = runner.invoke(app, ["check", str(case)])
    _assert_bad(result, Path(named).name, f"this is {kind}, not a mission file")


def test_a_misspelt_key_of_the_right_kind_of_file_still_gets_its_closest_key(tmp_path):
    case = copy_shipped_case(tmp_path)
    (tmp_path / "m.yaml").write_text("name: m\nsegmnts: []\n")
    mission = f"  mission: {{file: {tmp_path / 'm.yaml'}, min_landing_charge_fraction: 0.2}}\n"
    case.write_text(case.read_text() + mission)
    _assert_bad(runner.invoke(app, ["check", str(case)]), "did you mean 'segments'?")


def test_small_hostile_leftovers_are_one_line_naming_the_flag_or_key(tmp_path, capsys):
    """Outside audit: `--dask ''` ran locally unsaid; a 5000-digit --set value was echoed
    whole; a campaign fan of 1e-300 m^2 was fitted; a table's 3e7 m/s airspeed was refused
    as 'points that do not determine a surface'."""
    from tuflexperf.cli import main

    def refused(args: list[str]) -> str:
        with pytest.raises(SystemExit) as done:
            main(args)
        assert done.value.code == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1, err
        return err

    assert "Invalid value for '--dask': empty" in refused(["check", "--samples", "50",
                                                           "--dask", ""])
    assert "--dask: empty address" in refused(["check", "--samples", "50", "--dask", "  "])
    long = refused(["check", "--set", "aircraft.mass_kg=1" + "x" * 5000])
    assert "not a number" in long and len(long) < 200
    manifest = ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml"
    tiny = tmp_path / "campaign.yaml"
    tiny.write_text(manifest.read_text().replace("fan_area_m2: 0.006793",
                                                 "fan_area_m2: 1.0e-300", 1))
    assert "fan_area_m2" in refused(["fit", str(tiny), "--out", str(tmp_path / "o.yaml")])
    table = tmp_path / "t.csv"
    rows = [f"E,{x},{v},{x}" for v in ("0", "10", "20", "3e7") for x in (0, 0.5, 1)]
    table.write_text("engine,throttle,airspeed_m_s,thrust_n\n" + "\n".join(rows) + "\n")
    assert "beyond the speed of sound" in refused(["fit", str(table), "--out",
                                                   str(tmp_path / "t.yaml")])


MISSION_FILE = str(ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml")


@pytest.mark.parametrize(("args", "said"), [
    (["mission", MISSION_FILE, "--csv", "-"], "--csv: '-' (stdout)"),
    (["mission", MISSION_FILE, "--csv", "--json"], "--csv: '--json' looks like an option"),
    (["sweep", "--vary", "aircraft.mass_kg=20:25:2", "--csv", "--plot"],
     "--csv: '--plot' looks like an option"),
    (["sweep", "--vary", "aircraft.mass_kg=20:25:2", "--plot", "-"], "--plot: '-' (stdout)"),
    (["export", "--out", "-"], "--out: '-' (stdout)"),
    (["export", "--out", "--json"], "--out: '--json' looks like an option"),
    (["report", "--out", "-"], "--out: '-' (stdout)"),
    (["fit", str(ROOT / "data/tuflex/campaign/campaign.yaml"), "--out", "--json"],
     "--out: '--json' looks like an option"),
])
def test_an_output_named_dash_or_like_an_option_is_refused(tmp_path, monkeypatch, capsys,
                                                           args, said):
    """`--csv --json` wrote a file named --json (read later by `--case --json`), `export
    --out -` a folder named -, with exit 0 (outside audit); fit already refused '-'."""
    from tuflexperf.cli import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as done:
        main(args)
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err, err
    assert list(tmp_path.iterdir()) == []


def test_small_leftovers_of_the_sixteenth_audit(tmp_path, capsys):
    """A mission and a case by position hinted the mission as the case; a propulsion file
    given to fit (sharing fan_area_m2 with a campaign) got "unknown key 'model' (and 6 more
    problems)" instead of what kind of file it is (outside audit)."""
    from tuflexperf.cli import main

    def refused(args: list[str]) -> str:
        with pytest.raises(SystemExit) as done:
            main(args)
        assert done.value.code == 2
        return capsys.readouterr().err

    case = str(ROOT / "requirements" / "tuflex.yaml")
    said = refused(["mission", MISSION_FILE, case])
    assert said.rstrip().endswith(f"give the case file with --case {case}")
    propulsion = str(ROOT / "data" / "tuflex" / "propulsion.yaml")
    said = refused(["fit", propulsion, "--out", str(tmp_path / "o.yaml")])
    assert "this is a propulsion file, not a campaign file" in said
    said = refused(["report", "--campaign", propulsion, "--out", str(tmp_path / "r")])
    assert "this is a propulsion file, not a campaign file" in said


def test_an_empty_value_or_a_gzipped_table_is_said_as_such(tmp_path, capsys):
    """``--case=`` became the path '.' ("is a directory"); a gzipped thrust table "cannot
    decode byte 0x8b", in fit and in report (outside audit)."""
    import gzip

    from tuflexperf.cli import main

    def refused(args: list[str]) -> str:
        with pytest.raises(SystemExit) as done:
            main(args)
        assert done.value.code == 2
        err = capsys.readouterr().err  # the report's progress lines, then one error line
        assert "Traceback" not in err
        assert [line.startswith("tuflexperf: error:") for line in err.splitlines()][-1:] == [True]
        return err.splitlines()[-1]

    assert "Invalid value for '--case': empty" in refused(["check", "--case="])
    assert "Invalid value for '--case': empty" in refused(["trim", "--case", ""])
    assert "an empty argument" in refused(["mission", ""])
    table = tmp_path / "table.csv.gz"
    table.write_bytes(gzip.compress(b"engine,throttle,airspeed_m_s,thrust_n\nE,0.5,0,10\n"))
    assert "table.csv.gz: gzip-compressed" in refused(
        ["fit", str(table), "--out", str(tmp_path / "p.yaml")])
    assert "table.csv.gz: gzip-compressed" in refused(
        ["report", "--campaign", str(table), "--out", str(tmp_path / "r")])
    assert not (tmp_path / "p.yaml").exists() and not (tmp_path / "r").exists()


def test_a_removed_working_directory_is_named(tmp_path):
    """fit without --out writes beside the working directory's paths: removed under it, the
    error said 'stdout: No such file or directory' (outside audit)."""
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    gone = tmp_path / "gone"
    gone.mkdir()
    done = subprocess.run(
        [sys.executable, "-m", "tuflexperf", "fit",
         str(ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml")],
        cwd=gone, preexec_fn=lambda: os.rmdir(gone), capture_output=True, text=True,
        timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 2, done.stderr
    assert done.stderr == ("tuflexperf: error: the working directory (removed while in use): "
                           "No such file or directory\n")


@pytest.mark.parametrize("line", ["exp_rate_per_ah: -50", "slope_v_per_ah: -5",
                                  "knee_v: -0.1", "exp_amplitude_v: -1"])
def test_a_pack_circuit_of_the_wrong_sign_names_its_key(tmp_path, line):
    """exp_rate_per_ah -50 (a voltage rising as e^{50 q}) "reached cut-off after 2.4e117 min"
    in a message that blamed capacity_ah (outside audit): the circuit's signs are bounded as
    the fit bounds them."""
    from tests.conftest import copy_shipped_case

    case = copy_shipped_case(tmp_path)
    battery = tmp_path / "data" / "tuflex" / "battery.yaml"
    key = line.split(":")[0]
    battery.write_text("\n".join(f"    {line}" if row.strip().startswith(f"{key}:") else row
                                 for row in battery.read_text().splitlines()) + "\n")
    result = runner.invoke(app, ["check", str(case)])
    assert result.exit_code == 2, result.stdout
    assert f"battery.yaml: fit.parameters.{key}: Input should be greater than" in result.stderr
    assert len(result.stderr.splitlines()) == 1


@pytest.mark.parametrize(("section", "path", "value", "said"), [
    ("aircraft", ["name"], "", "a name cannot be empty"),
    ("aircraft", ["name"], "TU-Flex \u202egnp.exe", "bidirectional text control"),
    ("propulsion", ["tested_airspeed_m_s"], [-30, 30], "tested_airspeed_m_s[0]: Input should be"),
])
def test_names_and_tested_range_that_mislead(tmp_path, section, path, value, said):
    """An empty aircraft name, a right-to-left override in a name (shown in another order
    than stored, in the exported C and XML) and a negative tested airspeed were accepted
    (outside audit)."""
    import copy

    from tests.conftest import MADE_UP_AIRCRAFT, MADE_UP_PROPULSION, write_case

    docs = {"aircraft": copy.deepcopy(MADE_UP_AIRCRAFT),
            "propulsion": copy.deepcopy(MADE_UP_PROPULSION)}
    target = docs[section]
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    case = write_case(tmp_path, aircraft=docs["aircraft"], propulsion=docs["propulsion"])
    result = runner.invoke(app, ["check", str(case)])
    assert result.exit_code == 2 and said in result.stderr, result.stderr
    assert len(result.stderr.splitlines()) == 1
