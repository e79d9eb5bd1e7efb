"""A campaign fitted: every run read and reduced, the delay, structure drag and surfaces fitted.

Steps 1-7 of :mod:`.pipeline` for a campaign manifest: sine sweeps give the delay, bare
velocity sweeps the structure drag, step runs the test points (:mod:`.step_runs`) from
which the poly22 surfaces and the electrical fits (:mod:`.electrical_fit`) are made.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.campaign import Campaign, CampaignRun, load_campaign
from tuflexperf.io.files import sha256_of
from tuflexperf.io.inputs import path_text
from tuflexperf.io.runs import (
    TABLE_EXTRA_COLUMNS,
    Run,
    read_run,
    render_thrust_table,
)
from tuflexperf.reduction.delay import DelayEstimate, estimate_delay
from tuflexperf.reduction.drag import DragModel, fit_structure_drag
from tuflexperf.reduction.electrical_fit import ElectricalFits, electrical_fits, electrical_means
from tuflexperf.reduction.filters import movmedian
from tuflexperf.reduction.fit_checks import (
    DEAD_LOAD_CELL_N,
    MIN_DRAG_SWEEP_AIRSPEED_M_S,
    MIN_DRAG_SWEEP_SPAN_M_S,
    MIN_SWEEP_THROTTLE_SWING,
    check_set_points,
    deaf_runs,
    poor_fit_notes,
    refuse_force_scale_outliers,
    refuse_unphysical_fit,
    set_point,
    speeds_by_engine,
)
from tuflexperf.reduction.fit_output import FitResult, fit_summary, render_propulsion, table_row
from tuflexperf.reduction.glauert import glauert_ratio
from tuflexperf.reduction.lack_of_fit import (
    BATCH_S,
    batch_mean_variance,
    engine_lack_of_fit,
    lack_of_fit_note,
)
from tuflexperf.reduction.poly22fit import Poly22Fit, fit_poly22
from tuflexperf.reduction.rig import IDLE_THROTTLE, rig_uncertainty
from tuflexperf.reduction.segments import (
    TestPoint,
    merge_test_points,
)
from tuflexperf.reduction.step_runs import (
    MIN_SEGMENT_S,
    Point,
    Progress,
    StepRunResult,
    SweepRunResult,
    clean_run,
    filter_windows,
    finite_or_none,
    mean_or_none,
    reduce_step_run,
    rounded,
    run_header,
)

# A sine sweep whose delay-and-lag model explains less of the force than this measured no
# response (noise alone fits R^2 ~0.01; very noisy real sweeps 0.26 still gave the delay
# to 2 ms; the shipped ones 0.999)
MIN_SWEEP_R2 = 0.1
# Sweeps of one rig further apart than this in their delay say one of them is off (the
# shipped campaign's agree to 0.2 ms; one logged with a tenth of its time base is 45 ms off)
MAX_DELAY_SPREAD_S = 0.01
# Engines' delays further apart than this (the paper's whole delay, 0.05 s) get one mean
# delay_s that fits neither engine
MAX_DELAY_ENGINES_APART_S = 0.05


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
            data, {**run_header(run, data), "wind": "none"},
            f"{run.file}: drag sweep without wind (airspeed at most {top:.2f} m/s): no "
            "structure drag measured, none added",
        )
    span = top - float(np.min(data["airspeed_m_s"]))
    if span < MIN_DRAG_SWEEP_SPAN_M_S:  # one airspeed: a curve in V^2 is not determined
        return _DragSweep(
            data, {**run_header(run, data), "wind": "one airspeed"},
            f"{run.file}: drag sweep over {span:.2f} m/s of airspeed only (needs "
            f">= {MIN_DRAG_SWEEP_SPAN_M_S:g}): no drag curve from it, left out",
        )
    if float(np.ptp(data["force_n"])) <= DEAD_LOAD_CELL_N:
        # the same force at every airspeed: no "D = 0 (R^2 nan)" added to every point
        return _DragSweep(
            data, {**run_header(run, data), "force": "constant"},
            f"{run.file}: drag sweep whose force is {float(data['force_n'][0]):.4g} N "
            "throughout (a dead load cell?): no structure drag measured, none added",
        )
    force, replaced = clean_run(campaign, data)
    _, _, k_med = filter_windows(campaign, data.sample_rate_hz)
    return _DragSweep(
        data, {**run_header(run, data), "outliers_replaced": replaced},
        curve=(movmedian(data["airspeed_m_s"], k_med), force),
    )

_Cell = tuple[TestPoint, tuple[float, float, float], tuple[float, int]]
"""A run's test point with its mean pack voltage [V], current [A] and ``U I`` [W], and the
variance of its mean force [N^2] from inside its segments with its degrees of freedom."""


def _hold_variance(result: StepRunResult, cell: TestPoint) -> tuple[float, int]:
    """The variance [N^2] of a test point's mean force by batch means inside each of its
    segments (:mod:`.lack_of_fit`), combined as the sample-weighted mean is, and its dof."""
    batch = max(1, int(round(BATCH_S * result.data.sample_rate_hz)))
    parts = [batch_mean_variance(result.segments[i].filtered_force_n, batch)
             for i in cell.members]
    weights = np.array([result.segments[i].n_samples for i in cell.members], dtype=float)
    variance = float(np.sum(weights**2 * np.array([v for v, _ in parts])) / weights.sum() ** 2)
    return variance, sum(d for _, d in parts)


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
            run_reports.append({**run_header(run, data), "excitation": "none"})
            continue
        if not estimate.r2 >= MIN_SWEEP_R2:  # noise fits some delay too: it measures nothing
            degenerate.append(
                f"{run.file}: the force does not follow the sine sweep (fit R^2 "
                f"{estimate.r2:.2f} < {MIN_SWEEP_R2:g}): left out of the delay"
            )
            run_reports.append({**run_header(run, data), "response": "none",
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
                **run_header(run, data),
                "delay_s": estimate.delay_s,
                "spool_lag_s": estimate.lag_s,
                "fit_r2": estimate.r2,
            }
        )
    measured_delay = mean_or_none([d["delay_s"] for d in delay_runs])
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
        # the model has one delay_s, their mean: for two ESCs 10x apart it fits neither
        named = ", ".join(f"{e} {v:.3f} s" for e, v in per_engine.items())
        degenerate.append(
            f"the engines disagree on the delay ({named}, more than "
            f"{MAX_DELAY_ENGINES_APART_S:g} s apart): the model's one delay_s is their mean "
            f"{measured_delay:.3f} s, which fits neither; is a run's time base off?"
        )
    # the spool lag after the dead time (issue 15): the sweeps' mean, written as lag_s
    measured_lag = mean_or_none([d["lag_s"] for d in delay_runs])
    delay = delay_s if delay_s is not None else measured_delay
    # where the steady part of a step starts: the engine's own sweeps if it has any
    onset_delay = {
        str(engine): delay_s
        if delay_s is not None
        else mean_or_none([d["delay_s"] for d in delay_runs if d["engine"] == engine])
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
        return result, [(cell, electrical_means(result, cell.members),
                         _hold_variance(result, cell))
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
    deaf_notes, deaf = deaf_runs(step_results)
    degenerate.extend(deaf_notes)
    # the set points the fit is given: a run left out as deaf gives none
    degenerate.extend(check_set_points(
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
        for cell, (volts, amps, watts), (variance, dof) in cells_of[index]:
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
                    throttle=rounded(cell.throttle),
                    airspeed_measured_m_s=rounded(cell.airspeed_m_s),
                    force_n=rounded(cell.force_n),
                    drag_n=rounded(d),
                    force_std_n=rounded(cell.force_std_n),
                    n_samples=cell.n_samples,
                    glauert_ratio=ratio,
                    airspeed_m_s=rounded(cell.airspeed_m_s if used_v is None else used_v),
                    thrust_n=rounded(thrust),
                    thrust_at_voltage_n=rounded(thrust),
                    voltage_v=volts,
                    current_a=amps,
                    electrical_power_w=watts,
                    hold_variance_n2=variance,
                    hold_dof=dof,
                )
            )
        point_ratios[index] = ratios

    engines = list(dict.fromkeys(str(r.run.engine) for r in step_results))
    electrical = electrical_fits(campaign, engines, points, pool)
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
    lack = {}
    for engine in engines:
        mine = [p for p in points if p.engine == engine]
        # the points as the fit saw them; set points from the measured airspeeds
        lack[engine] = engine_lack_of_fit(
            [p.throttle for p in mine], [p.airspeed_m_s for p in mine],
            [p.thrust_n for p in mine], [set_point(p.airspeed_measured_m_s) for p in mine],
            [p.hold_variance_n2 for p in mine], sum(p.hold_dof for p in mine))
        note = lack_of_fit_note(engine, lack[engine]) if lack[engine] is not None else None
        if note:
            degenerate.append(note)
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

    speeds = speeds_by_engine((p.engine, p.airspeed_m_s) for p in points)
    volts = [p.voltage_v for p in points if math.isfinite(p.voltage_v)]
    rig = rig_uncertainty(
        str(campaign.path), campaign.rig_uncertainty,
        [d for r in step_results if r.run.file not in deaf
         for d in [_idle_drift(r, fits[str(r.run.engine)], drag, electrical)] if d is not None],
        max((p.airspeed_measured_m_s for p in points), default=0.0),
        max((p.thrust_n for p in points), default=0.0),
        float(np.mean(volts)) if volts else None,
    )
    degenerate.extend(rig.notes)
    files = [
        {"file": r.file, "kind": r.kind, "engine": r.engine, "sha256": digest.result()}
        for r, digest in digests
    ]
    source = {
        "tool": "tuflexperf fit",
        "input": path_text(campaign.path.resolve()),  # a name's bytes no UTF-8 takes: escaped
        "input_sha256": sha256_of(campaign.path),
        "campaign": campaign.name,
        "files": files,
        "filters": campaign.filters.model_dump(),
        "structure_drag": drag.as_dict() if drag else None,
        "glauert_applied": glauert,
        "delay_measured_s": measured_delay,
        "rig_uncertainty_basis": rig.basis,
    }
    table_rows = [table_row(p) for p in points]
    summary = fit_summary(
        kind="campaign",
        input_path=campaign.path,
        fits=fits,
        delay=delay,
        speeds=speeds,
        lack_of_fit=lack,
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
            "windmilling": windmilling_summary(campaign, engines, electrical),
            "rig_uncertainty": rig.summary(),
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
                "r2": finite_or_none(fit.r2),
                "rmse_w": finite_or_none(fit.rmse_n),
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
    # the dynamic model fitted on either excitation, both reported (issue 47 item 6); the
    # sweeps' is the model's (delay_s, lag_s): the steps' is its check
    summary["dynamics_fits"] = {
        "sine_sweep": _dynamics_fit(delay_runs),
        "throttle_steps": _dynamics_fit(_step_dynamics(step_results, pool)),
    }
    propulsion = render_propulsion(
        name=campaign.name,
        fits=fits,
        speeds=speeds,
        delay=delay,
        lag=measured_lag,
        density=campaign.air_density_kg_m3 if campaign.density_given else None,
        source=source,
        electrical=electrical,
        fan_area_m2=campaign.fan_area_m2,
        lack_of_fit=lack,
        rig_uncertainty=rig.document(),
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


def _step_dynamics(results: list[StepRunResult],
                   pool: ThreadPoolExecutor) -> list[dict[str, Any]]:
    """The dead time and spool lag fitted on the throttle steps (:func:`estimate_delay`: its
    model holds for any throttle history), of each engine's run at its highest airspeed,
    where the fan's lag matters to flight; a run whose fit explains nothing is left out."""
    top: dict[str, StepRunResult] = {}
    for result in results:
        speed = float(np.mean(result.data["airspeed_m_s"]))
        engine = str(result.run.engine)
        if float(np.ptp(result.data["throttle"])) >= MIN_SWEEP_THROTTLE_SWING and (
                engine not in top
                or speed > float(np.mean(top[engine].data["airspeed_m_s"]))):
            top[engine] = result
    fits = [(r, pool.submit(estimate_delay, r.data.time_s, r.data["throttle"],
                            r.data["force_n"], r.data.sample_rate_hz)) for r in top.values()]
    runs = []
    for result, future in fits:
        fit = future.result()
        if fit.r2 >= MIN_SWEEP_R2:
            runs.append({"file": result.run.file, "engine": result.run.engine,
                         "delay_s": fit.delay_s, "lag_s": fit.lag_s, "r2": fit.r2})
    return runs


def _dynamics_fit(runs: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The mean dead time and spool lag [s] of the runs fitted, with their count and the
    least R^2 (None without a run)."""
    if not runs:
        return None
    return {"delay_s": float(np.mean([r["delay_s"] for r in runs])),
            "lag_s": float(np.mean([r["lag_s"] for r in runs])),
            "n_runs": len(runs), "min_r2": float(min(r["r2"] for r in runs)),
            "runs": runs}


def _idle_drift(result: StepRunResult, fit: Poly22Fit, drag: DragModel | None,
                electrical: ElectricalFits) -> float | None:
    """How far a run's idle hold at its end reads from the one at its start [N], beyond what
    the model expects from their airspeeds and pack voltages (:mod:`.rig`); None: the run
    does not start and end idle."""
    segments = result.segments
    if len(segments) < 2 or max(abs(segments[0].throttle), abs(segments[-1].throttle)) > \
            IDLE_THROTTLE:
        return None
    exponent, reference = electrical.exponent, electrical.reference_voltage_v
    residuals = []
    for segment in (segments[0], segments[-1]):
        model = float(fit.predict([0.0], [segment.airspeed_m_s])[0])
        if exponent is not None and reference is not None and "voltage_v" in result.data.columns:
            volts = float(np.nanmean(result.data["voltage_v"][segment.start:segment.stop]))
            model *= (volts / reference) ** exponent
        if drag is not None:
            model -= float(drag.drag_n(segment.airspeed_m_s))
        residuals.append(segment.force_n - model)
    return residuals[1] - residuals[0]


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


def windmilling_summary(campaign: Campaign, engines: list[str], electrical: ElectricalFits
                        ) -> dict[str, Any]:
    """Per engine: the ``windmilling_drag_coefficient`` estimated from the campaign's
    throttle-0 holds, on the disk area ``fan_area_m2``, or why none is (issue 43 item 5)."""
    from tuflexperf.reduction.power import IDLE_THROTTLE, MIN_WINDMILL_AIRSPEED_M_S

    out: dict[str, Any] = {"fan_area_m2": campaign.fan_area_m2, "engines": {}}
    for name in engines:
        fit = electrical.windmilling.get(name)
        if fit is not None:
            out["engines"][name] = {"estimated": True, **fit.to_dict(),
                                    "source": "throttle-0 holds"}
        else:
            out["engines"][name] = {
                "estimated": False,
                "reason": (f"fewer than two throttle-0 holds (throttle <= {IDLE_THROTTLE:g}) at "
                           f"{MIN_WINDMILL_AIRSPEED_M_S:g} m/s or more: no "
                           "windmilling_drag_coefficient (a dead fan flies its own thrust "
                           "model at throttle 0)"),
            }
    return out
