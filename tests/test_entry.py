"""The console entry point ends the process at once, with Python's exit status and every
byte of output written (it skips only the interpreter's teardown)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.conftest import PASSING
from tuflexperf.entry import exit_status


def _tool(*argv: str) -> list[str]:
    return [sys.executable, "-m", "tuflexperf", *argv]


def test_exit_status_is_pythons(capsys):
    assert exit_status(None) == 0
    assert exit_status(0) == 0 and exit_status(1) == 1 and exit_status(2) == 2
    assert exit_status(256 + 3) == 3  # as the OS keeps it
    assert exit_status("gone") == 1  # SystemExit("gone"): the message on stderr, status 1
    assert capsys.readouterr().err == "gone\n"


@pytest.mark.parametrize(
    ("argv", "status"),
    # the shipped case is UNPROVEN (exit 1, like a FAIL); PASSING makes it pass
    [(["check", "--json", *PASSING], 0), (["check", "--json"], 1),
     (["check", "--json", "--set", "aircraft.mass_kg=60"], 1)],
)
def test_a_command_ends_with_its_status_and_whole_output(argv, status):
    done = subprocess.run(_tool(*argv), capture_output=True,
                          text=True)
    assert done.returncode == status, done.stderr
    result = json.loads(done.stdout)  # the whole object, not a buffer cut at exit
    assert result["passed"] is (status == 0)


def test_bad_input_still_one_line_and_exit_2():
    done = subprocess.run(_tool("check", "--set",
                           "aircraft.mas_kg=3"), capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "aircraft.mass_kg" in done.stderr


def test_a_bug_still_unwinds_with_its_traceback():
    """Only an exit skips the teardown: an error that is not one is raised as usual."""
    code = (
        "import tuflexperf.cli as cli\n"
        "def broken(argv=None):\n    raise ZeroDivisionError('bug')\n"
        "cli.main = broken\n"
        "from tuflexperf.entry import main\n"
        "main()\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 1
    assert "ZeroDivisionError: bug" in done.stderr and "Traceback" in done.stderr


def test_numpy_overflow_warnings_stay_off_the_screen():
    """An extreme margin search overflows exp (an inf the analysis handles); numpy's
    RuntimeWarning with its source line was printed on stderr (outside audit)."""
    done = subprocess.run(_tool("margins", "--set",
                           "aircraft.mass_kg=80"), capture_output=True, text=True)
    assert done.returncode in (0, 1), done.stderr
    assert "RuntimeWarning" not in done.stderr and "Traceback" not in done.stderr


def _fake_pydantic_plugin(root, marker):
    """A distribution on ``root`` whose pydantic plugin, once loaded, writes ``marker``."""
    (root / "fakeplug.py").write_text(
        f"open({str(marker)!r}, 'w').close()\n"
        "class _Plugin:\n"
        "    def new_schema_validator(self, *args, **kwargs):\n"
        "        return None, None, None\n"
        "plugin = _Plugin()\n")
    info = root / "fakeplug-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: fakeplug\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[pydantic]\nfake = fakeplug:plugin\n")


@pytest.mark.parametrize(("setting", "loaded"), [(None, False), ("someone_else", True)])
def test_pydantic_plugins_stay_out_unless_the_user_asks(tmp_path, setting, loaded):
    """pydantic scans every installed distribution for plugins on the first schema it
    builds (~12 ms of each `check`); the tool turns that off, keeping the user's setting."""
    import os

    marker = tmp_path / "plugin_loaded"
    _fake_pydantic_plugin(tmp_path, marker)
    env = {k: v for k, v in os.environ.items() if k != "PYDANTIC_DISABLE_PLUGINS"}
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), *sys.path[1:]])
    if setting is not None:
        env["PYDANTIC_DISABLE_PLUGINS"] = setting
    done = subprocess.run(_tool("check", "--json", *PASSING),
                          capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert marker.exists() is loaded


@pytest.mark.parametrize(("mass", "status"), [("22", 0), ("29", 1)])
def test_a_reader_gone_leaves_the_verdict_its_exit_status(mass, status):
    """`check | true`: the reader closes the pipe before the first line. The write's
    BrokenPipeError ended a failing check with 0 (a PASS under `set -o pipefail`; outside
    audit); now the command runs on, its lines dropped, and exits with its own verdict."""
    proc = subprocess.Popen(_tool("check", "--set", f"aircraft.mass_kg={mass}", *PASSING),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # before the ~0.3 s of imports are over: every write hits EPIPE
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == status, err
    assert b"Traceback" not in err and err == b""


def test_a_closed_stream_is_no_traceback():
    """Started with stdout or stderr closed (`>&-`, a daemon): Python's sys.stdout is None,
    and the first write was an AttributeError traceback with exit 1 (a PASS and bad input
    alike)."""
    import os

    def run(argv: list[str], fd: int) -> subprocess.CompletedProcess:
        return subprocess.run(_tool(*argv), capture_output=True, timeout=120,
                              preexec_fn=lambda: os.close(fd))

    assert run(["check", *PASSING], 1).returncode == 0
    assert run(["check", "--set", "aircraft.mass_kg=29"], 1).returncode == 1
    assert run(["check"], 1).returncode == 1  # the shipped case is UNPROVEN
    refused = run(["check", "nonexistent.yaml"], 2)
    assert refused.returncode == 2 and refused.stdout == b""
    assert run(["check", "nonexistent.yaml"], 1).returncode == 2


def test_a_stream_whose_reader_went_away_drops_its_writes():
    import os

    from tuflexperf.io.streams import ReaderTolerantStream

    read_end, write_end = os.pipe()
    os.close(read_end)
    with os.fdopen(write_end, "w") as raw:
        stream = ReaderTolerantStream(raw)
        assert stream.write("one line\n") == 9
        stream.flush()  # EPIPE: the reader is gone
        assert stream.reader_gone
        stream.writelines(["and more\n"] * 3)
        stream.flush()
    # its descriptor points at /dev/null now: the interpreter's last flush cannot raise


def test_library_exit_cleanups_still_run(tmp_path):
    """os._exit skipped atexit: matplotlib's temporary config folder (made where its own is
    not writable) stayed in TMPDIR after every plot."""
    import os

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch), "MPLCONFIGDIR": "/proc/not-writable"}
    done = subprocess.run(_tool("sweep", "--vary", "aircraft.mass_kg=20:24:2", "--plot",
                                str(tmp_path / "s.png")), capture_output=True, env=env,
                          timeout=300)
    assert done.returncode in (0, 1), done.stderr
    assert (tmp_path / "s.png").exists()
    assert list(scratch.iterdir()) == []


def test_a_full_device_is_no_traceback_and_keeps_the_status():
    """stderr on a full disk changed bad input's exit 2 into 1; `--version` on a full
    stdout was a traceback (second outside audit)."""
    import os

    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    with open("/dev/full", "w") as full:
        refused = subprocess.run(_tool("check", "--set", "aircraft.mas_kg=3"),
                                 stdout=subprocess.DEVNULL, stderr=full, timeout=120)
        failing = subprocess.run(_tool("check", "--set", "aircraft.mass_kg=29"),
                                 stdout=subprocess.DEVNULL, stderr=full, timeout=120)
        version = subprocess.run(_tool("--version"), stdout=full, stderr=subprocess.PIPE,
                                 text=True, timeout=120)
    assert refused.returncode == 2 and failing.returncode == 1
    assert version.returncode == 2
    assert version.stderr == "tuflexperf: error: stdout: disk full\n"


def test_stdin_and_stdout_closed_keep_stdout_on_descriptor_1(tmp_path):
    """With stdin closed too, the stand-in for a closed stdout took descriptor 0, and
    descriptor 1 went to the next file opened: a C-level write to stdout would have landed
    in an output file (second outside audit)."""
    import os

    probe = ("import os, sys\n"
             "from tuflexperf.io.streams import guard_standard_streams\n"
             "guard_standard_streams()\n"
             "print(sys.stdout.fileno(), os.readlink('/proc/self/fd/1'), file=sys.stderr)\n")

    def closed() -> None:
        os.close(0)
        os.close(1)

    done = subprocess.run([sys.executable, "-c", probe], preexec_fn=closed,
                          capture_output=False, stderr=subprocess.PIPE, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stderr.split() == ["1", os.devnull]
