"""A mission flown for a batch of sampled parameter sets: the single case's own equations.

The equations of :class:`tuflexperf.analysis.mission.MissionModel` take the sampled
parameters (:meth:`MissionModel.parameters`) and the take-off's step rows as inputs; the
single case builds its CasADi function on them, a batch evaluates them on numpy rows
(:func:`tuflexperf.analysis.mission_rows.fly_rows`), in :data:`SAMPLED_STEPS` RK4 steps a
segment (the single case's :data:`~tuflexperf.analysis.mission.STEPS` give the same
numbers to 1e-9, held in ``tests/verification/test_mission_samples.py``). Per row
the take-off's airspeed history, rotation and path to the obstacle come from the batch's
take-off (:class:`tuflexperf.analysis.batch_model.BatchModel`, the closed forms held to the single
case in ``tests/verification/test_batch_equals_deterministic.py``), and the flight's checks
are :meth:`MissionModel._result`'s, vectorised: a row that stalls, cuts off, needs more
than full throttle, does not climb, outruns its fans or its pack's rating is not met
(NaN), never dropped.

Every mission the single case flies is sampled: a catapult's release and a take-off on
sagging packs (the batch's launch, :meth:`BatchEvaluator.launch`), a level flight at a fixed
throttle (:func:`level_speeds_at_throttle`) or at its best-endurance airspeed
(:func:`best_endurance_eas_rows`), each row's airspeed found as the single plan finds it, and
a drawn capacity (each row's packs: :func:`pack_rows_of`, the circuit's packs a parameter of
the chained function). A drawn key the mission does not fly is said, not guessed
(:func:`why_not_sampled`). ``solve_for`` is solved per row (:func:`longest_rows`),
vectorised over the batch.

References
----------
SPEC 4 (uncertainty block, mission file); Butcher, *Numerical Methods for Ordinary
Differential Equations*, 2nd ed., 2.3 (classic RK4, its error as the step's fourth power).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.mission import (
    BURST_OVER_CONTINUOUS,
    CORRECTION_SIZE,
    RATING_SEGMENT_S,
    SECONDS_PER_HOUR,
    MissionModel,
    airborne_path,
    takeoff_layout,
    takeoff_matrix,
)
from tuflexperf.analysis.mission_plan import best_endurance_eas_rows, level_speeds_at_throttle
from tuflexperf.analysis.mission_rows import (
    Memo,
    aux_size,
    digest,
    flight_phases,
    suffix_rows,
)
from tuflexperf.analysis.mission_solve import longest_rows
from tuflexperf.models.battery import first_window_beyond

Array = NDArray[np.float64]
FLOWN_KEYS = ("aircraft.mass_kg", "aircraft.wing_area_m2", "aircraft.cd0", "aircraft.k",
              "aircraft.cl_max", "atmosphere.altitude_m", "atmosphere.temperature_offset_k",
              "requirements.envelope.stall_margin",
              "requirements.mission.min_landing_charge_fraction",
              "requirements.takeoff.obstacle_height_m", "battery.cutoff_voltage_per_cell_v",
              "aircraft.launch_speed_m_s", "aircraft.launch_energy_j")
"""The drawn keys a sampled mission flies (with ``aircraft.takeoff.*``, through the batch's
take-off); other requirements' limits leave it alone."""
NODE_VALUES_PER_CALL = 4_000_000
"""States and aux values [-] one call of :func:`fly_rows` keeps (32 MB): the rows flown at
once are as many as fit (a row's history is ~80 kB at 64 steps a segment)."""
SAMPLED_STEPS = 8
"""RK4 steps of each sampled segment (and of the take-off's roll and arc): over 2 x 2500
draws of the shipped case with its test flight (seeds 1 and 4, the nominal and both readings)
the landing charge is within 2.4e-7 (relative) of 64 steps' (the single case's
:data:`STEPS`; 6 steps: 6.9e-7, 4: 3.3e-6), far below the Monte Carlo's standard error
(1.6e-4 at 10,000 samples); the error falls as the steps' fourth power. A ``solve_for``
cruise of 40 min moves by 6.6e-7 (relative)."""
MISSION_LANDING = "mission_landing_charge"
MISSION_SOLVED = "mission_solved_time"


def scale_power_laws(model: MissionModel, par: Array, scale: Array) -> None:
    """``par``'s power correction laws times ``scale`` ``(B,)`` [-] per row, in place: the
    law's ``c0``, ``c_x`` and ``c_V`` scale its ratio, so every fan's power (engines' and the
    fan-power law's) is the drawn multiple of the row's model (:data:`CORRECTION_SIZE`)."""
    first = model.n_par - 1 - CORRECTION_SIZE * (model.n + 1)
    for law in range(first, model.n_par - 1, CORRECTION_SIZE):
        par[law:law + 3] *= scale


def why_not_sampled(model: MissionModel, keys: list[str]) -> str | None:
    """Why the batch cannot fly ``model``'s mission for draws of ``keys`` (None: it can)."""
    for key in keys:
        # the case's requirement holds the reserve; of the requirements' numbers the mission
        # reads only FLOWN_KEYS' (the others are other requirements' limits)
        if key.startswith(("battery.mission.", "requirements.")) or key == "battery.capacity_ah":
            continue  # the reserve, the packs (pack_rows_of)
        if key not in FLOWN_KEYS and not key.startswith("aircraft.takeoff."):
            return f"{key} is drawn and the sampled mission does not fly it"
    return None


def _column(values: Mapping[str, Array], key: str, nominal: Any, size: int) -> Array:
    return np.broadcast_to(np.asarray(values.get(key, nominal), dtype=float).reshape(-1),
                           (size,)).copy()


def _takeoff_rows(model: MissionModel, m: Any, roll: tuple[Array, Array, Array, Array],
                  height: Array, layout: list[tuple[str, int]]
                  ) -> tuple[Array, NDArray[np.bool_]]:
    """The take-off's step rows per row ``(B, P + 1, columns)`` from the batch's take-off
    ``m`` and its ``roll`` (:meth:`BatchEvaluator.launch`: on sagging packs its history and
    airborne gradients are the packs'), and where the take-off reaches the obstacle."""
    from tuflexperf.models._math import interp_rows
    from tuflexperf.models.aircraft import (
        climb_gradient,
        obstacle_distances_m,
        transition_beyond_cl_max,
        transition_radius_m,
    )

    size = m.size
    _, time, v_lo, ok = roll
    ok = ok > 0.5
    rotation = _column({}, "", m.aircraft.takeoff.rotation_time_s, size)
    roll_s = np.where(ok, time - rotation, 0.0)
    sagging = m.packs_roll is not None
    t_hist = np.where(ok[:, None], np.nan_to_num(m.packs_roll.history_time) if sagging
                      else m.roll_history(ok), 0.0)
    v_hist = np.where(ok, v_lo, 0.0)[:, None] * np.linspace(0.0, 1.0, t_hist.shape[1])[None, :]
    steps = dict(layout)["roll"]
    stage_t = roll_s[:, None] / (2 * steps) * np.arange(2 * steps + 1)[None, :]
    stage_t[:, -1] = roll_s
    stages = interp_rows(stage_t, t_hist, v_hist)
    v_tr = m.transition_speed()
    load = _column({}, "", m.aircraft.takeoff.transition_load_factor, size)
    radius = np.asarray(transition_radius_m(v_tr, load), dtype=float)
    if sagging:  # the packs sag over the arc and the climb: their settled gradients
        arc_gradient = np.asarray(m.packs_air.arc_gradient, dtype=float) * np.ones(size)
        gradient = np.asarray(m.packs_air.climb_gradient, dtype=float) * np.ones(size)
    else:
        thrust = np.asarray(m.thrust(1.0, v_tr[:, None]), dtype=float).reshape(-1)
        gradient = np.asarray(climb_gradient(m.aircraft, thrust[:, None], v_tr[:, None],
                                             m.density), dtype=float).reshape(-1) * np.ones(size)
        arc_gradient = gradient
    arc, climb, top = (np.asarray(x, dtype=float).reshape(-1) * np.ones(size)
                       for x in obstacle_distances_m(radius, arc_gradient, height, gradient))
    air = None
    if model.takeoff_to_obstacle:
        air = airborne_path(v_tr, radius, height, gradient, arc_gradient, top >= height,
                            dict(layout)["arc"])
        ok &= np.isfinite(arc + climb) & ~np.asarray(transition_beyond_cl_max(load), dtype=bool)
    rows = takeoff_matrix(layout, stages, roll_s, rotation, np.where(ok, v_lo, 0.0), air)
    return np.where(ok[:, None, None], rows, 0.0), ok


_LAUNCH_STATE = ("packs_roll", "packs_airborne", "packs_beyond", "packs_air", "release")
"""What :meth:`BatchEvaluator.launch` leaves on the model besides its roll tuple."""


def _launch(evaluator: Any, m: Any, size: int, height: Array, battery: dict[str, Array],
            memo: Memo | None) -> tuple[Array, Array, Array, Array]:
    """The rows' take-off (:meth:`BatchEvaluator.launch`), or with a ``memo`` the one a
    flight of the batch on the same thrust and power made (a reading that moves only a dead
    engine's drag), its state set on ``m`` as the launch sets it."""
    from tuflexperf.analysis.readings import launch_identity

    def launched() -> tuple[tuple[Array, Array, Array, Array], dict[str, Any]]:
        # a column, as the batch's own take-off passes it: a (B,) height broadcast the
        # launch's airborne part to (B, B) and judged every row at the first row's height
        roll = evaluator.launch(m, size, height[:, None], battery)
        return roll, {name: getattr(m, name) for name in _LAUNCH_STATE}

    if memo is None:
        return launched()[0]
    roll, state = memo.get(digest("launch", launch_identity(evaluator.case), height,
                                  str(sorted(battery)), *(battery[k] for k in sorted(battery))),
                           launched)
    for name, value in state.items():
        setattr(m, name, value)
    return roll


@dataclass(frozen=True)
class PackRowsOfMission:
    """Per row the packs a drawn ``battery.capacity_ah`` makes: charge per engine [Ah] the
    landing fraction counts, the circuit's measured packs [-], the pole of its knee [Ah]
    and the pack's continuous rating [A] (None without one)."""

    capacity_ah: Array
    packs: Array
    pole_ah: Array
    rating_a: Array | None


def pack_rows_of(model: MissionModel, values: Mapping[str, Array], size: int
                 ) -> PackRowsOfMission:
    """The rows' packs as :class:`MissionModel` builds them for one capacity
    (``battery.circuit_packs``, ``capacity_ah x packs in parallel``, ``_pack_rating_a``)."""
    from tuflexperf.models.battery import equivalent_packs

    battery = model.battery
    capacity = _column(values, "battery.capacity_ah", battery.capacity_ah, size)
    per_engine = battery.packs_in_parallel_per_engine
    packs = (np.full(size, model.packs) if "battery.capacity_ah" not in values else
             np.asarray(equivalent_packs(per_engine, capacity, battery.as_read.capacity_ah),
                        dtype=float) * np.ones(size))
    c_rate = battery.max_discharge_c
    return PackRowsOfMission(capacity * per_engine, packs, packs * model.params.max_capacity_ah,
                             None if c_rate is None else float(c_rate) * capacity)


def sampled_landing(model: MissionModel, evaluator: Any, values: Mapping[str, Array],
                    size: int, coefficients: Array | None,
                    extrapolation_n: Array | None, steps: int = SAMPLED_STEPS,
                    memo: Memo | None = None, power_scale: Array | None = None
                    ) -> dict[str, tuple[Array, Array]]:
    """Per requirement its values and limits per row: ``mission_landing_charge`` (the least
    landing charge fraction, NaN where the mission is not attainable; the reserve) and with
    ``solve_for`` ``mission_solved_time`` (the longest time of that segment [min], solved
    per row by :func:`longest_rows`; the file's own).

    ``evaluator`` the case's :class:`tuflexperf.analysis.batch.BatchEvaluator` (its rows'
    aircraft, propulsion and density); ``values`` dotted key -> ``(B,)``; thrust
    ``coefficients`` ``(E, B, 6)`` and ``extrapolation_n`` ``(E, B)`` [N per m/s] as drawn;
    ``steps`` the RK4 steps of each segment (:func:`tuflexperf.analysis.mission_rows.fly_rows`);
    ``memo`` shared by the nominal case and its readings for one batch (what a reading does
    not change is flown once); ``power_scale`` ``(B,)`` [-] the drawn scale on every fan's
    electrical power (the power model's and the battery fit's errors), as the batch's
    endurance flies it: on the launch and on each correction law of ``par``.
    """
    from tuflexperf.analysis.airborne import obstacle_height_of
    from tuflexperf.analysis.attainable import stall_margin_of
    from tuflexperf.analysis.batch_model import BatchModel as _Model
    from tuflexperf.analysis.batch_model import SharedRows
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
    cutoff = model.battery.cells_in_series * _column(
        values, "battery.cutoff_voltage_per_cell_v", model.battery.cutoff_voltage_per_cell_v,
        size)
    ok = np.ones(size, dtype=bool)
    stall = margin * np.asarray(stall_speed_eas_m_s(aircraft), dtype=float).reshape(-1)
    durations = np.repeat(model.durations[:, None], size, axis=1)
    # the readings' take-offs on the nominal's thrust take its thrust-only results
    m = _Model(aircraft=aircraft, propulsion=evaluator._propulsion(coefficients),
               density=evaluator._density(values, size), extrapolation_n=extrapolation_n,
               size=size, stall_margin=margin, power_scale=power_scale,
               shared=None if memo is None else SharedRows(memo.rows,
                                                           *evaluator.thrust_identity))
    theta = np.repeat(model.theta[:, None], size, axis=1)
    for plan, segment in zip(model.plans, model.mission.segments, strict=True):
        eas: Any = plan.eas
        if eas is not None and segment.airspeed_m_s is None:  # each row's best endurance
            eas = best_endurance_eas_rows(model, plan.start_h, plan.dead, m, field_m, dt_k,
                                          stall)
            ok &= np.isfinite(eas)
            eas = np.where(np.isfinite(eas), eas, plan.eas)
            theta[3 * plan.index + 1] = eas
        if eas is not None:  # below stall: the plan itself is not attainable
            ok &= ~(eas < stall * (1 - 1e-12))
            if plan.kind == "time" and segment.distance_km is not None:
                rho = np.asarray(isa_density_kg_m3(field_m + plan.start_h, dt_k), dtype=float)
                durations[plan.index] = 1000.0 * segment.distance_km / np.asarray(
                    true_airspeed_m_s(eas, rho), dtype=float)
    # every phase a row may fly (a rotation, a straight climb), of no time where it does not
    layout = (takeoff_layout(True, model.takeoff_to_obstacle, True, steps) if model.tk_layout
              else [])
    cells = pack_rows_of(model, values, size)
    battery = evaluator._battery_rows(values, size)
    # data physics forbids (analysis.plausibility), as the batch refuses its requirements:
    # every row, or per row the packs beyond their rated C at the row's capacity
    if any("mission" in f.blocks and f.rule != "battery_rating" for f in evaluator.implausible):
        ok[:] = False
    if evaluator._side is not None:
        from tuflexperf.analysis.plausibility import rating_rows

        ok &= ~rating_rows(case, evaluator._side, battery["battery.capacity_ah"]).reshape(-1)
    par = model.parameters(aircraft, (field_m, dt_k), coefficients, extrapolation_n, size,
                           cells.packs)
    if power_scale is not None:
        scale_power_laws(model, par, np.asarray(power_scale, dtype=float))
    tk = np.zeros((size, model.tk.shape[0], 0))
    tk_key: str | None = None  # the take-off rows' memo key (a digest of them)
    for plan in model.plans:
        if plan.solve_v:  # level at a fixed throttle: each row's own airspeed to start from
            guess = level_speeds_at_throttle(model, plan.start_h, plan.throttle, plan.dead, m,
                                             field_m, dt_k)[0]
            ok &= np.isfinite(guess)
            theta[3 * plan.index + 2] = np.where(np.isfinite(guess), guess, plan.v_guess)
    if model.mission.segments and model.mission.segments[0].type == "takeoff":
        # a runway's roll or a catapult's release, per row as the batch's take-off flies it
        height = _column(values, "requirements.takeoff.obstacle_height_m",
                         obstacle_height_of(case), size)
        roll = _launch(evaluator, m, size, height, battery, memo)
        ok &= roll[3] > 0.5
        if layout:
            def rows() -> tuple[Array, NDArray[np.bool_]]:
                return _takeoff_rows(model, m, roll, height, layout)

            # the rows read the thrust alone but on sagging packs: a reading on the same
            # thrust, from the same launch, takes the nominal's
            if memo is not None and m.packs_roll is None:
                tk_key = digest("takeoff rows", evaluator.thrust_identity[0],
                                str(model.takeoff_to_obstacle), str(layout),
                                digest(*roll, height))
                tk, launched = memo.get(tk_key, rows)
            else:
                tk, launched = rows()
            ok &= launched
    k = model.mission.solve_for
    nodes = sum((sum(c + 1 for _, c in layout) if plan.kind == "takeoff" else steps + 1)
                for plan in model.plans if plan.kind != "event")
    count = max(1, NODE_VALUES_PER_CALL // (nodes * (2 * model.n + 3 + aux_size(model.n))))

    def fly(durations: Array) -> tuple[Array, Array | None]:
        landing, start = np.full(size, np.nan), None
        if k is not None:
            start = np.full((2 * model.n + 3, size), np.nan)
        for first in range(0, size, count):
            rows = slice(first, min(first + count, size))
            propulsion = evaluator._propulsion(None if coefficients is None
                                               else coefficients[:, rows, :])
            flown, end, entry = _flown(
                model, flight_phases(model, durations[:, rows], theta[:, rows], par[:, rows],
                                     tk[rows], layout, steps, memo=memo,
                                     tk_key=None if tk_key is None
                                     else f"{tk_key}:{rows.start}:{rows.stop}"),
                propulsion, field_m[rows], dt_k[rows], cutoff[rows], stall[rows], cells, rows,
                k)
            with np.errstate(invalid="ignore"):
                value = np.min(1.0 - end[:model.n] / cells.capacity_ah[rows], axis=0)
            landing[rows] = np.where(flown & ok[rows], value, np.nan)
            if start is not None:
                start[:, rows] = entry
        return landing, start

    landing, start = fly(durations)
    if k is None:
        return {MISSION_LANDING: (landing, reserve)}
    written = durations[k] / 60.0
    with np.errstate(invalid="ignore"):
        durations[k] = longest_rows(model, k, np.where(ok, 1.0, np.nan) * start, durations,
                                    theta, par, reserve, cutoff, cells.capacity_ah,
                                    cells.pole_ah, suffix_rows(model, k, steps))[0]
    landing, _ = fly(durations)
    solved = np.where(np.isfinite(landing), durations[k] / 60.0, np.nan)
    return {MISSION_LANDING: (landing, reserve), MISSION_SOLVED: (solved, written)}


def _flown(model: MissionModel, flight: Iterator[tuple[Any, list[tuple[Array, Any]]]],
           propulsion: Any, field_m: Array, dt_k: Array, cutoff: Array, stall: Array,
           cells: PackRowsOfMission, rows: slice, entered: int | None = None
           ) -> tuple[NDArray[np.bool_], Array, Array | None]:
    """Per row: the whole ``flight`` (:func:`~tuflexperf.analysis.mission_rows.flight_phases`)
    is attainable by :meth:`MissionModel._result`'s rules (the cut-off, full throttle, the
    pack's burst and continuous ratings, the fans' jet velocity, climbs that climb and
    descents that descend, a fixed throttle's airspeed above stall), judged phase by phase
    as it is flown; and the states at the landing and where segment ``entered`` begins
    (``(2n + 3, B)``, None without). Per row the field [m], temperature offset [K], the
    packs' cut-off [V] and the least EAS of level flight [m/s]; the ``rows`` of ``cells``'
    packs (:func:`pack_rows_of`)."""
    n = model.n
    pole = cells.pole_ah[rows]
    rating = None if cells.rating_a is None else cells.rating_a[rows]
    per_pack = model.battery.packs_in_parallel_per_engine
    ok = np.ones(field_m.shape[0], dtype=bool)
    heavy = np.zeros_like(ok)  # rows with a step beyond the continuous rating
    histories: list[tuple[Array, Array]] = []  # each phase's time and charges
    end: Array = np.empty(0)
    entry = None
    with np.errstate(invalid="ignore", over="ignore"):
        for plan, phases in flight:
            if entered is not None and plan.index == entered:
                entry = phases[0][0][:, 0] if phases else end
            for states, aux in phases:
                ok &= _phase_ok(model, plan, states, aux, propulsion, field_m, dt_k, cutoff,
                                stall, pole, rating, per_pack)
                q, t = states[:n], states[2 * n + 2]
                histories.append((t, q))
                if rating is not None:
                    # a stretch's mean current is a mean of the steps' (charge linear between
                    # nodes): only rows with a step beyond the rating can have a stretch
                    # beyond it (a phase's first node is the one before's last: no step)
                    dt = np.broadcast_to(np.diff(t, axis=0), q[:, 1:].shape)
                    dq = np.diff(q, axis=1) * SECONDS_PER_HOUR / per_pack
                    step = np.divide(dq, dt, out=np.where(dq == 0.0, 0.0, np.inf),
                                     where=dt > 0)
                    heavy |= np.any(~(step <= rating[None, None, :]), axis=(0, 1))
                end = states[:, -1]
        index = np.flatnonzero(heavy)
        if index.size and len(histories) > 0 and sum(t.shape[0] for t, _ in histories) > 1:
            t = np.concatenate([t[:, index] for t, _ in histories]).T
            q = np.concatenate([q[:, :, index] for _, q in histories], axis=1)
            last = first_window_beyond(t, q.transpose(2, 0, 1) / per_pack, rating[index],
                                       RATING_SEGMENT_S)[0]
            ok[index] &= ~np.isfinite(last)
    return ok, end, entry


def _phase_ok(model: MissionModel, plan: Any, states: Array, aux: Any, propulsion: Any,
              field_m: Array, dt_k: Array, cutoff: Array, stall: Array, pole: Array,
              rating: Array | None, per_pack: int) -> NDArray[np.bool_]:
    """Per row: one phase of segment ``plan`` (``states``/``aux`` ``(k, S + 1, B)``) breaks
    none of :func:`_flown`'s rules but the continuous rating (``aux`` a sequence of
    :func:`~tuflexperf.analysis.mission_rows.aux_size` rows)."""
    from tuflexperf.models.atmosphere import isa_density_kg_m3
    from tuflexperf.models.powertrain import beyond_jet_velocity
    from tuflexperf.models.thrust import density_ratio, engine_thrust_n

    n = model.n
    q, h = states[:n], states[2 * n]
    v, rate, reached, idle, thrust = aux[1], aux[2], aux[3], aux[4], aux[6 + 3 * n]
    rising = np.all(np.diff(q, axis=1) >= -1e-12, axis=(0, 1))
    ok = rising & np.all(np.isfinite(q) & (q < pole), axis=(0, 1))
    for i in range(n):
        ok &= np.all(np.isfinite(aux[6 + i]) & (aux[6 + i] >= 0.0), axis=0)
    live = [i for i in range(n) if i != plan.dead]
    least = functools.reduce(np.minimum, [aux[6 + n + i] for i in live])
    ok &= np.all(least >= cutoff - 1e-9, axis=0)
    ok &= np.all(reached >= 0.5, axis=0)
    if rating is not None and live:
        peak = np.max([np.max(aux[6 + i], axis=0) for i in live], axis=0) / per_pack
        ok &= ~(peak > BURST_OVER_CONTINUOUS * (1.0 + 1e-9) * rating)
    if plan.kind != "takeoff":
        rho = (np.full(h.shape, model.fixed_density) if model.fixed_density is not None
               else isa_density_kg_m3(field_m + h, dt_k))
        if plan.solve_v:  # the airspeed is an outcome here: stall bounds it; the throttle
            # must hold level flight all along
            ok &= np.all(np.abs(aux[5]) < 1e-9, axis=0)
            ok &= ~np.any(v < stall * np.sqrt(1.225 / rho) * (1 - 1e-12), axis=0)
            # a live fan whose models give no thrust, or thrust on no power, flies no cruise
            # (MissionModel._braking_engine)
            # (row-major: a drawn thrust's coefficients are columns, one a row)
            sigma = density_ratio(propulsion, rho.T)
            for i in live:
                pull = engine_thrust_n(propulsion.engines[i], plan.throttle, v.T, sigma)
                power = model._modelled_power(i, plan.throttle, v.T, rho.T)
                ok &= ~np.any((np.asarray(pull) <= 0.0) | (np.asarray(power) <= 0.0), axis=1)
        fast = np.asarray(beyond_jet_velocity(propulsion, v.T, rho.T), dtype=bool)
        ok &= ~np.any(fast & (thrust.T > 0.0), axis=1)
    if plan.kind == "height":
        climbing = plan.end_h > plan.start_h
        ok &= ~np.any((rate <= 0) if climbing else (rate >= 0), axis=0)
        if plan.solve_x:
            ok &= ~np.any(abs(plan.rate) >= v, axis=0)
            if not climbing:
                ok &= ~np.any(idle > 1e-9, axis=0)
    return ok
