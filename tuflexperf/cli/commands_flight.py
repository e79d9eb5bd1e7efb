"""The flight commands on the battery model: ``mission`` and ``endurance``. Each parses its
flags, loads the case, calls the analysis and hands the result to
:mod:`tuflexperf.cli.render`; the exit code is the verdict (SPEC 5)."""

from __future__ import annotations

import math
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
    refuse_implausible,
    replaced,
)
from tuflexperf.errors import NotAttainable


def mission(
    mission_file: Path | None = typer.Argument(
        None, help="Mission file (default: the case's mission requirement)."
    ),
    case_file: Path | None = CaseOption,
    csv_text: str | None = typer.Option(None, "--csv", metavar="<path>",
                                        help="Write the time history to this CSV."),
    as_json: bool = JsonOption,
    sets: list[str] | None = SetOption,
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Fly a mission with the battery model; charge at landing against the reserve."""
    from tuflexperf.analysis.mission import solve_mission
    from tuflexperf.analysis.requirements import (
        judged_block,
        mission_file_verdicts,
        mission_path,
        mission_verdicts,
    )
    from tuflexperf.io.mission import load_mission

    csv = output_file(csv_text, "--csv")
    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    requirement = case.requirements.mission
    if mission_file is None:
        if requirement is None:
            fail_input("MISSION: give a mission file (the case has no mission requirement)")
        mission_file = mission_path(case)
    plan = load_mission(mission_file)
    refuse_implausible(case, "mission", "mission", as_json)
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
        render.show_mission_not_flown(plan.name, str(exc), limit, as_json)
        raise typer.Exit(1) from None
    if csv is not None:
        from tuflexperf.io.files import atomic_write_text

        atomic_write_text(csv, render.history_csv(result.history))
    own = requirement is not None and Path(mission_file).resolve() == mission_path(case)
    # the case's own mission is judged as check judges it, another file on every reading
    # of the case's disputed evidence too
    verdicts = (judged_block(case, "mission", lambda: mission_verdicts(result)) if own
                else mission_file_verdicts(case, plan, limit, result))
    render.show_mission(case, result, verdicts, csv, as_json)
    raise typer.Exit(0 if all(v.passed for v in verdicts) else 1)


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
    aircraft: Path | None = AircraftFileOption,
    propulsion: Path | None = PropulsionFileOption,
    battery: Path | None = BatteryFileOption,
) -> None:
    """Level-flight airspeed, electrical power, pack and flight endurance at a throttle."""
    from tuflexperf.analysis.endurance import solve_best, solve_endurance
    from tuflexperf.analysis.flown_reading import flown_flights, flown_power_ratio
    from tuflexperf.analysis.requirements import (
        endurance_verdict,
        judged_block,
        with_flown_power,
    )

    if throttle is None and not best:
        fail_input("--throttle: required (a fraction in [0, 1]), or use --best")
    if throttle is not None and not (math.isfinite(throttle) and 0.0 <= throttle <= 1.0):
        # a percent looks like one (50, 75); 1.0000001 or 1.5 is no percent
        hint = (f" (did you mean {throttle / 100:g}? throttle is a fraction, not percent)"
                if math.isfinite(throttle) and 2.0 <= throttle <= 100.0 else "")
        fail_input(f"--throttle: must be a fraction in [0, 1], got {throttle!r}{hint}")
    case = load_case_with(case_file, sets, replaced(aircraft, propulsion, battery))
    refuse_implausible(case, "endurance", "endurance", as_json)
    # the throttle asked for first: its own reason, not one of the best search's throttles
    asked = solve_endurance(case, throttle) if throttle is not None else None
    best_result = solve_best(case) if best else None
    result = asked if asked is not None else best_result.endurance
    requirement = case.requirements.endurance
    judged = requirement is not None and abs(requirement.throttle - result.throttle) < 1e-12
    # the one verdict rule, on every reading of disputed evidence as check judges it
    verdict = (judged_block(case, "endurance", lambda: [
        with_flown_power(case, endurance_verdict(requirement, result))])[0] if judged else None)
    met = verdict is None or verdict.passed
    # the flights' flown/predicted power, as check prints it beside the endurance verdict (at
    # any throttle: it is the flown bins', not the throttle asked for)
    flown = flown_power_ratio(flown_flights(case)) if case.validation_flights else None
    render.show_endurance(case, result, best_result, requirement, verdict, as_json, flown)
    raise typer.Exit(0 if met else 1)
