"""The review's views (issue 47 item 4) against the analyses they compose: the envelope at
the case's altitude is the point performance's level-speed range, the mass trade at the
case's mass is the best endurance, the height profile ends where the take-off says."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tuflexperf.analysis.study import Study
from tuflexperf.io.case import load_case


@pytest.fixture(scope="module")
def study():
    return Study(load_case(None))


def test_the_envelope_at_the_case_altitude_is_the_level_speed_range(study):
    perf = study.performance()
    env = study.flight_envelope()
    assert env.altitude_m[0] == pytest.approx(study.case.atmosphere.altitude_m)
    assert env.low_m_s[0, 0] == pytest.approx(perf.min_level_speed_m_s, abs=0.2)
    assert env.high_m_s[0, 0] == pytest.approx(perf.max_level_speed_m_s, abs=0.2)
    oei_max = perf.oei_max_level_speed_m_s
    assert np.nanmin(env.high_m_s[1:, 0]) == pytest.approx(oei_max, abs=0.2)
    grid = env.altitude_m[1] - env.altitude_m[0]
    assert env.ceiling_m[0] == pytest.approx(perf.absolute_ceiling_m, abs=grid)
    assert all(c < env.ceiling_m[0] for c in env.ceiling_m[1:])  # an engine out is lower
    assert np.all(np.isnan(env.low_m_s[0, env.altitude_m > env.ceiling_m[0]]))  # none above


def test_the_mass_trade_at_the_case_mass_is_the_best_endurance(study):
    sweep = study.mass_sweep()
    best = study.best_endurance()
    at = float(np.interp(sweep.nominal_mass_kg, sweep.mass_kg, sweep.best_endurance_min))
    # a refined throttle grid of the batch against IPOPT's optimum of the single case
    assert at == pytest.approx(best.endurance.flight_endurance_min, rel=0.005)
    assert np.all(np.diff(sweep.best_endurance_min) < 0)  # heavier flies shorter
    assert np.all(np.diff(sweep.best_range_km) < 0)


def test_the_mass_trade_at_the_requirement_throttle_is_the_batch_verdict_value(study):
    from tuflexperf.analysis.requirements import study_verdicts

    sweep = study.mass_sweep()
    throttle = study.case.requirements.endurance.throttle
    k = int(np.argmin(np.abs(sweep.throttle - throttle)))
    assert sweep.throttle[k] == pytest.approx(throttle)
    # the mass trade flies the case as given: the verdict's nominal reading (the first)
    verdict = next(v for v in study_verdicts(study) if v.name == "flight_endurance")
    value = verdict.readings[0].value if verdict.readings else verdict.value
    at = float(np.interp(sweep.nominal_mass_kg, sweep.mass_kg, sweep.endurance_min[:, k]))
    assert at == pytest.approx(value, rel=0.01)


def test_the_height_profile_ends_at_the_obstacle(study):
    from tuflexperf.analysis.review_views import takeoff_height_profile

    result = study.takeoff()
    profile = takeoff_height_profile(result)
    assert profile.distance_m[-1] == pytest.approx(result.distance_to_obstacle_m)
    assert profile.height_m[-1] == pytest.approx(result.obstacle_height_m)
    on_ground = profile.distance_m <= result.ground_roll_m
    assert np.all(profile.height_m[on_ground] == 0.0)
    assert np.all(np.diff(profile.height_m) >= 0) and np.all(np.diff(profile.distance_m) >= 0)
    arc = (profile.distance_m > profile.liftoff_m) & (profile.distance_m <= profile.arc_end_m)
    assert profile.height_m[arc].max() == pytest.approx(result.transition_height_m)


def test_a_heavy_case_has_a_smaller_envelope():
    heavy = load_case(None)
    heavy = dataclasses.replace(heavy, aircraft=dataclasses.replace(heavy.aircraft,
                                                                    mass_kg=30.0))
    light, heavier = Study(load_case(None)).flight_envelope(), Study(heavy).flight_envelope()
    assert heavier.ceiling_m[0] < light.ceiling_m[0]
    assert np.nanmin(heavier.low_m_s[0]) > np.nanmin(light.low_m_s[0])
