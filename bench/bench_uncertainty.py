"""Monte Carlo benchmark: batched evaluation vs the per-sample loop, and whole processes paired.

* in process: every requirement of the shipped case (take-off, trim, OEI and the endurance)
  for 10,000 samples (mass, cd0, temperature and every source of the error model:
  covariance, model form, rig, extrapolation, power model, battery fit), batched; printed
  as samples/s (target >= 20,000/s);
* the naive way, a Python loop calling the single-case analyses (``check_case`` on a case
  with the sample's values) -- timed on 200 samples and scaled: target batched >= 100x;
* whole process, paired: ``tuflexperf check --samples 10000`` and the deterministic
  ``check`` taking turns (A B A B ...), the median of the pairs' ratios (target <= 1.5x);
  on a shared machine only the ratio of neighbouring runs means much;
* ``--workers 2`` (whole process, 40,000 samples) vs in-process, for the record
  (``--full``);
* the load average before and after, and so whether a batch's second half runs in a helper
  process (in process, only where a second core is idle); in process, the helper against
  one process whatever the load.

Run: ``python bench/bench_uncertainty.py [PAIRS] [--full] [--whole]`` (``--whole``: the
paired whole processes alone)
"""

from __future__ import annotations

import dataclasses
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from timing import byte_compile_package, wall  # noqa: E402

from tuflexperf.analysis.error_model import error_model_for
from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.uncertainty import (
    SamplingPlan,
    draw_chunk,
    evaluator_for,
    run_samples,
    second_core_idle,
)
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values
from tuflexperf.io.schemas import PropulsionUncertaintySchema
from tuflexperf.models.thrust import POLY22_TERMS

PARAMETERS = (
    ("aircraft.cd0", "normal", (0.020, 0.002)),
    ("aircraft.mass_kg", "normal", (22.17, 0.5)),
    ("atmosphere.temperature_offset_k", "uniform", (0.0, 20.0)),
)
TUFLEXPERF = str(Path(sys.executable).with_name("tuflexperf"))


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    print(cores_line())
    if "--whole" not in sys.argv[1:]:
        in_process()
    pairs = int(args[0]) if args else 7
    det, mc = paired([TUFLEXPERF, "check"], [TUFLEXPERF, "check", "--samples", "10000"], pairs)
    ratios = [b / a for a, b in zip(det, mc, strict=True)]
    print(f"whole process, {pairs} pairs taking turns: check {statistics.median(det):.2f} s, "
          f"check --samples 10000 {statistics.median(mc):.2f} s (medians); ratio median "
          f"{statistics.median(ratios):.2f}x, range {min(ratios):.2f}-{max(ratios):.2f}x "
          "(target <= 1.5x)")
    print(cores_line())
    if "--full" in sys.argv[1:]:
        t_mc40 = wall([TUFLEXPERF, "check", "--samples", "40000"], 3)
        t_mc40_w2 = wall([TUFLEXPERF, "check", "--samples", "40000", "--workers", "2"], 3)
        print(f"whole process, 40,000 samples: in-process {t_mc40:.2f} s, --workers 2 "
              f"{t_mc40_w2:.2f} s ({t_mc40 / t_mc40_w2:.2f}x; 2 cores shared with others)")


def cores_line() -> str:
    """The load now, and so where a batch's second half runs (uncertainty.second_core_idle:
    the runnable tasks now, not the load average)."""
    load = os.getloadavg()[0]
    where = ("in a helper process" if second_core_idle()
             else "here too (no idle second core)")
    return (f"load average {load:.2f} on {len(os.sched_getaffinity(0))} usable cores: a batch's "
            f"second half {where}")


def two_cores_line(case: object, plan: SamplingPlan, rounds: int = 5) -> str:
    """In process, a batch's second half in a helper process against all of it here, taking
    turns whatever the load (medians of ``rounds``; the helper gains only on an idle core)."""
    from tuflexperf.analysis import uncertainty

    gate = uncertainty.second_core_idle
    times: dict[bool, list[float]] = {True: [], False: []}
    try:
        for _ in range(rounds):
            for split in (False, True):
                uncertainty.second_core_idle = lambda split=split: split
                start = time.perf_counter()
                run_samples(case, plan)  # type: ignore[arg-type]
                times[split].append(time.perf_counter() - start)
    finally:
        uncertainty.second_core_idle = gate
    one, two = (statistics.median(times[k]) for k in (False, True))
    return (f"in process, 10,000 samples: one process {one:.3f} s, half the rows in a helper "
            f"{two:.3f} s ({one / two:.2f}x, medians of {rounds} taking turns)")


def in_process() -> None:
    """Samples per second in process, and against the per-sample loop."""
    case = load_case()
    # every source of the error model on, as `check --samples` draws them by default
    plan = SamplingPlan(10_000, 1, 0.95, PARAMETERS, True, True, True,
                        error_model_for(case, PropulsionUncertaintySchema()))
    run_samples(case, plan)  # build once (the CLI's deterministic check builds the same)
    batched = []
    for _ in range(5):
        start = time.perf_counter()
        run_samples(case, plan)
        batched.append(time.perf_counter() - start)
    t_batch = statistics.median(batched)
    split = two_cores_line(case, plan)

    # the naive way: one single-case analysis per sample (same draws)
    loop_n = 200
    draw = draw_chunk(case, dataclasses.replace(plan, samples=loop_n), 0)
    evaluator_for(case)
    start = time.perf_counter()
    for i in range(loop_n):
        engines = tuple(
            dataclasses.replace(e, coefficients={
                t: float(draw.coefficients[j, i, k]) for k, t in enumerate(POLY22_TERMS)})
            for j, e in enumerate(case.propulsion.engines)
        )
        single = with_values(case, {k: float(v[i]) for k, v in draw.values.items()})
        single = dataclasses.replace(
            single, propulsion=dataclasses.replace(single.propulsion, engines=engines))
        check_case(single)
    t_loop = (time.perf_counter() - start) / loop_n * plan.samples

    print(f"in process: {plan.samples:,} samples x {len(evaluator_for(case).requirements)} "
          f"requirements in {t_batch:.3f} s (median of 5) = {plan.samples / t_batch:,.0f} "
          "samples/s (target >= 20,000/s)")
    print(split)
    print(f"per-sample loop of single-case analyses: {t_loop:.1f} s for 10,000 "
          f"(measured on {loop_n}); batched is {t_loop / t_batch:.0f}x faster (target >= 100x)")


def paired(first: list[str], second: list[str], pairs: int) -> tuple[list[float], list[float]]:
    """Wall times [s] of two whole processes run in turns (A B A B ...), ``pairs`` of each,
    after one warm-up of each (the file cache); package byte-compiled first."""
    byte_compile_package()
    for argv in (first, second):
        subprocess.run(argv, capture_output=True, check=False)
    times: tuple[list[float], list[float]] = ([], [])
    for _ in range(pairs):
        for argv, out in ((first, times[0]), (second, times[1])):
            start = time.perf_counter()
            # exit 1 is a verdict (a requirement short of its probability), not a failure
            done = subprocess.run(argv, capture_output=True, check=False)
            if done.returncode not in (0, 1):
                raise RuntimeError(f"{argv}: exit {done.returncode}: {done.stderr[-300:]!r}")
            out.append(time.perf_counter() - start)
    return times


if __name__ == "__main__":
    main()
