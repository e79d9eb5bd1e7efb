"""Models against closed forms and standard tables; numpy and CasADi evaluate alike."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from tuflexperf.models.aircraft import (
    Aircraft,
    TakeoffConfig,
    level_flight_drag_n,
    minimum_drag_n,
    minimum_drag_speed_m_s,
    stall_speed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3, isa_pressure_pa, isa_temperature_k
from tuflexperf.models.thrust import Engine, Propulsion, total_thrust_n, windmilling_thrust_n

AIRCRAFT = Aircraft("test", 20.0, 1.2, 0.025, 0.03, 1.4, TakeoffConfig(cl_ground=0.5))
COEFFS = {"p00": 0.3, "p10": 5.0, "p01": -0.1, "p20": 40.0, "p11": -0.4, "p02": 0.001}
PROPULSION = Propulsion(
    "p",
    (Engine("a", COEFFS), Engine("b", {**COEFFS, "p10": 7.0})),
    (0.0, 30.0),
    0.05,
    reference_density_kg_m3=1.2,
)


@pytest.mark.parametrize(
    ("altitude_m", "temperature_k", "pressure_pa", "density_kg_m3"),
    [  # ICAO standard atmosphere table values
        (0.0, 288.15, 101325.0, 1.2250),
        (1000.0, 281.65, 89874.6, 1.1116),
        (5000.0, 255.65, 54019.9, 0.73612),
        (11000.0, 216.65, 22632.1, 0.36392),
        (15000.0, 216.65, 12044.6, 0.19367),
    ],
)
def test_isa_matches_standard_table(altitude_m, temperature_k, pressure_pa, density_kg_m3):
    assert float(isa_temperature_k(altitude_m)) == pytest.approx(temperature_k, abs=1e-9)
    assert float(isa_pressure_pa(altitude_m)) == pytest.approx(pressure_pa, rel=2e-5)
    assert float(isa_density_kg_m3(altitude_m)) == pytest.approx(density_kg_m3, rel=2e-4)


def test_isa_temperature_offset_lowers_density_at_same_pressure():
    hot = float(isa_density_kg_m3(2000.0, 20.0))
    expected = float(isa_pressure_pa(2000.0)) / (287.05287 * (288.15 - 13.0 + 20.0))
    assert hot == pytest.approx(expected, rel=1e-12)
    assert hot < float(isa_density_kg_m3(2000.0))


def test_minimum_drag_closed_form():
    rho = 1.1
    v = np.linspace(5.0, 60.0, 200001)
    drag = level_flight_drag_n(AIRCRAFT, v, rho)
    assert float(drag.min()) == pytest.approx(minimum_drag_n(AIRCRAFT), rel=1e-9)
    assert v[np.argmin(drag)] == pytest.approx(
        float(minimum_drag_speed_m_s(AIRCRAFT, rho)), abs=1e-3
    )
    # at V_md induced drag equals parasite drag (Anderson section 5.4)
    v_md = float(minimum_drag_speed_m_s(AIRCRAFT, rho))
    q_s = 0.5 * rho * v_md**2 * AIRCRAFT.wing_area_m2
    assert q_s * AIRCRAFT.cd0 == pytest.approx(AIRCRAFT.k * AIRCRAFT.weight_n**2 / q_s, rel=1e-12)


def test_stall_speed_gives_cl_max():
    rho = 1.0
    v_s = float(stall_speed_m_s(AIRCRAFT, rho))
    lift = 0.5 * rho * v_s**2 * AIRCRAFT.wing_area_m2 * AIRCRAFT.cl_max
    assert lift == pytest.approx(AIRCRAFT.weight_n, rel=1e-12)


def _casadi_eval(fn, *values):
    symbols = [ca.MX.sym(f"s{i}") for i in range(len(values))]
    f = ca.Function("f", symbols, [fn(*symbols)])
    return float(f(*values))


@pytest.mark.parametrize("throttle", [0.0, 0.37, 1.0])
@pytest.mark.parametrize("airspeed", [0.0, 12.5, 44.0])
@pytest.mark.parametrize("dead", [None, 0, 1])
def test_thrust_numpy_and_casadi_agree(throttle, airspeed, dead):
    def thrust(x, v, rho):
        return total_thrust_n(PROPULSION, x, v, rho, dead_engine=dead)

    numeric = float(thrust(throttle, airspeed, 1.05))
    symbolic = _casadi_eval(thrust, throttle, airspeed, 1.05)
    assert symbolic == pytest.approx(numeric, rel=1e-14, abs=1e-12)


def test_density_scaling_and_windmilling():
    rho = 0.9
    e = PROPULSION.engines[0]
    t0 = COEFFS["p00"] + COEFFS["p01"] * 30.0 + COEFFS["p02"] * 900.0  # T(0, 30) < 0
    assert t0 < 0
    assert float(windmilling_thrust_n(e, 30.0, rho / 1.2)) == pytest.approx(t0 * rho / 1.2)
    assert float(windmilling_thrust_n(e, 0.0)) == 0.0  # p00 > 0: never thrust
    one = float(
        total_thrust_n(PROPULSION, [1.0, 0.0], 30.0, rho, dead_engine=1, dead_engine_mode="zero")
    )
    full = 0.3 + 5.0 - 3.0 + 40.0 - 12.0 + 0.9
    assert one == pytest.approx(full * rho / 1.2, rel=1e-14)


def test_drag_numpy_and_casadi_agree():
    for v in (10.0, 25.0, 45.0):
        numeric = float(level_flight_drag_n(AIRCRAFT, v, 1.1))
        assert _casadi_eval(lambda s: level_flight_drag_n(AIRCRAFT, s, 1.1), v) == pytest.approx(
            numeric, rel=1e-14
        )
    vec = np.array([10.0, 20.0])
    assert np.allclose(
        level_flight_drag_n(AIRCRAFT, vec, 1.1),
        [level_flight_drag_n(AIRCRAFT, x, 1.1) for x in vec],
    )
