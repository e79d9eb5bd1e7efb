"""A progress bar on stderr for work that takes over a second: only on a terminal.

Off a terminal (a pipe, a file, a CI log, a test) it writes nothing at all, so stderr keeps
only notes and errors and ``--json``'s stdout is never touched. The bar shows once the work
has run :data:`DELAY_S`; a quicker command never flashes one.
"""

from __future__ import annotations

import os
import sys
import threading
from typing import Any

DELAY_S = 1.0  # work quicker than this shows no bar


def _maybe_terminal() -> bool:
    """False where rich's ``Console(stderr=True).is_terminal`` is surely False: stderr no
    terminal, and neither ``TTY_COMPATIBLE=1`` nor ``FORCE_COLOR`` says otherwise."""
    if os.environ.get("TTY_COMPATIBLE", "") == "1" or "FORCE_COLOR" in os.environ:
        return True
    isatty = getattr(sys.stderr, "isatty", None)
    try:
        return bool(isatty is not None and isatty())
    except ValueError:  # a closed stream, as rich takes it
        return False


class TerminalProgress:
    """``with TerminalProgress("samples") as bar: work(progress=bar)``; ``bar(done, total,
    label)`` is the callback. Rich's transient bar on stderr when it is a terminal."""

    def __init__(self, what: str, console: Any = None, delay_s: float = DELAY_S) -> None:
        self.what = what
        if console is None and not _maybe_terminal():
            # rich's import (~15 ms, more than all else `check --samples` adds but the batch)
            # for its own answer, "no terminal", known here already
            self.console, self.enabled = None, False
        else:
            if console is None:
                from rich.console import Console

                console = Console(stderr=True)
            self.console = console
            self.enabled = bool(console.is_terminal)
        self.delay_s = delay_s
        self._lock = threading.Lock()
        self._state: tuple[int, int | None, str] = (0, None, "")
        self._bar: Any = None
        self._task: Any = None
        self._timer: threading.Timer | None = None
        self._closed = False

    def __enter__(self) -> TerminalProgress:
        if self.enabled:
            self._timer = threading.Timer(self.delay_s, self._show)
            self._timer.daemon = True  # never keeps the command alive
            self._timer.start()
        return self

    def _show(self) -> None:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
        )

        with self._lock:
            if self._closed:
                return
            done, total, label = self._state
            self._bar = Progress(TextColumn(self.what), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), TextColumn("{task.description}"),
                                 console=self.console, transient=True)
            self._bar.start()
            self._task = self._bar.add_task(label, total=total, completed=done)

    def __call__(self, done: int, total: int | None, label: str = "") -> None:
        with self._lock:
            self._state = (done, total, label)
            if self._bar is not None:
                self._bar.update(self._task, completed=done, total=total, description=label)

    def __exit__(self, *exc: object) -> None:
        if self._timer is not None:
            self._timer.cancel()
        with self._lock:
            self._closed = True
            if self._bar is not None:
                self._bar.stop()
