"""Samples per second over every requirement of the shipped case with a 7-segment mission,
the batch's map against a numpy-free loop of the same function, and `check --samples 10000`
against the deterministic `check` (whole processes, taking turns).

Run as `python bench/bench_mission_samples.py [SAMPLES]`. Figures, not verdicts.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import yaml
from timing import walls  # noqa: E402

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
        model.sampled_chain()  # expanded once per process
        print(f"mission build + SX expansion: {time.perf_counter() - start:.2f} s")
        evaluate_batch(case, plan, range(0, 1))  # the evaluator and its caches
        start = time.perf_counter()
        for chunks in [range(i, min(i + 4, len(plan.chunks)))
                       for i in range(0, len(plan.chunks), 4)]:
            evaluate_batch(case, plan, chunks)
        elapsed = time.perf_counter() - start
        print(f"in process, every requirement incl. endurance and the mission: "
              f"{samples / elapsed:,.0f} samples/s ({samples} in {elapsed:.2f} s)")
        # the map against one call per row of the same expanded function
        history = model.sampled_chain()[0]
        rows = 200
        import numpy as np

        args = [np.repeat(model.durations[:, None], rows, 1),
                np.repeat(model.theta[:, None], rows, 1), np.repeat(model.par, rows, 1)]
        width = sum(c for _, c in model.sampled_chain()[2])
        tk = np.zeros((model.tk.shape[0], width * rows))
        for name, f in (("map serial", history.map(rows)),
                        ("map thread 2", history.map(rows, "thread", 2))):
            start = time.perf_counter()
            f(*args, tk)
            print(f"{name}: {(time.perf_counter() - start) / rows * 1e3:.2f} ms a row")
        start = time.perf_counter()
        for _ in range(20):
            history(model.durations, model.theta, model.par, tk[:, :width])
        print(f"one call a row: {(time.perf_counter() - start) / 20 * 1e3:.2f} ms a row")
        cli = [str(Path(sys.executable).parent / "tuflexperf")]
        times = walls({"check": [*cli, "check", str(path), "--json"],
                       "samples": [*cli, "check", str(path), "--json", "--samples", "10000"]},
                      rounds=2)
        print(f"check {times['check']:.2f} s, check --samples 10000 {times['samples']:.2f} s: "
              f"ratio {times['samples'] / times['check']:.2f}")


if __name__ == "__main__":
    main()
