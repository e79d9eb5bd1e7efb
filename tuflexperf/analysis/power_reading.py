"""The discharge runs' measured power as a reading of the case (see :mod:`readings`).

The battery file's ``fit.power_correction`` (written by ``fit``) is the runs' measured over
modelled power as a law over throttle and airspeed
(:class:`tuflexperf.models.power_correction.PowerCorrection`). Where a run's measured power
lies further than :data:`RUN_POWER_TOLERANCE` from the power model (the disagreement the
endurance's note has always named), the case is flown a second time with the correction on
every fan's power (:func:`with_power_correction`): the one multiplication in
``engine_power_w`` and the fan-power law that the single-case problems and the batch both go
through. Everything here is read from the battery file's parameters; no run is opened.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from tuflexperf.analysis.battery_fit import (
    RUN_POWER_TOLERANCE,
    cached_case_battery,
    characterise_battery,
)
from tuflexperf.analysis.readings import Reading
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.models.power_correction import PowerCorrection
from tuflexperf.reduction.battery import (
    correction_form,
    fit_power_correction,
    run_model_power_w,
)

# Every requirement whose verdict uses the fans' electrical power: the endurance and the
# mission fly the packs, and the take-off, trim and OEI hold the packs' rating and power
AFFECTS = frozenset({"endurance", "mission", "takeoff", "envelope", "oei"})
# The stored law is the case's when its model powers at the runs agree this closely
SAME_MODEL = 1e-6


@dataclass(frozen=True)
class MeasuredPower:
    """The measured power correction a case flies, and the runs behind it.

    Attributes
    ----------
    correction : PowerCorrection
        Measured over modelled power [-].
    form : str
        ``constant``, ``linear in throttle``, ...
    model : str
        The power model it corrects, in words.
    refitted : bool
        True where the battery file's law was fitted against another power model than the
        case's (another propulsion file, a what-if) and was fitted again here from the
        file's ``fit.runs``.
    runs : tuple[tuple[str, float, float, float, float], ...]
        Per run: file name, throttle [-], airspeed [m/s], measured and modelled power [W].
    source : str
        The battery file and key, e.g. ``"battery.yaml fit.power_correction"``.
    """

    correction: PowerCorrection
    form: str
    model: str
    refitted: bool
    runs: tuple[tuple[str, float, float, float, float], ...]
    source: str

    @property
    def disagrees(self) -> bool:
        """Whether a run's power is further from the model than :data:`RUN_POWER_TOLERANCE`
        (the endurance's note says so on the same test)."""
        return any(abs(model - measured) > RUN_POWER_TOLERANCE * measured
                   for _, _, _, measured, model in self.runs)


def case_measured_power(case: Case) -> MeasuredPower | None:
    """The measured power correction of ``case``'s battery file against the case's power
    model, or ``None`` where the file has none (or the case no battery).

    The stored law is used where its runs' model powers are the case's; else (another
    propulsion file, a what-if of its power surfaces) it is fitted again from the file's
    ``fit.runs`` against the case's model by the same reduction ``fit`` uses.
    """
    if case.battery_path is None:
        return None
    battery = cached_case_battery(case)
    stored = battery.as_read.fitted
    if stored is None or stored.power_correction is None:
        return None
    block = stored.power_correction
    ch = characterise_battery(battery, case)
    model_w, label = run_model_power_w(battery.as_read, case.propulsion, ch.runs,
                                       ch.power.model)
    kept = np.array([r.model_power_w for r in block.runs], dtype=float)
    same = kept.shape == model_w.shape and bool(
        np.all(np.abs(kept / model_w - 1.0) <= SAME_MODEL))
    if same:
        law = PowerCorrection(block.constant, block.per_throttle, block.per_airspeed_s_m,
                              (block.throttle_span[0], block.throttle_span[1]),
                              (block.airspeed_span_m_s[0], block.airspeed_span_m_s[1]))
    else:
        law = fit_power_correction(ch.runs, model_w)
    runs = tuple((r.path.name, float(r.throttle_setting), float(r.airspeed_setting_m_s),
                  float(r.mean_power_w), float(m)) for r, m in zip(ch.runs, model_w, strict=True))
    return MeasuredPower(law, block.form if same else correction_form(law), label, not same,
                         runs, f"{battery.path.name} fit.power_correction")


def with_power_correction(case: Case, correction: PowerCorrection) -> Case:
    """``case`` with every fan's electrical power times ``correction``: on each engine (the
    propulsion's power surfaces) and so on the battery file's fan-power law, which takes
    the runs' engine's (:func:`tuflexperf.analysis.battery_fit.characterise_battery`)."""
    engines = tuple(dataclasses.replace(e, power_correction=correction)
                    for e in case.propulsion.engines)
    return dataclasses.replace(case, propulsion=dataclasses.replace(case.propulsion,
                                                                    engines=engines))


def flown_point(case: Case) -> tuple[float, float] | None:
    """The endurance requirement's cruise throttle [-] and its level-flight airspeed [m/s]
    (the thrust model sets it, the same on either power), or None."""
    from tuflexperf.analysis.endurance import endurance_model

    requirement = case.requirements.endurance
    if requirement is None:
        return None
    try:
        speed = endurance_model(case).level_airspeed_m_s(float(requirement.throttle))
    except (NotAttainable, InputError):
        return None
    return float(requirement.throttle), speed


def measured_power_disputed(case: Case) -> bool:
    """Whether ``case`` is flown on the measured power too: the battery file has a power
    correction and a run's power disagrees with the model by more than
    :data:`RUN_POWER_TOLERANCE` (:func:`measured_power_readings` then has its reading)."""
    measured = case_measured_power(case)
    return measured is not None and measured.disagrees


def measured_power_readings(case: Case) -> tuple[Reading, ...]:
    """The case flown on the measured power correction law, when
    :func:`measured_power_disputed`."""
    measured = case_measured_power(case)
    if measured is None or not measured.disagrees:
        return ()
    law = measured.correction
    name, x, v, p_run, p_model = max(measured.runs, key=lambda r: abs(math.log(r[3] / r[4])))
    point = flown_point(case)
    flown = ""
    outside: list[str] = []
    if point is not None:
        fx, fv = point
        outside = law.extrapolates(fx, fv)
        ratio = float(law.ratio(fx, fv))
        flown = f"; the cruise at throttle {fx:.2f}, {fv:.1f} m/s flies x{ratio:.3f}"
        if outside:
            flown += f", extrapolated ({'; '.join(outside)}: held at the tested edge)"
    launch = law.extrapolates(1.0, law.airspeed_span_m_s[0])
    if launch and (case.requirements.endurance is not None
                   or case.requirements.mission is not None):
        flown += f"; the full-throttle launch is extrapolated too ({launch[0]})"
    refitted = (" (fitted again from fit.runs against this case's power model)"
                if measured.refitted else "")
    evidence = (
        f"{measured.source} ({measured.form}{refitted}): {name} measured {p_run:.0f} W at "
        f"throttle {x:.2f}, {v:.1f} m/s; {measured.model} gives {p_model:.0f} W "
        f"({100 * (p_model / p_run - 1):+.0f} %){flown}"
    )
    if point is not None and outside:
        fx, fv = point
        parts = ([f"throttle {fx:.2f}"] if law.extrapolates(fx, law.airspeed_span_m_s[0])
                 else []) + ([f"{fv:.1f} m/s"] if law.extrapolates(law.throttle_span[0], fv)
                             else [])
        settle = f"a discharge run at {', '.join(parts)}"
    else:
        settle = f"a repeat discharge run at throttle {x:.2g}, {v:.0f} m/s"
    return (Reading(
        key="measured_power",
        label="the discharge runs' measured power",
        nominal_label=f"the power model ({measured.model})",
        case=with_power_correction(case, law),
        affects=AFFECTS,
        evidence=evidence,
        settle=settle,
    ),)
