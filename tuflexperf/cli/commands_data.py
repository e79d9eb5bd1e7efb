"""The data commands: ``fit`` (raw runs to a propulsion or battery file), ``report``
(figures and a PDF) and ``export`` (the thrust model for simulators). Each parses its
flags, calls the work and hands the result to :mod:`tuflexperf.cli.render`."""

from __future__ import annotations

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
    as_json: bool = JsonOption,
) -> None:
    """Reduce raw runs (or a thrust table) to the poly22 propulsion file."""
    from tuflexperf.reduction.pipeline import is_battery_file, run_fit

    out, table = output_file(out_text, "--out"), output_file(table_text, "--table")
    if out is None:
        battery = input_file.is_file() and is_battery_file(input_file)
        out = Path("battery_fit.yaml" if battery else "propulsion_fit.yaml")
    with render.FitProgress() as progress:
        summary = run_fit(input_file, out, table, glauert, delay_s, progress)
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
) -> None:
    """Design-review figures (PNG, 150 dpi) and one multi-page PDF, review.pdf."""
    from tuflexperf.report import build_report  # lazy: matplotlib stays out of `check`

    refuse_dash(out_text, "--out")
    replace = replaced(aircraft, propulsion, battery)
    case = load_case_with(case_file, sets, replace) if sets or replace else case_file
    result = build_report(case, Path(out_text), campaign=campaign)
    render.show_report(result, as_json)


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
