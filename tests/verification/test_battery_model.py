"""Exact checks of the discharge model: closed forms, quadrature, rootfinder, fit recovery."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from tuflexperf.io.discharge import DischargeRun, read_discharge_run
from tuflexperf.models.battery import (
    PARAMETER_NAMES,
    DischargeParameters,
    FanPowerModel,
    current_at_power_a,
    cutoff_charge_ah,
    cutoff_residual_v,
    discharge_time_s,
    open_circuit_voltage_v,
    published_static_power_w,
    terminal_voltage_v,
    time_to_cutoff_s,
)
from tuflexperf.reduction.battery import (
    DischargeFit,
    _finish_fit,
    _fit_setup,
    _residual_function,
    fit_discharge,
    fit_fan_power,
)

# A plausible 12S 5 Ah pack (the values only need to be physical, not the shipped ones).
PACK = DischargeParameters(
    e0_v=48.6, slope_v_per_ah=0.72, exp_amplitude_v=1.44, exp_rate_per_ah=3.0,
    knee_v=0.24, max_capacity_ah=5.25, resistance_ohm=0.05,
)
CUTOFF_V = 40.8


@pytest.mark.parametrize("packs", [1, 2, 3])
@pytest.mark.parametrize("power_w", [200.0, 1300.0, 2500.0])
def test_current_delivers_the_power(packs: int, power_w: float) -> None:
    q = np.linspace(0.0, 0.9 * packs * PACK.max_capacity_ah, 25)
    i = current_at_power_a(PACK, q, power_w, packs)
    np.testing.assert_allclose(terminal_voltage_v(PACK, q, i, packs) * i, power_w, rtol=1e-12)


def test_parallel_packs_are_one_bigger_pack() -> None:
    # n packs carrying n i at n q behave like one pack carrying i at q.
    q, i = 2.0, 30.0
    for n in (2, 4):
        assert terminal_voltage_v(PACK, n * q, n * i, n) == pytest.approx(
            terminal_voltage_v(PACK, q, i, 1), rel=1e-14
        )


def test_numpy_and_casadi_agree() -> None:
    q, p = ca.SX.sym("q"), ca.SX.sym("p")
    f = ca.Function("f", [q, p], [current_at_power_a(PACK, q, p, 2),
                                  cutoff_residual_v(PACK, q, p, CUTOFF_V, 2),
                                  discharge_time_s(PACK, p, 0.5, q, 2)])
    for qv, pv in [(1.0, 900.0), (7.5, 2100.0)]:
        out = [float(v) for v in f(qv, pv)]
        assert out[0] == pytest.approx(float(current_at_power_a(PACK, qv, pv, 2)), rel=1e-13)
        residual = float(cutoff_residual_v(PACK, qv, pv, CUTOFF_V, 2))
        assert out[1] == pytest.approx(residual, rel=1e-12)
        assert out[2] == pytest.approx(float(discharge_time_s(PACK, pv, 0.5, qv, 2)), rel=1e-12)


@pytest.mark.parametrize("power_w", [800.0, 1400.0, 2300.0])
def test_cutoff_charge_is_where_loaded_voltage_hits_cutoff(power_w: float) -> None:
    q_cut = cutoff_charge_ah(PACK, power_w, CUTOFF_V)
    i = current_at_power_a(PACK, q_cut, power_w)
    assert terminal_voltage_v(PACK, q_cut, i) == pytest.approx(CUTOFF_V, abs=1e-9)
    assert 0.0 < q_cut < PACK.max_capacity_ah


@pytest.mark.parametrize("power_w", [800.0, 1400.0, 2300.0])
def test_time_to_cutoff_matches_time_domain_simulation(power_w: float) -> None:
    """Gauss-Legendre in charge == an adaptive ODE in time stopped at the cut-off event."""

    def rate(_t: float, y: np.ndarray) -> list[float]:
        return [float(current_at_power_a(PACK, y[0], power_w)) / 3600.0]

    def hits_cutoff(_t: float, y: np.ndarray) -> float:
        i = current_at_power_a(PACK, y[0], power_w)
        return float(terminal_voltage_v(PACK, y[0], i)) - CUTOFF_V

    hits_cutoff.terminal = True
    sim = solve_ivp(rate, (0.0, 1e5), [0.0], events=hits_cutoff, rtol=1e-11, atol=1e-13)
    assert sim.t_events[0].size == 1
    assert time_to_cutoff_s(PACK, power_w, CUTOFF_V) == pytest.approx(sim.t_events[0][0], rel=1e-7)


def test_energy_bookkeeping() -> None:
    """P t (power over the discharge) == integral of V dq (energy the pack gave)."""
    power_w = 1500.0
    q_cut = cutoff_charge_ah(PACK, power_w, CUTOFF_V)
    t = time_to_cutoff_s(PACK, power_w, CUTOFF_V)

    def volts(q: float) -> float:
        return float(terminal_voltage_v(PACK, q, current_at_power_a(PACK, q, power_w)))

    energy_j = 3600.0 * quad(volts, 0.0, q_cut, epsabs=1e-10, epsrel=1e-12)[0]
    assert power_w * t == pytest.approx(energy_j, rel=1e-9)
    # and the loss split: chemical energy = delivered + I^2 R heat
    ocv_j = 3600.0 * quad(lambda q: float(open_circuit_voltage_v(PACK, q)), 0.0, q_cut)[0]
    heat_j = 3600.0 * quad(
        lambda q: PACK.resistance_ohm * float(current_at_power_a(PACK, q, power_w)), 0.0, q_cut
    )[0]
    assert ocv_j == pytest.approx(energy_j + heat_j, rel=1e-9)


def _rate(q: float, power_w: float) -> float:
    return float(current_at_power_a(PACK, q, power_w)) / 3600.0


def _synthetic_run(path: Path, power_w: float, throttle: float) -> Path:
    """A noise-free run of PACK at constant power, 2 Hz, 10 s idle before the step."""
    dt, t, q, rows = 0.5, 0.0, 0.0, []
    while True:
        on = t >= 10.0
        i = float(current_at_power_a(PACK, q, power_w)) if on else 0.0
        v = float(terminal_voltage_v(PACK, q, i))
        rows.append((t, 0.0, 30.0, throttle if on else 0.0, v, i))
        if on and v <= CUTOFF_V:
            break
        if on:  # RK4 on dq/dt = i(q)/3600 at constant power
            k1 = _rate(q, power_w)
            k2 = _rate(q + dt / 2 * k1, power_w)
            k3 = _rate(q + dt / 2 * k2, power_w)
            k4 = _rate(q + dt * k3, power_w)
            q += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += dt
    lines = ["time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a"]
    lines += [",".join(f"{x:.10g}" for x in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_fit_recovers_the_model_it_was_given(tmp_path: Path) -> None:
    runs = [
        read_discharge_run(_synthetic_run(tmp_path / "a.csv", 1300.0, 0.5)),
        read_discharge_run(_synthetic_run(tmp_path / "b.csv", 2200.0, 0.75)),
    ]
    fit = fit_discharge(runs, cells_in_series=12, capacity_ah=5.0)
    # Trapezoid charge from 2 Hz samples and 1-s blocks leave millivolts, not more.
    assert fit.rms_v < 0.01
    for power in (1000.0, 1800.0):
        assert time_to_cutoff_s(fit.parameters, power, CUTOFF_V) == pytest.approx(
            time_to_cutoff_s(PACK, power, CUTOFF_V), rel=5e-3
        )


def fit_discharge_ipopt(
    runs: Sequence[DischargeRun], cells_in_series: int, capacity_ah: float
) -> DischargeFit:
    """The same least-squares fit as :func:`fit_discharge`, solved by CasADi's IPOPT: the
    reference the Levenberg-Marquardt fit is held to (about ten times slower)."""
    q, i, v, scale, lower, upper, z0 = _fit_setup(runs, cells_in_series, capacity_ah)
    residual = _residual_function(scale)
    z = ca.MX.sym("z", len(PARAMETER_NAMES))
    data = [ca.DM(column).T for column in (q, i, v)]
    r = residual.map(q.size, "serial")(z, *data)[0]
    objective = 0.5 * ca.sumsqr(r) / q.size
    solver = ca.nlpsol(
        "discharge_fit",
        "ipopt",
        {"x": z, "f": objective},
        {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
         "ipopt.tol": 1e-12, "ipopt.max_iter": 500},
    )
    solution = solver(x0=z0, lbx=lower, ubx=upper)
    status = solver.stats()["return_status"]
    params = DischargeParameters.from_vector(np.asarray(solution["x"]).ravel() * scale)
    ok = status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    return _finish_fit(runs, params, ok, status)


def test_levenberg_marquardt_reaches_the_ipopt_optimum(tmp_path: Path) -> None:
    """The fast fit used by check and the general NLP solver agree on the same problem."""
    runs = [
        read_discharge_run(_synthetic_run(tmp_path / "a.csv", 1300.0, 0.5)),
        read_discharge_run(_synthetic_run(tmp_path / "b.csv", 2200.0, 0.75)),
    ]
    fast = fit_discharge(runs, cells_in_series=12, capacity_ah=5.0)
    reference = fit_discharge_ipopt(runs, cells_in_series=12, capacity_ah=5.0)
    assert np.allclose(
        fast.parameters.as_vector(), reference.parameters.as_vector(), rtol=1e-6, atol=1e-9
    )
    assert fast.rms_v == pytest.approx(reference.rms_v, rel=1e-9)


def test_published_static_power_interpolates_the_table() -> None:
    ends = ((2400.0, 4100.0), (41.0, 59.0))
    assert published_static_power_w(41.0, *ends) == pytest.approx(2400.0)
    assert published_static_power_w(59.0, *ends) == pytest.approx(4100.0)
    # power ~ thrust^s with s = ln(4100/2400)/ln(59/41), close to momentum theory's 1.5
    s = math.log(4100 / 2400) / math.log(59 / 41)
    assert published_static_power_w(50.0, *ends) == pytest.approx(2400.0 * (50 / 41) ** s)
    assert abs(s - 1.5) < 0.05


def test_power_fit_recovers_an_exact_power_law(tmp_path: Path) -> None:
    law = FanPowerModel(3700.0, 1.4, 90.0)
    runs = []
    for name, x in (("a.csv", 0.5), ("b.csv", 0.75)):
        p = float(law.electrical_power_w(x, 30.0))
        t = np.arange(0.0, 60.0, 0.1)
        on = t >= 5.0
        rows = np.column_stack([t, np.zeros_like(t), np.full_like(t, 30.0), np.where(on, x, 0.0),
                                np.full_like(t, 45.0), np.where(on, p / 45.0, 0.0)])
        path = tmp_path / name
        np.savetxt(path, rows, delimiter=",", comments="",
                   header="time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a")
        runs.append(read_discharge_run(path))
    fit = fit_fan_power(runs, 3700.0, 90.0)
    assert fit.model.exponent == pytest.approx(1.4, rel=1e-9)
    assert fit.model.static_full_throttle_w == pytest.approx(3700.0, rel=1e-9)
    assert fit.rms_log_error < 1e-9


def test_the_first_stretch_beyond_a_rating_is_found_as_a_fine_scan_finds_it() -> None:
    """first_window_beyond (the pack's continuous rating over any 30 s of a flight) against a
    brute-force scan of every stretch between the points of a 0.05 s grid, on random
    histories of uneven nodes: the stretch it reports exceeds the limit, and no stretch of
    the scan does so ending more than one node interval earlier."""
    from tuflexperf.models.battery import first_window_beyond

    rng = np.random.default_rng(7)
    for _ in range(25):
        t = np.cumsum(np.r_[0.0, rng.uniform(0.2, 9.0, 40)])
        current = rng.uniform(5.0, 60.0, t.size - 1)  # A, constant between nodes
        q = np.r_[0.0, np.cumsum(current * np.diff(t))] / 3600.0
        limit = float(rng.uniform(25.0, 45.0))
        end, start, mean = (float(v[0]) for v in first_window_beyond(
            t[None, :], q[None, None, :], limit, 30.0))
        grid = np.arange(0.0, t[-1] + 1e-9, 0.05)
        qg = np.interp(grid, t, q)
        s, e = np.meshgrid(grid, grid, indexing="ij")
        with np.errstate(divide="ignore", invalid="ignore"):
            means = (qg[None, :] - qg[:, None]) * 3600.0 / (e - s)
        over = (e - s >= 30.0 - 1e-9) & (means > limit * (1 + 1e-9))
        if not over.any():
            assert end == np.inf
            continue
        scan_end = float(np.min(e[over]))
        assert end - start >= 30.0 - 1e-9
        exact = (np.interp(end, t, q) - np.interp(start, t, q)) * 3600.0 / (end - start)
        assert exact == pytest.approx(mean, rel=1e-9) and mean > limit
        gap = float(np.max(np.diff(t)))
        assert scan_end - 0.05 - 1e-9 <= end <= scan_end + gap + 1e-9


def test_a_row_of_times_that_are_not_finite_leaves_the_other_rows_as_they_are() -> None:
    """The rows are searched as one sorted array (models._math.interp_rows): a row holding a
    NaN time (a batch row the flight refuses) must not change another row's answer."""
    from tuflexperf.models.battery import first_window_beyond

    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(1.0, 20.0, (6, 8)), axis=1)
    q = np.cumsum(rng.uniform(0.0, 0.3, (6, 1, 8)), axis=2)
    alone = [first_window_beyond(t[i:i + 1], q[i:i + 1], 40.0, 30.0) for i in range(6)]
    spoiled = t.copy()
    spoiled[2, 4] = np.nan
    together = first_window_beyond(spoiled, q, 40.0, 30.0)
    for i in (0, 1, 3, 4, 5):
        for got, want in zip(together, alone[i], strict=True):
            assert got[i] == want[0] or (np.isnan(got[i]) and np.isnan(want[0]))
    assert np.isfinite(together[0][[0, 1, 3, 4, 5]]).any()  # some row is beyond the limit
