"""The exported C, compiled with gcc and loaded with ctypes, against the Python model.

Thousands of random points per model, to 1e-9 N; the inverse round trip; the delay buffer.
Skipped only when no C compiler exists.
"""

from __future__ import annotations

import copy
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.c_model import CThrustModel, compile_shared, throttle_for_thrust
from tests.conftest import MADE_UP_PROPULSION, model_from_propulsion_file
from tuflexperf.export.c_code import (
    DELAY_CAPACITY,
    RETURN_BAD_ARGUMENT,
    RETURN_CAPACITY,
    RETURN_NOT_REACHABLE,
    header_text,
    source_text,
)
from tuflexperf.export.cbuild import find_compiler
from tuflexperf.export.model import ExportModel
from tuflexperf.models.thrust import (
    density_ratio,
    engine_thrust_n,
    max_model_airspeed_m_s,
    total_thrust_n,
)

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_PROPULSION = ROOT / "data" / "tuflex" / "propulsion.yaml"

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) installed")


def _engine(name: str, **coefficients: float) -> dict:
    base = {"p00": 0.0, "p10": 0.0, "p01": 0.0, "p20": 0.0, "p11": 0.0, "p02": 0.0}
    return {"name": name, "coefficients": {**base, **coefficients}}


def _percent_engines() -> list[dict]:
    engines = copy.deepcopy(MADE_UP_PROPULSION["engines"])
    for engine in engines:
        c = engine["coefficients"]
        c["p10"] /= 100.0
        c["p20"] /= 1e4
        c["p11"] /= 100.0
    return engines


VARIANTS: dict[str, dict] = {
    "made_up": {},
    "dense": {"reference_density_kg_m3": 1.15},
    "percent": {"throttle_unit": "percent", "engines": _percent_engines()},
    # thrust peaks inside [0, 1] (concave): the least root is the first crossing
    "concave": {
        "engines": [
            _engine("a", p10=100.0, p20=-80.0, p01=-0.1, p11=-0.5),
            _engine("b", p10=90.0, p20=-70.0, p01=-0.1, p11=-0.4),
        ],
        "delay_s": 0.0,
    },
    "one_engine": {"engines": [_engine("solo", p10=20.0, p20=30.0, p01=-0.2, p11=-0.6)]},
    "three_engines": {
        "engines": [
            _engine("l", p10=10.0, p20=30.0, p01=-0.1, p11=-0.3, p02=0.001),
            _engine("c", p00=0.5, p10=-5.0, p20=40.0, p01=-0.1, p11=-0.2),  # dips first
            _engine("r", p10=12.0, p20=25.0, p01=-0.12, p11=-0.35, p02=0.0005),
        ],
        "reference_density_kg_m3": 1.2,
    },
}


def _build(folder: Path, model: ExportModel) -> CThrustModel:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tfp_thrust.h").write_text(header_text(model))
    (folder / "tfp_thrust.c").write_text(source_text(model))
    library = compile_shared([folder / "tfp_thrust.c"], folder / "libtfp.so")
    return CThrustModel(library, model.n_engines)


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[ExportModel, CThrustModel]]:
    root = tmp_path_factory.mktemp("c_models")
    out: dict[str, tuple[ExportModel, CThrustModel]] = {}
    shipped = model_from_propulsion_file(SHIPPED_PROPULSION)
    out["shipped"] = (shipped, _build(root / "shipped", shipped))
    for key, changes in VARIANTS.items():
        data = copy.deepcopy(MADE_UP_PROPULSION)
        data.update(copy.deepcopy(changes))
        path = root / f"{key}.yaml"
        path.write_text(yaml.safe_dump(data))
        model = model_from_propulsion_file(path)
        out[key] = (model, _build(root / key, model))
    return out


ALL = ["shipped", *VARIANTS]


@pytest.mark.parametrize("key", ALL)
def test_c_thrust_equals_python_model(built: dict, key: str) -> None:
    model, c = built[key]
    prop = model.propulsion
    rng = np.random.default_rng(42)
    n = 3000
    throttle = rng.uniform(0.0, 1.0, (n, model.n_engines))
    airspeed = rng.uniform(0.0, min(50.0, max_model_airspeed_m_s(prop)), n)
    density = rng.uniform(0.8, 1.35, n)
    scale = density_ratio(prop, density)
    expected = np.column_stack(
        [engine_thrust_n(e, throttle[:, i], airspeed, scale) for i, e in enumerate(prop.engines)]
    )
    got = np.empty_like(expected)
    got_v = np.empty_like(expected)
    total = np.empty(n)
    for k in range(n):
        code, got[k] = c.thrust(throttle[k], airspeed[k], density[k])
        assert code == 0
        code, got_v[k] = c.thrust_v(throttle[k], airspeed[k], density[k])
        assert code == 0
        total[k] = c.total_thrust(throttle[k, 0], airspeed[k], density[k])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got_v, expected, rtol=0, atol=1e-9)
    common = total_thrust_n(prop, throttle[:, 0], airspeed, density)
    np.testing.assert_allclose(total, common, rtol=0, atol=1e-9)


def test_density_is_ignored_without_reference_and_scales_with_one(built: dict) -> None:
    _, plain = built["made_up"]
    model, dense = built["dense"]
    _, at_1 = plain.thrust([0.7, 0.4], 20.0, 1.0)
    assert plain.thrust([0.7, 0.4], 20.0, 0.5)[1] == at_1
    ref = model.propulsion.reference_density_kg_m3
    half = dense.thrust([0.7, 0.4], 20.0, 0.5 * ref)[1]
    assert half == pytest.approx([0.5 * t for t in at_1], rel=1e-14)


@pytest.mark.parametrize("key", ALL)
def test_c_inverse_round_trip(built: dict, key: str) -> None:
    model, c = built[key]
    prop = model.propulsion
    rng = np.random.default_rng(9)
    n = 2000
    airspeed = rng.uniform(0.0, min(50.0, max_model_airspeed_m_s(prop)), n)
    density = rng.uniform(0.8, 1.35, n)
    idle = total_thrust_n(prop, 0.0, airspeed, density)
    full = total_thrust_n(prop, 1.0, airspeed, density)
    demand = rng.uniform(np.minimum(idle, full) - 5.0, np.maximum(idle, full) + 10.0)
    ref_throttle, ref_reached = throttle_for_thrust(prop, demand, airspeed, density)
    grid = np.linspace(0.0, 1.0, 2001)
    for k in range(n):
        code, x = c.throttle_for_thrust(demand[k], airspeed[k], density[k])
        assert code in (0, RETURN_NOT_REACHABLE)
        assert (code == 0) == bool(ref_reached[k])
        assert x == pytest.approx(float(ref_throttle[k]), abs=1e-12)
        curve = total_thrust_n(prop, grid, airspeed[k], density[k])
        if code == 0 and idle[k] >= demand[k]:
            assert x == 0.0  # idle suffices
        elif code == 0:
            assert c.total_thrust(x, airspeed[k], density[k]) == pytest.approx(demand[k], abs=1e-9)
            # least: no grid throttle clearly below x reaches the demand
            assert np.all(curve[grid < x - 1e-6] < demand[k])
        else:
            assert np.all(curve < demand[k])  # nothing in [0, 1] reaches it
            assert c.total_thrust(x, airspeed[k], density[k]) >= curve.max() - 1e-9


def test_c_inverse_edges(built: dict) -> None:
    model, c = built["shipped"]
    prop = model.propulsion
    full = float(total_thrust_n(prop, 1.0, 25.0, 1.225))
    assert c.throttle_for_thrust(full, 25.0, 1.225) == (0, pytest.approx(1.0, abs=1e-12))
    code, x = c.throttle_for_thrust(full + 1e-6, 25.0, 1.225)
    assert code == RETURN_NOT_REACHABLE and x == 1.0
    assert c.throttle_for_thrust(-1e3, 25.0, 1.225) == (0, 0.0)
    assert c.throttle_for_thrust(math.nan, 25.0, 1.225)[0] == RETURN_BAD_ARGUMENT
    assert c.throttle_for_thrust(10.0, math.inf, 1.225)[0] == RETURN_BAD_ARGUMENT


def test_c_thrust_refuses_what_the_model_does_not_have(built: dict) -> None:
    """Throttle 1.5 gave 60 % more than full throttle with TFP_OK, and tfp_total_thrust
    answered anything (-10 m/s, a negative density, 60 m/s past the model's limit) (outside
    audit): now TFP_BAD_THROTTLE / the point's code, and NaN from the total."""
    from tuflexperf.export.c_code import RETURN_BAD_THROTTLE

    model, c = built["shipped"]
    for throttle in ((1.5, 0.5), (0.5, -0.2)):
        code, thrust = c.thrust(throttle, 20.0, 1.225)
        assert code == RETURN_BAD_THROTTLE and all(math.isnan(t) for t in thrust)
        code, thrust = c.thrust_v(throttle, 20.0, 1.225)
        assert code == RETURN_BAD_THROTTLE and all(math.isnan(t) for t in thrust)
    for args in ((1.5, 20.0, 1.225), (1.0, -10.0, 1.225), (1.0, 20.0, -1.225),
                 (1.0, 60.0, 1.225), (math.nan, 20.0, 1.225)):
        assert math.isnan(c.total_thrust(*args)), args
    assert c.thrust((1.0, 0.0), 20.0, 1.225)[0] == 0 and math.isfinite(c.total_thrust(1.0, 20.0,
                                                                                      1.225))
    # one rounding step above full throttle (0.1 * 3 / 0.3) is still full throttle
    assert c.thrust((0.1 * 3 / 0.3, 0.0), 20.0, 1.225)[0] == 0
    assert c.thrust((1.0001, 0.0), 20.0, 1.225)[0] == RETURN_BAD_THROTTLE


def test_extrapolation_flag(built: dict) -> None:
    model, c = built["shipped"]
    low, high = model.propulsion.tested_airspeed_m_s
    assert not c.is_extrapolated(low) and not c.is_extrapolated(high)
    assert not c.is_extrapolated(0.5 * (low + high))
    assert c.is_extrapolated(high + 0.1) and c.is_extrapolated(low - 0.1)


@pytest.mark.parametrize("sample_time_s", [0.001, 0.0037, 0.01, 0.013, 0.02, 0.05, 0.07, 1.0])
def test_delay_buffer_delays_by_rounded_samples(built: dict, sample_time_s: float) -> None:
    model, c = built["made_up"]
    delay_s = model.propulsion.delay_s
    expected_n = math.floor(delay_s / sample_time_s + 0.5)
    code, buffer = c.new_delay(sample_time_s, 0.25)
    assert code == 0
    assert c.lib.tfp_delay_samples(buffer) == expected_n
    commands = np.random.default_rng(1).uniform(0.0, 1.0, 3 * expected_n + 20)
    outputs = [c.lib.tfp_delay_step(buffer, u) for u in commands]
    for k, out in enumerate(outputs):
        assert out == (commands[k - expected_n] if k >= expected_n else 0.25)


def test_delay_zero_passes_through_and_limits(built: dict) -> None:
    model, c = built["concave"]  # delay_s: 0
    assert model.propulsion.delay_s == 0.0
    code, buffer = c.new_delay(0.01)
    assert code == 0 and c.lib.tfp_delay_samples(buffer) == 0
    assert c.lib.tfp_delay_step(buffer, 0.6) == 0.6
    model, c = built["made_up"]
    tiny = model.propulsion.delay_s / (DELAY_CAPACITY + 5)
    assert c.new_delay(tiny)[0] == RETURN_CAPACITY
    assert c.new_delay(0.0)[0] == RETURN_BAD_ARGUMENT
    assert c.new_delay(-0.01)[0] == RETURN_BAD_ARGUMENT
    assert c.new_delay(math.nan)[0] == RETURN_BAD_ARGUMENT


def test_header_serves_a_plain_c99_program(built: dict, tmp_path: Path) -> None:
    """A flight-software-like caller: header + source + main, strict flags, run it."""
    model, _ = built["shipped"]
    (tmp_path / "tfp_thrust.h").write_text(header_text(model))
    (tmp_path / "tfp_thrust.c").write_text(source_text(model))
    (tmp_path / "main.c").write_text(
        '#include <stdio.h>\n#include "tfp_thrust.h"\n'
        "int main(void) {\n"
        "    double t1, t2, x; tfp_delay_t d; int i;\n"
        "    if (tfp_thrust(1.0, 1.0, 0.0, 1.225, &t1, &t2) != TFP_OK) return 1;\n"
        "    if (tfp_throttle_for_thrust(t1 + t2, 0.0, 1.225, &x, NULL) != TFP_OK) return 2;\n"
        "    if (tfp_delay_init(&d, 0.01, 0.0) != TFP_OK) return 3;\n"
        "    for (i = 0; i < 10; ++i) x = tfp_delay_step(&d, 1.0);\n"
        '    printf("%.17g %.17g %.17g %d %s\\n", t1, t2, x, TFP_N_ENGINES, TFP_MODEL_NAME);\n'
        "    return 0;\n}\n"
    )
    exe = tmp_path / "demo"
    cmd = [find_compiler(), "-std=c99", "-Wall", "-Werror", "-O2", "-o", str(exe),
           str(tmp_path / "main.c"), str(tmp_path / "tfp_thrust.c"), "-lm"]
    subprocess.run(cmd, check=True, capture_output=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split()
    prop = model.propulsion
    for i, engine in enumerate(prop.engines):
        scale = density_ratio(prop, 1.225)  # the call's density over the model's reference
        assert float(out[i]) == pytest.approx(engine_thrust_n(engine, 1.0, 0.0, scale), abs=1e-9)
    assert float(out[2]) == 1.0  # 10 samples of 0.01 s, delay 5 samples: the command is through
    assert int(out[3]) == len(prop.engines)
