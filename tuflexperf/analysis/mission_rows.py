"""A mission flown for a batch of rows in numpy: the chained CasADi function's equations, once.

The same :meth:`~tuflexperf.analysis.mission_equations.SegmentEquations._algebra` that builds
the single case's CasADi step functions evaluates numpy rows here (its kernels dispatch on
the operands, :mod:`tuflexperf.models._math`), vectorised over the batch: a Python loop over
segments and steps, never over rows. Classic RK4 as the chained function flies it, with the
same nodes and aux outputs (:func:`fly_rows`), so the flight's checks after it are the
chained function's (``mission_samples._flown``).

Without a reference voltage the flight (throttle, airspeed, height rate, power) does not
depend on the packs' charge: per segment it is evaluated once at every RK4 stage point of
all rows (the heights of the stages are known before the packs are flown), and only the
packs' charge is stepped (:func:`_decoupled_phase`; RK4 on a system whose flight part does
not read the charge takes the very same stages). With one the loaded voltage couples them:
every stage is solved to rounding as the CasADi instant function solves it (Newton's chord
method on the loaded voltages and a fixed throttle's airspeed, a forward-difference
Jacobian: :func:`instant_rows`).

References
----------
Butcher, *Numerical Methods for Ordinary Differential Equations*, 2nd ed., 2.3 (classic
RK4); Press et al., *Numerical Recipes*, 3rd ed., 9.6 (Newton for systems), 5.7 (numerical
derivatives).
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.mission_equations import (
    _P_SIZE,
    SAMPLED_AIRCRAFT,
    SECONDS_PER_HOUR,
)
from tuflexperf.models.aircraft import true_airspeed_m_s
from tuflexperf.models.battery import current_at_power_a, open_circuit_voltage_v

Array = NDArray[np.float64]
_FD_STEP = 1e-7  # relative step of the Jacobian's forward differences: error ~1e-7
_CHORD_STEPS = 30  # from a few % off each chord step gains ~4 digits, from a stage nearby ~7


class Memo:
    """Phases flown for one batch, keyed on all they read (:func:`fly_rows`): the nominal
    case and its readings fly the same rows, and a reading differs from the nominal in one
    thing (the fans' power, a dead engine's drag), so most of its flight is the nominal's.
    Kept for one batch only (a batch's flights are ~100 MB at 10,000 rows). ``rows`` the
    take-offs' thrust-only results (:class:`tuflexperf.analysis.batch_model.SharedRows`):
    the batch's own where it evaluated the same rows."""

    def __init__(self, rows: dict[Any, Any] | None = None) -> None:
        self._items: dict[Any, Any] = {}
        self.rows: dict[Any, Any] = {} if rows is None else rows

    def get(self, key: Any, build: Any) -> Any:
        """The entry for ``key``, built by ``build()`` on first use."""
        if key not in self._items:
            self._items[key] = build()
        return self._items[key]


def digest(*values: Any) -> str:
    """A digest of numbers and arrays (their shapes and bytes): a memo's key."""
    h = hashlib.blake2b(digest_size=16)
    for value in values:
        if isinstance(value, str):  # a digest already
            h.update(value.encode())
            continue
        array = np.ascontiguousarray(value, dtype=float)
        h.update(repr(array.shape).encode())
        h.update(array.data)
    return h.hexdigest()


def aux_size(n: int) -> int:
    """Rows of the aux output per node: throttle, airspeed, rate, reached, idle excess,
    level residual, per engine current, voltage and power, thrust."""
    return 7 + 3 * n


def _phases(model: Any, plan: Any, durations: Array, theta: Array, tk: Array,
            layout: list[tuple[str, int]], steps: int) -> list[tuple[str, Any, list[Any]]]:
    """A segment's phases: kind (time, height), step per step and row (``(S, B)``) and the
    ten step parameters of :meth:`SegmentEquations._step_functions` (numbers, ``(1, B)``
    per row or ``(S, B)`` per step and row: a step's rows are contiguous)."""
    if plan.kind == "takeoff":
        out, first = [], 0
        for _, cols in layout:
            block = tk[:, :, first:first + cols]
            # a parameter the same for every row and step is a number: the equations take
            # its branch alone (full throttle: no throttle to solve for)
            out.append(("time", np.ascontiguousarray(block[:, _P_SIZE].T), [
                float(block[0, j, 0]) if np.all(block[:, j] == block[0, j, 0])
                else np.ascontiguousarray(block[:, j].T) for j in range(_P_SIZE)]))
            first += cols
        return out
    j = 3 * plan.index
    p = [1.0 if plan.solve_x else 0.0, theta[j][None, :], float(plan.rate),
         1.0 if plan.rate_from_excess else 0.0, theta[j + 1][None, :], 0.0, 0.0, 0.0, 0.0,
         theta[j + 2][None, :]]
    size = durations.shape[1]
    if plan.kind == "time":
        step = np.repeat((durations[plan.index] / steps)[None, :], steps, axis=0)
        return [("time", step, p)]
    return [("height", np.full((steps, size), (plan.end_h - plan.start_h) / steps), p)]


def instant_rows(model: Any, dead: int | None, solve_v: bool, q: list[Array], v_in: Array,
                 rho: Array, p: list[Any], par: Any, guess: Array | None = None
                 ) -> dict[str, Any]:
    """The CasADi instant function (:meth:`SegmentEquations._build_instant_function`) on
    rows: the loaded voltages (with a reference voltage) and a fixed throttle's airspeed
    solved from the open-circuit voltages and ``v_in`` (or ``guess``, the unknowns of a
    stage nearby), to rounding as the CasADi function's Newton steps: Newton's chord
    method, its Jacobian once by forward differences, each row until a step moves its
    unknowns by less than 1e-13 (relative)."""
    n = model.n
    voltage_unknown = model.case.propulsion.reference_voltage_v is not None
    packs = par[model.n_par - 1]
    ocv = [open_circuit_voltage_v(model.params, q[i], packs) for i in range(n)]
    m = (n if voltage_unknown else 0) + (1 if solve_v else 0)
    if not m:
        return model._algebra(ocv, v_in, q, rho, p, dead, par)

    def equations(z: Array) -> tuple[Array, dict[str, Any]]:
        u = [z[i] for i in range(n)] if voltage_unknown else ocv
        alg = model._algebra(u, z[m - 1] if solve_v else v_in, q, rho, p, dead, par)
        parts = list(alg["u_residual"]) if voltage_unknown else []
        if solve_v:
            parts.append(alg["level_residual"])
        return np.stack([np.broadcast_to(x, z.shape[1:]) for x in parts]), alg

    if guess is None:
        guess = np.stack([*(ocv if voltage_unknown else []), *([v_in] if solve_v else [])])
    z = np.broadcast_to(guess, (m, *np.broadcast_shapes(*(np.shape(x) for x in guess)))).copy()
    res, alg = equations(z)
    jac = np.empty((m, m, *z.shape[1:]))
    for j in range(m):
        h = _FD_STEP * np.maximum(np.abs(z[j]), 1.0)
        moved = z.copy()
        moved[j] += h
        jac[:, j] = (equations(moved)[0] - res) / h
    inverse = np.linalg.inv(np.moveaxis(jac, (0, 1), (-2, -1)))
    # each row (point) stops at its own convergence: its numbers are its own, whatever rows
    # it is solved beside (the batches, the two cores' halves)
    active = np.ones(z.shape[1:], dtype=bool)
    for _ in range(_CHORD_STEPS):
        delta = np.einsum("...ij,j...->i...", inverse, res)
        z = z - np.where(active, delta, 0.0)
        res, alg = equations(z)
        active &= np.any(np.abs(delta) > 1e-13 * np.maximum(np.abs(z), 1.0), axis=0)
        if not active.any():
            break
    return alg


def _aux_rows(alg: dict[str, Any], n: int, shape: tuple[int, ...]) -> list[Array]:
    """The aux output's rows (:func:`aux_size`) from :meth:`_algebra`'s dict, each
    ``shape`` (views where they can be: a phase's aux is read, never written)."""
    parts = [alg["x"], alg["v"], alg["rate"], alg["reached"], alg["idle_excess"],
             alg["level_residual"], *alg["current"], *alg["voltage"], *alg["power"],
             alg["thrust"]]
    return [np.broadcast_to(np.asarray(x, dtype=float), shape) for x in parts]


def _coupled_phase(model: Any, plan: Any, kind: str, step: Array, p: list[Any], state: Array,
                   par: Any) -> tuple[Array, Array]:
    """One phase flown with the flight read from the packs' loaded voltage: every RK4 stage
    solved (:func:`instant_rows`), as the chained function flies it. Returns the nodes'
    states ``(2n + 3, S + 1, B)`` and aux ``(aux, S + 1, B)``."""
    n, size, steps = model.n, state.shape[1], step.shape[0]
    forced = plan.kind == "takeoff"  # the take-off's rows: airspeed and rate given

    def at(column: Any, k: int) -> Any:  # a step's parameter per row (or one for all)
        if np.ndim(column) < 2:
            return column
        return column[k if column.shape[0] > 1 else 0]

    voltage_unknown = model.case.propulsion.reference_voltage_v is not None
    last: list[Array] = []  # the unknowns of the stage before: the next one starts there

    def evaluate(s: Array, k: int, which: int) -> Array:
        rho = model._rho(s[2 * n], par)
        pk = [at(c, k) for c in p]
        if forced:
            v_in = pk[which]
        else:
            v_in = pk[9] if plan.solve_v else true_airspeed_m_s(pk[4], rho)
        alg = instant_rows(model, plan.dead, plan.solve_v, list(s[:n]), v_in, rho, pk[:4], par,
                           last[-1] if last else None)
        if forced:
            alg["rate"] = pk[2]
        a = np.stack(_aux_rows(alg, n, (size,)))
        last[:] = [np.concatenate([a[6 + n:6 + 2 * n] if voltage_unknown else a[:0],
                                   a[1:2] if plan.solve_v else a[:0]])]
        return a

    def derivative(a: Array, k: int) -> Array:
        d = np.concatenate([a[6:6 + n] / SECONDS_PER_HOUR, a[6 + 2 * n:6 + 3 * n]
                            / SECONDS_PER_HOUR, a[2:3], a[1:2], np.ones((1, size))])
        if kind == "height":
            rate = a[2]
            safe = np.where(step[k] > 0, np.maximum(rate, 1e-6), np.minimum(rate, -1e-6))
            d = d / safe
        return d

    # a node's aux is the next step's first stage where that step starts as this one ends
    joined = not forced or all(np.ndim(c) < 2 or np.array_equal(c[:-1], c[1:])
                               for c in p[:6]) and np.array_equal(
        np.broadcast_to(p[8], step.shape)[:-1], np.broadcast_to(p[6], step.shape)[1:])
    states, auxes = [state], [evaluate(state, 0, 6)]
    for k in range(steps):
        dt = step[k]
        k1 = derivative(auxes[-1] if joined or k == 0 else evaluate(state, k, 6), k)
        k2 = derivative(evaluate(state + 0.5 * dt * k1, k, 7), k)
        k3 = derivative(evaluate(state + 0.5 * dt * k2, k, 7), k)
        k4 = derivative(evaluate(state + dt * k3, k, 8), k)
        state = state + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        states.append(state)
        auxes.append(evaluate(state, k, 8))
    return np.stack(states, axis=1), np.stack(auxes, axis=1)


def fly_rows(model: Any, durations: Array, theta: Array, par: Array, tk: Array,
             layout: list[tuple[str, int]], steps: int, start: Array | None = None,
             first: int = 0, memo: Memo | None = None
             ) -> tuple[Array, Array, list[tuple[int, int]]]:
    """The chained function's ``(states, aux)`` at every node for a batch of rows, from
    segment ``first`` on (from ``start``, ``(2n + 3, B)``, else full packs on the field),
    each segment in ``steps`` RK4 steps (the take-off in its rows' own, ``tk``), and each
    segment's node range.

    ``durations`` ``(segments, B)`` [s], ``theta`` ``(3 segments, B)``, ``par``
    ``(n_par, B)`` (:meth:`SegmentEquations.parameters`), ``tk`` ``(B, P + 1, columns)``
    the take-off's step rows of the phases ``layout``. Returns ``states``
    ``(2n + 3, B, nodes)`` and ``aux`` ``(aux_size(n), B, nodes)``. With a ``memo`` shared
    by the readings of one batch, a phase flown already from the same inputs is not flown
    again (nor its flight where only the fans' power differs).
    """
    states: list[Array] = []
    auxes: list[Array] = []
    bounds: list[tuple[int, int]] = []
    nodes = 0
    for plan, phases in flight_phases(model, durations, theta, par, tk, layout, steps, start,
                                      first, memo):
        if plan.kind == "event":
            bounds.append((nodes, 0))
            continue
        begin = nodes
        for s, a in phases:
            states.append(s)
            auxes.append(np.asarray(a))
            nodes += s.shape[1]
        bounds.append((begin, nodes))
    return (np.concatenate(states, axis=1).transpose(0, 2, 1),
            np.concatenate(auxes, axis=1).transpose(0, 2, 1), bounds)


def flight_phases(model: Any, durations: Array, theta: Array, par: Array, tk: Array,
                  layout: list[tuple[str, int]], steps: int, start: Array | None = None,
                  first: int = 0, memo: Memo | None = None, tk_key: str | None = None
                  ) -> Iterator[tuple[Any, list[tuple[Array, Any]]]]:
    """:func:`fly_rows`'s flight segment by segment (arguments as it takes): each plan and
    its phases' ``(states, aux)``, node-major as flown (``(2n + 3, S + 1, B)``, and
    :func:`aux_size` rows ``(S + 1, B)``, an array or a list of them; a node's rows
    contiguous; an event has none). A phase's
    first node is the one before's last. ``tk_key``: a digest of ``tk`` known already (a
    memo's key: ``tk`` need not be read to tell one flight's from another's)."""
    n = model.n
    size = par.shape[1]
    state = np.zeros((2 * n + 3, size)) if start is None else np.asarray(start, dtype=float)
    coupled = model.case.propulsion.reference_voltage_v is not None
    height_key: Any = None
    state_key: Any = None
    if memo is not None:  # the flight reads par's rows before the power corrections
        flight_par = digest(par[:len(SAMPLED_AIRCRAFT) + 2 + 7 * n])
        whole_par = digest(flight_par, par[len(SAMPLED_AIRCRAFT) + 2 + 7 * n:])
        # what the phases' steps and parameters are made of (_phases): read once
        made_of = (digest(durations, theta, tk_key or tk), steps, tuple(layout))
    for plan in model.plans[first:]:
        if plan.kind == "event":
            yield plan, []
            continue
        phases = []
        for number, (kind, step, p) in enumerate(_phases(model, plan, durations, theta, tk,
                                                          layout, steps)):
            with np.errstate(all="ignore"):
                if coupled or (kind == "time" and isinstance(p[3], float) and p[3] > 0.5):
                    s, a = _coupled_phase(model, plan, kind, step, p, state, par)
                    height_key = state_key = None
                elif memo is None:
                    s, a = _decoupled_phase(model, plan, kind, step, p, state, par)
                else:
                    # a phase's end is known by its key: the next one's start need not be
                    # read again (its height by the flight's key: the power does not move it)
                    height_key = height_key or digest(state[2 * n])
                    state_key = state_key or digest(state)
                    inputs = (model._flight_key(plan.dead), plan, kind, number, made_of)
                    aero_key = (*inputs, height_key, flight_par, "aero")
                    full_key = (*inputs, state_key, whole_par)
                    s, a = memo.get(full_key, functools.partial(
                        _decoupled_phase, model, plan, kind, step, p, state, par, memo,
                        aero_key))
                    height_key, state_key = aero_key, full_key
            phases.append((s, a))
            state = s[:, -1]
        yield plan, phases


def _accumulate(first: Array, increments: Array) -> Array:
    """``first``, then it plus each step's ``increments`` in turn (axis -2: steps), as RK4
    adds a step to the state: ``(..., S + 1, B)``. A loop over the steps on rows (numpy's
    cumsum across rows is ten times slower)."""
    out = np.empty(increments.shape[:-2] + (increments.shape[-2] + 1, increments.shape[-1]))
    out[..., 0, :] = first
    for k in range(increments.shape[-2]):
        np.add(out[..., k, :], increments[..., k, :], out=out[..., k + 1, :])
    return out


_FLIGHT_KEYS = ("x", "v", "rate", "reached", "idle_excess", "level_residual", "thrust")


def _decoupled_phase(model: Any, plan: Any, kind: str, step: Array, p: list[Any],
                     state: Array, par: Array, memo: Any = None,
                     memo_key: Any = None) -> tuple[Array, list[Array]]:
    """One phase flown where the flight does not read the packs (no reference voltage):
    the flight at every stage point of every row at once, then RK4 on the packs' charge.
    As :func:`_coupled_phase` returns, the aux a list of rows (views of the flight's: not
    copied into one array). ``memo`` (:class:`Memo`) keeps the flight before its
    power under ``memo_key``: a reading that changes only the fans' power reuses it."""
    n, size, steps = model.n, state.shape[1], step.shape[0]
    forced = plan.kind == "takeoff"  # the take-off's rows: airspeed and height rate given
    rise = step if kind == "height" else step * p[2]  # dh/dh = 1 over height
    h = _accumulate(state[2 * n], rise)  # at the nodes
    mid = h[:-1] + 0.5 * rise
    # the throttle is given in the take-off: its rate is not read (nor any row's fixed
    # throttle that stays along the steps)
    pk = [p[0], p[1], 0.0, p[3]] if forced else p[:4]
    steady = [c if np.ndim(c) < 2 else c[:1] for c in pk]
    given = [np.broadcast_to(c, (steps, size)) for c in p[6:9]] if forced else []
    joined = not forced or (np.array_equal(given[2][:-1], given[0][1:]) and all(
        np.ndim(c) < 2 or np.array_equal(c[:-1], c[1:]) for c in pk))
    if joined:  # nodes then middles: a node ends one step and starts the next
        points = np.concatenate([h, mid], axis=0)
        v_in = (np.concatenate([given[0][:1], given[2], given[1]], axis=0) if forced
                else None)
        pk = steady
        start, middle, end = (slice(0, steps), slice(steps + 1, 2 * steps + 1),
                              slice(1, steps + 1))
        nodes = slice(0, steps + 1)
    else:  # starts, middles, ends: a take-off's airspeed jumps between its steps
        points = np.concatenate([h[:-1], mid, h[1:]], axis=0)
        v_in = np.concatenate(given, axis=0)
        pk = [c if np.ndim(c) < 2 else np.concatenate([c, c, c], axis=0) for c in pk]
        start, middle, end = (slice(0, steps), slice(steps, 2 * steps),
                              slice(2 * steps, 3 * steps))
        nodes = np.r_[0, 2 * steps:3 * steps]
    shape = points.shape
    # a level segment (a rotation) flies one point: its flight is evaluated there once
    if all(np.ndim(c) < 2 or np.all(c == c[:1]) for c in (points, v_in, *pk)):
        points = points[:1]
        v_in = None if v_in is None else v_in[:1]
        pk = [c if np.ndim(c) < 2 else c[:1] for c in pk]
    parb = par[:, None, :]

    def aero() -> tuple[dict[str, Any], Any]:
        rho = model._rho(points, parb)
        if forced:
            return model._flight(None, v_in, rho, pk, plan.dead, parb), rho
        if plan.solve_v:
            q0 = [np.broadcast_to(state[i][None, :], points.shape) for i in range(n)]
            v_guess = np.broadcast_to(p[9], points.shape)
            return instant_rows(model, plan.dead, True, q0, v_guess, rho, pk, parb), rho
        return (model._flight(None, true_airspeed_m_s(p[4], rho), rho, pk, plan.dead, parb),
                rho)

    flight, rho = aero() if memo is None else memo.get(memo_key, aero)
    flight = {**flight, "power": model._powers(None, flight["x"], flight["v"], rho, plan.dead,
                                               parb)}
    live = [i for i in range(n) if i != plan.dead]
    power = np.stack([np.broadcast_to(flight["power"][i], shape) for i in live])
    v = np.broadcast_to(flight["v"], shape)
    if forced:  # each step's given rate, at its start, middle and end
        rates = [np.broadcast_to(p[2], (steps, size))] * 3
        node_rate = np.concatenate([rates[0][:1], rates[2]], axis=0)
    else:
        rate = np.broadcast_to(flight["rate"], shape)
        rates = [rate[start], rate[middle], rate[end]]
        node_rate = rate[nodes]
    if kind == "height":
        div = [np.where(step[:1] > 0, np.maximum(r, 1e-6), np.minimum(r, -1e-6))
               for r in rates]
        # a stage that stops climbing (descending): the step's heights are not its own
        wrong = np.any([np.any(d != r, axis=0) for d, r in zip(div, rates, strict=True)],
                       axis=0)
        inv = [1.0 / (SECONDS_PER_HOUR * d) for d in div]
    else:
        div = [1.0, 1.0, 1.0]
        wrong = np.zeros(size, dtype=bool)
        inv = [np.full((steps, size), 1.0 / SECONDS_PER_HOUR)] * 3
    stage_power = [np.ascontiguousarray(power[:, c]) for c in (start, middle, end)]
    packs = par[model.n_par - 1]
    q = state[live]
    charge = [q]
    for k in range(steps):  # the packs' charge: the one state the flight does not give
        dt = step[k]
        k1 = current_at_power_a(model.params, q, stage_power[0][:, k], packs) * inv[0][k]
        k2 = current_at_power_a(model.params, q + 0.5 * dt * k1, stage_power[1][:, k],
                                packs) * inv[1][k]
        k3 = current_at_power_a(model.params, q + 0.5 * dt * k2, stage_power[1][:, k],
                                packs) * inv[1][k]
        k4 = current_at_power_a(model.params, q + dt * k3, stage_power[2][:, k],
                                packs) * inv[2][k]
        q = q + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        charge.append(q)

    def integral(first: Array, values: list[Array]) -> Array:  # RK4 of a rate the state
        # does not change
        return _accumulate(first, step / 6.0 * (values[0] + 4.0 * values[1] + values[2]))

    states = np.empty((2 * n + 3, steps + 1, size))
    states[:] = state[:, None, :]
    states[live] = np.stack(charge, axis=1)
    states[[n + i for i in live]] = integral(state[[n + i for i in live]], [
        w * d for w, d in zip(stage_power, inv, strict=True)])
    v_stages = [v[start], v[middle], v[end]]
    if kind == "height":
        states[2 * n] = h
        states[2 * n + 1] = integral(state[2 * n + 1],
                                     [x / d for x, d in zip(v_stages, div, strict=True)])
        states[2 * n + 2] = integral(state[2 * n + 2], [1.0 / d for d in div])
    else:
        states[2 * n] = integral(state[2 * n], rates)
        states[2 * n + 1] = integral(state[2 * n + 1], v_stages)
        states[2 * n + 2] = _accumulate(state[2 * n + 2], step)
    states[:, 1:, wrong] = np.nan
    # the aux at the nodes: the flight there and the packs at the nodes' charge
    alg = {key: np.broadcast_to(flight[key], shape)[nodes] for key in _FLIGHT_KEYS}
    alg["rate"] = node_rate
    alg["power"] = [np.broadcast_to(x, shape)[nodes] for x in flight["power"]]
    alg.update(model._packs(None, list(states[:n]), alg["power"], plan.dead, parb))
    return states, _aux_rows(alg, n, (steps + 1, size))


def suffix_rows(model: Any, k: int, steps: int) -> Any:
    """``(start, durations, theta, par) -> (landing state, aux at segment k's end, most
    charge per pack, least loaded voltage of a live engine [V])`` on rows: the mission from
    where segment ``k`` begins, as :meth:`SolveFor._suffix_function` gives it (the least
    voltage segment ``k``'s at its end and every later segment's at each of its nodes)."""
    n = model.n

    def flown(start: Array, durations: Array, theta: Array, par: Array
              ) -> tuple[Array, Array, Array, Array]:
        size = start.shape[1]
        states, aux, bounds = fly_rows(model, durations, theta, par,
                                       np.zeros((size, _P_SIZE + 1, 0)), [], steps, start, k)
        least = np.full(size, np.inf)
        for plan, (a, b) in zip(model.plans[k:], bounds, strict=True):
            if plan.kind == "event":
                continue
            live = [6 + n + i for i in range(n) if i != plan.dead]
            nodes = slice(b - 1, b) if plan.index == k else slice(a, b)
            least = np.minimum(least, np.min(aux[live, :, nodes], axis=(0, 2)))
        at_k = aux[:, :, bounds[0][1] - 1]
        return states[:, :, -1], at_k, np.max(states[:n], axis=2), least

    return flown
