"""Mission integration (issue 13): closed forms, the battery model, energy balance, solve_for."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp
from scipy.optimize import brentq

from tests.conftest import copy_shipped_case
from tuflexperf.analysis.mission import MissionModel
from tuflexperf.errors import NotAttainable
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


def test_a_mission_without_a_takeoff_says_it_starts_airborne(tmp_path: Path) -> None:
    """It flies (a plan may start in the air), but the launch's charge is not in it: said in
    the text and the JSON, and not said of a mission that takes off."""
    path = tmp_path / "airborne.yaml"
    path.write_text("name: airborne\nsegments:\n"
                    "  - {type: cruise, airspeed_m_s: 26, time_min: 8}\n")
    code, out, _ = _run("mission", str(path))
    assert code == 0 and "note: mission 'airborne' has no takeoff segment" in out, out
    code, out, _ = _run("mission", str(path), "--json")
    assert any("starts airborne" in w for w in json.loads(out)["warnings"])
    code, out, _ = _run("mission", str(SHIPPED_MISSION), "--json")
    assert not any("airborne" in w for w in json.loads(out)["warnings"])


@pytest.mark.parametrize(
    ("segment", "reason"),
    [
        ("{type: cruise, airspeed_m_s: 26, time_min: 90}", "segment 2 (cruise): the pack"),
        ("{type: loiter, airspeed_m_s: 5, time_min: 1}", "below stall"),
        ("{type: climb, to_altitude_m: 200, airspeed_m_s: 20, climb_rate_m_s: 15}",
         "needs more than full throttle"),
        ("{type: cruise, airspeed_m_s: 60, time_min: 1}",
         "segment 2 (cruise): needs more than full throttle at "),
        ("{type: climb, to_altitude_m: 100, airspeed_m_s: 8, throttle: 1.0}", "below stall"),
        ("{type: loiter, throttle: 0.1, time_min: 1}", "holds level flight at no airspeed"),
        ("{type: descent, to_altitude_m: 5, airspeed_m_s: 20, descent_rate_m_s: 5}",
         "needs less than idle thrust"),
        ("{type: climb, to_altitude_m: 3000, airspeed_m_s: 20, throttle: 0.3}",
         "cannot climb at throttle 0.3"),
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
    data = json.loads(out)  # one JSON object with the mission's keys on exit 1 too
    assert data["passed"] is False and data["attainable"] is False
    assert reason in data["reason"]
    # the take-off before the failing segment is flown and reported (and the failing one as
    # far as it was flown, when it fails in flight)
    assert [s["type"] for s in data["segments"]][0] == "takeoff"
    assert len(data["segments"]) <= 2
    assert data["ended_at_s"] == pytest.approx(sum(s["time_s"] for s in data["segments"]))


def test_a_segment_that_cannot_be_planned_ends_the_flight_there(tmp_path: Path) -> None:
    """A cruise below stall after take-off and climb: the JSON had no segments at all; the
    README promises the segment and the time (outside audit)."""
    path = _mission(tmp_path, """\
        name: slow cruise
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}
          - {type: cruise, airspeed_m_s: 12, time_min: 2}
          - {type: loiter, airspeed_m_s: 20, time_min: 2}
        """)
    code, out, _ = _run("mission", str(path), "--json")
    assert code == 1
    data = json.loads(out)
    assert data["passed"] is False and data["attainable"] is False
    assert data["reason"].startswith("segment 3 (cruise)") and "below stall" in data["reason"]
    assert [s["type"] for s in data["segments"]] == ["takeoff", "climb"]
    assert data["segments"][-1]["altitude_m"] == pytest.approx(100.0)
    assert data["ended_at_s"] == pytest.approx(sum(s["time_s"] for s in data["segments"]))
    code, human, _ = _run("mission", str(path))
    assert code == 1 and "climb" in human and "segment 3 (cruise)" in human and "FAIL" in human
    # nothing before it: the one-line answer as before
    first = _mission(tmp_path, """\
        name: slow from the start
        segments:
          - {type: cruise, airspeed_m_s: 12, time_min: 2}
        """)
    code, out, _ = _run("mission", str(first), "--json")
    assert code == 1 and json.loads(out)["segments"] == []


def test_cli_mission_bad_key_is_exit_2(tmp_path: Path) -> None:
    path = _mission(tmp_path, """\
        name: typo
        segments:
          - {type: cruise, airspeed_m_s: 26, time_mins: 5}
        """)
    code, _, err = _run("mission", str(path))
    assert code == 2
    assert str(path) in err and "time_mins" in err


@pytest.mark.parametrize(("segment", "direction"), [
    ("{type: climb, to_altitude_m: 0, airspeed_m_s: 20, throttle: 1.0}", "up"),
    ("{type: descent, to_altitude_m: 0, airspeed_m_s: 20, throttle: 0.1}", "down"),
])
def test_a_climb_or_descent_to_its_own_height_is_bad_input(tmp_path: Path, segment,
                                                            direction) -> None:
    """A descent from 0 m to 0 m was flown (exit 0) where the like climb is refused."""
    path = _mission(tmp_path, f"""\
        name: level
        segments:
          - {segment}
        """)
    code, _, err = _run("mission", str(path))
    assert code == 2 and f"must go {direction}, got 0 m" in err, err


def test_catapult_launch_starts_airborne_and_skips_the_runway(tmp_path: Path) -> None:
    """launch: catapult (SPEC 4): endurance and missions start airborne at the release speed;
    an aircraft that could never roll on a runway still flies its endurance and mission."""

    from tuflexperf.analysis.endurance import solve_endurance

    copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    text = aircraft.read_text().replace(
        "takeoff:", "launch: catapult\nlaunch_speed_m_s: 18\nlaunch_energy_j: 12000\ntakeoff:", 1)
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


# --- an independent integration of a whole mission, with the pack-voltage effect -----------
def _voltage_case(tmp_path: Path, exponent: float = 2.0):

    copy_shipped_case(tmp_path)
    prop = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    prop.write_text(prop.read_text().replace(
        "fan_area_m2:", f"reference_voltage_v: 46.0\nvoltage_exponent: {exponent}\n"
        "fan_area_m2:", 1))
    return load_case(tmp_path / "requirements" / "tuflex.yaml")


class _Spec:
    """SPEC 3/4 at one instant from the landed files, solved with scipy's brentq.

    Loaded voltage ``U = OCV(q/n) - (R/n) P / U`` with ``P = sigma P_surface(x, V)
    (U/U_ref)^(1.5 k)``, thrust ``sigma T(x, V) (U/U_ref)^k``; a dead engine windmills
    (``-Cd_wm q A_fan``) and draws nothing.
    """

    def __init__(self, model: MissionModel) -> None:
        self.m, self.case = model, model.case
        self.prop, self.aircraft = model.case.propulsion, model.case.aircraft
        self.u_ref, self.k = self.prop.reference_voltage_v, self.prop.voltage_exponent
        self.r = model.params.resistance_ohm / model.packs

    def rho(self, h: float) -> float:
        return float(isa_density_kg_m3(h, 0.0))

    def engine(self, i: int, q: float, x: float, v: float, rho: float) -> tuple[float, ...]:
        from tuflexperf.models.battery import open_circuit_voltage_v
        from tuflexperf.models.thrust import engine_thrust_n

        e = self.prop.engines[i]
        sigma = density_ratio(self.prop, rho)
        p0 = sigma * float(engine_power_w(e, x, v))
        ocv = float(open_circuit_voltage_v(self.m.params, q, self.m.packs))
        u = brentq(lambda u: ocv - self.r * p0 * (u / self.u_ref) ** (1.5 * self.k) / u - u,
                   0.6 * ocv, 1.2 * ocv, xtol=1e-14, rtol=1e-14)
        power = p0 * (u / self.u_ref) ** (1.5 * self.k)
        thrust = float(engine_thrust_n(e, x, v, sigma)) * (u / self.u_ref) ** self.k
        return thrust, power / u, u

    def state(self, q: np.ndarray, x: float, v: float, rho: float, dead: int | None
              ) -> tuple[float, list[float], list[float]]:
        from tuflexperf.models.thrust import windmilling_thrust_n

        thrust, currents, volts = 0.0, [], []
        for i in range(len(self.prop.engines)):
            if i == dead:
                e = self.prop.engines[i]
                thrust += float(windmilling_thrust_n(e, v, density_ratio(self.prop, rho), rho,
                                                     self.prop.fan_area_m2))
                currents.append(0.0)
                continue
            t, c, u = self.engine(i, q[i], x, v, rho)
            thrust, currents, volts = thrust + t, currents + [c], volts + [u]
        return thrust, currents, volts

    def excess(self, q: np.ndarray, x: float, v: float, rho: float, dead: int | None) -> float:
        return self.state(q, x, v, rho, dead)[0] - float(
            level_flight_drag_n(self.aircraft, v, rho))

    def level_throttle(self, q: np.ndarray, v: float, rho: float, dead: int | None,
                       extra_n: float = 0.0) -> float:
        return brentq(lambda x: self.excess(q, x, v, rho, dead) - extra_n, 0.0, 1.0,
                      xtol=1e-15, rtol=1e-14)


def _spec_segment(spec: _Spec, s, q: np.ndarray, h0: float, dead: int | None,
                  guess: float) -> tuple[np.ndarray, float, float, float | None]:
    """One segment by solve_ivp: end charges, time [s], least live voltage, end airspeed."""
    aircraft = spec.aircraft
    opts = {"rtol": 1e-11, "atol": 1e-13, "method": "DOP853"}

    def tas(h: float) -> float:
        return float(true_airspeed_m_s(s.airspeed_m_s, spec.rho(h)))

    if s.type in ("climb", "descent"):
        cmd = s.climb_rate_m_s if s.type == "climb" else (
            -s.descent_rate_m_s if s.descent_rate_m_s else None)

        def point(h: float, y: np.ndarray) -> tuple[float, float, float]:
            rho, v = spec.rho(h), tas(h)
            if s.throttle is not None:
                return s.throttle, v, spec.excess(y, s.throttle, v, rho, dead) * v \
                    / aircraft.weight_n
            return spec.level_throttle(y, v, rho, dead, aircraft.weight_n * cmd / v), v, cmd

        def rhs(h: float, y: np.ndarray) -> list[float]:
            x, v, rate = point(h, y[:2])
            currents = spec.state(y[:2], x, v, spec.rho(h), dead)[1]
            return [c / 3600.0 / rate for c in currents] + [1.0 / rate]

        sol = solve_ivp(rhs, (h0, s.to_altitude_m), [*q, 0.0], dense_output=True, **opts)
        least = np.inf
        for h in np.linspace(h0, s.to_altitude_m, 201):
            y = sol.sol(h)[:2]
            x, v, _ = point(h, y)
            least = min(least, *spec.state(y, x, v, spec.rho(h), dead)[2])
        return sol.y[:2, -1], float(sol.y[2, -1]), least, None

    rho = spec.rho(h0)

    def level(y: np.ndarray) -> tuple[float, float]:
        if s.throttle is None:
            return spec.level_throttle(y, tas(h0), rho, dead), tas(h0)
        return s.throttle, brentq(lambda v: spec.excess(y, s.throttle, v, rho, dead),
                                  0.7 * guess, 1.2 * guess, xtol=1e-13, rtol=1e-14)

    def rhs_t(t: float, y: np.ndarray) -> list[float]:
        x, v = level(y)
        return [c / 3600.0 for c in spec.state(y, x, v, rho, dead)[1]]

    duration = 60.0 * s.time_min
    sol = solve_ivp(rhs_t, (0.0, duration), q, dense_output=True, **opts)
    least, v = np.inf, None
    for t in np.linspace(0.0, duration, 201):
        y = sol.sol(t)
        x, v = level(y)
        least = min(least, *spec.state(y, x, v, rho, dead)[2])
    return sol.y[:, -1], duration, least, v


def test_independent_mission_with_voltage_effect_and_engine_failure(tmp_path: Path) -> None:
    """Every kind of airborne segment with the sagging pack: solve_ivp (DOP853, tight) per
    segment, brentq for the loaded voltage, the throttle and the fixed throttle's airspeed;
    segment times, landing charge and the least voltage agree to 1e-6."""
    case = _voltage_case(tmp_path)
    path = _mission(tmp_path, """\
        name: every airborne segment, sagging pack
        segments:
          - {type: climb, to_altitude_m: 120, airspeed_m_s: 22, throttle: 0.9}
          - {type: cruise, airspeed_m_s: 25, time_min: 4}
          - {type: climb, to_altitude_m: 160, airspeed_m_s: 21, climb_rate_m_s: 1.5}
          - {type: engine_failure, engine: EDF2}
          - {type: loiter, throttle: 0.95, time_min: 1}
          - {type: descent, to_altitude_m: 60, airspeed_m_s: 20, descent_rate_m_s: 1.0}
          - {type: descent, to_altitude_m: 30, airspeed_m_s: 20, throttle: 0.2}
        """)
    model = MissionModel(case, load_mission(path), None)
    result = model.fly()
    assert result.attainable, result.reason
    spec = _Spec(model)
    q, h, dead, least = np.zeros(2), 0.0, None, np.inf
    times, v_loiter = [], None
    for k, s in enumerate(load_mission(path).segments):
        if s.type == "engine_failure":
            dead = 1
            times.append(0.0)
            continue
        q, t, low, v_end = _spec_segment(spec, s, q, h, dead, model.plans[k].v_guess)
        times.append(t)
        least = min(least, low)
        h = s.to_altitude_m if s.to_altitude_m is not None else h
        v_loiter = v_end if s.throttle is not None and s.type == "loiter" else v_loiter
    for k, seg in enumerate(result.segments):
        assert seg.time_s == pytest.approx(times[k], rel=1e-6, abs=1e-9), seg.type
    assert result.landing_charge_fraction == pytest.approx(
        float(np.min(1.0 - q / model.capacity_ah)), rel=1e-7)
    for i, name in enumerate(result.engines):
        assert result.history[f"charge_ah_{name}"][-1] == pytest.approx(q[i], rel=1e-7)
    flown = min(s.min_voltage_v for s in result.segments if s.type != "engine_failure")
    assert flown == pytest.approx(least, rel=1e-6)
    # the fixed-throttle loiter's airspeed fell as its pack sagged, to the SPEC's value
    a, b = model.bounds[4]
    assert result.history["airspeed_m_s"][b - 1] == pytest.approx(v_loiter, rel=1e-7)
    assert result.history["airspeed_m_s"][b - 1] < result.history["airspeed_m_s"][a]


def test_cutoff_ends_the_flight_at_the_event_time(tmp_path: Path) -> None:
    """A cruise too long for the packs: not attainable, the segment named, the cut-off time
    equal to solve_ivp's event (the loaded voltage U(q, i) = U_cut, constant power)."""
    from tuflexperf.models.battery import terminal_voltage_v

    path = _mission(tmp_path, """\
        name: too long
        segments:
          - {type: takeoff}
          - {type: cruise, airspeed_m_s: 26, time_min: 90}
          - {type: loiter, airspeed_m_s: 20, time_min: 5}
        """)
    model = MissionModel(load_case(None), load_mission(path), None)
    result = model.fly()
    assert not result.attainable and not result.passed
    assert result.reason.startswith("segment 2 (cruise): the pack reaches its cut-off voltage")
    assert [s.type for s in result.segments] == ["takeoff", "cruise"]  # nothing after it
    assert result.history["time_s"][-1] == pytest.approx(result.ended_at_s, abs=1e-5)
    a = model.bounds[1][0]
    q0 = np.array([result.history[f"charge_ah_{n}"][a] for n in result.engines])
    t0 = float(result.history["time_s"][a])
    power = [float(result.history[f"power_w_{n}"][a]) for n in result.engines]
    p, packs = model.params, model.packs

    def rhs(t: float, q: np.ndarray) -> list[float]:
        return [float(current_at_power_a(p, q[i], power[i], packs)) / 3600.0 for i in range(2)]

    def cut(t: float, q: np.ndarray) -> float:
        return min(float(terminal_voltage_v(p, q[i], current_at_power_a(p, q[i], power[i],
                                                                          packs), packs))
                   for i in range(2)) - model.cutoff_v

    cut.terminal = True
    sol = solve_ivp(rhs, (0.0, 5400.0), q0, events=cut, rtol=1e-11, atol=1e-13,
                    method="DOP853")
    assert result.ended_at_s == pytest.approx(t0 + float(sol.t_events[0][0]), abs=1e-3)
    code, out, _ = _run("mission", str(path), "--json")
    assert code == 1
    data = json.loads(out)
    assert data["passed"] is False and data["ended_at_s"] == pytest.approx(result.ended_at_s)
    assert "segment 2 (cruise)" in data["reason"]


def test_a_climb_that_meets_the_cutoff_ends_at_its_last_node_and_says_so(tmp_path) -> None:
    """A climb (integrated over height) too long for the packs: the history, the segment
    table and ended_at_s end at the last node before the cut-off, and the reason names the
    two nodes around it (it named the node after, past the history's end: a second audit)."""
    from tuflexperf.io.dotted import with_values

    path = _mission(tmp_path, """\
        name: too high
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 9500, airspeed_m_s: 28, throttle: 1.0}
          - {type: cruise, airspeed_m_s: 28, time_min: 1}
        """)
    case = with_values(load_case(None), {"aircraft.mass_kg": 50.0})
    model = MissionModel(case, load_mission(path), None)
    result = model.fly()
    assert not result.attainable
    assert "segment 2 (climb): the pack reaches its cut-off voltage" in result.reason
    assert "between" in result.reason
    last = float(result.history["time_s"][-1])
    assert result.ended_at_s == pytest.approx(last, abs=1e-9)
    assert sum(s.time_s for s in result.segments) == pytest.approx(last, abs=1e-9)
    assert result.segments[-1].min_voltage_v >= model.cutoff_v - 1e-9  # before the cut-off
    assert f"{last:.1f}" in result.reason


def test_solve_for_stops_at_the_cutoff_when_it_comes_before_the_reserve(
    tmp_path: Path,
) -> None:
    """With no reserve the pack's cut-off ends the longest cruise: flown plainly, the answer
    ends exactly on the cut-off voltage and is attainable."""
    path = _mission(tmp_path, """\
        name: to the cut-off
        segments:
          - {type: takeoff}
          - {type: cruise, airspeed_m_s: 30, time_min: 1}
        solve_for: cruise
        """)
    model = MissionModel(load_case(None), load_mission(path), 0.0)
    result = model.solve_for()
    assert result.solved["ends_at"] == "cut-off"
    assert result.attainable and result.passed
    assert result.segments[-1].min_voltage_v == pytest.approx(model.cutoff_v, abs=1e-6)
    durations = model.durations.copy()
    durations[1] = 60.0 * result.solved["time_min"]
    assert model.fly(durations).segments[-1].min_voltage_v == pytest.approx(
        model.cutoff_v, abs=1e-6)


def test_solve_for_with_the_voltage_effect_lands_on_the_reserve(tmp_path: Path) -> None:
    """solve_for a middle segment (loiter at a fixed throttle, its airspeed sagging) with the
    pack-voltage effect: flown as a plain mission, the answer lands exactly on the reserve."""
    case = _voltage_case(tmp_path)
    path = _mission(tmp_path, """\
        name: how long may I loiter
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}
          - {type: loiter, throttle: 0.55, time_min: 1}
          - {type: engine_failure, engine: EDF1}
          - {type: descent, to_altitude_m: 30, airspeed_m_s: 20, throttle: 0.3}
          - {type: cruise, airspeed_m_s: 22, distance_km: 1.5}
        solve_for: loiter
        """)
    model = MissionModel(case, load_mission(path), 0.25)
    solved = model.solve_for()
    assert solved.passed and solved.solved["ends_at"] == "landing reserve"
    assert solved.landing_charge_fraction == pytest.approx(0.25, abs=1e-9)
    durations = model.durations.copy()
    durations[2] = 60.0 * solved.solved["time_min"]
    flown = model.fly(durations)
    assert flown.passed and flown.landing_charge_fraction == pytest.approx(0.25, abs=1e-9)
    longer = durations.copy()
    longer[2] += 1.0  # a second more and the reserve is not met
    assert not model.fly(longer).passed


def test_a_cruise_far_too_long_is_cut_off_not_a_pass(tmp_path: Path) -> None:
    """70 days of cruise: one RK4 step would leap past the pack's knee (where the circuit
    model's voltage rises again); the flight still ends at the same cut-off as a 90 min one."""
    results = []
    for minutes in (90, 100000):
        path = _mission(tmp_path, f"""\
            name: long
            segments:
              - {{type: takeoff}}
              - {{type: cruise, airspeed_m_s: 26, time_min: {minutes}}}
            """)
        result = MissionModel(load_case(None), load_mission(path), None).fly()
        assert not result.attainable and not result.passed
        assert "cut-off voltage" in result.reason
        results.append(result)
    assert results[1].ended_at_s == pytest.approx(results[0].ended_at_s, abs=1e-5)
    for r in results:  # the history ends at the event, on the cut-off voltage
        assert r.history["time_s"][-1] == pytest.approx(r.ended_at_s, abs=1e-5)
        assert min(r.history["voltage_v_EDF1"][-1], r.history["voltage_v_EDF2"][-1]) \
            == pytest.approx(40.8, abs=1e-3)
        assert np.all(np.diff(r.history["charge_ah_EDF1"]) >= 0)


def test_a_second_engine_failure_is_bad_input(tmp_path: Path) -> None:
    path = _mission(tmp_path, """\
        name: both out
        segments:
          - {type: takeoff}
          - {type: engine_failure, engine: EDF1}
          - {type: engine_failure, engine: EDF2}
          - {type: loiter, airspeed_m_s: 20, time_min: 1}
        """)
    code, out, err = _run("mission", str(path))
    assert code == 2 and out == ""
    assert str(path) in err and "segments[2]" in err and "second engine_failure" in err


@pytest.mark.parametrize("failed", [False, True])
def test_loiter_without_airspeed_flies_the_least_power_speed(tmp_path: Path,
                                                             failed: bool) -> None:
    """A loiter with no airspeed flies at the least electrical power in level flight (SPEC 4:
    the best-endurance speed), on the live engine alone after an engine failure: against
    scipy's bounded minimisation of the SPEC's power at the level-flight throttle (brentq)."""
    from scipy.optimize import minimize_scalar

    from tuflexperf.models.thrust import total_thrust_n

    failure = "  - {type: engine_failure, engine: EDF2}\n" if failed else ""
    path = _mission(tmp_path, "name: loiter\nsegments:\n  - {type: takeoff}\n" + failure
                    + "  - {type: loiter, time_min: 3}\n")
    case = load_case(None)
    model = MissionModel(case, load_mission(path), None)
    result = model.fly()
    assert result.attainable, result.reason
    eas = result.segments[-1].airspeed_eas_m_s
    rho = float(isa_density_kg_m3(15.0, 0.0))  # the loiter is at the obstacle height
    dead = 1 if failed else None
    prop = case.propulsion

    def power(e: float) -> float:
        v = float(true_airspeed_m_s(e, rho))
        drag = float(level_flight_drag_n(case.aircraft, v, rho))
        x = brentq(lambda s: float(total_thrust_n(prop, s, v, rho, dead)) - drag, 0.0, 1.0,
                   xtol=1e-14)
        return sum(float(density_ratio(prop, rho) * engine_power_w(en, x, v))
                   for i, en in enumerate(prop.engines) if i != dead)

    best = minimize_scalar(power, bounds=(0.9 * eas, 1.1 * eas), method="bounded",
                           options={"xatol": 1e-6})
    assert eas == pytest.approx(best.x, abs=0.03)
    assert power(eas) == pytest.approx(best.fun, rel=1e-5)


def test_takeoff_segment_equals_an_independent_integration(tmp_path: Path) -> None:
    """The take-off segment: the roll along the take-off analysis's airspeed history, the
    rotation at V_LO, then the airborne path at V_tr: the arc R (1 - cos(V t / R)) to the
    climb angle asin(G), the straight climb at V G to the obstacle (Anderson 6.7); full
    throttle, each fan's sigma(h) P(1, V) from its packs (solve_ivp, DOP853)."""
    import math

    from tuflexperf.analysis.takeoff import solve_takeoff

    case = load_case(None)
    path = _mission(tmp_path, "name: take-off\nsegments:\n  - {type: takeoff}\n")
    model = MissionModel(case, load_mission(path), None)
    segment = model.fly().segments[0]
    to = solve_takeoff(case)
    t_hist, v_hist = np.asarray(to.history_time_s), np.asarray(to.history_airspeed_m_s)
    radius, v_tr, g = to.transition_radius_m, to.transition_speed_m_s, to.climb_gradient
    assert not to.obstacle_cleared_in_transition
    angle = math.asin(g)
    arc_s = radius * angle / v_tr
    h_arc = radius * (1.0 - math.cos(angle))
    climb_s = (to.obstacle_height_m - h_arc) / (v_tr * g)
    prop, p, packs = case.propulsion, model.params, model.packs

    def rhs(speed_height):
        def f(t: float, q: np.ndarray) -> list[float]:
            v, h = speed_height(t)
            rho = float(isa_density_kg_m3(h, 0.0))
            return [float(current_at_power_a(
                p, q[i], float(density_ratio(prop, rho) * engine_power_w(e, 1.0, v)), packs))
                / 3600.0 for i, e in enumerate(prop.engines)]
        return f

    opts = {"rtol": 1e-12, "atol": 1e-14, "method": "DOP853"}
    q = solve_ivp(rhs(lambda t: (float(np.interp(t, t_hist, v_hist)), 0.0)),
                  (0.0, float(t_hist[-1])), [0.0, 0.0], **opts).y[:, -1]
    if to.rotation_time_s > 0:
        q = solve_ivp(rhs(lambda t: (to.liftoff_speed_m_s, 0.0)), (0.0, to.rotation_time_s),
                      q, **opts).y[:, -1]
    q = solve_ivp(rhs(lambda t: (v_tr, radius * (1.0 - math.cos(v_tr * t / radius)))),
                  (0.0, arc_s), q, **opts).y[:, -1]
    q = solve_ivp(rhs(lambda t: (v_tr, h_arc + v_tr * g * t)), (0.0, climb_s), q,
                  **opts).y[:, -1]
    assert segment.time_s == pytest.approx(to.time_s + arc_s + climb_s, rel=1e-12)
    assert segment.end_altitude_m == pytest.approx(to.obstacle_height_m, abs=1e-9)
    for i in range(2):
        assert segment.charge_ah[i] == pytest.approx(q[i], rel=1e-7)


def test_cli_mission_csv_replaces_only_its_own_history(tmp_path: Path) -> None:
    """--csv never replaces a file the command did not write: the case's inputs (down to the
    battery's discharge runs) and any other existing file are bad input, untouched; its own
    earlier history is replaced whole."""
    foreign = tmp_path / "notes.csv"
    foreign.write_text("my,data\n1,2\n")
    run = ROOT / "data" / "tuflex" / "endurance" / "edf1_endurance_50.csv"
    before = run.read_bytes()
    for target in (foreign, run, SHIPPED_MISSION):
        code, out, err = _run("mission", str(SHIPPED_MISSION), "--csv", str(target))
        assert code == 2 and out == "" and "--csv" in err and str(target) in err
    assert foreign.read_text() == "my,data\n1,2\n" and run.read_bytes() == before
    own = tmp_path / "history.csv"
    for _ in range(2):  # written, then replaced by the same command
        code, _, _ = _run("mission", str(SHIPPED_MISSION), "--csv", str(own))
        assert code == 0
    assert own.read_text().startswith("time_s,segment,")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["history.csv", "notes.csv"]


def test_a_pack_asked_for_more_than_its_c_rating_ends_the_flight(tmp_path: Path) -> None:
    """max_discharge_c was read and never used: a pack drawn far beyond it passed (outside
    audit). It is the continuous rating of every segment of 30 s or more, on average, with
    twice it as the burst: a short take-off above it is no failure."""

    copy_shipped_case(tmp_path)
    battery = tmp_path / "data" / "tuflex" / "battery.yaml"
    original = battery.read_text()
    case_path = tmp_path / "requirements" / "tuflex.yaml"
    flown = MissionModel(load_case(case_path), load_mission(SHIPPED_MISSION), None).fly()
    assert flown.attainable  # 40 C: the shipped flight stays within it

    def fly(rating: str, packs: str, mission: Path) -> object:
        battery.write_text(original.replace("max_discharge_c: 40 ", f"max_discharge_c: {rating} ")
                           .replace("packs_in_parallel_per_engine: 2 ",
                                    f"packs_in_parallel_per_engine: {packs} "))
        return MissionModel(load_case(case_path), load_mission(mission), None).fly()

    # 9 C at take-off: beyond a 2 x 4 C burst; the take-off analysis the mission flies
    # refuses it already (analysis.pack_limits)
    with pytest.raises(NotAttainable, match="beyond its burst rating 40.0 A") as caught:
        fly("4", "2", SHIPPED_MISSION)
    assert "beyond the battery" in str(caught.value)
    # 9 C for the 26 s of take-off and climb: within a 2 x 5 C burst, but 8.1 C over the
    # flight's first 30 s, beyond 5 C continuous (the pack does not see where the take-off,
    # the climb and the cruise begin and end)
    first = fly("5", "2", SHIPPED_MISSION)
    assert not first.attainable and "on average over 30 s (0-30 s into the mission" in \
        first.reason and "beyond its continuous rating 25.0 A" in first.reason
    # it ends in the cruise, but was drawn by the take-off and climb too: all are named
    assert first.reason.startswith("segment 3 (cruise)")
    assert "over segments 1-3 (takeoff, climb, cruise)" in first.reason
    assert fly("9", "2", SHIPPED_MISSION).attainable
    high = _mission(tmp_path, """\
        name: a long climb
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 300, airspeed_m_s: 20, throttle: 1.0}
        """)
    long_climb = fly("6", "2", high)  # ~45 A per pack for a minute against 30 A continuous
    assert not long_climb.attainable
    assert long_climb.reason.startswith("segment 2 (climb): draws")
    assert "beyond its continuous rating 30.0 A" in long_climb.reason
    short = _mission(tmp_path, """\
        name: take off and cruise
        segments:
          - {type: takeoff}
          - {type: cruise, airspeed_m_s: 24, time_min: 2}
        """)
    one_pack = fly("40", "1", short)
    peak = max(float(np.max(one_pack.history[f"current_a_{e}"])) for e in one_pack.engines)
    assert one_pack.attainable and 85.0 < peak < 170.0
    assert fly("17", "1", short).attainable  # above 85 A for seconds: within the burst
    # 2 x 40 A = 80 A burst, below the take-off's peak: the take-off analysis refuses it
    with pytest.raises(NotAttainable, match="beyond its burst rating 80.0 A"):
        fly("8", "1", short)


@pytest.mark.parametrize("first", ["{type: takeoff}", "{type: engine_failure, engine: EDF2}"])
def test_nothing_flown_before_a_segment_that_cannot_be_planned(tmp_path: Path, first) -> None:
    """A catapult release or an engine failure flies no time: the partial flight had no node
    and raised an IndexError traceback (outside regression review); the answer is the
    one-line not attainable, as before."""

    copy_shipped_case(tmp_path)
    aircraft = tmp_path / "data" / "tuflex" / "aircraft.yaml"
    aircraft.write_text(aircraft.read_text().replace(
        "takeoff:", "launch: catapult\nlaunch_speed_m_s: 19\nlaunch_energy_j: 6000\ntakeoff:", 1))
    path = _mission(tmp_path, f"""\
        name: nothing before
        segments:
          - {first}
          - {{type: cruise, throttle: 0.3, time_min: 5}}
        """)
    code, out, err = _run("mission", str(path), "--case",
                          str(tmp_path / "requirements" / "tuflex.yaml"), "--json")
    assert code == 1 and "Traceback" not in err, err
    data = json.loads(out)
    assert data["segments"] == [] and data["landing_charge_fraction"] is None
    assert data["reason"].startswith("segment 2 (cruise): throttle 0.3")


@pytest.mark.parametrize("pieces", [1, 8])
def test_the_continuous_rating_holds_over_any_30_s_not_per_segment(tmp_path: Path,
                                                                     pieces: int) -> None:
    """A 3.6 min cruise at 45 m/s (~43 A per pack) against a 6 C (30 A) rating failed as
    one segment and passed as eight of 27 s each: the mean was bounded per segment of 30 s
    or more (outside audit). The pack sees the flight, not its segments."""
    copy_shipped_case(tmp_path)
    battery = tmp_path / "data" / "tuflex" / "battery.yaml"
    battery.write_text(battery.read_text().replace("max_discharge_c: 40 ",
                                                   "max_discharge_c: 6 "))
    case = load_case(tmp_path / "requirements" / "tuflex.yaml")
    minutes = 3.6 / pieces

    def fly(airspeed: float) -> object:
        cruise = f"  - {{type: cruise, airspeed_m_s: {airspeed}, time_min: {minutes!r}}}\n"
        path = _mission(tmp_path, "name: split\nsegments:\n" + cruise * pieces)
        return MissionModel(case, load_mission(path), None).fly()

    fast = fly(45.0)
    assert not fast.attainable and not fast.passed
    assert "beyond its continuous rating 30.0 A" in fast.reason
    assert "on average over 30 s (0-30 s into the mission" in fast.reason
    assert ("over segments 1-2 (cruise, cruise)" in fast.reason) == (pieces > 1)
    slow = fly(26.0)  # ~11 A per pack: the same segments, within the rating
    assert slow.attainable


def test_a_segment_beyond_the_tested_airspeeds_says_so(tmp_path: Path,
                                                      shipped: MissionModel) -> None:
    """SPEC: extrapolation is said; a mission cruising at 38 m/s (tested to 30) said nothing."""
    assert not [w for w in shipped.fly().warnings if "extrapolated" in w]
    fast = _mission(tmp_path, """\
        name: fast
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}
          - {type: cruise, airspeed_m_s: 38, time_min: 2}
          - {type: loiter, airspeed_m_s: 20, time_min: 1}
        """)
    result = MissionModel(load_case(None), load_mission(fast), None).fly()
    notes = [w for w in result.warnings if "extrapolated" in w]
    true = float(true_airspeed_m_s(38.0, isa_density_kg_m3(100.0)))
    assert notes == [f"segment 3 (cruise): thrust model extrapolated at {true:.1f} m/s true "
                     "(tested 0-30 m/s)"]


@pytest.mark.parametrize(("last", "said"), [
    ("  - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}\n", True),
    ("  - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}\n"
     "  - {type: descent, to_altitude_m: 0, airspeed_m_s: 20, throttle: 0.1}\n", False),
])
def test_a_mission_that_ends_in_the_air_says_it_did_not_land(tmp_path, last, said) -> None:
    """A take-off and a climb to 100 m 'landed with 93.4 %' and PASSed, unsaid (outside
    audit): the descent and landing are not flown, and the flight says so."""
    from tuflexperf.analysis.mission import solve_mission

    case = load_case(copy_shipped_case(tmp_path))
    path = tmp_path / "m.yaml"
    path.write_text("name: m\nsegments:\n  - {type: takeoff}\n" + last)
    flown = solve_mission(case, load_mission(path))
    assert flown.attainable
    notes = [w for w in flown.warnings if "descent and landing are not flown" in w]
    assert bool(notes) is said
    if said:
        assert "ends 100 m above the field" in notes[0]


def _case_with_mission(tmp_path: Path, mission_text: str, reserve: float = 0.2) -> Path:
    """The shipped case, its only requirement the mission ``mission_text`` (a file beside)."""
    import yaml

    case = copy_shipped_case(tmp_path)
    (case.parent / "planned.yaml").write_text(textwrap.dedent(mission_text))
    data = yaml.safe_load(case.read_text())
    data["requirements"] = {"mission": {"file": "planned.yaml",
                                        "min_landing_charge_fraction": reserve}}
    case.write_text(yaml.safe_dump(data, sort_keys=False))
    return case


PLANNED = """\
    name: planned
    segments:
      - {type: takeoff}
      - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}
      - {type: cruise, airspeed_m_s: 26, CRUISE}
      - {type: engine_failure, engine: EDF2}
      - {type: loiter, airspeed_m_s: 20, time_min: LOITER}
      - {type: descent, to_altitude_m: 0, airspeed_m_s: 20, throttle: 0.1}
"""


@pytest.mark.parametrize(("cruise", "loiter", "fits"), [
    ("time_min: 8", 12.2, False), ("time_min: 8", 2, True), ("distance_km: 5", 2, True),
    ("distance_km: 13", 12.2, False),
])
def test_check_holds_a_solved_mission_to_the_time_its_file_plans(
        tmp_path: Path, cruise: str, loiter: float, fits: bool) -> None:
    """With solve_for the flown mission lands on the reserve by construction: check passed
    a cruise planned at 8 min whose longest is 0.47 min, and never showed the 0.47 (outside
    audit). The plan's verdict is now that of the same file without solve_for."""
    from typer.testing import CliRunner

    from tuflexperf.cli import app

    plan = PLANNED.replace("CRUISE", cruise).replace("LOITER", str(loiter))
    solved_case = _case_with_mission(tmp_path / "solved", plan + "    solve_for: cruise\n")
    plain_case = _case_with_mission(tmp_path / "plain", plan)
    runner = CliRunner()
    out = runner.invoke(app, ["check", "--json", "--case", str(solved_case)])
    results = {r["name"]: r for r in json.loads(out.stdout)["results"]}
    assert set(results) == {"mission_landing_charge", "mission_solved_time"}
    solved = results["mission_solved_time"]
    flown = json.loads(runner.invoke(app, ["mission", "--json", "--case", str(solved_case)]).stdout)
    written = 8.0 if cruise == "time_min: 8" else None
    if written is None:  # a distance: its time at the segment's true airspeed (26 m/s EAS)
        km = float(cruise.split(":")[1])
        written = 1000.0 * km / float(true_airspeed_m_s(26.0, isa_density_kg_m3(100.0))) / 60.0
        assert flown["solved"]["written_distance_km"] == km
    assert solved["limit"] == pytest.approx(written, rel=1e-12)
    # EDF2 fails in it, and its windmilling coefficient and thrust model disagree: the value
    # shown is the worse reading's, the first reading the mission as flown
    nominal = solved["readings"][0]["value"] if "readings" in solved else solved["value"]
    assert nominal == pytest.approx(flown["solved"]["time_min"], rel=1e-12)
    assert solved["passed"] is fits and json.loads(out.stdout)["passed"] is fits
    assert out.exit_code == (0 if fits else 1)
    # the mission command gives the same verdict, and the file as written agrees with both
    assert flown["passed"] is fits
    by_mission = {r["name"]: r for r in flown["results"]}["mission_solved_time"]
    assert by_mission["verdict"] == solved["verdict"]
    assert by_mission["value"] == (None if solved["value"] is None
                                   else pytest.approx(solved["value"], rel=1e-12))
    plain = json.loads(runner.invoke(app, ["check", "--json", "--case", str(plain_case)]).stdout)
    assert plain["passed"] is fits
    text = runner.invoke(app, ["mission", "--case", str(solved_case)]).stdout
    assert f"solve_for: {flown['solved']['time_min']:.2f} min" in text
    line = next(x for x in text.splitlines() if x.startswith("  solve_for:"))
    assert line.endswith("PASS" if fits else "FAIL")  # the readings' lines follow it


@pytest.mark.parametrize("loiter_min", [100, 21])
def test_solve_for_after_a_segment_that_empties_the_packs_names_that_segment(
        tmp_path: Path, loiter_min: int) -> None:
    """A 100 min loiter before the solved cruise hits the cut-off; the solve blamed the
    cruise with "the rest of the mission alone leaves -80.0 %" (an emptied pack's marker;
    outside audit). The file without solve_for names the loiter, and so does the solve."""
    body = f"""\
        name: x
        segments:
          - {{type: takeoff}}
          - {{type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}}
          - {{type: loiter, airspeed_m_s: 26, time_min: {loiter_min}}}
          - {{type: cruise, airspeed_m_s: 26, time_min: 5}}
          - {{type: descent, to_altitude_m: 0, airspeed_m_s: 20, throttle: 0.1}}
        """
    case = load_case(None)
    plain = MissionModel(case, load_mission(_mission(tmp_path, body)), None).fly()
    solved = MissionModel(case, load_mission(_mission(tmp_path, body + "solve_for: cruise\n")),
                          None)
    with pytest.raises(NotAttainable) as refused:
        solved.solve_for()
    said = str(refused.value)
    if loiter_min == 100:
        assert not plain.attainable and plain.reason.startswith("segment 3 (loiter)")
        assert said.startswith(plain.reason) and "segment 4 (cruise), the one solved for" in said
    else:  # the rest lands, short of the reserve: by how much, as flown without the cruise
        left = float(said.split("leaves ")[1].split(" %")[0])
        assert said.startswith("segment 4 (cruise): no duration lands") and 0 < left < 20


def test_a_climb_with_thrust_above_weight_is_flown_vertical_and_said(tmp_path: Path) -> None:
    """At 3 kg the full-throttle excess thrust is above the weight: the small-angle rate of
    climb ``(T - D) V / W`` would climb faster than the aircraft flies (an outside audit saw
    85 m gained on a 21 m path). The climb is vertical at most: height gained <= path flown,
    equal where it is vertical, and the result says so."""
    from tuflexperf.io.dotted import with_values

    path = _mission(tmp_path, """\
        name: light
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}
          - {type: cruise, airspeed_m_s: 26, time_min: 1}
        """)
    case = with_values(load_case(None), {"aircraft.mass_kg": 3.0})
    model = MissionModel(case, load_mission(path), None)
    result = model.fly()
    assert result.attainable, result.reason
    sl = _segment_slice(model, 1)
    h, dist = result.history["altitude_m"][sl], result.history["distance_m"][sl]
    climbed, flown = np.diff(h), np.diff(dist)
    assert np.all(climbed <= flown * (1 + 1e-9))
    assert climbed == pytest.approx(flown, rel=1e-9)  # vertical all the way, at 3 kg
    assert result.history["climb_rate_m_s"][sl] == pytest.approx(
        result.history["airspeed_m_s"][sl], rel=1e-12)
    assert any(w.startswith("segment 2 (climb): thrust at throttle 1 exceeds weight plus drag")
               for w in result.warnings)
    # the shipped mass climbs at a gradient below 1 and says nothing of it
    heavy = MissionModel(load_case(None), load_mission(path), None).fly()
    assert not any("weight plus drag" in w for w in heavy.warnings)


def test_a_commanded_climb_steeper_than_vertical_is_not_attainable(tmp_path: Path) -> None:
    """25 m/s of climb at 20 m/s: a path steeper than vertical, whatever the thrust."""
    path = _mission(tmp_path, """\
        name: steep
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, climb_rate_m_s: 25}
          - {type: cruise, airspeed_m_s: 26, time_min: 1}
        """)
    result = MissionModel(load_case(None), load_mission(path), None).fly()
    assert not result.attainable
    assert ("segment 2 (climb): a climb at 25 m/s is steeper than vertical at 20.0 m/s true "
            "airspeed: not attainable") in result.reason


def test_a_climb_that_cannot_climb_says_nothing_of_a_vertical_climb(tmp_path: Path) -> None:
    """Throttle 0.3 at 20 m/s: thrust below drag, so the climb fails; the nodes integrated
    past that failure (unphysical states, enormous densities) are not read for the vertical
    note (it said "exceeds weight plus drag: flown as a vertical climb" beside the FAIL)."""
    path = _mission(tmp_path, """\
        name: weak
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 0.3}
        """)
    result = MissionModel(load_case(None), load_mission(path), None).fly()
    assert not result.attainable
    assert "segment 2 (climb): cannot climb at throttle 0.3" in result.reason
    assert not any("weight plus drag" in w for w in result.warnings)


def test_solve_for_sees_a_cutoff_in_a_later_one_engine_segment(tmp_path: Path) -> None:
    """A cruise before an engine failure: the one-engine loiter after it draws the most and
    cuts off first. The longest cruise is the one whose loiter just reaches the cut-off; the
    search looked at the cruise's own end only, answered the reserve's longer cruise and then
    refused it (outside audit: 18.43 min, where 16.04 min is the longest that flies)."""
    from tuflexperf.io.dotted import with_values

    case = with_values(load_case(None), {"battery.cutoff_voltage_per_cell_v": 3.7})
    path = _mission(tmp_path, """\
        name: a loiter on one engine after the cruise
        segments:
          - {type: takeoff}
          - {type: climb, to_altitude_m: 100, airspeed_m_s: 20, throttle: 1.0}
          - {type: cruise, airspeed_m_s: 26, time_min: 8}
          - {type: engine_failure, engine: EDF2}
          - {type: loiter, airspeed_m_s: 20, time_min: 2}
          - {type: descent, to_altitude_m: 0, airspeed_m_s: 20, throttle: 0.1}
        solve_for: cruise
        """)
    model = MissionModel(case, load_mission(path), 0.2)
    solved = model.solve_for()
    assert solved.attainable and solved.passed, solved.reason
    assert solved.solved["ends_at"] == "cut-off"
    assert solved.landing_charge_fraction > 0.2  # the cut-off, not the reserve, binds
    loiter = solved.segments[4]
    assert loiter.type == "loiter"
    assert loiter.min_voltage_v == pytest.approx(model.cutoff_v, abs=1e-6)
    # flown as a plain mission: the answer is where the flight turns not attainable
    durations = model.durations.copy()
    for seconds, flies in ((-1.0, True), (1.0, False)):
        durations[2] = 60.0 * solved.solved["time_min"] + seconds
        assert model.fly(durations).attainable == flies


def test_a_set_cutoff_is_the_one_reported_and_drawn(tmp_path: Path) -> None:
    """``--set battery.cutoff_voltage_per_cell_v`` is flown, and the endurance's JSON and the
    mission's result (whose figure draws the line) carry that cut-off, not the file's 40.8 V
    (outside audit: the figure showed a 5 V margin where 0.85 V was left)."""
    from tuflexperf.analysis.study import Study
    from tuflexperf.io.dotted import with_values

    shipped_case = load_case(None)
    case = with_values(shipped_case, {"battery.cutoff_voltage_per_cell_v": 3.6})
    study = Study(case)
    battery = study.endurance_model().battery
    flown = battery.cutoff_voltage_v
    assert flown == pytest.approx(3.6 * battery.cells_in_series)
    assert flown != Study(shipped_case).endurance_model().battery.cutoff_voltage_v
    assert study.endurance(0.5).to_dict()["cutoff_voltage_v"] == flown
    mission = MissionModel(case, load_mission(SHIPPED_MISSION), 0.2).fly()
    assert mission.cutoff_voltage_v == flown
