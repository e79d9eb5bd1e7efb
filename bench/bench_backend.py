"""One kernel, two evaluations (issue 42): the least level-flight throttle over a batch.

The same backend-neutral model functions (:func:`tuflexperf.models.thrust.least_throttle_of`
on :func:`~tuflexperf.models.thrust.total_thrust_n` and
:func:`~tuflexperf.models.aircraft.level_flight_drag_n`) evaluated over N samples of airspeed
and density two ways:

- numpy: the functions called once on arrays of N (what a numpy namespace dispatching on its
  input type does for ``--samples``, ``sweep`` and ``margins``);
- CasADi: the functions traced once on scalar SX symbols into a ``Function``, then
  ``Function.map(N)`` evaluated on 1 x N rows (serial, and with 2 threads).

Prints per-evaluation times (median of 7 after a warm-up), the build times, the ratios and
the largest difference between the two answers. Ratios, not absolute times, are the result.

Run: .venv/bin/python bench/bench_backend.py [N]
"""

from __future__ import annotations

import sys
import time

import casadi as ca
import numpy as np
from timing import per_call

from tuflexperf.io.case import load_case
from tuflexperf.models.aircraft import level_flight_drag_n
from tuflexperf.models.thrust import least_throttle_of, total_thrust_n


def main(n: int = 10_000) -> None:
    case = load_case(None)
    aircraft, propulsion = case.aircraft, case.propulsion
    rng = np.random.default_rng(42)
    speed = rng.uniform(15.0, 45.0, n)  # [m/s], the envelope the case asks for
    density = case.density_kg_m3 * rng.uniform(0.8, 1.05, n)  # [kg/m^3]

    def kernel(v: object, rho: object) -> tuple[object, object]:
        drag = level_flight_drag_n(aircraft, v, rho)
        return least_throttle_of(lambda x: total_thrust_n(propulsion, x, v, rho) - drag)

    t = time.perf_counter()
    v_sym, rho_sym = ca.SX.sym("v"), ca.SX.sym("rho")
    x_sym, ok_sym = kernel(v_sym, rho_sym)
    one = ca.Function("least_throttle", [v_sym, rho_sym], [x_sym, ok_sym])
    serial, threaded = one.map(n), one.map(n, "thread", 2)
    build_s = time.perf_counter() - t
    v_row, rho_row = ca.DM(speed).T, ca.DM(density).T

    def on_numpy() -> np.ndarray:
        return np.asarray(kernel(speed, density)[0], dtype=float)

    def on_map() -> np.ndarray:
        return np.asarray(serial(v_row, rho_row)[0]).reshape(-1)

    def on_threads() -> np.ndarray:
        return np.asarray(threaded(v_row, rho_row)[0]).reshape(-1)

    numpy_s, map_s, thread_s = per_call(on_numpy), per_call(on_map), per_call(on_threads)
    gap = float(np.max(np.abs(on_numpy() - on_map())))
    print(f"least throttle over {n} samples (airspeed 15-45 m/s, density 0.8-1.05 x the case's)")
    print(f"  numpy arrays            {numpy_s * 1e3:8.2f} ms  ({n / numpy_s:,.0f} samples/s)")
    print(f"  CasADi map, serial      {map_s * 1e3:8.2f} ms  ({map_s / numpy_s:.2f} x numpy)")
    print(f"  CasADi map, 2 threads   {thread_s * 1e3:8.2f} ms  ({thread_s / numpy_s:.2f} x numpy)")
    print(f"  CasADi trace + map build{build_s * 1e3:8.2f} ms  (once per model)")
    print(f"  largest difference      {gap:.1e} (throttle fraction)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000)
