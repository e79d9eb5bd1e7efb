"""`--workers`: an interrupt ends every process quietly, a killed worker is one line, no hang.

Found as a hostile user (process group interrupted at random moments, 40 times): the
process pool's workers printed tracebacks of their own, and a worker killed while it wrote
its result left half a message on the pool's shared pipe that the command waited on at
exit, for ever.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, "fork") or not Path("/proc").is_dir(),
                                reason="needs fork and /proc")

COMMAND = [sys.executable, "-m", "tuflexperf", "check", "--samples", "400000", "--seed", "11",
           "--workers", "2"]


def _processes() -> list[tuple[int, str, int, int]]:
    """(pid, state, parent pid, process group) of every process, from /proc."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        found.append((int(stat.parent.name), fields[0], int(fields[1]), int(fields[2])))
    return found


def _children(pid: int) -> list[int]:
    return [child for child, _, parent, _ in _processes() if parent == pid]


def _group_alive(group: int) -> list[int]:
    return [pid for pid, state, _, pgrp in _processes() if pgrp == group and state != "Z"]


def _start_with_workers() -> tuple[subprocess.Popen[str], list[int]]:
    process = subprocess.Popen(COMMAND, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    deadline = time.monotonic() + 60
    workers: list[int] = []
    while len(workers) < 2 and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.01)
        workers = _children(process.pid)
    assert len(workers) >= 2, "the workers never started"
    return process, workers


@pytest.mark.parametrize(("signum", "after_s", "group"), [
    (signal.SIGINT, 0.0, True), (signal.SIGINT, 0.3, True), (signal.SIGTERM, 0.15, True),
    # to the command alone (a supervisor's SIGTERM): its workers are stopped by it
    (signal.SIGTERM, 0.0, False), (signal.SIGINT, 0.3, False),
    # a hang-up to the command alone had left its workers running, orphaned (outside audit)
    (signal.SIGHUP, 0.3, False),
])
def test_an_interrupt_ends_the_command_and_its_workers_quietly(
    signum: int, after_s: float, group: bool
) -> None:
    process, _ = _start_with_workers()
    time.sleep(after_s)
    (os.killpg if group else os.kill)(process.pid, signum)
    _, err = process.communicate(timeout=60)  # a hang fails here
    assert process.returncode == 130, (process.returncode, err)
    assert "Traceback" not in err and "Exception ignored" not in err, err
    time.sleep(0.2)
    assert _group_alive(process.pid) == []


def test_a_worker_killed_from_outside_is_one_line_and_no_hang() -> None:
    process, workers = _start_with_workers()
    time.sleep(0.2)
    os.kill(workers[0], signal.SIGKILL)
    _, err = process.communicate(timeout=60)
    lines = err.strip().splitlines()
    assert process.returncode == 2 and len(lines) == 1 and "--workers" in lines[0], err
    time.sleep(0.2)
    assert _group_alive(process.pid) == []
