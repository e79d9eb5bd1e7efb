"""Momentum theory, the thrust/power agreement warnings, windmilling drag and the electrical fits.

Closed forms (Leishman, *Principles of Helicopter Aerodynamics*, 2.2-2.8): static thrust
``T = rho A v_e^2`` so ``v_e = sqrt(T / (rho A))`` and ``P_i = T v_e / 2``; in axial flight
``T = rho A v_e (v_e - V)``. Fits are checked on points made from a known law.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from tuflexperf.models.agreement import agreement_at, power_agreement
from tuflexperf.models.powertrain import (
    engine_power_w,
    exit_velocity_m_s,
    figure_of_merit,
    ideal_power_w,
    overall_efficiency,
    windmilling_drag_n,
)
from tuflexperf.models.thrust import Engine, Propulsion, poly22, total_thrust_n
from tuflexperf.reduction.power import fit_power_surface, fit_voltage_exponent, fit_windmilling

RHO = 1.225
AREA = 0.0050
THRUST = {"p00": 0.0, "p10": 0.45, "p01": -0.13, "p20": 54.7, "p11": -0.39, "p02": 0.0007}


def test_static_ideal_power_closed_form() -> None:
    t = 55.0
    v_e = math.sqrt(t / (RHO * AREA))
    assert float(exit_velocity_m_s(t, 0.0, RHO, AREA)) == pytest.approx(v_e, rel=1e-12)
    assert float(ideal_power_w(t, 0.0, RHO, AREA)) == pytest.approx(t * v_e / 2, rel=1e-12)


@pytest.mark.parametrize("airspeed", [5.0, 20.0, 45.0])
def test_exit_velocity_satisfies_momentum_balance(airspeed: float) -> None:
    t = 12.0
    v_e = float(exit_velocity_m_s(t, airspeed, RHO, AREA))
    assert RHO * AREA * v_e * (v_e - airspeed) == pytest.approx(t, rel=1e-12)
    assert float(ideal_power_w(t, airspeed, RHO, AREA)) == pytest.approx(
        t * (airspeed + v_e) / 2, rel=1e-12
    )


def test_drag_has_no_ideal_power_and_casadi_matches_numpy() -> None:
    assert float(ideal_power_w(-3.0, 30.0, RHO, AREA)) == 0.0
    t, v, p = ca.SX.sym("t"), ca.SX.sym("v"), ca.SX.sym("p")
    f = ca.Function("f", [t, v, p], [figure_of_merit(t, v, RHO, AREA, p),
                                     overall_efficiency(t, v, p)])
    merit, eff = f(20.0, 25.0, 900.0)
    assert float(merit) == pytest.approx(float(figure_of_merit(20.0, 25.0, RHO, AREA, 900.0)))
    assert float(eff) == pytest.approx(20.0 * 25.0 / 900.0)


def test_published_fan_figures_are_seventy_percent_of_momentum_theory() -> None:
    # Table 1: 41-59 N static, 82-98 m/s exit, 2.4-4.1 kW, 70-71 %: T v_e / 2 / P = 0.70
    for thrust, v_e, power in ((41.0, 82.0, 2400.0), (59.0, 98.0, 4100.0)):
        area = thrust / (RHO * v_e**2)
        merit = float(figure_of_merit(thrust, 0.0, RHO, area, power))
        assert merit == pytest.approx(0.70, abs=0.01)


def test_consistent_point_no_warning_inconsistent_point_warns() -> None:
    # 10 N at 25 m/s on a fan of 0.005 m^2: ideal 399 W, so 600 W is a real fan's 66 %
    good = power_agreement("cruise", "EDF1", 0.5, 25.0, 10.0, 600.0, RHO, AREA)
    assert good.warnings == ()
    assert 0.2 < good.overall_efficiency < 1.0 and good.figure_of_merit < 1.0
    # same thrust on 1.5 kW: efficiency 0.17 -> warning naming the point
    low = power_agreement("cruise", "EDF1", 0.5, 25.0, 10.0, 1500.0, RHO, AREA)
    assert len(low.warnings) == 1 and "overall efficiency" in low.warnings[0]
    assert "EDF1" in low.warnings[0] and "25.0 m/s" in low.warnings[0]
    # thrust the power cannot make: 50 N static on 500 W
    high = power_agreement("static", "EDF1", 1.0, 0.0, 50.0, 500.0, RHO, AREA)
    assert high.figure_of_merit > 1 and "figure of merit" in high.warnings[0]
    assert high.overall_efficiency is None  # static: no overall efficiency


def test_agreement_uses_each_engines_power_surface() -> None:
    power = {"p00": 10.0, "p10": 0.0, "p01": 0.0, "p20": 3600.0, "p11": 0.0, "p02": 0.0}
    engine = Engine("EDF1", THRUST, power_coefficients=power)
    propulsion = Propulsion("p", (engine,), (0.0, 30.0), fan_area_m2=AREA)
    (point,) = agreement_at("x", propulsion, 0.5, 25.0, RHO)
    assert point.electrical_power_w == pytest.approx(910.0)
    assert float(engine_power_w(engine, 0.5, 25.0)) == pytest.approx(910.0)
    assert point.thrust_n == pytest.approx(poly22(0.5, 25.0, THRUST))


def test_windmilling_law_with_coefficient_and_fallback() -> None:
    wm = Engine("b", THRUST, windmilling_drag_coefficient=0.4)
    live = Engine("a", THRUST)
    with_cd = Propulsion("p", (live, wm), (0.0, 30.0), fan_area_m2=0.006793)
    v = np.array([15.0, 30.0, 45.0])
    total = total_thrust_n(with_cd, 0.6, v, RHO, dead_engine=1)
    expected = poly22(0.6, v, THRUST) - 0.4 * 0.5 * RHO * v**2 * 0.006793
    np.testing.assert_allclose(total, expected, rtol=1e-12)
    assert np.all(np.asarray(windmilling_drag_n(0.4, v, RHO, 0.006793)) < 0)
    # no fan area: the old min(T(0, V), 0) of its own model
    without = Propulsion("p", (live, wm), (0.0, 30.0))
    fallback = total_thrust_n(without, 0.6, v, RHO, dead_engine=1)
    np.testing.assert_allclose(
        fallback, poly22(0.6, v, THRUST) + np.minimum(poly22(0.0, v, THRUST), 0.0), rtol=1e-12
    )


def _grid() -> tuple[np.ndarray, np.ndarray]:
    x, v = np.meshgrid(np.linspace(0.1, 1.0, 10), [0.0, 15.0, 20.0, 25.0, 30.0])
    return x.ravel(), v.ravel()


def test_voltage_exponent_recovered_when_voltage_varies_independently() -> None:
    x, v = _grid()
    rng = np.random.default_rng(3)
    volts = 47.0 + rng.uniform(-1.5, 1.5, x.size)  # pack state of charge varies by run
    thrust = poly22(x, v, THRUST) * (volts / 47.0) ** 2 + rng.normal(0.0, 0.02, x.size)
    fit = fit_voltage_exponent(x, v, thrust, volts, 47.0)
    assert fit.identified and fit.exponent == pytest.approx(2.0, abs=3 * fit.standard_error)
    assert fit.standard_error < 0.05


def test_voltage_exponent_not_claimed_when_voltage_is_constant() -> None:
    x, v = _grid()
    fit = fit_voltage_exponent(x, v, poly22(x, v, THRUST), np.full(x.size, 47.0), 47.0)
    assert not fit.identified and "varies by only" in fit.reason


def test_power_surface_and_windmilling_coefficient_recovered() -> None:
    x, v = _grid()
    power = {"p00": 12.0, "p10": -300.0, "p01": 2.0, "p20": 3900.0, "p11": -20.0, "p02": 0.05}
    fit = fit_power_surface(x, v, poly22(x, v, power))
    for term, value in power.items():
        assert fit.coefficients[term] == pytest.approx(value, abs=1e-6)
    speeds = np.array([15.0, 20.0, 25.0, 30.0, 0.0])
    drag = -0.6 * 0.5 * RHO * speeds**2 * 0.006793
    wm = fit_windmilling(np.zeros(5), speeds, drag, RHO, 0.006793)
    assert wm is not None and wm.n_points == 4  # the static point carries no drag
    assert wm.drag_coefficient == pytest.approx(0.6, rel=1e-12) and wm.rms_n < 1e-12
    assert fit_windmilling(np.ones(5), speeds, drag, RHO, 0.006793) is None


def _shipped_with_power(tmp_path, factor: float):
    """The shipped case with every engine's power surface scaled by ``factor``."""
    import yaml

    from tuflexperf.io.case import load_case, shipped_case_path

    shipped = shipped_case_path()
    case = yaml.safe_load(shipped.read_text())
    for key in ("aircraft", "battery"):
        case[key] = str((shipped.parent / case[key]).resolve())
    propulsion = yaml.safe_load((shipped.parent / case["propulsion"]).read_text())
    for engine in propulsion["engines"]:
        engine["power"]["coefficients"] = {
            t: factor * c for t, c in engine["power"]["coefficients"].items()
        }
    (tmp_path / "propulsion.yaml").write_text(yaml.safe_dump(propulsion))
    case["propulsion"] = str(tmp_path / "propulsion.yaml")
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(case))
    return load_case(tmp_path / "case.yaml")


@pytest.mark.parametrize("factor, warns", [(1.0, False), (2.5, True)])
def test_endurance_warns_on_power_that_the_thrust_does_not_need(tmp_path, factor, warns):
    from tuflexperf.analysis.endurance import solve_endurance

    result = solve_endurance(_shipped_with_power(tmp_path, factor), 0.5)
    flagged = [w for w in result.warnings if "overall efficiency" in w]
    assert bool(flagged) is warns
    for agreement in result.power_agreement:
        # the overall efficiency goes as 1 / power: 2.5 x the power, 0.4 x the efficiency
        assert agreement.electrical_power_w > 0
        assert (agreement.overall_efficiency < 0.2) is warns


def test_propulsion_keys_are_validated(tmp_path) -> None:
    import yaml

    from tuflexperf.errors import InputError
    from tuflexperf.io.case import load_case, load_propulsion

    shipped = load_case().propulsion_path
    document = yaml.safe_load(shipped.read_text())
    del document["fan_area_m2"]  # a windmilling coefficient refers to the fan area
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(InputError, match="windmilling_drag_coefficient needs fan_area_m2"):
        load_propulsion(tmp_path / "a.yaml")
    document = yaml.safe_load(shipped.read_text())
    document["engines"][1]["power"]["model"] = "poly33"
    (tmp_path / "b.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(InputError, match=r"engines\[1\]\.power\.model"):
        load_propulsion(tmp_path / "b.yaml")
    document = yaml.safe_load(shipped.read_text())
    document["engines"][0]["windmilling_drag_coefficient"] = -0.3
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(InputError, match="windmilling_drag_coefficient"):
        load_propulsion(tmp_path / "c.yaml")
