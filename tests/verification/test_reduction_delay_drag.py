"""Delay from sine sweeps, structure drag and the Glauert correction against known answers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from tuflexperf.reduction.delay import estimate_delay
from tuflexperf.reduction.drag import fit_structure_drag
from tuflexperf.reduction.glauert import glauert_ratio


def sweep(fs: float, delay: float, tau: float, lag_first: bool, seed: int = 0):
    """Throttle 25-75 % sine rising 0.2 -> 5 Hz; force = fan(delayed throttle) + noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 30.0, 1.0 / fs)
    ts = np.clip(t - 2.0, 0.0, 26.0)
    x = np.where(t < 1.0, 0.0, 0.5 + 0.25 * np.sin(2 * np.pi * (0.2 * ts + 0.5 * 4.8 / 26 * ts**2)))
    u = np.interp(t - delay, t, x, left=0.0)

    def lag(v: np.ndarray) -> np.ndarray:
        if tau == 0:
            return v
        a = np.exp(-1.0 / fs / tau)
        return lfilter([1 - a], [1, -a], v)

    force = 52 * lag(u) ** 2 + 2 * lag(u) if lag_first else lag(52 * u**2 + 2 * u)
    force = force - 3.0 + rng.normal(0, 0.8, t.size)
    spikes = rng.random(t.size) < 1e-3
    force[spikes] += rng.choice([-12.0, 12.0], int(spikes.sum()))
    return t, x, force


@pytest.mark.parametrize(
    ("fs", "delay", "tau", "lag_first"),
    [
        (1000.0, 0.05, 0.08, True),  # the paper's rate and delay, with spool lag
        (1000.0, 0.05, 0.08, False),  # lag acting on thrust rather than rpm
        (250.0, 0.12, 0.0, True),  # pure dead time, other rate
        (100.0, 0.03, 0.15, True),  # slow log, long lag
    ],
)
def test_delay_recovered_within_12_ms(fs: float, delay: float, tau: float, lag_first: bool) -> None:
    t, x, force = sweep(fs, delay, tau, lag_first)
    estimate = estimate_delay(t, x, force, fs)
    assert estimate.delay_s == pytest.approx(delay, abs=0.012)
    assert estimate.lag_s == pytest.approx(tau, abs=0.02)
    if tau >= 0.08:
        # why the lag is fitted: plain cross-correlation reports dead time plus lag
        assert abs(estimate.xcorr_lag_s - delay) > 0.012


def fine_sweep(fs: float, delay: float, tau: float, seed: int = 1):
    """The rig simulated at 20 kHz (so its own discretisation is no part of the truth), then
    logged at ``fs``: throttle 25-75 % rising 0.1 -> 5 Hz over 60 s, dead time, spool lag
    on the rpm, thrust ~ rpm^2, 0.3 N noise."""
    rng = np.random.default_rng(seed)
    sim = 20_000.0
    t = np.arange(0.0, 62.0, 1.0 / sim)
    ts = np.clip(t - 1.0, 0.0, 60.0)
    x = 0.5 + 0.25 * np.sin(2 * np.pi * (0.1 * ts + 0.5 * 4.9 / 60 * ts**2))
    u = np.interp(t - delay, t, x, left=x[0])
    if tau > 0:
        a = np.exp(-1.0 / sim / tau)
        u = lfilter([1 - a], [1, -a], u, zi=[a * u[0]])[0]
    force = 30.0 * u**2 + 2.0 * u
    step = int(round(sim / fs))
    t, x, force = t[::step], x[::step], force[::step]
    return t, x, force + rng.normal(0.0, 0.3, t.size)


@pytest.mark.parametrize(("delay", "tau"), [
    (0.05, 0.0),   # the paper's 50 ms as a pure delay: was 41 ms + a 12 ms lag
    (0.05, 0.01), (0.04, 0.02), (0.04, 0.03), (0.08, 0.02),  # were 6-18 ms off
    (0.02, 0.03), (0.05, 0.08), (0.04, 0.06),
])
@pytest.mark.parametrize("fs", [1000.0, 500.0])
def test_dead_time_and_lag_split_against_a_known_truth(fs: float, delay: float,
                                                        tau: float) -> None:
    """Dead time and spool lag each within 3 ms (outside audit: the coarse search took the
    wrong side of the valley d + tau = const, and the lag ran half a block ahead, +2 ms)."""
    t, x, force = fine_sweep(fs, delay, tau)
    estimate = estimate_delay(t, x, force, fs)
    assert estimate.delay_s == pytest.approx(delay, abs=0.003)
    assert estimate.lag_s == pytest.approx(tau, abs=0.003)


def test_the_grid_equals_the_direct_residual_at_whole_sample_delays() -> None:
    from tuflexperf.reduction.delay import _projected_sse, _shifted_grid_sse
    from tuflexperf.reduction.filters import block_mean

    t, x, force = fine_sweep(1000.0, 0.045, 0.03)
    t, x, y = (block_mean(v, 5) for v in (t, x, force))
    taus = np.array([0.0, 0.002, 0.03, 0.2])
    grid = _shifted_grid_sse(t, x, y, 0.005, taus, 12)
    direct = _projected_sse(t, x, y, 0.005)
    expected = np.array([direct(k * 0.005, taus) for k in range(13)]).T
    np.testing.assert_allclose(grid, expected, rtol=1e-6)


def test_structure_drag_exact_on_noise_free_sweep_with_tare() -> None:
    v = np.linspace(0, 30, 500)
    drag = 0.0006 * v + 0.0031 * v * v
    model = fit_structure_drag([(v, 0.25 - drag), (v[::2], -0.1 - drag[::2])])
    assert model.c1_n_per_m_s == pytest.approx(0.0006, abs=1e-12)
    assert model.c2_n_per_m2_s2 == pytest.approx(0.0031, abs=1e-12)
    assert model.tares_n == pytest.approx((0.25, -0.1), abs=1e-10)
    assert model.drag_n(0.0) == 0.0
    assert model.r2 == pytest.approx(1.0)


def test_structure_drag_least_squares_with_noise() -> None:
    rng = np.random.default_rng(5)
    v = np.linspace(0, 30, 20_000)
    force = -0.5 * 1.225 * 0.0055 * v * v + rng.normal(0, 0.1, v.size)
    model = fit_structure_drag([(v, force)])
    assert float(model.drag_n(30.0)) == pytest.approx(0.5 * 1.225 * 0.0055 * 900, abs=0.02)


def test_glauert_matches_hand_computation_and_paper_bound() -> None:
    # T = 40 N, V = 30 m/s, rho = 1.225, A = 0.0068 m^2, C = 0.16 m^2 (SPEC 3 form)
    t_n, v, rho, area, tunnel = 40.0, 30.0, 1.225, 0.0068, 0.16
    tau = t_n / (rho * area * v * v)
    expected = 1 - (t_n / (rho * tunnel * v * v)) / (2 * np.sqrt(1 + 2 * tau))
    ratio = float(glauert_ratio(t_n, v, rho, area, tunnel))
    assert ratio == pytest.approx(expected, rel=1e-14)
    # the paper: under 4 % and under 1 m/s at 30 m/s
    assert 0 < 1 - ratio < 0.04
    assert (1 - ratio) * v < 1.0


def test_glauert_undefined_at_rest_and_for_strong_windmilling() -> None:
    ratios = glauert_ratio([50.0, -20.0, 10.0], [0.0, 5.0, 20.0], 1.225, 0.0068, 0.16)
    assert np.isnan(ratios[0])  # no stream to correct
    assert np.isnan(ratios[1])  # 1 + 2 tau < 0
    assert 0.9 < ratios[2] < 1.0


def test_the_residual_at_several_delays_equals_one_delay_at_a_time() -> None:
    """The refinement's stencil asks for three dead times at once: each row is to the bit
    what a call with that dead time alone gives (lags 0 and > 0, a delay past the grid)."""
    from tuflexperf.reduction.delay import _projected_sse
    from tuflexperf.reduction.filters import block_mean

    t, x, force = fine_sweep(1000.0, 0.045, 0.03)
    t, x, y = (block_mean(v, 5) for v in (t, x, force))
    sse = _projected_sse(t, x, y, 0.005)
    delays = np.array([0.0, 0.0437, 0.05, 0.2])
    taus = np.array([0.0, 0.003, 0.031])
    together = sse(delays, taus)
    assert together.shape == (delays.size, taus.size)
    for row, delay in zip(together, delays, strict=True):
        assert np.array_equal(row, sse(float(delay), taus))
        assert np.array_equal(row[1:2], sse(float(delay), taus[1:2]))
