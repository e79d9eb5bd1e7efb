"""`mission FILE` (not the case's own requirement) is judged on every reading of the case's
disputed evidence, as `check` judges the case's mission (issue 43 item 2)."""

from __future__ import annotations

import json

from tests.conftest import copy_shipped_case, tuflexperf


def _mission(tmp_path, reserve: float) -> tuple[int, dict]:
    case = copy_shipped_case(tmp_path)
    battery = tmp_path / "data" / "tuflex" / "battery.yaml"
    battery.write_text(battery.read_text().replace("landing_reserve_fraction: 0.2",
                                                   f"landing_reserve_fraction: {reserve}"))
    mission = tmp_path / "data" / "tuflex" / "missions" / "test_flight.yaml"
    done = tuflexperf("mission", str(mission), "--case", str(case), "--json")
    return done.returncode, json.loads(done.stdout)


def test_a_mission_file_shows_each_reading_that_changes_its_landing_charge(tmp_path) -> None:
    code, data = _mission(tmp_path, 0.2)
    landing = next(r for r in data["results"] if r["name"] == "mission_landing_charge")
    keys = [r["key"] for r in landing["readings"]]
    # more power drawn than the model says, and the dead fan's larger drag; the flight stays
    # inside the tested airspeeds, so the extrapolation bound leaves it alone
    assert keys == ["nominal", "measured_power", "windmilling_model_drag"]
    nominal, measured, windmilling = (r["value"] for r in landing["readings"])
    assert measured < windmilling < nominal
    assert landing["value"] == measured and landing["verdict"] == "PASS" and code == 0


def test_a_reserve_between_the_readings_is_unproven(tmp_path) -> None:
    code, data = _mission(tmp_path, 0.45)
    landing = next(r for r in data["results"] if r["name"] == "mission_landing_charge")
    assert landing["verdict"] == "UNPROVEN" and code == 1
    assert "measured power" in landing["reason"] and landing["settle"]
