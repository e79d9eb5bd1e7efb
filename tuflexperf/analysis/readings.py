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

from collections.abc import Callable
from dataclasses import dataclass

from tuflexperf.io.case import Case


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
    """

    key: str
    label: str
    nominal_label: str
    case: Case
    affects: frozenset[str]
    evidence: str
    settle: str


Provider = Callable[[Case], tuple[Reading, ...]]
