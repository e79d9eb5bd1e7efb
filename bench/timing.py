"""Timing helpers every bench script shares (run the scripts as `python bench/<name>.py`)."""

from __future__ import annotations

import statistics
import subprocess
import time
from collections.abc import Callable


def wall(argv: list[str], repeats: int = 5) -> float:
    """Median wall time [s] of a whole process."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=False)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def per_call(fn: Callable[[], object], repeats: int = 7) -> float:
    """Median time [s] of one call, after a warm-up call that builds what it needs."""
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)
