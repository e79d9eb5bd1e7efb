"""``tuflexperf fit``: campaign manifest or thrust table -> propulsion file (paper section 4).

Campaign path, in the paper's order:

1. read every run (CSV, gzip CSV or .mat; a few NaN samples repaired and reported);
2. sine sweeps -> dead time and spool lag per run (:mod:`.delay`), one mean delay;
3. bare-structure velocity sweeps -> structure drag ``D(V)`` (:mod:`.drag`);
4. throttle-step runs -> outliers filled (2 s moving mean, 1.5 local standard
   deviations), moving median, change points in the force cross-checked against
   the logged throttle steps, transients left out, steady segment means
   (:mod:`.filters`, :mod:`.changepoints`, :mod:`.segments`);
5. thrust = force + D(V); Glauert blockage ratio per point (:mod:`.glauert`),
   applied to the airspeed only when asked;
6. poly22 per engine by ordinary least squares (:mod:`.poly22fit`), and each run's
   validation error: the model (minus structure drag) against the measured force
   over the run's steady segments, as mean negative / mean positive error;
7. where the step runs log ``voltage_v`` and ``current_a`` (:mod:`.power`): the voltage
   exponent (thrust brought to the reference voltage before step 6 when the runs determine
   it), the electrical power surface per engine, and the windmilling drag coefficient
   from the zero-throttle points.

Outputs are rendered in memory, the propulsion file is validated against the
schema ``check`` uses, and only then are files written, atomically.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tuflexperf.errors import InputError
from tuflexperf.io.campaign import Campaign, CampaignRun, load_campaign
from tuflexperf.io.files import FIT_PROPULSION_HEADER, sealed, sha256_of
from tuflexperf.io.runs import (
    REFIT_TABLE_EXTRA_COLUMNS,
    TABLE_EXTRA_COLUMNS,
    Run,
    ThrustTable,
    format_number,
    read_run,
    read_thrust_table,
    render_thrust_table,
)
from tuflexperf.models.thrust import DEFAULT_VOLTAGE_EXPONENT, POLY22_TERMS
from tuflexperf.reduction.changepoints import cross_check, force_changepoints, throttle_plateaus
from tuflexperf.reduction.delay import MAX_DELAY_S, DelayEstimate, estimate_delay
from tuflexperf.reduction.drag import DragModel, fit_structure_drag
from tuflexperf.reduction.filters import filloutliers_movmean, movmedian, window_samples
from tuflexperf.reduction.glauert import glauert_ratio
from tuflexperf.reduction.poly22fit import Poly22Fit, fit_poly22
from tuflexperf.reduction.power import (
    VoltageFit,
    WindmillingFit,
    fit_power_surface,
    fit_voltage_exponent,
    fit_windmilling,
)
from tuflexperf.reduction.segments import (
    MIN_STEADY_SHARE,
    SteadyMean,
    TestPoint,
    fit_transients,
    merge_test_points,
    steady_means,
)

Progress = Callable[[int, int, str], None]
"""``progress(done, total, label)``: called before each run is reduced."""

MIN_SEGMENT_S = 0.5
# A sine sweep whose delay-and-lag model explains less of the force than this measured no
# response (noise alone fits R^2 ~0.01; very noisy real sweeps 0.26 still gave the delay
# to 2 ms; the shipped ones 0.999)
MIN_SWEEP_R2 = 0.1
# A thrust surface that explains less of its points than this is no fan's (the paper's
# 0.9968; a run with its force sign flipped gave 0.43 and was written: outside audit); below
# POOR_POLY22_R2 it is said (a small fan's noisy table gave 0.89 and is a fit)
MIN_POLY22_R2 = 0.5
POOR_POLY22_R2 = 0.9
# Sweeps of one rig further apart than this in their delay say one of them is off (the
# shipped campaign's agree to 0.2 ms; a sweep logged with a tenth of its time base came out
# 45 ms off and passed the earlier 0.05 s unseen: outside audit)
MAX_DELAY_SPREAD_S = 0.01
# Engines' delays further apart than this (the paper's whole delay, 0.05 s) get one mean
# delay_s that fits neither engine
MAX_DELAY_ENGINES_APART_S = 0.05
ELECTRICAL_COLUMNS = ("voltage_v", "current_a")


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


@dataclass
class FitResult:
    """Everything ``fit`` found: the JSON summary and the rendered output files."""

    summary: dict[str, Any]
    propulsion_text: str
    table_text: str | None
    engines: dict[str, Poly22Fit] = field(default_factory=dict)
    power: dict[str, Poly22Fit] = field(default_factory=dict)
    step_runs: list[StepRunResult] = field(default_factory=list)
    sweep_runs: list[SweepRunResult] = field(default_factory=list)


# --- run reduction --------------------------------------------------------------------------
def _windows(campaign: Campaign, sample_rate_hz: float) -> tuple[int, float, int]:
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
    k_out, threshold, k_med = _windows(campaign, run.sample_rate_hz)
    filled, replaced = filloutliers_movmean(run[column], k_out, threshold)
    return movmedian(filled, k_med), replaced


def _run_header(run: CampaignRun, data: Run) -> dict[str, Any]:
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
    k_out, threshold, k_med = _windows(campaign, fs)
    report = _run_header(run, data)
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
    # the local spread): what it lets through there showed as changes 0.85-0.94 s before the
    # shipped runs' steps, each noted as a change without a step (audit); a real change that
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


def _mean_or_none(values: list[float]) -> float | None:
    return float(np.mean(values)) if values else None


def _validation(
    result: StepRunResult,
    fit: Poly22Fit,
    drag: DragModel | None,
    ratios: list[float],
    glauert: bool,
    electrical: ElectricalFits | None = None,
) -> dict[str, Any]:
    """Model minus measured force over a run's steady segments (paper Fig. 16/17).

    The model sees the airspeed the fit used (Glauert-corrected with ``--glauert``) and,
    with a reference voltage, the logged pack voltage (the exponent the fit brought the
    thrust to it with); the structure drag is the measured airspeed's.
    """
    exponent = electrical.exponent if electrical is not None else None
    errors = []
    for segment, ratio in zip(result.segments, ratios, strict=True):
        v = result.data["airspeed_m_s"][segment.start : segment.stop]
        v_model = v * ratio if glauert and math.isfinite(ratio) else v
        model = fit.predict(np.full(v.size, segment.throttle), v_model)
        if exponent is not None and electrical is not None:
            u = result.data["voltage_v"][segment.start : segment.stop]
            model = model * (u / electrical.reference_voltage_v) ** exponent
        if drag is not None:
            model = model - drag.drag_n(v)
        errors.append(model - segment.filtered_force_n)
    if not errors:
        return {"mean_negative_error_n": None, "mean_positive_error_n": None, "rms_error_n": None}
    e = np.concatenate(errors)
    below, above = e[e < 0], e[e > 0]
    return {
        "mean_negative_error_n": float(below.mean()) if below.size else None,
        "mean_positive_error_n": float(above.mean()) if above.size else None,
        "mean_error_n": float(e.mean()),
        "rms_error_n": float(np.sqrt(np.mean(e * e))),
    }


# --- campaign ---------------------------------------------------------------------------------
MIN_SWEEP_THROTTLE_SWING = 0.05  # a sweep whose throttle barely moves measures no delay
MIN_DRAG_SWEEP_AIRSPEED_M_S = 1.0  # a drag sweep that never blows measures no drag
MIN_DRAG_SWEEP_SPAN_M_S = 5.0  # ... and one that holds one airspeed measures no curve
SET_POINT_RESOLUTION_M_S = 0.5  # tunnel set points closer than this are one set point
MIN_SET_POINTS = 3  # airspeeds a poly22 surface (quadratic in airspeed) needs


def _check_set_points(campaign: Any, step_results: list[Any]) -> list[str]:
    """Bad input: an engine whose step runs cover fewer than 3 airspeed set points; and a
    note per set point an engine has two or more runs at (repeats are fitted together; a run
    labelled with the wrong engine looks the same, and only the user can tell).

    Counted from each run's median airspeed rounded to the set-point resolution, not from
    the measured values (their noise makes any two runs look like many airspeeds and
    defeats the rank test of the fit).
    """
    by_engine: dict[str, dict[float, list[str]]] = {}
    empty: dict[str, list[str]] = {}
    for result in step_results:
        runs = by_engine.setdefault(str(result.run.engine), {})
        speeds = [seg.airspeed_m_s for seg in result.segments]
        if not speeds:  # no test point: no airspeed either (it counted as 0 m/s: audit)
            empty.setdefault(str(result.run.engine), []).append(result.run.file)
            continue
        runs.setdefault(_set_point(float(np.median(speeds))), []).append(result.run.file)
    for engine, points in by_engine.items():
        if len(points) < MIN_SET_POINTS:
            listed = "; ".join(f"{v:g} m/s ({', '.join(files)})" for v, files in
                               sorted(points.items()))
            without = empty.get(engine, [])
            raise InputError(
                f"{campaign.path}: {engine}: the throttle-step runs cover only {len(points)} "
                f"airspeed set point(s){', ' + listed if listed else ''}; a poly22 surface "
                f"needs at least {MIN_SET_POINTS}"
                + (f" ({', '.join(without)} gave no test point)" if without else "")
            )
    return [
        f"{engine}: {len(files)} throttle-step runs at {v:g} m/s ({', '.join(files)}): fitted "
        "together as repeats; is one another engine's?"
        for engine, points in by_engine.items() for v, files in sorted(points.items())
        if len(files) > 1
    ]


def _set_point(airspeed_m_s: float) -> float:
    """The tunnel set point [m/s] an airspeed belongs to (:data:`SET_POINT_RESOLUTION_M_S`)."""
    return round(airspeed_m_s / SET_POINT_RESOLUTION_M_S) * SET_POINT_RESOLUTION_M_S


def fit_campaign(
    manifest: Path | str,
    glauert: bool = False,
    delay_s: float | None = None,
    progress: Progress | None = None,
) -> FitResult:
    """Reduce a campaign and fit the poly22 per engine (module docstring)."""
    campaign = load_campaign(Path(manifest))
    if glauert and campaign.tunnel_area_m2 is None:
        raise InputError(f"--glauert: {campaign.path}: tunnel_area_m2 is not given (a static "
                         "stand has no tunnel walls to correct for)")
    pool = ThreadPoolExecutor(max_workers=_workers(), thread_name_prefix="tuflexperf-fit")
    try:
        # every run is read, and each sweep reduced, as soon as a worker is free; the results
        # are taken in the manifest's order, so reports, warnings and errors come as before
        sine = [(run, pool.submit(_sine_sweep, run)) for run in campaign.of_kind("sine_sweep")]
        bare = [(run, pool.submit(_drag_sweep, campaign, run))
                for run in campaign.of_kind("drag_sweep")]
        reads = [(run, pool.submit(read_run, run.path, vendor=run.vendor))
                 for run in campaign.of_kind("throttle_steps")]
        return _fit_campaign(campaign, glauert, delay_s, progress, pool, sine, bare, reads)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _workers() -> int:
    """Threads that read and reduce runs: one per core, at most 4 (numpy, Bottleneck, SciPy's
    filters, zlib and pandas' parser release the GIL; past a few the GIL holds them back)."""
    return max(1, min(4, os.cpu_count() or 1))


def _sine_sweep(run: CampaignRun) -> tuple[Run, DelayEstimate | None]:
    """Read a sine-sweep run and fit its delay (None when its throttle barely moves)."""
    data = read_run(run.path, vendor=run.vendor)
    if float(np.ptp(data["throttle"])) < MIN_SWEEP_THROTTLE_SWING:
        return data, None
    return data, estimate_delay(data.time_s, data["throttle"], data["force_n"],
                                data.sample_rate_hz)


@dataclass(frozen=True)
class _DragSweep:
    """A drag-sweep run read and, unless it measures no drag, cleaned."""

    data: Run
    report: dict[str, Any]
    problem: str = ""  # why it gives no drag curve ("" when it gives one)
    curve: tuple[np.ndarray, np.ndarray] | None = None  # airspeed [m/s], force [N] cleaned


def _drag_sweep(campaign: Campaign, run: CampaignRun) -> _DragSweep:
    """Read and clean one bare-structure velocity sweep (module docstring, step 3)."""
    data = read_run(run.path, vendor=run.vendor)
    top = float(np.max(data["airspeed_m_s"]))
    if top < MIN_DRAG_SWEEP_AIRSPEED_M_S:
        return _DragSweep(
            data, {**_run_header(run, data), "wind": "none"},
            f"{run.file}: drag sweep without wind (airspeed at most {top:.2f} m/s): no "
            "structure drag measured, none added",
        )
    span = top - float(np.min(data["airspeed_m_s"]))
    if span < MIN_DRAG_SWEEP_SPAN_M_S:  # one airspeed: a curve in V^2 is not determined
        return _DragSweep(
            data, {**_run_header(run, data), "wind": "one airspeed"},
            f"{run.file}: drag sweep over {span:.2f} m/s of airspeed only (needs "
            f">= {MIN_DRAG_SWEEP_SPAN_M_S:g}): no drag curve from it, left out",
        )
    if float(np.ptp(data["force_n"])) <= DEAD_LOAD_CELL_N:
        # the same force at every airspeed: "D = 0 (R^2 nan)" was added to every point
        # unremarked (outside audit)
        return _DragSweep(
            data, {**_run_header(run, data), "force": "constant"},
            f"{run.file}: drag sweep whose force is {float(data['force_n'][0]):.4g} N "
            "throughout (a dead load cell?): no structure drag measured, none added",
        )
    force, replaced = clean_run(campaign, data)
    _, _, k_med = _windows(campaign, data.sample_rate_hz)
    return _DragSweep(
        data, {**_run_header(run, data), "outliers_replaced": replaced},
        curve=(movmedian(data["airspeed_m_s"], k_med), force),
    )


_Cell = tuple[TestPoint, tuple[float, float, float]]
"""A run's test point with its mean pack voltage [V], current [A] and ``U I`` [W]."""


def _fit_campaign(
    campaign: Campaign,
    glauert: bool,
    delay_s: float | None,
    progress: Progress | None,
    pool: ThreadPoolExecutor,
    sine: list[tuple[CampaignRun, Future[tuple[Run, DelayEstimate | None]]]],
    bare: list[tuple[CampaignRun, Future[_DragSweep]]],
    reads: list[tuple[CampaignRun, Future[Run]]],
) -> FitResult:
    """:func:`fit_campaign` on runs that ``pool`` reads (and sweeps it reduces) meanwhile."""
    total = len(campaign.runs)
    done = 0

    def tick(label: str) -> None:
        nonlocal done
        if progress is not None:
            progress(done, total, label)
        done += 1

    run_reports: list[dict[str, Any]] = []
    delay_runs: list[dict[str, Any]] = []
    degenerate: list[str] = []  # runs that carry no information, named (issue 10)
    sweep_results: list[SweepRunResult] = []
    for run, future in sine:
        tick(run.file)
        data, estimate = future.result()
        if estimate is None:
            swing = float(np.ptp(data["throttle"]))
            degenerate.append(
                f"{run.file}: sine sweep without excitation (throttle swings {swing:.3f}, "
                f"needs >= {MIN_SWEEP_THROTTLE_SWING}): left out of the delay"
            )
            run_reports.append({**_run_header(run, data), "excitation": "none"})
            continue
        if not estimate.r2 >= MIN_SWEEP_R2:  # noise fits some delay too: it measures nothing
            degenerate.append(
                f"{run.file}: the force does not follow the sine sweep (fit R^2 "
                f"{estimate.r2:.2f} < {MIN_SWEEP_R2:g}): left out of the delay"
            )
            run_reports.append({**_run_header(run, data), "response": "none",
                                "fit_r2": estimate.r2})
            continue
        sweep_results.append(SweepRunResult(run, data, estimate))
        delay_runs.append(
            {
                "file": run.file,
                "engine": run.engine,
                "delay_s": estimate.delay_s,
                "lag_s": estimate.lag_s,
                "r2": estimate.r2,
                "xcorr_lag_s": estimate.xcorr_lag_s,
            }
        )
        run_reports.append(
            {
                **_run_header(run, data),
                "delay_s": estimate.delay_s,
                "spool_lag_s": estimate.lag_s,
                "fit_r2": estimate.r2,
            }
        )
    measured_delay = _mean_or_none([d["delay_s"] for d in delay_runs])
    per_engine: dict[str, float] = {}
    for engine in sorted({str(d["engine"]) for d in delay_runs}):
        # one engine's sweeps measure one ESC: two engines may well differ
        spread = [d["delay_s"] for d in delay_runs if str(d["engine"]) == engine]
        per_engine[engine] = float(np.mean(spread))
        if max(spread) - min(spread) > MAX_DELAY_SPREAD_S:
            degenerate.append(
                f"{engine}: its sine sweeps disagree on the delay: {min(spread):.3f}-"
                f"{max(spread):.3f} s (more than {MAX_DELAY_SPREAD_S:g} s apart): is a run's "
                "time base shifted?"
            )
    if per_engine and max(per_engine.values()) - min(per_engine.values()) > \
            MAX_DELAY_ENGINES_APART_S:
        # the model has one delay_s, their mean: two ESCs 10x apart got one that fits neither,
        # unsaid (outside audit)
        named = ", ".join(f"{e} {v:.3f} s" for e, v in per_engine.items())
        degenerate.append(
            f"the engines disagree on the delay ({named}, more than "
            f"{MAX_DELAY_ENGINES_APART_S:g} s apart): the model's one delay_s is their mean "
            f"{measured_delay:.3f} s, which fits neither; is a run's time base off?"
        )
    # the spool lag after the dead time (issue 15): the sweeps' mean, written as lag_s
    measured_lag = _mean_or_none([d["lag_s"] for d in delay_runs])
    delay = delay_s if delay_s is not None else measured_delay
    # where the steady part of a step starts: the engine's own sweeps if it has any
    onset_delay = {
        str(engine): delay_s
        if delay_s is not None
        else _mean_or_none([d["delay_s"] for d in delay_runs if d["engine"] == engine])
        for engine in {r.engine for r in campaign.runs}
    }

    drag: DragModel | None = None
    sweeps = []
    for run, bare_future in bare:
        tick(run.file)
        swept = bare_future.result()
        run_reports.append(swept.report)
        if swept.curve is None:
            degenerate.append(swept.problem)
            continue
        sweeps.append(swept.curve)
    if sweeps:
        drag = fit_structure_drag(sweeps)

    def reduce(run: CampaignRun, read: Future[Run]) -> tuple[StepRunResult, list[_Cell]]:
        onset = onset_delay.get(str(run.engine)) or delay or 0.0
        result = reduce_step_run(campaign, run, read.result(), max(onset, 0.0))
        # the run's test points and their pack voltage and current, while on the worker
        return result, [(cell, _electrical(result, cell.members))
                        for cell in merge_test_points(result.segments)]

    # queued behind every read: a worker waits at most on a read another one is doing
    reduced = [(run, pool.submit(reduce, run, read)) for run, read in reads]
    digests = [(r, pool.submit(sha256_of, r.path)) for r in campaign.runs]  # for the source
    step_results: list[StepRunResult] = []
    cells_of: list[list[_Cell]] = []
    for run, step_future in reduced:
        tick(run.file)
        result, cells = step_future.result()
        cells_of.append(cells)
        data = result.data
        if not result.segments:  # e.g. 50 rows, or time stamps in microseconds
            degenerate.append(
                f"{run.file}: no steady throttle plateau of at least {MIN_SEGMENT_S:g} s "
                f"({data.time_s[-1] - data.time_s[0]:.3g} s logged at "
                f"{data.sample_rate_hz:.4g} Hz): no test point from it"
            )
        step_results.append(result)
    if progress is not None:
        progress(total, total, "fit")
    refuse_force_scale_outliers(campaign, step_results)
    deaf_notes, deaf = _deaf_runs(step_results)
    degenerate.extend(deaf_notes)
    # the set points the fit is given: a run left out as deaf gives none
    degenerate.extend(_check_set_points(
        campaign, [r for r in step_results if r.run.file not in deaf]))
    stepped = {str(r.engine) for r in campaign.of_kind("throttle_steps")}
    if delay_s is None and measured_delay is not None:
        swept = {str(d["engine"]) for d in delay_runs}
        for engine in sorted(stepped - swept):
            degenerate.append(f"{engine}: no sine sweep of its own measured a delay: its "
                              f"throttle steps settle with the others' {measured_delay:.3f} s")
    for engine in sorted({str(r.engine) for r in campaign.runs if r.engine} - stepped):
        degenerate.append(f"{engine}: runs but no throttle_steps run: no thrust model for it "
                          "(its sine sweeps still enter the delay)")

    points: list[Point] = []
    point_ratios: dict[int, list[float]] = {}
    for index, result in enumerate(step_results):
        ratios = [float("nan")] * len(result.segments)
        if result.run.file in deaf:  # no fan's response: it would bend the surface
            point_ratios[index] = ratios
            continue
        for cell, (volts, amps, watts) in cells_of[index]:
            d = float(drag.drag_n(cell.airspeed_m_s)) if drag is not None else 0.0
            thrust = cell.force_n + d
            # no tunnel (a static stand): no walls, no blockage to correct
            ratio = math.nan if campaign.tunnel_area_m2 is None else float(
                glauert_ratio(
                    thrust,
                    cell.airspeed_m_s,
                    campaign.air_density_kg_m3,
                    campaign.fan_area_m2,
                    campaign.tunnel_area_m2,
                )
            )
            for member in cell.members:
                ratios[member] = ratio
            used_v = cell.airspeed_m_s * ratio if glauert and math.isfinite(ratio) else None
            # the table stores 10 significant digits; the fit uses exactly those numbers,
            # so `tuflexperf fit TABLE` reproduces this fit
            points.append(
                Point(
                    engine=str(result.run.engine),
                    run=result.run.file,
                    throttle=_rounded(cell.throttle),
                    airspeed_measured_m_s=_rounded(cell.airspeed_m_s),
                    force_n=_rounded(cell.force_n),
                    drag_n=_rounded(d),
                    force_std_n=_rounded(cell.force_std_n),
                    n_samples=cell.n_samples,
                    glauert_ratio=ratio,
                    airspeed_m_s=_rounded(cell.airspeed_m_s if used_v is None else used_v),
                    thrust_n=_rounded(thrust),
                    thrust_at_voltage_n=_rounded(thrust),
                    voltage_v=volts,
                    current_a=amps,
                    electrical_power_w=watts,
                )
            )
        point_ratios[index] = ratios

    engines = list(dict.fromkeys(str(r.run.engine) for r in step_results))
    electrical = _electrical_fits(campaign, engines, points, pool)
    fits: dict[str, Poly22Fit] = {}
    for engine in engines:
        mine = [p for p in points if p.engine == engine]
        fits[engine] = fit_poly22(
            [p.throttle for p in mine],
            [p.airspeed_m_s for p in mine],
            [p.thrust_n for p in mine],
            label=f"{campaign.path}: engine {engine}",
        )
    refuse_unphysical_fit(str(campaign.path), fits, drag, points)
    degenerate.extend(poor_fit_notes(fits))
    validations = [
        pool.submit(_validation, result, fits[str(result.run.engine)], drag, point_ratios[index],
                    glauert, electrical)
        for index, result in enumerate(step_results)
    ]
    for result, validation in zip(step_results, validations, strict=True):
        result.report["validation"] = validation.result()
        run_reports.append(result.report)

    # The summary speaks of thrusting points, as the paper's check did: for a windmilling
    # fan's drag, 1 + 2 tau nears zero and eq. 5 (derived for a thrusting rotor) blows up.
    valid = [p for p in points if math.isfinite(p.glauert_ratio) and p.thrust_n > 0]
    worst = max(valid, key=lambda p: abs(1 - p.glauert_ratio), default=None)
    glauert_report: dict[str, Any] = {
        "applied": glauert,
        "air_density_kg_m3": campaign.air_density_kg_m3,
        "points_with_correction": len(valid),
        "max_correction_percent": 100 * abs(1 - worst.glauert_ratio) if worst else None,
        "max_correction_m_s": (
            abs(1 - worst.glauert_ratio) * worst.airspeed_measured_m_s if worst else None
        ),
        "at_airspeed_m_s": worst.airspeed_measured_m_s if worst else None,
        "max_correction_at_top_airspeed_percent": None,
    }
    if valid:
        top = max(p.airspeed_measured_m_s for p in valid)
        at_top = [abs(1 - p.glauert_ratio) for p in valid if p.airspeed_measured_m_s > top - 1.0]
        glauert_report["max_correction_at_top_airspeed_percent"] = 100 * max(at_top)

    speeds = _speeds_by_engine((p.engine, p.airspeed_m_s) for p in points)
    files = [
        {"file": r.file, "kind": r.kind, "engine": r.engine, "sha256": digest.result()}
        for r, digest in digests
    ]
    source = {
        "tool": "tuflexperf fit",
        "input": str(campaign.path.resolve()),
        "input_sha256": sha256_of(campaign.path),
        "campaign": campaign.name,
        "files": files,
        "filters": campaign.filters.model_dump(),
        "structure_drag": drag.as_dict() if drag else None,
        "glauert_applied": glauert,
        "delay_measured_s": measured_delay,
    }
    table_rows = [_table_row(p) for p in points]
    summary = _summary(
        kind="campaign",
        input_path=campaign.path,
        fits=fits,
        delay=delay,
        speeds=speeds,
    )
    summary.update(
        {
            "delay_measured_s": measured_delay,
            "delay_runs": delay_runs,
            "structure_drag": drag.as_dict() if drag else None,
            "glauert": glauert_report,
            "runs": run_reports,
            "ignored_runs": [
                {"file": r.file, "kind": r.kind, "engine": r.engine} for r in campaign.ignored
            ],
            "points": table_rows,
            "electrical": electrical.summary(),
        }
    )
    summary["warnings"].extend(electrical.warnings)
    summary["warnings"].extend(degenerate)
    # SPEC 4: discharge runs are the pack model's, fitted from the battery file that lists
    # them (it holds the cells and capacity the fit needs): said, not dropped in silence
    summary["warnings"].extend(
        f"{r.file}: endurance (discharge) run: not part of the thrust fit; the pack model is "
        "fitted from the battery file that lists it (`tuflexperf fit BATTERY.yaml --out FILE`)"
        for r in campaign.ignored
    )
    for entry in summary["engines"]:
        name = entry["name"]
        if name in electrical.power:
            fit = electrical.power[name]
            entry["power"] = {
                "model": "poly22",
                "coefficients": fit.coefficients,
                "r2": _finite_or_none(fit.r2),
                "rmse_w": _finite_or_none(fit.rmse_n),
                "n_points": fit.n_points,
            }
        if name in electrical.windmilling:
            wm = electrical.windmilling[name]
            entry["windmilling_drag_coefficient"] = wm.drag_coefficient
    if drag is None:
        summary["warnings"].append("no drag_sweep run: thrust not corrected for structure drag")
    if not delay_runs and delay_s is None:
        summary["warnings"].append("no sine_sweep run: delay not measured")
    for report in run_reports:
        summary["warnings"].extend(f"{report['file']}: {w}" for w in report.get("warnings", []))
    summary["lag_s"] = measured_lag
    propulsion = _propulsion_text(
        name=campaign.name,
        fits=fits,
        speeds=speeds,
        delay=delay,
        lag=measured_lag,
        density=campaign.air_density_kg_m3 if campaign.density_given else None,
        source=source,
        electrical=electrical,
        fan_area_m2=campaign.fan_area_m2,
    )
    table = render_thrust_table(table_rows, TABLE_EXTRA_COLUMNS)
    return FitResult(
        summary=summary,
        propulsion_text=propulsion,
        table_text=table,
        engines=fits,
        power=electrical.power,
        step_runs=step_results,
        sweep_runs=sweep_results,
    )


# --- electrical: voltage effect, power surface, windmilling (module docstring, step 7) -------
def _electrical(result: StepRunResult, members: tuple[int, ...]) -> tuple[float, float, float]:
    """Sample-weighted mean pack voltage (V), current (A) and ``U I`` (W) of a test point.

    ``nan`` for all three when the run does not log both columns.
    """
    data = result.data
    if not all(name in data.columns for name in ELECTRICAL_COLUMNS):
        return math.nan, math.nan, math.nan
    volts, amps = [], []
    for member in members:
        segment = result.segments[member]
        volts.append(data["voltage_v"][segment.start : segment.stop])
        amps.append(data["current_a"][segment.start : segment.stop])
    u, i = np.concatenate(volts), np.concatenate(amps)
    ok = np.isfinite(u) & np.isfinite(i)
    if not np.any(ok):
        return math.nan, math.nan, math.nan
    return (
        _rounded(float(np.mean(u[ok]))),
        _rounded(float(np.mean(i[ok]))),
        _rounded(float(np.mean(u[ok] * i[ok]))),
    )


@dataclass
class ElectricalFits:
    """What the logged voltage and current give, per engine (empty when nothing is logged)."""

    reference_voltage_v: float | None = None
    voltage: dict[str, VoltageFit] = field(default_factory=dict)
    power: dict[str, Poly22Fit] = field(default_factory=dict)
    windmilling: dict[str, WindmillingFit] = field(default_factory=dict)
    agreement: dict[str, dict[str, Any]] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    @property
    def exponent(self) -> float | None:
        """One exponent for the file: the mean over the engines whose runs determine it
        (None if none does: then the SPEC default applies)."""
        fits = [f for f in self.voltage.values() if f.identified]
        if not fits:
            return None
        return float(np.mean([f.exponent for f in fits]))

    def summary(self) -> dict[str, Any]:
        return {
            "reference_voltage_v": self.reference_voltage_v,
            "voltage_exponent": self.exponent,
            "voltage_fits": {name: f.to_dict() for name, f in self.voltage.items()},
            "power": {
                name: {"r2": _finite_or_none(f.r2), "rmse_w": _finite_or_none(f.rmse_n),
                       "n_points": f.n_points}
                for name, f in self.power.items()
            },
            "windmilling": {name: f.to_dict() for name, f in self.windmilling.items()},
            "thrust_power_agreement": self.agreement,
        }


def _electrical_fits(
    campaign: Campaign, engines: list[str], points: list[Point],
    pool: ThreadPoolExecutor | None = None,
) -> ElectricalFits:
    """Voltage exponent, power surface and windmilling drag per engine (module docstring, 7).

    With a determined voltage exponent every point's ``thrust_n`` is brought to the
    reference voltage in place (``T (U_ref / U)^n``), so the poly22 holds at ``U_ref``.
    The engines' exponent profiles (independent, ~300 least squares each) run on ``pool``
    when one is given.
    """
    out = ElectricalFits()
    logged = [p for p in points if math.isfinite(p.voltage_v) and p.voltage_v > 0]
    if logged:
        # the voltage the full-throttle thrust was measured at (mean over those points, to
        # 0.1 V), else over the thrusting points: where a published maximum thrust holds
        full = [p.voltage_v for p in logged if p.throttle >= 0.95]
        thrusting = [p.voltage_v for p in logged if p.thrust_n > 0]
        chosen = full or thrusting or [p.voltage_v for p in logged]
        out.reference_voltage_v = round(float(np.mean(chosen)), 1)
    reference = out.reference_voltage_v

    def voltage_fit(mine: list[Point], reference_v: float) -> VoltageFit:
        # idle points carry no thrust to scale: the exponent is fitted on thrusting ones
        fit_pts = [p for p in mine if p.throttle > 1e-3]
        return fit_voltage_exponent(
            [p.throttle for p in fit_pts],
            [p.airspeed_m_s for p in fit_pts],
            [p.thrust_n for p in fit_pts],
            [p.voltage_v for p in fit_pts],
            reference_v,
        )

    by_engine = {engine: [p for p in points if p.engine == engine] for engine in engines}
    logged_all = {
        engine: all(math.isfinite(p.voltage_v) and p.voltage_v > 0 for p in mine)
        for engine, mine in by_engine.items()
    }
    pending = {
        engine: pool.submit(voltage_fit, by_engine[engine], reference)
        for engine in engines if pool is not None and reference is not None and logged_all[engine]
    }
    unlogged: list[str] = []
    for engine in engines:
        mine = by_engine[engine]
        label = f"{campaign.path}: engine {engine}"
        with_volts = [p for p in mine if math.isfinite(p.voltage_v) and p.voltage_v > 0]
        if out.reference_voltage_v is not None and len(with_volts) == len(mine):
            out.voltage[engine] = (pending[engine].result() if engine in pending
                                   else voltage_fit(mine, out.reference_voltage_v))
        elif out.reference_voltage_v is not None:
            unlogged.append(f"engine {engine} ({len(with_volts)} of {len(mine)} points)")
        with_power = [p for p in mine if math.isfinite(p.electrical_power_w)]
        if len(with_power) >= 6:
            try:
                out.power[engine] = fit_power_surface(
                    [p.throttle for p in with_power],
                    [p.airspeed_m_s for p in with_power],
                    [p.electrical_power_w for p in with_power],
                    label=label,
                )
            except InputError as exc:
                out.warnings.append(f"no power surface: {exc}")
    if unlogged:
        # one reference voltage and exponent hold for every engine of the file: the thrust of
        # an engine whose voltage is not known everywhere cannot be brought to it
        out.warnings.append(
            f"{campaign.path}: voltage and current are not logged at every point of "
            f"{', '.join(unlogged)}: no voltage effect fitted, thrust used as measured"
        )
        out.reference_voltage_v = None
        out.voltage.clear()
    exponent = out.exponent
    for name, fit in out.voltage.items():
        if not fit.identified:
            out.warnings.append(
                f"{campaign.path}: engine {name}: voltage exponent not determined by the runs "
                f"({fit.reason}); " + (f"the other engines' {exponent:.3g} applies"
                                       if exponent is not None else
                                       f"the SPEC default {DEFAULT_VOLTAGE_EXPONENT:g} applies")
            )
    if exponent is not None and out.reference_voltage_v is not None:
        # every engine's thrust at U_ref with the one exponent the file states: an engine
        # whose own runs do not determine it takes the others' (one engine's corrupt run left
        # every engine uncorrected). Where none determines it, the thrust stays as measured:
        # the voltage then moved with the throttle, and the poly22 holds the two together
        for p in points:
            p.thrust_n = _rounded(p.thrust_at_voltage_n
                                  * (out.reference_voltage_v / p.voltage_v) ** exponent)
    for engine in engines:
        mine = [p for p in points if p.engine == engine]
        wm = fit_windmilling(
            [p.throttle for p in mine],
            [p.airspeed_m_s for p in mine],
            [p.thrust_n for p in mine],
            campaign.air_density_kg_m3,
            campaign.fan_area_m2,
        )
        if wm is not None:
            out.windmilling[engine] = wm
        _agreement(campaign, engine, mine, out)
    return out


# A test point is a working point of the fan (checked for T V / P_el) from this share of the
# engine's largest measured thrust: near zero thrust the ESC's idle draw rules the ratio.
WORKING_THRUST_SHARE = 0.1


def _agreement(campaign: Campaign, engine: str, mine: list[Point], out: ElectricalFits) -> None:
    """Measured thrust against measured ``U I`` at the engine's working points (SPEC 3)."""
    from tuflexperf.analysis.powertrain import power_agreement

    measured = [p for p in mine if math.isfinite(p.electrical_power_w)]
    if not measured:
        return
    for p in measured:  # every point with a power carries the SPEC 3 figures in the table
        a = power_agreement("", engine, p.throttle, p.airspeed_m_s, p.thrust_at_voltage_n,
                            p.electrical_power_w, campaign.air_density_kg_m3,
                            campaign.fan_area_m2, warn_efficiency=False)
        p.ideal_power_w = _rounded(a.ideal_power_w) if a.ideal_power_w is not None else math.nan
        p.figure_of_merit = (_rounded(a.figure_of_merit) if a.figure_of_merit is not None
                             else math.nan)
        p.overall_efficiency = (_rounded(a.overall_efficiency)
                                if a.overall_efficiency is not None else math.nan)
    largest = max(p.thrust_at_voltage_n for p in measured)
    working = [p for p in measured if p.thrust_at_voltage_n >= WORKING_THRUST_SHARE * largest]
    checks = [
        power_agreement(
            f"{campaign.path.name} test point", engine, p.throttle, p.airspeed_m_s,
            p.thrust_at_voltage_n, p.electrical_power_w, campaign.air_density_kg_m3,
            campaign.fan_area_m2, warn_efficiency=False,
        )
        for p in working
    ]
    merits = [c.figure_of_merit for c in checks if c.figure_of_merit is not None]
    efficiencies = [c.overall_efficiency for c in checks if c.overall_efficiency is not None]
    out.agreement[engine] = {
        "working_points": len(checks),
        "figure_of_merit_range": [min(merits), max(merits)] if merits else None,
        "overall_efficiency_range": (
            [min(efficiencies), max(efficiencies)] if efficiencies else None
        ),
    }
    out.warnings.extend(w for c in checks for w in c.warnings)


def _rounded(value: float) -> float:
    return float(format_number(float(value)))


def _table_row(p: Point) -> dict[str, Any]:
    return {
        "engine": p.engine,
        "throttle": p.throttle,
        "airspeed_m_s": p.airspeed_m_s,
        "thrust_n": p.thrust_n,
        "airspeed_measured_m_s": p.airspeed_measured_m_s,
        "force_n": p.force_n,
        "drag_n": p.drag_n,
        "force_std_n": p.force_std_n,
        "n_samples": p.n_samples,
        "glauert_ratio": p.glauert_ratio if math.isfinite(p.glauert_ratio) else None,
        "run": p.run,
        "thrust_at_voltage_n": p.thrust_at_voltage_n,
        "voltage_v": p.voltage_v if math.isfinite(p.voltage_v) else None,
        "current_a": p.current_a if math.isfinite(p.current_a) else None,
        "electrical_power_w": (
            p.electrical_power_w if math.isfinite(p.electrical_power_w) else None
        ),
        **{
            key: value if math.isfinite(value) else None
            for key, value in (
                ("ideal_power_w", p.ideal_power_w),
                ("figure_of_merit", p.figure_of_merit),
                ("overall_efficiency", p.overall_efficiency),
            )
        },
    }


# --- table ----------------------------------------------------------------------------------
# A structure drag this far below zero at the top airspeed (as a share of the largest force
# the fans' runs measured) is no drag: the sweep's sign is flipped, not noise around a clean rig
NEGATIVE_DRAG_SHARE = 0.01


DEAD_LOAD_CELL_N = 1e-9  # a drag sweep's force spanning no more than this never moved [N]
# A throttle-step run whose steady force moves by less than this share of the campaign's
# largest while its throttle moves by at least DEAF_THROTTLE_SPAN measured no thrust
DEAF_FORCE_SHARE = 0.02
DEAF_THROTTLE_SPAN = 0.3


FORCE_SCALE_RATIO = 20.0
"""Two runs of one fan whose largest forces are this many times apart: one is in another
unit (mN, kgf), or another engine's (a run of low throttle steps alone reaches ~1/10)."""


def _largest_force(result: StepRunResult) -> float:
    return max((abs(s.force_n) for s in result.segments), default=0.0)


def _follows_its_throttle(result: StepRunResult) -> bool:
    """The run's force moves with its throttle (by a tenth of its largest, or more)."""
    force = [s.force_n for s in result.segments]
    return len(force) >= 2 and max(force) - min(force) > 0.1 * _largest_force(result)


def _typical_largest_force(results: list[StepRunResult]) -> dict[str, float]:
    """Per engine, the median over its step runs whose force follows the throttle (all of
    them if none does) of each run's largest segment force [N]: stuck runs, however many,
    do not make a good run look like one in another unit."""
    live: dict[str, list[float]] = {}
    every: dict[str, list[float]] = {}
    for r in results:
        if r.segments:
            engine = str(r.run.engine)
            every.setdefault(engine, []).append(_largest_force(r))
            if _follows_its_throttle(r):
                live.setdefault(engine, []).append(_largest_force(r))
    return {engine: float(np.median(live.get(engine) or values))
            for engine, values in every.items()}


def refuse_force_scale_outliers(campaign: Any, results: list[StepRunResult]) -> None:
    """Bad input: two step runs of one engine, each with a force that follows its throttle,
    whose largest forces are more than :data:`FORCE_SCALE_RATIO` apart: one group is in
    another unit (mN, kgf) or another engine's. Which one cannot be told from the runs: one
    run in mN wrote a 1.5 MN fan; four of seven, by the median, a 55 kN one (outside
    audits)."""
    by_engine: dict[str, list[StepRunResult]] = {}
    for r in results:
        if _follows_its_throttle(r):
            by_engine.setdefault(str(r.run.engine), []).append(r)
    for engine, runs in by_engine.items():
        low = min(runs, key=_largest_force)
        high = max(runs, key=_largest_force)
        small, large = _largest_force(low), _largest_force(high)
        if small > 0 and large > FORCE_SCALE_RATIO * small:
            raise InputError(
                f"{campaign.path}: {engine}: {high.run.file} reaches {large:.4g} N and "
                f"{low.run.file} {small:.4g} N ({large / small:.3g} x): runs of one fan in "
                "another unit (mN, kgf), or another engine's run?"
            )


def _deaf_runs(results: list[StepRunResult]) -> tuple[list[str], set[str]]:
    """A note per step run whose force does not follow its throttle (a dead load cell), and
    those runs' files: their points are left out of the fit (fitted, one stuck run brought
    EDF1's surface to R^2 0.78)."""
    # per engine (a small fan beside a big one is no deaf one), the median run's largest
    # force: by the largest of all, one run logged in mN made six good ones "deaf" and the
    # fit took the bad run's 11 points alone (outside audit)
    largest = _typical_largest_force(results)
    notes = []
    deaf: set[str] = set()
    for result in results:
        if len(result.segments) < 2:
            continue
        throttle = [s.throttle for s in result.segments]
        force = [s.force_n for s in result.segments]
        if (max(throttle) - min(throttle) >= DEAF_THROTTLE_SPAN
                and max(force) - min(force) < DEAF_FORCE_SHARE * largest[str(result.run.engine)]):
            notes.append(
                f"{result.run.file}: the force stays within {max(force) - min(force):.3g} N "
                f"while the throttle moves {min(throttle):.2f}-{max(throttle):.2f}: a dead load "
                "cell? its points are left out of the fit"
            )
            deaf.add(result.run.file)
    return notes, deaf


def poor_fit_notes(fits: dict[str, Poly22Fit]) -> list[str]:
    """A note per engine whose surface explains its points poorly, but not so poorly that
    it is refused (:data:`MIN_POLY22_R2` .. :data:`POOR_POLY22_R2`)."""
    return [
        f"engine {engine}: the poly22 surface explains only R^2 = {fit.r2:.3f} of its points "
        f"(the paper's 0.997): noisy points, or a run's force sign, unit or engine label?"
        for engine, fit in fits.items() if math.isfinite(fit.r2) and fit.r2 < POOR_POLY22_R2
    ]


def refuse_unphysical_fit(
    label: str, fits: dict[str, Poly22Fit], drag: DragModel | None = None,
    points: list[Point] | None = None,
) -> None:
    """Bad input: a fit that ``check`` would refuse, or a structure drag no rig has.

    A full-throttle static thrust that is not positive (the runs' force sign flipped); a
    structure drag at the top airspeed that is negative beyond noise (the drag sweep's sign
    flipped) or larger than every force the fans' runs measured (the sweep in mN: it was
    added to every point and "passed" check with a 3000 N fan).
    """
    for engine, fit in fits.items():
        static = float(np.ravel(fit.predict(1.0, 0.0))[0])
        if not static > 0:
            raise InputError(f"{label}: engine {engine}: the fitted full-throttle static thrust "
                             f"is {static:.3g} N, not positive: is the force sign of its runs "
                             "flipped?")
        throttle, airspeed, thrust = fit.points
        if not math.isfinite(fit.r2):  # every point the same thrust
            raise InputError(f"{label}: engine {engine}: every point has the thrust "
                             f"{float(thrust[0]):.4g} N: it answers neither throttle nor airspeed")
        if fit.r2 < MIN_POLY22_R2:
            raise InputError(
                f"{label}: engine {engine}: the poly22 surface explains only R^2 = "
                f"{fit.r2:.3f} of its points (the paper's 0.997; at least {MIN_POLY22_R2:g}): "
                "is a run's force sign, unit or engine label wrong?"
            )
        low, high = float(throttle.min()), float(throttle.max())
        for v in (float(airspeed.min()), float(airspeed.max())):
            rise = float(np.ravel(fit.predict(high, v))[0] - np.ravel(fit.predict(low, v))[0])
            if not rise > 0:
                raise InputError(
                    f"{label}: engine {engine}: the fitted thrust at {v:.1f} m/s does not rise "
                    f"from throttle {low:.2f} to {high:.2f} ({rise:+.3g} N): is a run's force "
                    "sign or throttle column wrong?"
                )
    if drag is None or not points:
        return
    top = max(p.airspeed_measured_m_s for p in points)
    at_top = float(drag.drag_n(top))
    largest = max(abs(p.force_n) for p in points)
    if at_top < -NEGATIVE_DRAG_SHARE * largest:
        raise InputError(f"{label}: drag_sweep: the structure drag at {top:.1f} m/s is "
                         f"{at_top:.3g} N, negative: is the force sign of the drag sweep flipped?")
    if at_top > largest:
        raise InputError(f"{label}: drag_sweep: the structure drag at {top:.1f} m/s is "
                         f"{at_top:.4g} N, more than any force the fans' runs measured "
                         f"({largest:.4g} N): is the drag sweep in other units (mN)?")


def fit_table(path: Path | str, delay_s: float | None = None) -> FitResult:
    """Fit the poly22 per engine to a thrust table alone (no reduction).

    ``path`` is a thrust table (SPEC 4) or a propeller-table manifest (UIUC / APC PER3 files,
    :mod:`tuflexperf.io.proptables`), converted to the same points.
    """
    from tuflexperf.io.proptables import is_propeller_manifest, read_propeller_tables

    manifest = is_propeller_manifest(Path(path))
    table: ThrustTable = read_propeller_tables(path) if manifest else read_thrust_table(path)
    for engine in table.engines():
        # a surface in airspeed needs airspeeds: as a campaign's step runs must cover three
        # set points, a table's rows must (counted at the set-point resolution)
        points = {_set_point(float(v)) for v in table.select(engine)[1]}
        if len(points) < MIN_SET_POINTS:
            raise InputError(
                f"{table.path}: {engine}: the rows cover only {len(points)} airspeed set "
                f"point(s); a poly22 surface needs at least {MIN_SET_POINTS}"
            )
    fits = {
        engine: fit_poly22(*table.select(engine), label=f"{table.path}: engine {engine}")
        for engine in table.engines()
    }
    refuse_unphysical_fit(str(table.path), fits)
    speeds = _speeds_by_engine(zip(table.engine, table.airspeed_m_s, strict=True))
    source = {
        "tool": "tuflexperf fit",
        "input": str(Path(path).resolve()),
        "input_sha256": sha256_of(Path(path)),
    }
    summary = _summary(kind="table", input_path=Path(path), fits=fits, delay=delay_s, speeds=speeds)
    summary["warnings"].extend(poor_fit_notes(fits))
    propulsion = _propulsion_text(
        name=f"poly22 fit of {Path(path).name}",
        fits=fits,
        speeds=speeds,
        delay=delay_s,
        density=None,
        source=source,
    )
    rows = []
    for e, x, v, t in zip(table.engine, table.throttle, table.airspeed_m_s, table.thrust_n,
                          strict=True):
        fitted = float(np.ravel(fits[e].predict(x, v))[0])
        rows.append({"engine": e, "throttle": x, "airspeed_m_s": v, "thrust_n": t,
                     "fitted_thrust_n": fitted, "residual_n": float(t) - fitted})
    return FitResult(
        summary=summary,
        propulsion_text=propulsion,
        table_text=render_thrust_table(rows, REFIT_TABLE_EXTRA_COLUMNS),
        engines=fits,
    )


# --- rendering --------------------------------------------------------------------------------
def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _speeds_by_engine(points: Iterable[tuple[str, float]]) -> dict[str, list[float]]:
    """Each engine's tested airspeeds [m/s] from ``(engine, airspeed)`` pairs."""
    speeds: dict[str, list[float]] = {}
    for engine, airspeed in points:
        speeds.setdefault(engine, []).append(float(airspeed))
    return speeds


def _engine_range(speeds: list[float]) -> tuple[float, float]:
    """One engine's airspeed range, to 0.1 m/s (the tunnel's set points are not more exact);
    from no lower than rest (a pitot's zero offset, -0.6 m/s at rest, is no reverse wind)."""
    return max(round(min(speeds), 1), 0.0) + 0.0, round(max(speeds), 1) + 0.0


def _tested_range(speeds: dict[str, list[float]], where: str) -> list[float]:
    """The airspeed range [m/s] every engine was tested over (the file has one range, and
    each engine's model is flown over all of it: an engine tested to 25 m/s beside one
    tested to 30 m/s was written as tested to 30, its extrapolation never said; outside
    audit). Engines with no airspeed in common are bad input."""
    ranges = {engine: _engine_range(v) for engine, v in speeds.items()}
    low = max(r[0] for r in ranges.values())
    high = min(r[1] for r in ranges.values())
    if low >= high:  # one airspeed in common is no range either (the schema's low < high)
        raise InputError(
            f"{where}: the engines were tested at no airspeed range in common ("
            + ", ".join(f"{e} {r[0]:g}-{r[1]:g} m/s" for e, r in ranges.items())
            + "): one propulsion file has one tested airspeed range")
    return [low, high]


RANGE_NOTE_M_S = 1.0  # engines' tested ends further apart than this are said (set points
# are 2.5 m/s or more apart; the measured means of one set point scatter by a few 0.1 m/s)


def tested_range_notes(speeds: dict[str, list[float]]) -> list[str]:
    """A warning where the engines' own tested ranges differ from the one written by more
    than :data:`RANGE_NOTE_M_S` at either end."""
    ranges = {engine: _engine_range(v) for engine, v in speeds.items()}
    lows, highs = [r[0] for r in ranges.values()], [r[1] for r in ranges.values()]
    if max(lows) - min(lows) <= RANGE_NOTE_M_S and max(highs) - min(highs) <= RANGE_NOTE_M_S:
        return []
    return [  # the range they share, as _tested_range writes it
        "the engines were tested over different airspeeds ("
        + ", ".join(f"{e} {r[0]:g}-{r[1]:g} m/s" for e, r in ranges.items())
        + f"): the file's tested_airspeed_m_s is the range they share, "
        f"{max(lows):g}-{min(highs):g} m/s"
    ]


def _summary(
    kind: str,
    input_path: Path,
    fits: dict[str, Poly22Fit],
    delay: float | None,
    speeds: dict[str, list[float]],
) -> dict[str, Any]:
    engines = []
    for name, fit in fits.items():
        engines.append(
            {
                "name": name,
                "coefficients": fit.coefficients,
                "r2": _finite_or_none(fit.r2),
                "rmse_n": _finite_or_none(fit.rmse_n),
                "standard_errors": {k: _finite_or_none(v) for k, v in fit.standard_errors.items()},
                "n_points": fit.n_points,
                **{k: v for k, v in _uncertainty_entry(fit).items() if k != "covariance"},
                "residuals_n": [float(r) for r in fit.residuals_n],
                "full_throttle_thrust_n": {
                    f"{v:g}": float(fit.predict([1.0], [v])[0]) for v in (0.0, 30.0, 40.0)
                },
            }
        )
    return {
        "input": str(input_path),
        "kind": kind,
        "engines": engines,
        "delay_s": delay,
        "lag_s": None,
        "tested_airspeed_m_s": _tested_range(speeds, str(input_path)),
        "warnings": tested_range_notes(speeds),
    }


def _propulsion_text(
    name: str,
    fits: dict[str, Poly22Fit],
    speeds: dict[str, list[float]],
    delay: float | None,
    density: float | None,
    source: dict[str, Any],
    lag: float | None = None,
    electrical: ElectricalFits | None = None,
    fan_area_m2: float | None = None,
) -> str:
    """The propulsion file (SPEC 4), validated against the schema ``check`` loads."""
    from tuflexperf.io.case import PropulsionSchema

    document: dict[str, Any] = {
        "name": name,
        "model": "poly22",
        "tested_airspeed_m_s": _tested_range(speeds, name),
    }
    if delay is not None:
        document["delay_s"] = max(float(delay), 0.0)
    if lag is not None and math.isfinite(lag):
        document["lag_s"] = round(max(float(lag), 0.0), 6)
    if density is not None:
        document["reference_density_kg_m3"] = float(density)
    if electrical is not None and electrical.reference_voltage_v is not None:
        document["reference_voltage_v"] = electrical.reference_voltage_v
        if electrical.exponent is not None:
            document["voltage_exponent"] = round(electrical.exponent, 3)
    if fan_area_m2 is not None:
        document["fan_area_m2"] = float(fan_area_m2)
    document["engines"] = []
    for engine, fit in fits.items():
        entry: dict[str, Any] = {
            "name": engine,
            "coefficients": {t: fit.coefficients[t] for t in POLY22_TERMS},
            "n_points": fit.n_points,
        }
        if math.isfinite(fit.r2):
            entry["r2"] = fit.r2
        if math.isfinite(fit.rmse_n):
            entry["rmse_n"] = fit.rmse_n
        if all(math.isfinite(v) for v in fit.standard_errors.values()):
            entry["standard_errors"] = {t: fit.standard_errors[t] for t in POLY22_TERMS}
        entry.update(_uncertainty_entry(fit))
        if electrical is not None and engine in electrical.windmilling:
            entry["windmilling_drag_coefficient"] = round(
                electrical.windmilling[engine].drag_coefficient, 4
            )
        if electrical is not None and engine in electrical.power:
            power = electrical.power[engine]
            entry["power"] = {
                "model": "poly22",
                "coefficients": {t: power.coefficients[t] for t in POLY22_TERMS},
                "n_points": power.n_points,
            }
            if math.isfinite(power.r2):
                entry["power"]["r2"] = power.r2
            if math.isfinite(power.rmse_n):
                entry["power"]["rmse_w"] = power.rmse_n
        document["engines"].append(entry)
    document["source"] = source
    header = (
        f"{FIT_PROPULSION_HEADER} by ordinary least squares, paper section 4).\n"
        "# T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2, x throttle fraction, v m/s.\n"
    )
    # libyaml's emitter and parser where PyYAML has them (same text, ~10x faster)
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    text = header + yaml.dump(_plain(document), Dumper=dumper, sort_keys=False,
                              allow_unicode=True)
    try:
        PropulsionSchema.model_validate(yaml.load(text, Loader=loader))  # noqa: S506 - safe
    except Exception as exc:  # noqa: BLE001 - the fit must never write a file check refuses
        from pydantic import ValidationError

        from tuflexperf.io.yamlio import validation_message

        problem = (validation_message(source.get("input", "the fit"), exc, PropulsionSchema)
                   if isinstance(exc, ValidationError) else str(exc).splitlines()[0])
        raise InputError(f"the fitted propulsion file would not be valid: {problem}") from None
    return text


def _uncertainty_entry(fit: Poly22Fit) -> dict[str, Any]:
    """The fit's covariance, residual and leave-one-airspeed-out error (SPEC 4), if defined."""
    from tuflexperf.reduction.uncertainty import leave_one_airspeed_out

    entry: dict[str, Any] = {}
    if np.all(np.isfinite(fit.covariance)):
        entry["covariance"] = [[float(c) for c in row] for row in fit.covariance]
        entry["residual_sd_n"] = float(fit.residual_sd_n)
    if fit.points:
        extrapolation = leave_one_airspeed_out(*fit.points).extrapolation_sd_n
        if extrapolation is not None and math.isfinite(extrapolation):
            entry["extrapolation_sd_n"] = extrapolation
    return entry


def _plain(value: Any) -> Any:
    """numpy scalars and NaN out, so the YAML is plain and loads strictly."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(float(value)) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


# --- writing --------------------------------------------------------------------------------
def write_files(files: dict[Path, str]) -> None:
    """Write several files all-or-nothing with the user's umask (the tool's one writer)."""
    from tuflexperf.io.files import write_files_atomically

    write_files_atomically(dict(files))


def _fit_inputs(input_path: Path) -> list[Path]:
    """Every file ``fit`` reads: the input and, for a campaign, each run file it names."""
    inputs = [input_path]
    if is_thrust_table(input_path):
        return inputs
    from tuflexperf.io.yamlio import read_yaml

    data = read_yaml(input_path)
    if isinstance(data, dict) and {"aircraft", "propulsion"} <= set(data):
        raise InputError(
            f"{input_path}: this is a case (requirement) file, not a campaign manifest or "
            "thrust table; give fit a campaign.yaml or a thrust-table .csv"
        )
    if isinstance(data, dict) and isinstance(data.get("runs"), list):
        for entry in data["runs"]:
            name = entry.get("file") if isinstance(entry, dict) else None
            # a name the OS cannot take is refused by the manifest's schema, naming it
            if isinstance(name, str) and "\x00" not in name:
                inputs.append(input_path.parent / name)
    return inputs


def is_battery_file(path: Path) -> bool:
    """A battery file (SPEC 4): a YAML mapping whose keys are more a battery file's than a
    campaign manifest's (so that a misspelt ``cells_in_series`` is still told apart, and
    named with the closest key, rather than read as a manifest with a dozen unknown keys)."""
    if is_thrust_table(path):
        return False
    from tuflexperf.io.battery import BatterySchema
    from tuflexperf.io.campaign import CampaignSchema
    from tuflexperf.io.yamlio import read_yaml

    data = read_yaml(path)
    if not isinstance(data, dict):
        return False
    keys = set(map(str, data))
    battery, campaign = set(BatterySchema.model_fields), set(CampaignSchema.model_fields)
    return len(keys & battery) > len(keys & campaign)


def _fit_battery(path: Path, out: Path, table: Path | None, glauert: bool,
                 delay_s: float | None) -> dict[str, Any]:
    """``fit BATTERY.yaml``: the pack model fitted to the file's discharge runs, written back."""
    from tuflexperf.reduction.battery import fitted_battery_text

    # a flag the pack fit has no use for is refused, not ignored (--delay-s was: outside audit)
    given = [flag for flag, used in (("--table", table is not None), ("--glauert", glauert),
                                     ("--delay-s", delay_s is not None)) if used]
    if given:
        raise InputError(f"{given[0]}: not for a battery file (it fits the pack model alone)")
    text, block = fitted_battery_text(path, out)
    write_files({out: sealed(text)})
    return {"kind": "battery", "input": str(path), "out": str(out), "table": None,
            "battery_fit": block}


def _check_output(path: Path, flag: str) -> None:
    if str(path) == "-":  # the shell's "stdout": fit writes files, and JSON with --json
        raise InputError(f"{flag}: '-' (stdout) is no file name; give a file, and --json for "
                         "the summary on stdout")
    if path.is_dir():
        raise InputError(f"{flag}: {path} is a directory, expected a file name")


def is_thrust_table(path: Path) -> bool:
    """A ``.csv`` input is a thrust table (a ``.csv.gz`` one is told to unpack it); anything
    else is a campaign manifest."""
    return path.name.lower().endswith((".csv", ".csv.gz"))


def default_table_path(out: Path) -> Path:
    """Where the campaign's thrust table goes without ``--table``: beside ``--out``."""
    return out.with_name(f"{out.stem}_thrust_table.csv")


def run_fit(
    input_path: Path,
    out: Path,
    table: Path | None = None,
    glauert: bool = False,
    delay_s: float | None = None,
    progress: Progress | None = None,
) -> dict[str, Any]:
    """The ``fit`` command: compute, validate, then write ``out`` (and the table).

    Returns the JSON summary, with ``out`` and ``table`` set to the files written.
    """
    input_path = Path(input_path)
    if not input_path.exists():
        raise InputError(f"{input_path}: file not found")
    if input_path.is_dir():
        raise InputError(f"{input_path}: is a directory, expected campaign.yaml or a table .csv")
    if delay_s is not None and not (math.isfinite(delay_s) and delay_s >= 0):
        raise InputError(f"--delay-s: must be a finite number >= 0, got {delay_s}")
    if delay_s is not None and delay_s > MAX_DELAY_S:
        # a dead time past every throttle plateau would leave no steady data to fit
        raise InputError(f"--delay-s: {delay_s:.10g} s is beyond {MAX_DELAY_S:g} s, the longest "
                         "delay the reduction knows (an EDF answers within tens of ms)")
    out = Path(out)
    _check_output(out, "--out")
    from tuflexperf.io.files import guard_outputs
    from tuflexperf.io.proptables import is_propeller_manifest

    inputs = _fit_inputs(input_path)
    battery = is_battery_file(input_path)
    guard_outputs({"--out": out}, inputs, "fit",
                  {"--out": "battery file" if battery else "propulsion file"})
    if battery:
        return _fit_battery(input_path, out, table, glauert, delay_s)

    if is_thrust_table(input_path) or is_propeller_manifest(input_path):
        if glauert:
            raise InputError("--glauert: needs a campaign (fan and tunnel areas), not a table")
        result = fit_table(input_path, delay_s)
    else:
        result = fit_campaign(input_path, glauert=glauert, delay_s=delay_s, progress=progress)
        if table is None:
            table = default_table_path(out)
    files = {out: sealed(result.propulsion_text)}
    if table is not None:
        table = Path(table)
        _check_output(table, "--table")
        if table.resolve() == out.resolve():
            raise InputError("--table: must differ from --out")
        guard_outputs({"--out": out, "--table": table}, inputs, "fit",
                      {"--out": "propulsion file", "--table": "thrust table"})
        if result.table_text is not None:
            files[table] = result.table_text
    write_files(files)
    summary = result.summary
    summary["out"] = str(out)
    summary["table"] = str(table) if table is not None else None
    return summary
