"""Regression pins of the shipped TU-Flex thrust model (SPEC 6), tolerances stated.

Pins, not validations (issue 9): the full-throttle thrust is the paper's measurement that
the shipped polynomial was derived from, so it is reproduced by construction; the shape
checks and the all-PASS verdict guard the shipped files against regressions. The
performance results the reconstruction was fitted to (55.5 m, 41 %, 56 %, 10 and 15 min)
are pinned in test_reconstruction_pins.py.
"""

from __future__ import annotations

import pytest

from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.io.case import load_case
from tuflexperf.models.thrust import engine_thrust_n

PUBLISHED_FULL_THROTTLE_N = {  # paper section 4: 0, 30, 40 m/s
    "EDF1": (55.12, 40.02, 35.26),
    "EDF2": (55.41, 41.76, 37.76),
}


@pytest.fixture(scope="module")
def case():
    return load_case()


def test_full_throttle_thrust_within_0_1_n(case):
    for engine in case.propulsion.engines:
        for v, published in zip(
            (0.0, 30.0, 40.0), PUBLISHED_FULL_THROTTLE_N[engine.name], strict=True
        ):
            assert float(engine_thrust_n(engine, 1.0, v)) == pytest.approx(published, abs=0.1)


def test_thrust_model_is_physical(case):
    for engine in case.propulsion.engines:
        assert abs(float(engine_thrust_n(engine, 0.0, 0.0))) < 1.0  # about zero at idle and rest
        for x in (0.0, 0.3, 0.6, 1.0):  # thrust falls with airspeed over the envelope
            t = [float(engine_thrust_n(engine, x, v)) for v in range(0, 46)]
            assert all(b < a for a, b in zip(t, t[1:], strict=False))
        assert float(engine_thrust_n(engine, 0.1, 40.0)) < 0  # drag at low throttle, high speed


def test_trim_beyond_30_m_s_is_flagged_as_extrapolated(case):
    result = solve_trim(case)
    assert result.extrapolated
    assert any("extrapolated" in w for w in result.warnings)


def test_every_requirement_met_but_the_endurance_the_runs_dispute_and_the_extrapolated_trim(
        case):
    verdicts = {v.name: v for v in check_case(case)}
    assert {"takeoff_ground_roll", "trim_throttle_max", "oei_min_throttle"} <= set(verdicts)
    # the discharge runs measured 25 % more power than the model: 14.0 min against 15
    assert verdicts.pop("flight_endurance").verdict == "UNPROVEN"
    # trim at 45 m/s, 15 m/s beyond the tested 30: not attainable at the thrust's 90 % bound
    trim = verdicts.pop("trim_throttle_max")
    assert trim.verdict == "UNPROVEN" and trim.readings[0].passed and trim.value is None
    assert all(v.verdict == "PASS" for v in verdicts.values())
