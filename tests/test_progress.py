"""Progress bars (issue 47): rich's bar on stderr for work over a second, only when stderr is
a terminal; never any progress text elsewhere, and never on --json's stdout."""

from __future__ import annotations

import io
import json
import os
import pty
import subprocess
import sys
import threading
from pathlib import Path

from typer.testing import CliRunner

from tuflexperf.cli import app
from tuflexperf.cli.progress import TerminalProgress

BAR = "\u2501"  # rich's bar character


def test_no_progress_text_when_stderr_is_no_terminal() -> None:
    runner = CliRunner()
    for args in (["check", "--samples", "20000", "--json"],
                 ["sweep", "--vary", "aircraft.mass_kg=20:30:3000", "--json"]):
        result = runner.invoke(app, args)
        assert result.exit_code in (0, 1), result.stderr
        json.loads(result.stdout)
        assert BAR not in result.stderr and args[0] not in result.stderr, result.stderr
        assert BAR not in result.stdout


def test_the_bar_draws_on_a_terminal_and_is_silent_before_its_delay() -> None:
    from rich.console import Console

    shown = io.StringIO()
    with TerminalProgress("samples", Console(file=shown, force_terminal=True), 0.0) as bar:
        bar(1, 4)
        threading.Event().wait(0.3)  # the timer thread shows it
        bar(3, 4)
    assert "samples" in shown.getvalue() and BAR in shown.getvalue()
    quick = io.StringIO()
    with TerminalProgress("sweep", Console(file=quick, force_terminal=True), 5.0) as bar:
        bar(1, 1)
    assert quick.getvalue() == ""  # quicker than the delay: no bar flashed
    silent = io.StringIO()
    with TerminalProgress("sweep", Console(file=silent, force_terminal=False), 0.0) as bar:
        assert not bar.enabled
        bar(1, 2)
    assert silent.getvalue() == ""


def test_check_samples_on_a_terminal_shows_a_bar_on_stderr_only() -> None:
    """A real pseudo-terminal as stderr, stdout a pipe: the bar there, the JSON clean."""
    exe = Path(sys.executable).with_name("tuflexperf")
    command = [str(exe)] if exe.exists() else [sys.executable, "-m", "tuflexperf"]
    master, slave = pty.openpty()
    env = {k: v for k, v in os.environ.items() if k not in ("NO_COLOR", "TERM")}
    proc = subprocess.Popen([*command, "check", "--samples", "300000", "--json"],
                            stdout=subprocess.PIPE, stderr=slave, env={**env, "TERM": "xterm"})
    os.close(slave)
    said = bytearray()

    def read() -> None:
        while True:
            try:
                chunk = os.read(master, 4096)
            except OSError:
                return
            if not chunk:
                return
            said.extend(chunk)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    out, _ = proc.communicate(timeout=300)
    reader.join(timeout=5)
    os.close(master)
    assert proc.returncode in (0, 1)
    assert json.loads(out)["results"]
    text = said.decode("utf-8", "replace")
    assert "samples" in text and BAR in text, text[-500:]
    assert BAR not in out.decode()
