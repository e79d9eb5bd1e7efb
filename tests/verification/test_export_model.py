"""Exact checks of the export's model layer: CasADi functions and the closed-form inverse.

No compiler needed. The references are the package's physics code (numpy) and brute force.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.c_model import throttle_for_thrust
from tests.conftest import MADE_UP_PROPULSION, model_from_propulsion_file
from tuflexperf.export.model import (
    inverse_function,
    least_throttle_reaching,
    quadratic_coefficients,
    thrust_function,
)
from tuflexperf.models.thrust import POLY22_TERMS, density_ratio, engine_thrust_n, total_thrust_n

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_PROPULSION = ROOT / "data" / "tuflex" / "propulsion.yaml"


def _variant(tmp_path: Path, name: str, **changes: object) -> Path:
    data = copy.deepcopy(MADE_UP_PROPULSION)
    data.update(changes)
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture
def models(tmp_path: Path) -> dict[str, object]:
    percent = copy.deepcopy(MADE_UP_PROPULSION["engines"])
    for engine in percent:  # the same physics with coefficients fitted against percent
        c = engine["coefficients"]
        c["p10"] /= 100.0
        c["p20"] /= 1e4
        c["p11"] /= 100.0
    return {
        "shipped": model_from_propulsion_file(SHIPPED_PROPULSION),
        "made_up": model_from_propulsion_file(_variant(tmp_path, "m")),
        "dense": model_from_propulsion_file(
            _variant(tmp_path, "d", reference_density_kg_m3=1.15)
        ),
        "percent": model_from_propulsion_file(
            _variant(tmp_path, "p", throttle_unit="percent", engines=percent)
        ),
    }


def _random_points(rng: np.random.Generator, n: int, n_engines: int) -> tuple[np.ndarray, ...]:
    throttle = rng.uniform(0.0, 1.0, (n, n_engines))
    airspeed = rng.uniform(0.0, 50.0, n)
    density = rng.uniform(0.8, 1.35, n)
    return throttle, airspeed, density


@pytest.mark.parametrize("key", ["shipped", "made_up", "dense", "percent"])
def test_casadi_thrust_function_is_the_python_model(models: dict, key: str) -> None:
    model = models[key]
    prop = model.propulsion
    n = model.n_engines
    rng = np.random.default_rng(7)
    throttle, airspeed, density = _random_points(rng, 2000, n)
    function = thrust_function(prop).map(len(airspeed))
    per_engine, total = function(throttle.T, airspeed[None, :], density[None, :])
    scale = density_ratio(prop, density)
    for i, engine in enumerate(prop.engines):
        expected = engine_thrust_n(engine, throttle[:, i], airspeed, scale)
        np.testing.assert_allclose(np.asarray(per_engine)[i], expected, rtol=0, atol=1e-9)
    expected_total = total_thrust_n(prop, list(throttle.T), airspeed, density)
    np.testing.assert_allclose(np.asarray(total).ravel(), expected_total, rtol=0, atol=1e-9)


def test_percent_model_equals_its_fraction_twin(models: dict) -> None:
    """Coefficients fitted against percent, scaled back, give the same thrust per fraction."""
    rng = np.random.default_rng(3)
    throttle, airspeed, density = _random_points(rng, 500, 2)
    a = total_thrust_n(models["made_up"].propulsion, list(throttle.T), airspeed, density)
    b = total_thrust_n(models["percent"].propulsion, list(throttle.T), airspeed, density)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("key", ["shipped", "made_up", "dense", "percent"])
def test_quadratic_coefficients_are_the_engine_sums(models: dict, key: str) -> None:
    """Derived symbolically from total_thrust_n; must equal the hand sums of poly22 terms."""
    prop = models[key].propulsion
    s = prop.engines[0].throttle_scale
    sums = {t: sum(e.coefficients[t] for e in prop.engines) for t in POLY22_TERMS}
    expected = {
        "qa": sums["p20"] * s * s,
        "qb0": sums["p10"] * s,
        "qb1": sums["p11"] * s,
        "qc0": sums["p00"],
        "qc1": sums["p01"],
        "qc2": sums["p02"],
    }
    got = quadratic_coefficients(prop)
    for key_, value in expected.items():
        assert got[key_] == pytest.approx(value, rel=1e-12, abs=1e-15), key_


def _brute_force_least(a: float, b: float, c: float, grid: np.ndarray) -> float | None:
    f = a * grid * grid + b * grid + c
    hits = np.nonzero(f >= 0.0)[0]
    return float(grid[hits[0]]) if hits.size else None


def test_least_throttle_reaching_against_brute_force() -> None:
    """Random quadratics, all shapes (convex, concave, ~linear, decreasing first)."""
    rng = np.random.default_rng(11)
    grid = np.linspace(0.0, 1.0, 20001)
    step = grid[1] - grid[0]
    a = rng.normal(0.0, 50.0, 400)
    a[::7] = 0.0  # exactly linear
    a[1::7] *= 1e-13  # quadratic term ~0
    b = rng.normal(0.0, 50.0, 400)
    c = rng.normal(-10.0, 15.0, 400)
    x, reached = least_throttle_reaching(a, b, c)
    for i in range(a.size):
        f = lambda t, i=i: a[i] * t * t + b[i] * t + c[i]  # noqa: E731
        expected = _brute_force_least(a[i], b[i], c[i], grid)
        if c[i] >= 0.0:
            assert x[i] == 0.0 and reached[i] == 1.0
        elif expected is None:
            assert reached[i] == 0.0
            # reported throttle gives the most thrust on the grid (within its resolution)
            assert f(x[i]) >= np.max(f(grid)) - 1e-9
        else:
            assert reached[i] == 1.0
            assert abs(f(x[i])) <= 1e-9 * max(1.0, abs(a[i]) + abs(b[i]) + abs(c[i]))
            # least: the first grid point reaching it is at most one step after the root
            assert expected - step - 1e-12 <= x[i] <= expected + 1e-12


def test_non_monotonic_picks_the_first_crossing() -> None:
    # f = -80 x^2 + 100 x - 20: roots ~0.2298 and ~1.0202 (concave, peaks at 0.625)
    x, reached = least_throttle_reaching(-80.0, 100.0, -20.0)
    assert reached == 1.0
    assert float(x) == pytest.approx((100 - np.sqrt(100**2 - 4 * 80 * 20)) / 160, rel=1e-14)
    # f = 40 x^2 - 10 x - 5: dips first, crosses once at ~0.5
    x, reached = least_throttle_reaching(40.0, -10.0, -5.0)
    assert float(x) == pytest.approx((10 + np.sqrt(100 + 800)) / 80, rel=1e-14)
    # demand above the peak: not reached, best throttle is the vertex
    x, reached = least_throttle_reaching(-80.0, 100.0, -40.0)
    assert reached == 0.0 and float(x) == pytest.approx(0.625, rel=1e-14)


@pytest.mark.parametrize("key", ["shipped", "made_up", "dense", "percent"])
def test_inverse_round_trip_numpy_and_casadi(models: dict, key: str) -> None:
    prop = models[key].propulsion
    rng = np.random.default_rng(5)
    n = 3000
    airspeed = rng.uniform(0.0, 50.0, n)
    density = rng.uniform(0.8, 1.35, n)
    idle = total_thrust_n(prop, 0.0, airspeed, density)
    full = total_thrust_n(prop, 1.0, airspeed, density)
    demand = rng.uniform(idle - 5.0, full + 5.0)
    throttle, reached = throttle_for_thrust(prop, demand, airspeed, density)
    got = total_thrust_n(prop, throttle, airspeed, density)
    ok = reached & (idle < demand)
    np.testing.assert_allclose(got[ok], demand[ok], rtol=0, atol=1e-9)
    assert np.all(throttle[idle >= demand] == 0.0)
    # these models are monotonic in throttle on [0, 1]: reachable exactly up to full thrust
    np.testing.assert_array_equal(reached, demand <= full + 1e-9)
    assert np.all(throttle[~reached] == 1.0)
    inverse = inverse_function(prop).map(n)
    c_throttle, c_reached = inverse(demand[None, :], airspeed[None, :], density[None, :])
    np.testing.assert_allclose(np.asarray(c_throttle).ravel(), throttle, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(np.asarray(c_reached).ravel() == 1.0, reached)


def test_a_fitted_voltage_law_is_stated_not_dropped(tmp_path) -> None:
    """The exported functions give thrust at the reference pack voltage; the JSON says so
    and keeps the fitted law (a second hostile audit: it was silently dropped, 25 % too much
    thrust at a sagged 41 V pack)."""
    import json

    from tests.conftest import MADE_UP_PROPULSION, write_case
    from tuflexperf.export import export_model, parse_formats

    plain = write_case(tmp_path / "plain")
    export_model(plain, parse_formats("json"), tmp_path / "plain_out")
    described = json.loads((tmp_path / "plain_out" / "tfp_thrust.json").read_text())
    assert described["pack_voltage"] is None
    with_voltage = {**MADE_UP_PROPULSION, "reference_voltage_v": 47.3, "voltage_exponent": 1.9}
    case = write_case(tmp_path / "volt", propulsion=with_voltage)
    export_model(case, parse_formats("json"), tmp_path / "volt_out")
    described = json.loads((tmp_path / "volt_out" / "tfp_thrust.json").read_text())
    assert described["pack_voltage"]["reference_voltage_v"] == 47.3
    assert described["pack_voltage"]["voltage_exponent"] == 1.9
