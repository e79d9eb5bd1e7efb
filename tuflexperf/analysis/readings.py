"""Readings of disputed evidence: the same case flown on each source where two disagree.

Where two sources of evidence disagree (the discharge runs' measured power against the power
model, the windmilling-drag coefficient against the thrust model at throttle 0, the thrust
beyond the tested airspeeds at the bound the required probability asks for), the case is
flown once on each. A :class:`Reading` is the case with one disputed input replaced by its
other source. The requirements registry judges each requirement on the nominal case and on
every reading that bears on it; the worse reading decides, and a requirement met on one
reading but not on another is UNPROVEN.

The readings are made from parameters only (no raw run is opened) by providers, each a pure
function ``Case -> tuple[Reading, ...]``, gathered in :mod:`tuflexperf.analysis.evidence`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

from tuflexperf.analysis.cache import ByObject, file_key, fingerprint
from tuflexperf.io.case import Case
from tuflexperf.models.thrust import thrust_part


@dataclass(frozen=True)
class Reading:
    """The case flown on one side of a disagreement.

    Attributes
    ----------
    key : str
        Stable identifier in the JSON, e.g. ``"measured_power"``.
    label : str
        The evidence this reading flies, in words ("the discharge runs' measured power").
    nominal_label : str
        The evidence the nominal case flies ("the power model").
    case : Case
        The case with the disputed input replaced.
    affects : frozenset[str]
        The requirement blocks it bears on (``"takeoff"``, ``"envelope"``, ``"oei"``,
        ``"endurance"``, ``"mission"``).
    evidence : str
        One line naming both sources and their values at a stated point, with the file and
        key ("battery.yaml fit.runs: edf1_endurance_50.csv measured 1328 W at throttle 0.50,
        30.0 m/s; the power model 1001 W").
    settle : str
        The measurement that would settle it ("a discharge run at 27.6 m/s").
    beyond_tested_only : bool
        The reading moves the thrust beyond the tested airspeeds only: a requirement whose
        nominal flight stays inside them has the nominal's value on it (not flown again).
    """

    key: str
    label: str
    nominal_label: str
    case: Case
    affects: frozenset[str]
    evidence: str
    settle: str
    beyond_tested_only: bool = False


Provider = Callable[[Case], tuple[Reading, ...]]


_IDENTITIES: ByObject[tuple[str, str]] = ByObject()
_LAUNCHES: ByObject[str] = ByObject()


def thrust_identity(case: Case) -> tuple[str, str]:
    """Fingerprints of what ``case``'s thrust reads: every engine running (the power
    correction of a reading left out, and the dead engines' windmilling drag), then with
    that drag. Two readings of a case with equal fingerprints fly the same thrust, so a
    batch's results that read only the thrust serve both
    (:class:`tuflexperf.analysis.batch_model.SharedRows`). Kept per case object."""
    return _IDENTITIES.get(case, lambda: _thrust_identity(case))


def launch_identity(case: Case) -> str:
    """A fingerprint of what ``case``'s take-off reads with every engine running: its thrust
    and its fans' power, never a dead engine's windmilling drag (a reading that moves only
    that flies the same take-off). Kept per case object."""
    return _LAUNCHES.get(case, lambda: fingerprint(*_case_parts(case), dataclasses.replace(
        case.propulsion, engines=tuple(dataclasses.replace(e, windmilling_drag_coefficient=None)
                                       for e in case.propulsion.engines))))


def _case_parts(case: Case) -> tuple[object, ...]:
    """What every fingerprint of ``case`` reads beside its propulsion."""
    battery = case.battery_path
    return (case.aircraft, case.atmosphere, case.requirements, case.overrides, str(battery),
            file_key(battery) if battery is not None and battery.exists() else None)


def _thrust_identity(case: Case) -> tuple[str, str]:
    parts = _case_parts(case)

    def engines(**cleared: None) -> object:
        thrust = thrust_part(case.propulsion)
        return dataclasses.replace(thrust, engines=tuple(
            dataclasses.replace(e, **cleared) for e in thrust.engines))

    return (fingerprint(*parts, engines(windmilling_drag_coefficient=None)),
            fingerprint(*parts, engines()))
