"""Timing helpers every bench script shares (run the scripts as `python bench/<name>.py`)."""

from __future__ import annotations

import statistics
import subprocess
import time
from collections.abc import Callable
from pathlib import Path


def byte_compile_package() -> None:
    """Write tuflexperf's ``.pyc`` files, as installing a wheel does.

    An editable install compiles on first import, unless ``PYTHONDONTWRITEBYTECODE`` is set
    (it is on some machines here): then every run recompiles ~1 MB of source (~90 ms), a cost
    the floor's packages, installed with their ``.pyc``, never pay.
    """
    import compileall

    import tuflexperf

    compileall.compile_dir(Path(tuflexperf.__file__).parent, quiet=1)


def wall(argv: list[str], repeats: int = 5) -> float:
    """Median wall time [s] of a whole process (tuflexperf byte-compiled first)."""
    byte_compile_package()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=False)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def walls(commands: dict[str, list[str]], rounds: int = 15) -> dict[str, float]:
    """Median wall time [s] of each whole process, the commands taking turns each round.

    On a shared VM whose speed drifts within a minute, timing one command five times and
    then the next compares different minutes; taking turns puts each ratio's two sides in
    the same ones.
    """
    byte_compile_package()
    for argv in commands.values():  # warm the file cache
        subprocess.run(argv, capture_output=True, check=False)
    times: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(rounds):
        for name, argv in commands.items():
            start = time.perf_counter()
            subprocess.run(argv, capture_output=True, check=False)
            times[name].append(time.perf_counter() - start)
    return {name: statistics.median(values) for name, values in times.items()}


def per_call(fn: Callable[[], object], repeats: int = 7) -> float:
    """Median time [s] of one call, after a warm-up call that builds what it needs."""
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)
