"""Command line: parses, calls the analyses, renders. No physics here.

Exit codes (SPEC 5): 0 done / all met, 1 not met or not attainable, 2 bad input.

The commands live in ``commands_*`` (thin: flags, case, analysis, result), what they show
in :mod:`tuflexperf.cli.render`, and the exit-code guard around them in
:mod:`tuflexperf.cli.guard`; this module holds the app and :func:`main`.
"""

from __future__ import annotations

import os
import sys
from typing import Any

import typer
from typer.core import TyperCommand, TyperGroup

from tuflexperf.cli import commands_core, commands_data, commands_flight
from tuflexperf.cli.commands_flightlog import flightlog_command
from tuflexperf.cli.guard import (
    case_hint,
    guarded,
    os_error_text,
    refuse_empty,
    refuse_repeated,
)
from tuflexperf.cli.inputs import load_case_with, parse_sets
from tuflexperf.messages import one_line

__all__ = ["app", "load_case_with", "main", "one_line", "parse_sets"]

class _HelpWithoutType:
    """``-h`` is a flag: its help row shows no value type (it showed ``<bool>``)."""

    def get_help_option(self, ctx: Any) -> Any:
        option = super().get_help_option(ctx)  # type: ignore[misc]
        if option is not None:
            option.metavar = ""
        return option


class _Command(_HelpWithoutType, TyperCommand):
    pass


class _Group(_HelpWithoutType, TyperGroup):
    pass


app = typer.Typer(
    cls=_Group,
    add_completion=False,
    context_settings={"help_option_names": ["-h", "--help"]},
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Wind-tunnel EDF runs -> thrust model -> aircraft-performance verdicts.",
)


def _version(value: bool) -> None:
    if value:
        from tuflexperf import __version__

        typer.echo(f"tuflexperf {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", metavar="", callback=_version, is_eager=True,
        help="Print the version and exit.",
    ),
) -> None:
    """Wind-tunnel EDF runs -> thrust model -> aircraft-performance verdicts."""


# in the order ``--help`` lists them
for _callback in (commands_core.check, commands_core.margins, commands_core.sweep,
                  commands_core.takeoff, commands_core.trim, commands_core.oei,
                  commands_core.performance, commands_flight.mission,
                  commands_flight.endurance):
    app.command(cls=_Command)(_callback)
app.command("fit", cls=_Command)(commands_data.fit_command)
app.command("report", cls=_Command)(commands_data.report_command)
app.command("export", cls=_Command)(commands_data.export_command)
app.command("flightlog", cls=_Command)(flightlog_command)  # issue 45
app.command("init", cls=_Command)(commands_data.init_command)

for _info in app.registered_commands:  # every command above, whichever module wrote it
    _info.callback = guarded(_info.callback)


def main(argv: list[str] | None = None) -> None:
    """Console entry point: usage errors become one line on stderr and exit 2."""
    from typer.exceptions import Abort, TyperException

    from tuflexperf.io.files import hold_interrupts, install_interrupt_handlers, interrupted
    from tuflexperf.io.streams import guard_standard_streams

    install_interrupt_handlers()  # SIGTERM unwinds like Ctrl-C: no staging left behind
    # `check | head -1`: the reader gone, the command still runs to its own exit status
    guard_standard_streams()
    # pydantic otherwise scans every installed package's entry points for plugins on the
    # first model (importlib.metadata, ~10 ms of each `check`); a user may still enable them
    os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")
    # numpy's overflow in an extreme sample or margin search (exp of a huge charge) gives an
    # inf that the analysis turns into "not attainable"; its warning, with a source line, is
    # noise on the user's screen
    import warnings

    warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"tuflexperf(\.|$)")
    def aborted() -> None:
        hold_interrupts()  # a second Ctrl-C here prints no traceback
        sys.stderr.write("tuflexperf: aborted\n")
        sys.exit(130)

    args = sys.argv[1:] if argv is None else list(argv)
    refuse_empty(args)
    refuse_repeated(app, args)
    try:
        code = app(args=argv, standalone_mode=False, prog_name="tuflexperf")
    except (Abort, KeyboardInterrupt):  # click's word for an interrupt, or one before click's
        aborted()
    except TyperException as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            app(args=["--help"], prog_name="tuflexperf")
        message = exc.format_message()
        sys.stderr.write(f"tuflexperf: error: {one_line(message + case_hint(message, argv))}\n")
        sys.exit(getattr(exc, "exit_code", 2) or 2)
    except OSError as exc:  # outside a command's own guard (--version, --help): stdout full
        if interrupted():
            aborted()
        sys.stderr.write(f"tuflexperf: error: {os_error_text(exc)}\n")
        sys.exit(2)
    except Exception:
        # an interrupt raised inside an import or a C extension comes out as its error
        # (RuntimeError, SystemError, ...): it is still the interrupt, not a failure
        if not interrupted():
            raise
        aborted()
    if interrupted():  # one a library dropped (printed as "ignored"): still no success
        aborted()  # (after the output replaced the earlier one, an interrupt is not noted)
    sys.exit(code if isinstance(code, int) else 0)
