"""Every requirement over a grid of parameter values (``tuflexperf sweep --vary ...``).

The grid is the Cartesian product of the ``--vary KEY=START:STOP:N`` axes (first axis
slowest); all points are evaluated as batches by
:class:`tuflexperf.analysis.batch.BatchEvaluator`, in chunks that may run in local
processes or on a Dask cluster (the same numbers wherever they run: no randomness).

References
----------
Raymer, *Aircraft Design*, 19.5 (carpet plots for design trades).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.verdict import requirement_met
from tuflexperf.errors import InputError
from tuflexperf.io.case import Case
from tuflexperf.io.dotted import check_value
from tuflexperf.io.yamlio import ambiguous_number

Array = NDArray[np.float64]
CHUNK_ROWS = 2500
MAX_POINTS = 1_000_000


def parse_vary(case: Case, spec: str) -> tuple[str, Array]:
    """``KEY=START:STOP:N`` -> (key, N values from START to STOP); bad input names the flag."""
    if "=" not in spec:
        raise InputError(f"--vary {spec!r}: expected KEY=START:STOP:N")
    key, _, grid = spec.partition("=")
    key = key.strip()
    parts = grid.split(":")
    for part in parts[:2]:  # as in the files and --set: 020 is no plain decimal
        odd = ambiguous_number(part)
        if odd is not None:
            raise InputError(f"--vary {spec!r}: {odd.problem()}")
    try:
        if len(parts) != 3:
            raise ValueError
        start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise InputError(f"--vary {spec!r}: expected KEY=START:STOP:N (N a whole number)") \
            from None
    if count < 1 or not (np.isfinite(start) and np.isfinite(stop)):
        raise InputError(f"--vary {spec!r}: need finite START, STOP and N >= 1")
    if count > MAX_POINTS:  # before the grid is made (1e23 points was a numpy traceback)
        raise InputError(f"--vary {spec!r}: {count} grid points; at most {MAX_POINTS}")
    if count == 1 and start != stop:
        # one point is START alone: STOP was never flown, and its FAIL never said (outside
        # audit: 18:30:1 PASSed at 18 kg where 30 kg fails trim)
        raise InputError(f"--vary {spec!r}: N = 1 flies START alone; give START = STOP for one "
                         "point, or N >= 2 to reach STOP")
    for value in (start, stop):  # the key's own bounds, as in the files (a negative mass)
        check_value(case, key, value, "--vary")
    return key, np.linspace(start, stop, count)


@dataclass(frozen=True)
class SweepResult:
    """Grid points ``(rows, P)``, and per requirement its values, limits and met flags."""

    parameters: tuple[str, ...]
    axes: tuple[Array, ...]
    points: Array
    values: dict[str, Array]
    limits: dict[str, Array]
    met: dict[str, NDArray[np.bool_]]
    units: dict[str, str]
    # rows whose answer flies the thrust model beyond its tested airspeeds (BatchResult's)
    extrapolated: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    # rows met on one reading of disputed evidence but not on another (analysis.batch_readings)
    disputed: dict[str, NDArray[np.bool_]] = field(default_factory=dict)

    def verdicts(self, name: str) -> NDArray[np.str_]:
        """PASS, FAIL or UNPROVEN per grid point, as ``check`` judges each point: met on
        every reading PASS, on some UNPROVEN, on none FAIL."""
        disputed = self.disputed.get(name, np.zeros(self.met[name].shape, dtype=bool))
        return np.where(self.met[name], "PASS", np.where(disputed, "UNPROVEN", "FAIL"))

    def extrapolation_notes(self, tested_m_s: tuple[float, float]) -> list[str]:
        """One line per requirement that extrapolates the thrust model at some grid point."""
        notes = []
        rows = self.points.shape[0]
        for name, beyond in self.extrapolated.items():
            count = int(np.count_nonzero(beyond))
            if count:
                where = "every grid point" if count == rows else f"{count} of {rows} grid points"
                notes.append(f"{name}: thrust model extrapolated beyond its tested "
                             f"{tested_m_s[0]:g}-{tested_m_s[1]:g} m/s at {where}")
        return notes

    def to_dict(self) -> dict[str, Any]:
        rows = []
        verdicts = {name: self.verdicts(name) for name in self.values}
        for i in range(self.points.shape[0]):
            row: dict[str, Any] = {k: float(self.points[i, j])
                                   for j, k in enumerate(self.parameters)}
            for name in self.values:
                value = float(self.values[name][i])
                row[name] = {"value": value if np.isfinite(value) else None,
                             "limit": float(self.limits[name][i]),
                             "verdict": str(verdicts[name][i]),
                             "passed": bool(self.met[name][i])}
                if name in self.extrapolated:
                    row[name]["extrapolated"] = bool(self.extrapolated[name][i])
            rows.append(row)
        return {"parameters": list(self.parameters), "units": self.units, "rows": rows}

    def to_csv(self) -> str:
        header = list(self.parameters)
        for name in self.values:
            header += [f"{name}_value", f"{name}_limit", f"{name}_passed", f"{name}_verdict"]
        lines = [",".join(header)]
        verdicts = {name: self.verdicts(name) for name in self.values}
        for i in range(self.points.shape[0]):
            cells = [repr(float(v)) for v in self.points[i]]
            for name in self.values:
                value = float(self.values[name][i])
                cells += ["" if not np.isfinite(value) else repr(value),
                          repr(float(self.limits[name][i])),
                          "true" if self.met[name][i] else "false", str(verdicts[name][i])]
            lines.append(",".join(cells))
        return "\n".join(lines) + "\n"


def evaluate_rows(case: Case, keys: tuple[str, ...], points: Array) -> dict[str, Array]:
    """One chunk of grid points as one batch (module level: picklable for processes/Dask),
    on every reading of the case's disputed evidence too (the worse reading's values)."""
    from tuflexperf.analysis.batch_readings import readings_evaluator

    result = readings_evaluator(case).evaluate({k: points[:, j] for j, k in enumerate(keys)},
                                               size=points.shape[0])
    out: dict[str, Array] = {}
    for name, values in result.values.items():
        out[f"value:{name}"] = values
        out[f"limit:{name}"] = result.limits[name]
        out[f"met:{name}"] = requirement_met(values, result.limits[name], result.kinds[name])
        out[f"extrapolated:{name}"] = result.extrapolated[name]
        out[f"disputed:{name}"] = result.disputed.get(name, np.zeros(values.shape, dtype=bool))
    return out


def _refuse_what_check_refuses(case: Case, keys: tuple[str, ...], points: Array) -> None:
    """A point the single case refuses is bad input: an aircraft whose static thrust is
    absurd for its weight, or envelope bounds that cross (or pass the speed of sound). The
    message names the point and the single case's fault."""
    from tuflexperf.analysis.evaluators import evaluator_for
    from tuflexperf.analysis.trim import envelope_of
    from tuflexperf.io.dotted import with_values

    values = {k: points[:, j] for j, k in enumerate(keys)}
    evaluator = evaluator_for(case)
    refused = (evaluator.rows_refused(values, len(points))
               | evaluator.rows_without_envelope(values, len(points)))
    if not refused.any():
        return
    point = {k: float(v[np.argmax(refused)]) for k, v in values.items()}
    where = ", ".join(f"{k}={v:g}" for k, v in point.items())
    single = with_values(case, point, "--vary")  # thrust, bounds out of order: its message
    try:
        envelope_of(single)
    except InputError as exc:
        raise InputError(f"--vary: at {where}: {str(exc).removeprefix(f'{single.path}: ')}") \
            from None
    raise InputError(f"--vary: at {where}: the envelope has no airspeeds")  # pragma: no cover


def run_sweep(case: Case, axes: list[tuple[str, Array]], workers: int | None = None,
              dask_address: str | None = None,
              progress: Callable[[int, int], None] | None = None) -> SweepResult:
    """Every requirement at every grid point (first axis slowest), as batches.

    References
    ----------
    Raymer, *Aircraft Design*, 19.5 (carpet plots for design trades).
    """
    from tuflexperf.analysis.batch import present_requirements
    from tuflexperf.analysis.uncertainty import run_chunks

    keys = tuple(k for k, _ in axes)
    if len(set(keys)) != len(keys):
        raise InputError(f"--vary: a key is given twice ({', '.join(keys)})")
    count = math.prod(a.size for _, a in axes)  # Python's integers: numpy's int64 wraps
    if count > MAX_POINTS:
        raise InputError(f"--vary: {count} grid points; at most {MAX_POINTS}")
    if not present_requirements(case):
        raise InputError(f"{case.path}: requirements: the case states none; nothing to sweep")
    points = np.array(list(itertools.product(*[a for _, a in axes])), dtype=float)
    _refuse_what_check_refuses(case, keys, points)
    chunks = [points[i:i + CHUNK_ROWS] for i in range(0, count, CHUNK_ROWS)]
    parts = run_chunks(evaluate_rows, [(case, keys, c) for c in chunks], workers, dask_address,
                       progress)
    names = [k.split(":", 1)[1] for k in parts[0] if k.startswith("value:")]

    def join(prefix: str, name: str) -> Any:
        return np.concatenate([p[f"{prefix}:{name}"] for p in parts])

    return SweepResult(
        parameters=keys,
        axes=tuple(a for _, a in axes),
        points=points,
        values={n: join("value", n) for n in names},
        limits={n: join("limit", n) for n in names},
        met={n: join("met", n) for n in names},
        units={r.name: r.unit for r in present_requirements(case)},
        extrapolated={n: join("extrapolated", n) for n in names},
        disputed={n: join("disputed", n) for n in names},
    )
