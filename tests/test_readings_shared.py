"""The readings of disputed evidence share what they do not change (issue 42, speed).

A batch evaluated on the measured power reads the nominal's thrust-only results
(:class:`tuflexperf.analysis.batch_model.SharedRows`) and gives the numbers it gives alone;
the single case does not fly the extrapolation bound for a requirement flown inside the
tested airspeeds, where its value is the nominal's.
"""

from __future__ import annotations

import numpy as np
import pytest

from tuflexperf.analysis.batch_readings import readings_evaluator
from tuflexperf.analysis.evaluators import evaluator_for
from tuflexperf.analysis.evidence import case_readings
from tuflexperf.analysis.readings import thrust_identity
from tuflexperf.analysis.requirements import study_verdicts
from tuflexperf.analysis.study import Study
from tuflexperf.io.case import load_case


@pytest.fixture(scope="module")
def case():
    return load_case()


@pytest.fixture(scope="module")
def rows():
    rng = np.random.default_rng(7)
    size = 64
    return {"aircraft.mass_kg": rng.normal(22.17, 0.8, size),
            "aircraft.cd0": rng.normal(0.020, 0.002, size)}, size


def _reading(case, key):
    return next(r for r in case_readings(case) if r.key == key)


def test_the_thrust_identity_leaves_out_the_power_and_the_dead_engines_drag(case) -> None:
    live, dead = thrust_identity(case)
    power = thrust_identity(_reading(case, "measured_power").case)
    windmilling = thrust_identity(_reading(case, "windmilling_model_drag").case)
    bound = thrust_identity(_reading(case, "extrapolation_bound").case)
    assert power == (live, dead)
    assert windmilling[0] == live and windmilling[1] != dead
    assert bound[0] != live and bound[1] != dead


def test_each_reading_gives_what_it_gives_on_its_own(case, rows) -> None:
    values, size = rows
    result = readings_evaluator(case).evaluate(values, size)
    assert set(result.reading_values) >= {"nominal", "measured_power",
                                          "windmilling_model_drag"}
    for reading in case_readings(case):
        theirs = result.reading_values.get(reading.key, {})
        if not theirs:
            continue
        alone = evaluator_for(reading.case, frozenset(reading.affects)).evaluate(values, size)
        for name, value in theirs.items():
            np.testing.assert_array_equal(value, alone.values[name], err_msg=name)


def test_the_power_reading_takes_the_nominal_thrust_results(case, rows) -> None:
    values, size = rows
    shared: dict = {}
    nominal = evaluator_for(case).evaluate(values, size, shared=shared)
    made = set(shared)
    power = _reading(case, "measured_power")
    other = evaluator_for(power.case).evaluate(values, size, shared=shared)
    added = {key[1] for key in set(shared) - made}
    # the roll, trim, OEI and every thrust the endurance asks for (its level-flight airspeed
    # and the launch's airspeeds whole) were the nominal's
    taken = {"ground_roll", "trim", "oei", "thrust", "roll_history", "force_range",
             "level_airspeed", "launch_path"}
    assert {"level_airspeed", "launch_path"} <= {key[1] for key in made}
    assert not added & taken
    np.testing.assert_array_equal(other.values["trim_throttle_max"],
                                  nominal.values["trim_throttle_max"])
    assert not np.allclose(other.values["flight_endurance"],
                           nominal.values["flight_endurance"])


def test_the_bound_is_flown_only_where_the_nominal_flies_beyond_the_tested_airspeeds(
        case) -> None:
    study = Study(case)
    study_verdicts(study)
    bound = _reading(case, "extrapolation_bound")
    throttle = case.requirements.endurance.throttle
    assert not study.endurance(throttle).extrapolated and study.trim().extrapolated
    flown = study.on_reading(bound).solved
    assert "trim" in flown and ("endurance", float(throttle)) not in flown
    # its value there is the nominal's: flown anyway, the same number
    again = Study(bound.case).endurance(throttle).flight_endurance_min
    assert again == pytest.approx(study.endurance(throttle).flight_endurance_min, rel=1e-9)


def test_the_power_reading_flies_the_nominal_mission_functions(case) -> None:
    from tuflexperf.analysis import endurance, mission_equations
    from tuflexperf.analysis.endurance import endurance_model
    from tuflexperf.analysis.mission_equations import CORRECTION_SIZE

    # from empty caches: a model kept from an earlier test may hold step functions the
    # bounded STEP_FUNCTIONS has since let go (the sharing is within one process's run)
    endurance._model_cache._items.clear()
    mission_equations.STEP_FUNCTIONS._items.clear()
    power = _reading(case, "measured_power")
    nominal = endurance_model(case).mission
    theirs = endurance_model(power.case).mission
    assert theirs is not nominal and theirs._steps
    # the same step functions: the correction is a parameter, the nominal's ratio 1
    for key, function in theirs._steps.items():
        assert function is nominal._steps[key]
    law = power.case.propulsion.engines[0].power_correction
    n = len(case.propulsion.engines)
    first = nominal.n_par - 1 - CORRECTION_SIZE * (n + 1)
    assert list(theirs.par[first:first + 3, 0]) == [law.constant, law.per_throttle,
                                                    law.per_airspeed_s_m]
    assert list(nominal.par[first:first + 3, 0]) == [1.0, 0.0, 0.0]
