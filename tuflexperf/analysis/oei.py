"""One engine inoperative: level flight on the remaining engine(s) (paper section 4).

Each engine in turn is the dead one (SPEC 3): a ``windmilling`` dead engine adds
``min(T(0, V), 0)`` of its own model, a ``zero`` one nothing. For each case the
least throttle over the envelope grid is found; the worse case (the higher least
throttle) is reported.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import (
    AttainableRange,
    jet_ceiling_note,
    stall_margin_of,
)
from tuflexperf.analysis.level_flight import ThrottleSweep, airspeed_grid
from tuflexperf.analysis.trim import (
    envelope_of,
    extrapolation_note,
    level_flight_over,
    level_flight_rows,
)
from tuflexperf.errors import InputError
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import stall_speed_m_s
from tuflexperf.models.thrust import (
    DeadEngineMode,
    Propulsion,
    density_ratio,
    engine_thrust_n,
    unlapsed_density_warning,
    windmilling_thrust_n,
)


@dataclass(frozen=True)
class DeadEngineCase(ThrottleSweep):
    """One dead engine over the envelope grid; the attainable range is exact (not the grid's)."""

    dead_engine: str
    reasons: tuple[str | None, ...] = ()
    attainable: AttainableRange = AttainableRange(None, None)

    @property
    def level_flight_airspeed_range_m_s(self) -> list[float] | None:
        """Exact [low, high] of level flight within the envelope (stall- and thrust-bounded)."""
        return self.attainable.as_list()

    def to_dict(self) -> dict[str, Any]:
        return {
            "dead_engine": self.dead_engine,
            "min_throttle": self.min_throttle,
            "airspeed_at_min_throttle_m_s": self.airspeed_at_min_throttle_m_s,
            "level_flight_airspeed_range_m_s": self.level_flight_airspeed_range_m_s,
            "least_attainable_airspeed_m_s": self.attainable.low,
            "level_flight_contiguous": self.attainable.contiguous,
            **self.lists(),
            "not_attainable_reason": list(self.reasons),
        }


@dataclass(frozen=True)
class OeiResult:
    dead_engine_mode: str
    cases: tuple[DeadEngineCase, ...]
    extrapolated: bool
    warnings: tuple[str, ...]
    stall_speed_m_s: float = float("nan")
    stall_margin: float = 1.0

    @property
    def critical(self) -> DeadEngineCase:
        """The worse case: unattainable first, else the higher least throttle."""

        def badness(c: DeadEngineCase) -> float:
            return np.inf if c.min_throttle is None else c.min_throttle

        return max(self.cases, key=badness)

    def to_dict(self) -> dict[str, Any]:
        worst = self.critical
        return {
            "min_throttle": worst.min_throttle,
            "airspeed_at_min_throttle_m_s": worst.airspeed_at_min_throttle_m_s,
            "level_flight_airspeed_range_m_s": worst.level_flight_airspeed_range_m_s,
            "least_attainable_airspeed_m_s": worst.attainable.low,
            "not_attainable_reason": list(worst.reasons),
            "stall_speed_m_s": self.stall_speed_m_s,
            "stall_margin": self.stall_margin,
            "critical_dead_engine": worst.dead_engine,
            "dead_engine_mode": self.dead_engine_mode,
            "cases": [c.to_dict() for c in self.cases],
            "extrapolated": self.extrapolated,
            "warnings": list(self.warnings),
        }


def refuse_one_engine(case: Case) -> None:
    """Bad input: one engine inoperative needs another one left."""
    if len(case.propulsion.engines) < 2:
        raise InputError(f"{case.propulsion_path}: engines: OEI needs at least two engines")


def solve_oei(case: Case, mode: DeadEngineMode | None = None) -> OeiResult:
    """Level flight with each engine dead in turn over the case's envelope grid."""
    refuse_one_engine(case)
    if mode is None:
        mode = case.requirements.oei.dead_engine if case.requirements.oei else "windmilling"
    speeds = airspeed_grid(*envelope_of(case))
    propulsion, rho = case.propulsion, case.density_kg_m3
    rows, grid = level_flight_rows(case), speeds[None, :]
    cases, pack_notes = [], []
    for index, engine in enumerate(propulsion.engines):
        throttle, reasons, attainable, notes = level_flight_over(
            case, rows, grid, f"OEI ({engine.name} dead)", index, mode)
        pack_notes.extend(notes)
        cases.append(DeadEngineCase(speeds, throttle, engine.name, reasons, attainable))
    extrapolated, warnings = extrapolation_note(case, speeds)
    warnings.extend(jet_ceiling_note(case, speeds))
    warnings.extend(pack_notes)
    density_note = unlapsed_density_warning(propulsion, rho)
    if density_note:
        warnings.append(density_note)
    if mode == "windmilling":
        warnings.extend(windmilling_notes(propulsion, rho))
    stall = float(stall_speed_m_s(case.aircraft, rho))
    return OeiResult(mode, tuple(cases), extrapolated, tuple(warnings), stall,
                     stall_margin_of(case))


WINDMILLING_SHORTFALL = 2.0
"""A coefficient's drag under 1/this of the model's own throttle-0 drag is said."""


@dataclass(frozen=True)
class WindmillingDisagreement:
    """One engine whose windmilling coefficient drags far less than its own thrust model
    does at throttle 0, at the top tested airspeed ``airspeed_m_s`` [m/s] (drags in N)."""

    engine: str
    coefficient: float
    airspeed_m_s: float
    by_coefficient_n: float
    by_model_n: float


def windmilling_disagreements(propulsion: Propulsion,
                              density_kg_m3: float) -> list[WindmillingDisagreement]:
    """Where an engine's ``windmilling_drag_coefficient`` drags less than
    1/:data:`WINDMILLING_SHORTFALL` of its own thrust model at throttle 0 (its measured
    idle, ``min(T(0, V), 0)``) at the highest tested airspeed: the one rule of the OEI note
    and of the windmilling reading (:mod:`tuflexperf.analysis.windmilling_reading`).

    References
    ----------
    SPEC 3 (one engine inoperative); Hoerner, *Fluid-Dynamic Drag*, ch. 3.
    """
    top = float(propulsion.tested_airspeed_m_s[1])
    if propulsion.fan_area_m2 is None or top <= 0.0:
        return []
    scale = density_ratio(propulsion, density_kg_m3)
    found = []
    for engine in propulsion.engines:
        if engine.windmilling_drag_coefficient is None:
            continue
        by_coefficient = -float(windmilling_thrust_n(engine, top, scale, density_kg_m3,
                                                     propulsion.fan_area_m2))
        by_model = -min(float(engine_thrust_n(engine, 0.0, top, scale)), 0.0)
        if by_model > WINDMILLING_SHORTFALL * by_coefficient:
            found.append(WindmillingDisagreement(engine.name,
                                                 engine.windmilling_drag_coefficient, top,
                                                 by_coefficient, by_model))
    return found


def windmilling_notes(propulsion: Propulsion, density_kg_m3: float) -> list[str]:
    """A note per :func:`windmilling_disagreements`: the dead engine takes the coefficient
    (SPEC 3), so the OEI figures are the coefficient's, and the data disagree (the shipped
    0.2 gives 0.48 N at 30 m/s where the model's idle drags 3.3 N; outside audit); the
    registry judges OEI on the model's drag too (the windmilling reading)."""
    return [
        f"{d.engine}'s windmilling_drag_coefficient {d.coefficient:g} drags "
        f"{d.by_coefficient_n:.2f} N at {d.airspeed_m_s:g} m/s, its own thrust model at "
        f"throttle 0 {d.by_model_n:.2f} N there "
        f"({d.by_model_n / max(d.by_coefficient_n, 1e-12):.1f}x): a dead {d.engine} is flown "
        "with the coefficient's drag (the propulsion file's rule); the data disagree"
        for d in windmilling_disagreements(propulsion, density_kg_m3)
    ]
