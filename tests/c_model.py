"""The exported C compiled and called from Python (ctypes), for the tests that hold it to the
Python model. Flight software compiles ``tfp_thrust.c`` with its own build."""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tuflexperf.export.c_code import DELAY_CAPACITY
from tuflexperf.export.cbuild import find_compiler, run_compiler
from tuflexperf.export.model import quadratic_coefficients
from tuflexperf.io import swap
from tuflexperf.models.thrust import Propulsion, density_ratio, least_throttle_reaching

#: Stricter than the contract's ``-std=c99 -Wall -Werror``: the generated code must pass these.
STRICT_CFLAGS: tuple[str, ...] = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2")


def compile_shared(
    sources: Sequence[Path | str], library: Path | str, cflags: Sequence[str] = STRICT_CFLAGS
) -> Path:
    """Compile C sources into a shared library (``-shared -fPIC ... -lm``).

    Raises RuntimeError with the compiler's output when it fails (a warning fails: ``-Werror``).
    """
    compiler = find_compiler()
    if compiler is None:
        raise RuntimeError("no C compiler found (set CC or install gcc)")
    library = Path(library)
    command = [compiler, *cflags, "-shared", "-fPIC", "-o", str(library)]
    command += [str(s) for s in sources] + ["-lm"]
    with swap.scratch("export") as scratch:
        done = run_compiler(command, scratch)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{done.stdout}{done.stderr}")
    return library


class CDelay(ctypes.Structure):
    """ctypes mirror of ``tfp_delay_t`` at the default capacity."""

    _fields_ = [
        ("samples", ctypes.c_double * DELAY_CAPACITY),
        ("length", ctypes.c_int),
        ("head", ctypes.c_int),
    ]


class CThrustModel:
    """The exported C model loaded with ctypes; methods mirror the C API (SI units)."""

    def __init__(self, library: Path | str, n_engines: int) -> None:
        self.n_engines = n_engines
        self.lib = ctypes.CDLL(str(Path(library).resolve()))
        d, p = ctypes.c_double, ctypes.POINTER(ctypes.c_double)
        lib = self.lib
        lib.tfp_thrust.argtypes = [d] * n_engines + [d, d] + [p] * n_engines
        lib.tfp_thrust.restype = ctypes.c_int
        lib.tfp_thrust_v.argtypes = [p, d, d, p]
        lib.tfp_thrust_v.restype = ctypes.c_int
        lib.tfp_total_thrust.argtypes = [d, d, d]
        lib.tfp_total_thrust.restype = d
        ip = ctypes.POINTER(ctypes.c_int)
        lib.tfp_throttle_for_thrust.argtypes = [d, d, d, p, ip]
        lib.tfp_throttle_for_thrust.restype = ctypes.c_int
        lib.tfp_engine_throttle_for_thrust.argtypes = [ctypes.c_int, d, d, d, p, ip]
        lib.tfp_engine_throttle_for_thrust.restype = ctypes.c_int
        lib.tfp_is_extrapolated.argtypes = [d]
        lib.tfp_is_extrapolated.restype = ctypes.c_int
        delay_p = ctypes.POINTER(CDelay)
        lib.tfp_delay_init.argtypes = [delay_p, d, d]
        lib.tfp_delay_init.restype = ctypes.c_int
        lib.tfp_delay_step.argtypes = [delay_p, d]
        lib.tfp_delay_step.restype = d
        lib.tfp_delay_push.argtypes = [delay_p, d]
        lib.tfp_delay_push.restype = None
        lib.tfp_delay_get.argtypes = [delay_p]
        lib.tfp_delay_get.restype = d
        lib.tfp_delay_samples.argtypes = [delay_p]
        lib.tfp_delay_samples.restype = ctypes.c_int
        lib.tfp_state_init.argtypes = [ctypes.c_void_p, d, p, d, d]
        lib.tfp_state_init.restype = ctypes.c_int
        lib.tfp_step.argtypes = [ctypes.c_void_p, p, d, d, p]
        lib.tfp_step.restype = ctypes.c_int

    def thrust(
        self, throttles: Sequence[float], airspeed_m_s: float, density_kg_m3: float
    ) -> tuple[int, list[float]]:
        """``tfp_thrust``: (return code, thrust per engine in N)."""
        outputs = [ctypes.c_double() for _ in range(self.n_engines)]
        code = self.lib.tfp_thrust(
            *[float(x) for x in throttles],
            float(airspeed_m_s),
            float(density_kg_m3),
            *[ctypes.byref(o) for o in outputs],
        )
        return code, [o.value for o in outputs]

    def thrust_v(
        self, throttles: Sequence[float], airspeed_m_s: float, density_kg_m3: float
    ) -> tuple[int, list[float]]:
        """``tfp_thrust_v``: (return code, thrust per engine in N)."""
        array = ctypes.c_double * self.n_engines
        out = array()
        code = self.lib.tfp_thrust_v(
            array(*throttles), float(airspeed_m_s), float(density_kg_m3), out
        )
        return code, list(out)

    def total_thrust(self, throttle: float, airspeed_m_s: float, density_kg_m3: float) -> float:
        """``tfp_total_thrust`` in N at a common throttle fraction."""
        return self.lib.tfp_total_thrust(throttle, airspeed_m_s, density_kg_m3)

    def throttle_for_thrust(
        self, total_thrust_n: float, airspeed_m_s: float, density_kg_m3: float
    ) -> tuple[int, float]:
        """``tfp_throttle_for_thrust``: (return code, throttle fraction)."""
        code, throttle, _ = self.throttle_for_thrust_flagged(
            total_thrust_n, airspeed_m_s, density_kg_m3
        )
        return code, throttle

    def _inverse(self, function: Any, *leading: Any) -> tuple[int, float, bool]:
        """An inverse of the C API: (return code, throttle fraction, extrapolated)."""
        out = ctypes.c_double(float("nan"))
        flag = ctypes.c_int(-1)
        code = function(*leading, ctypes.byref(out), ctypes.byref(flag))
        return code, out.value, bool(flag.value)

    def throttle_for_thrust_flagged(
        self, total_thrust_n: float, airspeed_m_s: float, density_kg_m3: float
    ) -> tuple[int, float, bool]:
        """``tfp_throttle_for_thrust``: (return code, throttle fraction, extrapolated)."""
        return self._inverse(self.lib.tfp_throttle_for_thrust, float(total_thrust_n),
                             float(airspeed_m_s), float(density_kg_m3))

    def engine_throttle_for_thrust(
        self, engine: int, thrust_n: float, airspeed_m_s: float, density_kg_m3: float
    ) -> tuple[int, float, bool]:
        """``tfp_engine_throttle_for_thrust``: (return code, throttle, extrapolated)."""
        return self._inverse(self.lib.tfp_engine_throttle_for_thrust, int(engine),
                             float(thrust_n), float(airspeed_m_s), float(density_kg_m3))

    def simulate(
        self,
        sample_time_s: float,
        commands: Sequence[Sequence[float]],
        airspeed_m_s: float,
        density_kg_m3: float,
        initial_throttle: Sequence[float] | None = None,
    ) -> tuple[int, list[list[float]]]:
        """``tfp_state_init`` then ``tfp_step`` per row of ``commands`` (one throttle per
        engine): (first non-OK code or 0, thrust per engine per step in N)."""
        size = ctypes.sizeof(CDelay) + 2 * ctypes.sizeof(ctypes.c_double)
        state = ctypes.create_string_buffer(size * self.n_engines + 64)
        array = ctypes.c_double * self.n_engines
        initial = array(*initial_throttle) if initial_throttle is not None else None
        code = self.lib.tfp_state_init(
            state, float(sample_time_s), initial, float(airspeed_m_s), float(density_kg_m3)
        )
        out: list[list[float]] = []
        if code != 0:
            return code, out
        thrust = array()
        for row in commands:
            code = self.lib.tfp_step(
                state, array(*row), float(airspeed_m_s), float(density_kg_m3), thrust
            )
            if code != 0:
                return code, out
            out.append(list(thrust))
        return 0, out

    def is_extrapolated(self, airspeed_m_s: float) -> bool:
        """``tfp_is_extrapolated``."""
        return bool(self.lib.tfp_is_extrapolated(float(airspeed_m_s)))

    def new_delay(self, sample_time_s: float, initial_throttle: float = 0.0) -> tuple[int, CDelay]:
        """``tfp_delay_init`` on a fresh buffer: (return code, buffer)."""
        buffer = CDelay()
        code = self.lib.tfp_delay_init(ctypes.byref(buffer), sample_time_s, initial_throttle)
        return code, buffer


def throttle_for_thrust(
    propulsion: Propulsion, total_thrust_n_: Any, airspeed_m_s: Any, density_kg_m3: Any
) -> tuple[Any, Any]:
    """Least common throttle fraction whose total thrust reaches ``total_thrust_n_`` (numpy).

    Returns ``(throttle, reached)``; see :func:`least_throttle_reaching`. Vectorised reference
    for the exported C and CasADi inverses (same coefficients, same steps).
    """
    q = quadratic_coefficients(propulsion)
    v = np.asarray(airspeed_m_s, dtype=float)
    s = np.asarray(density_ratio(propulsion, np.asarray(density_kg_m3, dtype=float)), dtype=float)
    a = s * q["qa"]
    b = s * (q["qb0"] + q["qb1"] * v)
    c = s * (q["qc0"] + q["qc1"] * v + q["qc2"] * v * v) - np.asarray(total_thrust_n_, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        throttle, reached = least_throttle_reaching(a, b, c)
    return np.asarray(throttle, dtype=float), np.asarray(reached, dtype=bool)
