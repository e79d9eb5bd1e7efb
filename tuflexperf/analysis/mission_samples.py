"""A mission flown for a batch of sampled parameter sets: the single case's own function.

The chained CasADi function of :class:`tuflexperf.analysis.mission.MissionModel` takes the
sampled parameters (:meth:`MissionModel.parameters`) and the take-off's step rows as inputs,
so a batch is that same function, expanded to SX and evaluated with ``Function.map(B,
"thread", 2)``; the nominal case is a batch of one with the case's own numbers. Per row
the take-off's airspeed history, rotation and path to the obstacle come from the batch's
take-off (:class:`tuflexperf.analysis.batch._Model`, the closed forms held to the single
case in ``tests/verification/test_batch_equals_deterministic.py``), and the flight's checks
are :meth:`MissionModel._result`'s, vectorised: a row that stalls, cuts off, needs more
than full throttle, does not climb, outruns its fans or its pack's rating is not met
(NaN), never dropped.

What the batch does not fly yet is said, not guessed (:func:`why_not_sampled`): battery or
propulsion keys drawn, a segment whose airspeed is solved (no ``airspeed_m_s``, or a level
flight at a fixed throttle), a catapult launch, a take-off on sagging packs, ``solve_for``.

References
----------
Andersson et al. (2019), "CasADi", Math. Prog. Comp. 11 (``Function.map``); SPEC 4
(uncertainty block, mission file).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.mission import (
    BURST_OVER_CONTINUOUS,
    RATING_SEGMENT_S,
    SECONDS_PER_HOUR,
    STEPS,
    MissionModel,
    airborne_path,
    takeoff_matrix,
)

Array = NDArray[np.float64]
FLOWN_KEYS = ("aircraft.mass_kg", "aircraft.wing_area_m2", "aircraft.cd0", "aircraft.k",
              "aircraft.cl_max", "atmosphere.altitude_m", "atmosphere.temperature_offset_k",
              "requirements.envelope.stall_margin",
              "requirements.mission.min_landing_charge_fraction",
              "requirements.takeoff.obstacle_height_m")
"""The drawn keys a sampled mission flies (with ``aircraft.takeoff.*``, through the batch's
take-off); other requirements' limits leave it alone."""
ROWS_PER_MAP = 2000  # rows per map call: the history is ~10 kB a row


def why_not_sampled(model: MissionModel, keys: list[str]) -> str | None:
    """Why the batch cannot fly ``model``'s mission for draws of ``keys`` (None: it can)."""
    case = model.case
    for key in keys:
        if key.startswith("requirements.") and not key.startswith(("requirements.mission.",
                                                                    "requirements.envelope.",
                                                                    "requirements.takeoff.")):
            continue
        if key not in FLOWN_KEYS and not key.startswith("aircraft.takeoff."):
            return f"{key} is drawn and the sampled mission does not fly it"
    if case.aircraft.launch == "catapult":
        return "a catapult launch is flown for the nominal case only"
    if model.mission.solve_for is not None:
        return "solve_for is solved for the nominal case only"
    if any(plan.solve_v for plan in model.plans):
        return "a level flight at a fixed throttle is flown for the nominal case only"
    if any(s.type not in ("takeoff", "engine_failure") and s.airspeed_m_s is None
           for s in model.mission.segments):
        return "a segment without airspeed_m_s is flown for the nominal case only"
    if model.tk_layout and case.propulsion.reference_voltage_v is not None:
        return "a take-off on sagging packs is flown for the nominal case only"
    return None


def _column(values: Mapping[str, Array], key: str, nominal: Any, size: int) -> Array:
    return np.broadcast_to(np.asarray(values.get(key, nominal), dtype=float).reshape(-1),
                           (size,)).copy()


def _takeoff_rows(model: MissionModel, m: Any, height: Array, layout: list[tuple[str, int]]
                  ) -> tuple[Array, NDArray[np.bool_]]:
    """The take-off's step rows per row ``(B, P + 1, columns)`` from the batch's take-off
    ``m``, and where the take-off reaches the obstacle."""
    from tuflexperf.models._math import interp_rows
    from tuflexperf.models.aircraft import (
        climb_gradient,
        obstacle_distances_m,
        transition_beyond_cl_max,
        transition_radius_m,
    )

    size = m.size
    _, time, v_lo, ok = m.ground_roll()
    ok = ok > 0.5
    rotation = _column({}, "", m.aircraft.takeoff.rotation_time_s, size)
    roll_s = np.where(ok, time - rotation, 0.0)
    t_hist = np.where(ok[:, None], m.roll_history(ok), 0.0)
    v_hist = np.where(ok, v_lo, 0.0)[:, None] * np.linspace(0.0, 1.0, t_hist.shape[1])[None, :]
    stage_t = roll_s[:, None] / (2 * STEPS) * np.arange(2 * STEPS + 1)[None, :]
    stage_t[:, -1] = roll_s
    stages = interp_rows(stage_t, t_hist, v_hist)
    v_tr = m.transition_speed()
    load = _column({}, "", m.aircraft.takeoff.transition_load_factor, size)
    radius = np.asarray(transition_radius_m(v_tr, load), dtype=float)
    thrust = np.asarray(m.thrust(1.0, v_tr[:, None]), dtype=float).reshape(-1)
    gradient = np.asarray(climb_gradient(m.aircraft, thrust[:, None], v_tr[:, None],
                                         m.density), dtype=float).reshape(-1) * np.ones(size)
    arc, climb, top = (np.asarray(x, dtype=float).reshape(-1) * np.ones(size)
                       for x in obstacle_distances_m(radius, gradient, height))
    air = None
    if model.takeoff_to_obstacle:
        air = airborne_path(v_tr, radius, height, gradient, gradient, top >= height)
        ok &= np.isfinite(arc + climb) & ~np.asarray(transition_beyond_cl_max(load), dtype=bool)
    rows = takeoff_matrix(layout, stages, roll_s, rotation, np.where(ok, v_lo, 0.0), air)
    return np.where(ok[:, None, None], rows, 0.0), ok


def sampled_landing(model: MissionModel, evaluator: Any, values: Mapping[str, Array],
                    size: int, coefficients: Array | None,
                    extrapolation_n: Array | None) -> dict[str, Array]:
    """Per row: ``mission_landing_charge`` (the least landing charge fraction, NaN where
    the mission is not attainable) and its limit (the reserve).

    ``evaluator`` the case's :class:`tuflexperf.analysis.batch.BatchEvaluator` (its rows'
    aircraft, propulsion and density); ``values`` dotted key -> ``(B,)``; thrust
    ``coefficients`` ``(E, B, 6)`` and ``extrapolation_n`` ``(E, B)`` [N] as drawn.
    """
    from tuflexperf.analysis.attainable import stall_margin_of
    from tuflexperf.analysis.batch import _Model
    from tuflexperf.analysis.takeoff import obstacle_height_of
    from tuflexperf.models.aircraft import stall_speed_eas_m_s, true_airspeed_m_s
    from tuflexperf.models.atmosphere import isa_density_kg_m3

    case = model.case
    aircraft = evaluator._aircraft(values, size)
    atmosphere = case.atmosphere
    field_m = _column(values, "atmosphere.altitude_m", atmosphere.altitude_m, size)
    dt_k = _column(values, "atmosphere.temperature_offset_k",
                   atmosphere.temperature_offset_k, size)
    margin = _column(values, "requirements.envelope.stall_margin", stall_margin_of(case), size)
    reserve = _column(values, "requirements.mission.min_landing_charge_fraction",
                      model.reserve, size)
    ok = np.ones(size, dtype=bool)
    stall = margin * np.asarray(stall_speed_eas_m_s(aircraft), dtype=float).reshape(-1)
    durations = np.repeat(model.durations[:, None], size, axis=1)
    for plan, segment in zip(model.plans, model.mission.segments, strict=True):
        if plan.eas is not None:  # below stall: the plan itself is not attainable
            ok &= ~(plan.eas < stall * (1 - 1e-12))
            if plan.kind == "time" and segment.distance_km is not None:
                rho = np.asarray(isa_density_kg_m3(field_m + plan.start_h, dt_k), dtype=float)
                durations[plan.index] = 1000.0 * segment.distance_km / np.asarray(
                    true_airspeed_m_s(plan.eas, rho), dtype=float)
    history, bounds, layout = model.sampled_chain()
    par = model.parameters(aircraft, (field_m, dt_k), coefficients, extrapolation_n, size)
    tk = np.zeros((size, model.tk.shape[0], 0))
    if layout:
        m = _Model(aircraft=aircraft, propulsion=evaluator._propulsion(coefficients),
                   density=evaluator._density(values, size), extrapolation_n=extrapolation_n,
                   size=size, stall_margin=margin)
        height = _column(values, "requirements.takeoff.obstacle_height_m",
                         obstacle_height_of(case), size)
        tk, launched = _takeoff_rows(model, m, height, layout)
        ok &= launched
    theta = np.repeat(model.theta[:, None], size, axis=1)
    landing = np.full(size, np.nan)
    for first in range(0, size, ROWS_PER_MAP):
        rows = slice(first, min(first + ROWS_PER_MAP, size))
        count = rows.stop - rows.start
        block = tk[rows]
        states, aux = (np.asarray(x, dtype=float) for x in history.map(count, "thread", 2)(
            durations[:, rows], theta[:, rows], par[:, rows],
            block.transpose(1, 0, 2).reshape(block.shape[1], -1)))
        nodes = states.shape[1] // count
        states = states.reshape(states.shape[0], count, nodes)
        aux = aux.reshape(aux.shape[0], count, nodes)
        propulsion = evaluator._propulsion(None if coefficients is None
                                           else coefficients[:, rows, :])
        flown = _flown(model, bounds, states, aux, propulsion, field_m[rows], dt_k[rows])
        q_end = states[:model.n, :, -1]
        with np.errstate(invalid="ignore"):
            value = np.min(1.0 - q_end / model.capacity_ah, axis=0)
        landing[rows] = np.where(flown & ok[rows], value, np.nan)
    return {"value": landing, "limit": reserve}


def _flown(model: MissionModel, bounds: list[tuple[int, int]], states: Array, aux: Array,
           propulsion: Any, field_m: Array, dt_k: Array) -> NDArray[np.bool_]:
    """Per row: the whole flight is attainable by :meth:`MissionModel._result`'s rules (the
    cut-off, full throttle, the pack's burst and continuous ratings, the fans' jet velocity,
    climbs that climb and descents that descend). ``states``/``aux`` ``(k, B, nodes)``."""
    from tuflexperf.models.atmosphere import isa_density_kg_m3
    from tuflexperf.models.battery import first_window_beyond
    from tuflexperf.models.powertrain import beyond_jet_velocity

    n = model.n
    q, h, t = states[:n], states[2 * n], states[2 * n + 2]
    v, rate, reached, idle = aux[1], aux[2], aux[3], aux[4]
    current, voltage, thrust = aux[6:6 + n], aux[6 + n:6 + 2 * n], aux[6 + 3 * n]
    size = q.shape[1]
    ok = np.ones(size, dtype=bool)
    pole = model.packs * model.params.max_capacity_ah
    rating = model._pack_rating_a()
    per_pack = model.battery.packs_in_parallel_per_engine
    with np.errstate(invalid="ignore", over="ignore"):
        rising = np.all(np.diff(q, axis=2) >= -1e-12, axis=(0, 2))
        ok &= rising & np.all(np.isfinite(q) & (q < pole), axis=(0, 2))
        ok &= np.all(np.isfinite(current) & (current >= 0.0), axis=(0, 2))
        if rating is not None and t.shape[1] > 1:
            # a stretch's mean current is a mean of the steps' (charge linear between nodes):
            # only rows with a step beyond the rating can have a stretch beyond it
            # (a segment's first node is the last one's end: no time between them, no step)
            dt = np.broadcast_to(np.diff(t, axis=1), q[:, :, 1:].shape)
            dq = np.diff(q, axis=2) * SECONDS_PER_HOUR / per_pack
            steps = np.divide(dq, dt, out=np.where(dq == 0.0, 0.0, np.inf), where=dt > 0)
            heavy = np.flatnonzero(np.any(~(steps <= rating), axis=(0, 2)))
            if heavy.size:
                end = first_window_beyond(t[heavy], q[:, heavy].transpose(1, 0, 2) / per_pack,
                                          rating, RATING_SEGMENT_S)[0]
                ok[heavy] &= ~np.isfinite(end)
        for plan, (a, b) in zip(model.plans, bounds, strict=True):
            if plan.kind == "event":
                continue
            live = [i for i in range(n) if i != plan.dead]
            sl = slice(a, b)
            ok &= np.all(np.min(voltage[live, :, sl], axis=0) >= model.cutoff_v - 1e-9, axis=1)
            ok &= np.all(reached[:, sl] >= 0.5, axis=1)
            if rating is not None and live:
                peak = np.max(current[live, :, sl], axis=0) / per_pack
                ok &= ~np.any(peak > BURST_OVER_CONTINUOUS * rating * (1.0 + 1e-9), axis=1)
            if plan.kind != "takeoff":
                rho = (np.full(h[:, sl].shape, model.fixed_density)
                       if model.fixed_density is not None
                       else isa_density_kg_m3(field_m[:, None] + h[:, sl], dt_k[:, None]))
                fast = np.asarray(beyond_jet_velocity(propulsion, v[:, sl], rho), dtype=bool)
                ok &= ~np.any(fast & (thrust[:, sl] > 0.0), axis=1)
            if plan.kind == "height":
                climbing = plan.end_h > plan.start_h
                wrong = (rate[:, sl] <= 0) if climbing else (rate[:, sl] >= 0)
                ok &= ~np.any(wrong, axis=1)
                if plan.solve_x:
                    ok &= ~np.any(abs(plan.rate) >= v[:, sl], axis=1)
                    if not climbing:
                        ok &= ~np.any(idle[:, sl] > 1e-9, axis=1)
    return ok
