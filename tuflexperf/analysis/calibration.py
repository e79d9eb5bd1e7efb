"""How well a set of Monte Carlo bands held their truths: coverage, z and reliability.

Used by the self-calibration study (``bench/calibration_study.py``, docs/validation.md): for
each truth of a requirement, the sampled band ``p05-p95`` and ``p50``; for the reliability
diagram, the sampled ``P(meet)`` at a limit and whether the truth met it.

- coverage: the fraction of truths within ``[p05, p95]`` (a 90 % band should hold 0.90),
  with its exact binomial (Clopper-Pearson) 95 % interval;
- ``z = (truth - p50) / ((p95 - p05) / 3.29)``: a normal band's width is 3.29 sd, so a
  calibrated band gives RMS z 1 and mean z ("bias", in band sds) 0;
- reliability: ``P(meet)`` in 5 equal bins against the fraction of those truths that met.

References
----------
Clopper & Pearson (1934), Biometrika 26, 404-413; Gneiting, Balabdaoui & Raftery (2007),
"Probabilistic forecasts, calibration and sharpness", JRSS B 69 (coverage, reliability).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.probability import clopper_pearson

BAND_WIDTH_SD = 3.29
"""``p95 - p05`` of a normal distribution in its standard deviations (2 x 1.645)."""
RELIABILITY_BINS = 5


@dataclass(frozen=True)
class Coverage:
    """One requirement's calibration over ``n`` truths (NaN where not defined)."""

    n: int
    covered: int
    coverage: float
    coverage_ci: tuple[float, float]
    rms_z: float
    bias_z: float
    above: int  # truths above p95
    below: int  # truths below p05

    def to_dict(self) -> dict[str, Any]:
        return {"n": self.n, "covered": self.covered, "coverage": self.coverage,
                "coverage_ci": list(self.coverage_ci), "rms_z": self.rms_z,
                "bias_z": self.bias_z, "above_p95": self.above, "below_p05": self.below}


def coverage(truth: Sequence[float], p05: Sequence[float], p50: Sequence[float],
             p95: Sequence[float], confidence: float = 0.95) -> Coverage:
    """Coverage of ``[p05, p95]``, its Clopper-Pearson interval, RMS z and mean z.

    A truth or median that is not finite (not attainable), or a band bound that is NaN, is
    left out of every statistic. A bound at infinity (more than 5 % of the samples not
    attainable on that side) still bounds the band: a finite truth beyond the other bound
    is covered, and z takes the finite half of the band, doubled, as its width. A band of
    zero width gives an infinite z unless the truth is on it.
    """
    t, lo, mid, hi = (np.asarray(a, dtype=float) for a in (truth, p05, p50, p95))
    ok = np.isfinite(t) & np.isfinite(mid) & ~np.isnan(lo) & ~np.isnan(hi) \
        & (np.isfinite(lo) | np.isfinite(hi))
    t, lo, mid, hi = t[ok], lo[ok], mid[ok], hi[ok]
    n = int(t.size)
    inside = (t >= lo) & (t <= hi)
    covered = int(np.count_nonzero(inside))
    width = np.where(np.isfinite(hi) & np.isfinite(lo), hi - lo,
                     2.0 * np.where(np.isfinite(lo), mid - lo, hi - mid))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(t == mid, 0.0, (t - mid) / (width / BAND_WIDTH_SD))
    rms = float(np.sqrt(np.mean(z * z))) if n else math.nan
    bias = float(np.mean(z)) if n else math.nan
    return Coverage(n, covered, covered / n if n else math.nan,
                    clopper_pearson(covered, n, confidence), rms, bias,
                    int(np.count_nonzero(t > hi)), int(np.count_nonzero(t < lo)))


@dataclass(frozen=True)
class ReliabilityBin:
    """Forecasts with ``low <= P(meet) < high``: their mean and how often the truth met."""

    low: float
    high: float
    n: int
    mean_probability: float
    met_fraction: float
    met_ci: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return {"low": self.low, "high": self.high, "n": self.n,
                "mean_probability": self.mean_probability, "met_fraction": self.met_fraction,
                "met_ci": list(self.met_ci)}


def reliability(probability: Sequence[float], met: Sequence[bool],
                bins: int = RELIABILITY_BINS) -> list[ReliabilityBin]:
    """The reliability diagram's rows: ``P(meet)`` in ``bins`` equal bins of [0, 1] (the
    last closed), each with its forecasts' mean and the fraction met (Clopper-Pearson CI)."""
    p = np.asarray(probability, dtype=float)
    hit = np.asarray(met, dtype=bool)
    index = np.minimum((p * bins).astype(int), bins - 1)
    rows = []
    for k in range(bins):
        inside = index == k
        n = int(np.count_nonzero(inside))
        hits = int(np.count_nonzero(hit[inside]))
        rows.append(ReliabilityBin(k / bins, (k + 1) / bins, n,
                                   float(np.mean(p[inside])) if n else math.nan,
                                   hits / n if n else math.nan, clopper_pearson(hits, n)))
    return rows


def probability_met(values: np.ndarray, limit: float, kind: str) -> float:
    """The fraction of samples meeting ``limit`` (``kind`` "max": value <= limit); a sample
    that is not attainable (NaN) does not meet it, as ``check`` counts it."""
    values = np.asarray(values, dtype=float)
    with np.errstate(invalid="ignore"):
        met = values <= limit if kind == "max" else values >= limit
    return float(np.count_nonzero(met & np.isfinite(values)) / max(values.size, 1))
