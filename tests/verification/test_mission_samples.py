"""Sampled missions: each batch row is the single case flown with the sample's --set values."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis.mission import STEPS, solve_mission
from tuflexperf.analysis.mission_samples import SAMPLED_STEPS, sampled_landing
from tuflexperf.analysis.uncertainty import evaluator_for, mission_for
from tuflexperf.cli import app
from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values
from tuflexperf.io.mission import load_mission

ROOT = SHIPPED_CASE.parent.parent
SHIPPED_MISSION = ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml"
AIRBORNE = """\
name: airborne
segments:
  - {type: climb, to_altitude_m: 150, airspeed_m_s: 22, climb_rate_m_s: 2.0}
  - {type: cruise, airspeed_m_s: 26, distance_km: 12}
  - {type: engine_failure, engine: EDF2}
  - {type: loiter, airspeed_m_s: 21, time_min: 2}
  - {type: descent, to_altitude_m: 0, airspeed_m_s: 20, throttle: 0.1}
"""
DRAWS = {"aircraft.mass_kg": [22.2, 24.0, 20.5], "aircraft.cd0": [0.021, 0.018, 0.026],
         "aircraft.k": [0.05, 0.047, 0.055],
         "atmosphere.temperature_offset_k": [0.0, 15.0, -5.0],
         "battery.cutoff_voltage_per_cell_v": [3.4, 3.45, 3.3]}


def _case(tmp_path: Path, mission: Path, uncertainty: dict | None = None) -> Path:
    data = yaml.safe_load(SHIPPED_CASE.read_text())
    for key in ("aircraft", "propulsion", "battery"):
        data[key] = str((SHIPPED_CASE.parent / data[key]).resolve())
    data["requirements"]["mission"] = {"file": str(mission),
                                       "min_landing_charge_fraction": 0.2}
    if uncertainty is not None:
        data["uncertainty"] = uncertainty
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _batch_and_single(case_path: Path, name: str = "mission_landing_charge"
                      ) -> tuple[np.ndarray, list[float]]:
    case = load_case(case_path)
    values = {k: np.array(v) for k, v in DRAWS.items()}
    model = mission_for(case, list(values))
    assert model is not None
    batch = sampled_landing(model, evaluator_for(case), values, 3, None, None, STEPS)[name][0]
    single = []
    for row in range(3):
        # the --set mechanism: the same dotted keys, validated as the files are
        one = with_values(case, {k: v[row] for k, v in DRAWS.items()})
        flown = solve_mission(one, load_mission(model.mission.path), 0.2)
        value = (flown.landing_charge_fraction if name == "mission_landing_charge"
                 else flown.solved["time_min"])
        single.append(value if flown.attainable else np.nan)
    return batch, single


def test_an_airborne_mission_row_is_the_single_case_flown_with_its_values(tmp_path) -> None:
    """No take-off: the batch runs the single case's very function, to rounding."""
    mission = tmp_path / "airborne.yaml"
    mission.write_text(AIRBORNE)
    batch, single = _batch_and_single(_case(tmp_path, mission))
    assert np.all(np.isfinite(batch)) and len(set(np.round(batch, 6))) == 3
    assert batch == pytest.approx(single, rel=1e-9)


def test_a_mission_with_a_takeoff_row_is_the_single_case_to_the_batch_takeoff(tmp_path) -> None:
    """The take-off's airspeed history per row is the take-off analysis's (one code for one
    row or many), the rest the single case's function."""
    batch, single = _batch_and_single(_case(tmp_path, SHIPPED_MISSION))
    assert np.all(np.isfinite(batch))
    assert batch == pytest.approx(single, rel=1e-7)


def test_a_sample_that_cannot_fly_the_mission_is_not_met_never_dropped(tmp_path) -> None:
    case = load_case(_case(tmp_path, SHIPPED_MISSION))
    # 20 m/s EAS segments below stall for a heavy aircraft; an empty-ish pack for a draggy one
    values = {"aircraft.mass_kg": np.array([22.2, 60.0]),
              "aircraft.cd0": np.array([0.021, 0.021])}
    model = mission_for(case, list(values))
    out = sampled_landing(model, evaluator_for(case), values, 2, None, None, STEPS)
    landing = out["mission_landing_charge"][0]
    assert np.isfinite(landing[0]) and np.isnan(landing[1])


def test_solve_for_per_row_is_the_single_cases_longest_segment(tmp_path) -> None:
    """solve_for solved over the batch (safeguarded Newton, vectorised) lands each row on
    the reserve with the single case's own duration; a row that stalls has none."""
    mission = tmp_path / "airborne.yaml"
    mission.write_text(AIRBORNE + "solve_for: cruise\n")
    path = _case(tmp_path, mission)
    batch, single = _batch_and_single(path, "mission_solved_time")
    assert np.all(np.isfinite(batch)) and np.all(batch > 10.0)  # the file plans 12 km
    assert batch == pytest.approx(single, rel=1e-9)
    landing, _ = _batch_and_single(path)
    assert landing == pytest.approx([0.2] * 3, abs=1e-11)
    case = load_case(path)
    values = {"aircraft.mass_kg": np.array([22.2, 60.0])}
    out = sampled_landing(mission_for(case, list(values)), evaluator_for(case), values, 2,
                          None, None, STEPS)
    assert np.isfinite(out["mission_solved_time"][0][0])
    assert np.isnan(out["mission_solved_time"][0][1])


def test_check_samples_shows_the_mission_and_workers_give_the_same_numbers(tmp_path) -> None:
    runner = CliRunner()
    path = _case(tmp_path, SHIPPED_MISSION, {
        "samples": 40, "seed": 3, "parameters": {"aircraft.mass_kg": {"normal": [22.2, 0.5]}}})
    here = runner.invoke(app, ["check", str(path), "--json"])
    data = json.loads(here.stdout)
    row = next(r for r in data["results"] if r["name"] == "mission_landing_charge")
    assert row["probability"] is not None and row["samples"] == 40
    assert row["p05"] <= row["p50"] <= row["p95"]
    assert 0 <= row["probability_ci"][0] <= row["probability"] <= row["probability_ci"][1] <= 1
    workers = json.loads(runner.invoke(app, ["check", str(path), "--json", "--workers",
                                             "2"]).stdout)
    assert workers["results"] == data["results"]


def test_a_dask_cluster_flies_the_sampled_mission_to_the_same_numbers(tmp_path) -> None:
    distributed = pytest.importorskip("distributed")
    from tuflexperf.analysis.uncertainty import plan_for, run_samples

    mission = tmp_path / "airborne.yaml"  # a loiter at its best-endurance airspeed too
    mission.write_text(AIRBORNE.replace("airspeed_m_s: 21, ", "") + "solve_for: cruise\n")
    case = load_case(_case(tmp_path, mission, {
        "samples": 30, "seed": 2, "parameters": {"aircraft.cd0": {"normal": [0.021, 0.002]},
                                                 "battery.capacity_ah": {"normal": [5.0, 0.2]}}}))
    plan = plan_for(case)
    here = run_samples(case, plan)
    assert np.isfinite(here.values["mission_solved_time"]).sum() >= 25
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        there = run_samples(case, plan, dask_address=cluster.scheduler_address)
    for name in ("mission_landing_charge", "mission_solved_time"):
        np.testing.assert_array_equal(here.values[name], there.values[name])


def test_solve_for_per_row_ends_at_the_cut_off_where_the_packs_cut_off_first(tmp_path) -> None:
    """A high cut-off ends the solved cruise before the reserve: the voltage's root per
    row, the single case's (its 'ends_at: cut-off') to 1e-9."""
    mission = tmp_path / "airborne.yaml"
    mission.write_text(AIRBORNE + "solve_for: cruise\n")
    case = load_case(_case(tmp_path, mission))
    cutoffs = [3.4, 3.7, 3.8]
    values = {"battery.cutoff_voltage_per_cell_v": np.array(cutoffs)}
    out = sampled_landing(mission_for(case, list(values)), evaluator_for(case), values, 3,
                          None, None, STEPS)
    for row, cutoff in enumerate(cutoffs):
        one = with_values(case, {"battery.cutoff_voltage_per_cell_v": cutoff})
        flown = solve_mission(one, load_mission(mission), 0.2)
        assert flown.solved["ends_at"] == ("landing reserve" if row == 0 else "cut-off")
        assert out["mission_solved_time"][0][row] == pytest.approx(flown.solved["time_min"],
                                                                   rel=1e-9)
        assert out["mission_landing_charge"][0][row] == pytest.approx(
            flown.landing_charge_fraction, rel=1e-9)


def test_what_the_batch_does_not_fly_is_named(tmp_path) -> None:
    from tuflexperf.analysis.mission_samples import why_not_sampled

    model = mission_for(load_case(_case(tmp_path, SHIPPED_MISSION)), [])
    assert why_not_sampled(model, ["requirements.takeoff.max_ground_roll_m",
                                   "requirements.envelope.min_airspeed_m_s",
                                   "aircraft.cl_max", "battery.mission.pattern_altitude_m"]) is None
    assert why_not_sampled(model, ["battery.capacity_ah", "aircraft.launch_energy_j"]) is None
    assert "aircraft.nonsense" in why_not_sampled(model, ["aircraft.nonsense"])


def test_a_loiter_at_its_best_endurance_airspeed_is_sampled_row_by_row(tmp_path) -> None:
    """No airspeed_m_s: each row loiters at its own airspeed of least power (the single
    plan's grid and golden section, per row); a row with no level flight is not met."""
    mission = tmp_path / "best.yaml"
    mission.write_text(AIRBORNE.replace("airspeed_m_s: 21, ", ""))
    batch, single = _rows_and_single(_case(tmp_path, mission), {
        "aircraft.mass_kg": [26.7064, 29.0, 24.0, 60.0], "aircraft.cd0": [0.04307, 0.03, 0.05,
                                                                          0.04]})
    assert np.all(np.isfinite(batch[:3])) and np.isnan(batch[3]) and np.isnan(single[3])
    assert batch == pytest.approx(single, rel=1e-9, nan_ok=True)


def _variant(tmp_path: Path, file_key: str, changes: dict, mission: Path = SHIPPED_MISSION
             ) -> Path:
    """The mission case with the aircraft or propulsion file changed by ``changes``."""
    path = _case(tmp_path, mission)
    data = yaml.safe_load(path.read_text())
    content = yaml.safe_load(Path(data[file_key]).read_text())
    content.update(changes)
    changed = tmp_path / f"{file_key}.yaml"
    changed.write_text(yaml.safe_dump(content))
    data[file_key] = str(changed)
    path.write_text(yaml.safe_dump(data))
    return path


def _rows_and_single(path: Path, draws: dict[str, list[float]]) -> tuple[np.ndarray, list]:
    case = load_case(path)
    values = {k: np.array(v, dtype=float) for k, v in draws.items()}
    model = mission_for(case, list(values))
    assert model is not None  # sampled, not refused
    size = len(next(iter(draws.values())))
    batch = sampled_landing(model, evaluator_for(case), values, size, None, None, STEPS)[
        "mission_landing_charge"][0]
    single: list[float] = []
    for row in range(size):
        one = with_values(case, {k: v[row] for k, v in draws.items()})
        try:
            flown = solve_mission(one, load_mission(model.mission.path), 0.2)
            single.append(flown.landing_charge_fraction if flown.attainable else np.nan)
        except NotAttainable:  # refused at its plan (the launch): not attainable
            single.append(np.nan)
    return batch, single


def test_a_catapult_launch_is_sampled_row_by_row(tmp_path) -> None:
    """Released airborne: a row whose catapult cannot give the release speed is not met,
    the others the single case to rounding (the batch's own release check)."""
    path = _variant(tmp_path, "aircraft", {"launch": "catapult", "launch_speed_m_s": 20.0,
                                           "launch_energy_j": 20000.0})
    batch, single = _rows_and_single(path, {
        "aircraft.launch_energy_j": [20000.0, 5000.0, 20000.0],
        "aircraft.mass_kg": [26.7, 26.7, 30.0]})
    assert np.isnan(batch[1]) and np.isnan(single[1])
    assert np.all(np.isfinite(batch[[0, 2]])) and batch[0] != batch[2]
    assert batch == pytest.approx(single, rel=1e-9, nan_ok=True)


def test_a_takeoff_on_sagging_packs_is_sampled_row_by_row(tmp_path) -> None:
    """With a reference voltage the roll's airspeed history and the arc's and climb's
    gradients are the take-off on the packs (one code for one row or many): each row the
    single case's to 1e-8."""
    path = _variant(tmp_path, "propulsion", {"reference_voltage_v": 46.0,
                                             "voltage_exponent": 1.5})
    batch, single = _rows_and_single(path, {"aircraft.mass_kg": [26.7064, 29.0, 25.0],
                                            "atmosphere.temperature_offset_k": [0.0, 10.0, -5.0]})
    assert np.all(np.isfinite(batch)) and len(set(np.round(batch, 6))) == 3
    assert batch[0] == pytest.approx(single[0], rel=1e-9)  # the nominal row
    assert batch == pytest.approx(single, rel=1e-8)


def test_a_cruise_at_a_fixed_throttle_is_sampled_row_by_row(tmp_path) -> None:
    """The airspeed is solved per row (the fast root of level flight at that throttle, as
    the single case's plan finds it); a row that holds no level flight is not met."""
    mission = tmp_path / "fixed.yaml"
    mission.write_text(SHIPPED_MISSION.read_text().replace(
        "{type: cruise, airspeed_m_s: 26, time_min: 8}", "{type: cruise, throttle: 0.6, "
        "time_min: 8}"))
    batch, single = _rows_and_single(_case(tmp_path, mission), {
        "aircraft.mass_kg": [26.7064, 33.0, 45.0], "aircraft.cd0": [0.04307, 0.03, 0.06],
        "atmosphere.temperature_offset_k": [0.0, 10.0, -5.0]})
    assert np.all(np.isfinite(batch[:2])) and batch[0] != batch[1]
    assert np.isnan(batch[2]) and np.isnan(single[2])
    assert batch == pytest.approx(single, rel=1e-9, nan_ok=True)


def test_a_drawn_capacity_is_flown_row_by_row(tmp_path) -> None:
    """battery.capacity_ah drawn: each row flies the circuit of its own packs (charge x the
    ratio, resistance / the ratio), the landing fraction of its own capacity and its own
    rating; a pack too small to take off is not met. solve_for too."""
    batch, single = _rows_and_single(_case(tmp_path, SHIPPED_MISSION), {
        "battery.capacity_ah": [5.0, 1.5, 6.5], "aircraft.mass_kg": [26.7064, 26.7064, 26.0]})
    assert np.isnan(batch[1]) and np.isnan(single[1])
    assert batch[2] > batch[0] and batch == pytest.approx(single, rel=1e-9, nan_ok=True)
    mission = tmp_path / "airborne.yaml"
    mission.write_text(AIRBORNE + "solve_for: cruise\n")
    case = load_case(_case(tmp_path, mission))
    values = {"battery.capacity_ah": np.array([4.0, 6.0])}
    out = sampled_landing(mission_for(case, list(values)), evaluator_for(case), values, 2,
                          None, None, STEPS)["mission_solved_time"][0]
    for row, capacity in enumerate([4.0, 6.0]):
        one = with_values(case, {"battery.capacity_ah": capacity})
        flown = solve_mission(one, load_mission(mission), 0.2)
        assert out[row] == pytest.approx(flown.solved["time_min"], rel=1e-9)


def test_a_fixed_throttle_cruise_on_a_braking_fan_is_not_met(tmp_path) -> None:
    """A small, clean wing cruises so fast that one fan's models give no thrust (or thrust
    on no power): the single case ends the flight there, and so does the row (it landed
    with 91 % in the batch)."""
    mission = tmp_path / "cruise.yaml"
    mission.write_text("name: cruise\nsegments:\n  - {type: cruise, throttle: 0.6, "
                       "time_min: 3}\n")
    batch, single = _rows_and_single(_case(tmp_path, mission), {
        "aircraft.cd0": [0.04307, 0.003], "aircraft.wing_area_m2": [0.36, 0.36]})
    assert np.isfinite(batch[0]) and np.isnan(batch[1]) and np.isnan(single[1])
    assert batch[0] == pytest.approx(single[0], rel=1e-9)


@pytest.mark.parametrize("variant", ["shipped", "airborne", "sagging packs", "fixed throttle"])
def test_numpy_rows_are_the_single_cases_casadi_flight_node_by_node(tmp_path, variant) -> None:
    """The rows (numpy) and the single case's chained CasADi function, at the same 64 steps:
    every node's state and aux output to 1e-9 relative (the flight read from the packs where
    a reference voltage couples them, Newton on the loaded voltages)."""
    from tuflexperf.analysis.mission_rows import fly_rows

    mission = SHIPPED_MISSION
    if variant == "airborne":
        mission = tmp_path / "airborne.yaml"
        mission.write_text(AIRBORNE)
    if variant == "fixed throttle":
        mission = tmp_path / "fixed.yaml"
        mission.write_text(SHIPPED_MISSION.read_text().replace(
            "{type: cruise, airspeed_m_s: 26, time_min: 8}", "{type: cruise, throttle: 0.6, "
            "time_min: 8}"))
    path = (_variant(tmp_path, "propulsion", {"reference_voltage_v": 46.0,
                                              "voltage_exponent": 1.5})
            if variant == "sagging packs" else _case(tmp_path, mission))
    model = mission_for(load_case(path), [])
    single = [np.asarray(x, dtype=float)
              for x in model._history(model.durations, model.theta, model.par, model.tk)]
    states, aux, bounds = fly_rows(model, model.durations[:, None], model.theta[:, None],
                                   model.par, model.tk[None], model.tk_layout, STEPS)
    assert bounds == model.bounds
    for rows, reference in ((states[:, 0], single[0]), (aux[:, 0], single[1])):
        finite = np.isfinite(reference)
        assert np.array_equal(np.isfinite(rows), finite) and finite.mean() > 0.9
        scale = np.maximum(np.abs(reference[finite]), 1e-3)
        assert np.max(np.abs(rows[finite] - reference[finite]) / scale) < 1e-9


def test_sampled_steps_move_the_landing_far_less_than_the_monte_carlo_error(tmp_path) -> None:
    """The sampled mission flies SAMPLED_STEPS a segment, not the single case's 64: on 400
    draws of the shipped case the landing charge moves by at most 1e-6 (relative), the same
    rows not met."""
    from tuflexperf.analysis.uncertainty import draw_chunk, plan_for

    case = load_case(_case(tmp_path, SHIPPED_MISSION))
    plan = plan_for(case, samples=400, seed=2)
    draw = draw_chunk(case, plan, 0)
    model = mission_for(case, list(draw.values))

    def landing(steps: int) -> np.ndarray:
        return sampled_landing(model, evaluator_for(case), draw.values, draw.size,
                               draw.coefficients, draw.extrapolation_n, steps)[
            "mission_landing_charge"][0]

    fine, coarse = landing(STEPS), landing(SAMPLED_STEPS)
    assert SAMPLED_STEPS < STEPS
    assert np.array_equal(np.isfinite(fine), np.isfinite(coarse))
    assert np.count_nonzero(np.isfinite(fine)) > 300
    assert coarse == pytest.approx(fine, rel=1e-6, nan_ok=True)
    assert not np.array_equal(coarse, fine)  # the steps are flown, not ignored


def test_the_readings_sharing_a_batchs_flights_fly_what_each_flies_alone(tmp_path) -> None:
    """The nominal case and its readings (the measured power, the dead engine's drag)
    share one Memo in a batch: each reading's landing is the one it flies alone, bit for
    bit, and the readings differ from the nominal (they were flown, not copied)."""
    from tuflexperf.analysis.batch_readings import readings_evaluator
    from tuflexperf.analysis.mission_rows import Memo
    from tuflexperf.analysis.uncertainty import draw_chunk, plan_for

    case = load_case(_case(tmp_path, SHIPPED_MISSION))
    plan = plan_for(case, samples=300, seed=3)
    draw = draw_chunk(case, plan, 0)
    readings = [r for r in readings_evaluator(case, drawn=plan.extrapolation).all_readings
                if "mission" in r.affects]
    assert {r.key for r in readings} >= {"measured_power", "windmilling_model_drag"}
    cases = [case] + [r.case for r in readings]
    memo = Memo()

    def landing(on, shared) -> np.ndarray:
        return sampled_landing(mission_for(on, list(draw.values)), evaluator_for(on),
                               draw.values, draw.size, draw.coefficients,
                               draw.extrapolation_n, memo=shared)["mission_landing_charge"][0]

    together = [landing(on, memo) for on in cases]
    alone = [landing(on, None) for on in cases]
    for shared, own in zip(together, alone, strict=True):
        assert np.array_equal(shared, own, equal_nan=True)
    assert np.count_nonzero(np.isfinite(together[0])) > 200
    for other in together[1:]:
        assert not np.array_equal(other, together[0], equal_nan=True)


@pytest.mark.parametrize("variant", ["sagging packs", "fixed throttle"])
def test_a_rows_landing_is_its_own_whatever_rows_fly_beside_it(tmp_path, variant) -> None:
    """Where the stages are solved (the loaded voltage, a fixed throttle's airspeed) each row
    stops at its own convergence: three rows flown together land bit for bit as each flown
    alone (the batches, the two cores' halves split rows anywhere)."""
    (tmp_path / "fixed.yaml").write_text(SHIPPED_MISSION.read_text().replace(
        "{type: cruise, airspeed_m_s: 26, time_min: 8}",
        "{type: cruise, throttle: 0.6, time_min: 8}"))
    path = (_variant(tmp_path, "propulsion", {"reference_voltage_v": 46.0,
                                              "voltage_exponent": 1.5})
            if variant == "sagging packs" else _case(tmp_path, tmp_path / "fixed.yaml"))
    case = load_case(path)
    draws = {k: np.array(v) for k, v in DRAWS.items()}
    model = mission_for(case, list(draws))

    def landing(rows: list[int]) -> np.ndarray:
        values = {k: v[rows] for k, v in draws.items()}
        return sampled_landing(model, evaluator_for(case), values, len(rows), None, None,
                               SAMPLED_STEPS)["mission_landing_charge"][0]

    together = landing([0, 1, 2])
    alone = np.concatenate([landing([i]) for i in range(3)])
    assert np.count_nonzero(np.isfinite(together)) >= 2
    assert np.array_equal(together, alone, equal_nan=True)



def test_a_drawn_power_scale_is_flown_as_the_correction_law_that_scales_every_fan(
        tmp_path) -> None:
    """The drawn power scale (the power model's and the battery fit's errors) reaches the
    sampled mission: a row at scale 1 is the unscaled row exactly, more power lands with less
    charge (the take-off's packs too), and an airborne row at scale s is the mission flown with
    a measured-power law r = s on every fan (the reading's path, held to the single case by
    the measured-power tests)."""
    import copy
    import dataclasses

    from tuflexperf.models.power_correction import PowerCorrection

    name = "mission_landing_charge"
    scale = np.array([1.0, 1.08, 0.93])
    values = {"aircraft.mass_kg": np.array([22.0, 22.0, 22.0])}
    case = load_case(_case(tmp_path, SHIPPED_MISSION))
    model = mission_for(case, list(values))
    plain = sampled_landing(model, evaluator_for(case), values, 3, None, None, STEPS)[name][0]
    scaled = sampled_landing(model, evaluator_for(case), values, 3, None, None, STEPS,
                             power_scale=scale)[name][0]
    assert scaled[0] == plain[0]
    assert scaled[1] < plain[0] < scaled[2]

    mission = tmp_path / "airborne.yaml"
    mission.write_text(AIRBORNE)
    case = load_case(_case(tmp_path, mission))
    model = mission_for(case, list(values))
    scaled = sampled_landing(model, evaluator_for(case), values, 3, None, None, STEPS,
                             power_scale=scale)[name][0]
    for row, s in enumerate(scale):
        law = PowerCorrection(float(s), 0.0, 0.0, (0.0, 1.0), (0.0, 1e3))
        with_law = copy.copy(model)  # the process's model stays as it is
        with_law.fan_power = dataclasses.replace(model.fan_power, power_correction=law)
        with_law.case = dataclasses.replace(case, propulsion=dataclasses.replace(
            case.propulsion, engines=tuple(dataclasses.replace(e, power_correction=law)
                                           for e in case.propulsion.engines)))
        one = {"aircraft.mass_kg": np.array([22.0])}
        flown = sampled_landing(with_law, evaluator_for(case), one, 1, None, None, STEPS)
        assert flown[name][0][0] == pytest.approx(scaled[row], rel=1e-12)
