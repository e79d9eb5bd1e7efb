"""The sampled batch's speed-ups change no answer.

- :func:`tuflexperf.analysis.batch.packs_surely_never_bind` (one bound shared by the batch)
  never says "the packs never bind" where the row-by-row test says they do;
- the take-off on the packs judged at each row's most power gives the row-by-row answer;
- the process settings of :mod:`tuflexperf.analysis.runtime` leave every number as it is,
  and are undone afterwards.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis import runtime
from tuflexperf.analysis.batch import BatchEvaluator, packs_surely_never_bind
from tuflexperf.analysis.batch_kernels import fan_power_rows
from tuflexperf.analysis.batch_model import BatchModel
from tuflexperf.analysis.pack_limits import operating_point, pack_rows, within_limits
from tuflexperf.analysis.uncertainty import evaluate_batch, plan_for
from tuflexperf.io.case import load_case

ROWS = 300


def _batch(seed: int, capacity_scale: float) -> tuple[BatchEvaluator, BatchModel,
                                                      dict[str, np.ndarray]]:
    """A batch of the shipped case with hostile masses, densities and battery capacities
    (but for 1: ``capacity_scale`` times the nominal, spread over a factor of four)."""
    rng = np.random.default_rng(seed)
    evaluator = BatchEvaluator(load_case(SHIPPED_CASE))
    values = {
        "aircraft.mass_kg": rng.uniform(12.0, 40.0, ROWS),
        "atmosphere.temperature_offset_k": rng.uniform(-30.0, 35.0, ROWS),
        "atmosphere.altitude_m": rng.uniform(0.0, 3000.0, ROWS),
    }
    battery = evaluator._battery_rows({}, ROWS)
    if capacity_scale != 1.0:
        battery["battery.capacity_ah"] = (battery["battery.capacity_ah"] * capacity_scale
                                          * rng.uniform(0.25, 1.0, ROWS))
    model = BatchModel(aircraft=evaluator._aircraft(values, ROWS),
                       propulsion=evaluator._propulsion(None),
                       density=evaluator._density(values, ROWS), extrapolation_n=None,
                       size=ROWS)
    return evaluator, model, battery


@pytest.mark.parametrize(("seed", "capacity_scale"), [(1, 1.0), (2, 0.05), (3, 0.3)])
def test_shared_bound_never_contradicts_the_row_by_row_test(seed: int,
                                                            capacity_scale: float) -> None:
    evaluator, model, battery = _batch(seed, capacity_scale)
    grid = evaluator._nominal_grid()[None, :]
    rng = np.random.default_rng(seed)
    for top in (np.ones(ROWS), rng.uniform(0.2, 1.0, ROWS),
                np.where(rng.uniform(size=ROWS) < 0.1, np.nan, 1.0)):
        sure = packs_surely_never_bind(model, grid, evaluator._packs, battery, top)
        exact = model.packs_never_bind(grid, evaluator._packs, battery, top)
        assert not sure or exact
        if capacity_scale == 1.0:  # the shipped packs, far from binding: the bound settles it
            assert sure and exact
        if capacity_scale == 0.05:  # packs a twentieth the size bind: never "sure"
            assert not exact and not sure


@pytest.mark.parametrize("capacity_scale", [1.0, 0.02, 0.004])
def test_take_off_judged_at_the_most_power_equals_every_airspeed(capacity_scale: float) -> None:
    """Per row, within_limits at every airspeed of the roll (and the charge after the most
    current) equals the same at the row's most power: the loaded voltage falls and the
    current rises with the power at a fixed power (no reference voltage)."""
    evaluator, model, battery = _batch(7, capacity_scale)
    packs = evaluator._packs
    assert model.propulsion.reference_voltage_v is None
    rows = pack_rows(packs.battery, battery)
    circuit, cutoff = rows.circuit_packs[:, None], rows.cutoff_v[:, None]
    burst = None if rows.rating_a is None else 2.0 * rows.rating_a[:, None]
    speeds = np.linspace(0.0, 1.0, 102)[None, :] * np.linspace(12.0, 40.0, ROWS)[:, None]
    seconds = np.linspace(1.0, 200.0, ROWS)
    verdicts = []
    for one_column in (False, True):
        ok = np.ones(ROWS, dtype=bool)
        for engine in model.propulsion.engines:
            power = np.maximum(fan_power_rows(packs, model, 1.0, speeds, engine), 0.0)
            if one_column:
                power = np.max(power, axis=1, keepdims=True)
            charge = np.zeros((ROWS, 1))
            for _ in range(2):
                u, current, _ = operating_point(packs.params, charge, power, circuit,
                                                rows.packs_per_engine, None, 2.0)
                ok &= np.all(within_limits(u, current, cutoff, burst), axis=1)
                charge = (np.max(current, axis=1) * rows.packs_per_engine * seconds
                          / 3600.0)[:, None]
        verdicts.append((ok, charge))
    assert np.array_equal(verdicts[0][0], verdicts[1][0])
    assert np.array_equal(verdicts[0][1], verdicts[1][1], equal_nan=True)
    if capacity_scale < 0.01:  # tiny packs: some rows fail, so the comparison means something
        assert not verdicts[0][0].all()


def test_process_settings_change_no_number_and_are_undone() -> None:
    import gc

    case = load_case(SHIPPED_CASE)
    plan = plan_for(case, samples=600, seed=5)
    plain = evaluate_batch(case, plan, range(0, 1))
    blas = runtime._openblas()
    threads = None if blas is None else blas[1]()
    with runtime.earlier_objects_frozen(), runtime.freed_arrays_kept(), \
            runtime.one_blas_thread():
        assert gc.get_freeze_count() > 0
        if blas is not None:
            assert blas[1]() == 1
        tuned = evaluate_batch(case, plan, range(0, 1))
    assert gc.get_freeze_count() == 0
    if blas is not None:
        assert blas[1]() == threads
    assert plain.keys() == tuned.keys()
    for key in plain:
        assert np.array_equal(plain[key], tuned[key], equal_nan=True), key
