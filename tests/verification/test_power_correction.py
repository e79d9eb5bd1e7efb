"""The discharge runs' measured power as a correction law and as a reading (issue 43 item 2).

``fit`` stores measured over modelled power in the battery file (``fit.power_correction``);
the kernel multiplies it once (``engine_power_w``, the fan-power law) for the single case and
the batch alike; the reading flies the case on it; ``check`` opens no raw run.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import yaml

from tests.conftest import SHIPPED_CASE, copy_shipped_case, files_opened
from tuflexperf.analysis import battery_fit
from tuflexperf.analysis import endurance as endurance_module
from tuflexperf.analysis.power_reading import (
    case_measured_power,
    measured_power_readings,
    with_power_correction,
)
from tuflexperf.analysis.study import Study
from tuflexperf.io.case import load_case
from tuflexperf.models.power_correction import PowerCorrection
from tuflexperf.reduction.battery import fit_power_correction

BATTERY = SHIPPED_CASE.parent.parent / "data" / "tuflex" / "battery.yaml"
PROPULSION = SHIPPED_CASE.parent.parent / "data" / "tuflex" / "propulsion.yaml"


def _runs(*points: tuple[float, float, float]) -> list[SimpleNamespace]:
    return [SimpleNamespace(throttle_setting=x, airspeed_setting_m_s=v, mean_power_w=p,
                            path=Path(f"run{k}.csv")) for k, (x, v, p) in enumerate(points)]


def _poly22(c: dict[str, float], x: float, v: float) -> float:
    """The propulsion file's power surface, written out here (not the tool's poly22)."""
    return (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x * x + c["p11"] * x * v
            + c["p02"] * v * v)


# --- the law fitted by `fit` -------------------------------------------------------------
def test_the_form_follows_the_runs_settings() -> None:
    one = fit_power_correction(_runs((0.5, 30.0, 1300.0)), [1000.0])
    assert (one.constant, one.per_throttle, one.per_airspeed_s_m) == pytest.approx((1.3, 0, 0))
    # two throttles at one airspeed (30.001 and 30.005 m/s are one setting): linear in throttle
    two = fit_power_correction(_runs((0.5, 30.001, 1300.0), (0.75, 30.005, 2200.0)),
                               [1000.0, 2000.0])
    assert two.per_airspeed_s_m == 0.0
    assert float(two.ratio(0.5, 30.0)) == pytest.approx(1.3)
    assert float(two.ratio(0.75, 30.0)) == pytest.approx(1.1)
    # three runs at two throttles and two airspeeds: both terms, through every run
    three = _runs((0.5, 20.0, 1200.0), (0.75, 20.0, 2400.0), (0.5, 30.0, 1500.0))
    law = fit_power_correction(three, [1000.0, 2000.0, 1000.0])
    for run, model in zip(three, [1000.0, 2000.0, 1000.0], strict=True):
        ratio = float(law.ratio(run.throttle_setting, run.airspeed_setting_m_s))
        assert ratio == pytest.approx(run.mean_power_w / model, rel=1e-12)
    # two runs differing in both: two points cannot fix three terms, so no airspeed term
    both = fit_power_correction(_runs((0.5, 20.0, 1200.0), (0.75, 30.0, 2400.0)),
                                [1000.0, 2000.0])
    assert both.per_throttle != 0.0 and both.per_airspeed_s_m == 0.0


def test_outside_its_span_the_law_is_held_at_the_tested_edge() -> None:
    law = PowerCorrection(2.0, -1.0, 0.0, (0.5, 0.75), (30.0, 30.0))
    assert float(law.ratio(1.0, 10.0)) == pytest.approx(float(law.ratio(0.75, 30.0)))
    assert float(law.ratio(0.2, 50.0)) == pytest.approx(1.5)
    assert law.extrapolates(0.6, 30.0) == []
    said = law.extrapolates(0.5, 27.6)
    assert said == ["27.6 m/s outside the runs' 30.0 m/s"]


def test_floats_arrays_and_casadi_give_the_same_corrected_power() -> None:
    import casadi as ca

    from tuflexperf.models.powertrain import engine_power_w

    case = load_case(SHIPPED_CASE)
    law = PowerCorrection(1.9, -1.2, 0.003, (0.5, 0.75), (20.0, 30.0))
    engine = with_power_correction(case, law).propulsion.engines[0]
    plain = case.propulsion.engines[0]
    xs, vs = np.array([0.3, 0.6, 1.0]), np.array([10.0, 25.0, 35.0])
    arrays = np.asarray(engine_power_w(engine, xs, vs), dtype=float)
    x, v = ca.SX.sym("x"), ca.SX.sym("v")
    function = ca.Function("p", [x, v], [engine_power_w(engine, x, v)])
    for k in range(3):
        one = float(engine_power_w(engine, float(xs[k]), float(vs[k])))
        assert arrays[k] == pytest.approx(one, rel=1e-14)
        assert float(function(xs[k], vs[k])) == pytest.approx(one, rel=1e-14)
        held_x = min(max(xs[k], 0.5), 0.75)
        held_v = min(max(vs[k], 20.0), 30.0)
        ratio = 1.9 - 1.2 * held_x + 0.003 * held_v
        assert one == pytest.approx(ratio * float(engine_power_w(plain, xs[k], vs[k])), rel=1e-14)


def test_the_shipped_correction_is_the_runs_over_the_power_surface() -> None:
    """Each run's stored ratio is its fit.runs mean power over EDF1's surface there, computed
    here from the two files' numbers."""
    fit = yaml.safe_load(BATTERY.read_text())["fit"]
    surface = yaml.safe_load(PROPULSION.read_text())["engines"][0]["power"]["coefficients"]
    block = fit["power_correction"]
    assert block["form"] == "linear in throttle" and block["propulsion"] == "propulsion.yaml"
    assert block["throttle_span"] == [0.5, 0.75]
    for run, stored in zip(fit["runs"], block["runs"], strict=True):
        model = _poly22(surface, run["throttle"], run["airspeed_m_s"])
        assert stored["file"] == run["file"]
        assert stored["model_power_w"] == pytest.approx(model, rel=1e-12)
        assert stored["ratio"] == pytest.approx(run["mean_power_w"] / model, rel=1e-12)
        law = block["constant"] + block["per_throttle"] * run["throttle"]
        assert law == pytest.approx(stored["ratio"], rel=1e-12)


def test_fit_writes_the_shipped_correction(tmp_path: Path) -> None:
    from tuflexperf.reduction.battery import fitted_battery_text

    copy_shipped_case(tmp_path)
    battery = tmp_path / "data" / "tuflex" / "battery.yaml"
    _, block = fitted_battery_text(battery, tmp_path / "data" / "tuflex" / "refit.yaml")
    shipped = yaml.safe_load(BATTERY.read_text())["fit"]["power_correction"]
    written = block["power_correction"]
    assert written.keys() == shipped.keys()
    for key in ("constant", "per_throttle", "per_airspeed_s_m"):
        assert written[key] == pytest.approx(shipped[key], rel=1e-9, abs=1e-12)
    # no propulsion file beside it, none named: no correction (fit cannot know the model)
    (tmp_path / "data" / "tuflex" / "propulsion.yaml").unlink()
    _, bare = fitted_battery_text(battery, tmp_path / "data" / "tuflex" / "refit2.yaml")
    assert "power_correction" not in bare


# --- the reading -------------------------------------------------------------------------
def test_the_shipped_case_has_a_measured_power_reading() -> None:
    case = load_case(SHIPPED_CASE)
    (reading,) = measured_power_readings(case)
    assert reading.key == "measured_power"
    assert {"endurance", "mission"} <= reading.affects
    assert reading.evidence.startswith("battery.yaml fit.power_correction (linear in throttle)")
    assert "edf1_endurance_50.csv measured 1328 W at throttle 0.50, 30.0 m/s" in reading.evidence
    assert "1001 W (-25 %)" in reading.evidence
    # the cruise flies 27.6 m/s, below the runs' 30 m/s: said, and what would settle it
    assert "27.6 m/s outside the runs' 30.0 m/s" in reading.evidence
    assert "extrapolated" in reading.evidence
    assert reading.settle == "a discharge run at 27.6 m/s"


def _independent_flight_min(case, result) -> float:
    """Climb plus a cruise integrated here (scipy) from the launch's charge to the landing
    reserve, two packs per fan at the measured power: the runs' ratio at throttle 0.5 times
    the larger fan surface at the cruise airspeed, written out from the files."""
    from scipy.integrate import solve_ivp

    fit = yaml.safe_load(BATTERY.read_text())["fit"]
    battery = yaml.safe_load(BATTERY.read_text())
    propulsion = yaml.safe_load(PROPULSION.read_text())
    surfaces = [e["power"]["coefficients"] for e in propulsion["engines"]]
    run = fit["runs"][0]
    assert run["throttle"] == 0.5
    ratio = run["mean_power_w"] / _poly22(surfaces[0], 0.5, run["airspeed_m_s"])
    speed = result.airspeed_m_s  # the thrust model's level flight: the same on either power
    rho_scale = case.density_kg_m3 / propulsion["reference_density_kg_m3"]
    power = ratio * rho_scale * max(_poly22(c, 0.5, speed) for c in surfaces)
    p = fit["parameters"]
    n = battery["packs_in_parallel_per_engine"]

    def current(q: float) -> float:
        s = q / n
        ocv = (p["e0_v"] - p["slope_v_per_ah"] * s + p["exp_amplitude_v"]
               * math.exp(-p["exp_rate_per_ah"] * s) - p["knee_v"] * s / (p["max_capacity_ah"] - s))
        r = p["resistance_ohm"] / n
        return (ocv - math.sqrt(ocv * ocv - 4 * r * power)) / (2 * r)

    reserve = n * battery["capacity_ah"] * (1 - battery["mission"]["landing_reserve_fraction"])

    def empty(_t: float, q: np.ndarray) -> float:
        return reserve - q[0]

    empty.terminal = True  # type: ignore[attr-defined]
    done = solve_ivp(lambda _t, q: [current(q[0]) / 3600.0], (0.0, 1e5),
                     [result.launch.charge_ah], events=empty, rtol=1e-10, atol=1e-12)
    return (done.t_events[0][0] + result.launch.climb_time_s) / 60.0


def test_the_shipped_case_flown_on_the_measured_power_is_about_14_min() -> None:
    case = load_case(SHIPPED_CASE)
    (reading,) = measured_power_readings(case)
    nominal = Study(case).endurance(0.5)
    measured = Study(reading.case).endurance(0.5)
    assert nominal.flight_endurance_min > 15.0  # the power model's PASS
    assert 13.0 < measured.flight_endurance_min < 15.0  # the measured power's FAIL
    assert measured.airspeed_m_s == pytest.approx(nominal.airspeed_m_s, rel=1e-9)
    assert measured.flight_endurance_min == pytest.approx(
        _independent_flight_min(case, measured), rel=1e-6)
    # the runs and the corrected model now agree: no disagreement note on this reading
    assert not any("data disagree" in w for w in measured.warnings)
    assert any("data disagree" in w for w in nominal.warnings)


def test_the_batch_of_one_flies_the_same_corrected_endurance() -> None:
    from tuflexperf.analysis.batch import BatchEvaluator

    case = load_case(SHIPPED_CASE)
    (reading,) = measured_power_readings(case)
    batch = BatchEvaluator(reading.case).evaluate().values["flight_endurance"][0]
    single = Study(reading.case).endurance(0.5).flight_endurance_min
    assert float(batch) == pytest.approx(single, rel=1e-9)
    assert float(batch) < BatchEvaluator(case).evaluate().values["flight_endurance"][0]


def _edited_case(tmp_path: Path, edit) -> Path:
    case_file = copy_shipped_case(tmp_path)
    path = tmp_path / "data" / "tuflex" / "battery.yaml"
    data = yaml.safe_load(path.read_text())
    edit(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return case_file


def test_no_reading_without_a_correction_or_within_the_tolerance(tmp_path: Path) -> None:
    bare = _edited_case(tmp_path / "bare", lambda d: d["fit"].pop("power_correction"))
    assert measured_power_readings(load_case(bare)) == ()

    # EDF1's surface raised by 310 W at throttle 0.5 and by nothing at 0.75: both runs within
    # 2 % of it, inside the 10 % the note uses
    agree = copy_shipped_case(tmp_path / "agree")
    path = agree.parent.parent / "data" / "tuflex" / "propulsion.yaml"
    data = yaml.safe_load(path.read_text())
    power = data["engines"][0]["power"]["coefficients"]
    power["p00"] += 930.0
    power["p10"] -= 1240.0
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    measured = case_measured_power(load_case(agree))
    assert measured is not None and measured.refitted and not measured.disagrees
    assert measured_power_readings(load_case(agree)) == ()


def test_a_scaled_power_surface_flies_the_same_measured_power(tmp_path: Path) -> None:
    """Surfaces scaled by 0.45 (issue 43): the file's law was fitted against the shipped
    surfaces, so it is fitted again from fit.runs against this case's; the measured power
    is the runs' whatever the model, and so is the endurance flown on it."""
    case_file = copy_shipped_case(tmp_path)
    path = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    data = yaml.safe_load(path.read_text())
    for engine in data["engines"]:
        engine["power"]["coefficients"] = {k: 0.45 * v for k, v in
                                           engine["power"]["coefficients"].items()}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    case = load_case(case_file)
    measured = case_measured_power(case)
    assert measured is not None and measured.refitted and measured.disagrees
    (reading,) = measured_power_readings(case)
    assert "fitted again from fit.runs" in reading.evidence
    shipped = measured_power_readings(load_case(SHIPPED_CASE))[0]
    assert (Study(reading.case).endurance(0.5).flight_endurance_min
            == pytest.approx(Study(shipped.case).endurance(0.5).flight_endurance_min, rel=1e-6))


def test_a_case_without_power_surfaces_corrects_the_fan_power_law(tmp_path: Path) -> None:
    case_file = copy_shipped_case(tmp_path)
    path = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    data = yaml.safe_load(path.read_text())
    for engine in data["engines"]:
        engine.pop("power")
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    case = load_case(case_file)
    measured = case_measured_power(case)
    assert measured is not None and measured.refitted
    assert "fan-power law" in measured.model
    # the law fitted through the runs and the published point: within 10 % of both runs,
    # so no reading; corrected, the fan law gives each run's measured power
    assert not measured.disagrees and measured_power_readings(case) == ()
    corrected = with_power_correction(case, measured.correction)
    ch = battery_fit.characterise_battery(battery_fit.cached_case_battery(corrected), corrected)
    assert ch.power.model.power_correction == measured.correction
    for _, x, v, power, _ in measured.runs:
        ratio = float(measured.correction.ratio(x, v))
        assert float(ch.power.model.electrical_power_w(x, v)) == pytest.approx(
            ratio * float(battery_fit.characterise_battery(
                battery_fit.cached_case_battery(case), case).power.model.electrical_power_w(x, v)))
        assert power > 0


# --- check opens no raw run --------------------------------------------------------------


def test_check_opens_no_discharge_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every file the endurance and the reading open is watched (Python's audit hook sees
    each open): neither run CSV is among them, and the note and the agreement check still
    come from the battery file's fit.runs."""
    battery_fit._characterisation_cache = battery_fit.BoundedCache()
    battery_fit._battery_cache = battery_fit.BoundedCache()
    endurance_module._model_cache = endurance_module.BoundedCache()
    with files_opened() as opened:
        case = load_case(SHIPPED_CASE)
        result = Study(case).endurance(0.5)
        (reading,) = measured_power_readings(case)
        Study(reading.case).endurance(0.5)
    assert any(name.endswith("battery.yaml") for name in opened)  # the hook does see opens
    assert not [name for name in opened if "endurance" in Path(name).parts
                or name.endswith((".csv", ".csv.gz", ".mat"))]
    assert any("fit.runs: edf1_endurance_50.csv: measured 1328 W" in w
               for w in result.warnings)


def test_fit_propulsion_names_the_model_the_correction_is_fitted_against(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from tuflexperf.cli import app

    copy_shipped_case(tmp_path)
    folder = tmp_path / "data" / "tuflex"
    moved = tmp_path / "elsewhere.yaml"
    (folder / "propulsion.yaml").rename(moved)
    out = folder / "refit.yaml"
    done = CliRunner().invoke(app, ["fit", str(folder / "battery.yaml"), "--out", str(out),
                                    "--propulsion", str(moved)])
    assert done.exit_code == 0, done.output
    assert "measured power correction (linear in throttle)" in done.stdout
    block = yaml.safe_load(out.read_text())["fit"]["power_correction"]
    assert block["propulsion"] == "../../elsewhere.yaml"
    shipped = yaml.safe_load(BATTERY.read_text())["fit"]["power_correction"]
    assert block["constant"] == pytest.approx(shipped["constant"], rel=1e-9)
    wrong = CliRunner().invoke(app, ["fit", str(tmp_path / "data" / "tuflex" / "campaign"
                                                / "campaign.yaml"), "--out",
                                     str(tmp_path / "p.yaml"), "--propulsion", str(moved)])
    assert wrong.exit_code == 2 and "--propulsion: only for a battery file" in wrong.output
