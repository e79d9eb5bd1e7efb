"""The thrust beyond the tested airspeeds at the bound the required probability asks for
(see :mod:`tuflexperf.analysis.readings`).

Beyond its tested airspeeds the fitted thrust is an extrapolation. Its error grows with the
distance beyond them: the propulsion file's ``extrapolation_sd_n`` (a leave-one-airspeed-out
error) per left-out step, the rate the samples draw too, whose coverage the calibration study
measured. A requirement that rests on it is shown only when it holds with probability at
least ``p`` (``requirements.extrapolation.required_probability``, default 0.9). Thrust helps
every requirement (more thrust never lengthens a roll nor raises a trim throttle), so
P(met) >= p exactly when the requirement holds with the thrust there moved to its ``p``
bound, ``T + mean(V) - z_p sd(V)`` with ``z_p`` the standard normal quantile (the mean the
fit measured for the fan's extrapolation, shrunk by its standard error): that is this
reading. The
engines' errors are taken as one (the same fan type, the same polynomial form): each is
lowered by its own ``z_p sd(V)``, the cautious choice. Inside the tested airspeeds nothing
changes, so a requirement flown there is judged the same on both readings.
"""

from __future__ import annotations

import dataclasses
from statistics import NormalDist

from tuflexperf.analysis.readings import Reading
from tuflexperf.io.case import Case
from tuflexperf.io.schemas import EXTRAPOLATION_REQUIRED_PROBABILITY
from tuflexperf.models.thrust import extrapolation_error_per_m_s

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
    """The case with each engine's thrust beyond its tested airspeeds lowered by ``z_p``
    times its extrapolation error, which grows with the distance beyond them
    (:func:`~tuflexperf.models.thrust.extrapolation_error_per_m_s`, the samples' rate); none
    where no engine states that error."""
    propulsion = case.propulsion
    low, high = (float(v) for v in propulsion.tested_airspeed_m_s)
    rates = [extrapolation_error_per_m_s(e, (low, high)) for e in propulsion.engines]
    if not any(r.sd_n_per_m_s > 0.0 or r.mean_n_per_m_s != 0.0 for r in rates):
        return ()
    affects = thrust_blocks(case)
    if not affects:
        return ()
    p = required_probability(case)
    z = NormalDist().inv_cdf(p)
    engines = tuple(dataclasses.replace(e, extrapolation_offset=(low, high,
                                                                 rate.bound_n_per_m_s(z)))
                    for e, rate in zip(propulsion.engines, rates, strict=True))
    reading_case = dataclasses.replace(
        case, propulsion=dataclasses.replace(propulsion, engines=engines))
    file = case.propulsion_path.name
    per_engine = ", ".join(
        f"{e.name} {rate.sd_n_per_m_s:.3g} N per m/s"
        + (f" about a mean of {rate.mean_n_per_m_s:+.3g}" if rate.mean_n_per_m_s else "")
        for e, rate in zip(propulsion.engines, rates, strict=True))
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
        evidence=(f"{file} extrapolation error {per_engine} beyond {low:g}-{high:g} m/s "
                  f"(extrapolation_sd_n over the left-out distance): the thrust is "
                  + ("moved by the mean and " if any(r.mean_n_per_m_s for r in rates) else "")
                  + f"lowered by {z:.2f} sd, growing with the distance, for P(met) >= {p:g} "
                  f"({key})"),
        settle=" and ".join(beyond),
        beyond_tested_only=True,
    ),)
