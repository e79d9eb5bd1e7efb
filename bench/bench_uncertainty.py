"""Monte Carlo benchmark: batched evaluation vs the per-sample loop, in the same run.

* 10,000 samples of every requirement of the shipped case (mass, cd0, temperature and the
  thrust model's covariance + extrapolation error), batched: target <= 1 s in-process;
* the naive way, a Python loop calling the single-case analyses (``check_case`` on a case
  with the sample's values) -- timed on 200 samples and scaled: target batched >= 100x;
* whole process: ``tuflexperf check --samples 10000`` vs the deterministic ``check``
  (target <= 2x);
* ``--workers 2`` (whole process, 40,000 samples) vs in-process, for the record.

Run: ``python bench/bench_uncertainty.py``
"""

from __future__ import annotations

import dataclasses
import statistics
import sys
import time
from pathlib import Path

from timing import wall  # noqa: E402

from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.uncertainty import (
    SamplingPlan,
    draw_chunk,
    evaluator_for,
    run_samples,
)
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values
from tuflexperf.models.thrust import POLY22_TERMS

PARAMETERS = (
    ("aircraft.cd0", "normal", (0.020, 0.002)),
    ("aircraft.mass_kg", "normal", (22.17, 0.5)),
    ("atmosphere.temperature_offset_k", "uniform", (0.0, 20.0)),
)
TUFLEXPERF = str(Path(sys.executable).with_name("tuflexperf"))




def main() -> None:
    case = load_case()
    plan = SamplingPlan(10_000, 1, 0.95, PARAMETERS, True, True)
    run_samples(case, plan)  # build once (the CLI's deterministic check builds the same)
    batched = []
    for _ in range(5):
        start = time.perf_counter()
        run_samples(case, plan)
        batched.append(time.perf_counter() - start)
    t_batch = statistics.median(batched)

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

    t_det = wall([TUFLEXPERF, "check"])
    t_mc = wall([TUFLEXPERF, "check", "--samples", "10000"])
    t_mc40 = wall([TUFLEXPERF, "check", "--samples", "40000"], 3)
    t_mc40_w2 = wall([TUFLEXPERF, "check", "--samples", "40000", "--workers", "2"], 3)

    print(f"10,000 samples x {len(evaluator_for(case).requirements)} requirements, batched: "
          f"{t_batch:.3f} s in-process (target <= 1 s)")
    print(f"per-sample loop of single-case analyses: {t_loop:.1f} s for 10,000 "
          f"(measured on {loop_n}); batched is {t_loop / t_batch:.0f}x faster (target >= 100x)")
    print(f"whole process: check {t_det:.2f} s, check --samples 10000 {t_mc:.2f} s = "
          f"{t_mc / t_det:.2f}x (target <= 2x)")
    print(f"whole process, 40,000 samples: in-process {t_mc40:.2f} s, --workers 2 "
          f"{t_mc40_w2:.2f} s ({t_mc40 / t_mc40_w2:.2f}x; 2 cores shared with others)")


if __name__ == "__main__":
    main()
