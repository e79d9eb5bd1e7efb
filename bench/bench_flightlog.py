"""flightlog speed (issue 45): a ~20 MB ULog reduced in at most 3 s, reading only its topics.

The log is the shipped real `sample_log_small.ulg` with every topic's data repeated end to
end (each copy's timestamps shifted past the last) until the file holds ~20 MB, written by
pyulog itself; a temporary file, deleted afterwards. Prints the whole `tuflexperf flightlog
--json` process time, and as a ratio to pyulog reading the whole file (every topic).

Run: .venv/bin/python bench/bench_flightlog.py
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from pyulog import ULog
from timing import walls

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "tests" / "data" / "flightlogs" / "sample_log_small.ulg"
TARGET_BYTES = 22 << 20  # pyulog writes back ~6 % less than it read


def tiled_log(out: Path) -> tuple[int, float]:
    """Write the tiled log to ``out``; returns its size [B] and span [s]."""
    ulog = ULog(str(SOURCE))
    copies = int(np.ceil(TARGET_BYTES / SOURCE.stat().st_size))
    # the data's own span (the header's start and last timestamps cover 1174 s of idling)
    first = min(int(d.data["timestamp"].min()) for d in ulog.data_list)
    span = max(int(d.data["timestamp"].max()) for d in ulog.data_list) - first + 1
    for data in ulog.data_list:
        columns = {}
        for name, values in data.data.items():
            tiles = [values] * copies
            if name in ("timestamp", "timestamp_sample") and values.dtype == np.uint64:
                tiles = [values + np.asarray(k * span, dtype=values.dtype) for k in range(copies)]
            columns[name] = np.concatenate(tiles)
        data.data = columns
    ulog._logged_messages = []  # text messages and parameter changes: not repeated
    ulog._changed_parameters = []
    ulog.write_ulog(str(out))
    return out.stat().st_size, copies * span * 1e-6


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "long.ulg"
        size, span = tiled_log(path)
        from tuflexperf.io.flightlog import ULOG_TOPICS

        start = time.perf_counter()
        ULog(str(path), list(ULOG_TOPICS))
        topics_in_process = time.perf_counter() - start
        start = time.perf_counter()
        ULog(str(path))
        whole_in_process = time.perf_counter() - start
        times = walls({
            "flightlog": [sys.executable, "-m", "tuflexperf", "flightlog", str(path), "--json"],
            "pyulog, every topic": [sys.executable, "-c",
                                    f"from pyulog import ULog; ULog({str(path)!r})"],
        }, rounds=3)
    print(f"log: {size / 2**20:.1f} MB of tiled real data ({span / 60:.0f} min of clock: each "
          "copy spans the source's whole clock, idle stretches included)")
    print(f"tuflexperf flightlog --json (whole process): {times['flightlog']:.2f} s "
          "(target <= 3 s)")
    print(f"pyulog reading every topic (whole process): {times['pyulog, every topic']:.2f} s; "
          f"in process {whole_in_process:.2f} s; only flightlog's topics {topics_in_process:.2f} s")
    print(f"ratio flightlog / pyulog-all: {times['flightlog'] / times['pyulog, every topic']:.2f}")


if __name__ == "__main__":
    main()
