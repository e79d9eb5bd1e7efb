"""The thrust at the bound its lack of fit allows (see :mod:`tuflexperf.analysis.readings`).

Where ``fit``'s lack-of-fit test finds the poly22 surface farther from its holds than their
own repeatability (the propulsion file's ``lack_of_fit.model_form_rms_n`` per engine, 0
where the test passes), the surface's shape error is evidence against it as much as the
holds are for it. A requirement that rests on the surface is shown only when it holds with
probability at least ``p`` (``requirements.extrapolation.required_probability``, the one
required probability of a deterministic verdict) with that error in the thrust: thrust helps
every requirement, so that is the requirement met with each engine's thrust lowered by
``z_p model_form_rms_n`` everywhere. That is this reading. The error's sign is unknown
where the worst hold lies; the bound takes it at every throttle and airspeed, the cautious
choice (the samples draw it as a surface instead, :mod:`tuflexperf.analysis.error_model`).

References
----------
Montgomery, *Design and Analysis of Experiments*, 8th ed., section 10.5 (lack of fit).
"""

from __future__ import annotations

import dataclasses
from statistics import NormalDist

from tuflexperf.analysis.extrapolation_reading import required_probability, thrust_blocks
from tuflexperf.analysis.readings import Reading
from tuflexperf.io.case import Case


def model_form_readings(case: Case) -> tuple[Reading, ...]:
    """The case with each engine's thrust lowered by ``z_p model_form_rms_n`` [N] at every
    throttle and airspeed; none where no engine's surface fails its lack-of-fit test."""
    propulsion = case.propulsion
    sds = [float(e.model_form_sd_n or 0.0) for e in propulsion.engines]
    if not any(sd > 0.0 for sd in sds):
        return ()
    affects = thrust_blocks(case)
    if not affects:
        return ()
    p = required_probability(case)
    z = NormalDist().inv_cdf(p)
    # p00 is the surface's constant term [N]: lowering it lowers the thrust everywhere
    engines = tuple(
        dataclasses.replace(e, coefficients={**e.coefficients,
                                             "p00": float(e.coefficients["p00"]) - z * sd})
        for e, sd in zip(propulsion.engines, sds, strict=True))
    reading_case = dataclasses.replace(
        case, propulsion=dataclasses.replace(propulsion, engines=engines))
    per_engine = ", ".join(f"{e.name} {sd:.3g} N" for e, sd in zip(propulsion.engines, sds,
                                                                     strict=True) if sd > 0)
    return (Reading(
        key="model_form_bound",
        label=f"the thrust at its {100 * p:g} % lower bound for the surface's lack of fit",
        nominal_label="the thrust model as fitted",
        case=reading_case,
        affects=affects,
        evidence=(f"{case.propulsion_path.name} engines[].lack_of_fit.model_form_rms_n "
                  f"{per_engine}: the poly22 misses its holds beyond their repeatability; "
                  f"thrust lowered by {z:.2f} x that error for P(met) >= {p:g}"),
        settle=("tunnel holds refitted with a surface that passes the lack-of-fit test "
                "(fit names the best alternative form), or repeated holds that show the "
                "scatter is noise"),
    ),)
