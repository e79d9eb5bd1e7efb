"""The process's settings while a batch of samples runs: memory kept, one BLAS thread, the
objects already made left out of the garbage collector's scans.

None changes a number: each only takes the operating system's, the thread pool's or the
collector's costs out of the batch's thousands of short array operations on a few MB each
(measured on ``check --samples 10000``, whole process, this 2-core machine;
``bench/bench_uncertainty.py``). Each is undone afterwards, and does nothing where its
library is not there (not glibc; numpy without OpenBLAS).
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from typing import Any

# glibc's mallopt parameters (malloc.h), what the batch sets them to and glibc's defaults
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
_KEPT = {_M_MMAP_THRESHOLD: 32 << 20, _M_TRIM_THRESHOLD: 1 << 30, _M_TOP_PAD: 64 << 20}
_DEFAULTS = {_M_MMAP_THRESHOLD: 128 << 10, _M_TRIM_THRESHOLD: 128 << 10, _M_TOP_PAD: 128 << 10}
# numpy's OpenBLAS (its wheels' own build, then a system one): thread count setter, getter
_OPENBLAS = (("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
             ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
             ("openblas_set_num_threads", "openblas_get_num_threads"))


@contextlib.contextmanager
def freed_arrays_kept() -> Iterator[None]:
    """Within: the process keeps the memory of freed arrays (up to 32 MB each) for the next
    ones, instead of handing it back to the system and faulting it in again page by page.

    A batch of 10,000 rows makes and drops thousands of arrays of a few MB; glibc maps each
    in fresh pages (or trims its heap), and those page faults were ~20 % of ``check
    --samples 10000`` (whole process 0.68 -> 0.54 s). Afterwards glibc's default values are
    set again (its sliding mmap threshold stays off): the kept memory serves the process's
    next arrays, and glibc trims its heap's top as it frees (``malloc_trim`` of all of it
    took 4 ms of a 0.2 s batch).
    """
    libc = _glibc()
    if libc is None:
        yield
        return
    for option, value in _KEPT.items():
        libc.mallopt(option, value)
    try:
        yield
    finally:
        for option, value in _DEFAULTS.items():
            libc.mallopt(option, value)


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Within: numpy's OpenBLAS runs on one thread.

    The batch's matrix products are ``(B, 6) @ (6, K)`` (sampled thrust coefficients
    against the airspeed grid): a few per batch, where waking OpenBLAS's threads on a
    shared 2-core machine took 6-28 ms a product against ~1 ms on one thread. They split
    no sum (the inner dimension is 6), so the numbers are the same.
    """
    library = _openblas()
    if library is None:
        yield
        return
    setter, getter = library
    before = int(getter())
    setter(1)
    try:
        yield
    finally:
        setter(before)


@contextlib.contextmanager
def earlier_objects_frozen() -> Iterator[None]:
    """Within: the objects made before (the case, CasADi's and pydantic's, the modules) sit
    in the collector's permanent generation, so its full collections scan only the batch's.

    One full collection of the ``check`` process's heap took ~30 ms of ``check --samples
    10000``, a tenth of the samples' cost. Cycles made within are collected as ever;
    afterwards the earlier objects are put back in the oldest generation.
    """
    import gc

    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def _glibc() -> Any:
    """The C library when it is glibc (it has ``mallopt``), else None."""
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    try:
        libc = ctypes.CDLL(None)
        libc.mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    except (OSError, AttributeError):  # musl and others: no mallopt
        return None
    return libc


def _openblas() -> tuple[Any, Any] | None:
    """numpy's loaded OpenBLAS thread-count setter and getter (Linux), else None."""
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
            paths = sorted({line.split()[-1] for line in maps
                            if "openblas" in line.lower() and ".so" in line})
    except OSError:
        return None
    for path in paths:
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for set_name, get_name in _OPENBLAS:
            if hasattr(library, set_name) and hasattr(library, get_name):
                setter, getter = getattr(library, set_name), getattr(library, get_name)
                setter.argtypes, setter.restype = [ctypes.c_int], None
                getter.argtypes, getter.restype = [], ctypes.c_int
                return setter, getter
    return None
