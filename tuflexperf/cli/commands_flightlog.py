"""``tuflexperf flightlog``: the flown side of a PX4 or ArduPilot log, and the case beside it.

The body of the command; :mod:`tuflexperf.cli` registers it. Bad input is an
:class:`InputError`, which the CLI's guard turns into exit 2; pyulog, pymavlink and
matplotlib are imported only when it runs.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import typer

from tuflexperf.cli.inputs import output_file
from tuflexperf.cli.render import emit_json, fmt
from tuflexperf.errors import InputError


def flightlog_command(
    log_path: Path = typer.Argument(..., metavar="LOG",
                                    help="PX4 .ulg, a ulog2csv folder, or an ArduPilot .bin."),
    case_file: Path | None = typer.Option(
        None, "--case", help="Requirement file: compare the model's power with the flown."),
    mass_kg: float | None = typer.Option(
        None, "--mass", help="Aircraft mass in kg (default: the case's)."),
    airborne_airspeed: float | None = typer.Option(
        None, "--airborne-airspeed",
        help="Airspeed in m/s of the airborne rule (default 1.1x the case's stall speed, "
        "or 8 m/s without a case)."),
    airborne_height: float = typer.Option(
        3.0, "--airborne-height", help="Height above ground in m of the airborne rule."),
    efficiency: float = typer.Option(
        0.5, "--efficiency",
        help="Electrical-to-climb-power efficiency of the climb correction."),
    as_json: bool = typer.Option(False, "--json", metavar="",
                                 help="Print one JSON object on stdout."),
    csv_text: str | None = typer.Option(None, "--csv", metavar="<path>",
                                        help="Write the aligned time series as CSV here."),
    plot_text: str | None = typer.Option(None, "--plot", metavar="<path>",
                                         help="Write flown power against airspeed (PNG) here."),
    summary_text: str | None = typer.Option(
        None, "--summary", metavar="<path>",
        help="With --case: write the flown bins beside the model (YAML) here, for the case's "
        "validation: {flights: [...]}."),
) -> None:
    """The flown side of a flight log (energy, power against airspeed); with --case, the model."""
    from tuflexperf.analysis.flown import reduce_flight
    from tuflexperf.io.flightlog import read_flight_log

    csv_out, plot = output_file(csv_text, "--csv"), output_file(plot_text, "--plot")
    summary_out = output_file(summary_text, "--summary")
    if summary_out is not None and case_file is None:
        raise InputError("--summary: needs --case (the summary sets the flown power beside "
                         "the case's model)")
    for flag, value in (("--mass", mass_kg), ("--airborne-airspeed", airborne_airspeed)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise InputError(f"{flag}: must be a positive number, got {value:g}")
    if not (math.isfinite(airborne_height) and airborne_height >= 0):
        raise InputError(f"--airborne-height: must be >= 0, got {airborne_height:g}")
    if not (math.isfinite(efficiency) and 0 < efficiency <= 1):
        raise InputError(f"--efficiency: must be in (0, 1], got {efficiency:g}")
    if plot is not None and plot.suffix.lower() != ".png":
        raise InputError(f"--plot {plot}: the figure is written as PNG (use .png)")
    case = None
    if case_file is not None:
        from tuflexperf.io.case import load_case

        case = load_case(case_file)
    outputs = {f: p for f, p in (("--csv", csv_out), ("--plot", plot),
                                 ("--summary", summary_out)) if p is not None}
    if outputs:
        from tuflexperf.io.files import guard_outputs

        inputs = [log_path]
        if case is not None:
            from tuflexperf.io.case import case_files

            inputs += [p for _, p in case_files(case)]
        guard_outputs(outputs, inputs, "flightlog",
                      {"--csv": "flight series", "--plot": "flight plot",
                       "--summary": "flight summary"})
    log = read_flight_log(log_path)
    mass = mass_kg if mass_kg is not None else (case.aircraft.mass_kg if case else None)
    threshold = airborne_airspeed
    if threshold is None:
        threshold = _default_threshold(case)
    flown = reduce_flight(log, threshold, airborne_height, mass, efficiency)
    comparison = None
    if case is not None:
        from tuflexperf.analysis.flown_compare import compare_with_case

        comparison = compare_with_case(case, log, flown, mass)
    written: dict[Path, bytes | str] = {}
    if csv_out is not None:
        from tuflexperf.analysis.flown import series_csv

        written[csv_out] = series_csv(flown.series)
    if plot is not None:
        from tuflexperf.report.flight_plot import flight_png

        written[plot] = flight_png(flown, comparison, f"{Path(log_path).name}")
    if summary_out is not None and comparison is not None:
        from tuflexperf.io.flight_summary import flight_summary_text, log_digest

        text = flight_summary_text(Path(log_path), log_digest(Path(log_path)), comparison,
                                   flown.window.duration_s, flown.energy_wh)
        if text is None:
            raise InputError(f"--summary: {Path(log_path).name}: no flown bin has a predicted "
                             "power to set it beside; nothing to summarise")
        written[summary_out] = text
    if written:
        from tuflexperf.io.files import write_files_atomically

        write_files_atomically(written)
    payload: dict[str, Any] = {"command": "flightlog", "log": str(log_path), "format": log.kind,
                               "sources": _sources(log), **flown.to_dict()}
    if comparison is not None:
        payload["comparison"] = comparison.to_dict()
        payload["notes"] = payload["notes"] + list(comparison.notes)
    if as_json:
        emit_json(payload)
        return
    _print_text(payload, [p for p in (csv_out, plot, summary_out) if p is not None])


def _default_threshold(case: Any) -> float:
    from tuflexperf.analysis.flown import DEFAULT_AIRBORNE_AIRSPEED_M_S

    if case is None:
        return DEFAULT_AIRBORNE_AIRSPEED_M_S
    from tuflexperf.models.aircraft import stall_speed_eas_m_s

    # the log's calibrated airspeed is (near the ground) the equivalent airspeed
    return 1.1 * float(stall_speed_eas_m_s(case.aircraft))


def _sources(log: Any) -> dict[str, Any]:
    def src(stream: Any) -> str | None:
        return None if stream is None else stream.source

    return {"batteries": [b.source for b in log.batteries], "airspeed": src(log.airspeed),
            "baro": src(log.baro), "climb": src(log.climb), "throttle": src(log.throttle),
            "land_detector": src(log.landed)}


def _print_text(p: dict[str, Any], written: list[Path]) -> None:
    echo = typer.echo
    echo(f"{p['log']} ({p['format']})")
    echo(f"airborne: {fmt(p['airborne_s'], 1)} s ({fmt(p['airborne_start_s'], 2)} to "
         f"{fmt(p['airborne_end_s'], 2)} s), {p['airborne_rule']}")
    echo(f"energy: {fmt(p['energy_wh'], 3)} Wh; charge {fmt(p['charge_mah'], 1)} mAh "
         f"(log counter), {fmt(p['integrated_charge_mah'], 1)} mAh (integrated current); "
         f"mean power {fmt(p['mean_power_w'], 1)} W")
    comparison = p.get("comparison")
    predicted = {b["airspeed_m_s"]: b for b in comparison["bins"]} if comparison else {}
    # the model (level flight) stands beside the bins it was compared with
    compared = (p["level_bins"] if comparison and comparison["bins"]
                and comparison["bins"][0]["bins"] == "level-flight" else p["bins"])
    for title, key, bins in (
        (f"power against {p['airspeed_kind']} airspeed (bins of 1 m/s, >= "
         f"{p['min_bin_time_s']:g} s each)", "flown_power_w", p["bins"]),
        (f"level flight (|climb rate| < {p['level_climb_rate_m_s']:g} m/s)", "flown_power_w",
         p["level_bins"]),
        (f"climb-corrected (P - m g dh/dt / {p['climb_efficiency']:g}, m = "
         f"{fmt(p['mass_kg'], 1)} kg)", "corrected_power_w", p["climb_corrected_bins"]),
    ):
        if not bins:
            continue
        echo(title)
        head = f"  {'V m/s':>6}{'time s':>8}{'P W':>9}{'sd W':>8}{'throttle':>10}"
        echo(head + (f"{'model W':>9}{'ratio':>7}{'model thr':>10}" if predicted and
                     bins is compared else ""))
        for b in bins:
            row = (f"  {b['airspeed_m_s']:>6.0f}{b['time_s']:>8.1f}{fmt(b[key], 1):>9}"
                   f"{fmt(b['power_std_w'], 1):>8}{fmt(b['throttle'], 3):>10}")
            if predicted and bins is compared:
                m = predicted.get(b["airspeed_m_s"], {})
                row += (f"{fmt(m.get('predicted_power_w'), 1):>9}{fmt(m.get('ratio'), 2):>7}"
                        f"{fmt(m.get('predicted_throttle'), 3):>10}")
            echo(row)
    if comparison:
        for line in comparison["summary"]:
            echo(line)
    for path in written:
        echo(f"wrote {path}")
    for note in p["notes"]:
        echo(f"  note: {note}")
