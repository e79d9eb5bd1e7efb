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


def per_call(fn: Callable[[], object], repeats: int = 7) -> float:
    """Median time [s] of one call, after a warm-up call that builds what it needs."""
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)
