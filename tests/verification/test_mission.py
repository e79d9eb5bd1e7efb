"""Mission integration (issue 13): closed forms, the battery model, energy balance, solve_for."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp
from scipy.optimize import brentq

from tuflexperf.analysis.mission import MissionModel
from tuflexperf.io.case import load_case
from tuflexperf.io.mission import load_mission
from tuflexperf.models.aircraft import level_flight_drag_n, true_airspeed_m_s
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.battery import (
    current_at_power_a,
    discharge_time_s,
    terminal_voltage_v,
)
from tuflexperf.models.powertrain import engine_power_w
from tuflexperf.models.thrust import density_ratio, total_thrust_n

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_MISSION = ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml"


def _mission(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "mission.yaml"
    path.write_text(textwrap.dedent(body))
    return path


@pytest.fixture(scope="module")
def shipped() -> MissionModel:
    return MissionModel(load_case(None), load_mission(SHIPPED_MISSION), None)


def _segment_slice(model: MissionModel, index: int) -> slice:
    a, b = model.bounds[index]
    return slice(a, b)


def test_constant_power_cruise_matches_closed_form_charge(shipped: MissionModel) -> None:
    """No voltage effect: a level cruise draws constant power, so t = 3600 int dq / i(q, P)."""
    result = shipped.fly()
    k = 2  # cruise
    sl = _segment_slice(shipped, k)
    h = result.history
    for i, name in enumerate(shipped.engines):
        current = h[f"current_a_{name}"][sl]
        voltage = h[f"voltage_v_{name}"][sl]
        power = current * voltage
        assert np.ptp(power) < 1e-9 * power.mean()  # constant power indeed
        q = h[f"charge_ah_{name}"][sl]
        t = float(discharge_time_s(shipped.params, power.mean(), q[0], q[-1], shipped.packs))
        assert t == pytest.approx(result.segments[k].time_s, rel=1e-8)
        del i


def test_loaded_voltage_is_the_battery_model(shipped: MissionModel) -> None:
    h = shipped.fly().history
    for name in shipped.engines:
        q, i = h[f"charge_ah_{name}"], h[f"current_a_{name}"]
        expected = terminal_voltage_v(shipped.params, q, i, shipped.packs)
        assert np.allclose(h[f"voltage_v_{name}"], expected, rtol=1e-12, atol=1e-9)


def test_energy_equals_integral_of_power(shipped: MissionModel) -> None:
    result = shipped.fly()
    h = result.history
    for k in (1, 2, 4, 6):  # climb, cruise, loiter, loiter
        sl = _segment_slice(shipped, k)
        t = h["time_s"][sl]
        for i, name in enumerate(shipped.engines):
            power = h[f"current_a_{name}"][sl] * h[f"voltage_v_{name}"][sl]
            integral_wh = simpson(power, x=t) / 3600.0
            flown = result.segments[k].energy_wh[i]
            assert flown == pytest.approx(integral_wh, rel=1e-6, abs=1e-9)


def test_solve_for_lands_exactly_on_the_reserve(tmp_path: Path) -> None:
    body = SHIPPED_MISSION.read_text() + "solve_for: cruise\n"
    model = MissionModel(load_case(None), load_mission(_mission(tmp_path, body)), 0.3)
    solved = model.solve_for()
    assert solved.landing_charge_fraction == pytest.approx(0.3, abs=1e-8)
    durations = model.durations.copy()
    durations[2] = 60.0 * solved.solved["time_min"]
    flown = model.fly(durations)  # the answer flown as a plain mission
    assert flown.landing_charge_fraction == pytest.approx(0.3, abs=1e-8)
    assert flown.segments[2].time_s == pytest.approx(durations[2], rel=1e-12)


def test_independent_integration_of_climb_and_cruise(tmp_path: Path) -> None:
    """solve_ivp on the SPEC equations (brentq throttle at every call) from the landed files."""
    case = load_case(None)
    path = _mission(tmp_path, """\
        name: climb and cruise
        segments:
          - {type: climb, to_altitude_m: 150, airspeed_m_s: 22, throttle: 0.9}
          - {type: cruise, airspeed_m_s: 25, time_min: 5}
        """)
    model = MissionModel(case, load_mission(path), None)
    result = model.fly()
    p, n_packs = model.params, model.packs
    prop, aircraft = case.propulsion, case.aircraft

    def power_w(x: float, v: float, rho: float) -> list[float]:
        return [float(density_ratio(prop, rho) * engine_power_w(e, x, v)) for e in prop.engines]

    def climb(h: float, y: np.ndarray) -> list[float]:
        rho = float(isa_density_kg_m3(h, 0.0))
        v = float(true_airspeed_m_s(22.0, rho))
        excess = float(total_thrust_n(prop, 0.9, v, rho) - level_flight_drag_n(aircraft, v, rho))
        rate = excess * v / aircraft.weight_n
        currents = [float(current_at_power_a(p, y[i], pw, n_packs))
                    for i, pw in enumerate(power_w(0.9, v, rho))]
        return [c / 3600.0 / rate for c in currents] + [1.0 / rate]

    def cruise(t: float, y: np.ndarray) -> list[float]:
        rho = float(isa_density_kg_m3(150.0, 0.0))
        v = float(true_airspeed_m_s(25.0, rho))
        drag = float(level_flight_drag_n(aircraft, v, rho))
        x = brentq(lambda s: float(total_thrust_n(prop, s, v, rho)) - drag, 0.0, 1.0, xtol=1e-14)
        return [float(current_at_power_a(p, y[i], pw, n_packs)) / 3600.0
                for i, pw in enumerate(power_w(x, v, rho))]

    up = solve_ivp(climb, (0.0, 150.0), [0.0, 0.0, 0.0], rtol=1e-11, atol=1e-13)
    level = solve_ivp(cruise, (0.0, 300.0), up.y[:2, -1], rtol=1e-11, atol=1e-13)
    assert result.segments[0].time_s == pytest.approx(up.y[2, -1], rel=1e-7)
    for i in range(2):
        assert result.segments[0].charge_ah[i] == pytest.approx(up.y[i, -1], rel=1e-7)
        assert result.segments[1].charge_ah[i] == pytest.approx(
            level.y[i, -1] - up.y[i, -1], rel=1e-7)


def _run(*args: str) -> tuple[int, str, str]:
    from typer.testing import CliRunner

    from tuflexperf.cli import app

    out = CliRunner().invoke(app, list(args))
    return out.exit_code, out.stdout, out.stderr


def test_cli_mission_passes_and_writes_history(tmp_path: Path) -> None:
    csv = tmp_path / "history.csv"
    code, out, _ = _run("mission", str(SHIPPED_MISSION), "--json", "--csv", str(csv))
    assert code == 0
    data = json.loads(out)
    assert data["passed"] is True
    assert [s["type"] for s in data["segments"]][:3] == ["takeoff", "climb", "cruise"]
    for key in ("time_s", "distance_m", "charge_ah", "energy_wh", "min_voltage_v"):
        assert key in data["segments"][0]
    header = csv.read_text().splitlines()[0]
    assert "voltage_v_EDF1" in header and "charge_ah_EDF2" in header


@pytest.mark.parametrize(
    ("segment", "reason"),
    [
        ("{type: cruise, airspeed_m_s: 26, time_min: 90}", "segment 2 (cruise): the pack"),
        ("{type: loiter, airspeed_m_s: 5, time_min: 1}", "below stall"),
        ("{type: climb, to_altitude_m: 200, airspeed_m_s: 20, climb_rate_m_s: 30}",
         "needs more than full throttle"),
    ],
)
def test_cli_mission_not_attainable_names_the_segment(
    tmp_path: Path, segment: str, reason: str
) -> None:
    path = _mission(tmp_path, f"""\
        name: hostile
        segments:
          - {{type: takeoff}}
          - {segment}
        """)
    code, out, err = _run("mission", str(path), "--json")
    assert code == 1
    text = out + err
    assert reason in text


def test_cli_mission_bad_key_is_exit_2(tmp_path: Path) -> None:
    path = _mission(tmp_path, """\
        name: typo
        segments:
          - {type: cruise, airspeed_m_s: 26, time_mins: 5}
        """)
    code, _, err = _run("mission", str(path))
    assert code == 2
    assert str(path) in err and "time_mins" in err


def test_catapult_launch_starts_airborne_and_skips_the_runway(tmp_path: Path) -> None:
    """launch: catapult (SPEC 4): endurance and missions start airborne at the release speed;
    an aircraft that could never roll on a runway still flies its endurance and mission."""
    import shutil

    from tuflexperf.analysis.endurance import solve_endurance

    for folder in ("requirements", "data"):
        shutil.copytree(ROOT / folder, tmp_path / folder)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    text = aircraft.read_text().replace(
        "takeoff:", "launch: catapult\nlaunch_speed_m_s: 18\nlaunch_energy_j: 2000\ntakeoff:", 1)
    text = "\n".join("  rolling_friction: 0.9" if line.strip().startswith("rolling_friction")
                     else line for line in text.splitlines()) + "\n"
    aircraft.write_text(text)
    case_file = tmp_path / "requirements" / "tuflex.yaml"
    case_file.write_text(case_file.read_text().replace("  takeoff: {max_ground_roll_m: 60}\n", ""))
    case = load_case(case_file)
    runway = solve_endurance(load_case(None), 0.5)
    catapult = solve_endurance(case, 0.5)
    assert catapult.launch.ground_roll_time_s == 0.0
    assert 0 < catapult.launch.charge_ah < runway.launch.charge_ah  # only the climb draws
    result = MissionModel(case, load_mission(SHIPPED_MISSION), None).fly()
    assert result.attainable and result.segments[0].charge_ah == (0.0, 0.0)
    assert result.segments[1].start_altitude_m == 0.0
