"""A batch of samples on two cores (issue 42, speed): half its rows in a forked helper give
the numbers of one batch, the readings judged over all rows at once, a mission flown half
there too; a helper that cannot start leaves its half to the parent, and an error in its
half is raised in the parent."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis import uncertainty
from tuflexperf.analysis.batch_readings import ReadingsEvaluator, readings_evaluator
from tuflexperf.analysis.uncertainty import plan_for, run_samples
from tuflexperf.io.case import load_case

SAMPLES = 1201  # one chunk, one batch; halves of 600 and 601 rows


@pytest.fixture(scope="module")
def case():
    return load_case()


@pytest.fixture(scope="module")
def plan(case):
    return plan_for(case, samples=SAMPLES, seed=11)


def _samples(case, plan, monkeypatch, split: bool):
    monkeypatch.setattr(uncertainty, "SPLIT_ROWS", 1000 if split else 10**9)
    monkeypatch.setattr(uncertainty, "second_core_idle", lambda: split)
    return run_samples(case, plan)


def _assert_same(one, other) -> None:
    assert list(one.values) == list(other.values)
    for name in one.values:
        assert np.array_equal(one.values[name], other.values[name], equal_nan=True), name
        assert np.array_equal(one.limits[name], other.limits[name]), name
    assert one.outside_bounds == other.outside_bounds
    assert {k: list(v) for k, v in one.reading_values.items()} == \
        {k: list(v) for k, v in other.reading_values.items()}
    for key, by_name in one.reading_values.items():
        for name, values in by_name.items():
            assert np.array_equal(values, other.reading_values[key][name], equal_nan=True)


def test_two_halves_give_the_numbers_of_one_batch(case, plan, monkeypatch) -> None:
    one = _samples(case, plan, monkeypatch, split=False)
    calls = []
    original = ReadingsEvaluator.readings_rows

    def counted(self, values=None, size=None, *rest):
        calls.append(size)
        return original(self, values, size, *rest)

    monkeypatch.setattr(ReadingsEvaluator, "readings_rows", counted)
    two = _samples(case, plan, monkeypatch, split=True)
    assert calls == [600]  # the parent's half here; the other half in the helper
    assert one.reading_values  # the shipped case's readings bear on the samples
    _assert_same(one, two)


def test_a_helper_that_cannot_start_leaves_its_half_here(case, plan, monkeypatch) -> None:
    from tuflexperf.io import files

    one = _samples(case, plan, monkeypatch, split=False)

    def no_process(*args, **kwargs):
        raise OSError("fork: Resource temporarily unavailable")

    monkeypatch.setattr(files, "start_helper", no_process)
    _assert_same(one, _samples(case, plan, monkeypatch, split=True))


def test_an_error_in_the_helpers_half_is_raised_here(case, plan, monkeypatch) -> None:
    original = ReadingsEvaluator.readings_rows

    def failing(self, values=None, size=None, *rest):
        if size == 601:  # the helper's half (forked with this method in place)
            raise ValueError("the helper's rows failed")
        return original(self, values, size, *rest)

    monkeypatch.setattr(ReadingsEvaluator, "readings_rows", failing)
    draw = uncertainty._joined([uncertainty.draw_chunk(case, plan, 0)])
    errors = plan.errors
    evaluator = readings_evaluator(case, drawn=plan.extrapolation,
                                   drawn_model_form=errors.model_form_maps is not None)
    with pytest.raises(ValueError, match="the helper's rows failed"):
        uncertainty._on_two_cores(evaluator, draw)


def test_a_mission_flown_on_two_halves_gives_the_numbers_of_one_batch(tmp_path, monkeypatch
                                                                      ) -> None:
    """The shipped case with its test flight as a mission requirement: the helper flies the
    mission for its half of the rows too (the parent flies only its own half)."""
    shipped = SHIPPED_CASE
    data = yaml.safe_load(shipped.read_text())
    for key in ("aircraft", "propulsion", "battery"):
        data[key] = str((shipped.parent / data[key]).resolve())
    flight = shipped.parent.parent / "data" / "tuflex" / "missions" / "test_flight.yaml"
    data["requirements"]["mission"] = {"file": str(flight), "min_landing_charge_fraction": 0.2}
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    case = load_case(path)
    plan = plan_for(case, samples=SAMPLES, seed=11)
    one = _samples(case, plan, monkeypatch, split=False)
    flown = []
    original = uncertainty.fly_missions

    def counted(case, evaluator, arguments, rows):
        flown.append(arguments[1])
        return original(case, evaluator, arguments, rows)

    monkeypatch.setattr(uncertainty, "fly_missions", counted)
    two = _samples(case, plan, monkeypatch, split=True)
    assert flown == [600]  # the parent's half here; the other half in the helper
    assert np.count_nonzero(np.isfinite(one.values["mission_landing_charge"])) > 500
    assert "mission_landing_charge" in one.reading_values["measured_power"]
    _assert_same(one, two)
