"""Endurance of the shipped TU-Flex against the paper (section 4), tolerances stated.

Paper: one 12S 5000 mAh pack "last[s] nearly up to 10 min" at 50 % throttle; with two
packs per fan and the launch, "a flight time of 15 minutes can be estimated", and the
requirements are met. Both numbers are in the reconstruction's least squares, so they are
pinned (with their residuals) in tests/verification/test_reconstruction_pins.py; here
only what the reconstruction does not fit: the model's own consistency (cross-validation,
monotonic trends, plausible power and current, the requirement verdict).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from tuflexperf.analysis.endurance import endurance_model, solve_endurance
from tuflexperf.analysis.requirements import check_case
from tuflexperf.io.case import load_case, shipped_case_path

ROOT = Path(__file__).resolve().parents[2]


def shipped_with_battery(folder: Path) -> Path:
    """The shipped case, with the TU-Flex battery and the endurance requirement if it lacks them."""
    shipped = shipped_case_path()
    data = yaml.safe_load(shipped.read_text())
    if data.get("battery") and (data.get("requirements") or {}).get("endurance"):
        return shipped
    for key in ("aircraft", "propulsion"):
        data[key] = str((shipped.parent / data[key]).resolve())
    data["battery"] = str(ROOT / "data" / "tuflex" / "battery.yaml")
    data.setdefault("requirements", {})["endurance"] = {"throttle": 0.5, "min_flight_time_min": 15}
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "tuflex_with_battery.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    return load_case(shipped_with_battery(tmp_path_factory.mktemp("case")))


def test_flight_uses_both_packs_less_launch_and_reserve(case):
    result = solve_endurance(case, 0.5)
    # flight time is more than one pack's but less than two packs' worth (launch + reserve)
    assert result.battery_endurance_min < result.flight_endurance_min
    assert result.flight_endurance_min < 2.2 * result.battery_endurance_min


def test_level_flight_and_power_are_plausible(case):
    result = solve_endurance(case, 0.5)
    assert 15.0 <= result.airspeed_m_s <= 45.0
    # half throttle draws well under the fan's published full-power 2.4-4.1 kW
    assert 500.0 < result.electrical_power_w < 2400.0
    # 12S pack current under its 40C (200 A) rating
    assert result.pack_current_a < 40 * endurance_model(case).battery.capacity_ah


def test_endurance_falls_as_throttle_rises(case):
    throttles = np.linspace(0.45, 0.75, 7)
    results = [solve_endurance(case, float(x)) for x in throttles]
    pack = np.array([r.battery_endurance_min for r in results])
    flight = np.array([r.flight_endurance_min for r in results])
    power = np.array([r.electrical_power_w for r in results])
    speed = np.array([r.airspeed_m_s for r in results])
    assert np.all(np.diff(pack) < 0)
    assert np.all(np.diff(flight) < 0)
    assert np.all(np.diff(power) > 0)
    assert np.all(np.diff(speed) > 0)


def test_fitted_model_predicts_the_run_it_was_not_fitted_on(case):
    """Cross-validation: fitted on one run, the other's time to cut-off within 5 %."""
    result = solve_endurance(case, 0.5)
    checks = result.to_dict()["cross_validation"]
    assert len(checks) == 2
    for check in checks:
        assert check["fitted_on"] != check["predicted_run"]
        assert abs(check["error_percent"]) < 5.0
    assert result.to_dict()["battery_fit"]["rms_v"] < 0.15  # 12S pack, volts


def test_endurance_requirement_is_checked_on_both_power_readings(case):
    # met on the power model (18.5 min), not on the discharge runs' measured power (14.0):
    # UNPROVEN, the shown value the worse reading's
    verdicts = {v.name: v for v in check_case(case)}
    assert "flight_endurance" in verdicts
    verdict = verdicts["flight_endurance"]
    assert verdict.verdict == "UNPROVEN" and not verdict.passed
    nominal, measured = verdict.readings[:2]
    assert nominal.value == pytest.approx(solve_endurance(case, 0.5).flight_endurance_min)
    assert nominal.passed and not measured.passed
    assert verdict.value == measured.value < verdict.limit < nominal.value
