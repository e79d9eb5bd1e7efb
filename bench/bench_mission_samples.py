"""Samples per second over every requirement of the shipped case with a 7-segment mission,
the sampled mission's rows (numpy, at the sampled and at the single case's steps) against a
call per row of the single case's chained CasADi function, and `check --samples 10000`
against the deterministic `check` (whole processes, taking turns).

Run as `python bench/bench_mission_samples.py [SAMPLES]`. Figures, not verdicts.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from timing import walls  # noqa: E402

from tuflexperf.analysis.mission import STEPS, takeoff_layout
from tuflexperf.analysis.mission_rows import fly_rows
from tuflexperf.analysis.mission_samples import SAMPLED_STEPS
from tuflexperf.analysis.uncertainty import evaluate_batch, mission_for, plan_for
from tuflexperf.io.case import load_case

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "requirements" / "tuflex.yaml"
MISSION = ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml"  # 7 segments


def case_with_mission(folder: Path) -> Path:
    """The shipped case with the shipped test flight as a mission requirement."""
    data = yaml.safe_load(SHIPPED.read_text())
    for key in ("aircraft", "propulsion", "battery"):
        data[key] = str((SHIPPED.parent / data[key]).resolve())
    data["requirements"]["mission"] = {"file": str(MISSION), "min_landing_charge_fraction": 0.2}
    path = folder / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def main() -> None:
    samples = int(sys.argv[1]) if len(sys.argv) > 1 else 2500
    with tempfile.TemporaryDirectory() as folder:
        path = case_with_mission(Path(folder))
        case = load_case(path)
        plan = plan_for(case, samples=samples, seed=1)
        start = time.perf_counter()
        model = mission_for(case, [key for key, _, _ in plan.parameters])
        print(f"mission build: {time.perf_counter() - start:.2f} s")
        evaluate_batch(case, plan, range(0, 1))  # the evaluator and its caches
        start = time.perf_counter()
        for chunks in [range(i, min(i + 4, len(plan.chunks)))
                       for i in range(0, len(plan.chunks), 4)]:
            evaluate_batch(case, plan, chunks)
        elapsed = time.perf_counter() - start
        print(f"in process, every requirement incl. endurance and the mission: "
              f"{samples / elapsed:,.0f} samples/s ({samples} in {elapsed:.2f} s)")
        # the mission's flight alone: numpy rows against one CasADi call a row (the rows'
        # take-off phases of no time: the same arithmetic as flown ones)
        rows = 2500
        for steps in (SAMPLED_STEPS, STEPS):
            shape = takeoff_layout(True, True, True, steps)
            width = sum(c for _, c in shape)
            tk = np.zeros((rows, model.tk.shape[0], width))
            start = time.perf_counter()
            fly_rows(model, np.repeat(model.durations[:, None], rows, 1),
                     np.repeat(model.theta[:, None], rows, 1), np.repeat(model.par, rows, 1),
                     tk, shape, steps)
            print(f"numpy rows, {steps} steps a segment: "
                  f"{(time.perf_counter() - start) / rows * 1e3:.3f} ms a row")
        start = time.perf_counter()
        for _ in range(20):
            model._history(model.durations, model.theta, model.par, model.tk)
        print(f"single case's CasADi function, one call: "
              f"{(time.perf_counter() - start) / 20 * 1e3:.2f} ms a row")
        cli = [str(Path(sys.executable).parent / "tuflexperf")]
        times = walls({"check": [*cli, "check", str(path), "--json"],
                       "samples": [*cli, "check", str(path), "--json", "--samples", "10000"]},
                      rounds=2)
        print(f"check {times['check']:.2f} s, check --samples 10000 {times['samples']:.2f} s: "
              f"ratio {times['samples'] / times['check']:.2f}")


if __name__ == "__main__":
    main()
