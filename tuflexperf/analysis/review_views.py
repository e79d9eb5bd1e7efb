"""The design review's views of a case that no requirement asks for (issue 47 item 4).

Each is the project's own models composed, vectorised over a grid, no new physics:

- the altitude-airspeed envelope of level flight at full throttle, all engines and each
  engine out (:func:`flight_envelope`): the models of :mod:`.performance` on an (h, V) grid;
- endurance and range against take-off mass (:func:`endurance_against_mass`): the batch
  endurance (:mod:`.batch_endurance`, verified equal to the single case) on a
  (mass, throttle) grid, the best throttle per mass;
- the take-off's height over distance to the obstacle (:func:`takeoff_height_profile`):
  the solved ground roll, transition arc and straight climb of :mod:`.takeoff`;
- the thrust model at the measured points (:func:`thrust_at_points`).

References
----------
Anderson, *Aircraft Performance and Design*, 5.4 (level-speed range), 5.11 (ceilings),
5.13-5.14 (range and endurance), 6.7 (take-off to the obstacle).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.io.case import Case

Array = NDArray[np.float64]

ENVELOPE_ALTITUDES = 121
ENVELOPE_SPEEDS = 2001
ENVELOPE_TOP_WITHOUT_CEILING_M = 5000.0
MASS_SHARES = np.linspace(0.7, 1.3, 17)  # take-off masses drawn, as shares of the case's
MASS_THROTTLES = np.linspace(0.05, 1.0, 96)  # cruise throttles searched per mass


@dataclass(frozen=True)
class FlightEnvelope:
    """Level flight at full throttle over altitude: per engine state the least and greatest
    airspeed [m/s] (NaN where there is none), and the least airspeed (stall x margin)."""

    altitude_m: Array  # (H,)
    states: tuple[str, ...]  # "all engines", then "<name> dead (<mode>)"
    low_m_s: Array  # (states, H)
    high_m_s: Array  # (states, H)
    least_airspeed_m_s: Array  # (H,) stall x the envelope's margin
    jet_ceiling_m_s: Array  # (H,) the fans' jet velocity (inf without fan_area_m2)
    ceiling_m: tuple[float | None, ...]  # per state: the highest altitude of level flight

    def to_dict(self) -> dict[str, Any]:
        return {"states": list(self.states), "ceiling_m": list(self.ceiling_m)}


def flight_envelope(case: Case, top_m: float | None = None) -> FlightEnvelope:
    """The altitude-airspeed envelope of level flight (module docstring).

    Parameters
    ----------
    case : Case
        The case (its atmosphere's temperature offset, its OEI requirement's dead-engine
        mode, windmilling by default).
    top_m : float or None
        Highest altitude drawn [m]; None: :data:`ENVELOPE_TOP_WITHOUT_CEILING_M`.

    Returns
    -------
    FlightEnvelope
    """
    from tuflexperf.analysis.attainable import stall_margin_of
    from tuflexperf.analysis.performance import _dead_mode
    from tuflexperf.models.aircraft import level_flight_drag_n, stall_speed_m_s
    from tuflexperf.models.atmosphere import isa_density_kg_m3
    from tuflexperf.models.powertrain import jet_velocity_ceiling_m_s
    from tuflexperf.models.thrust import total_thrust_n

    foot = min(0.0, float(case.atmosphere.altitude_m))
    top = top_m if top_m is not None and math.isfinite(top_m) and top_m > foot else \
        ENVELOPE_TOP_WITHOUT_CEILING_M
    h = np.linspace(foot, top, ENVELOPE_ALTITUDES)
    rho = np.asarray(isa_density_kg_m3(h, case.atmosphere.temperature_offset_k), dtype=float)
    least = stall_margin_of(case) * np.asarray(stall_speed_m_s(case.aircraft, rho), dtype=float)
    jet = np.asarray(jet_velocity_ceiling_m_s(case.propulsion, rho), dtype=float) * np.ones_like(h)
    finite = jet[np.isfinite(jet)]
    v_top = min(float(finite.max()) if finite.size else math.inf, 6.0 * float(least.max()))
    # from half the least stall speed: level flight starts above it, and V = 0 has no drag
    v = np.linspace(0.5 * float(least.min()), v_top, ENVELOPE_SPEEDS)[None, :]
    mode = _dead_mode(case)
    engines = case.propulsion.engines
    dead: list[int | None] = [None] + (list(range(len(engines))) if len(engines) >= 2 else [])
    drag = np.asarray(level_flight_drag_n(case.aircraft, v, rho[:, None]), dtype=float)
    lows, highs, ceilings = [], [], []
    for engine in dead:  # a state per engine out: two or three, each a whole (h, V) grid
        thrust = np.asarray(total_thrust_n(case.propulsion, 1.0, v, rho[:, None], engine, mode),
                            dtype=float)
        ok = (thrust >= drag) & (v >= least[:, None]) & (v < jet[:, None])
        some = ok.any(axis=1)
        first = np.argmax(ok, axis=1)
        last = ok.shape[1] - 1 - np.argmax(ok[:, ::-1], axis=1)
        lows.append(np.where(some, v[0, first], np.nan))
        highs.append(np.where(some, v[0, last], np.nan))
        ceilings.append(float(h[some][-1]) if some.any() and not some[-1] else None)
    states = ("all engines",) + tuple(f"{engines[k].name} dead ({mode})"
                                      for k in dead[1:] if k is not None)
    return FlightEnvelope(h, states, np.array(lows), np.array(highs), least, jet,
                          tuple(ceilings))


@dataclass(frozen=True)
class MassSweep:
    """Endurance [min] and range [km] against take-off mass [kg]: on a (mass, throttle) grid
    and the best throttle per mass (NaN where no throttle flies)."""

    mass_kg: Array  # (M,)
    nominal_mass_kg: float
    throttle: Array  # (X,)
    endurance_min: Array  # (M, X) flight endurance at each cruise throttle
    airspeed_m_s: Array  # (M, X) the cruise's level-flight airspeed
    best_endurance_min: Array  # (M,)
    best_endurance_throttle: Array  # (M,)
    best_range_km: Array  # (M,) cruise airspeed x flight endurance, at its best throttle
    best_range_throttle: Array  # (M,)

    def to_dict(self) -> dict[str, Any]:
        return {"mass_kg": self.mass_kg.tolist(),
                "best_endurance_min": self.best_endurance_min.tolist(),
                "best_range_km": self.best_range_km.tolist()}


def endurance_against_mass(case: Case, shares: Array = MASS_SHARES,
                           throttles: Array = MASS_THROTTLES) -> MassSweep:
    """Flight endurance and range against take-off mass (module docstring).

    The batch evaluates the endurance requirement at each (mass, throttle); the case's own
    endurance requirement, or none, does not matter (its limit is not read here). Range is
    the cruise's true airspeed times the flight endurance (the climb flown at cruise speed).

    Parameters
    ----------
    case : Case
        The case; needs a battery file.
    shares : ndarray
        Take-off masses as shares of the case's mass [-].
    throttles : ndarray
        Cruise throttles searched [fraction].

    Returns
    -------
    MassSweep
    """
    from tuflexperf.analysis.batch import BatchEvaluator
    from tuflexperf.io.schemas import EnduranceRequirement

    # endurance alone: the other requirements' batches are not this page's
    asked = case.requirements.model_copy(update={
        "takeoff": None, "envelope": None, "oei": None, "mission": None,
        "endurance": EnduranceRequirement(throttle=0.5, min_flight_time_min=1.0)})
    evaluator = BatchEvaluator(dataclasses.replace(case, requirements=asked))
    nominal = float(case.aircraft.mass_kg)
    mass = nominal * np.asarray(shares, dtype=float)
    x = np.asarray(throttles, dtype=float)
    grid_m, grid_x = np.meshgrid(mass, x, indexing="ij")
    minutes, speed = _flown(evaluator, grid_m, grid_x)
    range_km = speed * minutes * 60.0 / 1000.0
    # each optimum again on a 20x finer grid around the coarse one's: the coarse grid's
    # best wanders by a step from mass to mass (kinks of up to 3 min on the shipped case)
    step = float(x[1] - x[0]) if x.size > 1 else 0.0
    fine = np.linspace(-step, step, 41)[None, :]
    best = []
    for values in (minutes, range_km):
        _, at = _best(values, x)
        near = np.clip(np.where(np.isfinite(at), at, x[-1])[:, None] + fine, x[0], x[-1])
        m_fine, s_fine = _flown(evaluator, np.broadcast_to(mass[:, None], near.shape), near)
        refined = m_fine if values is minutes else s_fine * m_fine * 60.0 / 1000.0
        both = np.concatenate([values, refined], axis=1)
        throttle = np.concatenate([np.broadcast_to(x, values.shape), near], axis=1)
        best.append(_best_rows(both, throttle))
    return MassSweep(mass, nominal, x, minutes, speed, *best[0], *best[1])


def _flown(evaluator: Any, mass: Array, throttle: Array) -> tuple[Array, Array]:
    """Flight endurance [min] and cruise airspeed [m/s] (NaN where not attainable) of the
    batch at each (mass [kg], throttle [-]), in their shape."""
    result = evaluator.evaluate({"aircraft.mass_kg": np.ravel(mass),
                                 "requirements.endurance.throttle": np.ravel(throttle)})
    minutes = result.values["flight_endurance"].reshape(np.shape(mass))
    speed = result.airspeeds["flight_endurance"].reshape(np.shape(mass))
    return minutes, np.where(np.isfinite(minutes), speed, np.nan)


def _best_rows(values: Array, throttle: Array) -> tuple[Array, Array]:
    """Per row the greatest value and its throttle, each row with throttles of its own."""
    some = np.any(np.isfinite(values), axis=1)
    k = np.argmax(np.where(np.isfinite(values), values, -np.inf), axis=1)
    rows = np.arange(values.shape[0])
    return (np.where(some, values[rows, k], np.nan), np.where(some, throttle[rows, k], np.nan))


def _best(values: Array, throttle: Array) -> tuple[Array, Array]:
    """Per row the greatest value and its throttle (NaN for a row of NaN)."""
    some = np.any(np.isfinite(values), axis=1)
    k = np.argmax(np.where(np.isfinite(values), values, -np.inf), axis=1)
    rows = np.arange(values.shape[0])
    return (np.where(some, values[rows, k], np.nan), np.where(some, throttle[k], np.nan))


@dataclass(frozen=True)
class HeightProfile:
    """Height over distance from brake release [m], ground roll to the obstacle (or as far
    as the take-off gets), and where each phase ends [m]."""

    distance_m: Array
    height_m: Array
    liftoff_m: float
    arc_end_m: float
    obstacle_m: float | None
    obstacle_height_m: float


def takeoff_height_profile(result: Any, points: int = 200) -> HeightProfile:
    """The take-off's path in the vertical plane: on the runway to the end of rotation, the
    transition arc (radius ``transition_radius_m``) to its height, the straight climb to the
    obstacle. Its corners are the solved result's own distances and heights.

    Parameters
    ----------
    result : TakeoffResult
        The solved take-off.
    points : int
        Points along the arc.
    """
    roll = float(result.ground_roll_m) if result.launch != "catapult" else 0.0
    radius = float(result.transition_radius_m)
    arc_height = float(result.transition_height_m)
    arc_length = float(result.transition_distance_m)
    obstacle = result.distance_to_obstacle_m
    height = float(result.obstacle_height_m)
    if result.obstacle_cleared_in_transition and obstacle is not None:
        arc_height, arc_length = height, float(obstacle) - roll
    if not (math.isfinite(radius) and radius > 0 and math.isfinite(arc_height)):
        return HeightProfile(np.array([0.0, roll]), np.zeros(2), roll, roll,
                             None if obstacle is None else float(obstacle), height)
    theta_end = math.acos(max(-1.0, 1.0 - arc_height / radius))
    theta = np.linspace(0.0, theta_end, points)
    # the arc's own geometry to its solved end: x = R sin, h = R (1 - cos), scaled so its end
    # lands on the result's distance (the solver's arc, to round-off)
    x_arc = radius * np.sin(theta)
    if x_arc[-1] > 0 and math.isfinite(arc_length):
        x_arc = x_arc * (arc_length / x_arc[-1])
    distance = [np.array([0.0, roll]), roll + x_arc]
    heights = [np.zeros(2), radius * (1.0 - np.cos(theta))]
    if obstacle is not None and not result.obstacle_cleared_in_transition:
        distance.append(np.array([float(obstacle)]))
        heights.append(np.array([height]))
    return HeightProfile(np.concatenate(distance), np.concatenate(heights), roll,
                         roll + (float(x_arc[-1]) if x_arc.size else 0.0),
                         None if obstacle is None else float(obstacle), height)


def thrust_at_points(case: Case, engine: tuple[str, ...], throttle: Array,
                     airspeed_m_s: Array) -> Array:
    """The thrust model at measured points [N], on its own basis (the reference density).

    Parameters
    ----------
    case : Case
        Its propulsion file.
    engine : tuple of str
        Each point's engine name (NaN for a name the model does not have).
    throttle, airspeed_m_s : ndarray
        The points [fraction], [m/s].
    """
    from tuflexperf.models.thrust import engine_thrust_n

    out = np.full(np.shape(throttle), np.nan)
    names = np.asarray(engine)
    for model in case.propulsion.engines:  # a handful of engines, each vectorised
        mine = names == model.name
        out[mine] = np.asarray(engine_thrust_n(model, throttle[mine], airspeed_m_s[mine]),
                               dtype=float)
    return out
