"""The console entry point: a Ctrl-C that lands before the command runs ends it quietly.

Python's own Ctrl-C handler raises KeyboardInterrupt wherever the interrupt lands: inside
the ~0.2 s of imports before :func:`tuflexperf.cli.main` installs its handlers that printed
a traceback, or, raised inside an import's callback, was printed as "ignored" and dropped
(the command then ran to the end and exited 0). Until then nothing has been written, so
no cleanup is owed: the process ends at once with the interrupt's exit code.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import sys

INTERRUPTED_EXIT = 130  # 128 + SIGINT; SIGTERM unwinds like Ctrl-C (tuflexperf.io.files)
# as tuflexperf.io.files.INTERRUPT_SIGNALS (not imported: nothing but the standard library
# is loaded before the command starts)
_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


def _exit_at_once(signum: int, frame: object) -> None:
    os._exit(INTERRUPTED_EXIT)


def _exit_on_interrupt() -> None:
    for signum in _SIGNALS:
        signal.signal(signum, _exit_at_once)


def exit_status(code: object) -> int:
    """The process exit status Python gives ``SystemExit(code)`` (a message prints, then 1)."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.write(f"{code}\n")
    return 1


def main() -> None:
    """``tuflexperf`` (the console script) and ``python -m tuflexperf``.

    A command that ends (``SystemExit``, as every command does) ends the process at once:
    its outputs are written, closed and moved in place by then (io.files), its helper
    processes joined and its Dask client closed (analysis.uncertainty), so what is left is
    the interpreter's teardown of CasADi's, pydantic's and numpy's objects, ~50 ms of CPU
    in each ``check`` that changes nothing. An error that is not an exit (a bug) unwinds
    as usual, with its traceback.
    """
    _exit_on_interrupt()
    from tuflexperf.cli import main as cli_main
    from tuflexperf.io.files import output_committed

    status = INTERRUPTED_EXIT
    try:
        cli_main()
        status = 0
    except SystemExit as done:
        status = exit_status(done.code)
    except KeyboardInterrupt:
        # a second Ctrl-C on the way out of an interrupted run: no traceback, still 130
        status = INTERRUPTED_EXIT
    finally:
        # the command is done, only the interpreter's teardown is left: an interrupt there
        # would be raised where nothing reports it (the process died of the signal). Once
        # the output has replaced the earlier one the run is done whatever comes now
        if output_committed():
            for signum in _SIGNALS:
                signal.signal(signum, signal.SIG_IGN)
        else:
            _exit_on_interrupt()
        # what libraries clean up at exit (matplotlib's temporary config folder where its
        # own is not writable) is not teardown: os._exit skipped it and left the folder
        atexit._run_exitfuncs()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(OSError, ValueError, AttributeError):  # None: closed
                stream.flush()
    os._exit(status)
