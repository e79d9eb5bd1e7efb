"""Command line: parses, calls the analyses, renders. No physics here.

Exit codes (SPEC 5): 0 done / all met, 1 not met or not attainable, 2 bad input.
"""

from __future__ import annotations

import functools
import json
import math
import os
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import typer

from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.messages import one_line

app = typer.Typer(
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


CaseOption = typer.Option(None, "--case", help="Requirement file (default: shipped TU-Flex case).")
JsonOption = typer.Option(False, "--json", metavar="", help="Print one JSON object on stdout.")
SetOption = typer.Option(
    None, "--set", metavar="KEY=VALUE",
    help="Change one numeric key of the case for this run (repeatable), e.g. "
    "aircraft.mass_kg=25 or atmosphere.altitude_m=1500; validated like the files.",
)


def parse_sets(sets: list[str] | None) -> dict[str, float]:
    """Every ``--set KEY=VALUE`` as ``{key: number}`` (bad input names the flag).

    The value is a plain decimal number as Python reads it (``20``, ``0.5``, ``1e3``): read
    as YAML, a comment, an anchor or a tag after it (``020 # twenty``, ``!!int 020``) took
    ``020`` as octal 16 past the check below (outside audit).
    """
    from tuflexperf.io.yamlio import ambiguous_number

    def shown(text: str) -> str:  # a 5000-digit value was echoed whole (outside audit)
        return repr(text if len(text) <= 60 else text[:57] + "...")

    values: dict[str, float] = {}
    for item in sets or []:
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            fail_input(f"--set: expected KEY=VALUE, got {shown(item)}")
        odd = ambiguous_number(text)
        if odd is not None:  # as in the files: 020 was a limit of 16 (outside audit)
            fail_input(f"--set: {key}: {odd.problem()}")
        try:
            value = float(text)
        except ValueError:
            fail_input(f"--set: {key}: not a number: {shown(text)}")
        if not math.isfinite(value):
            fail_input(f"--set: {key}: not a finite number: {shown(text)}")
        if key.strip() in values:  # the last one won, silently (outside audit)
            fail_input(f"--set: {key.strip()} given twice ({values[key.strip()]:g} and "
                       f"{value:g}); give each key once")
        values[key.strip()] = value
    return values


def refuse_empty_address(dask: str | None) -> None:
    """``--dask ''`` ran locally without a word (outside audit): an address is needed."""
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
    the path (``--csv --json`` wrote a file named --json, ``export --out -`` a folder named
    -, and a later ``--case --json`` read it; outside audit)."""
    if value == "-":
        fail_input(f"{flag}: '-' (stdout) is no file name; give a path, and --json for JSON "
                   "on stdout")
    if value.startswith("-"):
        fail_input(f"{flag}: {one_line(value)!r} looks like an option, not a path (the value "
                   f"is missing?); for a file of that name give ./{one_line(value)}")


def load_case_with(case_file: Path | None, sets: list[str] | None) -> Any:
    """The case, with every ``--set KEY=VALUE`` applied and validated by the schemas."""
    from tuflexperf.io.case import load_case

    case = load_case(case_file)
    if not sets:
        return case
    from tuflexperf.io.dotted import with_values

    return with_values(case, parse_sets(sets), "--set")


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
    sys.stderr.write(f"tuflexperf: error: {one_line(message)}\n")
    raise typer.Exit(2)


# ---- performance core: check, takeoff, trim, oei (issue 2) ---------------------------------


def _echo_electrical(electrical: dict[str, Any] | None) -> None:
    """fit's voltage, power-surface, windmilling and thrust/power lines (logged V and I)."""
    if not electrical or electrical.get("reference_voltage_v") is None:
        return
    fits = electrical["voltage_fits"]
    per_engine = ", ".join(
        f"{name} {_fmt(f['exponent'], 3)} +- {_fmt(f['standard_error'], 3)}"
        for name, f in fits.items()
    )
    exponent = electrical["voltage_exponent"]
    typer.echo(
        f"pack voltage: reference {electrical['reference_voltage_v']:g} V; thrust ~ (U/U_ref)^n, "
        + (f"n = {exponent:.3f} ({per_engine}); thrust brought to U_ref"
           if exponent is not None else f"n not determined ({per_engine}); default 2")
    )
    for name, power in electrical["power"].items():
        typer.echo(f"power surface {name}: poly22 in W, R^2 {_fmt(power['r2'], 4)}, "
                   f"RMSE {_fmt(power['rmse_w'], 0)} W over {power['n_points']} points")
    for name, wm in electrical["windmilling"].items():
        typer.echo(f"windmilling {name}: Cd {wm['windmilling_drag_coefficient']:.3f} on the fan "
                   f"area, rms {wm['rms_n']:.2f} N over {wm['n_points']} idle points")
    for name, agree in electrical["thrust_power_agreement"].items():
        merit, eff = agree["figure_of_merit_range"], agree["overall_efficiency_range"]
        if merit:
            typer.echo(
                f"thrust vs power {name}: figure of merit {merit[0]:.2f}-{merit[1]:.2f}"
                + (f", overall efficiency {eff[0]:.2f}-{eff[1]:.2f}" if eff else "")
                + f" over {agree['working_points']} working points"
            )


def _fmt(value: float | None, digits: int = 3) -> str:
    # NaN is what a result holds where no value exists (an arc beyond cl_max): never printed
    return "n/a" if value is None or value != value else f"{value:.{digits}f}"


def _print_warnings(warnings: list[str]) -> None:
    for line in warnings:
        typer.echo(f"  note: {line}")


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


@app.command()
def check(
    case_file: Path | None = typer.Argument(None, help="Requirement file (default: TU-Flex)."),
    case_option: Path | None = typer.Option(
        None, "--case", help="Requirement file (the same as the argument)."
    ),
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    samples: int | None = SamplesOption,
    seed: int | None = SeedOption,
    workers: int | None = WorkersOption,
    dask: str | None = DaskOption,
) -> None:
    """Verify every requirement in the case: value, limit, margin, PASS/FAIL."""
    from tuflexperf.analysis.requirements import CHECKS, check_case, sampled_result

    if case_file is not None and case_option is not None and case_file != case_option:
        fail_input("--case: give the case once, as the argument or as --case, not both")
    case_file = case_file if case_file is not None else case_option

    case = load_case_with(case_file, sets)
    if workers is not None and workers < 1:
        fail_input(f"--workers: must be at least 1, got {workers}")
    if seed is not None and seed < 0:
        fail_input(f"--seed: must be >= 0, got {seed}")
    if all(getattr(case.requirements, name) is None for name in CHECKS):
        # a check of nothing is no PASS: the blocks may all have been commented out
        fail_input(f"{case.path}: requirements: none stated, nothing to verify (give at least "
                   f"one of {', '.join(CHECKS)})")
    refuse_empty_address(dask)
    sampling = samples is not None or case.uncertainty is not None
    for flag, value in (("--seed", seed), ("--workers", workers), ("--dask", dask)):
        if value is not None and not sampling:  # it would change nothing: say so
            fail_input(f"{flag}: nothing is sampled (give --samples N, or an uncertainty: "
                       "block in the case)")
    verdicts = check_case(case)
    probabilistic: dict[str, Any] = {}
    outside: dict[str, int] = {}
    plan = None
    sample_notes: list[str] = []
    if sampling:
        from tuflexperf.analysis.requirements import probabilistic_verdicts
        from tuflexperf.analysis.uncertainty import (
            ENVELOPE_KEY,
            REFUSED_AIRCRAFT_KEY,
            plan_for,
            run_samples,
        )

        plan = plan_for(case, samples, seed)
        drawn = {key for key, _, _ in plan.parameters}
        # the deterministic row takes --set, the samples the block
        sample_notes += [f"--set {key}: the samples draw it from the uncertainty block "
                         "(the deterministic value uses --set)"
                         for key in _set_keys(sets) if key in drawn]
        sample_notes += _scaled_pack_notes([*drawn, *_set_keys(sets)])
        sample_set = run_samples(case, plan, workers, dask)
        probabilistic = probabilistic_verdicts(sample_set)
        outside = {k: n for k, n in sample_set.outside_bounds.items() if n}
    # with samples, each result's verdict is the nominal one and P(met) shown together
    results = [sampled_result(v, probabilistic.get(v.name)) if sampling else v.to_dict()
               for v in verdicts]
    passed = all(r["passed"] for r in results)
    if as_json:
        payload: dict[str, Any] = {
            "case": case.name,
            "case_file": str(case.path),
            "passed": passed,
            "results": results,
        }
        if plan is not None:
            payload["uncertainty"] = {**plan.to_dict(), "samples_outside_bounds": outside,
                                      "notes": sample_notes}
        emit_json(payload)
    else:
        typer.echo(f"{case.name}  ({case.path})")
        w = _name_width(v.name for v in verdicts)
        header = (f"{'requirement':<{w}}{'value':>10}{'limit':>10}{'unit':>10}{'margin':>10}"
                  "  verdict")
        typer.echo(header)
        typer.echo("-" * len(header))
        for v in verdicts:
            typer.echo(
                f"{v.name:<{w}}{_cell(_fmt(v.value))}{_cell(_fmt(v.limit))}{_cell(v.unit)}"
                f"{_cell(_fmt(v.margin))}  {'PASS' if v.passed else 'FAIL'}"
            )
            typer.echo(f"  {v.reason}")
            _print_warnings(v.details.get("warnings", []))
        if plan is not None:
            _print_probabilities(plan, probabilistic)
            for r in results:
                if "probability_note" in r:
                    typer.echo(f"{r['name']:<{_name_width(probabilistic)}}  FAIL  "
                               f"{r['probability_note']}")
            for key, count in outside.items():
                what = {
                    ENVELOPE_KEY: "have no envelope (the least airspeed not below the greatest, "
                    "or the greatest beyond the speed of sound); trim and OEI count them as "
                    "not met",
                    REFUSED_AIRCRAFT_KEY: "are aircraft check refuses (a full-throttle static "
                    "thrust not positive or above 10 x the weight: physically absurd; a stall "
                    "beyond the speed of sound; a release or lift-off speed below stall; "
                    "cl_ground above cl_max); they count as not met",
                }.get(key, f"of {key} fall outside its valid range; they count as not met")
                typer.echo(f"  note: {count} samples {what}")
            for note in sample_notes:
                typer.echo(f"  note: {note}")
        typer.echo(f"overall: {'PASS' if passed else 'FAIL'}")
    raise typer.Exit(0 if passed else 1)


def _cell(text: str, width: int = 10) -> str:
    """Right-aligned in ``width``; a longer value keeps a space before it (never run on)."""
    return text.rjust(width) if len(text) < width else " " + text


def _name_width(names: Iterable[str]) -> int:
    """Width of the requirement column: 22, or the longest name and two spaces."""
    return max([22, *(len(n) + 2 for n in names)])


def _print_probabilities(plan: Any, probabilistic: dict[str, Any]) -> None:
    typer.echo("")
    typer.echo(
        f"Monte Carlo: {plan.samples} samples, seed {plan.seed}; a requirement passes when the "
        f"95 % interval of P(met) lies at or above {plan.required_probability:g}"
    )
    w = _name_width(probabilistic)
    header = (f"{'requirement':<{w}}{'P(met)':>8}{'95 % CI':>17}{'p05':>10}{'p50':>10}"
              f"{'p95':>10}{'n/a':>7}  verdict")
    typer.echo(header)
    typer.echo("-" * len(header))
    for name, p in probabilistic.items():
        low, high = p.probability_ci
        p05, p50, p95 = p.quantiles
        typer.echo(
            f"{name:<{w}}{p.probability:>8.4f}{f'[{low:.4f}, {high:.4f}]':>17}{_fmt(p05):>10}"
            f"{_fmt(p50):>10}{_fmt(p95):>10}{p.not_attainable:>7}  "
            f"{'PASS' if p.passed else 'FAIL'}"
        )
    typer.echo("  (n/a: samples where the requirement is not attainable; they count as not met "
               "and as the worst value, so a percentile that falls on them shows n/a)")


@app.command()
def margins(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
) -> None:
    """Per requirement and parameter: the value where it just holds, and d(value)/d(parameter)."""
    from tuflexperf.analysis.margins import extrapolation_notes, solve_margins

    case = load_case_with(case_file, sets)
    rows = solve_margins(case)
    notes = (extrapolation_notes(rows, case.propulsion.tested_airspeed_m_s)
             + _batch_notes(case, [], None) + _scaled_pack_notes({m.parameter for m in rows}))
    if as_json:
        emit_json({"case": case.name, "case_file": str(case.path),
                   "margins": [m.to_dict() for m in rows], "notes": notes})
        return
    typer.echo(f"{case.name}  ({case.path})")
    typer.echo("limit value: the parameter's value (others nominal) where the requirement "
               "just holds, nearest the nominal; sensitivity by CasADi AD")
    header = (f"{'requirement':<30}{'parameter':<40}{'nominal':>11}{'limit value':>13}"
              f"{'sensitivity':>13}")
    current = None
    for m in rows:
        if m.requirement != current:
            current = m.requirement
            typer.echo("")
            typer.echo(header)
            typer.echo("-" * len(header))
        if m.limit_value is None:
            limit = "none"
        else:
            limit = f"{m.limit_value:.5g}" + {"not attainable": "*", "envelope ends": "^",
                                               "aircraft refused": "#"}.get(m.binds, "")
        slope = "n/a" if m.sensitivity is None else f"{m.sensitivity:.4g}"
        typer.echo(f"{m.requirement:<30}{m.parameter:<40}{m.value:>11.5g}{limit:>13}"
                   f"{slope:>13}")
    typer.echo("")
    typer.echo("none: never binds in the searched range (0.5x-2x the nominal; altitude "
               "-500..5000 m, temperature offset -50..50 K); *: binds by becoming not attainable")
    if any(m.binds == "aircraft refused" for m in rows):
        typer.echo("#: where check refuses the aircraft as bad input (a lift-off or catapult "
                   "release below stall, a stall beyond the speed of sound, thrust above 10 x "
                   "the weight, cl_ground above cl_max): the search ends there")
    if any(m.binds == "envelope ends" for m in rows):
        typer.echo("^: where the envelope's bounds cross (an equivalent-airspeed bound at that "
                   "density): beyond it the case has no envelope to fly")
    for note in notes:
        typer.echo(f"note: {note}")


@app.command()
def sweep(
    vary: list[str] = typer.Option(..., "--vary", help="KEY=START:STOP:N (repeatable)."),
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    csv_text: str | None = typer.Option(None, "--csv", metavar="<path>",
                                        help="Write the grid as CSV here."),
    plot_text: str | None = typer.Option(None, "--plot", metavar="<path>",
                                         help="Write a carpet plot (PNG) here."),
    workers: int | None = WorkersOption,
    dask: str | None = DaskOption,
) -> None:
    """Every requirement over a grid of parameter values."""
    from tuflexperf.analysis.sweep import run_sweep
    from tuflexperf.io.files import write_files_atomically

    if workers is not None and workers < 1:
        fail_input(f"--workers: must be at least 1, got {workers}")
    refuse_empty_address(dask)
    csv_out, plot = output_file(csv_text, "--csv"), output_file(plot_text, "--plot")
    case, axes = _sweep_case(case_file, sets, vary)
    outputs = {flag: target for flag, target in (("--csv", csv_out), ("--plot", plot))
               if target is not None}
    if plot is not None and plot.suffix.lower() != ".png":
        fail_input(f"--plot {plot}: the carpet plot is written as PNG (use .png)")
    if outputs:
        from tuflexperf.io.case import case_files
        from tuflexperf.io.files import guard_outputs

        guard_outputs(outputs, [path for _, path in case_files(case)], "sweep",
                      {"--csv": "sweep grid", "--plot": "sweep plot"})
    result = run_sweep(case, axes, workers, dask)
    notes = (result.extrapolation_notes(case.propulsion.tested_airspeed_m_s)
             + _batch_notes(case, [key for key, _ in axes], sets))
    written: dict[Path, bytes | str] = {}
    if plot is not None:
        from tuflexperf.report.sweep_plot import carpet_png

        written[plot] = carpet_png(result, f"{case.name}: sweep")
    if csv_out is not None:
        written[csv_out] = result.to_csv()
    if written:  # both or neither: an interrupt between them left a new plot by an old CSV
        write_files_atomically(written)
    if as_json:
        emit_json({"case": case.name, "case_file": str(case.path), **result.to_dict(),
                   "notes": notes})
        return
    names = list(result.values)
    # each parameter column as wide as its name and a space (max_airspeed_m_s ran into the next)
    widths = [max(16, len(k.split(".")[-1]) + 2) for k in result.parameters]
    header = "".join(f"{k.split('.')[-1]:>{w}}" for k, w in zip(result.parameters, widths,
                                                                 strict=True)) + "".join(
        f"{n:>30}" for n in names)
    typer.echo(f"{case.name}  ({case.path}): {result.points.shape[0]} grid points")
    typer.echo(header)
    typer.echo("-" * len(header))
    for i in range(result.points.shape[0]):
        cells = "".join(f"{v:>{w}.5g}" for v, w in zip(result.points[i], widths, strict=True))
        for n in names:
            value = result.values[n][i]
            text = "not attainable" if not np.isfinite(value) else f"{value:.4g}"
            cells += f"{text + (' PASS' if result.met[n][i] else ' FAIL'):>30}"
        typer.echo(cells)
    for target in (csv_out, plot):
        if target is not None:
            typer.echo(f"wrote {target}")
    for note in notes:
        typer.echo(f"  note: {note}")


def _sweep_case(case_file: Path | None, sets: list[str] | None, vary: list[str]
                ) -> tuple[Any, list[tuple[str, Any]]]:
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
    base = load_case(case_file)
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


def _batch_notes(case: Any, varied: list[str], sets: list[str] | None) -> list[str]:
    """What a batch (sweep, margins) leaves out or overrides, said (outside audit): the
    mission requirement is flown for the nominal case only, and a --set on a varied key is
    replaced by the grid's values."""
    notes = []
    if case.requirements.mission is not None:
        notes.append("mission_landing_charge is not in the batch: a mission is flown for the "
                     "nominal case only (check gives its verdict)")
    notes += [f"--set {key}: the grid varies it (the --set value is not used)"
              for key in _set_keys(sets) if key in varied]
    return notes + _scaled_pack_notes([*varied, *_set_keys(sets)])


SCALED_PACK_NOTE = (
    "battery.capacity_ah: a capacity other than the battery file's flies the measured pack "
    "scaled (as capacity/measured packs in parallel: charge x the ratio, resistance / the "
    "ratio; no run measured such a pack), and the aircraft's mass is as given"
)


def _scaled_pack_notes(keys: Iterable[str]) -> list[str]:
    """The scaled-pack note where ``keys`` (varied, drawn or set) hold the pack's capacity."""
    return [SCALED_PACK_NOTE] if "battery.capacity_ah" in keys else []


def _set_keys(sets: list[str] | None) -> list[str]:
    """The dotted keys of ``--set KEY=VALUE`` items (their values are load_case_with's)."""
    return [item.split("=", 1)[0].strip() for item in sets or []]


@app.command()
def takeoff(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
) -> None:
    """Take-off at full throttle: ground roll, rotation, transition arc, climb to the obstacle."""
    from tuflexperf.analysis.requirements import takeoff_verdicts
    from tuflexperf.analysis.takeoff import solve_takeoff

    case = load_case_with(case_file, sets)
    result = solve_takeoff(case)
    requirement = case.requirements.takeoff
    verdicts = takeoff_verdicts(requirement, result) if requirement is not None else []
    met = all(v.passed for v in verdicts)
    if as_json:
        payload = result.to_dict()
        if requirement is not None:
            payload["max_ground_roll_m"] = requirement.max_ground_roll_m
            payload["max_distance_to_obstacle_m"] = requirement.max_distance_to_obstacle_m
            payload["passed"] = met
            payload["results"] = [v.to_dict() for v in verdicts]
        emit_json(payload)
    else:
        r = result
        catapult = r.launch == "catapult"
        typer.echo(f"{case.name}: take-off at full throttle ({r.density_kg_m3:.4f} kg/m^3)"
                   + (", catapult launch" if catapult else ""))
        typer.echo(
            f"  {'release speed ' if catapult else 'lift-off speed'}     "
            f"{r.liftoff_speed_m_s:8.2f} m/s  "
            f"({r.liftoff_speed_eas_m_s:.2f} m/s EAS; stall {r.stall_speed_m_s:.2f} m/s)"
        )
        if catapult and r.acceleration_distance_m > 0.0:  # level, before the arc
            typer.echo(f"  acceleration       {r.acceleration_distance_m:8.2f} m  (level, "
                       f"{r.liftoff_speed_m_s:.2f} -> {r.transition_speed_m_s:.2f} m/s)")
        if not catapult:  # a catapult has no runway: nothing rolls
            typer.echo(f"  acceleration       {r.acceleration_distance_m:8.2f} m")
            typer.echo(
                f"  rotation           {r.rotation_distance_m:8.2f} m  ({r.rotation_time_s:g} s)"
            )
        typer.echo(f"  ground roll        {r.ground_roll_m:8.2f} m  in {r.time_s:.2f} s")
        typer.echo(
            f"  transition arc     {_fmt(r.transition_distance_m, 2):>8} m  "
            f"(R {r.transition_radius_m:.1f} m at {r.transition_speed_m_s:.2f} m/s, "
            f"n {r.transition_load_factor:g})"
        )
        angle = r.climb_angle_deg
        typer.echo(
            f"  climb              {_fmt(r.climb_distance_m, 2):>8} m  (gradient "
            f"{r.climb_gradient:.3f}" + ("" if angle is None else f", {angle:.1f} deg")
            + (": thrust above weight plus drag, a vertical climb" if r.climb_gradient >= 1.0
               else "") + ")"
        )
        typer.echo(
            f"  to {r.obstacle_height_m:g} m obstacle  {_fmt(r.distance_to_obstacle_m, 2):>8} m"
            + ("  (cleared in the arc)" if r.obstacle_cleared_in_transition else "")
        )
        if r.obstacle_reason:
            typer.echo(f"  {r.obstacle_reason}")
        for v in verdicts:
            typer.echo(
                f"  {v.name:<30} {_fmt(v.value, 2)} <= {v.limit:g} m  "
                f"{'PASS' if v.passed else 'FAIL'}"
            )
        _print_warnings(list(result.warnings))
    raise typer.Exit(0 if met else 1)


def _throttle_table(
    airspeeds: list[float], throttles: list[float | None], reasons: list[str | None]
) -> None:
    typer.echo(f"  {'airspeed m/s':>12}  {'throttle':>8}")
    for v, x, why in zip(airspeeds, throttles, reasons, strict=True):
        typer.echo(f"  {v:12.1f}  {f'  not attainable: {why}' if x is None else f'{x:8.3f}'}")


@app.command()
def trim(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    table: bool = typer.Option(
        False, "--table", metavar="", help="Print the throttle at every airspeed."
    ),
) -> None:
    """Least throttle for level flight at each airspeed of the envelope (0.5 m/s grid)."""
    from tuflexperf.analysis.trim import solve_trim

    case = load_case_with(case_file, sets)
    result = solve_trim(case)
    data = result.to_dict()
    from tuflexperf.analysis.requirements import trim_verdict

    if case.requirements.envelope is None:
        fail_input(f"{case.path}: requirements.envelope: trim needs the envelope requirement")
    limit = case.requirements.envelope.max_trim_throttle
    verdict = trim_verdict(case.requirements.envelope, result)  # the one verdict rule
    met = verdict.passed
    if as_json:
        emit_json({**data, "max_trim_throttle": limit, "passed": met})
    else:
        v = data["airspeed_m_s"]
        typer.echo(f"{case.name}: trim over {v[0]:.4g}-{v[-1]:.4g} m/s ({len(v)} airspeeds)")
        if result.min_throttle is None:
            typer.echo("  least throttle   none: level flight attainable nowhere in the envelope")
        else:
            typer.echo(
                f"  least throttle   {result.min_throttle:.3f} at "
                f"{result.airspeed_at_min_throttle_m_s:.1f} m/s"
            )
        typer.echo(f"  highest throttle {_fmt(result.max_throttle)} (limit {limit:g})")
        typer.echo(
            f"  stall {result.stall_speed_m_s:.2f} m/s x {result.stall_margin:g}; level flight "
            + ("nowhere in the envelope" if result.attainable.low is None else
               f"{result.attainable.low:.2f}-{result.attainable.high:.2f} m/s")
        )
        if not result.all_feasible:
            from tuflexperf.analysis.attainable import describe_unattainable

            for phrase in describe_unattainable(result.airspeed_m_s, result.reasons):
                typer.echo(f"  NOT ATTAINABLE: {phrase}")
        if table:
            _throttle_table(v, data["throttle"], data["not_attainable_reason"])
        _print_warnings(data["warnings"])
        # the verdict and why, as take-off and OEI print theirs (SPEC 5: exit 1 says why)
        why = (verdict.reason if verdict.value is None else
               f"highest throttle {verdict.value:.3f} above the limit {limit:g}")
        typer.echo(f"  {verdict.name}: {'PASS' if met else 'FAIL'}"
                   + ("" if met else f" ({why})"))
    raise typer.Exit(0 if met else 1)


@app.command()
def oei(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    dead_engine: str | None = typer.Option(
        None, "--dead-engine", help="windmilling or zero (default: the case's oei block)."
    ),
) -> None:
    """Level flight with one engine inoperative; each engine dead in turn, worse case."""
    from tuflexperf.analysis.oei import solve_oei

    dead_engine = dead_engine.lower() if dead_engine is not None else None
    if dead_engine is not None and dead_engine not in ("windmilling", "zero"):
        fail_input(f"--dead-engine: must be windmilling or zero, got {dead_engine!r}")
    case = load_case_with(case_file, sets)
    result = solve_oei(case, dead_engine)  # type: ignore[arg-type]
    data = result.to_dict()
    requirement = case.requirements.oei
    limit = requirement.max_throttle if requirement is not None else 1.0
    worst = result.critical
    from tuflexperf.analysis.requirements import oei_verdict

    met = oei_verdict(requirement, result).passed  # the one verdict rule
    if as_json:
        emit_json({**data, "max_throttle": limit, "passed": met})
    else:
        typer.echo(f"{case.name}: one engine inoperative ({result.dead_engine_mode} dead engine)")
        for c in result.cases:
            span = c.level_flight_airspeed_range_m_s
            typer.echo(
                f"  {c.dead_engine} dead: level flight attainable nowhere in the envelope"
                if span is None else
                f"  {c.dead_engine} dead: least throttle {_fmt(c.min_throttle)} at "
                f"{_fmt(c.airspeed_at_min_throttle_m_s, 1)} m/s; level flight "
                f"{span[0]:.2f}-{span[1]:.2f} m/s"
            )
            if c.min_throttle is None or not c.all_feasible:
                from tuflexperf.analysis.attainable import describe_unattainable

                for phrase in describe_unattainable(c.airspeed_m_s, c.reasons):
                    typer.echo(f"    not attainable: {phrase}")
        typer.echo(
            f"  worse case: {worst.dead_engine} dead, "
            + ("not attainable" if worst.min_throttle is None
               else f"throttle {_fmt(worst.min_throttle)}")
            + f" (limit {limit:g})  {'PASS' if met else 'FAIL'}"
        )
        _print_warnings(data["warnings"])
    raise typer.Exit(0 if met else 1)


@app.command()
def performance(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
) -> None:
    """Point performance: stall, V_md, level speeds, climb (Vx, Vy), ceilings, OEI, obstacle."""
    from tuflexperf.analysis.performance import solve_performance

    case = load_case_with(case_file, sets)
    result = solve_performance(case)
    data = result.to_dict()
    attainable = result.min_level_speed_m_s is not None
    if as_json:
        emit_json({**data, "attainable": attainable})
    else:
        r = result
        typer.echo(
            f"{case.name}: point performance at {r.altitude_m:g} m "
            f"({r.density_kg_m3:.4f} kg/m^3), full throttle; true airspeeds"
        )
        rows = [
            ("stall speed", r.stall_speed_m_s, "m/s"),
            (f"least airspeed (stall x {r.stall_margin:g})", r.least_airspeed_m_s, "m/s"),
            ("minimum-drag speed", r.minimum_drag_speed_m_s, "m/s"),
            ("least level speed", r.min_level_speed_m_s, "m/s"),
            ("max level speed", r.max_level_speed_m_s, "m/s"),
            ("max rate of climb", r.max_climb_rate_m_s, "m/s"),
            ("  at Vy", r.best_climb_rate_speed_m_s, "m/s"),
            ("max climb gradient", r.max_climb_gradient, "-"),
            ("  at Vx", r.best_climb_angle_speed_m_s, "m/s"),
            ("service ceiling (0.5 m/s)", r.service_ceiling_m, "m"),
            ("absolute ceiling", r.absolute_ceiling_m, "m"),
            (f"OEI max climb gradient ({r.oei_dead_engine_mode})", r.oei_max_climb_gradient, "-"),
            ("OEI max level speed", r.oei_max_level_speed_m_s, "m/s"),
            (f"take-off to {r.takeoff_obstacle_height_m:g} m obstacle",
             r.takeoff_distance_to_obstacle_m, "m"),
        ]
        if r.jet_velocity_ceiling_m_s is not None:  # the fans make no thrust from there on
            rows.append(("fans' static jet velocity", r.jet_velocity_ceiling_m_s, "m/s"))
        for label, value, unit in rows:
            typer.echo(f"  {label:<36}{_fmt(value, 3 if unit == '-' else 2):>10} {unit}")
        worst = r.oei_critical
        if worst is not None:
            typer.echo(f"  (OEI worse case: {worst.dead_engine} dead)")
        for note in r.notes:
            typer.echo(f"  {note}")
        if not attainable:
            typer.echo("  NOT ATTAINABLE: no level flight at full throttle above stall")
        _print_warnings(list(r.warnings))
    raise typer.Exit(0 if attainable else 1)


# ---- mission (issue 13) --------------------------------------------------------------------
@app.command()
def mission(
    mission_file: Path | None = typer.Argument(
        None, help="Mission file (default: the case's mission requirement)."
    ),
    case_file: Path | None = CaseOption,
    csv_text: str | None = typer.Option(None, "--csv", metavar="<path>",
                                        help="Write the time history to this CSV."),
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
) -> None:
    """Fly a mission with the battery model; charge at landing against the reserve."""
    from tuflexperf.analysis.mission import solve_mission
    from tuflexperf.analysis.requirements import mission_path, mission_verdicts
    from tuflexperf.io.mission import load_mission

    csv = output_file(csv_text, "--csv")
    case = load_case_with(case_file, sets)
    requirement = case.requirements.mission
    if mission_file is None:
        if requirement is None:
            fail_input("MISSION: give a mission file (the case has no mission requirement)")
        mission_file = mission_path(case)
    plan = load_mission(mission_file)
    if csv is not None:
        from tuflexperf.io.case import case_files
        from tuflexperf.io.files import guard_outputs

        # every file the flight reads: the case's (SPEC 5) and the mission itself
        inputs = [Path(mission_file), *(path for _, path in case_files(case))]
        guard_outputs({"--csv": csv}, inputs, "mission", {"--csv": "mission history"})
    limit = requirement.min_landing_charge_fraction if requirement is not None else None
    try:
        result = solve_mission(case, plan, limit)
    except NotAttainable as exc:
        if as_json:  # the mission's own keys (SPEC 5), nothing flown
            emit_json({"command": "mission", "mission": plan.name, "passed": False,
                       "attainable": False, "reason": str(exc),
                       "landing_charge_fraction": None, "min_landing_charge_fraction": limit,
                       "segments": []})
        sys.stderr.write(f"tuflexperf: not attainable: {exc}\n")
        raise typer.Exit(1) from None
    if csv is not None:
        from tuflexperf.io.files import atomic_write_text

        names = list(result.history)
        rows = zip(*(result.history[k] for k in names), strict=True)
        text = ",".join(names) + "\n" + "".join(
            ",".join(f"{value:.10g}" for value in row) + "\n" for row in rows
        )
        atomic_write_text(csv, text)
    if as_json:
        emit_json(result.to_dict())
    else:
        typer.echo(f"{case.name}: mission {result.name}")
        header = (f"  {'segment':<16}{'time min':>9}{'dist km':>9}{'alt m':>8}{'EAS m/s':>8}"
                  f"{'charge Ah':>10}{'energy Wh':>10}{'min V':>8}{'max thr':>8}")
        typer.echo(header)
        for s in result.segments:
            eas = "" if s.airspeed_eas_m_s is None else f"{s.airspeed_eas_m_s:.1f}"
            thr = "" if s.max_throttle is None else f"{s.max_throttle:.3f}"
            label = f"{s.dead_engine} fails" if s.type == "engine_failure" else s.type
            typer.echo(
                f"  {label:<16}{s.time_s / 60:9.2f}{s.distance_m / 1000:9.2f}"
                f"{s.end_altitude_m:8.0f}{eas:>8}{sum(s.charge_ah):10.3f}"
                f"{sum(s.energy_wh):10.1f}{s.min_voltage_v:8.2f}{thr:>8}"
            )
        for note in result.warnings:  # the JSON's "warnings": said in the text too
            typer.echo(f"  note: {note}")
        landing, *solved = mission_verdicts(result)
        typer.echo(f"  {result.reason}  {'PASS' if landing.passed else 'FAIL'}")
        for verdict in solved:  # solve_for: the longest segment against the file's own
            value = "not attainable" if verdict.value is None else f"{verdict.value:.2f} min"
            typer.echo(f"  solve_for: {value}, {verdict.reason}  "
                       f"{'PASS' if verdict.passed else 'FAIL'}")
        if csv is not None:
            typer.echo(f"  wrote {csv}")
    raise typer.Exit(0 if result.passed else 1)


# ---- endurance (issue 3) -------------------------------------------------------------------
@app.command()
def endurance(
    throttle: float | None = typer.Option(
        None, "--throttle", help="Throttle fraction in [0, 1], all engines."
    ),
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    best: bool = typer.Option(
        False, "--best", metavar="",
        help="Also the throttle/airspeed of longest flight and of best range.",
    ),
) -> None:
    """Level-flight airspeed, electrical power, pack and flight endurance at a throttle."""
    from tuflexperf.analysis.endurance import solve_best, solve_endurance

    if throttle is None and not best:
        fail_input("--throttle: required (a fraction in [0, 1]), or use --best")
    if throttle is not None and not (math.isfinite(throttle) and 0.0 <= throttle <= 1.0):
        # a percent looks like one (50, 75); 1.0000001 or 1.5 is no percent (outside audit)
        hint = (f" (did you mean {throttle / 100:g}? throttle is a fraction, not percent)"
                if math.isfinite(throttle) and 2.0 <= throttle <= 100.0 else "")
        fail_input(f"--throttle: must be a fraction in [0, 1], got {throttle!r}{hint}")
    case = load_case_with(case_file, sets)
    # the throttle asked for first: its own reason, not one of the best search's throttles
    asked = solve_endurance(case, throttle) if throttle is not None else None
    best_result = solve_best(case) if best else None
    result = asked if asked is not None else best_result.endurance
    data = result.to_dict()
    requirement = case.requirements.endurance
    judged = requirement is not None and abs(requirement.throttle - result.throttle) < 1e-12
    from tuflexperf.analysis.requirements import endurance_verdict

    met = not judged or endurance_verdict(requirement, result).passed  # the one verdict rule
    if as_json:
        payload = dict(data)
        if best_result is not None:
            payload["best"] = best_result.to_dict()
        if judged:
            payload["min_flight_time_min"] = requirement.min_flight_time_min
            payload["passed"] = met
        emit_json(payload)
    else:
        typer.echo(f"{case.name}: endurance at throttle {result.throttle:.3f}")
        rows = [
            ("level-flight airspeed", data["airspeed_m_s"], "m/s"),
            ("electrical power per fan", data["electrical_power_w"], "W"),
            ("pack current (full)", data["pack_current_a"], "A"),
            ("one pack, full to cut-off", data["battery_endurance_min"], "min"),
            ("flight (climb + cruise)", data["flight_endurance_min"], "min"),
            ("  cruise", data["cruise_time_min"], "min"),
            ("  launch charge per fan", data["launch"]["charge_ah"], "Ah"),
        ]
        for label, value, unit in rows:
            shown = f"{value:10.2f}" if math.isfinite(value) else f"{'n/a':>10}"
            typer.echo(f"  {label:<28}{shown} {unit}")
        typer.echo(
            f"  cruise ends at the {data['cruise_ends_at']} "
            f"({data['packs_in_parallel_per_engine']} packs per fan, "
            f"reserve {100 * data['landing_reserve_fraction']:g} %)"
        )
        typer.echo(
            f"  battery fit: rms {data['battery_fit']['rms_v']:.3f} V over "
            f"{data['battery_fit']['n_points']} samples"
        )
        for cv in data["cross_validation"]:
            typer.echo(
                f"  cross-check: fitted on {cv['fitted_on']}, {cv['predicted_run']} cut-off "
                f"{cv['predicted_min']:.2f} min vs {cv['observed_min']:.2f} measured "
                f"({cv['error_percent']:+.1f} %)"
            )
        if judged:
            typer.echo(
                f"  requirement: >= {requirement.min_flight_time_min:g} min  "
                f"{'PASS' if met else 'FAIL'}"
            )
        if best_result is not None:
            b = best_result.to_dict()
            e, r = b["best_endurance"], b["best_range"]
            def held(best: dict[str, Any], better: str) -> str:
                return (f" (held at {b['least_airspeed_is']}, {b['least_airspeed_m_s']:.1f} "
                        f"m/s: slower would fly {better})" if best["held_at_least_airspeed"]
                        else "")

            typer.echo(
                f"  longest flight: throttle {e['throttle']:.3f} at {e['airspeed_m_s']:.1f} m/s, "
                f"{e['flight_endurance_min']:.2f} min" + held(e, "longer")
            )
            typer.echo(
                f"  best range: throttle {r['throttle']:.3f} at {r['airspeed_m_s']:.1f} m/s, "
                f"{r['cruise_range_km']:.1f} km in cruise" + held(r, "farther")
            )
        _print_warnings(data["warnings"])
    raise typer.Exit(0 if met else 1)


# ---- fit (issue 4) -------------------------------------------------------------------------
class _FitProgress:
    """Rich progress bar on stderr while the campaign is reduced (silent when not a TTY)."""

    def __enter__(self) -> _FitProgress:
        from rich.console import Console
        from rich.progress import BarColumn, Progress, TextColumn

        console = Console(stderr=True)
        self._bar = Progress(
            TextColumn("reducing"),
            BarColumn(),
            TextColumn("{task.completed}/{task.total} {task.description}"),
            console=console,
            transient=True,
            disable=not console.is_terminal,
        )
        self._bar.__enter__()
        self._task = self._bar.add_task("", total=None)
        return self

    def __call__(self, done: int, total: int, label: str) -> None:
        self._bar.update(self._task, completed=done, total=total, description=label)

    def __exit__(self, *exc: object) -> None:
        self._bar.__exit__(*exc)


def _print_fit(summary: dict[str, Any]) -> None:
    typer.echo(f"poly22 fit of {summary['input']} ({summary['kind']})")
    header = (
        f"{'engine':<8}{'n':>4}{'p00':>9}{'p10':>9}{'p01':>9}{'p20':>9}{'p11':>9}{'p02':>11}"
        f"{'R^2':>9}{'RMSE N':>8}{'T(1,0)':>8}{'T(1,30)':>8}"
    )
    typer.echo(header)
    typer.echo("-" * len(header))
    for e in summary["engines"]:
        c = e["coefficients"]
        full = e["full_throttle_thrust_n"]
        typer.echo(
            f"{e['name']:<8}{e['n_points']:>4}{c['p00']:>9.4f}{c['p10']:>9.4f}{c['p01']:>9.4f}"
            f"{c['p20']:>9.4f}{c['p11']:>9.4f}{c['p02']:>11.3e}{_fmt(e['r2'], 5):>9}"
            f"{_fmt(e['rmse_n']):>8}{full['0']:>8.2f}{full['30']:>8.2f}"
        )
    delay = summary.get("delay_s")
    runs = summary.get("delay_runs", [])
    line = f"delay: {_fmt(delay)} s"
    if runs:
        values = [r["delay_s"] for r in runs]
        lags = [r["lag_s"] for r in runs]
        line += (
            f" (mean of {len(runs)} sine sweeps, {min(values):.3f}-{max(values):.3f} s; "
            f"spool lag {sum(lags) / len(lags):.3f} s)"
        )
    typer.echo(line)
    drag = summary.get("structure_drag")
    if drag:
        typer.echo(
            f"structure drag: D = {drag['c1_n_per_m_s']:.4g} V + {drag['c2_n_per_m2_s2']:.4g} V^2, "
            f"{drag['drag_at_max_airspeed_n']:.2f} N at {drag['airspeed_range_m_s'][1]:.1f} m/s "
            f"(R^2 {drag['r2']:.4f}); added to every point"
        )
    glauert = summary.get("glauert")
    if glauert and glauert["max_correction_percent"] is not None:
        typer.echo(
            f"Glauert blockage: up to {glauert['max_correction_percent']:.1f} % "
            f"({glauert['max_correction_m_s']:.2f} m/s) at {glauert['at_airspeed_m_s']:.1f} m/s, "
            f"{glauert['max_correction_at_top_airspeed_percent']:.1f} % at the top airspeed; "
            + ("applied" if glauert["applied"] else "not applied (--glauert applies it)")
        )
    _echo_electrical(summary.get("electrical"))
    runs = [r for r in summary.get("runs", []) if "validation" in r]
    if runs:
        typer.echo("validation, model - measured force over steady segments (mean -/+, N):")
        width = max(len(str(r["file"])) for r in runs) + 2
        for r in runs:
            v = r["validation"]
            typer.echo(
                f"  {r['file']:<{width}}{r['engine']:<8}{_fmt(v['mean_negative_error_n'], 2):>7} / "
                f"+{_fmt(v['mean_positive_error_n'], 2)}   {r['segments']} segments"
            )
    _print_warnings(summary.get("warnings", []))
    typer.echo(f"wrote {summary['out']}" + (f" and {summary['table']}" if summary["table"] else ""))


@app.command("fit")
def fit_command(
    input_file: Path = typer.Argument(
        ..., help="Campaign manifest (campaign.yaml), propeller-table manifest, thrust table "
        "(.csv) or battery file."
    ),
    out_text: str | None = typer.Option(
        None, "--out", metavar="<path>",
        help="File to write (default: propulsion_fit.yaml, or battery_fit.yaml for a battery "
        "file).",
    ),
    table_text: str | None = typer.Option(
        None,
        "--table", metavar="<path>",
        help="Thrust table to write (campaign default: <out>_thrust_table.csv beside --out).",
    ),
    glauert: bool = typer.Option(
        False, "--glauert", metavar="",
        help="Fit against Glauert-corrected airspeeds (paper eq. 5).",
    ),
    delay_s: float | None = typer.Option(
        None, "--delay-s", help="Delay in s to write instead of the measured one."
    ),
    as_json: bool = JsonOption,
) -> None:
    """Reduce raw runs (or a thrust table) to the poly22 propulsion file."""
    from tuflexperf.reduction.pipeline import is_battery_file, run_fit

    out, table = output_file(out_text, "--out"), output_file(table_text, "--table")
    if out is None:
        battery = input_file.is_file() and is_battery_file(input_file)
        out = Path("battery_fit.yaml" if battery else "propulsion_fit.yaml")
    with _FitProgress() as progress:
        summary = run_fit(input_file, out, table, glauert, delay_s, progress)
    if as_json:
        emit_json(summary)
    elif summary.get("kind") == "battery":
        fit = summary["battery_fit"]
        typer.echo(f"pack model of {summary['input']}: rms {fit['rms_v']:.3f} V (max "
                   f"{fit['max_abs_v']:.3f} V) over {fit['n_points']} points of "
                   f"{len(fit['runs'])} runs")
        for c in fit["cross_validation"]:
            typer.echo(f"  fitted on {c['fitted_on']}: {c['predicted_run']} cut-off "
                       f"{c['predicted_min']:.2f} min vs {c['observed_min']:.2f} measured")
        typer.echo(f"wrote {summary['out']}")
    else:
        _print_fit(summary)


# ---- report (issue 5) ----------------------------------------------------------------------
@app.command("report")
def report_command(
    case_file: Path | None = CaseOption,
    out_text: str = typer.Option(..., "--out", metavar="<path>",
                                 help="Directory for the PNG figures and review.pdf."),
    campaign: Path | None = typer.Option(
        None,
        "--campaign",
        help="Measured data: campaign or propeller-table manifest, or thrust-table CSV "
        "(default: the propulsion file's source, else campaign/campaign.yaml beside it).",
    ),
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
) -> None:
    """Design-review figures (PNG, 150 dpi) and one multi-page PDF, review.pdf."""
    from tuflexperf.report import build_report  # lazy: matplotlib stays out of `check`

    refuse_dash(out_text, "--out")
    case = load_case_with(case_file, sets) if sets else case_file
    result = build_report(case, Path(out_text), campaign=campaign)
    if as_json:
        emit_json(result.to_dict())
        return
    typer.echo(
        f"wrote {len(result.files)} files to {result.out_dir} "
        f"({result.pages}-page {result.pdf.name}, {result.seconds:.1f} s); requirements "
        + ("all met" if result.passed else "NOT all met")
    )
    for path in result.files:
        typer.echo(f"  {path.name}")
    for note in result.notes:
        typer.echo(f"  note: {note}")


# ---- export (issue 6) ----------------------------------------------------------------------
@app.command("export")
def export_command(
    case_file: Path | None = CaseOption,
    formats: str = typer.Option(
        "c,casadi,json",
        "--format",
        help="Comma list of c, casadi, json, jsbsim, fmu (default: c,casadi,json).",
    ),
    out_text: str = typer.Option(..., "--out", metavar="<path>",
                                 help="Directory to write the model files into."),
    as_json: bool = JsonOption,
) -> None:
    """The thrust model for simulation and flight software: C99, CasADi, JSON, JSBSim, FMU."""
    from tuflexperf.export import export_model, parse_formats

    refuse_dash(out_text, "--out")
    result = export_model(case_file, parse_formats(formats), Path(out_text))
    if as_json:
        emit_json(result.as_dict())
        return
    prop = result.model.propulsion
    typer.echo(
        f"{prop.name}: {result.model.n_engines} engines, delay {prop.delay_s:g} s, "
        f"spool lag {prop.lag_s:g} s"
    )
    for path in result.files:
        typer.echo(f"  wrote {path}")
    if prop.reference_voltage_v is not None:
        typer.echo(
            f"  note: the exported thrust is at the reference pack voltage "
            f"{prop.reference_voltage_v:g} V; at U it is (U / {prop.reference_voltage_v:g})"
            f"^{prop.voltage_exponent:.3g} times that (the JSON's pack_voltage)"
        )


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


def _os_error_text(exc: OSError) -> str:
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


def _guarded(callback: Any) -> Any:
    """Turn InputError into exit 2 and NotAttainable into exit 1, one line on stderr each."""

    @functools.wraps(callback)
    def run(*args: Any, **kwargs: Any) -> Any:
        try:
            return callback(*args, **kwargs)
        except InputError as exc:
            _unless_interrupted()
            sys.stderr.write(f"tuflexperf: error: {one_line(str(exc))}\n")
            raise typer.Exit(2) from None
        except BrokenPipeError:  # a pipe of the command's own (io.streams guards stdout):
            # no verdict was given, so none is claimed (exit 0 here "passed" `check | head`)
            sys.stderr.write("tuflexperf: error: the output's reader went away\n")
            raise typer.Exit(2) from None
        except OverflowError:  # a number of the input far beyond any aircraft's
            _unless_interrupted()
            sys.stderr.write("tuflexperf: error: a number of the input is too large to compute "
                             "with (floating-point overflow); check the magnitudes of the "
                             "input files' keys and of the flags\n")
            raise typer.Exit(2) from None
        except OSError as exc:  # a file the OS refuses (name too long, disk full, ...)
            _unless_interrupted()
            sys.stderr.write(f"tuflexperf: error: {_os_error_text(exc)}\n")
            raise typer.Exit(2) from None
        except RuntimeError as exc:
            # pathlib's resolve() of a symbolic link that leads back to itself (Python < 3.13;
            # later versions raise the OSError above)
            if not str(exc).startswith(_SYMLINK_LOOP):
                raise
            _unless_interrupted()
            where = str(exc).removeprefix(_SYMLINK_LOOP).strip("'\"")
            sys.stderr.write(f"tuflexperf: error: {one_line(where)}: symbolic link loop\n")
            raise typer.Exit(2) from None
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
    --throttle 0.6` flew 0.6; outside audit). A flag said twice means the same: allowed."""
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


def _refuse_repeated(args: list[str]) -> None:
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


def _refuse_empty(args: list[str]) -> None:
    """Exit 2 naming an option (or argument) given an empty value: ``--case=`` or ``--case ''``
    became the path '.', reported as "is a directory" (outside audit)."""
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


for _info in app.registered_commands:  # every command above, whichever section wrote it
    _info.callback = _guarded(_info.callback)


def _case_hint(message: str, argv: list[str] | None) -> str:
    """For ``report case.yaml``: only ``check`` and ``mission`` take a file by position."""
    args = sys.argv[1:] if argv is None else argv
    if not message.startswith("Got unexpected extra argument") or "--case" in args:
        return ""
    # the argument refused, as the message names it: `mission M.yaml CASE.yaml` was told to
    # give the mission file as the case (outside audit)
    named = message.rpartition("(")[2].partition(")")[0].split()
    extra = next((a for a in (*named, *args[1:]) if a.lower().endswith((".yaml", ".yml"))),
                 None)
    return "" if extra is None else f": give the case file with --case {extra}"


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
    # noise on the user's screen (outside audit)
    import warnings

    warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"tuflexperf(\.|$)")
    def aborted() -> None:
        hold_interrupts()  # a second Ctrl-C here printed a traceback (outside audit)
        sys.stderr.write("tuflexperf: aborted\n")
        sys.exit(130)

    args = sys.argv[1:] if argv is None else list(argv)
    _refuse_empty(args)
    _refuse_repeated(args)
    try:
        code = app(args=argv, standalone_mode=False, prog_name="tuflexperf")
    except (Abort, KeyboardInterrupt):  # click's word for an interrupt, or one before click's
        aborted()
    except TyperException as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            app(args=["--help"], prog_name="tuflexperf")
        message = exc.format_message()
        sys.stderr.write(f"tuflexperf: error: {one_line(message + _case_hint(message, argv))}\n")
        sys.exit(getattr(exc, "exit_code", 2) or 2)
    except OSError as exc:  # outside a command's own guard (--version, --help): stdout full
        if interrupted():
            aborted()
        sys.stderr.write(f"tuflexperf: error: {_os_error_text(exc)}\n")
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
