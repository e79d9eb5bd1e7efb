"""The exported C's dynamic model (dead time + spool lag), its checked inverses and provenance.

- ``tfp_step`` against an independent discrete-time simulation written here from the propulsion
  file's numbers alone (plain Python loop: a list as the delay line, ``exp(-dt / lag_s)`` as the
  pole), to 1e-12 relative, and against the continuous-time step response sampled at the
  same instants;
- the inverses' edge cases: negative and absurd airspeed, density <= 0, each a distinct return
  code; the extrapolation flag from the same call; the single-engine inverse round trip;
- no absolute local path in the generated files.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.c_model import CThrustModel, compile_shared
from tests.conftest import MADE_UP_PROPULSION, model_from_propulsion_file
from tuflexperf.export.c_code import (
    RETURN_AIRSPEED_BEYOND_MODEL,
    RETURN_BAD_ARGUMENT,
    RETURN_BAD_DENSITY,
    RETURN_NEGATIVE_AIRSPEED,
    RETURN_NOT_REACHABLE,
    header_text,
    source_text,
)
from tuflexperf.export.cbuild import find_compiler
from tuflexperf.models.thrust import max_model_airspeed_m_s

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) installed")

LAG_S = 0.081
DELAY_S = 0.052
DENSITY_REF = 1.19


def _write(folder: Path, **changes: object) -> Path:
    data = copy.deepcopy(MADE_UP_PROPULSION)
    data.update(changes)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "propulsion.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _build(folder: Path, path: Path) -> tuple[dict, CThrustModel]:
    model = model_from_propulsion_file(path)
    (folder / "tfp_thrust.h").write_text(header_text(model))
    (folder / "tfp_thrust.c").write_text(source_text(model))
    library = compile_shared([folder / "tfp_thrust.c"], folder / "libtfp.so")
    return yaml.safe_load(path.read_text()), CThrustModel(library, model.n_engines)


@pytest.fixture(scope="module")
def lagged(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, CThrustModel]:
    folder = tmp_path_factory.mktemp("lagged")
    path = _write(folder, lag_s=LAG_S, delay_s=DELAY_S, reference_density_kg_m3=DENSITY_REF)
    return _build(folder, path)


def _static(engine: dict, x: float, v: float, rho: float) -> float:
    """poly22 typed from SPEC 4, scaled by rho / rho_ref: independent of tuflexperf.models."""
    c = engine["coefficients"]
    poly = (
        c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x**2 + c["p11"] * x * v
        + c["p02"] * v**2
    )
    return rho / DENSITY_REF * poly


def _independent(
    data: dict, dt: float, commands: np.ndarray, v: float, rho: float, initial: list[float]
) -> np.ndarray:
    """Dead time of round(d / dt) samples, then y_k = a y_(k-1) + (1 - a) u_k per engine."""
    steps = int(math.floor(data["delay_s"] / dt + 0.5))
    a = math.exp(-dt / data["lag_s"]) if data.get("lag_s", 0) > 0 else 0.0
    out = np.empty_like(commands)
    for j, engine in enumerate(data["engines"]):
        line = [initial[j]] * steps  # commands waiting in the dead time
        y = _static(engine, initial[j], v, rho)
        for k, command in enumerate(commands[:, j]):
            line.append(float(command))
            u = line.pop(0)
            y = a * y + (1.0 - a) * _static(engine, u, v, rho)
            out[k, j] = y
    return out


@pytest.mark.parametrize("dt", [0.001, 0.0025, 0.01])
def test_c_step_equals_independent_simulation(lagged: tuple, dt: float) -> None:
    data, c = lagged
    rng = np.random.default_rng(7)
    n = int(round(1.5 / dt))
    # held random commands (a throttle trace as a flight controller gives it) plus noise
    commands = np.repeat(rng.uniform(0, 1, (n // 20 + 1, 2)), 20, axis=0)[:n]
    commands = np.clip(commands + rng.normal(0, 0.02, commands.shape), 0, 1)
    v, rho, initial = 17.0, 1.1, [0.3, 0.6]
    code, got = c.simulate(dt, commands.tolist(), v, rho, initial)
    assert code == 0
    expected = _independent(data, dt, commands, v, rho, initial)
    np.testing.assert_allclose(np.array(got), expected, rtol=1e-12, atol=1e-12)


def test_c_step_response_is_dead_time_then_exponential(lagged: tuple) -> None:
    """A throttle step at t = 0: flat for the dead time, then T1 + (T0 - T1) exp(-t'/lag)."""
    data, c = lagged
    dt, v, rho = 0.001, 10.0, DENSITY_REF
    n = 600
    commands = [[0.8, 0.8]] * n
    code, got = c.simulate(dt, commands, v, rho, [0.2, 0.2])
    assert code == 0
    steps = round(DELAY_S / dt)
    for j, engine in enumerate(data["engines"]):
        t0, t1 = _static(engine, 0.2, v, rho), _static(engine, 0.8, v, rho)
        trace = np.array(got)[:, j]
        np.testing.assert_allclose(trace[:steps], t0, rtol=1e-13)
        # sample k >= steps has seen (k - steps + 1) samples of the new input
        k = np.arange(steps, n)
        analytic = t1 + (t0 - t1) * np.exp(-(k - steps + 1) * dt / LAG_S)
        np.testing.assert_allclose(trace[steps:], analytic, rtol=1e-12)
        # 63 % of the step one time constant after the dead time (the lag's definition)
        at = steps - 1 + round(LAG_S / dt)
        assert (trace[at] - t0) / (t1 - t0) == pytest.approx(1 - math.exp(-1), abs=2e-3)


def test_step_refuses_a_nan_command_and_bad_initial_conditions(lagged: tuple) -> None:
    _, c = lagged
    code, _ = c.simulate(0.01, [[0.5, 0.5], [math.nan, 0.5]], 10.0, 1.2)
    assert code == RETURN_BAD_ARGUMENT
    code, _ = c.simulate(0.01, [[0.5, 0.5]], -1.0, 1.2, [0.5, 0.5])
    assert code == RETURN_NEGATIVE_AIRSPEED  # tfp_state_init refuses it already


def test_zero_lag_is_the_papers_pure_delay(tmp_path: Path) -> None:
    data, c = _build(tmp_path, _write(tmp_path, lag_s=0.0, delay_s=0.03))
    dt = 0.01
    commands = np.random.default_rng(3).uniform(0, 1, (40, 2))
    code, got = c.simulate(dt, commands.tolist(), 5.0, 1.0, [0.0, 0.0])
    assert code == 0
    for k in range(40):
        delayed = commands[k - 3] if k >= 3 else np.zeros(2)
        assert got[k] == list(c.thrust(delayed, 5.0, 1.0)[1])


def test_inverse_rejects_meaningless_input_with_distinct_codes(lagged: tuple) -> None:
    _, c = lagged
    codes = {
        "negative airspeed": c.throttle_for_thrust_flagged(10.0, -1.0, 1.2)[0],
        "absurd airspeed": c.throttle_for_thrust_flagged(10.0, 300.0, 1.2)[0],
        "zero density": c.throttle_for_thrust_flagged(10.0, 10.0, 0.0)[0],
        "negative density": c.throttle_for_thrust_flagged(10.0, 10.0, -1.2)[0],
        "nan demand": c.throttle_for_thrust_flagged(math.nan, 10.0, 1.2)[0],
    }
    assert codes == {
        "negative airspeed": RETURN_NEGATIVE_AIRSPEED,
        "absurd airspeed": RETURN_AIRSPEED_BEYOND_MODEL,
        "zero density": RETURN_BAD_DENSITY,
        "negative density": RETURN_BAD_DENSITY,
        "nan demand": RETURN_BAD_ARGUMENT,
    }
    assert len({RETURN_NEGATIVE_AIRSPEED, RETURN_AIRSPEED_BEYOND_MODEL, RETURN_BAD_DENSITY,
                RETURN_BAD_ARGUMENT, RETURN_NOT_REACHABLE, 0}) == 6
    # a rejected call never hands back a usable throttle
    assert math.isnan(c.throttle_for_thrust_flagged(10.0, -1.0, 1.2)[1])
    # the static thrust refuses the same points
    assert c.thrust([0.0, 0.0], 300.0, 1.2)[0] == RETURN_AIRSPEED_BEYOND_MODEL
    assert all(math.isnan(t) for t in c.thrust([0.0, 0.0], 300.0, 1.2)[1])
    assert c.thrust([0.5, 0.5], -3.0, 1.2)[0] == RETURN_NEGATIVE_AIRSPEED
    assert c.thrust([0.5, 0.5], 10.0, 0.0)[0] == RETURN_BAD_DENSITY


def test_max_model_airspeed_is_where_idle_thrust_turns_up(lagged: tuple) -> None:
    """Made-up fans: dT/dV = p01 + p11 x + 2 p02 V; at idle the 'right' fan turns at 90 m/s,
    the 'left' at 75 m/s; 4 x the top tested 25 m/s = 100 m/s caps it."""
    data, c = lagged
    limit = max_model_airspeed_m_s(model_from_propulsion_file(_write_tmp(data)).propulsion)
    left = 0.12 / (2 * 0.0008)
    right = 0.09 / (2 * 0.0005)
    assert limit == pytest.approx(min(left, right, 100.0)) == pytest.approx(75.0)
    assert c.throttle_for_thrust_flagged(1.0, limit - 1e-6, 1.2)[0] in (0, RETURN_NOT_REACHABLE)
    assert c.throttle_for_thrust_flagged(1.0, limit + 1e-6, 1.2)[0] == RETURN_AIRSPEED_BEYOND_MODEL


def _write_tmp(data: dict) -> Path:
    import tempfile

    folder = Path(tempfile.mkdtemp())
    path = folder / "p.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_extrapolation_flag_comes_from_the_same_call(lagged: tuple) -> None:
    _, c = lagged
    code, x, flag = c.throttle_for_thrust_flagged(10.0, 20.0, 1.2)
    assert code == 0 and 0 < x < 1 and flag is False
    code, x, flag = c.throttle_for_thrust_flagged(10.0, 30.0, 1.2)  # tested up to 25 m/s
    assert code == 0 and 0 < x < 1 and flag is True
    code, _, flag = c.throttle_for_thrust_flagged(10.0, 25.0, 1.2)
    assert code == 0 and flag is False


def test_single_engine_inverse_round_trip(lagged: tuple) -> None:
    data, c = lagged
    rng = np.random.default_rng(11)
    for _ in range(300):
        j = int(rng.integers(0, 2))
        v, rho, x = rng.uniform(0, 40), rng.uniform(0.9, 1.3), rng.uniform(0.05, 1.0)
        demand = _static(data["engines"][j], x, v, rho)
        code, got, flag = c.engine_throttle_for_thrust(j, demand, v, rho)
        assert code == 0 and flag == (v > 25.0)
        if _static(data["engines"][j], 0.0, v, rho) >= demand:
            assert got == 0.0  # idle already makes it (thrust dips first at high airspeed)
        else:  # convex in throttle with f(0) < demand: x is the only crossing in (0, 1]
            assert got == pytest.approx(x, abs=1e-9)
    assert c.engine_throttle_for_thrust(2, 5.0, 10.0, 1.2)[0] == RETURN_BAD_ARGUMENT
    assert c.engine_throttle_for_thrust(-1, 5.0, 10.0, 1.2)[0] == RETURN_BAD_ARGUMENT
    assert c.engine_throttle_for_thrust(0, 5.0, -1.0, 1.2)[0] == RETURN_NEGATIVE_AIRSPEED


def test_generated_files_carry_no_absolute_path(tmp_path: Path) -> None:
    from tuflexperf.export import export_model

    out = tmp_path / "export"
    export_model(None, ("c", "json"), out)
    for name in ("tfp_thrust.c", "tfp_thrust.h", "tfp_thrust.json"):
        text = (out / name).read_text()
        assert str(Path(__file__).resolve().parents[2]) not in text
        assert "sha256" in text
    assert "../data/tuflex/propulsion.yaml" in (out / "tfp_thrust.h").read_text()
