"""Moving-window filters against MATLAB's documented examples and hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest

from tuflexperf.reduction.filters import (
    block_mean,
    filloutliers_movmean,
    movmean,
    movmedian,
    movstd,
    window_samples,
)

# MATLAB documentation, movmean / movmedian: "Centered Moving Average of Vector"
A = np.array([4.0, 8.0, 6.0, -1.0, -2.0, -3.0, -1.0, 3.0, 4.0, 5.0])


def test_movmean_matlab_doc_example() -> None:
    # M = movmean(A,3) -> 6.0000 6.0000 4.3333 1.0000 -2.0000 -2.0000 -0.3333 2.0000 4.0000 4.5000
    expected = [6.0, 6.0, 13 / 3, 1.0, -2.0, -2.0, -1 / 3, 2.0, 4.0, 4.5]
    np.testing.assert_allclose(movmean(A, 3), expected, rtol=0, atol=1e-12)


def test_movmedian_matlab_doc_example() -> None:
    # M = movmedian(A,3) -> 6 6 6 -1 -2 -2 -1 3 4 4.5
    expected = [6.0, 6.0, 6.0, -1.0, -2.0, -2.0, -1.0, 3.0, 4.0, 4.5]
    np.testing.assert_array_equal(movmedian(A, 3), expected)


def test_movstd_hand_computed_shrinking_ends() -> None:
    # window [4 8] at the start: std = sqrt(((4-6)^2 + (8-6)^2) / 1) = 2*sqrt(2)
    # window [8 6 -1]: mean 13/3, deviations 11/3, 5/3, -16/3 -> var = (121+25+256)/9/2
    out = movstd(A, 3)
    assert out[0] == pytest.approx(2 * np.sqrt(2))
    assert out[2] == pytest.approx(np.sqrt((121 + 25 + 256) / 18))
    assert out[-1] == pytest.approx(np.sqrt(0.5))  # [4 5]


def test_even_window_spans_half_before_and_half_minus_one_after() -> None:
    # MATLAB: an even window k is centred on the current and previous elements:
    # k/2 samples before, k/2 - 1 after. movmean(1:6, 4) at index 3 (value 3): mean(1:4).
    x = np.arange(1.0, 7.0)
    assert movmean(x, 4)[2] == pytest.approx(np.mean([1, 2, 3, 4]))
    assert movmean(x, 4)[0] == pytest.approx(np.mean([1, 2]))  # shrunk: [1 2]
    assert movmedian(x, 4)[2] == pytest.approx(2.5)  # average of the two middle values


@pytest.mark.parametrize("k", [1, 2, 3, 4, 7, 10, 33, 200])
def test_moving_filters_equal_brute_force(k: int) -> None:
    rng = np.random.default_rng(k)
    x = rng.normal(size=97) * 3 + np.repeat([0.0, 5.0, -2.0], [30, 40, 27])
    before, after = k // 2, k - 1 - k // 2
    windows = [x[max(i - before, 0) : i + after + 1] for i in range(x.size)]
    np.testing.assert_allclose(movmean(x, k), [w.mean() for w in windows], atol=1e-12)
    np.testing.assert_allclose(movmedian(x, k), [np.median(w) for w in windows], atol=1e-12)
    stds = [w.std(ddof=1) if w.size > 1 else 0.0 for w in windows]
    np.testing.assert_allclose(movstd(x, k), stds, atol=1e-9)


@pytest.mark.parametrize("k", [2, 4, 100, 250])
def test_even_window_median_equals_both_rank_filters_to_the_bit(k: int) -> None:
    # the even window's one-pass running median (Bottleneck) against the mean of SciPy's
    # two middle-rank filters it replaced, on a long signal with steps and ties, and
    # against the brute-force median of every window
    from scipy.ndimage import rank_filter

    rng = np.random.default_rng(k)
    x = np.round(rng.normal(size=5000) * 2 + np.repeat([0.0, 40.0, -7.0, 12.0], 1250), 1)
    out = movmedian(x, k)
    before, after = k // 2, k - 1 - k // 2
    upper = rank_filter(x, rank=k // 2, size=k, mode="nearest")
    lower = rank_filter(x, rank=k // 2 - 1, size=k, mode="nearest")
    np.testing.assert_array_equal(out[before : x.size - after],
                                  (0.5 * (lower + upper))[before : x.size - after])
    windows = [x[max(i - before, 0) : i + after + 1] for i in range(x.size)]
    np.testing.assert_allclose(out, [np.median(w) for w in windows], rtol=0, atol=1e-12)


def test_isoutlier_mean_matlab_doc_example() -> None:
    # MATLAB isoutlier doc, "Outliers Using Mean Detection": only 300 is 3 std from the mean.
    # A moving window covering the whole vector reduces to that global method.
    b = np.array([57, 59, 60, 100, 59, 58, 57, 58, 300, 61, 62, 60, 62, 58, 57], dtype=float)
    filled, count = filloutliers_movmean(b, k=2 * b.size + 1, threshold=3.0)
    assert count == 1 and list(np.flatnonzero(filled != b)) == [8]


def test_filloutliers_center_replaces_with_local_mean() -> None:
    # 21 ones with a spike of 11 in the middle, window 21 (all), threshold 1.5:
    # mean = 1 + 10/21; the spike is 200/21 = 9.52 above it, std = sqrt(42000/441/20) = 2.18,
    # i.e. 4.4 std (an outlier); the ones are 0.48 = 0.22 std below (kept)
    x = np.ones(21)
    x[10] = 11.0
    filled, count = filloutliers_movmean(x, 21, threshold=1.5)
    assert count == 1
    centre = np.mean(x[0:21])  # window of sample 10 covers all 21 samples
    assert filled[10] == pytest.approx(centre)
    np.testing.assert_array_equal(np.delete(filled, 10), np.ones(20))


def test_filloutliers_short_window_keeps_a_spike_it_dominates() -> None:
    # window 3 around a spike h: |h - mean| = 2h/3, std = h/sqrt(3): ratio 1.15 < 1.5
    x = np.array([0.0, 0.0, 0.0, 9.0, 0.0, 0.0, 0.0])
    _, count = filloutliers_movmean(x, 3, threshold=1.5)
    assert count == 0


def test_threshold_is_strict() -> None:
    # [0 0 1 0 0] whole window: mean 0.2, std sqrt(0.2) ~ 0.447; |1 - 0.2| = 0.8 = 1.789 std
    x = np.array([0.0, 0.0, 1.0, 0.0, 0.0])
    ratio = 0.8 / np.sqrt(0.2)
    assert filloutliers_movmean(x, 11, threshold=ratio * (1 - 1e-9))[1] == 1
    assert filloutliers_movmean(x, 11, threshold=ratio * (1 + 1e-9))[1] == 0


def test_window_samples_from_seconds() -> None:
    assert window_samples(2.0, 1000.0) == 2000  # the paper's 2 s at 1 kHz
    assert window_samples(2.0, 250.0) == 500
    assert window_samples(0.001, 100.0) == 1  # never zero
    with pytest.raises(ValueError):
        window_samples(0.0, 100.0)


def test_block_mean_drops_partial_block() -> None:
    np.testing.assert_array_equal(block_mean(np.arange(7.0), 3), [1.0, 4.0])


@pytest.mark.parametrize("n", [1, 2, 3, 10, 37, 200])
def test_movmedian_with_a_window_longer_than_the_signal_is_the_definition(n: int) -> None:
    """Windows of n..2n+3 samples (a run logged in microseconds spans its 0.1 s window):
    each sample's window cut to the signal, ties included, equals np.median of it."""
    rng = np.random.default_rng(n)
    x = np.round(rng.normal(size=n), 1)  # rounded: ties
    for k in range(n, 2 * n + 4):
        kk = min(k, 2 * n + 1)
        before, after = kk // 2, kk - 1 - kk // 2
        expected = [np.median(x[max(i - before, 0):min(i + after + 1, n)]) for i in range(n)]
        np.testing.assert_array_equal(movmedian(x, k), expected)


@pytest.mark.parametrize("k", [1, 2, 7, 100, 101])
def test_movmedians_equal_one_movmedian_per_piece(k: int) -> None:
    """The pieces filtered together (one running median over their concatenation, one sort
    for every cut-short end) give to the bit what movmedian gives each piece on its own:
    long and short pieces, NaN in one, ties and signed zeros among the values."""
    from tuflexperf.reduction.filters import movmedians

    rng = np.random.default_rng(k)
    sizes = [3085, 2 * k + 5, k + 1, k, max(k - 3, 1), 1, 4000, 250]
    pieces = [np.round(rng.normal(30.0, 2.0, size=n), 1) for n in sizes]
    pieces[1][::7] = 0.0
    pieces[1][3::7] = -0.0
    pieces[6][100] = np.nan  # movmedian's path for NaN, not the shared one
    together = movmedians(pieces, k)
    assert len(together) == len(pieces)
    for piece, filtered in zip(pieces, together, strict=True):
        alone = movmedian(piece, k)
        assert filtered.shape == alone.shape
        assert np.array_equal(filtered, alone, equal_nan=True)
        assert np.array_equal(np.signbit(filtered), np.signbit(alone))
