"""One study per case: every analysis solved at most once, its result (or its failure) kept.

``check``, the single-analysis commands and ``report`` all ask a :class:`Study` for
take-off, trim, OEI, endurance, point performance and the mission, so a result flows
once from the solver to the verdict, the table and the figure; nothing is solved twice
for the same case. The CasADi functions behind each analysis are built once per
content hash of the models (:mod:`tuflexperf.analysis.cache`); the study memoises the
*results* of one case, keyed on the question (e.g. the throttle of an endurance), never
on ``repr`` of user data.

A "not attainable" answer is a result too: it is kept and raised again on every later
request, so a failing aircraft fails the same way in every command and figure.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import TYPE_CHECKING, Any, TypeVar

from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.io.mission import mission_path

if TYPE_CHECKING:  # the analyses are imported when first asked for: `check` stays lean
    from tuflexperf.analysis.endurance import BestResult, EnduranceModel, EnduranceResult
    from tuflexperf.analysis.margins import Tornado
    from tuflexperf.analysis.mission import MissionResult
    from tuflexperf.analysis.oei import OeiResult
    from tuflexperf.analysis.performance import PerformanceResult
    from tuflexperf.analysis.plausibility import Implausibility
    from tuflexperf.analysis.review_views import FlightEnvelope, MassSweep
    from tuflexperf.analysis.takeoff import TakeoffResult
    from tuflexperf.analysis.trim import TrimResult

T = TypeVar("T")


class Study:
    """The analyses of one :class:`~tuflexperf.io.case.Case`, each solved once.

    Parameters
    ----------
    case : Case
        The validated case (aircraft, propulsion, battery, atmosphere, requirements).

    Notes
    -----
    Every accessor returns the same object on every call; an analysis that raised
    :class:`~tuflexperf.errors.NotAttainable` raises the same exception again.
    ``solved`` lists what has been computed, in order (the report's provenance and the
    tests' proof that nothing is solved twice).
    """

    def __init__(self, case: Case) -> None:
        self.case = case
        self._memo: dict[Hashable, tuple[bool, Any]] = {}
        self.solved: list[Hashable] = []

    def once(self, key: Hashable, compute: Callable[[], T]) -> T:
        """``compute()`` the first time ``key`` is asked for, its result (or failure) after."""
        if key not in self._memo:
            try:
                self._memo[key] = (True, compute())
            except NotAttainable as exc:
                self._memo[key] = (False, exc)
            self.solved.append(key)
        ok, value = self._memo[key]
        if not ok:
            raise value
        return value  # type: ignore[no-any-return]

    # --- the analyses ---------------------------------------------------------------------
    def plausibility(self) -> tuple[Implausibility, ...]:
        """What the case's data claim that physics forbids (:func:`implausible`), scanned once."""
        from tuflexperf.analysis.plausibility import implausible

        return self.once("plausibility", lambda: implausible(self.case))

    def takeoff(self) -> TakeoffResult:
        """Take-off to the obstacle at full throttle (:func:`solve_takeoff`)."""
        from tuflexperf.analysis.takeoff import solve_takeoff

        return self.once("takeoff", lambda: solve_takeoff(self.case))

    def trim(self) -> TrimResult:
        """Least trim throttle over the envelope (:func:`solve_trim`)."""
        from tuflexperf.analysis.trim import solve_trim

        return self.once("trim", lambda: solve_trim(self.case))

    def oei(self, dead_engine: str | None = None) -> OeiResult:
        """One engine inoperative; ``dead_engine`` the SPEC mode, else the requirement's."""
        from tuflexperf.analysis.oei import solve_oei

        if dead_engine is None and self.case.requirements.oei is not None:
            dead_engine = self.case.requirements.oei.dead_engine
        return self.once(("oei", dead_engine),
                          lambda: solve_oei(self.case, dead_engine))  # type: ignore[arg-type]

    def endurance_model(self) -> EnduranceModel:
        """The endurance problem of the case's battery (built once)."""
        from tuflexperf.analysis.endurance import endurance_model

        return self.once("endurance_model", lambda: endurance_model(self.case))

    def endurance(self, throttle: float) -> EnduranceResult:
        """Flight endurance at a fixed cruise throttle [fraction]."""
        from tuflexperf.analysis.endurance import solve_endurance

        return self.once(("endurance", float(throttle)),
                          lambda: solve_endurance(self.case, float(throttle)))

    def best_endurance(self) -> BestResult:
        """Best-endurance and best-range airspeeds (IPOPT)."""
        from tuflexperf.analysis.endurance import solve_best

        return self.once("best", lambda: solve_best(self.case))

    def performance(self) -> PerformanceResult:
        """Point performance: stall, speeds, climb, ceilings, OEI gradient."""
        from tuflexperf.analysis.performance import solve_performance

        return self.once("performance", lambda: solve_performance(self.case))

    def mission(self) -> MissionResult:
        """The case's mission requirement flown (requires ``requirements.mission``)."""
        from tuflexperf.analysis.mission import solve_mission
        from tuflexperf.io.mission import load_mission

        requirement = self.case.requirements.mission
        if requirement is None:
            raise NotAttainable("the case has no mission requirement")

        def fly() -> MissionResult:
            mission = load_mission(mission_path(self.case))
            return solve_mission(self.case, mission, requirement.min_landing_charge_fraction)

        return self.once("mission", fly)

    def flight_envelope(self) -> FlightEnvelope:
        """Level flight over altitude and airspeed, all engines and each one out, up to
        1.15 x the absolute ceiling (:func:`flight_envelope`)."""
        from tuflexperf.analysis.review_views import flight_envelope

        def solve() -> FlightEnvelope:
            try:
                top = self.performance().absolute_ceiling_m
            except NotAttainable:
                top = None
            return flight_envelope(self.case, None if top is None else 1.15 * top)

        return self.once("flight_envelope", solve)

    def mass_sweep(self) -> MassSweep:
        """Endurance and range against take-off mass (:func:`endurance_against_mass`)."""
        from tuflexperf.analysis.review_views import endurance_against_mass

        return self.once("mass_sweep", lambda: endurance_against_mass(self.case))

    def tornado(self, requirement: str) -> Tornado:
        """A requirement's value with each parameter moved -/+ 10 % (:func:`tornado`)."""
        from tuflexperf.analysis.margins import tornado

        return self.once(("tornado", requirement), lambda: tornado(self.case, requirement))

    def limit_values(self) -> dict[tuple[str, str], tuple[float | None, str, tuple[float, float]]]:
        """(requirement, parameter) -> the parameter's value where the requirement just
        holds, how it binds, and the search range (:func:`limit_values`)."""
        from tuflexperf.analysis.margins import limit_values

        return self.once("limit_values", lambda: limit_values(self.case))

