"""The batch evaluator's speed-ups change no answer (issue 12, item 5).

Each shortcut is held to the plain way it replaces, on parameter sets chosen to defeat it:
masses, drags and densities far from the nominal (so the highest trim throttle and the least
OEI throttle move away from the nominal's candidate airspeeds), high ``cl_ground`` (the
friction clamp's kink inside the roll), hot-and-high (lift-off beyond the tested 30 m/s,
where the extrapolation error jumps), sampled thrust coefficients, and not-attainable rows.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis import batch_endurance
from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.batch_kernels import nominal_engines
from tuflexperf.analysis.batch_model import BatchModel
from tuflexperf.analysis.ground_roll import _STEEP_FORCE_SHARE
from tuflexperf.io.case import load_case
from tuflexperf.models._math import interp_rows

ROWS = 400


def _hostile_batch(seed: int) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    values = {
        "aircraft.mass_kg": rng.uniform(12.0, 45.0, ROWS),
        "aircraft.cd0": rng.uniform(0.01, 0.06, ROWS),
        "aircraft.k": rng.uniform(0.02, 0.09, ROWS),
        "aircraft.takeoff.cl_ground": rng.uniform(0.1, 2.5, ROWS),
        "aircraft.takeoff.liftoff_speed_factor": rng.uniform(1.05, 2.6, ROWS),
        "atmosphere.altitude_m": rng.uniform(0.0, 4000.0, ROWS),
        "atmosphere.temperature_offset_k": rng.uniform(-20.0, 35.0, ROWS),
    }
    case = load_case(SHIPPED_CASE)
    nominal = nominal_engines(case.propulsion)
    coefficients = nominal[:, None, :] * (1.0 + 0.05 * rng.standard_normal((2, ROWS, 6)))
    extrapolation = rng.normal(0.0, 1.0, (2, ROWS))
    return values, coefficients, extrapolation


def _model(evaluator: BatchEvaluator, values, coefficients, extrapolation) -> BatchModel:
    return evaluator.model(values, ROWS, coefficients, extrapolation)


@pytest.mark.parametrize(("seed", "own_bounds"), [(1, False), (2, False), (6, True)])
def test_candidate_airspeeds_give_the_full_grid_answer(seed: int, own_bounds: bool) -> None:
    """``own_bounds``: each row flies its own envelope (a grid per row, shorter or longer
    than the nominal's, whose candidate indices are then only hints)."""
    case = load_case(SHIPPED_CASE)
    evaluator = BatchEvaluator(case)
    values, coefficients, extrapolation = _hostile_batch(seed)
    grid = evaluator._nominal_grid()[None, :]
    if own_bounds:
        rng = np.random.default_rng(seed)
        low = rng.uniform(12.0, 25.0, ROWS)
        values["requirements.envelope.min_airspeed_m_s"] = low
        values["requirements.envelope.max_airspeed_m_s"] = low + rng.uniform(2.0, 40.0, ROWS)
        grid, none = evaluator._grids(values, evaluator._density(values, ROWS), ROWS)
        assert grid.shape[0] == ROWS and not none.any()
    trim_candidates, oei_candidates = evaluator._candidates()
    fast = _model(evaluator, values, coefficients, extrapolation)
    full = _model(evaluator, values, coefficients, extrapolation)
    got_trim = fast.trim_max_throttle(grid, trim_candidates)
    want_trim = full.trim_max_throttle(grid, None)
    got_oei = fast.oei_min_throttle(grid, "windmilling", oei_candidates)
    want_oei = full.oei_min_throttle(grid, "windmilling", None)
    for got, want in ((got_trim, want_trim), (got_oei, want_oei)):
        assert np.array_equal(np.isnan(got), np.isnan(want))
        assert np.allclose(got, want, rtol=1e-12, atol=0.0, equal_nan=True)
    # the batch really is hostile: some rows unattainable, and extremes far from nominal's
    assert np.isnan(want_trim).any() and np.isfinite(want_trim).any()
    assert np.isnan(want_oei).any() and np.isfinite(want_oei).any()
    # and the verification rejected the candidates for some rows (the fallback ran): the
    # least OEI throttle sits away from the nominal's candidate airspeeds there
    terms = full._grid_terms(grid)
    above = full._flyable(grid)
    throttle = full.least_throttle(grid, 0, "windmilling", terms)
    lowest = np.argmin(np.where(above & np.isfinite(throttle), throttle, np.inf), axis=1)
    assert not np.isin(lowest[np.isfinite(want_oei)], oei_candidates[0]).all()


@pytest.mark.parametrize("seed", [3, 4])
def test_piecewise_quadratic_roll_equals_node_by_node(seed: int) -> None:
    case = load_case(SHIPPED_CASE)
    evaluator = BatchEvaluator(case)
    values, coefficients, extrapolation = _hostile_batch(seed)
    fast = _model(evaluator, values, coefficients, extrapolation)
    slow = _model(evaluator, values, coefficients, extrapolation)
    slow._pieces = False  # evaluate the force at every node
    got, want = fast.ground_roll(), slow.ground_roll()
    assert fast._pieces  # the quadratic form held for every row
    # where the force all but vanishes the pieces' stretched rule is exact and node by node
    # takes 8 panels of 16 nodes a part of each history interval (its sums within 1e-12)
    least, most = fast.force_range()
    steep = least < _STEEP_FORCE_SHARE * most
    assert steep[np.isfinite(got[0])].any()
    for a, b in zip(got, want, strict=True):
        assert np.array_equal(np.isnan(a), np.isnan(b))
        assert np.allclose(a, b, rtol=1e-10, atol=0.0, equal_nan=True)
    assert np.allclose(fast.uniform_force(), slow.uniform_force(), rtol=1e-9, atol=1e-9)
    # the history likewise: the pieces' quadratics or the force node by node, on the same
    # parts of each interval (the stretched rule where the force all but vanishes)
    history, by_node = fast.roll_history(), slow.roll_history()
    assert np.allclose(history[~steep], by_node[~steep], rtol=1e-9, equal_nan=True)
    v_lo = fast.liftoff_speed()[:, 0]
    clamp = fast._breaks(fast.liftoff_speed())[1][:, 0]
    assert (v_lo > 30.0).any()  # lift-off beyond the tested range: the jump is crossed
    assert (clamp < v_lo).any()  # the friction clamp's kink inside the roll
    assert np.isnan(want[0]).any() and np.isfinite(want[0]).any()


def test_launch_in_fewer_steps_equals_the_mission_steps(monkeypatch) -> None:
    """The batch's launch flies a roll whose force does not all but vanish in 16 RK4 steps,
    the rotation in 2 and a climb drawing under 10 % of the packs in 8: the mission's 64, 8
    and 64 give the same endurance to 1e-8 on a hostile batch."""
    case = load_case(SHIPPED_CASE)
    evaluator = BatchEvaluator(case)
    values, coefficients, extrapolation = _hostile_batch(5)
    values = {k: v for k, v in values.items() if k != "atmosphere.altitude_m"}
    got = evaluator.evaluate(values, ROWS, coefficients, extrapolation).values
    monkeypatch.setattr(batch_endurance, "_ROLL_STEPS", 64)
    monkeypatch.setattr(batch_endurance, "_ROTATION_STEPS", 8)
    monkeypatch.setattr(batch_endurance, "_CLIMB_STEPS", 64)
    want = evaluator.evaluate(values, ROWS, coefficients, extrapolation).values
    endurance = got["flight_endurance"]
    assert np.array_equal(np.isnan(endurance), np.isnan(want["flight_endurance"]))
    assert np.isfinite(endurance).sum() > ROWS // 4
    assert np.allclose(endurance, want["flight_endurance"], rtol=1e-8, equal_nan=True)


def test_row_wise_interpolation_equals_numpy_interp() -> None:
    rng = np.random.default_rng(6)
    t_hist = np.cumsum(rng.uniform(0.0, 0.2, (60, 101)), axis=1)
    t_hist[:, 0] = 0.0
    t_hist[:7] = np.round(t_hist[:7] / 0.05) * 0.05 + np.arange(101) * 1e-9  # near-ties
    v_hist = np.cumsum(rng.uniform(0.0, 1.0, (60, 101)), axis=1)
    step = rng.uniform(0.02, 0.3, 60)
    step[:7] = 0.05
    t = step[:, None] * np.arange(90)[None, :]  # reaches beyond the last history time
    t[7:, 5] = t_hist[7:, 40]  # exactly on a history time
    got = interp_rows(t, t_hist, v_hist)
    want = np.array([np.interp(t[i], t_hist[i], v_hist[i]) for i in range(60)])
    assert np.allclose(got, want, rtol=0.0, atol=1e-12)
