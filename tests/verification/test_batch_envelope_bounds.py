"""Envelope bounds that vary per row of a batch (SPEC 4: "any numeric key of the case").

Verification: each row flies its own airspeed grid, the same numbers as the single case's
(:func:`airspeed_grid`), so a batch row equals ``check`` with ``--set`` on those bounds; an
equivalent-airspeed bound follows each row's density. Rows whose bounds cross are bad input
for a sweep (as the single case is) and not met, counted, for samples.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from tests.conftest import SHIPPED_CASE, copy_shipped_case
from tests.verification.test_batch_equals_deterministic import assert_equal_to_deterministic
from tests.verification.test_margins import deterministic
from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.level_flight import MAX_GRID_STEP_M_S, airspeed_grid, airspeed_grids
from tuflexperf.analysis.margins import limit_values, margin_parameters, sensitivities
from tuflexperf.analysis.requirements import check_case
from tuflexperf.cli import app
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values

runner = CliRunner()
SHIPPED_ENVELOPE = "envelope: {min_airspeed_m_s: 15, max_airspeed_m_s: 45, max_trim_throttle: 1.0}"
MAX = "requirements.envelope.max_airspeed_m_s"
MIN = "requirements.envelope.min_airspeed_m_s"


def _eas_case(tmp_path, altitude_m: float = 2000.0,
              bounds: str = "min_airspeed_eas_m_s: 30, max_airspeed_m_s: 42"):
    """The shipped case at ``altitude_m`` with its least airspeed an EAS of 30 m/s."""
    path = copy_shipped_case(tmp_path)
    text = path.read_text().replace(
        SHIPPED_ENVELOPE, f"envelope: {{{bounds}, max_trim_throttle: 1.0}}")
    path.write_text(text.replace("altitude_m: 0,", f"altitude_m: {altitude_m:g},"))
    return path


def test_each_row_of_the_grids_is_the_single_grid_to_the_bit() -> None:
    rng = np.random.default_rng(7)
    low = rng.uniform(0.0, 100.0, 3000)
    high = low + np.concatenate([MAX_GRID_STEP_M_S * rng.integers(1, 80, 100),  # exact steps
                                 rng.uniform(1e-6, 240.0, 2900)])
    grids = airspeed_grids(low, high)
    for i in range(low.size):
        single = airspeed_grid(low[i], high[i])
        assert np.array_equal(grids[i, :single.size], single)
        assert np.all(grids[i, single.size:] == high[i])  # padded with its greatest airspeed
        assert np.array_equal(single, np.linspace(low[i], high[i], single.size))
        assert np.max(np.diff(single)) <= MAX_GRID_STEP_M_S + 1e-12


def test_varied_bounds_equal_single_cases_with_those_bounds() -> None:
    case = load_case(SHIPPED_CASE)
    sets = [
        {MIN: 15.0, MAX: 45.0},  # the nominal
        {MIN: 15.0, MAX: 40.0},
        {MIN: 18.3, MAX: 45.0},  # OEI's least throttle moves with the foot
        {MIN: 20.0, MAX: 21.0},  # a narrow envelope: few grid points, the rest padded
        {MIN: 10.0, MAX: 45.0},  # below stall at the foot: not attainable in both
        {MIN: 15.0, MAX: 55.0},  # beyond full throttle: not attainable in both
        {MIN: 16.0, MAX: 30.0, "aircraft.mass_kg": 30.0},
    ]
    keys = sorted({k for s in sets for k in s})
    nominal = {MIN: 15.0, MAX: 45.0, "aircraft.mass_kg": case.aircraft.mass_kg}
    values = {k: np.array([s.get(k, nominal[k]) for s in sets]) for k in keys}
    result = BatchEvaluator(case).evaluate(values)
    for row, s in enumerate(sets):
        assert_equal_to_deterministic(with_values(case, s), result.values, row)
    assert math.isnan(result.values["trim_throttle_max"][4])
    assert math.isnan(result.values["trim_throttle_max"][5])
    assert result.values["oei_min_throttle"][2] > result.values["oei_min_throttle"][0]


def test_equivalent_airspeed_bounds_follow_each_rows_density(tmp_path) -> None:
    case = load_case(_eas_case(tmp_path))
    sets = [{"atmosphere.altitude_m": h, "atmosphere.temperature_offset_k": dt}
            for h, dt in ((0.0, 0.0), (1000.0, 10.0), (2000.0, 0.0), (3000.0, -15.0))]
    values = {k: np.array([s[k] for s in sets]) for k in sets[0]}
    result = BatchEvaluator(case).evaluate(values)
    for row, s in enumerate(sets):
        assert_equal_to_deterministic(with_values(case, s), result.values, row)
    # the least throttle's airspeed moves with the density: one shared grid would not
    trims = result.values["trim_throttle_max"]
    assert len(set(np.round(trims, 9))) == len(sets)


def test_crossed_bounds_have_no_envelope_and_the_other_rows_solve() -> None:
    case = load_case(SHIPPED_CASE)
    evaluator = BatchEvaluator(case)
    values = {MAX: np.array([45.0, 14.0, 15.0, 400.0, 40.0])}
    none = evaluator.rows_without_envelope(values, 5)
    assert none.tolist() == [False, True, True, True, False]
    result = evaluator.evaluate(values)
    for name in ("trim_throttle_max", "oei_min_throttle"):
        assert np.isnan(result.values[name][none]).all()
        assert np.isfinite(result.values[name][~none]).all()
    assert np.isfinite(result.values["takeoff_ground_roll"]).all()  # no envelope in a roll


def test_a_sweep_over_the_bounds_is_the_single_case_at_each_point() -> None:
    # tops to 40 m/s: beyond, trim at the thrust's 90 % bound is not attainable
    result = runner.invoke(app, ["sweep", "--json", "--vary", f"{MAX}=36:40:3",
                                 "--vary", f"{MIN}=15:19:2"])
    assert result.exit_code == 0, result.stderr
    rows = json.loads(result.stdout)["rows"]
    case = load_case(SHIPPED_CASE)
    assert len(rows) == 6
    for row in rows:
        single = {v.name: v.value for v in check_case(
            with_values(case, {MAX: row[MAX], MIN: row[MIN]}))}
        for name in ("trim_throttle_max", "oei_min_throttle"):
            assert row[name]["value"] == pytest.approx(single[name], rel=1e-9)


@pytest.mark.parametrize(("vary", "message"), [
    (f"{MAX}=10:45:8", f"--vary: {MAX}=10: min_airspeed_m_s (15.0) must be below"),
    ("atmosphere.altitude_m=0:8000:3",
     "--vary: at atmosphere.altitude_m=8000: requirements.envelope: the least airspeed "
     "45.82 m/s is not below the greatest 42.00 m/s"),
])
def test_a_sweep_point_without_an_envelope_is_bad_input(tmp_path, vary, message) -> None:
    result = runner.invoke(app, ["sweep", "--case", str(_eas_case(tmp_path) if "altitude"
                                                        in vary else SHIPPED_CASE),
                                 "--vary", vary])
    assert result.exit_code == 2 and message in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_samples_of_crossed_bounds_count_as_not_met_and_are_said(tmp_path) -> None:
    path = copy_shipped_case(tmp_path)
    # an endurance every reading meets (the shipped 15 min is UNPROVEN: the discharge runs)
    path.write_text(path.read_text().replace("min_flight_time_min: 15",
                                             "min_flight_time_min: 12") + (
        "uncertainty:\n  samples: 400\n  seed: 3\n"
        # the envelope bound the only draw: the thrust, rig and power errors left out, so
        # that the take-off and the endurance have nothing of their own to miss on
        "  propulsion: {covariance: false, extrapolation: false, model_form: false, rig: false,"
        " power_model: false, battery_fit: false}\n  parameters:\n"
        f"    {MAX}: {{uniform: [10, 45]}}\n"))
    result = runner.invoke(app, ["check", str(path), "--json"])
    assert result.exit_code == 1, result.stderr
    data = json.loads(result.stdout)
    crossed = data["uncertainty"]["samples_outside_bounds"]["requirements.envelope"]
    # max drawn uniform on [10, 45] against a least airspeed of 15: 5/35 of the samples
    assert crossed == pytest.approx(400 * 5 / 35, abs=4 * math.sqrt(400 * 5 / 35))
    results = {r["name"]: r for r in data["results"]}
    assert results["trim_throttle_max"]["probability"] <= 1.0 - crossed / 400  # not met there
    # the aircraft still takes off and flies its endurance: those are the sample's own
    assert results["takeoff_ground_roll"]["probability"] == 1.0
    assert results["flight_endurance"]["probability"] == 1.0
    text = runner.invoke(app, ["check", str(path)]).stdout
    assert f"note: {crossed} samples have no envelope" in text
    assert "trim and OEI count them as not met" in text


def test_bounds_outside_their_range_build_no_long_grid() -> None:
    """A least airspeed drawn at -3000 m/s (counted outside its range) built a 6000-point
    grid per row: 3.7 GB for 2500 samples (outside audit). It has no envelope now."""
    case = load_case(SHIPPED_CASE)
    evaluator = BatchEvaluator(case)
    values = {MIN: np.array([-3000.0, 0.0, -1e6, 15.0])}
    assert evaluator.rows_without_envelope(values, 4).tolist() == [True, True, True, False]
    grid, none = evaluator._grids(values, case.density_kg_m3, 4)
    assert grid.shape[1] == airspeed_grid(15.0, 45.0).size and none[:3].all()


def test_a_batch_of_a_case_without_an_envelope_says_so() -> None:
    """sweep printed an AttributeError traceback for a case with an OEI requirement and no
    envelope block (outside audit); check says the envelope is missing, and so does it."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        path = copy_shipped_case(Path(folder))
        path.write_text(path.read_text().replace(f"  {SHIPPED_ENVELOPE}\n", ""))
        for args in (["check", str(path)],
                     ["sweep", "--case", str(path), "--vary", "aircraft.mass_kg=20:25:3"]):
            result = runner.invoke(app, args)
            assert result.exit_code == 2, (args, result.output)
            assert "requirements.envelope: missing" in result.stderr


def test_margins_say_where_an_envelope_ends(tmp_path) -> None:
    """An EAS least airspeed passes the true greatest at some altitude: trim's margin there
    is the envelope ending (the single case is bad input beyond), not trim failing."""
    # P(met) >= 0.55: at the default 0.9 trim at 45 m/s is not attainable at the thrust's bound
    case = with_values(load_case(_eas_case(tmp_path, 0.0, "min_airspeed_eas_m_s: 40, "
                                                          "max_airspeed_m_s: 45")),
                       {"requirements.extrapolation.required_probability": 0.55})
    limits = limit_values(case, {"atmosphere.altitude_m": 0.0})
    value, binds, _ = limits[("trim_throttle_max", "atmosphere.altitude_m")]
    assert binds == "envelope ends"
    below = with_values(case, {"atmosphere.altitude_m": value - 1.0})
    trim = {v.name: v for v in check_case(below)}["trim_throttle_max"]
    assert trim.passed and trim.margin > 0.01  # trim holds with room right up to the end
    beyond = runner.invoke(app, ["check", str(case.path), "--set",
                                 f"atmosphere.altitude_m={value + 1.0}"])
    assert beyond.exit_code == 2 and "is not below the greatest" in beyond.stderr
    shown = runner.invoke(app, ["margins", "--case", str(case.path), "--set",
                                "requirements.extrapolation.required_probability=0.55"])
    assert "^: where the envelope's bounds cross" in shown.stdout


def test_a_bound_of_the_other_kind_is_named_in_a_batch() -> None:
    result = runner.invoke(app, ["sweep", "--vary",
                                 "requirements.envelope.max_airspeed_eas_m_s=40:44:2"])
    assert result.exit_code == 2
    assert "gives this bound as a true airspeed; vary requirements.envelope.max_airspeed_m_s" \
        in result.stderr


def test_margins_over_the_atmosphere_follow_an_equivalent_airspeed_bound(tmp_path) -> None:
    """margins left the atmosphere out of a case with EAS bounds (one grid for all rows):
    the sensitivities are those of the grid that moves with the density."""
    # both bounds equivalent airspeeds, so trim's highest throttle (at the greatest) and OEI's
    # least (inside the envelope) sit at airspeeds that move with the density
    case = load_case(_eas_case(tmp_path, 1000.0,
                               "min_airspeed_eas_m_s: 22, max_airspeed_eas_m_s: 38"))
    keys = ["atmosphere.altitude_m", "atmosphere.temperature_offset_k"]
    assert set(keys) <= set(margin_parameters(case))
    slopes = sensitivities(case, keys)
    verdicts = check_case(case)
    assert all(v.value is not None for v in verdicts)
    for verdict in verdicts:  # the sensitivities fly the case as given (the first reading)
        for key in keys:
            nominal = getattr(case.atmosphere, key.split(".")[1])
            # as test_margins: the endurance's climb-speed grid needs the finer step
            scale = 1e-6 if verdict.name == "flight_endurance" else 1e-5
            step = scale * max(abs(nominal), 1.0)
            central = (deterministic(case, key, nominal + step, verdict.name, nominal=True)
                       - deterministic(case, key, nominal - step, verdict.name,
                                       nominal=True)) / (2 * step)
            noise = 1e-9 * abs(verdict.value) / step
            assert slopes[verdict.name][key] == pytest.approx(central, rel=1e-3, abs=noise), (
                verdict.name, key)


def test_a_batch_refuses_the_aircraft_a_single_case_refuses(tmp_path) -> None:
    """A 0.01 kg draw of the 26.7 kg aircraft (static thrust 572 x its weight at the case's
    air) passed every requirement in a sweep, where check refuses it as physically absurd
    (outside audit)."""
    swept = runner.invoke(app, ["sweep", "--vary", "aircraft.mass_kg=0.01:1000:7"])
    assert swept.exit_code == 2 and len(swept.stderr.strip().splitlines()) == 1
    assert "--vary aircraft.mass_kg=0.01" in swept.stderr and "physically absurd" in \
        swept.stderr and "572 x the aircraft's weight (0.0981 N)" in swept.stderr
    single = runner.invoke(app, ["check", "--set", "aircraft.mass_kg=0.01"])
    assert single.exit_code == 2 and "physically absurd" in single.stderr
    path = copy_shipped_case(tmp_path)
    path.write_text(path.read_text() + (
        "uncertainty:\n  samples: 400\n  seed: 2\n  parameters:\n"
        "    aircraft.mass_kg: {uniform: [0.01, 1.1]}\n"))
    result = runner.invoke(app, ["check", str(path), "--json"])
    data = json.loads(result.stdout)
    absurd = data["uncertainty"]["samples_outside_bounds"]["aircraft"]
    # each fan's 55.1 N static thrust is 10 x the weight of 0.562 kg
    share = (0.5618 - 0.01) / (1.1 - 0.01)
    assert absurd == pytest.approx(400 * share, abs=4 * math.sqrt(400 * share))
    roll = next(r for r in data["results"] if r["name"] == "takeoff_ground_roll")
    assert roll["probability"] <= 1.0 - absurd / 400 and result.exit_code == 1
    assert f"note: {absurd} samples are aircraft check refuses" in runner.invoke(
        app, ["check", str(path)]).stdout
