"""The endurance flight planned: the mission it flies and the launch's energy budget.

Step 5 of :mod:`tuflexperf.analysis.endurance`: "take off, climb to the pattern altitude,
cruise at the throttle until the reserve" written as a mission (:func:`endurance_mission`)
for the one mission integrator, and the climb of best rate it starts with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.errors import NotAttainable
from tuflexperf.io.battery import (
    Battery,
)
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import stall_speed_m_s


# --- launch: ground roll + climb at full throttle -------------------------------------------
@dataclass(frozen=True)
class LaunchBudget:
    """Charge and energy per fan for the ground roll and the climb to pattern altitude."""

    ground_roll_time_s: float
    liftoff_speed_m_s: float
    climb_airspeed_m_s: float
    climb_rate_m_s: float
    climb_time_s: float
    pattern_altitude_m: float
    charge_ah: float
    energy_wh: float

    def to_dict(self) -> dict[str, float]:
        return dict(self.__dict__)


def _best_climb(case: Case) -> tuple[float, float]:
    """Airspeed (m/s) and rate (m/s) of the best full-throttle climb from the lift-off (a
    catapult's release) speed: the batch's
    :func:`~tuflexperf.analysis.batch_kernels.best_climb` on the case's one row, so the
    mission's record climbs where the endurance's rows do."""
    from tuflexperf.analysis.batch_kernels import best_climb
    from tuflexperf.analysis.level_flight import LevelFlightRows
    from tuflexperf.models.aircraft import liftoff_speed_m_s, true_airspeed_m_s

    aircraft, rho = case.aircraft, case.density_kg_m3
    low = (true_airspeed_m_s(aircraft.launch_speed_m_s, rho) if aircraft.launch == "catapult"
           else liftoff_speed_m_s(aircraft, rho))
    speed, rate = best_climb(LevelFlightRows(aircraft, case.propulsion, rho, None, 1),
                             np.array([float(low)]),
                             np.array([float(stall_speed_m_s(aircraft, rho))]))
    return float(speed[0]), float(rate[0])


def endurance_mission(case: Case, battery: Battery, throttle: float = 0.5) -> Any:
    """The endurance flight as a mission: take off, climb to the pattern, cruise at ``throttle``.

    Segments (SPEC 4 mission types): the full-throttle take-off to lift-off (runway; a
    catapult starts airborne), a full-throttle climb at the best-rate airspeed
    (:func:`_best_climb`) to the battery file's pattern altitude, and a level cruise at
    ``throttle`` whose airspeed follows (its duration is solved, see
    :meth:`EnduranceModel.solve`).

    References
    ----------
    Paper section 4 (the launch, then cruise); Anderson, *Aircraft Performance and
    Design*, 5.10 (climb).
    """
    from tuflexperf.io.mission import MissionFile, SegmentSchema

    height = battery.pattern_altitude_m
    segments = [SegmentSchema(type="takeoff")]
    if height > 0:
        climb_speed, climb_rate = _best_climb(case)
        if climb_rate <= 0:
            raise NotAttainable("cannot climb at full throttle: no excess power after lift-off")
        eas = climb_speed * math.sqrt(case.density_kg_m3 / 1.225)  # flown at the case's rho
        from pydantic import ValidationError

        try:
            segments.append(SegmentSchema(type="climb", to_altitude_m=height,
                                          airspeed_m_s=eas, throttle=1.0))
        except ValidationError as exc:  # e.g. a stall near Mach 1: no climb a mission flies
            raise NotAttainable(
                f"the best-rate climb at {eas:.0f} m/s EAS cannot be flown: "
                f"{exc.errors()[0]['msg'].lower()} m/s"
            ) from None
    segments.append(SegmentSchema(type="cruise", throttle=throttle, time_min=1.0))
    return MissionFile("endurance", case.path, tuple(segments), None)


def endurance_mission_model(case: Case, battery: Battery, throttle: float = 0.5) -> Any:
    """The endurance mission built once (:class:`MissionModel`; the throttle is an input).

    ``throttle`` [fraction] only plans the cruise (it must hold level flight); each solve
    flies the cruise at its own throttle.

    The endurance figure is the case's point performance: the whole flight is flown at
    the case's density (the climb's height costs energy, not density), the take-off to
    lift-off (the climb starts from the runway), the cruise to the battery file's landing
    reserve.

    References
    ----------
    Paper section 4 (endurance estimate); SPEC 4 ("Mission file").
    """
    from tuflexperf.analysis.mission import MissionModel

    mission = endurance_mission(case, battery, throttle)
    return MissionModel(case, mission, battery.landing_reserve_fraction,
                        fixed_density_kg_m3=case.density_kg_m3, takeoff_to_obstacle=False,
                        battery=battery)


def launch_of(model: Any, flown: Any = None) -> LaunchBudget:
    """The launch segments of the endurance mission ``model`` (per fan: the larger engine's),
    from its flight ``flown`` (the launch is the same whatever the cruise), else flown."""
    flown = model.fly() if flown is None else flown
    case = model.case
    takeoff = getattr(model, "takeoff", None)
    climb = next((s for s in flown.segments if s.type == "climb"), None)
    if case.aircraft.launch == "catapult":
        from tuflexperf.models.aircraft import true_airspeed_m_s

        lift_off = float(true_airspeed_m_s(case.aircraft.launch_speed_m_s, case.density_kg_m3))
        roll_s = 0.0
    else:
        lift_off, roll_s = float(takeoff.liftoff_speed_m_s), float(takeoff.time_s)
    launch = [s for s in flown.segments if s.type in ("takeoff", "climb")]
    charge = [sum(s.charge_ah[i] for s in launch) for i in range(model.n)]
    energy = [sum(s.energy_wh[i] for s in launch) for i in range(model.n)]
    worst = int(np.argmax(charge))
    height = model.battery.pattern_altitude_m
    climb_time = climb.time_s if climb is not None else 0.0
    climb_speed = (float(flown.history["airspeed_m_s"][model.bounds[climb.index][0]])
                   if climb is not None else lift_off)
    return LaunchBudget(
        ground_roll_time_s=roll_s,
        liftoff_speed_m_s=lift_off,
        climb_airspeed_m_s=climb_speed,
        climb_rate_m_s=height / climb_time if climb_time > 0 else 0.0,
        climb_time_s=climb_time,
        pattern_altitude_m=height,
        charge_ah=charge[worst],
        energy_wh=energy[worst],
    )

