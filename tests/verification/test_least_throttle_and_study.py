"""One solver for the least level-flight throttle, and one Study per case (issue 9).

- The closed-form least throttle (three evaluations of a quadratic excess, the least root
  in [0, 1]) equals an independent root-find: a dense scan for the first sign change, then
  ``scipy.optimize.brentq``, on made-up engines whose excess is non-monotonic in throttle.
- A Study solves each analysis once: the report's analyses and the verdicts share results.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from tuflexperf.analysis.level_flight import least_throttle_solver
from tuflexperf.analysis.requirements import study_verdicts
from tuflexperf.analysis.study import Study
from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values


def _independent_least_root(excess, v: float) -> float:
    grid = np.linspace(0.0, 1.0, 20001)
    values = np.array([excess(x, v) for x in grid])
    if values[0] >= 0:
        return 0.0
    above = np.nonzero(values >= 0)[0]
    if above.size == 0:
        return float("nan")
    k = above[0]
    return brentq(lambda x: excess(x, v), grid[k - 1], grid[k], xtol=1e-15)


@pytest.mark.parametrize("seed", range(6))
def test_closed_form_least_throttle_equals_independent_root_find(seed: int) -> None:
    rng = np.random.default_rng(seed)
    p20 = rng.uniform(-60.0, 60.0)  # concave or convex in throttle: two roots possible
    p10, p11 = rng.uniform(20.0, 90.0), rng.uniform(-0.6, 0.1)
    p00, p01, p02 = rng.uniform(-2.0, 1.0), rng.uniform(-0.3, 0.0), rng.uniform(-0.004, 0.002)
    k_drag, c_drag = rng.uniform(0.01, 0.05), rng.uniform(1.0, 20.0)

    def excess(x, v):
        thrust = p00 + p10 * x + p01 * v + p20 * x * x + p11 * x * v + p02 * v * v
        return thrust - (k_drag * v * v + c_drag * 100.0 / (v * v))  # parasite + induced

    speeds = np.linspace(10.0, 45.0, 36)
    ours = least_throttle_solver(excess)(speeds)
    reference = np.array([_independent_least_root(excess, float(v)) for v in speeds])
    assert np.array_equal(np.isnan(ours), np.isnan(reference))
    finite = np.isfinite(reference)
    assert np.max(np.abs(ours[finite] - reference[finite]), initial=0.0) < 1e-9


def test_study_solves_each_analysis_once_and_shares_results() -> None:
    from tuflexperf.report.data import run_analyses

    study = Study(load_case(None))
    verdicts = study_verdicts(study)
    analyses = run_analyses(study)
    assert analyses.verdicts is verdicts
    assert analyses.takeoff is study.takeoff()
    assert analyses.trim is study.trim()
    requirement = study.case.requirements.endurance
    assert analyses.endurance_at_requirement is study.endurance(requirement.throttle)
    assert len(study.solved) == len(set(study.solved))  # nothing solved twice


def test_study_keeps_not_attainable_and_raises_it_again() -> None:
    heavy = with_values(load_case(None), {"aircraft.mass_kg": 400.0})
    study = Study(heavy)
    with pytest.raises(NotAttainable) as first:
        study.takeoff()
    with pytest.raises(NotAttainable) as second:
        study.takeoff()
    assert first.value is second.value
    assert study.solved.count("takeoff") == 1
    verdict = {v.name: v for v in study_verdicts(study)}["takeoff_ground_roll"]
    assert verdict.value is None and not verdict.passed
