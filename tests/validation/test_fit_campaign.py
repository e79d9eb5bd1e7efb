"""The shipped synthetic campaign, reduced end to end, against its known ground truth.

Ground truth: data/tuflex/campaign/truth.yaml (written by scripts/generate_campaign.py).
Tolerances: full-throttle thrust within 0.5 N (the paper's accuracy goal, section 1) of the
truth brought to the fit's reference voltage (the truth holds at its own ``U_ref``, thrust
``~ (U/U_ref)^2``), delay within 12 ms (a quarter of the published 0.05 s), voltage exponent
within 0.1 of the truth's 2.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from tuflexperf.cli import app
from tuflexperf.io.case import load_propulsion
from tuflexperf.models.thrust import poly22
from tuflexperf.reduction.pipeline import fit_table, run_fit

ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml"
TRUTH = yaml.safe_load((CAMPAIGN.parent / "truth.yaml").read_text(encoding="utf-8"))
SHIPPED_CASE = ROOT / "requirements" / "tuflex.yaml"


@pytest.fixture(scope="module")
def fitted(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp("fit")
    summary = run_fit(CAMPAIGN, folder / "propulsion_fit.yaml")
    return {"summary": summary, "out": Path(summary["out"]), "table": Path(summary["table"])}


@pytest.mark.parametrize("airspeed", [0.0, 30.0])
@pytest.mark.parametrize("engine", ["EDF1", "EDF2"])
def test_full_throttle_thrust_matches_ground_truth(fitted, engine: str, airspeed: float) -> None:
    truth = next(e for e in TRUTH["engines"] if e["name"] == engine)["coefficients"]
    model = load_propulsion(fitted["out"])
    coefficients = next(e for e in model.engines if e.name == engine).coefficients
    scale = (model.reference_voltage_v / TRUTH["reference_voltage_v"]) ** TRUTH[
        "voltage_exponent"
    ]
    assert poly22(1.0, airspeed, coefficients) == pytest.approx(
        scale * poly22(1.0, airspeed, truth), abs=0.5
    )


def test_voltage_power_and_windmilling_from_the_logged_runs(fitted) -> None:
    model = load_propulsion(fitted["out"])
    assert model.voltage_exponent == pytest.approx(TRUTH["voltage_exponent"], abs=0.1)
    assert model.reference_voltage_v is not None
    assert model.fan_area_m2 == pytest.approx(0.006793)
    electrical = fitted["summary"]["electrical"]
    for name, fit in electrical["voltage_fits"].items():
        assert fit["identified"] and fit["standard_error"] < 0.1, name
    for engine in model.engines:
        assert engine.power_coefficients is not None
        assert engine.windmilling_drag_coefficient is not None
        assert engine.windmilling_drag_coefficient > 0
    for name, power in electrical["power"].items():
        assert power["r2"] > 0.99 and power["n_points"] == 77, name


def test_delay_matches_ground_truth(fitted) -> None:
    summary = fitted["summary"]
    assert summary["delay_s"] == pytest.approx(TRUTH["delay_s"], abs=0.012)
    assert len(summary["delay_runs"]) == 4
    for run in summary["delay_runs"]:
        assert run["delay_s"] == pytest.approx(TRUTH["delay_s"], abs=0.012)
        assert run["lag_s"] == pytest.approx(TRUTH["spool_lag_s"], abs=0.02)
    assert load_propulsion(fitted["out"]).delay_s == pytest.approx(summary["delay_s"])
    # the dynamic model as fitted (issue 15): the spool lag is written beside the dead time
    assert summary["lag_s"] == pytest.approx(TRUTH["spool_lag_s"], abs=0.01)
    assert load_propulsion(fitted["out"]).lag_s == pytest.approx(summary["lag_s"], abs=1e-6)


def test_structure_drag_and_glauert(fitted) -> None:
    drag = fitted["summary"]["structure_drag"]
    v = drag["airspeed_range_m_s"][1]
    expected = 0.5 * TRUTH["air_density_kg_m3"] * TRUTH["structure_cda_m2"] * v * v
    assert drag["drag_at_max_airspeed_n"] == pytest.approx(expected, abs=0.05)
    glauert = fitted["summary"]["glauert"]
    assert glauert["applied"] is False
    # the paper: under 4 % at the top airspeed (30 m/s), so it was neglected
    assert 0 < glauert["max_correction_at_top_airspeed_percent"] < 4.0


def test_propulsion_file_is_complete(fitted) -> None:
    document = yaml.safe_load(fitted["out"].read_text(encoding="utf-8"))
    model = load_propulsion(fitted["out"])
    assert model.tested_airspeed_m_s == pytest.approx((0.0, 30.0), abs=0.3)
    for engine in document["engines"]:
        assert engine["r2"] > 0.999
        assert 0 < engine["rmse_n"] < 0.25
        assert engine["n_points"] == 7 * 11  # 7 airspeeds x (100 % .. 10 % and 0 %)
        assert set(engine["standard_errors"]) == set(engine["coefficients"])
    files = document["source"]["files"]
    assert len(files) == 19 and all(len(f["sha256"]) == 64 for f in files)
    # the campaign's test-day density: the fit lapses with altitude like the shipped file
    # (without it, "used as measured" at 3000 m, the endurance PASSed; outside audit)
    assert document["reference_density_kg_m3"] == TRUTH["air_density_kg_m3"]


def test_validation_error_within_the_papers_accuracy_goal(fitted) -> None:
    runs = [r for r in fitted["summary"]["runs"] if r["kind"] == "throttle_steps"]
    assert len(runs) == 14
    for run in runs:
        v = run["validation"]
        assert -0.5 < v["mean_negative_error_n"] < 0 < v["mean_positive_error_n"] < 0.5
        assert run["changepoints"]["matched_steps"] >= run["changepoints"]["throttle_steps"] - 1


def test_written_table_refits_to_the_same_coefficients(fitted) -> None:
    again = fit_table(fitted["table"])
    for engine in fitted["summary"]["engines"]:
        assert again.engines[engine["name"]].coefficients == engine["coefficients"]


@pytest.mark.skipif(not SHIPPED_CASE.is_file(), reason="shipped case not in this checkout")
def test_fitted_model_is_a_drop_in_for_check(fitted, tmp_path: Path) -> None:
    case = yaml.safe_load(SHIPPED_CASE.read_text(encoding="utf-8"))
    for key in ("aircraft", "battery"):
        if key in case:
            case[key] = str((SHIPPED_CASE.parent / case[key]).resolve())
    case["propulsion"] = str(fitted["out"])
    path = tmp_path / "fitted_case.yaml"
    path.write_text(yaml.safe_dump(case, sort_keys=False), encoding="utf-8")
    runner = CliRunner()
    shipped = runner.invoke(app, ["check", str(SHIPPED_CASE), "--json"])
    refit = runner.invoke(app, ["check", str(path), "--json"])
    verdicts = {r["name"]: r["passed"] for r in json.loads(shipped.stdout)["results"]}
    results = {r["name"]: r for r in json.loads(refit.stdout)["results"]}
    # the refit carries its runs' pack voltage (reference_voltage_v), which the shipped
    # reconstruction has not: trim is flown at the landing reserve's loaded voltage, where
    # the top of the envelope needs more than full throttle (analysis.pack_limits)
    trim = results.pop("trim_throttle_max")
    assert refit.exit_code == 1 and not trim["passed"], refit.stderr
    assert "beyond the battery at 42.5-45 m/s" in trim["reason"]
    assert any("loaded voltage" in w for w in trim["warnings"])
    verdicts.pop("trim_throttle_max")
    # the endurance is judged on the discharge runs' measured power too: the shipped power
    # model lies 25 % below the runs (UNPROVEN), the campaign's 30 % below, but on its
    # thrust the case meets 15 min on both readings
    endurance = results.pop("flight_endurance")
    assert not verdicts.pop("flight_endurance")
    assert [r["key"] for r in endurance["readings"]] == ["nominal", "measured_power"]
    assert endurance["verdict"] == "PASS" and all(r["passed"] for r in endurance["readings"])
    assert {name: r["passed"] for name, r in results.items()} == verdicts
