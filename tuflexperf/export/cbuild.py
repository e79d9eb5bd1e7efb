"""The C compiler the FMU export builds its binary with (tests compile the exported C too)."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
from collections.abc import Sequence
from pathlib import Path


def find_compiler() -> str | None:
    """Path of the C compiler (``$CC``, else ``gcc``, else ``cc``), or None when there is none."""
    for name in (os.environ.get("CC", ""), "gcc", "cc"):
        found = shutil.which(name) if name else None
        if found:
            return found
    return None


def run_compiler(command: Sequence[str], scratch: Path | str) -> subprocess.CompletedProcess[str]:
    """Run a compiler ``command`` with its temporary files in ``scratch`` (``TMPDIR``) and
    in a process group of its own, which an interrupt ends whole (``subprocess.run`` kills the
    driver alone, leaving its ``cc*.s`` / ``cc*.o`` in the user's ``$TMPDIR``)."""
    env = {**os.environ, "TMPDIR": str(scratch)}
    process = subprocess.Popen(list(command), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=env, start_new_session=True)
    try:
        out, err = process.communicate()
    except BaseException:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        raise
    return subprocess.CompletedProcess(list(command), process.returncode, out, err)
