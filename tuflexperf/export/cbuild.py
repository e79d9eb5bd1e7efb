"""Compile the exported C and call it from Python (ctypes): for verification and benchmarks.

Flight software does not need this module; it compiles ``tfp_thrust.c`` with its own build.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

from tuflexperf.export.c_code import DELAY_CAPACITY

#: Stricter than the contract's ``-std=c99 -Wall -Werror``: the generated code must pass these.
STRICT_CFLAGS: tuple[str, ...] = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2")


def find_compiler() -> str | None:
    """Path of the C compiler (``$CC``, else ``gcc``, else ``cc``), or None when there is none."""
    for name in (os.environ.get("CC", ""), "gcc", "cc"):
        found = shutil.which(name) if name else None
        if found:
            return found
    return None


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
    done = subprocess.run(command, capture_output=True, text=True, check=False)
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
        lib.tfp_throttle_for_thrust.argtypes = [d, d, d, p]
        lib.tfp_throttle_for_thrust.restype = ctypes.c_int
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
        out = ctypes.c_double(float("nan"))
        code = self.lib.tfp_throttle_for_thrust(
            float(total_thrust_n), float(airspeed_m_s), float(density_kg_m3), ctypes.byref(out)
        )
        return code, out.value

    def is_extrapolated(self, airspeed_m_s: float) -> bool:
        """``tfp_is_extrapolated``."""
        return bool(self.lib.tfp_is_extrapolated(float(airspeed_m_s)))

    def new_delay(self, sample_time_s: float, initial_throttle: float = 0.0) -> tuple[int, CDelay]:
        """``tfp_delay_init`` on a fresh buffer: (return code, buffer)."""
        buffer = CDelay()
        code = self.lib.tfp_delay_init(ctypes.byref(buffer), sample_time_s, initial_throttle)
        return code, buffer
