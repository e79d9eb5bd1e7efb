"""Analyses against closed forms: Raymer-style ground roll and exact quadratic trim roots."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from tests.conftest import MADE_UP_AIRCRAFT, MADE_UP_PROPULSION, write_case
from tuflexperf.analysis.level_flight import airspeed_grid
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import load_case
from tuflexperf.models.aircraft import level_flight_drag_n
from tuflexperf.models.atmosphere import isa_density_kg_m3


def _quadratic_thrust_case(tmp_path, static_n, lapse_n_s2_m2, liftoff=None, **takeoff):
    """One engine with T(1, V) = T0 - a V^2: the ground roll has a closed form."""
    aircraft = copy.deepcopy(MADE_UP_AIRCRAFT)
    aircraft["takeoff"].update(takeoff)
    if liftoff is not None:
        aircraft["takeoff"]["liftoff_speed_m_s"] = liftoff
    propulsion = copy.deepcopy(MADE_UP_PROPULSION)
    propulsion["engines"] = [
        {
            "name": "only",
            "coefficients": {
                "p00": 0.0,
                "p10": static_n,
                "p01": 0.0,
                "p20": 0.0,
                "p11": 0.0,
                "p02": -lapse_n_s2_m2,
            },
        }
    ]
    return load_case(write_case(tmp_path, aircraft, propulsion, requirements={}))


def _closed_form_roll(case, static_n, lapse):
    """s = m/(2B) ln(A/(A - B V^2)), t = m/sqrt(AB) artanh(V sqrt(B/A)) for F = A - B V^2."""
    ac, rho = case.aircraft, case.density_kg_m3
    to = ac.takeoff
    cd0 = ac.cd0 if to.cd0_ground is None else to.cd0_ground
    k = ac.k if to.k_ground is None else to.k_ground
    a_force = static_n - to.rolling_friction * ac.weight_n
    b_force = lapse + 0.5 * rho * ac.wing_area_m2 * (
        cd0 + k * to.cl_ground**2 - to.rolling_friction * to.cl_ground
    )
    v = to.liftoff_speed_m_s or 1.1 * math.sqrt(
        2 * ac.weight_n / (rho * ac.wing_area_m2 * ac.cl_max)
    )
    distance = ac.mass_kg / (2 * b_force) * math.log(a_force / (a_force - b_force * v * v))
    time = ac.mass_kg / math.sqrt(a_force * b_force) * math.atanh(v * math.sqrt(b_force / a_force))
    return distance, time, v


@pytest.mark.parametrize(
    ("static_n", "lapse", "extra"),
    [
        (90.0, 0.02, {}),
        (60.0, 0.05, {"cd0_ground": 0.06, "k_ground": 0.02}),
        (120.0, 0.01, {"rolling_friction": 0.1}),
        (45.0, 0.08, {"liftoff": 17.0}),
    ],
)
def test_ground_roll_equals_closed_form(tmp_path, static_n, lapse, extra):
    case = _quadratic_thrust_case(tmp_path, static_n, lapse, **extra)
    result = solve_takeoff(case)
    distance, time, v_lo = _closed_form_roll(case, static_n, lapse)
    assert result.liftoff_speed_m_s == pytest.approx(v_lo, rel=1e-12)
    assert result.ground_roll_m == pytest.approx(distance, rel=1e-6)
    assert result.time_s == pytest.approx(time, rel=1e-6)
    # the history is monotonic and ends at the answer
    assert np.all(np.diff(result.history_distance_m) > 0)
    assert result.history_distance_m[-1] == result.ground_roll_m


def test_ground_roll_never_lifts_off(tmp_path):
    # net force A - B V^2 vanishes at sqrt(A/B) < lift-off speed
    import re

    from scipy.optimize import brentq

    from tuflexperf.analysis.ground_roll import net_force_n
    from tuflexperf.models.aircraft import liftoff_speed_m_s

    case = _quadratic_thrust_case(tmp_path, 40.0, 0.3, liftoff=15.0)
    with pytest.raises(NotAttainable, match="never reaches lift-off") as caught:
        solve_takeoff(case)
    rho = case.density_kg_m3
    v_lo = float(liftoff_speed_m_s(case.aircraft, rho))
    # the speed where the roll stalls, to the message's two decimals, against a root-finder
    root = brentq(lambda v: float(net_force_n(case.aircraft, case.propulsion, v, rho)),
                  0.0, v_lo, xtol=1e-12)
    said = float(re.search(r"vanishes at ([0-9.]+) m/s", str(caught.value)).group(1))
    assert said == pytest.approx(root, abs=0.006)
    # what was known before the answer was no goes with it (the JSON's keys on exit 1)
    assert caught.value.known["liftoff_speed_m_s"] == pytest.approx(v_lo, rel=1e-12)


def test_ground_roll_never_starts(tmp_path):
    case = _quadratic_thrust_case(tmp_path, 5.0, 0.0)  # 5 N < 0.05 x 176 N friction
    with pytest.raises(NotAttainable, match="never starts"):
        solve_takeoff(case)


def _exact_least_throttle(a, b, c):
    """Least x in [0, 1] with a x^2 + b x + c >= 0; NaN if none (closed form)."""
    if c >= 0:
        return 0.0
    if abs(a) < 1e-15:
        roots = [-c / b] if b != 0 else []
    else:
        disc = b * b - 4 * a * c
        if disc < 0:
            return math.nan
        sq = math.sqrt(disc)
        roots = sorted([(-b - sq) / (2 * a), (-b + sq) / (2 * a)])
    for r in roots:
        if 0 <= r <= 1:
            return r
    return math.nan


def _excess_quadratic(case, v, engines, dead=None, mode="windmilling"):
    """Coefficients of total thrust - drag as a quadratic in a common throttle x."""
    rho = case.density_kg_m3
    scale = (
        1.0
        if case.propulsion.reference_density_kg_m3 is None
        else rho / case.propulsion.reference_density_kg_m3
    )
    a = b = c = 0.0
    for i, e in enumerate(engines):
        p = e["coefficients"]
        zero = p["p00"] + p["p01"] * v + p["p02"] * v * v
        if i == dead:
            if mode == "windmilling":
                c += scale * min(zero, 0.0)
            continue
        a += scale * p["p20"]
        b += scale * (p["p10"] + p["p11"] * v)
        c += scale * zero
    return a, b, c - float(level_flight_drag_n(case.aircraft, v, rho))


@pytest.mark.parametrize(
    "atmosphere",
    [
        {"altitude_m": 0, "temperature_offset_k": 0},
        {"altitude_m": 2200, "temperature_offset_k": 25},
    ],
)
def test_trim_equals_exact_roots(tmp_path, atmosphere):
    propulsion = copy.deepcopy(MADE_UP_PROPULSION)
    propulsion["reference_density_kg_m3"] = 1.19  # thrust scales with density (hot and high)
    case = load_case(write_case(tmp_path, propulsion=propulsion, atmosphere=atmosphere))
    assert case.density_kg_m3 == pytest.approx(float(isa_density_kg_m3(**atmosphere)))
    result = solve_trim(case)
    assert np.allclose(np.diff(result.airspeed_m_s), 0.5)
    ac = case.aircraft
    stall = math.sqrt(2 * ac.weight_n / (case.density_kg_m3 * ac.wing_area_m2 * ac.cl_max))
    for v, x in zip(result.airspeed_m_s, result.throttle, strict=True):
        expected = _exact_least_throttle(*_excess_quadratic(case, v, propulsion["engines"]))
        if v < stall:  # hot and high: the envelope's foot is below stall (SPEC 3)
            assert math.isnan(x)
        elif math.isnan(expected):
            assert math.isnan(x)
        else:
            assert x == pytest.approx(expected, abs=1e-9)


def test_trim_needs_more_than_full_throttle_at_the_top(tmp_path):
    requirements = {"envelope": {"min_airspeed_m_s": 14, "max_airspeed_m_s": 48}}
    case = load_case(write_case(tmp_path, requirements=requirements))
    result = solve_trim(case)
    data = result.to_dict()
    assert not data["all_feasible"]
    assert data["throttle"][-1] is None and data["throttle"][0] is not None
    assert data["max_throttle"] is None
    top = np.array(data["throttle"], dtype=float)
    # the infeasible airspeeds are exactly those where full throttle falls short
    engines = MADE_UP_PROPULSION["engines"]
    for v, x in zip(result.airspeed_m_s, top, strict=True):
        a, b, c = _excess_quadratic(case, v, engines)
        assert math.isnan(x) == (a + b + c < 0)


@pytest.mark.parametrize("mode", ["windmilling", "zero"])
def test_oei_equals_exact_roots_each_engine_dead(tmp_path, mode):
    case = load_case(write_case(tmp_path))
    result = solve_oei(case, mode)
    engines = MADE_UP_PROPULSION["engines"]
    worst_min = -1.0
    for dead, dead_case in enumerate(result.cases):
        exact = np.array(
            [
                _exact_least_throttle(*_excess_quadratic(case, v, engines, dead, mode))
                for v in dead_case.airspeed_m_s
            ]
        )
        assert np.allclose(dead_case.throttle, exact, atol=1e-9, equal_nan=True)
        finite = exact[np.isfinite(exact)]
        if finite.size:
            assert dead_case.min_throttle == pytest.approx(finite.min(), abs=1e-9)
            feasible_v = dead_case.airspeed_m_s[np.isfinite(exact)]
            # the range is exact (SPEC 3 stall / thrust bounds), the grid lies inside it
            low, high = dead_case.level_flight_airspeed_range_m_s
            assert 0 <= feasible_v.min() - low < 0.5 and 0 <= high - feasible_v.max() < 0.5
            worst_min = max(worst_min, finite.min())
    assert result.to_dict()["min_throttle"] == pytest.approx(worst_min, abs=1e-9)


def test_windmilling_needs_more_throttle_than_zero(tmp_path):
    case = load_case(write_case(tmp_path))
    windmilling = solve_oei(case, "windmilling").to_dict()["min_throttle"]
    zero = solve_oei(case, "zero").to_dict()["min_throttle"]
    assert windmilling > zero


@pytest.mark.parametrize(
    ("low", "high", "n"), [(15, 45, 61), (14, 30, 33), (10, 10.3, 2), (20, 21.2, 4)]
)
def test_airspeed_grid_steps_at_most_half_a_metre_per_second(low, high, n):
    grid = airspeed_grid(low, high)
    assert grid[0] == low and grid[-1] == high and grid.size == n
    assert np.all(np.diff(grid) <= 0.5 + 1e-12)


def test_percent_throttle_file_gives_the_same_answers(tmp_path):
    """Coefficients fitted against percent (throttle_unit: percent) mean the same aircraft."""
    percent = copy.deepcopy(MADE_UP_PROPULSION)
    percent["throttle_unit"] = "percent"
    for engine in percent["engines"]:
        c = engine["coefficients"]
        c["p10"] /= 100.0
        c["p11"] /= 100.0
        c["p20"] /= 10000.0
    fraction_case = load_case(write_case(tmp_path / "fraction"))
    percent_case = load_case(write_case(tmp_path / "percent", propulsion=percent))
    a, b = solve_trim(fraction_case), solve_trim(percent_case)
    assert np.allclose(a.throttle, b.throttle, atol=1e-9, equal_nan=True)
    assert solve_takeoff(percent_case).ground_roll_m == pytest.approx(
        solve_takeoff(fraction_case).ground_roll_m, rel=1e-9
    )


def test_least_throttle_on_random_surfaces_equals_exact_roots():
    """Seeded random poly22 surfaces, convex and concave in throttle, against closed form:
    each surface one row of one batch (the code trim and OEI fly on one row)."""
    from tests.verification.test_least_throttle_and_study import made_up_rows
    from tuflexperf.models.thrust import POLY22_TERMS

    rng = np.random.default_rng(20261122)
    speeds = airspeed_grid(10.0, 45.0)
    surfaces = []
    for _ in range(60):
        p00, p10, p01 = rng.uniform(-1, 1), rng.uniform(0, 60), rng.uniform(-0.3, 0.0)
        p20, p11, p02 = rng.uniform(-40, 60), rng.uniform(-0.8, 0.1), rng.uniform(-2e-3, 2e-3)
        d0 = rng.uniform(2.0, 40.0)  # drag d0 ((V/30)^2 + (30/V)^2) / 2 [N], least d0 at 30 m/s
        surfaces.append(((p00, p10, p01, p20, p11, p02), d0 / 1800.0, 450.0 * d0))
    coefficients = {t: np.array([[s[0][i]] for s in surfaces])
                    for i, t in enumerate(("p00", "p10", "p01", "p20", "p11", "p02"))}
    assert set(coefficients) == set(POLY22_TERMS)
    rows = made_up_rows(coefficients, np.array([[s[1]] for s in surfaces]),
                        np.array([[s[2]] for s in surfaces]))
    got = rows.least_throttle(speeds[None, :])
    checked = 0
    for (c, parasite, induced), row in zip(surfaces, got, strict=True):
        for v, x in zip(speeds, row, strict=True):
            drag = parasite * v * v + induced / (v * v)
            expected = _exact_least_throttle(
                c[3], c[1] + c[4] * v, c[0] + c[2] * v + c[5] * v * v - drag
            )
            assert math.isnan(x) == math.isnan(expected), (v, x, expected)
            if not math.isnan(expected):
                assert x == pytest.approx(expected, abs=1e-9)
                checked += 1
    assert checked > 1000  # the random cases are mostly attainable, not vacuous
