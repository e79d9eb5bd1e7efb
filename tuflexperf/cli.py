"""Command line: parses, calls the analyses, renders. No physics here.

Exit codes (SPEC 5): 0 done / all met, 1 not met or not attainable, 2 bad input.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import typer

from tuflexperf.errors import InputError, NotAttainable

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Wind-tunnel EDF runs -> thrust model -> aircraft-performance verdicts.",
)

CaseOption = typer.Option(None, "--case", help="Requirement file (default: shipped TU-Flex case).")
JsonOption = typer.Option(False, "--json", help="Print one JSON object on stdout.")


def _json_default(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _clean(value: Any) -> Any:
    """NaN/inf become null so the JSON stays standard."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def emit_json(payload: dict[str, Any]) -> None:
    sys.stdout.write(json.dumps(_clean(payload), default=_json_default, indent=2) + "\n")


def fail_input(message: str) -> None:
    """Bad input: one line on stderr, exit 2."""
    sys.stderr.write(f"tuflexperf: error: {message}\n")
    raise typer.Exit(2)


# ---- performance core: check, takeoff, trim, oei (issue 2) ---------------------------------


# ---- endurance (issue 3) -------------------------------------------------------------------


# ---- fit (issue 4) -------------------------------------------------------------------------


# ---- report (issue 5) ----------------------------------------------------------------------


# ---- export (issue 6) ----------------------------------------------------------------------


def main(argv: list[str] | None = None) -> None:
    """Console entry point: usage errors and InputError become one line and exit 2."""
    import click

    try:
        code = app(args=argv, standalone_mode=False)
    except click.exceptions.UsageError as exc:
        flag = f"{exc.param.get_error_hint(exc.ctx)}: " if getattr(exc, "param", None) else ""
        message = exc.format_message() if not flag else exc.format_message()
        sys.stderr.write(f"tuflexperf: error: {message}\n")
        sys.exit(2)
    except click.exceptions.Abort:
        sys.stderr.write("tuflexperf: aborted\n")
        sys.exit(130)
    except InputError as exc:
        sys.stderr.write(f"tuflexperf: error: {exc}\n")
        sys.exit(2)
    except NotAttainable as exc:
        sys.stderr.write(f"tuflexperf: not attainable: {exc}\n")
        sys.exit(1)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    sys.exit(code if isinstance(code, int) else 0)
