"""Change points, throttle plateaus, transients and segment means on synthetic steps."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from tuflexperf.reduction.changepoints import cross_check, force_changepoints, throttle_plateaus
from tuflexperf.reduction.segments import fit_transients, merge_test_points, steady_means

FS = 500.0


def staircase(levels, seconds, fs=FS):
    counts = [int(round(s * fs)) for s in seconds]
    return np.repeat(np.asarray(levels, dtype=float), counts), np.cumsum(counts)[:-1]


def test_force_changepoints_find_synthetic_steps() -> None:
    rng = np.random.default_rng(1)
    force, edges = staircase([0, 50, 42, 35, 35.0, 20], [2, 3, 2.5, 3, 2, 3])
    # 35 -> 35 is no change: 4 true changes
    noisy = force + rng.normal(0, 0.3, force.size)
    found = force_changepoints(noisy, FS)
    true = [e for i, e in enumerate(edges) if i != 3]
    assert len(found) == len(true)
    assert np.max(np.abs(np.array(found) - true)) <= 2  # within 2 samples (4 ms)


def test_force_changepoints_ignore_pure_noise() -> None:
    rng = np.random.default_rng(2)
    assert force_changepoints(40 + rng.normal(0, 1.0, 20_000), FS) == []


def test_a_long_run_searched_in_windows_finds_what_one_search_finds() -> None:
    """A run longer than one PELT window (here 3.5 windows of block means, with steps on and
    near the windows' seams) gives the change points of one search over the whole run: PELT
    grows with the square of a steady run's length, the windows with it (outside audit)."""
    import ruptures

    from tuflexperf.reduction import changepoints

    rng = np.random.default_rng(3)
    n = int(3.5 * changepoints.PELT_WINDOW_BLOCKS)
    core = changepoints.PELT_WINDOW_BLOCKS - 2 * changepoints.PELT_MARGIN_BLOCKS
    steps = sorted({700, core - 3, core + 15, 2 * core, 2 * core + 40, 3 * core - 600, n - 300})
    levels = np.cumsum(rng.choice([-1.0, 1.0], len(steps) + 1) * rng.uniform(0.5, 3.0,
                                                                            len(steps) + 1))
    coarse = np.repeat(levels, np.diff([0, *steps, n])) + rng.normal(0.0, 0.05, n)
    penalty = 10 * 0.05**2 * np.log(n)
    whole = ruptures.KernelCPD(kernel="linear", min_size=10, jump=1).fit(
        coarse.reshape(-1, 1)).predict(pen=penalty)[:-1]
    assert whole == steps  # the test's own truth, found by one search
    assert changepoints.kernel_breaks(coarse, 10, penalty) == whole


def test_throttle_plateaus_from_logged_steps() -> None:
    throttle, edges = staircase([0, 1.0, 0.9, 0.8, 0.8, 0.0], [1, 2, 2, 1, 1, 1])
    plateaus = throttle_plateaus(throttle, FS)
    assert [p.throttle for p in plateaus] == [0, 1.0, 0.9, 0.8, 0.0]
    assert plateaus[0].step_index is None
    # a step starts where the command changed; repeated levels are one plateau
    assert [p.step_index for p in plateaus[1:]] == [edges[0], edges[1], edges[2], edges[4]]
    assert all(p.steady for p in plateaus)


def test_throttle_plateaus_with_logging_noise_and_a_ramp() -> None:
    rng = np.random.default_rng(3)
    throttle, _ = staircase([0.5, 0.7], [2, 2])
    ramp = np.linspace(0.7, 0.2, int(2 * FS))  # a slow ramp: not a steady point
    x = np.concatenate([throttle, ramp, np.full(int(2 * FS), 0.2)])
    x = x + rng.normal(0, 0.0005, x.size)
    plateaus = throttle_plateaus(x, FS)
    steady = [round(p.throttle, 2) for p in plateaus if p.steady]
    assert steady == [0.5, 0.7, 0.2]


def test_cross_check_sorts_changes() -> None:
    steps = [1000, 3000]
    changes = [1030, 1200, 2000, 3040]
    check = cross_check(steps, changes, before=100, after=300, expected_lag=25)
    assert check.matched == {1000: 1030, 3000: 3040}
    assert check.in_transient == [1200]
    assert check.changes_without_step == [2000]
    assert check.steps_without_change == []
    assert cross_check([5000], [], before=10, after=10).steps_without_change == [5000]


def _lagged_steps(tau: float, delay: float, fs: float = FS):
    throttle, edges = staircase([0.0, 1.0, 0.8, 0.5, 0.3], [1, 3, 3, 3, 3], fs)
    t = np.arange(throttle.size) / fs
    u = np.interp(t - delay, t, throttle, left=0.0)
    a = np.exp(-1 / fs / tau)
    lagged = lfilter([1 - a], [1, -a], u)
    return t, throttle, edges, 50.0 * lagged


def test_fit_transients_recovers_time_constant() -> None:
    tau, delay = 0.12, 0.04
    t, _, edges, force = _lagged_steps(tau, delay)
    d = int(round(delay * FS))
    onsets = [e + d for e in edges]
    stops = [*edges[1:], t.size]
    fit = fit_transients(t, force, onsets, stops, FS)
    assert fit.tau_s == pytest.approx(tau, rel=0.03)
    # amplitude of the 1.0 -> 0.8 step: 50 * 0.2 = 10 N above the new level
    assert fit.amplitude_n[1] == pytest.approx(10.0, rel=0.03)
    # settled when 10 exp(-t/tau) < 0.01 N
    assert fit.settle_s[1] == pytest.approx(tau * np.log(10.0 / 0.01), rel=0.05)


def test_steady_mean_excludes_spikes_and_matches_level() -> None:
    rng = np.random.default_rng(4)
    n = 2000
    force = 30.0 + rng.normal(0, 0.5, n)
    force[rng.integers(0, n, 20)] += 15.0  # isolated spikes
    seg = steady_means(force, np.full(n, 20.0), np.full(n, 0.6), [(0, n)], 1000, 1.5, 25)[0]
    assert seg.force_n == pytest.approx(30.0, abs=0.05)
    assert seg.outliers_replaced >= 20
    assert (seg.throttle, seg.airspeed_m_s, seg.n_samples) == (0.6, 20.0, n)


def test_merge_test_points_weights_by_samples() -> None:
    def held(n: int, force: float, throttle: float) -> object:
        return steady_means(np.full(n, force), np.zeros(n), np.full(n, throttle), [(0, n)],
                            5, 1.5, 3)[0]

    base, other, again = held(10, 1.0, 0.0), held(30, 2.0, 0.5), held(30, 3.0, 0.001)
    cells = merge_test_points([base, other, again])
    assert [c.members for c in cells] == [(0, 2), (1,)]
    assert cells[0].force_n == pytest.approx((10 * 1.0 + 30 * 3.0) / 40)
    assert cells[0].n_samples == 40


@pytest.mark.parametrize("n_values", [5, 10_000, 70_000])
def test_grid_sse_in_blocks_equals_the_whole_grid_at_once(n_values: int) -> None:
    """The time-constant grid evaluated a few rows at a time (cache-sized temporaries) gives
    the bit-identical SSE of evaluating all rows in one broadcast, as the fit did before."""
    from tuflexperf.reduction.segments import _grid_sse, _segment_sse

    rng = np.random.default_rng(n_values)
    cuts = np.sort(rng.choice(np.arange(1, n_values), size=min(11, n_values - 1), replace=False))
    starts = np.concatenate(([0], cuts)).astype(np.intp)
    t = np.concatenate([np.sort(rng.uniform(0, 3, size=b - a))
                        for a, b in zip(starts, [*starts[1:], n_values], strict=True)])
    y = rng.normal(20.0, 5.0, size=n_values)
    taus = np.geomspace(2e-3, 1.0, 40)
    whole = _segment_sse(y, np.exp(-t / taus[:, None]), starts)[0]
    assert np.array_equal(_grid_sse(t, y, taus, starts), whole)
