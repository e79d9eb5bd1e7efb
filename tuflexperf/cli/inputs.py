"""What every command reads from its flags: the shared options, ``--set``, output paths,
the case with its overrides, and the one-line exit 2 of bad input (SPEC 5)."""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import typer

from tuflexperf.errors import InputError
from tuflexperf.messages import one_line

CaseOption = typer.Option(None, "--case", help="Requirement file (default: shipped TU-Flex case).")
JsonOption = typer.Option(False, "--json", metavar="", help="Print one JSON object on stdout.")
SetOption = typer.Option(
    None, "--set", metavar="KEY=VALUE",
    help="Change one numeric key of the case for this run (repeatable), e.g. "
    "aircraft.mass_kg=25 or atmosphere.altitude_m=1500; validated like the files.",
)

SamplesOption = typer.Option(
    None, "--samples", help="Monte Carlo samples (default: the case's uncertainty block)."
)
SeedOption = typer.Option(None, "--seed", help="Seed of the samples (default: the block's, or 1).")
WorkersOption = typer.Option(
    None, "--workers", help="Run sample/sweep chunks in N local processes."
)
DaskOption = typer.Option(
    None, "--dask", help="Send sample/sweep chunks to a Dask scheduler (tcp://HOST:PORT)."
)
# a file the case names, replaced for this run (relative to the working directory)
AircraftFileOption = typer.Option(
    None, "--aircraft", metavar="<path>",
    help="Aircraft file to use instead of the one the case names (this run only).",
)
PropulsionFileOption = typer.Option(
    None, "--propulsion", metavar="<path>",
    help="Propulsion file to use instead of the one the case names (this run only).",
)
BatteryFileOption = typer.Option(
    None, "--battery", metavar="<path>",
    help="Battery file to use instead of the one the case names (this run only).",
)


def replaced(aircraft: Path | None, propulsion: Path | None, battery: Path | None
             ) -> dict[str, Path]:
    """The files ``--aircraft``, ``--propulsion`` and ``--battery`` give, by the case's key."""
    given = (("aircraft", aircraft), ("propulsion", propulsion), ("battery", battery))
    return {key: path for key, path in given if path is not None}


def fail_input(message: str) -> None:
    """Bad input: one line on stderr, exit 2."""
    sys.stderr.write(f"tuflexperf: error: {one_line(message)}\n")
    raise typer.Exit(2)


def parse_sets(sets: list[str] | None) -> dict[str, float]:
    """Every ``--set KEY=VALUE`` as ``{key: number}`` (bad input names the flag).

    The value is a plain decimal number as Python reads it (``20``, ``0.5``, ``1e3``): read
    as YAML, a comment, an anchor or a tag after it (``020 # twenty``, ``!!int 020``) would
    take ``020`` as octal 16 past the check below.
    """
    from tuflexperf.io.yamlio import ambiguous_number

    def shown(text: str) -> str:  # a 5000-digit value is not echoed whole
        return repr(text if len(text) <= 60 else text[:57] + "...")

    values: dict[str, float] = {}
    for item in sets or []:
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            fail_input(f"--set: expected KEY=VALUE, got {shown(item)}")
        odd = ambiguous_number(text)
        if odd is not None:  # as in the files: 020 is no limit of 16
            fail_input(f"--set: {key}: {odd.problem()}")
        try:
            value = float(text)
        except ValueError:
            fail_input(f"--set: {key}: not a number: {shown(text)}")
        if not math.isfinite(value):
            fail_input(f"--set: {key}: not a finite number: {shown(text)}")
        if key.strip() in values:  # given twice: the last would win, silently
            fail_input(f"--set: {key.strip()} given twice ({values[key.strip()]:g} and "
                       f"{value:g}); give each key once")
        values[key.strip()] = value
    return values


def refuse_empty_address(dask: str | None) -> None:
    """``--dask ''`` would run locally without a word: an address is needed."""
    if dask is not None and not dask.strip():
        fail_input("--dask: empty address; give the scheduler's tcp://HOST:PORT, or leave "
                   "--dask out to run here")


def output_file(value: str | None, flag: str) -> Path | None:
    """A file output's path as given; one that ends in a separator names a folder (as a
    ``Path`` it lost the slash, and ``--csv newdir/`` wrote a file named ``newdir``)."""
    if value is None:
        return None
    refuse_dash(value, flag)
    if value.endswith(("/", "\\")) or value in ("", ".", ".."):
        fail_input(f"{flag}: {value!r} names a folder; give a file name")
    return Path(value)


def refuse_dash(value: str, flag: str) -> None:
    """An output named ``-`` or ``-...``: the shell's stdout, or the next option taken as
    the path (``--csv --json`` would write a file named --json)."""
    if value == "-":
        fail_input(f"{flag}: '-' (stdout) is no file name; give a path, and --json for JSON "
                   "on stdout")
    if value.startswith("-"):
        fail_input(f"{flag}: {one_line(value)!r} looks like an option, not a path (the value "
                   f"is missing?); for a file of that name give ./{one_line(value)}")


def load_case_with(case_file: Path | None, sets: list[str] | None,
                   replace: dict[str, Path] | None = None) -> Any:
    """The case, with the files ``replace`` gives (:func:`replaced`) read instead of the ones
    it names, and every ``--set KEY=VALUE`` applied and validated by the schemas."""
    from tuflexperf.io.case import load_case

    case = load_case(case_file, replace)
    if not sets:
        return case
    from tuflexperf.io.dotted import with_values

    return with_values(case, parse_sets(sets), "--set")



def sweep_case(case_file: Path | None, sets: list[str] | None, vary: list[str],
               replace: dict[str, Path] | None = None) -> tuple[Any, list[tuple[str, Any]]]:
    """The sweep's nominal case and its axes.

    The grid gives a varied key its values: a ``--set`` of that key is not used (a note says
    so), so a nominal that only such a value, or a ``--set`` crossing the grid's own key
    (a maximum below the file's minimum, where the minimum is varied), makes bad input is
    taken at the grid's first point instead; it was refused though every point was valid.
    """
    from tuflexperf.analysis.sweep import parse_vary
    from tuflexperf.io.case import load_case
    from tuflexperf.io.dotted import with_values

    values = parse_sets(sets)
    base = load_case(case_file, replace)
    axes = [parse_vary(base, spec) for spec in vary]
    if not values:
        return base, axes
    try:
        return with_values(base, values, "--set"), axes
    except InputError as refused:
        first = {key: float(grid[0]) for key, grid in axes}
        kept = {key: value for key, value in values.items() if key not in first}
        try:
            return with_values(base, {**kept, **first}, "--set"), axes
        except InputError:
            raise refused from None


def batch_notes(case: Any, varied: list[str], sets: list[str] | None) -> list[str]:
    """What a batch (sweep, margins) leaves out or overrides, said: the
    mission requirement is flown for the nominal case only, and a --set on a varied key is
    replaced by the grid's values."""
    notes = []
    if case.requirements.mission is not None:
        notes.append("mission_landing_charge is not in the batch: a mission is flown for the "
                     "nominal case only (check gives its verdict)")
    notes += [f"--set {key}: the grid varies it (the --set value is not used)"
              for key in set_keys(sets) if key in varied]
    return notes + scaled_pack_notes([*varied, *set_keys(sets)])


SCALED_PACK_NOTE = (
    "battery.capacity_ah: a capacity other than the battery file's flies the measured pack "
    "scaled (as capacity/measured packs in parallel: charge x the ratio, resistance / the "
    "ratio; no run measured such a pack), and the aircraft's mass is as given"
)


def scaled_pack_notes(keys: Iterable[str]) -> list[str]:
    """The scaled-pack note where ``keys`` (varied, drawn or set) hold the pack's capacity."""
    return [SCALED_PACK_NOTE] if "battery.capacity_ah" in keys else []


def set_keys(sets: list[str] | None) -> list[str]:
    """The dotted keys of ``--set KEY=VALUE`` items (their values are load_case_with's)."""
    return [item.split("=", 1)[0].strip() for item in sets or []]



def refuse_implausible(case: Any, command: str, block: str | None, as_json: bool,
                       varied: Iterable[str] = ()) -> None:
    """Exit 1 with the plausibility reasons that bear on requirement ``block`` (all of them
    with None): the single-analysis commands give the verdict ``check`` gives on the same
    data (:func:`tuflexperf.analysis.plausibility.implausible`, issue 43 item 3). A sweep
    that ``varied`` the capacity has the packs' rating judged per point (the batch)."""
    from tuflexperf.analysis.plausibility import implausible
    from tuflexperf.cli.render import show_implausible

    per_point = {"battery_rating"} if "battery.capacity_ah" in set(varied) else set()
    found = [f for f in implausible(case) if (block is None or block in f.blocks)
             and f.rule not in per_point]
    if found:
        from tuflexperf.cli.guard import _RESULT_KEYS

        # SPEC 5: the command's own keys are there on exit 1 too, null (no answer stands)
        keys: dict[str, Any] = dict.fromkeys(_RESULT_KEYS.get(command, ()))
        if command == "mission":
            keys.update(landing_charge_fraction=None, segments=[])
        show_implausible(command, found, as_json, keys)
        raise typer.Exit(1)
