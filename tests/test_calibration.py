"""The self-calibration statistics (coverage, z, reliability) and a small study of their own.

The whole study is bench/calibration_study.py (minutes a truth); here the same statistics
on cases whose answer is known: calibrated normal bands, bands too narrow or off-centre,
and the sampler's own bands on a mass-only take-off whose truths are drawn from the very
distribution the sampler draws from (a calibrated forecast by construction).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis.calibration import (
    BAND_WIDTH_SD,
    coverage,
    probability_met,
    reliability,
)
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.analysis.uncertainty import plan_for, quantiles, run_samples
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values


def _normal_bands(n: int, width_factor: float, shift: float, seed: int = 1):
    """``n`` truths ~ N(mu, 1) each with its forecast N(mu, 1): p05/p50/p95 of a band whose
    sd is ``width_factor`` and whose centre is off by ``shift`` sd."""
    rng = np.random.default_rng(seed)
    mu = rng.normal(0.0, 5.0, n)
    truth = mu + rng.standard_normal(n)
    centre = mu + shift
    half = 1.645 * width_factor
    return truth, centre - half, centre, centre + half


def test_a_calibrated_band_covers_ninety_percent_with_rms_z_one() -> None:
    result = coverage(*_normal_bands(4000, 1.0, 0.0))
    low, high = result.coverage_ci
    assert low <= 0.90 <= high
    assert result.rms_z == pytest.approx(1.0, abs=0.05)
    assert abs(result.bias_z) < 0.06
    assert result.covered + result.above + result.below == result.n == 4000


@pytest.mark.parametrize(("width", "shift", "rms"), [(0.5, 0.0, 2.0), (1.0, 1.0, math.sqrt(2.0)),
                                                     (2.0, 0.0, 0.5)])
def test_a_band_too_narrow_off_centre_or_too_wide_is_found(width, shift, rms) -> None:
    result = coverage(*_normal_bands(4000, width, shift))
    low, high = result.coverage_ci
    assert not low <= 0.90 <= high
    assert result.rms_z == pytest.approx(rms, rel=0.06)
    assert result.bias_z == pytest.approx(-shift / width, abs=0.06)


def test_not_attainable_truths_and_bands_are_left_out() -> None:
    result = coverage([1.0, math.nan, 2.0], [0.0, 0.0, math.nan], [1.0, 1.0, 1.0], [2.0, 2.0, 3.0])
    assert result.n == 1 and result.covered == 1 and result.rms_z == 0.0


def test_a_band_open_on_its_unattainable_side_still_bounds_the_truth() -> None:
    """p95 not attainable (+inf for a "max" requirement): a truth above p05 is covered and
    its z takes the lower half band, doubled, as the width; one below p05 is not covered."""
    result = coverage([3.0, -1.0], [0.0, 0.0], [1.0, 1.0], [math.inf, math.inf])
    assert result.n == 2 and result.covered == 1 and result.below == 1
    half = 2 * 1.0 / BAND_WIDTH_SD
    assert result.bias_z == pytest.approx(((3 - 1) / half + (-1 - 1) / half) / 2)
    low = coverage([0.5], [-math.inf], [1.0], [2.0])  # p05 not attainable ("min")
    assert low.covered == 1 and low.rms_z == pytest.approx(0.5 / (2.0 / BAND_WIDTH_SD))


def test_reliability_bins_hold_their_forecasts() -> None:
    """Events drawn with the forecast probability: each bin's fraction met within its CI."""
    rng = np.random.default_rng(3)
    p = rng.uniform(0.0, 1.0, 5000)
    met = rng.uniform(0.0, 1.0, 5000) < p
    rows = reliability(p, met)
    assert [r.n for r in rows] == [int(np.sum((p >= k / 5) & (p < (k + 1) / 5))) for k in range(5)]
    for row in rows:
        assert row.met_ci[0] <= row.mean_probability <= row.met_ci[1]
    # a forecast that says 0.9 where the truth meets half the time is found out
    bad = reliability(np.full(400, 0.9), rng.uniform(size=400) < 0.5)
    assert bad[4].met_ci[1] < 0.8 and bad[0].n == 0


def test_probability_met_counts_not_attainable_as_not_met() -> None:
    values = np.array([1.0, 2.0, np.nan, 4.0])
    assert probability_met(values, 2.0, "max") == 0.5
    assert probability_met(values, 2.0, "min") == 0.5


def test_the_samplers_bands_cover_truths_drawn_as_it_draws(tmp_path) -> None:
    """A small study: the take-off of the shipped aircraft with an uncertain mass (the thrust
    model's sources off). Each truth is the single-case roll at a mass drawn from the same
    N(27.5, 0.8) kg: the sampler's p05-p95 must hold 90 % of them and P(meet) must mean it."""
    data = yaml.safe_load(SHIPPED_CASE.read_text())
    for key in ("aircraft", "propulsion", "battery"):
        data[key] = str((SHIPPED_CASE.parent / data[key]).resolve())
    data["requirements"] = {"takeoff": {"max_ground_roll_m": 60}}
    data["uncertainty"] = {"samples": 5000, "seed": 4, "propulsion": {
        "covariance": False, "extrapolation": False, "model_form": False, "rig": False,
        "power_model": False, "battery_fit": False},
        "parameters": {"aircraft.mass_kg": {"normal": [27.5, 0.8]}}}
    path = tmp_path / "mass.yaml"
    path.write_text(yaml.safe_dump(data))
    case = load_case(path)
    values = run_samples(case, plan_for(case)).values["takeoff_ground_roll"]
    p05, p50, p95 = quantiles(values, "max")
    masses = np.random.default_rng(11).normal(27.5, 0.8, 60)
    truths = [solve_takeoff(with_values(case, {"aircraft.mass_kg": float(m)})).ground_roll_m
              for m in masses]
    result = coverage(truths, [p05] * 60, [p50] * 60, [p95] * 60)
    low, high = result.coverage_ci
    assert low <= 0.90 <= high, result
    assert 0.7 < result.rms_z < 1.3, result
    # P(meet) at the median: about half the truths meet it
    limit = float(p50)
    p = probability_met(values, limit, "max")
    met = [t <= limit for t in truths]
    assert p == pytest.approx(0.5, abs=0.02)
    assert 0.3 < np.mean(met) < 0.7
