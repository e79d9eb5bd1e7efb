"""The verdict commands: ``check``, ``margins``, ``sweep``, ``takeoff``, ``trim``, ``oei``,
``performance``. Each parses its flags, loads the case, calls the analysis and hands the
result to :mod:`tuflexperf.cli.render`; the exit code is the verdict (SPEC 5)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import typer

from tuflexperf.cli import render, render_tables
from tuflexperf.cli.inputs import (
    AircraftFileOption,
    BatteryFileOption,
    CaseOption,
    DaskOption,
    JsonOption,
    PropulsionFileOption,
    SamplesOption,
    SeedOption,
    SetOption,
    WorkersOption,
    batch_notes,
    fail_input,
    load_case_with,
    output_file,
    refuse_empty_address,
    refuse_implausible,
    replaced,
    scaled_pack_notes,
    set_keys,
    sweep_case,
)


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
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Verify every requirement in the case: value, limit, margin, PASS/FAIL."""
    from tuflexperf.analysis.requirements import CHECKS, check_case, sampled_result

    if case_file is not None and case_option is not None and case_file != case_option:
        fail_input("--case: give the case once, as the argument or as --case, not both")
    case_file = case_file if case_file is not None else case_option

    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
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
        from tuflexperf.analysis.uncertainty import plan_for, run_samples

        plan = plan_for(case, samples, seed)
        drawn = {key for key, _, _ in plan.parameters}
        # the deterministic row takes --set, the samples the block
        sample_notes += [f"--set {key}: the samples draw it from the uncertainty block "
                         "(the deterministic value uses --set)"
                         for key in set_keys(sets) if key in drawn]
        sample_notes += scaled_pack_notes([*drawn, *set_keys(sets)])
        from tuflexperf.cli.progress import TerminalProgress

        with TerminalProgress("samples") as bar:
            sample_set = run_samples(case, plan, workers, dask, bar)
        probabilistic = probabilistic_verdicts(sample_set)
        outside = {k: n for k, n in sample_set.outside_bounds.items() if n}
    # with samples, each result's verdict is the nominal one and P(met) shown together
    results = [sampled_result(v, probabilistic.get(v.name)) if sampling else v.to_dict()
               for v in verdicts]
    passed = all(r["passed"] for r in results)
    render.show_check(case, verdicts, results, passed, plan, probabilistic, outside,
                      sample_notes, as_json)
    raise typer.Exit(0 if passed else 1)


def margins(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Per requirement and parameter: the value where it just holds, and d(value)/d(parameter).

    Grouped by requirement, the binding parameters first.

    Order: smallest |limit value - nominal| / |nominal| first (nominal 0: over the range).

    The parameters that never bind come last. --json keeps the analysis' order.
    """
    from tuflexperf.analysis.margins import extrapolation_notes, solve_margins

    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    refuse_implausible(case, "margins", None, as_json)
    rows = solve_margins(case)
    notes = (extrapolation_notes(rows, case.propulsion.tested_airspeed_m_s)
             + batch_notes(case, [], None) + scaled_pack_notes({m.parameter for m in rows}))
    render_tables.show_margins(case, rows, notes, as_json)


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
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
    fail_on_fail: bool = typer.Option(
        False, "--fail-on-fail", metavar="",
        help="Exit 1 when any grid point FAILs a requirement.",
    ),
) -> None:
    """Every requirement over a grid of parameter values.

    Exit code: 0 once the grid is computed, whatever its verdicts (a sweep explores).

    With --fail-on-fail: 1 when any grid point FAILs. Bad input: 2.
    """
    from tuflexperf.analysis.sweep import run_sweep
    from tuflexperf.io.files import write_files_atomically

    if workers is not None and workers < 1:
        fail_input(f"--workers: must be at least 1, got {workers}")
    refuse_empty_address(dask)
    csv_out, plot = output_file(csv_text, "--csv"), output_file(plot_text, "--plot")
    case, axes = sweep_case(case_file, sets, vary, replaced(aircraft, propulsion, battery))
    outputs = {flag: target for flag, target in (("--csv", csv_out), ("--plot", plot))
               if target is not None}
    if plot is not None and plot.suffix.lower() != ".png":
        fail_input(f"--plot {plot}: the carpet plot is written as PNG (use .png)")
    if outputs:
        from tuflexperf.io.case import case_files
        from tuflexperf.io.files import guard_outputs

        guard_outputs(outputs, [path for _, path in case_files(case)], "sweep",
                      {"--csv": "sweep grid", "--plot": "sweep plot"})
    from tuflexperf.cli.progress import TerminalProgress

    with TerminalProgress("sweep") as bar:
        result = run_sweep(case, axes, workers, dask, bar)
    # after every refusal of bad input (exit 2, some in run_sweep) and before any output is
    # written: the data's own verdict, FAIL (exit 1)
    refuse_implausible(case, "sweep", None, as_json, [key for key, _ in axes])
    notes = (result.extrapolation_notes(case.propulsion.tested_airspeed_m_s)
             + batch_notes(case, [key for key, _ in axes], sets))
    written: dict[Path, bytes | str] = {}
    if plot is not None:
        from tuflexperf.report.sweep_plot import carpet_png

        written[plot] = carpet_png(result, f"{case.name}: sweep")
    if csv_out is not None:
        written[csv_out] = result.to_csv()
    if written:  # both or neither: an interrupt between them left a new plot by an old CSV
        write_files_atomically(written)
    render_tables.show_sweep(case, result, notes, (csv_out, plot), as_json)
    if fail_on_fail and not all(bool(np.all(met)) for met in result.met.values()):
        raise typer.Exit(1)


def takeoff(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Take-off at full throttle: ground roll, rotation, transition arc, climb to the obstacle."""
    from tuflexperf.analysis.requirements import takeoff_verdicts
    from tuflexperf.analysis.takeoff import solve_takeoff

    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    refuse_implausible(case, "takeoff", "takeoff", as_json)
    result = solve_takeoff(case)
    requirement = case.requirements.takeoff
    verdicts = takeoff_verdicts(requirement, result) if requirement is not None else []
    met = all(v.passed for v in verdicts)
    render.show_takeoff(case, result, requirement, verdicts, met, as_json)
    raise typer.Exit(0 if met else 1)


def trim(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    table: bool = typer.Option(
        False, "--table", metavar="", help="Print the throttle at every airspeed."
    ),
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Least throttle for level flight at each airspeed of the envelope (0.5 m/s grid)."""
    from tuflexperf.analysis.requirements import trim_verdict
    from tuflexperf.analysis.trim import solve_trim

    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    result = solve_trim(case)
    if case.requirements.envelope is None:
        fail_input(f"{case.path}: requirements.envelope: trim needs the envelope requirement")
    refuse_implausible(case, "trim", "envelope", as_json)
    limit = case.requirements.envelope.max_trim_throttle
    verdict = trim_verdict(case.requirements.envelope, result)  # the one verdict rule
    render.show_trim(case, result, verdict, limit, table, as_json)
    raise typer.Exit(0 if verdict.passed else 1)


def oei(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    dead_engine: str | None = typer.Option(
        None, "--dead-engine", help="windmilling or zero (default: the case's oei block)."
    ),
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Level flight with one engine inoperative; each engine dead in turn, worse case."""
    from tuflexperf.analysis.oei import solve_oei
    from tuflexperf.analysis.requirements import oei_verdict

    dead_engine = dead_engine.lower() if dead_engine is not None else None
    if dead_engine is not None and dead_engine not in ("windmilling", "zero"):
        fail_input(f"--dead-engine: must be windmilling or zero, got {dead_engine!r}")
    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    refuse_implausible(case, "oei", "oei", as_json)
    result = solve_oei(case, dead_engine)  # type: ignore[arg-type]
    requirement = case.requirements.oei
    limit = requirement.max_throttle if requirement is not None else 1.0
    met = oei_verdict(requirement, result).passed  # the one verdict rule
    render.show_oei(case, result, limit, met, as_json)
    raise typer.Exit(0 if met else 1)


def performance(
    case_file: Path | None = CaseOption,
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Point performance: stall, V_md, level speeds, climb (Vx, Vy), ceilings, OEI, obstacle."""
    from tuflexperf.analysis.performance import solve_performance

    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    refuse_implausible(case, "performance", None, as_json)
    result = solve_performance(case)
    attainable = result.min_level_speed_m_s is not None
    render.show_performance(case, result, attainable, as_json)
    raise typer.Exit(0 if attainable else 1)
