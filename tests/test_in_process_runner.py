"""``tests.conftest.tuflexperf`` (the CLI in this process) gives what the console gives.

Most command-line tests run in-process: a subprocess costs ~0.3 s of CPU in imports alone.
These pin the runner to the real process, so a test moved in-process keeps its power.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from tests.conftest import PASSING, tuflexperf


@pytest.mark.parametrize("argv", [
    ["check", "--json"],  # exit 0, the JSON on stdout
    ["check", "nowhere.yaml"],  # bad input: exit 2, one line
    ["trim", "--tabel"],  # a usage error, as click and cli.main word it
    ["check", "--set", "requirements.takeoff.max_ground_roll_m=5"],  # not met: exit 1
    ["--version"],
], ids=["pass", "bad input", "usage", "fail", "version"])
def test_the_same_status_stdout_and_stderr_as_a_process(tmp_path: Path, argv) -> None:
    process = subprocess.run([sys.executable, "-m", "tuflexperf", *argv], cwd=tmp_path,
                             capture_output=True, text=True, timeout=120)
    here = tuflexperf(*argv, cwd=tmp_path)
    assert (here.returncode, here.stdout, here.stderr) == (
        process.returncode, process.stdout, process.stderr)


def test_what_it_changes_it_puts_back(tmp_path: Path) -> None:
    """The working folder, the streams and the signal handlers are this process's again."""
    import os

    before = (os.getcwd(), sys.stdout, sys.stderr, signal.getsignal(signal.SIGINT),
              signal.getsignal(signal.SIGTERM), sys.unraisablehook)
    assert tuflexperf("check", *PASSING, cwd=tmp_path).returncode == 0
    assert (os.getcwd(), sys.stdout, sys.stderr, signal.getsignal(signal.SIGINT),
            signal.getsignal(signal.SIGTERM), sys.unraisablehook) == before


def test_a_warning_the_command_lets_out_is_on_its_stderr(monkeypatch) -> None:
    """As a process prints it (pytest would otherwise record it out of the test's sight),
    unless the test asks for PYTHONWARNINGS=ignore."""
    from tuflexperf import cli

    main = cli.main

    def warned(argv):
        warnings.warn("a stray warning", UserWarning, stacklevel=1)
        main(argv)

    monkeypatch.setattr(cli, "main", warned)
    assert "UserWarning: a stray warning" in tuflexperf("check").stderr
    assert tuflexperf("check", warnings_shown=False).stderr == ""


def test_what_a_c_library_or_a_forked_helper_writes_is_captured(monkeypatch) -> None:
    """CasADi writes to descriptor 2 itself and the report's helpers are forked: in a
    process both reach the pipe, so here both reach the captured stderr too."""
    import os

    from tuflexperf import cli

    main = cli.main

    def noisy(argv):
        os.write(2, b"written to descriptor 2\n")
        child = os.fork()
        if child == 0:  # as a forked helper writes
            sys.stderr.write("a forked helper's line\n")
            sys.stderr.flush()
            os._exit(0)
        os.waitpid(child, 0)
        main(argv)

    monkeypatch.setattr(cli, "main", noisy)
    done = tuflexperf("check", "nowhere.yaml")
    assert done.stderr.splitlines() == ["written to descriptor 2", "a forked helper's line",
                                        "tuflexperf: error: nowhere.yaml: file not found"]
    assert done.returncode == 2 and done.stdout == ""
