"""The windmilling drag's other reading: a dead engine flown on its own thrust model at
throttle 0 (see :mod:`tuflexperf.analysis.readings`).

A dead engine takes the propulsion file's ``windmilling_drag_coefficient`` where one is
given (SPEC 3). Where that coefficient drags far less than the same engine's thrust model
does at throttle 0 (:func:`tuflexperf.analysis.oei.windmilling_disagreements`, the rule
of the OEI note), the data disagree: the OEI requirement, and a mission that loses an
engine, are judged on the model's throttle-0 drag too.
"""

from __future__ import annotations

import dataclasses

from tuflexperf.analysis.oei import windmilling_disagreements
from tuflexperf.analysis.readings import Reading
from tuflexperf.io.case import Case


def _mission_loses_an_engine(case: Case) -> bool:
    """Whether the case's mission has an engine-failure segment (its file read, no run)."""
    from tuflexperf.io.mission import load_mission, mission_path

    if case.requirements.mission is None:
        return False
    return any(s.type == "engine_failure" for s in load_mission(mission_path(case)).segments)


def windmilling_readings(case: Case) -> tuple[Reading, ...]:
    """The case with each disagreeing engine's coefficient dropped, so that a dead one drags
    ``min(T(0, V), 0)`` of its own model; none where the data agree or no engine dies
    windmilling."""
    oei = case.requirements.oei
    mode = oei.dead_engine if oei is not None else "windmilling"
    if mode != "windmilling":
        return ()
    found = windmilling_disagreements(case.propulsion, case.density_kg_m3)
    if not found:
        return ()
    affects = {"oei"} if oei is not None else set()
    if _mission_loses_an_engine(case):
        affects.add("mission")
    if not affects:
        return ()
    names = {d.engine for d in found}
    engines = tuple(dataclasses.replace(e, windmilling_drag_coefficient=None)
                    if e.name in names else e for e in case.propulsion.engines)
    reading_case = dataclasses.replace(
        case, propulsion=dataclasses.replace(case.propulsion, engines=engines))
    index = {e.name: i for i, e in enumerate(case.propulsion.engines)}
    file = case.propulsion_path.name
    evidence = "; ".join(
        f"{file} engines[{index[d.engine]}].windmilling_drag_coefficient {d.coefficient:g} "
        f"drags {d.by_coefficient_n:.2f} N at {d.airspeed_m_s:g} m/s, {d.engine}'s own thrust "
        f"model at throttle 0 {d.by_model_n:.2f} N "
        f"({d.by_model_n / max(d.by_coefficient_n, 1e-12):.1f}x)"
        for d in found)
    settle = "; ".join(
        f"a windmilling (throttle-0) hold of {d.engine} at {d.airspeed_m_s:g} m/s in the tunnel"
        for d in found)
    return (Reading(
        key="windmilling_model_drag",
        label="the thrust model's throttle-0 drag of the dead engine",
        nominal_label="the windmilling_drag_coefficient",
        case=reading_case,
        affects=frozenset(affects),
        evidence=evidence,
        settle=settle,
    ),)
