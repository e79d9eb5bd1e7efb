"""Standard streams whose reader may go away: the command runs on and its verdict decides.

``tuflexperf check case.yaml | head -1`` closes the pipe after one line. Python raises
``BrokenPipeError`` at the next write, which ended the command with exit 0 whatever the
verdict (a failing case "passed" under ``set -o pipefail``), and a
progress line on a closed stderr ended a ``report`` half-way. A stream closed before the
start (``>&-``) is ``None`` in Python, and the first write was a traceback.

:func:`guard_standard_streams` makes both streams drop what their reader no longer takes:
the command computes to the end and exits with its own status (0 met, 1 not met, 2 bad
input), as it does when every line is read.

References
----------
Python documentation, "Note on SIGPIPE" (``signal`` module): point the descriptor at
``os.devnull`` so the interpreter's final flush does not raise again.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterable
from typing import Any, TextIO


class ReaderTolerantStream:
    """A text stream that drops its writes once its reader has gone (``EPIPE``)."""

    def __init__(self, inner: TextIO, dropped: type[OSError] = BrokenPipeError) -> None:
        self._inner = inner
        self._dropped = dropped  # stderr: any OSError (a full disk), its messages are extras
        self.reader_gone = False

    def write(self, text: str) -> int:
        if not self.reader_gone:
            try:
                return self._inner.write(text)
            except self._dropped:
                self._reader_went_away()
        return len(text)

    def writelines(self, lines: Iterable[str]) -> None:
        for line in lines:
            self.write(line)

    def flush(self) -> None:
        if not self.reader_gone:
            try:
                self._inner.flush()
            except self._dropped:
                self._reader_went_away()

    def _reader_went_away(self) -> None:
        self.reader_gone = True
        # the bytes still buffered go to /dev/null at the interpreter's last flush
        with contextlib.suppress(OSError, ValueError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._inner.fileno())
            os.close(devnull)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


def guard_standard_streams() -> None:
    """Give ``sys.stdout`` and ``sys.stderr`` a :class:`ReaderTolerantStream` each (a
    closed one becomes ``os.devnull``). Idempotent."""
    for name, fd in (("stdout", 1), ("stderr", 2)):
        stream = getattr(sys, name)
        if isinstance(stream, ReaderTolerantStream):
            continue
        if stream is None:  # closed before the start: what is written goes nowhere
            # on its own descriptor (os.open takes the lowest free one: with stdin closed
            # too that was 0, and descriptor 1 went to the next output file opened)
            devnull = os.open(os.devnull, os.O_WRONLY)
            if devnull != fd:
                os.dup2(devnull, fd)
                os.close(devnull)
            stream = open(fd, "w", encoding="utf-8", closefd=False)  # noqa: SIM115
        if getattr(stream, "errors", None) == "strict":
            # a file name's bytes that are no UTF-8 (a Latin-1 folder) in a line of output
            # raised UnicodeEncodeError in a UTF-8 locale: written escaped, as \xfc
            from tuflexperf.io.inputs import register_name_errors

            with contextlib.suppress(AttributeError, ValueError):
                stream.reconfigure(errors=register_name_errors())
        setattr(sys, name, ReaderTolerantStream(
            stream, OSError if name == "stderr" else BrokenPipeError))
