"""The lack of fit's bound as a reading: a surface that misses its holds is judged on the
thrust lowered by z_p model_form_rms_n (issue 43 items 1 and 4)."""

from __future__ import annotations

from statistics import NormalDist

import pytest
import yaml

from tests.conftest import copy_shipped_case
from tuflexperf.analysis.requirements import check_case
from tuflexperf.io.case import load_case

RMS_N = 0.4


def _with_lack_of_fit(folder, rms_n: float, shift_p00_n: float = 0.0):
    """The shipped case whose engines carry a lack-of-fit block (model-form ``rms_n`` N),
    their p00 moved by ``shift_p00_n`` [N]."""
    case = copy_shipped_case(folder)
    path = folder / "data" / "tuflex" / "propulsion.yaml"
    data = yaml.safe_load(path.read_text())
    for engine in data["engines"]:
        engine["coefficients"]["p00"] += shift_p00_n
        if rms_n:
            engine["lack_of_fit"] = {
                "f_statistic": 250.0, "p_value": 1e-30, "model_form_rms_n": rms_n,
                "pure_error_rms_n": 0.015, "dof_lack_of_fit": 64, "dof_pure_error": 140}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return case


def test_the_bound_is_the_thrust_lowered_by_z_times_the_model_form_error(tmp_path) -> None:
    z = NormalDist().inv_cdf(0.9)
    judged = {v.name: v for v in check_case(load_case(_with_lack_of_fit(tmp_path / "a",
                                                                         RMS_N)))}
    # independently: the same case with every engine's p00 lowered by hand, no block
    lowered = {v.name: v for v in check_case(load_case(
        _with_lack_of_fit(tmp_path / "b", 0.0, -z * RMS_N)))}
    roll = judged["takeoff_ground_roll"]
    keys = [r.key for r in roll.readings]
    assert keys[0] == "nominal" and "model_form_bound" in keys
    bound = next(r for r in roll.readings if r.key == "model_form_bound")
    hand = lowered["takeoff_ground_roll"]
    assert bound.value == pytest.approx(hand.readings[0].value if hand.readings
                                        else hand.value, rel=1e-9)
    assert bound.value > roll.readings[0].value  # less thrust, a longer roll
    assert "lack_of_fit.model_form_rms_n" in roll.reason or roll.verdict == "PASS"


def test_a_margin_inside_the_model_form_error_is_unproven(tmp_path) -> None:
    case = _with_lack_of_fit(tmp_path, RMS_N)
    judged = {v.name: v for v in check_case(load_case(case))}
    roll = judged["takeoff_ground_roll"]
    nominal = roll.readings[0].value
    bound = next(r.value for r in roll.readings if r.key == "model_form_bound")
    limit = 0.5 * (nominal + bound)  # met as fitted, not at the bound
    case.write_text(case.read_text().replace("max_ground_roll_m: 60",
                                             f"max_ground_roll_m: {limit!r}"))
    roll = {v.name: v for v in check_case(load_case(case))}["takeoff_ground_roll"]
    assert roll.verdict == "UNPROVEN"
    assert "model_form_rms_n" in roll.reason and "lack-of-fit" in roll.settle


def test_a_surface_that_fits_its_holds_has_no_such_reading(tmp_path) -> None:
    judged = check_case(load_case(_with_lack_of_fit(tmp_path, 0.0)))
    assert all(r.key != "model_form_bound" for v in judged for r in v.readings)
