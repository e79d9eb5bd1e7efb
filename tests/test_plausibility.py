"""One plausibility rule, applied by every command (issue 43 item 3).

The shipped power surfaces scaled by 0.45 (figure of merit ~1.3 on the disk area) had
``check`` PASS with 43 min of endurance; scaled by 0.30 ``endurance`` refused while
``mission`` PASSed. Each rule is checked against an independent computation of momentum
theory here, and every command must give the same answer on the same data.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.conftest import ROOT, SHIPPED_CASE, tuflexperf
from tuflexperf.analysis.plausibility import BLOCKS, implausible
from tuflexperf.analysis.requirements import check_case
from tuflexperf.cli.inputs import load_case_with, replaced

PROPULSION = ROOT / "data" / "tuflex" / "propulsion.yaml"
MISSION = ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml"


def _scaled(tmp_path: Path, power: float = 1.0, thrust: float = 1.0,
            surfaces: bool = True) -> Path:
    """The shipped propulsion file with its power surfaces x ``power`` and its thrust
    coefficients x ``thrust`` (without ``surfaces``: no power surfaces at all)."""
    document = yaml.safe_load(PROPULSION.read_text())
    for engine in document["engines"]:
        engine["coefficients"] = {k: thrust * c for k, c in engine["coefficients"].items()}
        if not surfaces:
            del engine["power"]
        else:
            engine["power"]["coefficients"] = {k: power * c for k, c in
                                               engine["power"]["coefficients"].items()}
    path = tmp_path / f"propulsion_{power:g}_{thrust:g}_{surfaces}.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def _case(propulsion: Path | None = None, sets: list[str] | None = None):
    return load_case_with(SHIPPED_CASE, sets, replaced(None, propulsion, None))


def _worst_merit(case, power_of) -> dict[str, float]:
    """Per engine the largest figure of merit over throttle 0..1 x 0..45 m/s at working points
    (thrust >= 10 % of the static), by momentum theory written out here: a wake as wide as
    the disk, ``T = rho A v_e (v_e - V)``, ``P_i = T (V + v_e) / 2``."""
    prop, rho = case.propulsion, case.density_kg_m3
    sigma = rho / prop.reference_density_kg_m3
    x, v = np.meshgrid(np.linspace(0, 1, 41), np.linspace(0, 45, 91), indexing="ij")
    out = {}
    for engine in prop.engines:
        c = engine.coefficients
        thrust = sigma * (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x * x
                          + c["p11"] * x * v + c["p02"] * v * v)
        exit_v = (v + np.sqrt(v * v + 4 * np.maximum(thrust, 0) / (rho * prop.fan_area_m2))) / 2
        ideal = np.maximum(thrust, 0) * (v + exit_v) / 2
        working = thrust >= 0.1 * sigma * (c["p10"] + c["p20"] + c["p00"])
        with np.errstate(invalid="ignore", divide="ignore"):
            merit = np.where(working, ideal / power_of(engine, x, v), 0)
        out[engine.name] = float(np.max(merit))
    return out


def _surface(case):
    sigma = case.density_kg_m3 / case.propulsion.reference_density_kg_m3

    def power(engine, x, v):
        c = engine.power_coefficients
        return sigma * (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x * x
                        + c["p11"] * x * v + c["p02"] * v * v)
    return power


def test_the_shipped_case_is_plausible() -> None:
    case = _case()
    assert implausible(case) == ()
    assert max(_worst_merit(case, _surface(case)).values()) < 1.0


@pytest.mark.parametrize("scale", [0.45, 0.30])
def test_a_power_surface_below_momentum_theory_is_implausible(tmp_path, scale) -> None:
    case = _case(_scaled(tmp_path, power=scale))
    found = {f.engine: f for f in implausible(case)}
    expected = _worst_merit(case, _surface(case))
    assert set(found) == {e for e, merit in expected.items() if merit > 1} == {"EDF1", "EDF2"}
    for index, (name, f) in enumerate(found.items()):
        assert f.rule == "figure_of_merit" and f.blocks == BLOCKS
        assert f.value == pytest.approx(expected[name], rel=1e-9)
        assert str(case.propulsion_path) in f.reason
        assert f"engines[{index}] ({name}).power" in f.reason
        assert f"throttle {f.throttle:.2f}, {f.airspeed_m_s:.1f} m/s" in f.reason
        assert f"figure of merit {f.value:.2f}" in f.reason and "\n" not in f.reason


def test_a_power_surface_just_above_momentum_theory_is_plausible(tmp_path) -> None:
    """The rule's edge: the scale at which the worst figure of merit is 1, and either side."""
    case = _case()
    edge = max(_worst_merit(case, _surface(case)).values())
    assert implausible(_case(_scaled(tmp_path, power=edge * 1.001))) == ()
    assert implausible(_case(_scaled(tmp_path, power=edge * 0.999)))


def test_thrust_above_momentum_theory_for_the_battery_files_fan_power(tmp_path) -> None:
    """Without power surfaces the fans fly the battery file's fan-power law: a thrust model
    2.5 x the shipped one makes more thrust than momentum theory allows for that power."""
    plain = _case(_scaled(tmp_path, surfaces=False))
    assert implausible(plain) == ()
    strong = _case(_scaled(tmp_path, thrust=2.5, surfaces=False))
    found = implausible(strong)
    assert found and all(f.rule == "thrust_momentum" for f in found)
    from tuflexperf.analysis.pack_limits import pack_side

    law = pack_side(strong).power

    def power(engine, x, v):
        return law.electrical_power_w(x, v)
    expected = _worst_merit(strong, power)
    for f in found:
        assert f.value == pytest.approx(expected[f.engine], rel=1e-9) and f.value > 1
        assert ".coefficients" in f.reason and "more than momentum theory allows" in f.reason


def test_a_battery_beyond_its_rated_c_is_implausible(tmp_path) -> None:
    """Two 5 Ah packs per fan at 4.3 kW draw ~45 A each on full charge: within 5 C's burst
    (2 x 25 A), beyond 4 C's (2 x 20 A; the current said is the power over the packs'
    loaded voltage)."""
    import re

    from tests.conftest import copy_shipped_case
    from tuflexperf.io.case import load_case

    path = copy_shipped_case(tmp_path)
    battery = tmp_path / "data" / "tuflex" / "battery.yaml"
    shipped = battery.read_text()

    def rated(c_rate: int):
        battery.write_text(shipped.replace("max_discharge_c: 40 ", f"max_discharge_c: {c_rate} "))
        return load_case(path)

    assert implausible(rated(5)) == ()
    case = rated(4)
    found = implausible(case)
    assert [f.rule for f in found] == ["battery_rating", "battery_rating"]
    for f in found:
        assert str(case.battery_path) in f.reason and "max_discharge_c" in f.reason
        assert "beyond the battery" in f.reason and f.throttle == 1.0 and f.value > 1.0
        watts, amps, volts = (float(g) for g in re.search(
            r"draws (\d+) W: ([\d.]+) A per pack at ([\d.]+) V", f.reason).groups())
        assert amps == pytest.approx(f.value * 2 * 4 * 5.0, rel=1e-3)
        assert 2 * amps * volts == pytest.approx(watts, rel=5e-3)
        assert 40.0 < amps < 50.0
    # packs that cannot deliver the power at all: no current, still implausible
    beyond = implausible(_case(sets=["battery.capacity_ah=0.6"]))
    assert beyond and all(math.isinf(f.value) and "more than the packs can deliver" in f.reason
                          for f in beyond)


def test_the_registry_fails_every_requirement_on_implausible_data(tmp_path) -> None:
    verdicts = check_case(_case(_scaled(tmp_path, power=0.45)))
    assert verdicts and not any(v.passed for v in verdicts)
    for v in verdicts:
        assert v.value is None and v.reason.startswith("implausible data")
        assert v.details["value_on_implausible_data"] is not None
    # the endurance the surface flew, 43 min (issue 43), is kept but no verdict passes on it
    endurance = next(v for v in verdicts if v.name == "flight_endurance")
    assert endurance.details["value_on_implausible_data"] > 30.0


COMMANDS = [
    ["check"],
    ["check", "--samples", "8", "--seed", "1"],
    ["endurance", "--throttle", "0.5"],
    ["mission", str(MISSION)],
    ["performance"],
    ["takeoff"],
    ["trim"],
    ["oei"],
    ["margins"],
    ["sweep", "--vary", "aircraft.mass_kg=25:27:2", "--fail-on-fail"],
    ["sweep", "--vary", "aircraft.mass_kg=25:27:2"],
]


@pytest.mark.parametrize("scale", [0.45, 0.30])
@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: " ".join(c[:2]))
def test_every_command_gives_the_same_answer_on_implausible_data(tmp_path, scale,
                                                                 command) -> None:
    propulsion = _scaled(tmp_path, power=scale)
    ran = tuflexperf(*command, "--propulsion", str(propulsion), "--json")
    assert ran.returncode == 1, ran.stderr
    said = json.loads(ran.stdout)
    text = json.dumps(said)
    assert "implausible data" in text and "figure of merit" in text
    assert '"passed": true' not in text


@pytest.mark.parametrize("command", COMMANDS[:1] + COMMANDS[2:4] + COMMANDS[-1:],
                         ids=lambda c: c[0])
def test_the_commands_pass_the_shipped_data(command) -> None:
    """The control: the same commands on the shipped surfaces are not refused."""
    ran = tuflexperf(*command, "--json")
    assert "implausible data" not in ran.stdout + ran.stderr
    assert ran.returncode in (0, 1) and json.loads(ran.stdout), ran.stderr


def test_report_exits_1_with_the_reason(tmp_path) -> None:
    propulsion = _scaled(tmp_path, power=0.30)
    ran = tuflexperf("report", "--out", str(tmp_path / "report"), "--propulsion",
                     str(propulsion))
    assert ran.returncode == 1
    assert "implausible data" in ran.stderr and (tmp_path / "report" / "review.pdf").exists()


def test_the_scan_is_cheap_and_numpy_only() -> None:
    """``check`` imports no matplotlib, pandas or scipy for it (one scan per study)."""
    import subprocess
    import sys

    code = ("import sys; from tuflexperf.analysis.plausibility import implausible;"
            "from tuflexperf.io.case import load_propulsion;"
            "print(sorted(m for m in ('matplotlib', 'pandas', 'scipy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={"PYTHONPATH": str(ROOT)})
    assert out.stdout.strip() == "[]"
    assert math.isfinite(len(implausible(_case())))


def test_the_batch_judges_the_packs_rating_per_row_as_the_single_case() -> None:
    """A sweep or the samples over the capacity: each row as ``check --set`` on it."""
    from tests.verification.test_batch_equals_deterministic import (
        assert_equal_to_deterministic,
    )
    from tuflexperf.analysis.batch import BatchEvaluator
    from tuflexperf.io.dotted import with_values

    case = _case()
    capacities = np.array([0.6, 0.8, 1.6, 2.5])
    result = BatchEvaluator(case).evaluate({"battery.capacity_ah": capacities})
    refused = []
    for row, capacity in enumerate(capacities):
        single = with_values(case, {"battery.capacity_ah": float(capacity)})
        assert_equal_to_deterministic(single, result.values, row)
        refused.append(bool(implausible(single)))
    assert refused == [True, True, False, False]
    assert np.isnan(result.values["oei_min_throttle"][:2]).all()
    assert np.isfinite(result.values["oei_min_throttle"][2:]).all()


def test_bad_input_is_refused_before_the_datas_verdict(tmp_path) -> None:
    """A file or flag the command refuses is exit 2 even on implausible data."""
    propulsion = _scaled(tmp_path, power=0.30)
    ran = tuflexperf("sweep", "--vary", "aircraft.mass_kg=25:27:2", "--plot",
                     str(tmp_path / "carpet.svg"), "--propulsion", str(propulsion))
    assert ran.returncode == 2 and "PNG" in ran.stderr
    ran = tuflexperf("endurance", "--throttle", "50", "--propulsion", str(propulsion))
    assert ran.returncode == 2 and "implausible" not in ran.stderr


@pytest.mark.parametrize("command", ["takeoff", "trim", "oei", "performance"])
def test_the_refusal_carries_the_commands_own_json_keys(tmp_path, command) -> None:
    """SPEC 5: on exit 1 a command's keys are there, null, as for "not attainable"."""
    from tuflexperf.cli.guard import _RESULT_KEYS

    ran = tuflexperf(command, "--propulsion", str(_scaled(tmp_path, power=0.30)), "--json")
    said = json.loads(ran.stdout)
    assert ran.returncode == 1 and said["verdict"] == "FAIL" and said["passed"] is False
    assert all(said[key] is None for key in _RESULT_KEYS[command])
