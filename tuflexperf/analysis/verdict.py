"""The judging rule: a value against its limit, and the verdict it makes.

One rule serves every requirement, the batch's per-sample masks (:func:`requirement_met`) and
the single case's :class:`Verdict` alike; the registry that applies it to a case is
:mod:`tuflexperf.analysis.requirements`. It sits below the analyses so that a result (a flown
mission) can be judged without importing the registry.

Margins are signed so that positive means met: ``limit - value`` for upper
limits (ground roll, throttle), ``value - limit`` for lower limits (endurance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray


class FlownMission(Protocol):
    """What :func:`mission_verdicts` reads of a flown mission (a ``MissionResult``)."""

    @property
    def name(self) -> str: ...
    @property
    def attainable(self) -> bool: ...
    @property
    def reason(self) -> str: ...
    @property
    def landing_charge_fraction(self) -> float: ...
    @property
    def min_landing_charge_fraction(self) -> float: ...
    @property
    def warnings(self) -> Any: ...
    @property
    def solved(self) -> dict[str, Any] | None: ...


MARGIN_TOLERANCE = 1e-12


def requirement_met(values: ArrayLike, limits: ArrayLike, kind: str) -> NDArray[np.bool_]:
    """Met per element by the same rule as :attr:`Verdict.passed`; NaN (not attainable) is not.

    ``kind`` "max": ``value <= limit``; "min": ``value >= limit`` (margin >= -1e-12).
    """
    v = np.asarray(values, dtype=float)
    limit = np.asarray(limits, dtype=float)
    margin = limit - v if kind == "max" else v - limit
    with np.errstate(invalid="ignore"):
        return np.isfinite(v) & (margin >= -MARGIN_TOLERANCE)


PASS, FAIL, UNPROVEN = "PASS", "FAIL", "UNPROVEN"


@dataclass(frozen=True)
class ReadingValue:
    """A requirement's value on one reading of the evidence (the nominal one first).

    ``key`` is ``"nominal"`` or the :class:`~tuflexperf.analysis.readings.Reading`'s key,
    ``label`` the evidence it flies, ``value`` [the requirement's unit] None where not
    attainable, ``passed`` whether the requirement is met on it.
    """

    key: str
    label: str
    value: float | None
    passed: bool

    def to_dict(self) -> dict[str, Any]:
        return {"key": self.key, "label": self.label, "value": self.value,
                "passed": self.passed}


def _met(value: float | None, limit: float, kind: str) -> bool:
    if value is None:
        return False
    margin = limit - value if kind == "max" else value - limit
    # a non-finite value (an endless endurance from a pack the runs contradict, a
    # diverged solve) never passes (SPEC: never a false PASS)
    return math.isfinite(margin) and margin >= -MARGIN_TOLERANCE


@dataclass(frozen=True)
class Verdict:
    """One requirement: ``value`` is ``None`` when the analysis found it not attainable.

    Where the evidence disagrees (:mod:`tuflexperf.analysis.readings`) ``readings`` holds
    the value on each reading, the nominal first; ``value`` is then the worse reading's and
    the verdict three-state: met on every reading PASS, on none FAIL, on some UNPROVEN
    (``settle``: the measurement that would settle it).
    """

    name: str
    value: float | None
    limit: float
    unit: str
    kind: str  # "max" (value <= limit) or "min" (value >= limit)
    reason: str = ""
    details: dict[str, Any] = field(default_factory=dict)
    readings: tuple[ReadingValue, ...] = ()
    settle: str = ""

    @property
    def margin(self) -> float | None:
        if self.value is None:
            return None
        return self.limit - self.value if self.kind == "max" else self.value - self.limit

    @property
    def verdict(self) -> str:
        """PASS, FAIL or UNPROVEN (met on one reading of disputed evidence, not another)."""
        if not self.readings:
            return PASS if _met(self.value, self.limit, self.kind) else FAIL
        met = [r.passed for r in self.readings]
        return PASS if all(met) else FAIL if not any(met) else UNPROVEN

    @property
    def passed(self) -> bool:
        """True for PASS only: an UNPROVEN requirement is not shown met."""
        return self.verdict == PASS

    def to_dict(self) -> dict[str, Any]:
        out = {
            "name": self.name,
            "value": self.value,
            "limit": self.limit,
            "unit": self.unit,
            "margin": self.margin,
            "verdict": self.verdict,
            "passed": self.passed,
            "reason": self.reason,
            **self.details,
        }
        if self.readings:
            out["readings"] = [r.to_dict() for r in self.readings]
            out["settle"] = self.settle
        return out


def same_value(a: float | None, b: float | None) -> bool:
    """Whether a reading left a requirement's value as it was (to 1e-9 relative: a solver's
    rounding on a graph that holds the offset, not a change of the evidence)."""
    if a is None or b is None:
        return a is None and b is None
    if not (math.isfinite(a) and math.isfinite(b)):
        return a == b or (math.isnan(a) and math.isnan(b))
    return abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))


def overall_verdict(verdicts: list[str]) -> str:
    """The case's verdict from its requirements': any FAIL fails, else any UNPROVEN is
    UNPROVEN, else PASS (none at all is no PASS: nothing was shown)."""
    if not verdicts or FAIL in verdicts:
        return FAIL
    return UNPROVEN if UNPROVEN in verdicts else PASS


def on_readings(nominal: Verdict, others: list[tuple[Any, Verdict]]) -> Verdict:
    """``nominal`` judged on every reading too: ``others`` pairs each
    :class:`~tuflexperf.analysis.readings.Reading` with the same requirement's verdict on
    its case. The shown value is the worse reading's; the reason of an UNPROVEN names
    each disagreeing reading's evidence and both values, ``settle`` what would settle it."""
    if not others:
        return nominal
    labels = list(dict.fromkeys(r.nominal_label for r, _ in others))
    # "the power model" says less than "the power model (EDF1's surface)": name it once
    nominal_label = " and ".join(a for a in labels
                                 if not any(b != a and b.startswith(a) for b in labels))
    values = [ReadingValue("nominal", nominal_label, nominal.value, nominal.passed)] + [
        ReadingValue(r.key, r.label, v.value, v.passed) for r, v in others]

    def badness(v: Verdict) -> float:
        margin = v.margin
        return math.inf if margin is None or not math.isfinite(margin) else -margin

    worst = max([nominal] + [v for _, v in others], key=badness)
    disagree = [(r, v) for r, v in others if v.passed != nominal.passed]
    reason, settle = nominal.reason, ""
    if disagree:

        def shown(value: float | None) -> str:
            return "not attainable" if value is None else f"{value:.4g} {nominal.unit}"

        met = {True: "met", False: "not met"}
        reason = "; ".join(
            [f"{nominal.name} {shown(nominal.value)} on {nominal_label} "
             f"({met[nominal.passed]})"]
            + [f"{shown(v.value)} on {r.label} ({met[v.passed]}): {r.evidence}"
               for r, v in disagree])
        settle = "; ".join(dict.fromkeys(r.settle for r, _ in disagree))
    return Verdict(nominal.name, worst.value, nominal.limit, nominal.unit, nominal.kind,
                   reason,
                   {**nominal.details, **({"nominal_reason": nominal.reason} if disagree else {})},
                   tuple(values), settle)


def mission_verdicts(result: FlownMission) -> list[Verdict]:
    """A flown mission's verdicts: the landing charge against the reserve, and with
    ``solve_for`` the longest time of that segment against the file's own (the solved flight
    lands on the reserve by construction: alone it passed a plan that cannot be flown)."""
    value = result.landing_charge_fraction if result.attainable else None
    verdicts = [Verdict(
        "mission_landing_charge", value, result.min_landing_charge_fraction, "fraction",
        "min", f"{result.name}: {result.reason}", {"warnings": list(result.warnings)},
    )]
    solved = result.solved
    if solved is not None:
        segment, written = solved["segment"], solved["written_time_min"]
        planned = (f"{solved['written_distance_km']:g} km ({written:.2f} min)"
                   if "written_distance_km" in solved else f"{written:g} min")
        bound = ("that lands on the reserve" if solved.get("ends_at") != "cut-off"
                 else "before the packs' cut-off")
        verdicts.append(Verdict(
            "mission_solved_time", solved["time_min"] if result.attainable else None, written,
            "min", "min",
            f"the longest {segment} (segment {solved['index'] + 1}) {bound}, against the "
            f"{planned} the mission file plans",
        ))
    return verdicts
