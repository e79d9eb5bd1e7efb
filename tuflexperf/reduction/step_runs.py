"""Throttle-step and sweep runs reduced one at a time (steps 4-6 of :mod:`.pipeline`).

A step run is cleaned (outliers filled, moving median), cut at the force's change points
cross-checked against the logged throttle steps, and averaged over its steady segments
into test points; each run's validation error is the fitted model against its own force.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.io.campaign import Campaign, CampaignRun
from tuflexperf.io.runs import (
    Run,
    format_number,
)
from tuflexperf.reduction.changepoints import cross_check, force_changepoints, throttle_plateaus
from tuflexperf.reduction.delay import DelayEstimate
from tuflexperf.reduction.filters import filloutliers_movmean, movmedian, window_samples
from tuflexperf.reduction.segments import (
    MIN_STEADY_SHARE,
    SteadyMean,
    fit_transients,
    steady_means,
)

Progress = Callable[[int, int, str], None]
"""``progress(done, total, label)``: called before each run is reduced."""

MIN_SEGMENT_S = 0.5


@dataclass
class Point:
    """One steady segment turned into a thrust-table row."""

    engine: str
    run: str
    throttle: float
    airspeed_measured_m_s: float
    force_n: float
    drag_n: float
    force_std_n: float
    n_samples: int
    glauert_ratio: float
    airspeed_m_s: float = 0.0  # the airspeed the fit uses (corrected with --glauert)
    thrust_n: float = 0.0  # what the fit uses: at the reference voltage when one is fitted
    thrust_at_voltage_n: float = math.nan  # as measured, at the point's pack voltage
    voltage_v: float = math.nan
    current_a: float = math.nan
    electrical_power_w: float = math.nan
    ideal_power_w: float = math.nan  # momentum theory (SPEC 3), thrusting points
    figure_of_merit: float = math.nan
    overall_efficiency: float = math.nan
    hold_variance_n2: float = math.nan  # of force_n, from inside the hold [N^2]
    hold_dof: int = 0  # its degrees of freedom


@dataclass
class StepRunResult:
    """One throttle-step run reduced: its steady segments and the whole-run cleaning.

    ``cleaned_force_n`` (outliers filled, moving median) and ``changepoints`` are kept
    so that the report draws the run as reduced, without reducing it again.
    """

    run: CampaignRun
    data: Run
    segments: list[SteadyMean]
    report: dict[str, Any]
    cleaned_force_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    changepoints: tuple[int, ...] = ()
    outliers_replaced: int = 0


@dataclass(frozen=True)
class SweepRunResult:
    """One sine-sweep run with its fitted dead time and spool lag."""

    run: CampaignRun
    data: Run
    estimate: DelayEstimate


# --- run reduction --------------------------------------------------------------------------
def filter_windows(campaign: Campaign, sample_rate_hz: float) -> tuple[int, float, int]:
    f = campaign.filters
    return (
        window_samples(f.outlier_window_s, sample_rate_hz),
        f.outlier_threshold,
        window_samples(f.median_window_s, sample_rate_hz),
    )


def clean_run(campaign: Campaign, run: Run, column: str = "force_n") -> tuple[np.ndarray, int]:
    """The paper's filters over a whole run: outliers filled, then the moving median.

    Returns the cleaned column and how many outliers were replaced.
    """
    k_out, threshold, k_med = filter_windows(campaign, run.sample_rate_hz)
    filled, replaced = filloutliers_movmean(run[column], k_out, threshold)
    return movmedian(filled, k_med), replaced


def run_header(run: CampaignRun, data: Run) -> dict[str, Any]:
    return {
        "file": run.file,
        "engine": run.engine,
        "kind": run.kind,
        "sample_rate_hz": data.sample_rate_hz,
        "n_samples": data.n_samples,
        "duration_s": data.duration_s,
        "nan_samples": dict(data.nan_samples),
        "warnings": list(data.warnings),
    }


def reduce_step_run(
    campaign: Campaign, run: CampaignRun, data: Run, delay_s: float
) -> StepRunResult:
    """Steady segment means of one throttle-step run (module docstring, step 4)."""
    fs = data.sample_rate_hz
    t = data.time_s
    k_out, threshold, k_med = filter_windows(campaign, fs)
    report = run_header(run, data)
    warnings: list[str] = report["warnings"]

    plateaus = throttle_plateaus(data["throttle"], fs, min_duration_s=MIN_SEGMENT_S)
    ramps = [p for p in plateaus if not p.steady]
    for p in ramps:
        warnings.append(
            f"throttle not steady over {t[p.start]:.2f}-{t[p.stop - 1]:.2f} s "
            f"(drifts by more than 2 %): segment skipped"
        )
    plateaus = [p for p in plateaus if p.steady]
    delay = window_samples(delay_s, fs) if delay_s > 0 else 0
    onsets = [
        min(p.start + delay if p.step_index is None else p.step_index + delay, p.stop - 1)
        for p in plateaus
    ]
    onsets = [max(o, p.start) for o, p in zip(onsets, plateaus, strict=True)]
    # one whole-run cleaning serves the spool-lag fit and the change-point cross-check
    cleaned, replaced = clean_run(campaign, data)
    transients = fit_transients(t, cleaned, onsets, [p.stop for p in plateaus], fs)

    spans: list[tuple[int, int]] = []
    settle_samples: list[int] = []
    for p, onset, settle_s in zip(plateaus, onsets, transients.settle_s, strict=True):
        settle = int(math.ceil(settle_s * fs))
        latest = p.stop - max(int(MIN_STEADY_SHARE * (p.stop - onset)), 1)
        start = min(onset + settle, latest)
        if onset + settle > latest:
            warnings.append(
                f"step at {t[onset]:.2f} s not settled within its plateau "
                f"(needs {settle_s:.2f} s): kept its last {MIN_STEADY_SHARE:.0%}"
            )
        settle_samples.append(start - onset)
        if p.stop - start < 3:
            warnings.append(f"plateau at {t[p.start]:.2f} s too short after the transient: skipped")
            continue
        spans.append((start, p.stop))
    segments = steady_means(
        data["force_n"], data["airspeed_m_s"], data["throttle"], spans, k_out, threshold, k_med
    )

    changes = force_changepoints(cleaned, fs, min_segment_s=MIN_SEGMENT_S)
    steps = [
        (p.step_index, s)
        for p, s in zip(plateaus, settle_samples, strict=True)
        if p.step_index is not None
    ]
    # A smooth transition of a few tenths of a second is best cut by the l2 detector
    # into an intermediate segment of at least MIN_SEGMENT_S, whose first change may
    # come that long (plus the refinement's half segment) before the step.
    margin = window_samples(1.5 * MIN_SEGMENT_S, fs)
    # the paper's outlier fill is blind within half its window of a step (the step inflates
    # the local spread): what it lets through there shows as changes 0.85-0.94 s before the
    # shipped runs' steps, not changes without a step; a real change that
    # close to a step cannot be told from them and is not said
    ahead = max(margin, k_out // 2)
    check = cross_check(
        [s for s, _ in steps],
        changes,
        before=ahead,
        after=[delay + settle + margin for _, settle in steps],
        expected_lag=delay,
    )
    for change in check.changes_without_step:
        warnings.append(f"force changes at {t[change]:.2f} s without a throttle step")
    report.update(
        {
            "outliers_replaced": replaced,
            "segments": len(segments),
            "spool_lag_s": transients.tau_s,
            "changepoints": {
                "force_changes": len(changes),
                "throttle_steps": len(steps),
                "matched_steps": len(check.matched),
                "force_lag_after_step_s": [
                    float(t[c] - t[s]) for s, c in sorted(check.matched.items())
                ],
                "steps_without_change_s": [float(t[s]) for s in check.steps_without_change],
                "changes_without_step_s": [float(t[c]) for c in check.changes_without_step],
            },
        }
    )
    return StepRunResult(
        run=run,
        data=data,
        segments=segments,
        report=report,
        cleaned_force_n=cleaned,
        changepoints=tuple(int(c) for c in changes),
        outliers_replaced=replaced,
    )


def mean_or_none(values: list[float]) -> float | None:
    return float(np.mean(values)) if values else None


def rounded(value: float) -> float:
    return float(format_number(float(value)))


# --- rendering --------------------------------------------------------------------------------
def finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None
