"""One least level-flight throttle, and one Study per case (issue 9, issue 42).

- The closed-form least throttle of :class:`LevelFlightRows` (the quadratic excess's least
  root in [0, 1], the code ``trim``, ``oei`` and the batches all run) equals an independent
  root-find: a dense scan for the first sign change, then ``scipy.optimize.brentq``, on
  made-up engines whose excess is non-monotonic in throttle; one surface alone (a case) and
  all of them as the rows of one batch (sampled coefficients).
- A Study solves each analysis once: the report's analyses and the verdicts share results.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from tuflexperf.analysis.level_flight import LevelFlightRows
from tuflexperf.analysis.requirements import study_verdicts
from tuflexperf.analysis.study import Study
from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values
from tuflexperf.models.aircraft import G0_M_S2, Aircraft, TakeoffConfig
from tuflexperf.models.thrust import POLY22_TERMS, Engine, Propulsion

MASS_KG = 10.0


def made_up_rows(coefficients: dict, parasite: object, induced: object) -> LevelFlightRows:
    """One engine of these poly22 ``coefficients`` [N] on an aircraft whose level-flight drag
    is ``parasite V^2 + induced / V^2`` [N] (``rho S / 2 = 1``); floats make one row, ``(B, 1)``
    columns ``B`` rows."""
    engine = Engine(name="made-up", coefficients=coefficients)
    propulsion = Propulsion(name="made-up", engines=(engine,), tested_airspeed_m_s=(0.0, 60.0))
    weight = MASS_KG * G0_M_S2
    aircraft = Aircraft(name="made-up", mass_kg=MASS_KG, wing_area_m2=2.0, cd0=parasite,
                        k=np.asarray(induced) / weight**2, cl_max=1.3,
                        takeoff=TakeoffConfig(cl_ground=0.5))
    size = int(np.size(parasite))
    return LevelFlightRows(aircraft, propulsion, 1.0, None, size)


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


def _surface(seed: int) -> tuple[dict[str, float], float, float]:
    rng = np.random.default_rng(seed)
    p20 = rng.uniform(-60.0, 60.0)  # concave or convex in throttle: two roots possible
    p10, p11 = rng.uniform(20.0, 90.0), rng.uniform(-0.6, 0.1)
    p00, p01, p02 = rng.uniform(-2.0, 1.0), rng.uniform(-0.3, 0.0), rng.uniform(-0.004, 0.002)
    k_drag, c_drag = rng.uniform(0.01, 0.05), rng.uniform(1.0, 20.0)
    coefficients = {"p00": p00, "p10": p10, "p01": p01, "p20": p20, "p11": p11, "p02": p02}
    return coefficients, k_drag, c_drag * 100.0


def _reference(seed: int, speeds: np.ndarray) -> np.ndarray:
    p, parasite, induced = _surface(seed)

    def excess(x, v):
        thrust = (p["p00"] + p["p10"] * x + p["p01"] * v + p["p20"] * x * x + p["p11"] * x * v
                  + p["p02"] * v * v)
        return thrust - (parasite * v * v + induced / (v * v))  # parasite + induced

    return np.array([_independent_least_root(excess, float(v)) for v in speeds])


SPEEDS = np.linspace(10.0, 45.0, 36)


def _assert_close(ours: np.ndarray, reference: np.ndarray) -> None:
    assert np.array_equal(np.isnan(ours), np.isnan(reference))
    finite = np.isfinite(reference)
    assert np.max(np.abs(ours[finite] - reference[finite]), initial=0.0) < 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_closed_form_least_throttle_equals_independent_root_find(seed: int) -> None:
    rows = made_up_rows(*_surface(seed))
    _assert_close(rows.least_throttle(SPEEDS[None, :])[0], _reference(seed, SPEEDS))


def test_a_batch_of_surfaces_equals_independent_root_finds() -> None:
    """The rows' sampled coefficients meet the airspeeds in one matrix product."""
    surfaces = [_surface(seed) for seed in range(6)]
    coefficients = {t: np.array([[s[0][t]] for s in surfaces]) for t in POLY22_TERMS}
    rows = made_up_rows(coefficients, np.array([[s[1]] for s in surfaces]),
                        np.array([[s[2]] for s in surfaces]))
    ours = rows.least_throttle(SPEEDS[None, :])
    reference = np.array([_reference(seed, SPEEDS) for seed in range(6)])
    _assert_close(ours, reference)
    assert np.isnan(reference).any() and np.isfinite(reference).any()


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
