"""A take-off flies every airspeed from rest (or the catapult's release) to the arc's, and the
endurance flight its launch and climb as well: where those leave the thrust model's tested
range, the result says it is extrapolated, in the single case and the batch alike (SPEC 3).

An outside audit found a model tested at 15-30 m/s giving a take-off PASS with no note: only
the lift-off and the arc's speeds were looked at, not the roll from rest below them.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import copy_shipped_case
from tests.verification.test_batch_equals_deterministic import (
    _catapult_case,
    assert_same_extrapolation,
)
from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.study import Study
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import numeric_keys
from tuflexperf.models.thrust import outside_tested_range, outside_tested_span


def _tested_from(case_file, low: float, high: float = 30.0):
    propulsion = case_file.parent.parent / "data" / "tuflex" / "propulsion.yaml"
    text = propulsion.read_text()
    assert "tested_airspeed_m_s: [0, 30]" in text
    propulsion.write_text(text.replace("tested_airspeed_m_s: [0, 30]",
                                       f"tested_airspeed_m_s: [{low:g}, {high:g}]", 1))
    return load_case(case_file)


def _rows(case, sets):
    nominal = numeric_keys(case)
    keys = sorted({k for s in sets for k in s})
    return {k: np.array([s.get(k, nominal[k]) for s in sets]) for k in keys}


def test_the_span_is_outside_where_either_end_is() -> None:
    from tuflexperf.io.case import load_case as load

    propulsion = load().propulsion  # tested 0-30 m/s
    slowest = np.array([0.0, 0.0, 10.0, -1.0, 5.0])
    fastest = np.array([30.0, 31.0, 20.0, 20.0, 30.0 + 1e-10])
    assert outside_tested_span(propulsion, slowest, fastest).tolist() == [
        False, True, False, True, False]
    # one airspeed is the span from itself to itself
    speeds = np.linspace(-5.0, 40.0, 91)
    assert np.array_equal(outside_tested_range(propulsion, speeds),
                          outside_tested_span(propulsion, speeds, speeds))


def test_a_roll_from_rest_below_the_tested_range_is_said(tmp_path) -> None:
    case = _tested_from(copy_shipped_case(tmp_path), 15.0)
    study = Study(case)
    takeoff = study.takeoff()
    assert takeoff.extrapolated
    assert any("0.0-15.0 m/s are below the thrust model's tested airspeed range 15-30" in w
               for w in takeoff.warnings), takeoff.warnings
    endurance = study.endurance(case.requirements.endurance.throttle)
    # the cruise (27.6 m/s) is tested; the launch from rest is not
    assert 15.0 <= endurance.airspeed_m_s <= 30.0
    assert endurance.extrapolated
    assert any(w.startswith("the launch and climb fly 0.0-") for w in endurance.warnings)
    sets = [{}, {"aircraft.mass_kg": 30.0}, {"atmosphere.altitude_m": 1500.0}]
    result = BatchEvaluator(case).evaluate(_rows(case, sets))
    for row in range(len(sets)):
        said = assert_same_extrapolation(load_case(case.path) if row == 0 else
                                         _with(case, sets[row]), result, row)
        assert said and all(said)  # every requirement here flies below 15 m/s or beyond 30


def _with(case, values):
    from tuflexperf.io.dotted import with_values

    return with_values(case, values)


def test_within_the_tested_range_nothing_is_said(tmp_path) -> None:
    # tested from rest: the shipped case's take-off and endurance are not extrapolated
    case = load_case(copy_shipped_case(tmp_path))
    study = Study(case)
    assert not study.takeoff().extrapolated
    assert not study.endurance(case.requirements.endurance.throttle).extrapolated
    result = BatchEvaluator(case).evaluate()
    assert not result.extrapolated["takeoff_ground_roll"][0]
    assert not result.extrapolated["flight_endurance"][0]


@pytest.mark.parametrize(("low", "high", "launch", "flight"), [
    (0.0, 30.0, False, False),  # release 18 m/s, arc 16.7, climb 26.5, cruise 27.6: tested
    (17.0, 30.0, True, False),  # the arc flies 16.7 m/s, below 17
    (0.0, 17.9, True, True),  # the release at 18 m/s beyond 17.9 (and the cruise)
])
def test_a_catapult_flies_from_its_release(tmp_path, low, high, launch, flight) -> None:
    case = _catapult_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    propulsion.write_text(propulsion.read_text().replace(
        "tested_airspeed_m_s: [0, 30]", f"tested_airspeed_m_s: [{low:g}, {high:g}]", 1))
    case = load_case(case.path)
    study = Study(case)
    assert study.takeoff().extrapolated == launch
    # the endurance flight climbs and cruises from the release on (the mission integrates no
    # thrust at the release or the arc): 26.5-27.6 m/s
    endurance = study.endurance(case.requirements.endurance.throttle)
    assert endurance.extrapolated == flight
    sets = [{}, {"aircraft.launch_speed_m_s": 21.0}]
    result = BatchEvaluator(case).evaluate(_rows(case, sets))
    assert_same_extrapolation(case, result, 0)
    assert_same_extrapolation(_with(case, sets[1]), result, 1)
