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


@dataclass(frozen=True)
class Verdict:
    """One requirement: ``value`` is ``None`` when the analysis found it not attainable."""

    name: str
    value: float | None
    limit: float
    unit: str
    kind: str  # "max" (value <= limit) or "min" (value >= limit)
    reason: str = ""
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def margin(self) -> float | None:
        if self.value is None:
            return None
        return self.limit - self.value if self.kind == "max" else self.value - self.limit

    @property
    def passed(self) -> bool:
        # a non-finite value (an endless endurance from a pack the runs contradict, a
        # diverged solve) never passes (SPEC: never a false PASS)
        return (self.margin is not None and math.isfinite(self.margin)
                and self.margin >= -MARGIN_TOLERANCE)

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "value": self.value,
            "limit": self.limit,
            "unit": self.unit,
            "margin": self.margin,
            "passed": self.passed,
            "reason": self.reason,
            **self.details,
        }


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
