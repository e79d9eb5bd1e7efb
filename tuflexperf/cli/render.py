"""Terminal and JSON rendering of every command's result: tables, verdicts, numbers.

The commands compute; this module only shows. Nothing here imports an analysis at the top
(``check`` stays light), and nothing here decides a verdict.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import typer

from tuflexperf.io.inputs import path_text
from tuflexperf.messages import CEILING_RULE, ceiling_text


def _json_default(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return path_text(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _clean(value: Any) -> Any:
    """NaN/inf become null, numpy scalars Python numbers and a file name's bytes that are no
    UTF-8 ``\\xfc``, so the JSON stays standard (a lone surrogate is no Unicode text)."""
    if hasattr(value, "item") and not hasattr(value, "__len__"):  # a float32 NaN too
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, str):
        return path_text(value)
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def emit_json(payload: dict[str, Any]) -> None:
    """``payload`` as one indented JSON object on stdout (NaN and inf as null)."""
    sys.stdout.write(json.dumps(_clean(payload), default=_json_default, indent=2) + "\n")


def fmt(value: float | None, digits: int = 3) -> str:
    """``value`` with ``digits`` decimals, or ``n/a`` for None and NaN."""
    # NaN is what a result holds where no value exists (an arc beyond cl_max): never printed
    return "n/a" if value is None or value != value else f"{value:.{digits}f}"


def print_warnings(warnings: list[str]) -> None:
    """Each warning as an indented note line."""
    for line in warnings:
        typer.echo(f"  note: {line}")


def _colours() -> bool:
    """Whether verdicts are coloured: on a terminal only, unless NO_COLOR is set."""
    import os

    return (sys.stdout.isatty() and "NO_COLOR" not in os.environ
            and os.environ.get("TERM") != "dumb")


#: each verdict's own colour on a terminal (UNPROVEN amber: neither met nor failed)
VERDICT_COLOURS = {"PASS": "green", "FAIL": "red", "UNPROVEN": "yellow"}


def verdict_word(verdict: bool | str) -> str:
    """PASS, FAIL or UNPROVEN (a bool: PASS or FAIL); on a terminal green, red or amber
    (rich's styles), elsewhere plain text."""
    word = verdict if isinstance(verdict, str) else "PASS" if verdict else "FAIL"
    if not _colours():
        return word
    from rich.color import ColorSystem
    from rich.style import Style

    return Style(color=VERDICT_COLOURS[word], bold=True).render(
        word, color_system=ColorSystem.STANDARD)


def overall_of(verdicts: list[Any]) -> str:
    """PASS, FAIL or UNPROVEN of several verdicts (the registry's rule)."""
    from tuflexperf.analysis.verdict import overall_verdict

    return overall_verdict([v.verdict for v in verdicts])


def print_disputed(verdict: Any) -> None:
    """An UNPROVEN verdict's disagreement, each reading's value and what would settle it."""
    if verdict.verdict == "UNPROVEN":
        typer.echo(f"  UNPROVEN: {verdict.reason}")
    print_readings(verdict.to_dict())


def print_readings(result: dict[str, Any]) -> None:
    """A disputed requirement's value on each reading, and what would settle an UNPROVEN."""
    for r in result.get("readings", []):
        value = "not attainable" if r["value"] is None else f"{r['value']:.4g}"
        typer.echo(f"  reading: {value} on {r['label']} "
                   f"({'met' if r['passed'] else 'not met'})")
    if result.get("verdict") == "UNPROVEN" and result.get("settle"):
        typer.echo(f"  to settle: {result['settle']}")


def cell(text: str, width: int = 10) -> str:
    """Right-aligned in ``width``; a longer value keeps a space before it (never run on)."""
    return text.rjust(width) if len(text) < width else " " + text


def name_width(names: Iterable[str]) -> int:
    """Width of the requirement column: 22, or the longest name and two spaces."""
    return max([22, *(len(n) + 2 for n in names)])


def replaced_files(case: Any) -> dict[str, str]:
    """The files a flag replaced for this run, by the case's key."""
    return {key: str(getattr(case, f"{key}_path")) for key in case.replaced}


def show_check(case: Any, verdicts: list[Any], results: list[dict[str, Any]], overall: str,
               plan: Any, probabilistic: dict[str, Any], outside: dict[str, int],
               sample_notes: list[str], as_json: bool) -> None:
    """``check``: the verdict table, and with samples P(met) per requirement."""
    if as_json:
        payload: dict[str, Any] = {
            "case": case.name,
            "case_file": str(case.path),
            "verdict": overall,
            "passed": overall == "PASS",
            "results": results,
        }
        if plan is not None:
            payload["uncertainty"] = {**plan.to_dict(), "samples_outside_bounds": outside,
                                      "notes": sample_notes}
        if case.replaced:  # said only when a flag replaced a file
            payload["files_replaced"] = replaced_files(case)
        emit_json(payload)
        return
    typer.echo(f"{case.name}  ({case.path})")
    for key, path in replaced_files(case).items():
        typer.echo(f"  {key}: {path} (--{key}, instead of the case's)")
    w = name_width(v.name for v in verdicts)
    header = (f"{'requirement':<{w}}{'value':>10}{'limit':>10}{'unit':>10}{'margin':>10}"
              "  verdict")
    typer.echo(header)
    typer.echo("-" * len(header))
    for v, r in zip(verdicts, results, strict=True):
        typer.echo(
            f"{v.name:<{w}}{cell(fmt(v.value))}{cell(fmt(v.limit))}{cell(v.unit)}"
            f"{cell(fmt(v.margin))}  {verdict_word(v.verdict)}"
        )
        if v.verdict == "UNPROVEN":  # the disagreement first, then what the analysis said
            typer.echo(f"  UNPROVEN: {v.reason}")
            typer.echo(f"  {v.details.get('nominal_reason', '')}")
        else:
            typer.echo(f"  {v.reason}")
        print_readings(r)
        print_warnings(v.details.get("warnings", []))
    if plan is not None:
        from tuflexperf.analysis.uncertainty import ENVELOPE_KEY, REFUSED_AIRCRAFT_KEY

        print_probabilities(plan, probabilistic)
        for r in results:
            if "probability_note" in r:
                typer.echo(f"{r['name']:<{name_width(probabilistic)}}  FAIL  "
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
    typer.echo(f"overall: {verdict_word(overall)}")


def print_probabilities(plan: Any, probabilistic: dict[str, Any]) -> None:
    typer.echo("")
    typer.echo(
        f"Monte Carlo: {plan.samples} samples, seed {plan.seed}; a requirement passes when the "
        f"95 % interval of P(met) lies at or above {plan.required_probability:g}"
    )
    w = name_width(probabilistic)
    header = (f"{'requirement':<{w}}{'P(met)':>8}{'95 % CI':>17}{'p05':>10}{'p50':>10}"
              f"{'p95':>10}{'n/a':>7}  verdict")
    typer.echo(header)
    typer.echo("-" * len(header))
    for name, p in probabilistic.items():
        low, high = p.probability_ci
        p05, p50, p95 = p.quantiles
        typer.echo(
            f"{name:<{w}}{p.probability:>8.4f}{f'[{low:.4f}, {high:.4f}]':>17}{fmt(p05):>10}"
            f"{fmt(p50):>10}{fmt(p95):>10}{p.not_attainable:>7}  "
            f"{verdict_word(p.verdict)}"
        )
        for _, label, probability, shown in p.readings:  # each reading of disputed evidence
            typer.echo(f"  P(met) {probability:.4f} on {label} "
                       f"({'shown' if shown else 'not shown'})")
    typer.echo("  (n/a: samples where the requirement is not attainable; they count as not met "
               "and as the worst value, so a percentile that falls on them shows n/a)")
    errors = getattr(plan, "errors", None)
    if errors is not None:
        from tuflexperf.analysis.error_model import listed

        typer.echo("error sources, drawn jointly (each sample one draw of every one):")
        for line in listed(errors.sources):
            typer.echo(f"  {line}")


def show_takeoff(case: Any, result: Any, requirement: Any, verdicts: list[Any], met: bool,
                 as_json: bool) -> None:
    """``takeoff``: the distances of each phase and the verdicts."""
    if as_json:
        payload = result.to_dict()
        if requirement is not None:
            payload["max_ground_roll_m"] = requirement.max_ground_roll_m
            payload["max_distance_to_obstacle_m"] = requirement.max_distance_to_obstacle_m
            payload["verdict"] = overall_of(verdicts)
            payload["passed"] = met
            payload["results"] = [v.to_dict() for v in verdicts]
        emit_json(payload)
        return
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
        f"  transition arc     {fmt(r.transition_distance_m, 2):>8} m  "
        f"(R {r.transition_radius_m:.1f} m at {r.transition_speed_m_s:.2f} m/s, "
        f"n {r.transition_load_factor:g})"
    )
    angle = r.climb_angle_deg
    typer.echo(
        f"  climb              {fmt(r.climb_distance_m, 2):>8} m  (sin(gamma) "
        f"{r.climb_gradient:.3f}" + ("" if angle is None else f", {angle:.1f} deg")
        + (": thrust above weight plus drag, a vertical climb" if r.climb_gradient >= 1.0
           else "") + ")"
    )
    typer.echo(
        f"  to {r.obstacle_height_m:g} m obstacle  {fmt(r.distance_to_obstacle_m, 2):>8} m"
        + ("  (cleared in the arc)" if r.obstacle_cleared_in_transition else "")
    )
    if r.obstacle_reason:
        typer.echo(f"  {r.obstacle_reason}")
    for v in verdicts:
        typer.echo(
            f"  {v.name:<30} {fmt(v.value, 2)} <= {v.limit:g} m  "
            f"{verdict_word(v.verdict)}"
        )
        print_disputed(v)


def throttle_table(
    airspeeds: list[float], throttles: list[float | None], reasons: list[str | None]
) -> None:
    typer.echo(f"  {'airspeed m/s':>12}  {'throttle':>8}")
    for v, x, why in zip(airspeeds, throttles, reasons, strict=True):
        typer.echo(f"  {v:12.1f}  {f'  not attainable: {why}' if x is None else f'{x:8.3f}'}")


def show_trim(case: Any, result: Any, verdict: Any, limit: float, table: bool,
              as_json: bool) -> None:
    """``trim``: the least and highest throttle over the envelope, and the verdict."""
    data = result.to_dict()
    met = verdict.passed
    if as_json:
        emit_json({**data, "max_trim_throttle": limit, "verdict": verdict.verdict,
                   "passed": met, "result": verdict.to_dict()})
        return
    v = data["airspeed_m_s"]
    typer.echo(f"{case.name}: trim over {v[0]:.4g}-{v[-1]:.4g} m/s ({len(v)} airspeeds)")
    if result.min_throttle is None:
        typer.echo("  least throttle   none: level flight attainable nowhere in the envelope")
    else:
        typer.echo(
            f"  least throttle   {result.min_throttle:.3f} at "
            f"{result.airspeed_at_min_throttle_m_s:.1f} m/s"
        )
    typer.echo(f"  highest throttle {fmt(result.max_throttle)} (limit {limit:g})")
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
        throttle_table(v, data["throttle"], data["not_attainable_reason"])
    print_warnings(data["warnings"])
    # the verdict and why, as take-off and OEI print theirs (SPEC 5: exit 1 says why)
    why = (verdict.reason if verdict.value is None else
           f"highest throttle {verdict.value:.3f} above the limit {limit:g}")
    typer.echo(f"  {verdict.name}: {verdict_word(verdict.verdict)}"
               + ("" if met or verdict.verdict == "UNPROVEN" else f" ({why})"))
    print_disputed(verdict)


def show_oei(case: Any, result: Any, limit: float, verdict: Any, as_json: bool) -> None:
    """``oei``: each engine dead in turn, the worse case and the verdict."""
    data = result.to_dict()
    worst = result.critical
    if as_json:
        emit_json({**data, "max_throttle": limit, "verdict": verdict.verdict,
                   "passed": verdict.passed, "result": verdict.to_dict()})
        return
    typer.echo(f"{case.name}: one engine inoperative ({result.dead_engine_mode} dead engine)")
    for c in result.cases:
        span = c.level_flight_airspeed_range_m_s
        typer.echo(
            f"  {c.dead_engine} dead: level flight attainable nowhere in the envelope"
            if span is None else
            f"  {c.dead_engine} dead: least throttle {fmt(c.min_throttle)} at "
            f"{fmt(c.airspeed_at_min_throttle_m_s, 1)} m/s; level flight "
            f"{span[0]:.2f}-{span[1]:.2f} m/s"
        )
        if c.min_throttle is None or not c.all_feasible:
            from tuflexperf.analysis.attainable import describe_unattainable

            for phrase in describe_unattainable(c.airspeed_m_s, c.reasons):
                typer.echo(f"    not attainable: {phrase}")
    typer.echo(
        f"  worse case: {worst.dead_engine} dead, "
        + ("not attainable" if worst.min_throttle is None
           else f"throttle {fmt(worst.min_throttle)}")
        + f" (limit {limit:g})  {verdict_word(verdict.verdict)}"
    )
    print_disputed(verdict)
    print_warnings(data["warnings"])


def show_performance(case: Any, result: Any, attainable: bool, as_json: bool) -> None:
    """``performance``: the point-performance table."""
    data = result.to_dict()
    if as_json:
        emit_json({**data, "attainable": attainable})
        return
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
        ("max climb gradient sin(gamma)", r.max_climb_gradient, "-"),
        ("  at Vx", r.best_climb_angle_speed_m_s, "m/s"),
        ("service ceiling (0.5 m/s)", r.service_ceiling_m, "m"),
        ("absolute ceiling", r.absolute_ceiling_m, "m"),
        (f"OEI max climb sin(gamma) ({r.oei_dead_engine_mode})", r.oei_max_climb_gradient,
         "-"),
        ("OEI max level speed", r.oei_max_level_speed_m_s, "m/s"),
        (f"take-off to {r.takeoff_obstacle_height_m:g} m obstacle",
         r.takeoff_distance_to_obstacle_m, "m"),
    ]
    if r.jet_velocity_ceiling_m_s is not None:  # the fans make no thrust from there on
        rows.append(("fans' static jet velocity", r.jet_velocity_ceiling_m_s, "m/s"))
    ceilings = {"service ceiling (0.5 m/s)", "absolute ceiling"}
    for label, value, unit in rows:
        shown = (ceiling_text(value) if label in ceilings and value is not None
                 else fmt(value, 3 if unit == '-' else 2))
        typer.echo(f"  {label:<36}{shown:>10} {unit}")
    typer.echo(f"  ({CEILING_RULE})")
    worst = r.oei_critical
    if worst is not None:
        typer.echo(f"  (OEI worse case: {worst.dead_engine} dead)")
    for note in r.notes:
        typer.echo(f"  {note}")
    if not attainable:
        typer.echo("  NOT ATTAINABLE: no level flight at full throttle above stall")
    print_warnings(list(r.warnings))


def show_mission(case: Any, result: Any, verdicts: list[Any], csv: Path | None,
                 as_json: bool) -> None:
    """``mission``: one row per segment, the landing charge and its verdict."""
    if as_json:
        emit_json({**result.to_dict(), "verdict": overall_of(verdicts),
                   "passed": all(v.passed for v in verdicts),
                   "results": [v.to_dict() for v in verdicts]})
        return
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
    packs_wh = sum(sum(s.energy_wh) for s in result.segments)
    if result.launch_kinetic_energy_wh > 0.0:  # what the catapult gave, beside the packs'
        typer.echo(f"  energy: {packs_wh:.1f} Wh from the packs + "
                   f"{result.launch_kinetic_energy_wh:.2f} Wh of the catapult's release "
                   f"(m V^2 / 2) = {packs_wh + result.launch_kinetic_energy_wh:.1f} Wh")
    for note in result.warnings:  # the JSON's "warnings": said in the text too
        typer.echo(f"  note: {note}")
    landing, *solved = verdicts
    typer.echo(f"  {result.reason}  {verdict_word(landing.verdict)}")
    print_disputed(landing)
    for verdict in solved:  # solve_for: the longest segment against the file's own
        # the flight above (the first reading); each reading's value follows where disputed
        flown = verdict.readings[0].value if verdict.readings else verdict.value
        value = "not attainable" if flown is None else f"{flown:.2f} min"
        typer.echo(f"  solve_for: {value}, {verdict.details.get('nominal_reason', verdict.reason)}"
                   f"  {verdict_word(verdict.verdict)}")
        print_disputed(verdict)
    if csv is not None:
        typer.echo(f"  wrote {csv}")


def show_endurance(case: Any, result: Any, best_result: Any, requirement: Any,
                   verdict: Any, as_json: bool, flown: dict[str, Any] | None = None) -> None:
    """``endurance``: airspeed, power, pack and flight endurance, and the best throttles
    (``verdict`` None: the throttle asked for is not the requirement's, nothing judged);
    ``flown`` the validation flights' flown/predicted power (``check``'s ``flown_power``)."""
    data = result.to_dict()
    if as_json:
        payload = dict(data)
        if flown is not None:
            payload["flown_power"] = flown
        if best_result is not None:
            payload["best"] = best_result.to_dict()
        if verdict is not None:
            payload["min_flight_time_min"] = requirement.min_flight_time_min
            payload["verdict"] = verdict.verdict
            payload["passed"] = verdict.passed
            payload["result"] = verdict.to_dict()
        emit_json(payload)
        return
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
    if verdict is not None:
        typer.echo(
            f"  requirement: >= {requirement.min_flight_time_min:g} min  "
            f"{verdict_word(verdict.verdict)}"
        )
        print_disputed(verdict)
    if flown is not None:
        from tuflexperf.analysis.flown_reading import flown_power_note

        print_warnings([flown_power_note(flown)])
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
    print_warnings(data["warnings"])


def echo_electrical(electrical: dict[str, Any] | None) -> None:
    """fit's voltage, power-surface, windmilling and thrust/power lines (logged V and I)."""
    if not electrical or electrical.get("reference_voltage_v") is None:
        return
    fits = electrical["voltage_fits"]
    per_engine = ", ".join(
        f"{name} {fmt(f['exponent'], 3)} +- {fmt(f['standard_error'], 3)}"
        for name, f in fits.items()
    )
    exponent = electrical["voltage_exponent"]
    typer.echo(
        f"pack voltage: reference {electrical['reference_voltage_v']:g} V; thrust ~ (U/U_ref)^n, "
        + (f"n = {exponent:.3f} ({per_engine}); thrust brought to U_ref"
           if exponent is not None else f"n not determined ({per_engine}); default 2")
    )
    for name, power in electrical["power"].items():
        typer.echo(f"power surface {name}: poly22 in W, R^2 {fmt(power['r2'], 4)}, "
                   f"RMSE {fmt(power['rmse_w'], 0)} W over {power['n_points']} points")
    for name, agree in electrical["thrust_power_agreement"].items():
        merit, eff = agree["figure_of_merit_range"], agree["overall_efficiency_range"]
        if merit:
            typer.echo(
                f"thrust vs power {name}: figure of merit {merit[0]:.2f}-{merit[1]:.2f}"
                + (f", overall efficiency {eff[0]:.2f}-{eff[1]:.2f}" if eff else "")
                + f" over {agree['working_points']} working points"
            )


def echo_windmilling(windmilling: dict[str, Any] | None) -> None:
    """fit's windmilling line per engine: estimated from the throttle-0 holds, or why not."""
    if not windmilling:
        return
    for name, wm in windmilling["engines"].items():
        if wm["estimated"]:
            low, high = wm["airspeed_range_m_s"]
            typer.echo(
                f"windmilling {name}: windmilling_drag_coefficient "
                f"{wm['windmilling_drag_coefficient']:.3f} estimated from {wm['n_points']} "
                f"throttle-0 holds at {low:.1f}-{high:.1f} m/s (rms {wm['rms_n']:.2f} N), on "
                f"the disk area fan_area_m2 {windmilling['fan_area_m2']:g} m^2; written to the "
                "file")
        else:
            typer.echo(f"windmilling {name}: not estimated: {wm['reason']}")


def echo_lack_of_fit(summary: dict[str, Any]) -> None:
    """Each engine's lack-of-fit test, one line, and the rig's systematic errors."""
    for e in summary["engines"]:
        lof = e.get("lack_of_fit")
        if lof is None:
            typer.echo(f"lack of fit {e['name']}: not tested (no repeated holds and no samples "
                       "inside the holds)")
            continue
        p = lof["p_value"]
        basis = "replicate holds" if lof["pure_error_basis"] == "replicate_holds" else \
            "within-hold scatter"
        typer.echo(
            f"lack of fit {e['name']}: F {fmt(lof['f_statistic'], 2)} on {lof['dof_lack_of_fit']}"
            f"/{lof['dof_pure_error']} dof, p {'n/a' if p is None else f'{p:.2g}'}; model-form "
            f"{fmt(lof['model_form_rms_n'])} N rms vs pure error {fmt(lof['pure_error_rms_n'])} N "
            f"({basis}); worst x {lof['worst_throttle']:.2f}, {lof['worst_airspeed_m_s']:.1f} m/s "
            f"({lof['worst_residual_n']:+.3f} N): "
            + ("no F (the pure error is 0)" if p is None else "fits" if p >= 0.01
               else "DOES NOT FIT its data")
        )
    rig = summary.get("rig_uncertainty")
    if rig:
        runs = {k: f", {e['runs']} runs' idle holds" for k, e in rig["estimates"].items()}
        parts = [f"{key} {rig['values'][key]:.3g} ({rig['basis'][key]}"
                 f"{runs.get(key, '') if rig['basis'][key] == 'estimated' else ''})"
                 for key in rig["values"]]
        typer.echo("rig uncertainty (sd): " + ", ".join(parts))


def print_fit(summary: dict[str, Any]) -> None:
    """``fit``'s table: each engine's poly22, its quality, and the full-throttle thrust at
    rest and at the top of the tested airspeeds."""
    typer.echo(f"poly22 fit of {summary['input']} ({summary['kind']})")
    top = float((summary.get("tested_airspeed_m_s") or [0.0, 30.0])[1])
    label = f"T(1,{top:g})"
    width = max(8, len(label) + 1)
    header = (
        f"{'engine':<8}{'n':>4}{'p00':>9}{'p10':>9}{'p01':>9}{'p20':>9}{'p11':>9}{'p02':>11}"
        f"{'R^2':>9}{'RMSE N':>8}{'T(1,0)':>8}{label:>{width}}"
    )
    typer.echo(header)
    typer.echo("-" * len(header))
    for e in summary["engines"]:
        c = e["coefficients"]
        full = e["full_throttle_thrust_n"]
        at_top = (c["p00"] + c["p10"] + c["p20"] + (c["p01"] + c["p11"]) * top
                  + c["p02"] * top * top)
        typer.echo(
            f"{e['name']:<8}{e['n_points']:>4}{c['p00']:>9.4f}{c['p10']:>9.4f}{c['p01']:>9.4f}"
            f"{c['p20']:>9.4f}{c['p11']:>9.4f}{c['p02']:>11.3e}{fmt(e['r2'], 5):>9}"
            f"{fmt(e['rmse_n']):>8}{full['0']:>8.2f}{at_top:>{width}.2f}"
        )
    delay = summary.get("delay_s")
    runs = summary.get("delay_runs", [])
    line = f"delay: {fmt(delay)} s"
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
    echo_electrical(summary.get("electrical"))
    echo_windmilling(summary.get("windmilling"))
    echo_lack_of_fit(summary)
    runs = [r for r in summary.get("runs", []) if "validation" in r]
    if runs:
        typer.echo("validation, model - measured force over steady segments (mean -/+, N):")
        width = max(len(str(r["file"])) for r in runs) + 2
        for r in runs:
            v = r["validation"]
            typer.echo(
                f"  {r['file']:<{width}}{r['engine']:<8}{fmt(v['mean_negative_error_n'], 2):>7} / "
                f"+{fmt(v['mean_positive_error_n'], 2)}   {r['segments']} segments"
            )
    print_warnings(summary.get("warnings", []))
    typer.echo(f"wrote {summary['out']}" + (f" and {summary['table']}" if summary["table"] else ""))


def show_fit(summary: dict[str, Any], as_json: bool) -> None:
    """``fit``: the propulsion fit's table and checks, or the battery fit's pack model."""
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
        correction = fit.get("power_correction")
        if correction is None:
            typer.echo("  no measured power correction (no propulsion.yaml beside the file)")
        else:
            ratios = ", ".join(f"{Path(r['file']).name} x{r['ratio']:.3f}"
                               for r in correction["runs"])
            typer.echo(f"  measured power correction ({correction['form']}) against "
                       f"{correction['model']} ({correction['propulsion']}): {ratios}")
        typer.echo(f"wrote {summary['out']}")
    else:
        print_fit(summary)


def show_report(result: Any, as_json: bool) -> None:
    """``report``: the files written and whether every requirement is met."""
    if as_json:
        emit_json(result.to_dict())
        return
    typer.echo(
        f"wrote {len(result.files)} files to {result.out_dir} "
        f"({result.pages}-page {result.pdf.name}, {result.seconds:.1f} s); requirements "
        + ("all met" if result.passed else "NOT all shown met (UNPROVEN)"
           if result.verdict == "UNPROVEN" else "NOT all met")
    )
    for path in result.files:
        typer.echo(f"  {path.name}")
    for note in result.notes:
        typer.echo(f"  note: {note}")



def show_export(result: Any, as_json: bool) -> None:
    """``export``: the files written and the reference voltage of the thrust."""
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


def show_mission_not_flown(name: str, reason: str, limit: float | None, as_json: bool) -> None:
    """``mission`` that could not be flown: the mission's own keys, nothing flown (SPEC 5)."""
    if as_json:
        emit_json({"command": "mission", "mission": name, "verdict": "FAIL", "passed": False,
                   "attainable": False, "reason": reason,
                   "landing_charge_fraction": None, "min_landing_charge_fraction": limit,
                   "segments": []})
    sys.stderr.write(f"tuflexperf: not attainable: {reason}\n")


def show_implausible(command: str, found: list[Any], as_json: bool,
                     keys: dict[str, Any] | None = None) -> None:
    """A command refused on data physics forbids: FAIL, one line per reason (issue 43);
    ``keys`` the command's own JSON keys, null."""
    if as_json:
        emit_json({"command": command, "passed": False, "verdict": "FAIL",
                   "reason": "; ".join(f.reason for f in found),
                   "implausible": [f.to_dict() for f in found], **(keys or {})})
    for f in found:
        sys.stderr.write(f"tuflexperf: FAIL: {f.reason}\n")


def history_csv(history: dict[str, Any]) -> str:
    """A mission's time history as CSV text: a header, then one row per time step."""
    names = list(history)
    rows = zip(*(history[k] for k in names), strict=True)
    return ",".join(names) + "\n" + "".join(
        ",".join(f"{value:.10g}" for value in row) + "\n" for row in rows
    )


def show_init(result: Any, as_json: bool) -> None:
    """``init``: the files written, what the datasheet gave, and the next command."""
    if as_json:
        emit_json(result.to_dict())
        return
    typer.echo(f"wrote {len(result.files)} files to {result.folder}")
    if len(result.files) <= 12:
        for path in result.files:
            typer.echo(f"  {path}")
    m = result.model
    if m is not None:
        typer.echo(
            f"  propulsion: momentum theory from {m.sheet.static_thrust_n:g} N, "
            f"{m.sheet.max_power_w:g} W, {m.sheet.fan_diameter_m:g} m: jet velocity "
            f"{m.jet_velocity_m_s:.1f} m/s, figure of merit {m.figure_of_merit:.2f}, thrust "
            f"+- {m.thrust_sd_n:.3g} N (1 sd)")
        typer.echo(f"  battery: stand-in discharge runs of the datasheet's circuit, "
                   f"{1000 * m.resistance_per_cell_ohm:.3g} mOhm per cell, "
                   f"{m.packs_in_parallel} pack(s) per fan")
    typer.echo(f"next: tuflexperf check {result.case}")
