"""Monte Carlo over the case's uncertain parameters and thrust model, in seeded chunks.

The samples are split in chunks of :data:`CHUNK_SIZE`; chunk ``i`` draws from
``numpy.random.default_rng(SeedSequence(seed).spawn(n_chunks)[i])``. Every
:data:`CHUNKS_PER_BATCH` consecutive chunks are evaluated by
:class:`tuflexperf.analysis.batch.BatchEvaluator` as one batch (the unit of work of
``--workers`` and Dask). Neither the chunking nor the batching depends on where batches run,
so in-process, ``--workers N`` local processes and a Dask cluster give the same numbers for
the same seed.

Draws per chunk, in this order: each declared parameter (sorted by key) -- normal
``[mean, sd]``, uniform ``[low, high]``, truncated normal ``[mean, sd, low, high]`` by
inverse CDF; then the error model's sources (:mod:`tuflexperf.analysis.error_model`: the
coefficients' covariance, the error beyond the tested range, the model-form surface, the
rig's systematic errors, then the power scale of the power model and the battery fit), all
jointly: each sample is one draw of every source.

A mission requirement is flown for every sample by the single case's own chained function
(:mod:`tuflexperf.analysis.mission_samples`), in the same batches, so it too gives the same
numbers wherever the batches run; a mission the batch cannot fly yet is said not sampled.

References
----------
Hanson & Beard (2010), "Applying Monte Carlo simulation to launch vehicle design and
requirements verification", NASA/TP-2010-216447; O'Neill (2015), "PCG" / numpy
``SeedSequence`` (independent streams by spawning).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.batch import BatchResult
from tuflexperf.analysis.batch_kernels import nominal_engines
from tuflexperf.analysis.cache import file_key, fingerprint
from tuflexperf.analysis.error_model import (
    ErrorModel,
    draw_power_scale,
    draw_thrust,
    error_model_for,
)
from tuflexperf.analysis.evaluators import EVALUATORS_KEPT, evaluator_for
from tuflexperf.analysis.probability import normal_logcdf, normal_ppf_of_log
from tuflexperf.analysis.runtime import (
    earlier_objects_frozen,
    freed_arrays_kept,
    one_blas_thread,
)
from tuflexperf.errors import InputError
from tuflexperf.io.case import MAX_SAMPLES, Case, UncertaintySchema
from tuflexperf.io.dotted import value_bounds

Array = NDArray[np.float64]
CHUNK_SIZE = 2500
CHUNKS_PER_BATCH = 4
"""Chunks evaluated as one batch: numpy's per-call cost spread over 10,000 rows, not 2,500
(10,000 samples took 0.32 s in four batches, 0.25 s in one), at a few MB per row array."""
ENVELOPE_KEY = "requirements.envelope"
"""The count key of samples whose envelope bounds cross (``samples_outside_bounds``)."""
REFUSED_AIRCRAFT_KEY = "aircraft"
"""The count key of samples whose aircraft ``check`` refuses (``BatchEvaluator.rows_refused``)."""


@dataclass(frozen=True)
class SamplingPlan:
    """What to draw: ``parameters`` key -> (kind, arguments); thrust model switches."""

    samples: int
    seed: int
    required_probability: float
    parameters: tuple[tuple[str, str, tuple[float, ...]], ...]
    covariance: bool
    extrapolation: bool
    residual: bool = False
    # every source the samples draw, or could not and why (None: the thrust switches alone)
    errors: ErrorModel | None = None

    @property
    def chunks(self) -> list[int]:
        """Sizes of the chunks (all :data:`CHUNK_SIZE` but the last)."""
        full, rest = divmod(self.samples, CHUNK_SIZE)
        return [CHUNK_SIZE] * full + ([rest] if rest else [])

    def to_dict(self) -> dict[str, Any]:
        return {
            "samples": self.samples,
            "seed": self.seed,
            "required_probability": self.required_probability,
            "chunk_size": CHUNK_SIZE,
            "chunks": len(self.chunks),
            "chunks_per_batch": CHUNKS_PER_BATCH,
            "parameters": {key: {kind: list(args)} for key, kind, args in self.parameters},
            "propulsion": {"covariance": self.covariance, "extrapolation": self.extrapolation,
                           "residual": self.residual},
            **({"sources": self.errors.to_dict()} if self.errors is not None else {}),
        }


def plan_for(case: Case, samples: int | None = None, seed: int | None = None) -> SamplingPlan:
    """The case's ``uncertainty:`` block, with ``--samples`` / ``--seed`` taking precedence.

    References
    ----------
    SPEC 4 (uncertainty block), SPEC 5 (``check --samples``).
    """
    block = case.uncertainty or UncertaintySchema()
    n = block.samples if samples is None else samples
    if not 1 <= n <= MAX_SAMPLES:
        raise InputError(f"--samples: must be from 1 to {MAX_SAMPLES:g}, got {n}")
    return SamplingPlan(
        samples=int(n),
        seed=int(block.seed if seed is None else seed),
        required_probability=float(block.required_probability),
        parameters=tuple(
            (key, dist.kind, tuple(dist.arguments))
            for key, dist in sorted(block.parameters.items())
        ),
        covariance=bool(block.propulsion.covariance),
        extrapolation=bool(block.propulsion.extrapolation),
        residual=bool(block.propulsion.residual),
        errors=error_model_for(case, block.propulsion),
    )


def _draw(rng: np.random.Generator, kind: str, args: Sequence[float], size: int) -> Array:
    if kind == "normal":
        return rng.normal(args[0], args[1], size)
    if kind == "uniform":
        return rng.uniform(args[0], args[1], size)
    mean, sd, low, high = args
    a, b = (low - mean) / sd, (high - mean) / sd
    u = rng.uniform(0.0, 1.0, size)
    # a window in the upper tail: Phi rounds to 1 beyond ~8.3 sd (every sample fell on
    # `high`); its mirror image in the lower tail has full precision. With 1 - u the
    # mirrored draw is the same sample, in exact arithmetic, as the direct one
    mirrored = a + b > 0.0
    first, last = (-b, -a) if mirrored else (a, b)
    # Phi(first) + (Phi(last) - Phi(first)) u in logs: beyond ~38.5 sd Phi underflows to 0
    # and every sample fell on the far bound, the wrong one (outside audit: a mass window
    # 40-100 sd below its mean drew every sample at its least value, a false PASS)
    log_last = normal_logcdf(last)
    ratio = np.exp(normal_logcdf(first) - log_last)
    with np.errstate(divide="ignore"):
        z = normal_ppf_of_log(log_last + np.log(ratio + (1.0 - ratio) * (1.0 - u if mirrored
                                                                           else u)))
    return np.clip(mean + sd * (-z if mirrored else z), low, high)


@dataclass(frozen=True)
class ChunkDraw:
    values: dict[str, Array]
    coefficients: Array | None
    extrapolation_n: Array | None
    size: int
    power_scale: Array | None = None  # per sample, on every fan's electrical power [-]


def _legacy_errors(case: Case, plan: SamplingPlan) -> ErrorModel:
    """A plan built without its error model (by hand): the thrust switches it names."""
    from tuflexperf.io.schemas import PropulsionUncertaintySchema

    return error_model_for(case, PropulsionUncertaintySchema(
        covariance=plan.covariance, extrapolation=plan.extrapolation, residual=plan.residual,
        model_form=plan.residual, rig=False, power_model=False, battery_fit=False))


def draw_chunk(case: Case, plan: SamplingPlan, index: int) -> ChunkDraw:
    """The samples of chunk ``index`` (its own spawned seed; see the module docstring).

    Parameter values in their keys' units; thrust coefficients ``(E, size, 6)``, the error
    beyond the tested range ``(E, size)`` [N] and the power scale ``(size,)`` [-] of the
    error model (:func:`tuflexperf.analysis.error_model.draw_thrust`).

    References
    ----------
    Rubinstein & Kroese, *Simulation and the Monte Carlo Method*, 3rd ed., 2.5 (multivariate
    normal by a matrix square root, inverse-CDF sampling of truncated distributions).
    """
    size = plan.chunks[index]
    child = np.random.SeedSequence(plan.seed).spawn(len(plan.chunks))[index]
    rng = np.random.default_rng(child)
    values = {key: _draw(rng, kind, args, size) for key, kind, args in plan.parameters}
    errors = plan.errors if plan.errors is not None else _legacy_errors(case, plan)
    coefficients, extrapolation = draw_thrust(rng, errors, nominal_engines(case.propulsion),
                                              size)
    return ChunkDraw(values, coefficients, extrapolation, size,
                     draw_power_scale(rng, errors, size))


def _joined(draws: Sequence[ChunkDraw]) -> ChunkDraw:
    """Consecutive chunks' draws as one (rows in chunk order)."""
    if len(draws) == 1:
        return draws[0]

    def along_rows(parts: list[Array | None]) -> Array | None:
        return None if parts[0] is None else np.concatenate(parts, axis=-1)

    return ChunkDraw(
        {key: np.concatenate([d.values[key] for d in draws]) for key in draws[0].values},
        # (E, size, 6): the rows are the middle axis
        None if draws[0].coefficients is None
        else np.concatenate([d.coefficients for d in draws], axis=1),  # type: ignore[misc]
        along_rows([d.extrapolation_n for d in draws]),
        sum(d.size for d in draws),
        along_rows([d.power_scale for d in draws]),
    )


def batches(plan: SamplingPlan) -> list[range]:
    """The chunk indices of each batch: :data:`CHUNKS_PER_BATCH` consecutive chunks."""
    n = len(plan.chunks)
    return [range(i, min(i + CHUNKS_PER_BATCH, n)) for i in range(0, n, CHUNKS_PER_BATCH)]


def evaluate_chunk(case: Case, plan: SamplingPlan, index: int) -> dict[str, Array]:
    """Draw and evaluate chunk ``index`` alone (:func:`evaluate_batch` of that chunk)."""
    return evaluate_batch(case, plan, range(index, index + 1))


def evaluate_batch(case: Case, plan: SamplingPlan, chunks: range,
                   two_cores: bool = False) -> dict[str, Array]:
    """Draw ``chunks`` and evaluate them as one batch: per requirement its values (NaN = not
    attainable), in chunk order, and per kind the samples counted as not met.

    A module-level function of picklable arguments, so local processes and Dask workers
    run it as they are. ``two_cores``: half the rows in a helper process where a second
    core is there (:func:`_on_two_cores`; the same numbers).
    """
    from tuflexperf.analysis.batch_readings import combine_rows, readings_evaluator

    draw = _joined([draw_chunk(case, plan, i) for i in chunks])
    # a sample outside its key's range (mass 1e300) counts as not met below; every reading
    # of disputed evidence flown too (the extrapolation band's bound not where it is drawn)
    errors = plan.errors if plan.errors is not None else _legacy_errors(case, plan)
    evaluator = readings_evaluator(case, drawn=plan.extrapolation,
                                   drawn_model_form=errors.model_form_maps is not None)
    if two_cores and draw.size >= SPLIT_ROWS and second_core_idle():
        result, mission = _on_two_cores(evaluator, draw, case)
    else:
        result, mission = _rows_and_mission(evaluator, _draw_rows(draw, slice(None)), case)
    # a sample outside a key's schema bounds (a negative cd0 from a wide normal) is no
    # aircraft: every requirement counts it as not met, and it is reported
    outside = np.zeros(draw.size, dtype=bool)
    out: dict[str, Array] = {}
    for key, values in draw.values.items():
        low, low_in, high, high_in = value_bounds(case, key)
        bad = ~(((values >= low) if low_in else (values > low))
                & ((values <= high) if high_in else (values < high)))
        out[f"outside:{key}"] = np.array([np.count_nonzero(bad)])
        outside |= bad
    # a draw the single case refuses as no aircraft (static thrust beyond 10x its weight, a
    # release or lift-off below its stall, ...): not met, and counted
    absurd = result.refused & ~outside
    out[f"outside:{REFUSED_AIRCRAFT_KEY}"] = np.array([np.count_nonzero(absurd)])
    outside |= absurd
    # bounds that cross (a least airspeed drawn above the greatest) leave no envelope to fly:
    # trim and OEI are not met there (the batch's NaN); the aircraft's other requirements are
    crossed = result.without_envelope & ~outside
    out[f"outside:{ENVELOPE_KEY}"] = np.array([np.count_nonzero(crossed)])
    out.update({f"value:{k}": np.where(outside, np.nan, v) for k, v in result.values.items()})
    out.update({f"limit:{k}": v for k, v in result.limits.items()})
    readings = {key: dict(by_name) for key, by_name in result.reading_values.items()}
    if mission is not None:
        flown, by_key = mission
        theirs = [(r, by_key[r.key]) for r in evaluator.all_readings if r.key in by_key]
        values = {n: v for n, (v, _) in flown.items()}
        limits = {n: lim for n, (_, lim) in flown.items()}
        worse, _, by_reading = combine_rows(values, limits, MISSION_KINDS, theirs)
        for key, by_name in by_reading.items():
            readings.setdefault(key, {}).update(by_name)
        for name, value in worse.items():
            out[f"value:{name}"] = np.where(outside, np.nan, value)
            out[f"limit:{name}"] = limits[name]
    for key, by_name in readings.items():  # each reading's own values ("nominal" first)
        for name, value in by_name.items():
            out[f"reading:{key}:{name}"] = np.where(outside, np.nan, value)
    return out


MissionRows = tuple[dict[str, tuple[Array, Array]], dict[str, dict[str, Array]]]
"""A mission flown for a batch's rows: per requirement its values and limits, and by reading
key each reading's values (:func:`fly_missions`)."""


def fly_missions(case: Case, evaluator: Any, arguments: tuple[Any, ...],
                 rows: dict[Any, Any] | None) -> MissionRows | None:
    """The case's mission flown for the rows ``arguments`` (:func:`_draw_rows`'s) on the
    nominal case and on every reading of ``evaluator`` that bears on it; None where the
    batch flies no mission. ``rows`` the batch's thrust-only results of the same rows
    (:class:`~tuflexperf.analysis.batch_model.SharedRows`), or None."""
    values, size, coefficients, extrapolation_n, power_scale = arguments
    model = mission_for(case, list(values))
    if model is None:
        return None
    from tuflexperf.analysis.mission_rows import Memo
    from tuflexperf.analysis.mission_samples import SAMPLED_STEPS, sampled_landing

    memo = Memo(rows)  # the readings fly the nominal's rows: what they do not change, once

    def fly(mission: Any, on: Case) -> dict[str, tuple[Array, Array]]:
        return sampled_landing(mission, evaluator_for(on), values, size, coefficients,
                               extrapolation_n, SAMPLED_STEPS, memo, power_scale)

    flown = fly(model, case)
    theirs: dict[str, dict[str, Array]] = {}
    for reading in evaluator.all_readings:
        other = (mission_for(reading.case, list(values))
                 if "mission" in reading.affects else None)
        if other is not None:
            theirs[reading.key] = {n: v for n, (v, _) in fly(other, reading.case).items()}
    return flown, theirs


def _joined_missions(parts: list[MissionRows | None]) -> MissionRows | None:
    """Consecutive rows' :func:`fly_missions` as those of one batch."""
    if parts[0] is None:
        return None
    done = [p for p in parts if p is not None]
    flown = {n: (np.concatenate([p[0][n][0] for p in done]),
                 np.concatenate([p[0][n][1] for p in done])) for n in done[0][0]}
    theirs = {k: {n: np.concatenate([p[1][k][n] for p in done]) for n in by_name}
              for k, by_name in done[0][1].items()}
    return flown, theirs


SPLIT_ROWS = 2 * CHUNK_SIZE
"""A batch of this many rows or more runs half its rows in a helper process (in process,
with a second core): the fork's ~20 ms against half of ~30 us a row."""


def second_core_idle() -> bool:
    """True where this process may run on two cores or more and, right now, fewer tasks are
    runnable than there are cores (this process included): on a machine busy with others the
    helper only adds the fork and its rows' fixed costs (~50 ms of CPU) to wait for. The
    runnable count of ``/proc/loadavg``, not the load average: a VM's load average also
    counts tasks asleep in the kernel, and read 2-3 on an idle 2-core machine. Linux only (a
    fork of a process holding CasADi and BLAS is not safe on macOS; Windows has none)."""
    import os

    if not sys.platform.startswith("linux"):
        return False
    usable = len(os.sched_getaffinity(0))
    if usable < 2:
        return False
    try:
        with open("/proc/loadavg") as status:
            runnable = int(status.read().split()[3].split("/")[0])
    except (OSError, ValueError, IndexError):
        return os.getloadavg()[0] < usable - 0.5
    return runnable < usable


def _draw_rows(draw: ChunkDraw, rows: slice) -> tuple[Any, ...]:
    """:meth:`ReadingsEvaluator.evaluate`'s arguments for ``rows`` of ``draw``."""
    def part(array: Array | None, axis: int = 0) -> Array | None:
        if array is None:
            return None
        return np.ascontiguousarray(array[(slice(None),) * axis + (rows,)])

    size = len(range(draw.size)[rows])
    return ({key: part(v) for key, v in draw.values.items()}, size,
            part(draw.coefficients, 1), part(draw.extrapolation_n, 1), part(draw.power_scale))


def _on_two_cores(evaluator: Any, draw: ChunkDraw, case: Case | None = None
                  ) -> tuple[Any, MissionRows | None]:
    """``evaluator.evaluate`` of ``draw``'s rows and ``case``'s mission flown for them
    (:func:`fly_missions`; None without a case), the second half of the rows in a forked
    helper process while this one does the first; the readings are judged over all rows
    at once.

    A row's results are its own whatever rows share its batch (each solver stops a row at
    its own convergence), so the numbers are those of one batch. A helper that cannot be
    forked, or that dies, leaves its half to be done here; an error in it is raised here.
    """
    import multiprocessing

    from tuflexperf.analysis.batch_readings import joined_rows
    from tuflexperf.io.files import raise_if_interrupted, start_helper, stop_helpers

    if "fork" not in multiprocessing.get_all_start_methods():  # it would pickle the models
        return _rows_and_mission(evaluator, _draw_rows(draw, slice(None)), case)
    half = draw.size // 2
    first, second = _draw_rows(draw, slice(0, half)), _draw_rows(draw, slice(half, None))
    reader, writer = multiprocessing.Pipe(duplex=False)
    helpers: list[Any] = []
    finished = False
    try:
        try:
            start_helper(_rows_beside, (evaluator, second, writer, case), helpers)
        except OSError:  # no process to be had: its half here (EOF below)
            pass
        writer.close()  # the helper's end: the pipe ends here when the helper does
        mine = _rows_and_mission(evaluator, first, case, combine=False)
        try:
            theirs: Any = reader.recv()
        except EOFError:  # no helper, or it died (killed from outside): its half here
            raise_if_interrupted()
            theirs = _rows_and_mission(evaluator, second, case, combine=False)
        if isinstance(theirs, BaseException):
            raise theirs
        finished = True
    finally:
        if not finished:
            stop_helpers(helpers)
        writer.close()
        reader.close()
        for helper in helpers:
            helper.join()
    return (evaluator.combined(*joined_rows([mine[0], theirs[0]])),
            _joined_missions([mine[1], theirs[1]]))


def _rows_and_mission(evaluator: Any, arguments: tuple[Any, ...], case: Case | None,
                      combine: bool = True) -> tuple[Any, MissionRows | None]:
    """The rows ``arguments`` (:func:`_draw_rows`'s): their ``readings_rows`` (judged on the
    readings where ``combine``) and ``case``'s mission flown for them, sharing their
    thrust-only results."""
    rows: dict[Any, Any] = {}
    result = evaluator.readings_rows(*arguments, rows)
    mission = None if case is None else fly_missions(case, evaluator, arguments, rows)
    return (evaluator.combined(*result) if combine else result), mission


def _rows_beside(evaluator: Any, arguments: tuple[Any, ...], writer: Any,
                 case: Case | None = None) -> None:
    """The helper of :func:`_on_two_cores`: its rows' readings_rows and mission (or the
    error they raised) sent on ``writer``."""
    try:
        outcome: Any = _rows_and_mission(evaluator, arguments, case, combine=False)
    except Exception as exc:  # raised again in the parent, as if the rows ran there
        outcome = exc
    try:
        writer.send(outcome)
    except OSError:  # the parent is gone: nobody to tell
        return
    writer.close()


MISSION_KINDS = {"mission_landing_charge": "min", "mission_solved_time": "min"}
_missions: dict[str, Any] = {}


def mission_for(case: Case, keys: list[str]) -> Any:
    """The case's mission model when the batch flies it for draws of ``keys``
    (:func:`tuflexperf.analysis.mission_samples.why_not_sampled`), else None; one per case
    and process, as :func:`evaluator_for`."""
    if case.requirements.mission is None:
        return None
    from tuflexperf.analysis.mission import mission_model
    from tuflexperf.analysis.mission_samples import why_not_sampled
    from tuflexperf.errors import NotAttainable
    from tuflexperf.io.mission import load_mission, mission_path

    path = mission_path(case)
    key = fingerprint(case.aircraft, case.propulsion, case.atmosphere, case.requirements,
                      case.overrides, str(case.battery_path), str(path), file_key(path))
    if key not in _missions:
        if len(_missions) >= EVALUATORS_KEPT:  # one case and its readings at a time
            _missions.clear()
        try:
            _missions[key] = mission_model(
                case, load_mission(path), case.requirements.mission.min_landing_charge_fraction)
        except NotAttainable:  # the nominal plan cannot be flown: said by the nominal verdict
            _missions[key] = None
    model = _missions[key]
    return None if model is None or why_not_sampled(model, keys) is not None else model


DASK_CONNECT_S = 10.0  # connect and handshake: a server that never answers hung for ever
DASK_WORKER_WAIT_S = 30.0  # a scheduler without workers: said, not waited on for ever


def dask_client(address: str) -> Any:
    """A ``distributed.Client`` on the scheduler at ``address`` (``tcp://HOST:PORT``) with at
    least one worker; :class:`InputError` naming ``--dask`` otherwise.

    distributed's own timeout covers the TCP connect only: a server that accepts and never
    answers (an HTTP server) hung for ever, one that speaks first (an SSH banner) raised
    "cannot allocate 2.82 EiB", a tls:// or ucx:// address a TypeError, and a scheduler
    with no worker took the chunks and waited for ever, all unsaid (outside audit).
    """
    import threading

    try:
        from distributed import Client
    except ImportError:
        raise InputError(
            "--dask: dask.distributed is not installed (pip install 'tuflexperf[dask]')"
        ) from None
    scheme = address.split("://", 1)[0].lower() if "://" in address else "tcp"
    if scheme != "tcp":
        raise InputError(f"--dask: {address!r}: only tcp://HOST:PORT scheduler addresses are "
                         f"supported, not {scheme}://")
    outcome: dict[str, Any] = {}

    def connect() -> None:
        try:
            outcome["client"] = Client(address, timeout="5s")
        except Exception as exc:  # whatever a server that is not a scheduler makes it raise
            outcome["error"] = exc

    thread = threading.Thread(target=connect, name="dask-connect", daemon=True)
    thread.start()
    thread.join(DASK_CONNECT_S)
    if thread.is_alive():  # left behind: a daemon thread, ended with the process
        raise InputError(f"--dask: no Dask scheduler answered at {address} within "
                         f"{DASK_CONNECT_S:g} s (is a scheduler listening there?)")
    error = outcome.get("error")
    if isinstance(error, ValueError):  # distributed's own word on a malformed address
        raise InputError(f"--dask: {address!r} is not a scheduler address (expected "
                         f"tcp://HOST:PORT): {_first_line(error)}")
    if error is not None:
        raise InputError(f"--dask: no Dask scheduler at {address}: {type(error).__name__}: "
                         f"{_first_line(error)}")
    client = outcome["client"]
    try:
        client.wait_for_workers(1, timeout=DASK_WORKER_WAIT_S)
    except Exception:  # distributed's TimeoutError (or the scheduler gone meanwhile)
        client.close()
        raise InputError(f"--dask: the scheduler at {address} has no worker (none joined "
                         f"within {DASK_WORKER_WAIT_S:g} s): start one with "
                         f"`dask worker {address}`") from None
    return client


def _first_line(error: BaseException) -> str:
    """An exception's first line (the CLI shortens a long one, as every message)."""
    text = str(error).strip().splitlines()
    return text[0] if text else ""


def run_chunks(
    function: Callable[..., dict[str, Array]],
    arguments: Sequence[tuple[Any, ...]],
    workers: int | None = None,
    dask_address: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[dict[str, Array]]:
    """``function(*a)`` for each argument tuple, in order: here, in processes, or on Dask;
    ``progress(done, total)`` after each (on Dask once, at the end)."""
    def done(count: int) -> None:
        if progress is not None:
            progress(count, len(arguments))

    done(0)
    if dask_address:
        client = dask_client(dask_address)
        try:
            futures = [client.submit(function, *a, pure=False) for a in arguments]
            results = list(client.gather(futures))
            done(len(arguments))
            return results
        finally:
            client.close()
    if workers is not None and workers > 1 and len(arguments) > 1:
        return _in_processes(function, arguments, workers, done)
    here = []
    for a in arguments:
        here.append(function(*a))
        done(len(here))
    return here


def _in_processes(
    function: Callable[..., dict[str, Array]], arguments: Sequence[tuple[Any, ...]], workers: int,
    done: Callable[[int], None] | None = None,
) -> list[dict[str, Array]]:
    """``function(*a)`` for each argument tuple in ``workers`` local processes, in order.

    Each worker takes every ``workers``-th batch and sends each result on its own pipe.
    Ctrl-C or SIGTERM ends the workers at once (the default action: none prints a
    traceback; any still running when the interrupt is raised here are killed) and is
    raised here, where the command reports it (exit 130); one that lands while a worker
    is forked is held until the fork is done, never dropped. A
    worker that dies shows as the end of its pipe, so nothing waits on it for ever (a
    process pool's shared result pipe did: a worker killed while it wrote left half a
    message that its reader waited on at exit). An error in a chunk is raised here.
    """
    import multiprocessing
    from multiprocessing.connection import wait

    from tuflexperf.io.files import raise_if_interrupted, start_helper, stop_helpers

    count = min(workers, len(arguments))
    results: list[Any] = [None] * len(arguments)
    helpers: list[Any] = []
    owed: dict[Any, int] = {}  # each worker's pipe: the results still to come on it
    finished = False
    try:
        for k in range(count):
            reader, writer = multiprocessing.Pipe(duplex=False)
            indices = range(k, len(arguments), count)
            start_helper(_worker, (function, arguments, indices, writer), helpers)
            writer.close()  # the worker's end: the pipe ends here when the worker does
            owed[reader] = len(indices)
        while owed:
            for reader in wait(list(owed)):
                try:
                    index, outcome = reader.recv()
                except EOFError:
                    raise_if_interrupted()  # the workers ended by the interrupt: that is news
                    raise InputError("--workers: a worker process ended without its results "
                                     "(killed from outside?); run again, or without --workers"
                                     ) from None
                if isinstance(outcome, BaseException):
                    raise outcome
                results[index] = outcome
                if done is not None:
                    done(sum(r is not None for r in results))
                owed[reader] -= 1
                if not owed[reader]:
                    del owed[reader]
                    reader.close()
        finished = True
        return results
    finally:
        if not finished:
            stop_helpers(helpers)
        for reader in owed:
            reader.close()
        for helper in helpers:
            helper.join()


def _worker(function: Callable[..., dict[str, Array]], arguments: Sequence[tuple[Any, ...]],
            indices: range, writer: Any) -> None:
    """One worker of :func:`_in_processes`: its batches in order, each result (or the error
    it raised) sent as ``(index, outcome)``."""
    for index in indices:
        try:
            outcome: Any = function(*arguments[index])
        except Exception as exc:  # raised again in the parent, as if the chunk ran there
            outcome = exc
        try:
            writer.send((index, outcome))
        except OSError:  # the parent is gone (killed): nobody to tell
            return
    writer.close()


@dataclass(frozen=True)
class SampleSet:
    """Every sample's value per requirement (NaN = not attainable) and the plan."""

    plan: SamplingPlan
    values: dict[str, Array]
    limits: dict[str, Array]
    kinds: dict[str, str] = field(default_factory=dict)
    # per parameter: samples outside its schema bounds (counted as not met everywhere)
    outside_bounds: dict[str, int] = field(default_factory=dict)
    # where readings of disputed evidence bear on a requirement: ``values`` are the worse
    # reading's, these each reading's (key -> requirement -> values; "nominal" first)
    reading_values: dict[str, dict[str, Array]] = field(default_factory=dict)
    # reading key -> (what it flies, what the nominal case flies in its place)
    reading_labels: dict[str, tuple[str, str]] = field(default_factory=dict)


def run_samples(
    case: Case,
    plan: SamplingPlan,
    workers: int | None = None,
    dask_address: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SampleSet:
    """All chunks of ``plan`` for ``case``; the same numbers wherever the chunks run.

    References
    ----------
    Hanson & Beard (2010), NASA/TP-2010-216447 (Monte Carlo requirement verification).
    """
    # in process (no --workers, no Dask): a batch's rows on two cores where one is idle
    here = not dask_address and workers is None
    with earlier_objects_frozen(), freed_arrays_kept(), one_blas_thread():
        parts = run_chunks(
            evaluate_batch,
            [(case, plan, chunks, here) for chunks in batches(plan)],
            workers,
            dask_address,
            progress,
        )
    names = [k.split(":", 1)[1] for k in parts[0] if k.startswith("value:")]
    values = {n: np.concatenate([p[f"value:{n}"] for p in parts]) for n in names}
    limits = {n: np.concatenate([p[f"limit:{n}"] for p in parts]) for n in names}
    kinds = {r.name: r.kind for r in evaluator_for(case).requirements}
    kinds.update(MISSION_KINDS)
    outside = {k.split(":", 1)[1]: int(sum(int(p[k][0]) for p in parts))
               for k in parts[0] if k.startswith("outside:")}
    readings: dict[str, dict[str, Array]] = {}
    for k in parts[0]:
        if k.startswith("reading:"):
            _, key, name = k.split(":", 2)
            readings.setdefault(key, {})[name] = np.concatenate([p[k] for p in parts])
    from tuflexperf.analysis.batch_readings import reading_labels

    return SampleSet(plan, values, limits, kinds, outside, readings,
                     reading_labels(case) if readings else {})


def as_batch(samples: SampleSet) -> BatchResult:
    """The samples as a :class:`BatchResult` (to use its verdict rule)."""
    return BatchResult(samples.values, samples.limits, samples.kinds)


def quantiles(values: Array, kind: str) -> list[float | None]:
    """5/50/95 % values [the requirement's unit]; a not-attainable sample counts as the worst
    value (None where a percentile falls on one).

    References
    ----------
    Hyndman & Fan (1996), "Sample quantiles in statistical packages", Am. Stat. 50 (type 1,
    inverted empirical CDF: every reported value is a sample's).
    """
    worst = math.inf if kind == "max" else -math.inf
    filled = np.where(np.isfinite(values), values, worst)
    q = np.quantile(filled, [0.05, 0.5, 0.95], method="inverted_cdf")
    return [float(x) if math.isfinite(x) else None for x in q]

