"""The thrust beyond the tested airspeeds at the bound the required probability asks for
(see :mod:`tuflexperf.analysis.readings`).

Beyond its tested airspeeds the fitted thrust is an extrapolation, with the propulsion
file's ``extrapolation_sd_n`` as its band (a leave-one-airspeed-out error). A requirement
that rests on it is shown only when it holds with probability at least ``p``
(``requirements.extrapolation.required_probability``, default 0.9). Thrust helps every
requirement (more thrust never lengthens a roll nor raises a trim throttle), so P(met) >= p
exactly when the requirement holds with the thrust there lowered to its ``p`` bound,
``T - z_p sd`` with ``z_p`` the standard normal quantile: that is this reading. The
engines' errors are taken as one (the same fan type, the same polynomial form): each is
lowered by its own ``z_p sd``, the cautious choice. Inside the tested airspeeds nothing
changes, so a requirement flown there is judged the same on both readings.
"""

from __future__ import annotations

import dataclasses
from statistics import NormalDist

from tuflexperf.analysis.readings import Reading
from tuflexperf.io.case import Case
from tuflexperf.io.schemas import EXTRAPOLATION_REQUIRED_PROBABILITY

#: every block: any flight may leave the tested airspeeds (a sweep's row where the nominal
#: does not); a requirement the bound leaves unchanged is judged on the nominal alone
_BLOCKS = ("takeoff", "envelope", "oei", "endurance", "mission")


def required_probability(case: Case) -> float:
    """The least P(met) of a requirement resting on extrapolated thrust [fraction]."""
    block = case.requirements.extrapolation
    return EXTRAPOLATION_REQUIRED_PROBABILITY if block is None else block.required_probability


def thrust_blocks(case: Case) -> frozenset[str]:
    """The case's requirement blocks that fly on the thrust (every one it has)."""
    return frozenset(b for b in _BLOCKS if getattr(case.requirements, b) is not None)


def extrapolation_readings(case: Case) -> tuple[Reading, ...]:
    """The case with each engine's thrust beyond its tested airspeeds lowered by
    ``z_p extrapolation_sd_n``; none where no engine states that error."""
    propulsion = case.propulsion
    sds = [float(e.extrapolation_sd_n or 0.0) for e in propulsion.engines]
    if not any(sd > 0.0 for sd in sds):
        return ()
    affects = thrust_blocks(case)
    if not affects:
        return ()
    p = required_probability(case)
    z = NormalDist().inv_cdf(p)
    low, high = (float(v) for v in propulsion.tested_airspeed_m_s)
    engines = tuple(dataclasses.replace(e, extrapolation_offset=(low, high, -z * sd))
                    for e, sd in zip(propulsion.engines, sds, strict=True))
    reading_case = dataclasses.replace(
        case, propulsion=dataclasses.replace(propulsion, engines=engines))
    file = case.propulsion_path.name
    per_engine = ", ".join(f"{e.name} {sd:g} N" for e, sd in zip(propulsion.engines, sds,
                                                                   strict=True))
    key = "requirements.extrapolation.required_probability"
    beyond = [f"tunnel points above {high:g} m/s"] + (
        [f"tunnel points below {low:g} m/s"] if low > 0.0 else [])
    return (Reading(
        key="extrapolation_bound",
        label=(f"the thrust beyond the tested {low:g}-{high:g} m/s at its {100 * p:g} % "
               "lower bound"),
        nominal_label="the thrust model as fitted",
        case=reading_case,
        affects=affects,
        evidence=(f"{file} extrapolation_sd_n {per_engine}: beyond {low:g}-{high:g} m/s the "
                  f"thrust is lowered by {z:.2f} sd for P(met) >= {p:g} ({key})"),
        settle=" and ".join(beyond),
        beyond_tested_only=True,
    ),)
