"""The sine sweep's first-harmonic amplitude per frequency (issue 47 item 6), on signals of
known amplitude and delay."""

from __future__ import annotations

import numpy as np
import pytest

from tuflexperf.reduction.delay import sweep_amplitudes


def _chirp(rate_hz: float = 1000.0):
    t = np.arange(0.0, 30.0, 1.0 / rate_hz)
    f0, f1 = 0.8, 5.5
    phase = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / t[-1] * t**2)
    freq = f0 + (f1 - f0) * t / t[-1]
    throttle = 0.5 + 0.25 * np.sin(phase)
    throttle = np.append(throttle, np.full(500, 0.5))  # held at the end, as the campaign's
    t = np.arange(throttle.size) / rate_hz
    return t, throttle, np.append(phase, np.zeros(500)), np.append(freq, np.zeros(500))


def test_a_known_amplitude_is_found_at_each_frequency_despite_noise_and_a_harmonic():
    t, throttle, phase, freq = _chirp()
    rng = np.random.default_rng(3)
    amplitude = 10.0 / (1.0 + freq)  # falls with frequency, like a lagged fan
    force = 20 + amplitude * np.sin(phase - 0.7) + 1.5 * np.sin(2 * phase)
    noisy = force + rng.normal(0.0, 0.8, t.size)
    double = 20 + 2.0 * amplitude * np.sin(phase - 0.7)
    result = sweep_amplitudes(t, throttle, np.vstack([noisy, double]))
    expected = 10.0 / (1.0 + result.frequency_hz)
    reached = np.isfinite(result.measured_n)
    assert reached.sum() >= 5  # 1-5 Hz are in the sweep: the test can fail
    np.testing.assert_allclose(result.measured_n[reached], expected[reached], rtol=0.05)
    np.testing.assert_allclose(result.error[0][reached], 1.0, atol=0.08)  # model twice as big
    assert not reached[0]  # 0.5 Hz is below the sweep: NaN, not a number made up


def test_a_sweep_that_never_moves_gives_no_amplitude():
    t = np.arange(0.0, 5.0, 1e-3)
    flat = np.full(t.size, 0.5)
    result = sweep_amplitudes(t, flat, np.vstack([flat, flat]))
    assert np.all(np.isnan(result.measured_n)) and result.model_n.shape[0] == 1


@pytest.mark.parametrize("delay_s", [0.0, 0.05])
def test_a_pure_delay_leaves_the_amplitude_alone(delay_s):
    t, throttle, phase, _ = _chirp()
    shift = int(round(delay_s * 1000))
    force = 30 * throttle
    delayed = np.concatenate([np.full(shift, force[0]), force[: force.size - shift]])
    result = sweep_amplitudes(t, throttle, np.vstack([force, delayed]))
    reached = np.isfinite(result.measured_n)
    np.testing.assert_allclose(result.error[0][reached], 0.0, atol=0.03)
