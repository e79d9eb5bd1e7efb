"""Min-max envelope decimation draws the same pixels as the whole series (issue 9)."""

from __future__ import annotations

import numpy as np

from tuflexperf.report.decimate import envelope, envelope_indices


def _render(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.69, 4), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.plot(t, y, color="black", linewidth=0.6, antialiased=False)
    ax.set_xlim(t[0], t[-1])
    ax.set_ylim(-4, 4)
    ax.axis("off")
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., 0] < 128


def test_envelope_keeps_every_column_extreme_and_the_ends() -> None:
    rng = np.random.default_rng(1)
    y = rng.normal(size=100_003)
    idx = envelope_indices(len(y), y, columns=100)
    assert idx[0] == 0 and idx[-1] == len(y) - 1 and np.all(np.diff(idx) > 0)
    per = len(y) // 100
    for c in range(100):
        block = y[c * per:(c + 1) * per]
        kept = y[idx[(idx >= c * per) & (idx < (c + 1) * per)]]
        assert kept.max() == block.max() and kept.min() == block.min()
    assert len(idx) <= 4 * 100 + len(y) - 100 * per


def test_short_series_are_untouched() -> None:
    t = np.arange(50.0)
    out_t, out_y = envelope(t, t**2)
    np.testing.assert_array_equal(out_t, t)
    np.testing.assert_array_equal(out_y, t**2)


def test_decimated_plot_draws_the_pixels_of_the_whole_series_and_plain_subsampling_does_not(
) -> None:
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 36.0, 144_000)
    y = np.sin(2 * np.pi * 0.05 * t * t) + 0.2 * rng.normal(size=t.size)
    y[rng.integers(0, t.size, 40)] += 3.0  # spikes the run-processing page must show
    full = _render(t, y)
    dt, dy = envelope(t, y)
    assert dt.size < t.size / 15
    step = t.size // dt.size
    diff_envelope = np.mean(full != _render(dt, dy)) / np.mean(full)
    diff_plain = np.mean(full != _render(t[::step], y[::step])) / np.mean(full)
    assert diff_envelope < 0.05, diff_envelope
    assert diff_plain > 4 * diff_envelope
