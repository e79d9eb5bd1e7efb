"""A pack of another capacity (``battery.capacity_ah`` in --set, samples, sweeps, margins).

The fitted circuit belongs to the measured pack; a pack of the same cells at ``s`` times
the capacity is ``s`` measured packs in parallel (models.battery.equivalent_packs). So a
case whose battery file holds one 5 Ah pack per fan, flown at 10 Ah, must give exactly
what the same file with two 5 Ah packs per fan gives: endurance, mission landing charge
and rating verdicts alike; and the batch must equal the single case at any capacity.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.conftest import SHIPPED_CASE, copy_shipped_case
from tests.verification.test_batch_equals_deterministic import assert_equal_to_deterministic
from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.study import Study
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values
from tuflexperf.models.battery import equivalent_packs


def _shipped_with_packs(folder: Path, packs: int, c_rate: float = 40) -> Path:
    copy_shipped_case(folder)
    battery = folder / "data" / "tuflex" / "battery.yaml"
    battery.write_text(battery.read_text()
                       .replace("packs_in_parallel_per_engine: 2 ",
                                f"packs_in_parallel_per_engine: {packs} ")
                       .replace("max_discharge_c: 40 ", f"max_discharge_c: {c_rate} "))
    case = folder / "requirements" / "tuflex.yaml"
    text = case.read_text()
    case.write_text(text + "  mission: {file: ../data/tuflex/missions/test_flight.yaml, "
                    "min_landing_charge_fraction: 0.2}\n")
    return case


def test_equivalent_packs_is_the_capacity_ratio() -> None:
    assert equivalent_packs(2, 6.0, 5.0) == pytest.approx(2.4)
    assert np.allclose(equivalent_packs(1, np.array([2.5, 5.0, 10.0]), 5.0), [0.5, 1.0, 2.0])


@pytest.mark.parametrize("c_rate", [40, 9])
def test_twice_the_capacity_flies_as_two_packs(tmp_path, c_rate) -> None:
    """c_rate 9: one 5 Ah pack is beyond its burst rating on the take-off (94 A against
    90 A); a 10 Ah pack, like two 5 Ah packs, is within it."""
    one = load_case(_shipped_with_packs(tmp_path / "one", 1, c_rate))
    two = load_case(_shipped_with_packs(tmp_path / "two", 2, c_rate))
    doubled = with_values(one, {"battery.capacity_ah": 10.0})
    got = {v.name: v for v in check_case(doubled)}
    want = {v.name: v for v in check_case(two)}
    assert set(got) == set(want)
    for name, verdict in want.items():
        if verdict.value is None:
            assert got[name].value is None, name
        else:
            assert got[name].value == pytest.approx(verdict.value, rel=1e-9), name
    assert got["flight_endurance"].value is not None
    if c_rate == 9:  # the one small pack alone fails on its rating
        alone = {v.name: v for v in check_case(one)}["flight_endurance"]
        assert alone.value is None and "beyond the battery" in alone.reason
    note = " ".join(Study(doubled).endurance(0.5).warnings)
    assert "measured 5 Ah pack scaled" in note


def test_the_batch_equals_the_single_case_at_any_capacity() -> None:
    case = load_case(SHIPPED_CASE)
    capacities = np.array([3.0, 4.2, 5.0, 6.5, 9.0])
    result = BatchEvaluator(case).evaluate({"battery.capacity_ah": capacities})
    for row, capacity in enumerate(capacities):
        single = with_values(case, {"battery.capacity_ah": float(capacity)})
        assert_equal_to_deterministic(single, result.values, row)
    endurance = result.values["flight_endurance"]
    assert np.all(np.diff(endurance) > 0)  # a larger pack flies longer


def test_the_nominal_of_a_changed_case_is_its_own() -> None:
    """--set battery.capacity_ah with samples: the batch's nominal row is the changed case
    (the capacity is not scaled twice)."""
    case = with_values(load_case(SHIPPED_CASE), {"battery.capacity_ah": 6.0})
    assert_equal_to_deterministic(case, BatchEvaluator(case).evaluate().values, 0)
    sampled = BatchEvaluator(case).evaluate({"battery.capacity_ah": np.array([6.0, 7.0])})
    assert_equal_to_deterministic(case, sampled.values, 0)
    assert_equal_to_deterministic(with_values(case, {"battery.capacity_ah": 7.0}),
                                  sampled.values, 1)


def test_the_sensitivity_to_capacity_is_the_batch_slope() -> None:
    from tuflexperf.analysis.margins import solve_margins

    case = load_case(SHIPPED_CASE)
    rows = [m for m in solve_margins(case) if m.parameter == "battery.capacity_ah"
            and m.requirement == "flight_endurance"]
    assert len(rows) == 1
    h = 1e-4
    values = BatchEvaluator(case).evaluate(
        {"battery.capacity_ah": np.array([5.0 - h, 5.0 + h])}).values["flight_endurance"]
    assert rows[0].sensitivity == pytest.approx((values[1] - values[0]) / (2 * h), rel=1e-4)


@pytest.mark.parametrize("key, value", [
    ("battery.capacity_ah", 1.5),  # 1.5 Ah cuts off in the climb
    ("battery.cutoff_voltage_per_cell_v", 3.95),  # so does a 3.95 V cut-off
])
def test_a_launch_that_reaches_the_cut_off_fails_in_the_batch_too(key, value) -> None:
    """check said "cut-off voltage 40.8 V between 2.7 and 2.8 s", sweep 4.33 min PASS: the
    batch looked at the pack's cut-off in the cruise only (outside audit)."""
    case = with_values(load_case(SHIPPED_CASE), {"requirements.endurance.min_flight_time_min": 3.0})
    single = with_values(case, {key: value})
    endurance = {v.name: v for v in check_case(single)}["flight_endurance"]
    assert endurance.value is None and "cut-off" in endurance.reason
    result = BatchEvaluator(case).evaluate({key: np.array([value])})
    assert np.isnan(result.values["flight_endurance"][0])
    assert_equal_to_deterministic(single, result.values, 0)


def test_one_pack_is_one_pack_of_the_capacity_flown() -> None:
    """endurance at 10 Ah still gave the measured 5 Ah pack's 11.6 min 'one pack, full to
    cut-off' (outside audit): one 10 Ah pack is two measured packs in parallel."""
    from tuflexperf.models.battery import time_to_cutoff_s

    case = load_case(SHIPPED_CASE)
    nominal = Study(case).endurance(0.5)
    doubled = Study(with_values(case, {"battery.capacity_ah": 10.0})).endurance(0.5)
    model = Study(case).endurance_model()
    expected = time_to_cutoff_s(model.params, doubled.electrical_power_w, model.cutoff_v, 2)
    assert doubled.battery_endurance_min == pytest.approx(expected / 60.0, rel=1e-6)
    assert doubled.battery_endurance_min > 2.0 * nominal.battery_endurance_min


def test_battery_keys_without_a_battery_and_an_absurd_capacity_are_bad_input(tmp_path) -> None:
    from typer.testing import CliRunner

    from tests.conftest import write_case
    from tuflexperf.cli import app

    bare = write_case(tmp_path / "bare")
    runner = CliRunner()
    result = runner.invoke(app, ["check", str(bare), "--set", "battery.capacity_ah=6"])
    assert result.exit_code == 2 and "names no battery file" in result.stderr
    result = runner.invoke(app, ["check", "--set", "battery.capacity_ah=1e308"])
    assert result.exit_code == 2 and "battery.capacity_ah" in result.stderr


def test_a_pack_far_too_small_fails_with_its_reason_and_nothing_on_stderr() -> None:
    """0.001 Ah: not attainable, said once in the verdict (CasADi's evaluation warnings
    from the root that does not exist went to stderr)."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "tuflexperf", "check", "--set",
                           "battery.capacity_ah=0.001"], capture_output=True, text=True)
    assert done.returncode == 1 and done.stderr == "", done.stderr
    # the take-off is flown on the packs: beyond the battery at the brake release
    assert "below their cut-off" in done.stdout or "cannot deliver" in done.stdout
    assert "beyond the battery" in done.stdout
