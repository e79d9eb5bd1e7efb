"""Requirement verdicts: each requirement block in the case -> value, limit, margin, and
PASS, FAIL or UNPROVEN.

Each requirement is judged on the nominal case and on every reading of disputed evidence
that bears on its block (:mod:`tuflexperf.analysis.readings`): met on all PASS, on none
FAIL, on some UNPROVEN (:func:`tuflexperf.analysis.verdict.on_readings`).

Margins are signed so that positive means met: ``limit - value`` for upper
limits (ground roll, throttle), ``value - limit`` for lower limits (endurance).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from tuflexperf.analysis.verdict import (
    PASS,
    Verdict,
    mission_verdicts,
    on_readings,
    overall_verdict,
    requirement_met,
    same_value,
)
from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.io.mission import mission_path as mission_path  # the commands ask here

if TYPE_CHECKING:
    from tuflexperf.analysis.study import Study


def _takeoff(study: Study) -> list[Verdict]:
    requirement = study.case.requirements.takeoff
    verdicts: list[Verdict] = []
    try:
        result = study.takeoff()
    except NotAttainable as exc:
        if requirement.max_ground_roll_m is not None:
            verdicts.append(
                Verdict("takeoff_ground_roll", None, requirement.max_ground_roll_m, "m", "max",
                        str(exc))
            )
        if requirement.max_distance_to_obstacle_m is not None:
            verdicts.append(
                Verdict("takeoff_distance_to_obstacle", None,
                        requirement.max_distance_to_obstacle_m, "m", "max", str(exc))
            )
        return verdicts
    return takeoff_verdicts(requirement, result)


def takeoff_verdicts(requirement: Any, result: Any) -> list[Verdict]:
    """Ground-roll and distance-to-obstacle verdicts of a solved take-off (either may be absent).

    ``requirement`` is the case's ``TakeoffRequirement``, ``result`` a ``TakeoffResult``.
    """
    verdicts: list[Verdict] = []
    warnings = {"warnings": list(result.warnings)}
    rotation = (
        f" (incl. {result.rotation_distance_m:.1f} m of rotation)"
        if result.rotation_time_s > 0 else ""
    )
    if requirement.max_ground_roll_m is not None:
        verdicts.append(
            Verdict(
                "takeoff_ground_roll",
                result.ground_roll_m,
                requirement.max_ground_roll_m,
                "m",
                "max",
                (f"catapult release at {result.liftoff_speed_m_s:.1f} m/s "
                 f"({result.liftoff_speed_eas_m_s:.1f} m/s EAS): no runway"
                 if result.launch == "catapult" else
                 f"lift-off at {result.liftoff_speed_m_s:.1f} m/s "
                 f"({result.liftoff_speed_eas_m_s:.1f} m/s EAS) after {result.time_s:.1f} s"
                 + rotation),
                warnings,
            )
        )
    if requirement.max_distance_to_obstacle_m is not None:
        if result.distance_to_obstacle_m is None:
            reason = result.obstacle_reason
        else:
            reason = (
                f"ground roll {result.ground_roll_m:.1f} m + airborne "
                f"{result.airborne_distance_m:.1f} m to {result.obstacle_height_m:g} m "
                + ("(cleared in the transition arc)" if result.obstacle_cleared_in_transition
                   else f"(arc {result.transition_distance_m:.1f} m, climb "
                        f"{result.climb_distance_m:.1f} m at {result.climb_angle_deg:.1f} deg)")
            )
        verdicts.append(
            Verdict(
                "takeoff_distance_to_obstacle",
                result.distance_to_obstacle_m,
                requirement.max_distance_to_obstacle_m,
                "m",
                "max",
                reason,
                warnings,
            )
        )
    return verdicts


def _trim(study: Study) -> Verdict:
    return trim_verdict(study.case.requirements.envelope, study.trim())


def trim_verdict(envelope: Any, result: Any) -> Verdict:
    """The trim requirement's verdict from a solved trim sweep (the CLI's ``trim`` too)."""
    # the grid's ends are the envelope's true airspeeds (converted from EAS bounds)
    span = f"{result.airspeed_m_s[0]:.4g}-{result.airspeed_m_s[-1]:.4g} m/s"
    if not result.all_feasible:
        from tuflexperf.analysis.attainable import describe_unattainable

        reason = "not attainable: " + "; ".join(
            describe_unattainable(result.airspeed_m_s, result.reasons)
        ) + (
            f" (stall {result.stall_speed_m_s:.2f} m/s x {result.stall_margin:g})"
        )
    else:
        reason = (
            f"highest trim throttle over {span}; least {result.min_throttle:.3f} "
            f"at {result.airspeed_at_min_throttle_m_s:g} m/s"
        )
    return Verdict(
        "trim_throttle_max",
        result.max_throttle,
        envelope.max_trim_throttle,
        "fraction",
        "max",
        reason,
        {
            "min_throttle": result.min_throttle,
            "least_attainable_airspeed_m_s": result.attainable.low,
            "warnings": list(result.warnings),
        },
    )


def _oei(study: Study) -> Verdict:
    requirement = study.case.requirements.oei
    return oei_verdict(requirement, study.oei(requirement.dead_engine))


def oei_verdict(requirement: Any, result: Any) -> Verdict:
    """The OEI verdict of a solved OEI case (``requirement`` None: full throttle the limit)."""
    if requirement is None:
        from tuflexperf.io.case import OeiRequirement

        requirement = OeiRequirement(dead_engine=result.dead_engine_mode)
    worst = result.critical
    if worst.min_throttle is None:
        from tuflexperf.analysis.attainable import describe_unattainable

        reason = (
            f"no level flight anywhere in the envelope with {worst.dead_engine} dead: "
            + "; ".join(describe_unattainable(worst.airspeed_m_s, worst.reasons))
        )
    else:
        low, high = worst.level_flight_airspeed_range_m_s
        reason = (
            f"{worst.dead_engine} dead ({requirement.dead_engine}): least throttle at "
            f"{worst.airspeed_at_min_throttle_m_s:g} m/s, level flight {low:.2f}-{high:.2f} m/s"
        )
    return Verdict(
        "oei_min_throttle",
        worst.min_throttle,
        requirement.max_throttle,
        "fraction",
        "max",
        reason,
        {"warnings": list(result.warnings)},
    )


def _endurance(study: Study) -> Verdict:
    requirement = study.case.requirements.endurance
    try:
        result = study.endurance(requirement.throttle)
    except NotAttainable as exc:
        verdict = Verdict(
            "flight_endurance", None, requirement.min_flight_time_min, "min", "min", str(exc)
        )
    else:
        verdict = endurance_verdict(requirement, result)
    return with_flown_power(study.case, verdict)


def with_flown_power(case: Case, verdict: Verdict) -> Verdict:
    """The validation flights' flown/predicted power beside the endurance verdict (its JSON's
    ``flown_power``, and a note), within the tolerance or not (issue 45 item 3); ``check``'s
    and the ``endurance`` command's verdict alike."""
    from tuflexperf.analysis.flown_reading import (
        flown_flights,
        flown_power_note,
        flown_power_ratio,
    )

    ratio = flown_power_ratio(flown_flights(case)) if case.validation_flights else None
    if ratio is None:
        return verdict
    warnings = [*verdict.details.get("warnings", []), flown_power_note(ratio)]
    return dataclasses.replace(verdict, details={**verdict.details, "warnings": warnings,
                                                 "flown_power": ratio})


def endurance_verdict(requirement: Any, result: Any) -> Verdict:
    """The endurance verdict of a solved endurance at the requirement's throttle.

    A cruise that ends at the packs' cut-off before the landing reserve is no endurance
    with a reserve: the ESC cuts the fans in cruise with the reserve's charge still in
    packs that cannot give the cruise's power, so nothing is kept in hand to land on. It is
    not attainable (FAIL), with the time to the cut-off in the reason (issue 43: it passed
    with a note).
    """
    if result.cruise_ends_at == "cut-off":
        return Verdict(
            "flight_endurance", None, requirement.min_flight_time_min, "min", "min",
            f"at throttle {requirement.throttle:g} the cruise ends at the packs' cut-off after "
            f"{result.flight_endurance_min:.1f} min of flight, before the landing reserve "
            f"({100 * result.landing_reserve_fraction:g} %): the ESC cuts the fans in cruise "
            "and no reserve is kept to land on",
            {"warnings": list(result.warnings),
             "time_to_cutoff_min": result.flight_endurance_min},
        )
    return Verdict(
        "flight_endurance",
        result.flight_endurance_min,
        requirement.min_flight_time_min,
        "min",
        "min",
        f"at throttle {requirement.throttle:g}, {result.airspeed_m_s:.1f} m/s, "
        f"{result.electrical_power_w:.0f} W per fan",
        {"warnings": list(result.warnings)},
    )


def _mission(study: Study) -> Verdict | list[Verdict]:
    limit = study.case.requirements.mission.min_landing_charge_fraction
    try:
        result = study.mission()
    except NotAttainable as exc:
        return Verdict("mission_landing_charge", None, limit, "fraction", "min", str(exc))
    return mission_verdicts(result)


CHECKS = {"takeoff": _takeoff, "envelope": _trim, "oei": _oei, "endurance": _endurance,
          "mission": _mission}


def study_verdicts(study: Study) -> list[Verdict]:
    """Verdicts for every requirement block present in the study's case, in SPEC order.

    Each verdict reads the study's memoised result, so a command or figure that asks the
    same study again gets the very result the verdict was made from.
    """
    return study.once("verdicts", lambda: _judge(study))


def _judge(study: Study) -> list[Verdict]:
    requirements = study.case.requirements
    verdicts: list[Verdict] = []
    for name in CHECKS:
        if getattr(requirements, name) is not None:
            # on every reading, then the one plausibility rule: data physics forbids FAIL
            verdicts.extend(implausible_verdict(v, study.plausibility(), name)
                            for v in block_verdicts(study, name))
    return verdicts


def _block(study: Study, block: str) -> list[Verdict]:
    def judge() -> list[Verdict]:
        result = CHECKS[block](study)
        return result if isinstance(result, list) else [result]

    # a command's own verdicts of the result it solved stand for the nominal (judged_block)
    return study.once(("nominal", block), judge)


def block_verdicts(study: Study, block: str) -> list[Verdict]:
    """The verdicts of one requirement block, judged on the nominal case and on every
    reading whose ``affects`` holds the block (each reading's study built only then).

    A reading whose value equals the nominal's is left out of the verdict: the disputed
    input never entered it (thrust inside the tested airspeeds, a flight with no dead
    engine). One that moves the thrust beyond the tested airspeeds only is not flown for a
    block whose nominal flight stays inside them: its value there is the nominal's.
    """
    nominal = _block(study, block)
    readings = [r for r in study.readings() if block in r.affects
                and not (r.beyond_tested_only and not _beyond_tested(study, block))]
    if not readings:
        return nominal
    others = [(r, {v.name: v for v in _block(study.on_reading(r), block)}) for r in readings]
    return _judged_on_readings(nominal, others)


def _beyond_tested(study: Study, block: str) -> bool:
    """Whether the nominal flight of ``block`` flies the thrust model beyond its tested
    airspeeds (its result's ``extrapolated``); a block not flown, or not attainable, may."""
    requirements = study.case.requirements
    flights: dict[str, Callable[[], Any]] = {
        "takeoff": study.takeoff, "envelope": study.trim, "oei": study.oei,
        "endurance": lambda: study.endurance(requirements.endurance.throttle)}
    if block not in flights:
        return True
    try:
        return bool(flights[block]().extrapolated)
    except NotAttainable:
        return True


def mission_file_verdicts(case: Case, plan: Any, limit: float | None,
                          result: Any) -> list[Verdict]:
    """A mission file's verdicts (``mission FILE``, not the case's own requirement) judged on
    every reading of the case's disputed evidence, as ``check`` judges the case's mission.

    ``plan`` the loaded mission, ``limit`` the reserve [fraction] or None for the file's own,
    ``result`` its flight on the case as given. A reading the flight never meets (thrust
    inside the tested airspeeds, no engine failure) leaves its value and is left out.
    """
    from tuflexperf.analysis.evidence import case_readings
    from tuflexperf.analysis.mission import solve_mission

    others = []
    for reading in case_readings(case):
        try:
            flown = mission_verdicts(solve_mission(reading.case, plan, limit))
        except NotAttainable:
            flown = []
        others.append((reading, {v.name: v for v in flown}))
    return _judged_on_readings(mission_verdicts(result), others)


def _judged_on_readings(nominal: list[Verdict],
                        others: list[tuple[Any, dict[str, Verdict]]]) -> list[Verdict]:
    """Each nominal verdict paired with its verdict on every reading that changes its value."""
    out = []
    for verdict in nominal:
        paired = []
        for reading, theirs in others:
            other = theirs.get(verdict.name)
            if other is None:  # the reading's flight ended sooner (a mission not flown)
                other = Verdict(verdict.name, None, verdict.limit, verdict.unit, verdict.kind)
            if not same_value(other.value, verdict.value):
                paired.append((reading, other))
        out.append(on_readings(verdict, paired))
    return out


def judged_block(case: Case, block: str,
                 nominal: Callable[[], list[Verdict]] | None = None) -> list[Verdict]:
    """One block's verdicts as ``check`` makes them (a fresh :class:`Study`): a single
    analysis' command (``trim``, ``oei``, ``takeoff``, ``endurance``) gives the same verdict.
    ``nominal`` the command's own verdicts of the result it solved (the study memoises
    nothing of it); the readings are solved here."""
    from tuflexperf.analysis.study import Study

    study = Study(case)
    if nominal is not None:
        study.once(("nominal", block), nominal)
    return block_verdicts(study, block)


def case_verdict(verdicts: list[Verdict]) -> str:
    """The case's verdict: any FAIL fails, else any UNPROVEN is UNPROVEN, else PASS."""
    return overall_verdict([v.verdict for v in verdicts])


# --- plausibility (issue 43 item 3): no verdict on data physics forbids passes ---------------
def implausible_verdict(verdict: Verdict, found: Any, block: str) -> Verdict:
    """``verdict`` as a FAIL with the plausibility reasons that bear on requirement ``block``
    (:func:`tuflexperf.analysis.plausibility.implausible`), else unchanged.

    The value flown on such data is no value the evidence backs: it is kept in the details
    (``value_on_implausible_data``) and the verdict has none, as a not-attainable one.
    """
    reasons = [f.reason for f in found if block in f.blocks]
    if not reasons:
        return verdict
    # the value the implausible surface flew is the nominal reading's (the first), each
    # other reading's kept beside it: none of them is evidence, so no reading can pass
    flown = verdict.readings[0].value if verdict.readings else verdict.value
    others = {r.key: r.value for r in verdict.readings[1:]}
    return Verdict(verdict.name, None, verdict.limit, verdict.unit, verdict.kind,
                   "; ".join(reasons),
                   {**verdict.details, "value_on_implausible_data": flown,
                    **({"readings_on_implausible_data": others} if others else {}),
                    "implausible": [f.to_dict() for f in found if block in f.blocks]})


def check_case(case: Case) -> list[Verdict]:
    """Verdicts for every requirement block present in ``case`` (a fresh :class:`Study`)."""
    from tuflexperf.analysis.study import Study

    return study_verdicts(Study(case))


# --- probabilistic verdicts (check --samples, SPEC 4 uncertainty block) --------------------
CONFIDENCE = 0.95


@dataclass(frozen=True)
class ProbabilisticVerdict:
    """How likely one requirement is met over the samples, and whether that is enough.

    ``passed`` when the lower end of the two-sided 95 % Clopper-Pearson interval of
    P(met) is at least ``required_probability`` (Hanson & Beard, NASA/TP-2010-216447:
    a requirement shown met in y % of cases at a stated confidence). A not-attainable
    sample counts as not met.
    """

    name: str
    samples: int
    met: int
    not_attainable: int
    probability_ci: tuple[float, float]
    quantiles: tuple[float | None, float | None, float | None]
    required_probability: float
    # where readings of disputed evidence bear on it: (key, label, P(met), passed) on each,
    # the nominal first; the counts above are then the worse reading's (met on every one)
    readings: tuple[tuple[str, str, float, bool], ...] = ()

    @property
    def probability(self) -> float:
        return self.met / self.samples

    @property
    def verdict(self) -> str:
        """PASS when P(met) is shown on every reading, FAIL on none, else UNPROVEN."""
        if not self.readings:
            return PASS if self.probability_ci[0] >= self.required_probability else "FAIL"
        shown = [r[3] for r in self.readings]
        return PASS if all(shown) else "FAIL" if not any(shown) else "UNPROVEN"

    @property
    def passed(self) -> bool:
        return self.verdict == PASS

    def to_dict(self) -> dict[str, Any]:
        p05, p50, p95 = self.quantiles
        extra: dict[str, Any] = {}
        if self.readings:
            extra["probability_readings"] = [
                {"key": k, "label": label, "probability": p, "passed": ok}
                for k, label, p, ok in self.readings]
        return {
            "probability": self.probability,
            "probability_ci": list(self.probability_ci),
            "p05": p05,
            "p50": p50,
            "p95": p95,
            "samples": self.samples,
            "samples_met": self.met,
            "samples_not_attainable": self.not_attainable,
            "required_probability": self.required_probability,
            "probability_verdict": self.verdict,
            "probability_passed": self.passed,
            **extra,
        }


NOT_SAMPLED = ("not sampled: this mission is flown for the nominal case only (its nominal plan "
               "is not attainable, or a drawn key it does not fly; analysis.mission_samples), "
               "so its P(met) is not shown "
               "and it does not pass the probabilistic test")


def sampled_result(verdict: Verdict, probabilistic: ProbabilisticVerdict | None) -> dict[str, Any]:
    """One requirement's JSON with its samples: ``passed`` is the verdict the exit code
    follows (the nominal case met and P(met) shown), ``nominal_passed`` the nominal alone.

    A ``passed: true`` beside a failed probability read as "met" to any tool that reads
    the results (outside audit): the overall verdict and each result's now agree. A
    requirement the samples do not evaluate (a mission the batch cannot fly yet,
    :func:`tuflexperf.analysis.mission_samples.why_not_sampled`) has no P(met) to show: it
    does not pass (a case whose mission lands on the reserve only nominally passed).
    """
    if probabilistic is None:
        return {**verdict.to_dict(), "probability": None, "probability_note": NOT_SAMPLED,
                "nominal_verdict": verdict.verdict, "nominal_passed": verdict.passed,
                "verdict": "FAIL", "passed": False}
    both = overall_verdict([verdict.verdict, probabilistic.verdict])
    return {**verdict.to_dict(), **probabilistic.to_dict(), "nominal_verdict": verdict.verdict,
            "nominal_passed": verdict.passed, "verdict": both, "passed": both == PASS}


def probabilistic_verdicts(samples: Any) -> dict[str, ProbabilisticVerdict]:
    """Per requirement of a :class:`tuflexperf.analysis.uncertainty.SampleSet`."""
    from functools import cache

    from tuflexperf.analysis.probability import clopper_pearson

    # the worse reading's count is often one reading's own: its interval is computed once
    clopper_pearson = cache(clopper_pearson)
    from tuflexperf.analysis.uncertainty import quantiles

    out: dict[str, ProbabilisticVerdict] = {}
    required = samples.plan.required_probability
    for name, values in samples.values.items():
        kind = samples.kinds[name]
        met = int(np.count_nonzero(requirement_met(values, samples.limits[name], kind)))
        n = int(values.size)
        # P(met) shown on each reading of disputed evidence (the nominal first)
        readings = []
        flown = [k for k, by_name in samples.reading_values.items() if name in by_name]
        labels = samples.reading_labels
        nominal = " and ".join(dict.fromkeys(labels[k][1] for k in flown if k in labels))
        for key in flown:
            on = int(np.count_nonzero(requirement_met(samples.reading_values[key][name],
                                                      samples.limits[name], kind)))
            label = nominal if key == "nominal" else labels.get(key, (key, ""))[0]
            readings.append((key, label, on / n,
                             clopper_pearson(on, n, CONFIDENCE)[0] >= required))
        out[name] = ProbabilisticVerdict(
            name=name,
            samples=n,
            met=met,
            not_attainable=int(np.count_nonzero(~np.isfinite(values))),
            probability_ci=clopper_pearson(met, n, CONFIDENCE),
            quantiles=tuple(quantiles(values, kind)),  # type: ignore[arg-type]
            required_probability=required,
            readings=tuple(readings),
        )
    return out
