"""`performance` against closed forms on made-up aircraft with quadratic thrust.

Thrust at full throttle ``T(V) = s (A + C V^2)`` with ``s = rho / rho_ref`` (SPEC 3),
drag ``D = P V^2 + Q / V^2`` with ``P = rho S cd0 / 2`` and ``Q = 2 k W^2 / (rho S)``,
and ``a = s C - P``:

- max / least level speed: ``a u^2 + s A u - Q = 0`` with ``u = V^2`` (Anderson, Aircraft
  Performance and Design, 5.4, the jet case with a quadratic thrust term);
- Vy: ``d/dV [V (T - D)] = 0``: ``3 a u^2 + s A u + Q = 0``; rate of climb ``V (T - D) / W``
  (Anderson 5.10);
- Vx: ``d/dV [(T - D) / W] = 0``: ``V^4 = -Q / a``;
- ceilings: the altitude where the (stall-bounded) best rate of climb equals 0.5 m/s
  (service) or 0 (absolute), by Brent's method on the closed-form best rate of climb,
  density from an ISA written out here (Anderson 5.11).
Each is bounded below by stall x margin. Tolerances 1e-7 (speeds, rates) and 1e-6
(ceilings) are far above the Newton rootfinders' round-off (abstol 1e-12).
"""

from __future__ import annotations

import copy
import json
import math

import pytest
from scipy.optimize import brentq

from tests.conftest import write_case
from tuflexperf.analysis.performance import solve_performance
from tuflexperf.cli import main
from tuflexperf.io.case import load_case

G = 9.80665
A_TOTAL, C_TOTAL = 80.0, -0.01
AIRCRAFT = {
    "name": "quadratic-thrust test aircraft",
    "mass_kg": 20.0,
    "wing_area_m2": 1.0,
    "cd0": 0.03,
    "k": 0.05,
    "cl_max": 1.6,
    "takeoff": {"cl_ground": 0.4, "rolling_friction": 0.05},
}


def _propulsion(reference=1.225, idle_drag=True):
    # p20 carries the throttle, so T(0, V) = p02 V^2 < 0: a windmilling dead fan is a drag
    half = {"p00": 0.0, "p10": 0.0, "p01": 0.0, "p20": A_TOTAL / 2, "p11": 0.0,
            "p02": C_TOTAL / 2 if idle_drag else 0.0}
    if not idle_drag:
        half["p11"] = 0.0
    prop = {
        "name": "quadratic fans",
        "model": "poly22",
        "tested_airspeed_m_s": [0, 80],
        "engines": [{"name": "L", "coefficients": dict(half)},
                    {"name": "R", "coefficients": dict(half)}],
    }
    if reference is not None:
        prop["reference_density_kg_m3"] = reference
    return prop


def _isa_density(h: float, offset: float = 0.0) -> float:
    if h <= 11000.0:
        t = 288.15 - 0.0065 * h
        p = 101325.0 * (t / 288.15) ** (G / (287.05287 * 0.0065))
    else:
        t = 216.65
        p = 22632.0400859 * math.exp(-G * (h - 11000.0) / (287.05287 * t))
    return p / (287.05287 * (t + offset))


class ClosedForm:
    def __init__(self, aircraft, rho, sigma, a_thrust, c_thrust, margin=1.0):
        self.w = aircraft["mass_kg"] * G
        s = aircraft["wing_area_m2"]
        self.p = 0.5 * rho * s * aircraft["cd0"]
        self.q = 2 * aircraft["k"] * self.w**2 / (rho * s)
        self.sa, self.a = sigma * a_thrust, sigma * c_thrust - self.p
        self.sc = sigma * c_thrust
        self.stall = margin * math.sqrt(2 * self.w / (rho * s * aircraft["cl_max"]))

    def excess(self, v):
        return self.sa + self.sc * v * v - self.p * v * v - self.q / (v * v)

    def rate(self, v):
        return v * self.excess(v) / self.w

    def level_speeds(self):
        disc = self.sa**2 + 4 * self.a * self.q
        u_max = (-self.sa - math.sqrt(disc)) / (2 * self.a)
        u_min = (-self.sa + math.sqrt(disc)) / (2 * self.a)
        return max(math.sqrt(u_min), self.stall), math.sqrt(u_max)

    def vy(self):
        u = (-self.sa - math.sqrt(self.sa**2 - 12 * self.a * self.q)) / (6 * self.a)
        return max(math.sqrt(u), self.stall)

    def vx(self):
        return max((-self.q / self.a) ** 0.25, self.stall)


def _case(tmp_path, aircraft=None, propulsion=None, atmosphere=None, requirements=None):
    return load_case(write_case(tmp_path, aircraft or AIRCRAFT, propulsion or _propulsion(),
                                requirements={} if requirements is None else requirements,
                                atmosphere=atmosphere))


@pytest.mark.parametrize(
    ("altitude", "offset", "margin"),
    [(0.0, 0.0, 1.0), (1500.0, 20.0, 1.0), (3000.0, -10.0, 1.2)],
)
def test_speeds_and_climb_equal_closed_forms(tmp_path, altitude, offset, margin):
    requirements = {"envelope": {"min_airspeed_m_s": 15, "max_airspeed_m_s": 40,
                                 "stall_margin": margin}}
    case = _case(tmp_path, atmosphere={"altitude_m": altitude, "temperature_offset_k": offset},
                 requirements=requirements)
    rho = _isa_density(altitude, offset)
    cf = ClosedForm(AIRCRAFT, rho, rho / 1.225, A_TOTAL, C_TOTAL, margin)
    r = solve_performance(case)
    v_min, v_max = cf.level_speeds()
    assert r.stall_speed_m_s * margin == pytest.approx(cf.stall, rel=1e-9)
    assert r.least_airspeed_m_s == pytest.approx(cf.stall, rel=1e-9)
    assert r.max_level_speed_m_s == pytest.approx(v_max, rel=1e-7)
    assert r.min_level_speed_m_s == pytest.approx(v_min, rel=1e-7)
    assert r.best_climb_rate_speed_m_s == pytest.approx(cf.vy(), rel=1e-7)
    assert r.max_climb_rate_m_s == pytest.approx(cf.rate(cf.vy()), rel=1e-7)
    assert r.best_climb_angle_speed_m_s == pytest.approx(cf.vx(), rel=1e-7)
    assert r.max_climb_gradient == pytest.approx(cf.excess(cf.vx()) / cf.w, rel=1e-7)
    k, s = AIRCRAFT["k"], AIRCRAFT["wing_area_m2"]
    vmd = math.sqrt(2 * cf.w / (rho * s) * math.sqrt(k / AIRCRAFT["cd0"]))
    assert r.minimum_drag_speed_m_s == pytest.approx(max(vmd, cf.stall), rel=1e-9)
    # the climb curve (for the report's figure) is the closed-form rate at its airspeeds
    for v, rate in zip(r.climb_airspeed_m_s, r.climb_rate_curve_m_s, strict=True):
        assert rate == pytest.approx(cf.rate(v), rel=1e-9, abs=1e-12)
    assert r.climb_airspeed_m_s[0] == pytest.approx(cf.stall, rel=1e-9)


def _best_rate_at(h, offset=0.0, reference=1.225, aircraft=AIRCRAFT):
    rho = _isa_density(h, offset)
    cf = ClosedForm(aircraft, rho, rho / reference, A_TOTAL, C_TOTAL)
    return cf.rate(cf.vy())


@pytest.mark.parametrize(
    ("offset", "cl_max"),
    [(0.0, 1.6), (15.0, 1.6), (0.0, 0.35)],  # 0.35: Vy is on the stall bound at the ceiling
)
def test_ceilings_with_density_lapse_equal_closed_form(tmp_path, offset, cl_max):
    # the ground roll's lift coefficient at most cl_max (the ceilings do not depend on it)
    aircraft = {**AIRCRAFT, "cl_max": cl_max,
                "takeoff": {**AIRCRAFT["takeoff"],
                            "cl_ground": min(AIRCRAFT["takeoff"]["cl_ground"], cl_max)}}
    case = _case(tmp_path, aircraft,
                 atmosphere={"altitude_m": 0, "temperature_offset_k": offset})
    r = solve_performance(case)

    def best(h):
        return _best_rate_at(h, offset, aircraft=aircraft)

    service = brentq(lambda h: best(h) - 0.5, 0.0, 20000.0, xtol=1e-9)
    absolute = brentq(best, 0.0, 20000.0, xtol=1e-9)
    assert r.service_ceiling_m == pytest.approx(service, rel=1e-6)
    assert r.absolute_ceiling_m == pytest.approx(absolute, rel=1e-6)
    assert 0 < service < absolute < 20000


@pytest.mark.parametrize("tested_top", [36.0, 37.0, 60.0])
def test_a_ceiling_flown_beyond_the_tested_airspeeds_is_said(tmp_path, tested_top):
    """True airspeeds grow with altitude: Vy at the ceilings (closed form, 36.4 and 37.5 m/s)
    extrapolates a model tested to 36 m/s and not one tested to 60; only the sea-level
    speeds were checked (SPEC: extrapolation is said)."""
    propulsion = {**_propulsion(), "tested_airspeed_m_s": [0, tested_top]}
    r = solve_performance(_case(tmp_path, propulsion=propulsion))
    said = " ".join(w for w in r.warnings if "extrapolated" in w)
    for label, height in (("service ceiling", r.service_ceiling_m),
                          ("absolute ceiling", r.absolute_ceiling_m)):
        rho = _isa_density(height)
        vy = ClosedForm(AIRCRAFT, rho, rho / 1.225, A_TOTAL, C_TOTAL).vy()
        assert (label in said) == (vy > tested_top), (label, vy)
    v_max = ClosedForm(AIRCRAFT, _isa_density(0.0), 1.0, A_TOTAL, C_TOTAL).level_speeds()[1]
    assert ("max level speed" in said) == (v_max > tested_top)
    assert (said == "") == (tested_top == 60.0)


def test_ceiling_without_lapse_is_not_claimed(tmp_path):
    r = solve_performance(_case(tmp_path, propulsion=_propulsion(reference=None)))
    # thrust as measured at every altitude: this aircraft climbs at 20 km; no ceiling is made up
    assert r.absolute_ceiling_m is None and r.service_ceiling_m is None
    assert any("20000 m" in n for n in r.notes)
    assert any("reference_density_kg_m3" in w for w in r.warnings)


@pytest.mark.parametrize("mode", ["zero", "windmilling"])
def test_oei_closed_forms(tmp_path, mode):
    requirements = {"oei": {"dead_engine": mode, "max_throttle": 1.0}}
    r = solve_performance(_case(tmp_path, requirements=requirements))
    rho = _isa_density(0.0)
    # live fan A/2 + C/2 V^2; a windmilling dead fan adds its T(0, V) = C/2 V^2 (a drag)
    c_oei = C_TOTAL / 2 + (C_TOTAL / 2 if mode == "windmilling" else 0.0)
    cf = ClosedForm(AIRCRAFT, rho, 1.0, A_TOTAL / 2, c_oei)
    assert r.oei_max_level_speed_m_s == pytest.approx(cf.level_speeds()[1], rel=1e-7)
    assert r.oei_max_climb_gradient == pytest.approx(cf.excess(cf.vx()) / cf.w, rel=1e-7)
    assert r.oei[0].max_climb_gradient_speed_m_s == pytest.approx(cf.vx(), rel=1e-7)


def test_stall_bounds_vx_and_least_speed(tmp_path):
    aircraft = copy.deepcopy(AIRCRAFT)
    aircraft["cl_max"] = 0.5  # stall 28 m/s, above the unbounded Vx of 18 m/s
    r = solve_performance(_case(tmp_path, aircraft))
    rho = _isa_density(0.0)
    cf = ClosedForm(aircraft, rho, 1.0, A_TOTAL, C_TOTAL)
    assert (-cf.q / cf.a) ** 0.25 < cf.stall
    assert r.best_climb_angle_speed_m_s == pytest.approx(cf.stall, rel=1e-7)
    assert r.min_level_speed_m_s == pytest.approx(cf.stall, rel=1e-9)
    assert any("stall-bounded" in n for n in r.notes)


def test_no_level_flight_is_exit_1_with_json(tmp_path, capsys):
    aircraft = copy.deepcopy(AIRCRAFT)
    aircraft["mass_kg"] = 200.0  # 80 N of thrust cannot hold 1960 N level
    path = write_case(tmp_path, aircraft, _propulsion(), requirements={})
    with pytest.raises(SystemExit) as exc:
        main(["performance", "--case", str(path), "--json"])
    assert exc.value.code == 1
    data = json.loads(capsys.readouterr().out)
    assert data["attainable"] is False and data["max_level_speed_m_s"] is None
    assert data["max_climb_rate_m_s"] < 0


def test_thrust_that_outgrows_drag_gives_no_max_speed(tmp_path):
    prop = _propulsion()
    for engine in prop["engines"]:
        engine["coefficients"]["p02"] = 0.05  # thrust grows faster than parasite drag
    r = solve_performance(_case(tmp_path, propulsion=prop))
    assert r.max_level_speed_m_s is None
    assert any("no maximum level speed" in n for n in r.notes)


def test_json_has_the_spec_keys(tmp_path, capsys):
    path = write_case(tmp_path, AIRCRAFT, _propulsion(), requirements={
        "takeoff": {"max_ground_roll_m": 100}})
    with pytest.raises(SystemExit) as exc:
        main(["performance", "--case", str(path), "--json"])
    assert exc.value.code == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("stall_speed_m_s", "minimum_drag_speed_m_s", "max_level_speed_m_s",
                "max_climb_rate_m_s", "best_climb_rate_speed_m_s", "best_climb_angle_speed_m_s",
                "service_ceiling_m", "absolute_ceiling_m", "oei_max_climb_gradient",
                "takeoff_distance_to_obstacle_m", "climb"):
        assert key in data
    assert len(data["climb"]["airspeed_m_s"]) == len(data["climb"]["climb_rate_m_s"]) > 10
    assert data["takeoff_distance_to_obstacle_m"] > 0


def test_thrust_above_weight_is_a_vertical_climb_said_and_bounded(tmp_path):
    """80 N of static thrust on a 5 kg aircraft (49 N): the small-angle gradient
    ``(T - D) / W`` passes 1 over a band of airspeeds. A climb cannot be steeper than
    vertical: the gradient is held at 1 and the rate of climb at the airspeed there
    (``V min((T - D) / W, 1)``), and the result says where (outside audit: a gradient of
    11.08 was printed)."""
    light = {**AIRCRAFT, "mass_kg": 5.0}
    r = solve_performance(_case(tmp_path, aircraft=light))
    rho = _isa_density(0.0)
    cf = ClosedForm(light, rho, rho / 1.225, A_TOTAL, C_TOTAL)

    def capped(v):
        return v * min(cf.excess(v) / cf.w, 1.0)

    # the band where T - D > W: a u^2 + (sA - W) u - Q = 0 in u = V^2
    disc = (cf.sa - cf.w) ** 2 + 4 * cf.a * cf.q
    top = math.sqrt((-(cf.sa - cf.w) - math.sqrt(disc)) / (2 * cf.a))
    low = max(math.sqrt((-(cf.sa - cf.w) + math.sqrt(disc)) / (2 * cf.a)), cf.stall)
    assert cf.excess(0.5 * (low + top)) > cf.w  # the case does climb vertically
    assert r.max_climb_gradient == 1.0
    assert low * (1 - 1e-9) <= r.best_climb_angle_speed_m_s <= top * (1 + 1e-9)
    for v, rate in zip(r.climb_airspeed_m_s, r.climb_rate_curve_m_s, strict=True):
        assert rate == pytest.approx(capped(v), rel=1e-9)
    # the best rate of climb: a golden section on the closed form (no steady climb beyond V)
    lo, hi = cf.stall, r.max_level_speed_m_s
    for _ in range(200):
        m1, m2 = hi - 0.618034 * (hi - lo), lo + 0.618034 * (hi - lo)
        lo, hi = (lo, m2) if capped(m1) >= capped(m2) else (m1, hi)
    assert r.max_climb_rate_m_s == pytest.approx(capped(0.5 * (lo + hi)), rel=1e-7)
    assert r.max_climb_rate_m_s <= r.best_climb_rate_speed_m_s * (1 + 1e-12)
    said = [w for w in r.warnings if w.startswith("full thrust exceeds weight plus drag")]
    assert len(said) == 1
    band = [float(x) for x in said[0].split(" at ")[1].split(" m/s")[0].split("-")]
    step = (r.climb_airspeed_m_s[-1] - cf.stall) / 1200  # the scan's spacing at most
    assert band[0] == pytest.approx(low, abs=0.05 + step)
    assert band[1] == pytest.approx(top, abs=0.05 + step)
    assert not any("stall-bounded" in note for note in r.notes)
    # the shipped-like mass climbs at a gradient below 1 and says nothing of it
    heavy = solve_performance(_case(tmp_path / "heavy"))
    assert heavy.max_climb_gradient < 1.0
    assert not any("weight plus drag" in w for w in heavy.warnings)
