"""What stands around every command: bad input, an OS refusal or "not attainable" as one
line on stderr and its exit code (SPEC 5), and the flags click would take silently (given
twice, given empty)."""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Iterable
from typing import Any

import typer

from tuflexperf.cli.render import emit_json
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.messages import one_line


def _unless_interrupted() -> None:
    """An error after Ctrl-C or SIGTERM is the interrupt, whatever a library made of it
    (pandas reports an interrupted read as a parse error): exit 130, never "bad input"."""
    from tuflexperf.io.files import interrupted

    if interrupted():
        raise KeyboardInterrupt from None


# SPEC 5's JSON keys of each command: on exit 1 (not attainable) they are there, null
_RESULT_KEYS: dict[str, tuple[str, ...]] = {
    "takeoff": ("ground_roll_m", "liftoff_speed_m_s", "time_s"),
    "trim": ("airspeed_m_s", "throttle", "min_throttle", "max_throttle", "all_feasible"),
    "oei": ("min_throttle", "airspeed_at_min_throttle_m_s", "level_flight_airspeed_range_m_s"),
    "endurance": ("throttle", "airspeed_m_s", "electrical_power_w", "battery_endurance_min",
                  "flight_endurance_min"),
    "performance": ("stall_speed_m_s", "minimum_drag_speed_m_s", "max_level_speed_m_s",
                    "max_climb_rate_m_s", "best_climb_rate_speed_m_s",
                    "best_climb_angle_speed_m_s", "service_ceiling_m", "absolute_ceiling_m",
                    "oei_max_climb_gradient", "takeoff_distance_to_obstacle_m", "climb"),
}


_SYMLINK_LOOP = "Symlink loop from "


def os_error_text(exc: OSError) -> str:
    """One line for an OS error: the file (or place) and why."""
    import errno

    where = exc.filename or _unnamed_os_error_place()
    why = "disk full" if exc.errno == errno.ENOSPC else (exc.strerror or str(exc))
    return one_line(f"{where}: {why}")


def _unnamed_os_error_place() -> str:
    """What an OS error without a file name is about: a working directory that was removed
    (a relative path resolves through it), else the output stream."""
    try:
        os.getcwd()
    except OSError:
        return "the working directory (removed while in use)"
    return "stdout"


def guarded(callback: Any) -> Any:
    """Turn InputError into exit 2 and NotAttainable into exit 1, one line on stderr each."""

    def bad_input(*lines: str) -> typer.Exit:
        """Exit 2 with each line on stderr (an interrupt first stays the interrupt)."""
        _unless_interrupted()
        for line in lines:
            sys.stderr.write(f"tuflexperf: error: {line}\n")
        return typer.Exit(2)

    @functools.wraps(callback)
    def run(*args: Any, **kwargs: Any) -> Any:
        try:
            return callback(*args, **kwargs)
        except InputError as exc:  # every problem found, each on its own line
            raise bad_input(*(one_line(problem) for problem in exc.problems)) from None
        except BrokenPipeError:  # a pipe of the command's own (io.streams guards stdout):
            # no verdict was given, so none is claimed (exit 0 here "passed" `check | head`)
            sys.stderr.write("tuflexperf: error: the output's reader went away\n")
            raise typer.Exit(2) from None
        except OverflowError:  # a number of the input far beyond any aircraft's
            raise bad_input("a number of the input is too large to compute with (floating-"
                            "point overflow); check the magnitudes of the input files' keys "
                            "and of the flags") from None
        except OSError as exc:  # a file the OS refuses (name too long, disk full, ...)
            raise bad_input(os_error_text(exc)) from None
        except RuntimeError as exc:
            # pathlib's resolve() of a symbolic link that leads back to itself (Python < 3.13;
            # later versions raise the OSError above)
            if not str(exc).startswith(_SYMLINK_LOOP):
                raise
            where = str(exc).removeprefix(_SYMLINK_LOOP).strip("'\"")
            raise bad_input(f"{one_line(where)}: symbolic link loop") from None
        except NotAttainable as exc:
            if kwargs.get("as_json"):  # SPEC 5: one JSON object on exit 1 as well
                command = callback.__name__.removesuffix("_command")
                # the command's SPEC keys, null where there is no answer, and what was known
                results = dict.fromkeys(_RESULT_KEYS.get(command, ()))
                if command == "endurance" and kwargs.get("throttle") is not None:
                    results["throttle"] = kwargs["throttle"]
                emit_json({"command": command, "passed": False, "attainable": False,
                           "reason": str(exc), **results, **exc.known})
            sys.stderr.write(f"tuflexperf: not attainable: {one_line(str(exc), None)}\n")
            raise typer.Exit(1) from None

    return run


def repeated_option(params: Iterable[Any], args: list[str]) -> tuple[Any, list[str]] | None:
    """The first option of ``params`` that takes one value and that ``args`` give more than
    once, with the values given, or None (click keeps the last silently: `--throttle 0.5
    --throttle 0.6` flies 0.6). A flag said twice means the same: allowed."""
    by_name = {name: p for p in params if getattr(p, "param_type_name", "") == "option"
               and not (p.multiple or p.count or p.is_flag)
               for name in (*p.opts, *p.secondary_opts)}
    seen: dict[str, list[str]] = {}
    tokens = iter(args)
    for token in tokens:
        if token == "--":  # what follows is arguments, not options
            break
        name, equals, value = token.partition("=")
        option = by_name.get(name if name.startswith("--") else token)
        if option is None:  # an argument, a flag, or an option that repeats
            continue
        if not equals:
            value = next(tokens, "")
        given = seen.setdefault(option.name, [])
        given.append(value)
        if len(given) > 1:
            return option, given
    return None


def refuse_repeated(app: typer.Typer, args: list[str]) -> None:
    """Exit 2 naming an option that takes one value and is given twice (see
    :func:`repeated_option`); the command's parameters are looked at only then (a custom
    command class for it cost every `check` ~20 ms)."""
    named = [token.partition("=")[0] for token in args if token.startswith("-")]
    if not args or len(named) == len(set(named)):
        return
    command = getattr(typer.main.get_command(app), "commands", {}).get(args[0])
    found = None if command is None else repeated_option(command.params, args[1:])
    if found is not None:
        option, given = found
        sys.stderr.write(f"tuflexperf: error: Invalid value for '{option.opts[0]}': given "
                         f"twice ({one_line(', '.join(given))}); give it once\n")
        sys.exit(2)


def refuse_empty(args: list[str]) -> None:
    """Exit 2 naming an option (or argument) given an empty value: ``--case=`` or ``--case ''``
    is not the path '.' ("is a directory")."""
    for k, token in enumerate(args):
        if token == "--":
            return
        name, equals, value = token.partition("=")
        if token.startswith("--") and equals and not value:
            empty = name
        elif token == "":
            before = args[k - 1] if k > 0 else ""
            empty = before if before.startswith("-") and "=" not in before else "an argument"
        else:
            continue
        what = (f"Invalid value for '{empty}': empty" if empty.startswith("-")
                else "an empty argument")
        sys.stderr.write(f"tuflexperf: error: {what}; give a value\n")
        sys.exit(2)



def case_hint(message: str, argv: list[str] | None) -> str:
    """For ``report case.yaml``: only ``check`` and ``mission`` take a file by position."""
    args = sys.argv[1:] if argv is None else argv
    if not message.startswith("Got unexpected extra argument") or "--case" in args:
        return ""
    # the argument refused, as the message names it (`mission M.yaml CASE.yaml`: CASE.yaml)
    named = message.rpartition("(")[2].partition(")")[0].split()
    extra = next((a for a in (*named, *args[1:]) if a.lower().endswith((".yaml", ".yml"))),
                 None)
    return "" if extra is None else f": give the case file with --case {extra}"
