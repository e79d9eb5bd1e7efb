"""The data commands: ``fit`` (raw runs to a propulsion or battery file), ``report``
(figures and a PDF), ``export`` (the thrust model for simulators) and ``init`` (a starter
case). Each parses its
flags, calls the work and hands the result to :mod:`tuflexperf.cli.render`."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from tuflexperf.cli import render
from tuflexperf.cli.inputs import (
    AircraftFileOption,
    BatteryFileOption,
    CaseOption,
    JsonOption,
    PropulsionFileOption,
    SetOption,
    fail_input,
    load_case_with,
    output_file,
    refuse_dash,
    replaced,
)


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
    propulsion: Path | None = typer.Option(
        None, "--propulsion", metavar="<path>",
        help="Battery file only: the propulsion file whose power model the discharge runs' "
        "measured power correction is fitted against (default: propulsion.yaml beside it).",
    ),
    as_json: bool = JsonOption,
) -> None:
    """Reduce raw runs (or a thrust table) to the poly22 propulsion file."""
    from tuflexperf.reduction.pipeline import is_battery_file, run_fit

    out, table = output_file(out_text, "--out"), output_file(table_text, "--table")
    if out is None:
        battery = input_file.is_file() and is_battery_file(input_file)
        out = Path("battery_fit.yaml" if battery else "propulsion_fit.yaml")
    from tuflexperf.cli.progress import TerminalProgress

    with TerminalProgress("reducing") as bar:  # the runs as a bar on a terminal
        summary = run_fit(input_file, out, table, glauert, delay_s, bar, propulsion)
    render.show_fit(summary, as_json)


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
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
    compare: list[Path] | None = typer.Option(
        None, "--compare", metavar="<path>",
        help="Another configuration's requirement file, drawn over --case on every comparable "
        "figure with the verdicts side by side (repeatable; --set applies to --case only).",
    ),
) -> None:
    """Design-review figures (PNG, 150 dpi) and one multi-page PDF, review.pdf."""
    from tuflexperf.report import build_report  # lazy: matplotlib stays out of `check`

    refuse_dash(out_text, "--out")
    replace = replaced(aircraft, propulsion, battery)
    case = load_case_with(case_file, sets, replace) if sets or replace else case_file
    from tuflexperf.cli.progress import TerminalProgress

    # the steps as a bar on a terminal; elsewhere nothing (stderr keeps notes and errors)
    with TerminalProgress("report") as bar:
        result = build_report(case, Path(out_text), campaign=campaign, progress=False,
                              bar=bar if bar.enabled else None, compare=list(compare or []))
    render.show_report(result, as_json)
    # the report is written (its verdicts say FAIL with the reason); the exit says it too
    from tuflexperf.analysis.plausibility import implausible

    found = implausible(case if not isinstance(case, (Path, type(None)))
                        else load_case_with(case_file, None, None))
    if found:
        for f in found:
            sys.stderr.write(f"tuflexperf: FAIL: {f.reason}\n")
        raise typer.Exit(1)


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
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """The thrust model for simulation and flight software: C99, CasADi, JSON, JSBSim, FMU."""
    from tuflexperf.export import export_model, parse_formats

    refuse_dash(out_text, "--out")
    replace = replaced(aircraft, propulsion, battery)
    case = load_case_with(case_file, None, replace) if replace else case_file
    result = export_model(case, parse_formats(formats), Path(out_text))
    render.show_export(result, as_json)


def init_command(
    folder: Path = typer.Argument(
        ..., metavar="DIR",
        help="Folder for the starter case (made if missing; nothing in it is replaced).",
    ),
    from_datasheet: bool = typer.Option(
        False, "--from-datasheet", metavar="",
        help="Build propulsion and battery from datasheet numbers (the flags below, or "
        "--datasheet FILE) instead of typical values.",
    ),
    datasheet: Path | None = typer.Option(
        None, "--datasheet", metavar="<path>",
        help="YAML of datasheet numbers, keys as the flags (static_thrust_n, ...).",
    ),
    static_thrust_n: float | None = typer.Option(
        None, "--static-thrust-n", help="Full-throttle static thrust of one fan, in N."),
    max_power_w: float | None = typer.Option(
        None, "--max-power-w", help="Full-throttle electrical power of one fan, in W."),
    fan_diameter_m: float | None = typer.Option(
        None, "--fan-diameter-m", help="Fan (duct) diameter, in m."),
    engines: int | None = typer.Option(None, "--engines", help="Number of fans (default 2)."),
    cells: int | None = typer.Option(None, "--cells", help="Cells in series of one pack."),
    capacity_ah: float | None = typer.Option(
        None, "--capacity-ah", help="Capacity of one pack, in Ah."),
    c_rating: float | None = typer.Option(
        None, "--c-rating", help="Continuous discharge rating of one pack, in C."),
    internal_resistance: float | None = typer.Option(
        None, "--internal-resistance-ohm",
        help="Internal resistance per cell, in Ohm (default: the shipped pack's, scaled to the "
        "capacity)."),
    example: str | None = typer.Option(
        None, "--example", metavar="NAME", help="Copy a shipped example instead: tuflex."),
    as_json: bool = JsonOption,
) -> None:
    """Write a commented starter case that check runs at once, for you to edit."""
    from tuflexperf.io.datasheet import TYPICAL
    from tuflexperf.reduction.starter import copy_example, write_starter

    flags = {"static_thrust_n": static_thrust_n, "max_power_w": max_power_w,
             "fan_diameter_m": fan_diameter_m, "engines": engines, "cells": cells,
             "capacity_ah": capacity_ah, "c_rating": c_rating,
             "internal_resistance_ohm_per_cell": internal_resistance}
    given = {key: value for key, value in flags.items() if value is not None}
    if example is not None:
        if from_datasheet or given or datasheet is not None:
            fail_input("--example: copies the shipped example; give no datasheet flags with it")
        result = copy_example(folder, example)
    else:
        if (given or datasheet is not None) and not from_datasheet:
            fail_input("--from-datasheet: give it to build the case from datasheet numbers")
        sheet = read_datasheet(datasheet, given) if from_datasheet else dict(TYPICAL)
        result = write_starter(folder, validated_datasheet(sheet, datasheet), from_datasheet)
    render.show_init(result, as_json)


def read_datasheet(path: Path | None, given: dict[str, float]) -> dict[str, object]:
    """The datasheet numbers: the file's, each flag given replacing its key."""
    from tuflexperf.io.datasheet import DATASHEET_KEYS
    from tuflexperf.io.yamlio import read_yaml

    data: dict[str, object] = {}
    if path is not None:
        read = read_yaml(path)
        if not isinstance(read, dict):
            fail_input(f"--datasheet: {path}: expected a mapping of keys at the top level")
        data = dict(read)
    data.update(given)
    missing = [key for key in ("static_thrust_n", "max_power_w", "fan_diameter_m", "cells",
                               "capacity_ah", "c_rating") if key not in data]
    if missing:
        flags = ", ".join("--" + key.replace("_", "-") for key in missing)
        fail_input(f"--from-datasheet: missing {flags} (or those keys in --datasheet FILE; "
                   f"keys: {', '.join(DATASHEET_KEYS)})")
    return data


def validated_datasheet(data: dict[str, object], path: Path | None) -> object:
    """``data`` validated as a datasheet; problems name the file or the flags."""
    from pydantic import ValidationError

    from tuflexperf.errors import InputError
    from tuflexperf.io.datasheet import DatasheetSchema
    from tuflexperf.io.yamlio import validation_problems

    try:
        return DatasheetSchema.model_validate(data)
    except ValidationError as exc:
        where = f"--datasheet {path}" if path is not None else "--from-datasheet"
        raise InputError.of(validation_problems(where, exc, DatasheetSchema)) from None
