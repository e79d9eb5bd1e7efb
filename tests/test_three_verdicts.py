"""Three verdicts (issue 43): PASS, FAIL and UNPROVEN, judged on every reading of disputed
evidence, and the same verdict from every command for the same data.

The readings' values are computed here independently, from the analyses on a case built by
hand (the windmilling coefficient dropped, the thrust beyond the tested airspeeds lowered),
and each limit is set between or beyond them, so every test fails if the registry judges
one reading only.
"""

from __future__ import annotations

import dataclasses
import json
from statistics import NormalDist

import numpy as np
import pytest

from tests.conftest import SHIPPED_CASE, copy_shipped_case, tuflexperf
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.io.case import load_case
from tuflexperf.models.thrust import engine_thrust_n


def _shipped():
    return load_case(SHIPPED_CASE)


def _without_coefficients(case):
    """The case whose dead engine drags its own model's throttle-0 drag (by hand)."""
    engines = tuple(dataclasses.replace(e, windmilling_drag_coefficient=None)
                    for e in case.propulsion.engines)
    return dataclasses.replace(case, propulsion=dataclasses.replace(case.propulsion,
                                                                    engines=engines))


def _lowered(case, p: float):
    """The case whose thrust beyond the tested airspeeds is lowered by z_p sd, the sd growing
    in proportion to the distance: extrapolation_sd_n per left-out step, the tested span / 12
    where the file names no distance (by hand)."""
    z = NormalDist().inv_cdf(p)
    low, high = case.propulsion.tested_airspeed_m_s
    step = (high - low) / 12.0
    engines = tuple(dataclasses.replace(e, extrapolation_offset=(
        low, high, -z * e.extrapolation_sd_n / step)) for e in case.propulsion.engines)
    return dataclasses.replace(case, propulsion=dataclasses.replace(case.propulsion,
                                                                    engines=engines))


@pytest.fixture(scope="module")
def oei_values() -> tuple[float, float]:
    """OEI's least throttle on the coefficient's drag and on the model's throttle-0 drag."""
    case = _shipped()
    return (solve_oei(case).critical.min_throttle,
            solve_oei(_without_coefficients(case)).critical.min_throttle)


@pytest.fixture(scope="module")
def trim_values() -> tuple[float, float]:
    """Trim's highest throttle on the fitted thrust and at its 60 % bound beyond 30 m/s (at the
    default 90 % the bound at 45 m/s is not attainable)."""
    case = _shipped()
    return solve_trim(case).max_throttle, solve_trim(_lowered(case, 0.6)).max_throttle


def _check(*sets: str) -> tuple[int, dict, str]:
    flags = [a for s in sets for a in ("--set", s)]
    ran = tuflexperf("check", "--json", *flags)
    text = tuflexperf("check", *flags)
    assert ran.returncode == text.returncode
    return ran.returncode, json.loads(ran.stdout), text.stdout


def _result(data: dict, name: str) -> dict:
    return next(r for r in data["results"] if r["name"] == name)


def test_disagreeing_readings_make_unproven_with_both_values(oei_values) -> None:
    nominal, model = oei_values
    assert nominal < model  # the model's drag is the larger (7x at 30 m/s)
    limit = 0.5 * (nominal + model)
    code, data, text = _check(f"requirements.oei.max_throttle={limit}")
    oei = _result(data, "oei_min_throttle")
    assert oei["verdict"] == "UNPROVEN" and oei["passed"] is False
    assert [r["key"] for r in oei["readings"]] == ["nominal", "windmilling_model_drag"]
    assert oei["readings"][0]["value"] == pytest.approx(nominal, rel=1e-9)
    assert oei["readings"][1]["value"] == pytest.approx(model, rel=1e-9)
    assert [r["passed"] for r in oei["readings"]] == [True, False]
    # the shown value is the worse reading's
    assert oei["value"] == pytest.approx(model, rel=1e-9) and oei["margin"] < 0
    # the reason names both pieces of evidence with their values, the file and the key
    assert f"{nominal:.4g}" in oei["reason"] and f"{model:.4g}" in oei["reason"]
    assert "windmilling_drag_coefficient" in oei["reason"] and "propulsion.yaml" in oei["reason"]
    assert "thrust model at throttle 0" in oei["reason"]
    assert "windmilling (throttle-0) hold of EDF1 at 30 m/s" in oei["settle"]
    assert code == 1 and data["verdict"] == "UNPROVEN" and data["passed"] is False
    assert "overall: UNPROVEN" in text and "to settle: a windmilling" in text
    assert "\n" not in oei["reason"]  # one line


def test_both_readings_met_pass_and_both_not_met_fail(oei_values) -> None:
    nominal, model = oei_values
    code, data, text = _check()  # the shipped limit 1.0 is above both
    oei = _result(data, "oei_min_throttle")
    assert oei["verdict"] == "PASS" and oei["passed"] is True
    assert [r["passed"] for r in oei["readings"]] == [True, True]
    assert oei["value"] == pytest.approx(max(nominal, model), rel=1e-9)
    assert oei["settle"] == ""
    below = 0.9 * nominal
    code, data, text = _check(f"requirements.oei.max_throttle={below}")
    oei = _result(data, "oei_min_throttle")
    assert oei["verdict"] == "FAIL" and oei["passed"] is False
    assert [r["passed"] for r in oei["readings"]] == [False, False]
    assert code == 1 and data["verdict"] == "FAIL" and "overall: FAIL" in text


def test_a_fail_outranks_an_unproven_and_the_shipped_case_is_unproven(oei_values) -> None:
    nominal, model = oei_values
    code, data, _ = _check(f"requirements.oei.max_throttle={0.5 * (nominal + model)}",
                           "requirements.takeoff.max_ground_roll_m=10")
    assert code == 1 and data["verdict"] == "FAIL"
    # the shipped endurance: met on the power model, not on the discharge runs' power
    code, data, text = _check()
    assert code == 1 and data["verdict"] == "UNPROVEN" and "overall: UNPROVEN" in text
    endurance = _result(data, "flight_endurance")
    assert endurance["verdict"] == "UNPROVEN"
    assert [r["key"] for r in endurance["readings"]] == ["nominal", "measured_power"]
    on_model, on_runs = (r["value"] for r in endurance["readings"])
    assert on_runs < endurance["limit"] <= on_model and endurance["value"] == on_runs
    assert endurance["settle"].startswith("a discharge run at")
    verdicts = {r["name"]: r["verdict"] for r in data["results"]}
    # trim at 45 m/s is not attainable at the thrust's 90 % bound there, 15 m/s beyond 30
    assert verdicts == {"takeoff_ground_roll": "PASS", "trim_throttle_max": "UNPROVEN",
                        "oei_min_throttle": "PASS", "flight_endurance": "UNPROVEN"}
    trim = _result(data, "trim_throttle_max")
    assert trim["readings"][1]["value"] is None and "not attainable" in trim["reason"]
    # a limit both readings meet passes, exit 0 (trim: asked at P(met) >= 0.6)
    code, data, text = _check(f"requirements.endurance.min_flight_time_min={0.99 * on_runs}",
                              "requirements.extrapolation.required_probability=0.6")
    assert code == 0 and data["verdict"] == "PASS" and "overall: PASS" in text
    assert all(r["verdict"] == "PASS" for r in data["results"])


def test_the_extrapolation_bound_makes_unproven_below_the_required_probability(
        trim_values) -> None:
    nominal, bound = trim_values
    assert nominal < bound < 1.0  # lower thrust beyond 30 m/s: more throttle at 45 m/s
    limit = 0.5 * (nominal + bound)
    code, data, _ = _check(f"requirements.envelope.max_trim_throttle={limit}",
                           "requirements.extrapolation.required_probability=0.6")
    trim = _result(data, "trim_throttle_max")
    assert trim["verdict"] == "UNPROVEN" and code == 1
    assert trim["readings"][1]["key"] == "extrapolation_bound"
    assert trim["readings"][1]["value"] == pytest.approx(bound, rel=1e-9)
    assert trim["settle"] == "tunnel points above 30 m/s"
    assert "extrapolation_sd_n" in trim["reason"] and "P(met) >= 0.6" in trim["reason"]
    # a lower required probability asks a smaller bound: settable, and it moves the reading
    code, data, _ = _check(f"requirements.envelope.max_trim_throttle={limit}",
                           "requirements.extrapolation.required_probability=0.55")
    trim = _result(data, "trim_throttle_max")
    expected = solve_trim(_lowered(_shipped(), 0.55)).max_throttle
    assert nominal < expected < bound
    assert trim["readings"][1]["value"] == pytest.approx(expected, rel=1e-9)
    assert trim["verdict"] == ("PASS" if expected <= limit else "UNPROVEN")


def test_a_requirement_flown_inside_the_tested_airspeeds_has_no_extrapolation_reading() -> None:
    _, data, _ = _check()
    # the ground roll (to 16.6 m/s) and the endurance (27.6 m/s) fly inside 0-30 m/s
    for name in ("takeoff_ground_roll", "flight_endurance"):
        keys = [r["key"] for r in _result(data, name).get("readings", [])]
        assert "extrapolation_bound" not in keys, name


def test_the_offset_lives_in_the_thrust_kernel_for_numpy_and_casadi() -> None:
    import casadi as ca

    engine = _shipped().propulsion.engines[0]
    moved = dataclasses.replace(engine, extrapolation_offset=(0.0, 30.0, -1.5))
    # -1.5 N per m/s beyond the tested range, 0 inside it (continuous at its edge)
    speeds = np.array([0.0, 15.0, 30.0, 30.25, 30.5, 45.0])
    delta = (np.asarray(engine_thrust_n(moved, 0.7, speeds, 0.9))
             - np.asarray(engine_thrust_n(engine, 0.7, speeds, 0.9)))
    assert delta == pytest.approx([0.0, 0.0, 0.0, -0.3375, -0.675, -20.25], abs=1e-12)
    v = ca.SX.sym("v")
    f = ca.Function("f", [v], [engine_thrust_n(moved, 0.7, v, 0.9)
                               - engine_thrust_n(engine, 0.7, v, 0.9)])
    assert [float(f(s)) for s in speeds] == pytest.approx(list(delta), abs=1e-12)


def test_every_command_gives_the_same_verdict_for_the_same_data(oei_values,
                                                                trim_values) -> None:
    oei_limit = 0.5 * sum(oei_values)
    trim_limit = 0.5 * sum(trim_values)
    sets = ["--set", f"requirements.oei.max_throttle={oei_limit}",
            "--set", f"requirements.envelope.max_trim_throttle={trim_limit}",
            "--set", "requirements.extrapolation.required_probability=0.6"]
    check = json.loads(tuflexperf("check", "--json", *sets).stdout)
    judged = {r["name"]: (r["verdict"], r["value"]) for r in check["results"]}
    assert judged["oei_min_throttle"][0] == judged["trim_throttle_max"][0] == "UNPROVEN"
    # sweep at one point (the batch's own physics, on every reading too)
    swept = tuflexperf("sweep", "--json", "--vary",
                       f"requirements.oei.max_throttle={oei_limit}:{oei_limit}:1",
                       "--set", f"requirements.envelope.max_trim_throttle={trim_limit}",
                       "--set", "requirements.extrapolation.required_probability=0.6")
    row = json.loads(swept.stdout)["rows"][0]
    for name, (verdict, value) in judged.items():
        assert row[name]["verdict"] == verdict, name
        assert row[name]["value"] == pytest.approx(value, rel=1e-6), name
    # margins: check's verdicts, and the limit values on the worse reading
    margins = json.loads(tuflexperf("margins", "--json", *sets).stdout)
    assert {v["name"]: v["verdict"] for v in margins["verdicts"]} == {
        k: v for k, (v, _) in judged.items()}
    assert margins["verdict"] == "UNPROVEN"
    # the single analyses' commands
    trim = tuflexperf("trim", "--json", *sets)
    oei = tuflexperf("oei", "--json", *sets)
    assert trim.returncode == oei.returncode == 1
    assert json.loads(trim.stdout)["verdict"] == json.loads(oei.stdout)["verdict"] == "UNPROVEN"


def test_a_mission_losing_an_engine_is_judged_on_both_drags(tmp_path) -> None:
    mission = SHIPPED_CASE.parent.parent / "data" / "tuflex" / "missions" / "test_flight.yaml"
    case = tmp_path / "case.yaml"
    data = SHIPPED_CASE.parent.parent / "data" / "tuflex"
    case.write_text(f"name: m\naircraft: {data / 'aircraft.yaml'}\n"
                    f"propulsion: {data / 'propulsion.yaml'}\nbattery: {data / 'battery.yaml'}\n"
                    f"requirements:\n  mission: {{file: {mission}, "
                    "min_landing_charge_fraction: 0.2}\n")
    flown = json.loads(tuflexperf("mission", "--case", str(case), "--json").stdout)
    landing = flown["results"][0]
    values = [r["value"] for r in landing["readings"]]
    assert values[1] < values[0]  # the larger drag lands with less
    limit = 0.5 * (values[0] + values[1])
    case.write_text(case.read_text().replace("0.2}", f"{limit}}}"))
    checked = tuflexperf("check", str(case), "--json")
    mission = tuflexperf("mission", "--case", str(case), "--json")
    assert checked.returncode == mission.returncode == 1
    assert (json.loads(checked.stdout)["results"][0]["verdict"]
            == json.loads(mission.stdout)["verdict"] == "UNPROVEN")
    assert "UNPROVEN" in tuflexperf("mission", "--case", str(case)).stdout


def test_samples_carry_the_verdict_and_each_readings_probability(oei_values) -> None:
    limit = 0.5 * sum(oei_values)
    ran = tuflexperf("check", "--json", "--samples", "300", "--set",
                     f"requirements.oei.max_throttle={limit}")
    data = json.loads(ran.stdout)
    oei = _result(data, "oei_min_throttle")
    assert oei["nominal_verdict"] == "UNPROVEN" and oei["verdict"] != "PASS"
    keys = [r["key"] for r in oei["probability_readings"]]
    assert keys == ["nominal", "windmilling_model_drag"]
    # the shown P(met) is the worse reading's
    assert oei["probability"] == min(r["probability"] for r in oei["probability_readings"])
    assert ran.returncode == 1 and data["verdict"] in ("UNPROVEN", "FAIL")


def test_unproven_has_its_own_colour_on_a_terminal_only(monkeypatch) -> None:
    import sys

    from tuflexperf.cli import render

    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setenv("TERM", "xterm")
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    words = {w: render.verdict_word(w) for w in ("PASS", "FAIL", "UNPROVEN")}
    assert all("\x1b[" in shown and w in shown for w, shown in words.items())
    assert len(set(words.values())) == 3 and "33" in words["UNPROVEN"]  # yellow/amber
    monkeypatch.setenv("NO_COLOR", "1")
    assert render.verdict_word("UNPROVEN") == "UNPROVEN"
    monkeypatch.delenv("NO_COLOR")
    monkeypatch.setattr(sys.stdout, "isatty", lambda: False)
    assert render.verdict_word("UNPROVEN") == "UNPROVEN"


def test_an_endurance_ending_at_the_cutoff_before_the_reserve_fails_everywhere() -> None:
    cutoff = "battery.cutoff_voltage_per_cell_v=3.75"
    code, data, _ = _check(cutoff)
    endurance = _result(data, "flight_endurance")
    assert endurance["verdict"] == "FAIL" and endurance["value"] is None
    assert "cut-off" in endurance["reason"] and "reserve" in endurance["reason"]
    assert endurance["time_to_cutoff_min"] > endurance["limit"]  # long enough, yet no reserve
    swept = json.loads(tuflexperf("sweep", "--json", "--vary",
                                  f"{cutoff.split('=')[0]}=3.75:3.75:1").stdout)
    assert swept["rows"][0]["flight_endurance"]["verdict"] == "FAIL"
    assert tuflexperf("endurance", "--throttle", "0.5", "--set", cutoff).returncode == 1


def test_the_required_probability_is_one_number_per_run() -> None:
    varied = tuflexperf("sweep", "--vary",
                        "requirements.extrapolation.required_probability=0.8:0.9:2")
    assert varied.returncode == 2 and "cannot be varied" in varied.stderr


def test_a_catapult_launch_adds_its_kinetic_energy_to_the_missions(tmp_path) -> None:
    case_file = copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    aircraft.write_text(aircraft.read_text().replace(
        "takeoff:", "launch: catapult\nlaunch_speed_m_s: 18\nlaunch_energy_j: 12000\ntakeoff:",
        1))
    case_file.write_text(case_file.read_text().replace(
        "  takeoff: {max_ground_roll_m: 60}\n", ""))
    mission = tmp_path / "data" / "tuflex" / "missions" / "test_flight.yaml"
    flown = json.loads(tuflexperf("mission", str(mission), "--case", str(case_file),
                                  "--json").stdout)
    case = load_case(case_file)
    from tuflexperf.models.aircraft import true_airspeed_m_s

    release = float(true_airspeed_m_s(18.0, case.density_kg_m3))
    kinetic_wh = 0.5 * case.aircraft.mass_kg * release ** 2 / 3600.0
    assert flown["launch_kinetic_energy_wh"] == pytest.approx(kinetic_wh, rel=1e-12)
    packs = sum(s["energy_wh"] for s in flown["segments"])
    assert flown["energy_wh"] == pytest.approx(packs + kinetic_wh, rel=1e-12)


def test_the_climb_gradient_is_labelled_as_the_sine_of_the_climb_angle() -> None:
    text = tuflexperf("performance").stdout
    assert "max climb gradient sin(gamma)" in text and "OEI max climb sin(gamma)" in text
    assert "(sin(gamma) " in tuflexperf("takeoff").stdout


def test_the_reports_first_page_shows_unproven_in_amber_with_its_reason(oei_values) -> None:
    from tuflexperf.analysis.requirements import check_case
    from tuflexperf.io.dotted import with_values
    from tuflexperf.report.first_page import CAVEAT_COLOUR, headline, verdict_lines

    limit = 0.5 * sum(oei_values)
    verdicts = check_case(with_values(_shipped(), {"requirements.oei.max_throttle": limit}))
    lines = verdict_lines(verdicts, 120)
    words = [(seg.text, seg.colour) for line in lines for seg in line]
    assert ("UNPROVEN", CAVEAT_COLOUR) in words
    said = " ".join(text for text, colour in words if colour == CAVEAT_COLOUR)
    assert "UNPROVEN: oei_min_throttle" in said and "to settle: a windmilling" in said
    head = " ".join(seg.text for line in headline(verdicts, 0) for seg in line)
    unproven = sum(v.verdict == "UNPROVEN" for v in verdicts)
    assert unproven >= 1 and f"{unproven} OF 4 REQUIREMENTS NOT SHOWN MET" in head
