"""Speed of the exported thrust model: C, CasADi, numpy and a plain Python/SciPy baseline.

Run: ``.venv/bin/python bench/bench_export.py [--calls 1e8]``. Exports the shipped TU-Flex model
to a temporary directory, compiles a C loop (``gcc -std=c99 -O2``, the model in its own
translation unit so every call is a real call) that calls ``tfp_thrust`` with varying inputs and
sums the outputs (so nothing is optimised away), and times, in the same run:

- C ``tfp_thrust`` and ``tfp_throttle_for_thrust`` (with its argument checks and extrapolation
  flag; target for each: >= 50 million calls per second);
- the Python model: a scalar loop over :func:`total_thrust_n` (the naive way) and numpy
  vectorised over arrays;
- the exported CasADi function, called per point and mapped over a batch;
- the inverse: C closed form vs numpy closed form vs ``scipy.optimize.brentq`` per point.

One evaluation = the thrust of both engines at one (throttles, airspeed, density) point.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tuflexperf.export import export_model  # noqa: E402
from tuflexperf.export.cbuild import find_compiler  # noqa: E402
from tuflexperf.export.model import throttle_for_thrust  # noqa: E402
from tuflexperf.models.thrust import total_thrust_n  # noqa: E402

C_LOOP = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "tfp_thrust.h"

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    const long n = argc > 1 ? atol(argv[1]) : 100000000L;
    const long n_inverse = n / 4;
    double t1, t2, x = 0.0, v = 0.0, rho = 1.0, sum = 0.0, start, thrust_s, inverse_s;
    long i;
    int failures = 0, flag = 0, extrapolated = 0;
    start = seconds();
    for (i = 0; i < n; ++i) {
        tfp_thrust(x, 1.0 - x, v, rho, &t1, &t2);
        sum += t1 + t2;
        x += 0.000977; if (x > 1.0) x -= 1.0;      /* throttle sweeps [0, 1] */
        v += 0.0731; if (v > 45.0) v -= 45.0;      /* airspeed sweeps [0, 45] m/s */
        rho += 0.00013; if (rho > 1.3) rho = 0.9;  /* density sweeps [0.9, 1.3] */
    }
    thrust_s = seconds() - start;
    start = seconds();
    for (i = 0; i < n_inverse; ++i) {
        failures += tfp_throttle_for_thrust(120.0 * x - 10.0, v, rho, &t1, &flag) != 0;
        extrapolated += flag;
        sum += t1;
        x += 0.000977; if (x > 1.0) x -= 1.0;
        v += 0.0731; if (v > 45.0) v -= 45.0;
    }
    inverse_s = seconds() - start;
    printf("%ld %.9f %ld %.9f %d %.17g %d\n", n, thrust_s, n_inverse, inverse_s, failures, sum,
           extrapolated);
    return 0;
}
"""


def _rate(count: float, seconds: float) -> float:
    return count / seconds if seconds > 0 else float("inf")


def _time(function, *args) -> float:  # noqa: ANN001 - small helper
    start = time.perf_counter()
    function(*args)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=float, default=1e8, help="C tfp_thrust calls")
    args = parser.parse_args()

    rows: list[tuple[str, float]] = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "export"
        result = export_model(None, ("c", "casadi"), out)
        prop = result.model.propulsion
        print(f"model: {prop.name}, {result.model.n_engines} engines "
              f"(propulsion sha256 {result.model.propulsion_sha256[:12]}...)")

        # --- C -----------------------------------------------------------------------------
        compiler = find_compiler()
        if compiler is None:
            print("no C compiler: C figures skipped")
        else:
            (out / "bench_main.c").write_text(C_LOOP)
            exe = Path(tmp) / "bench_c"
            subprocess.run(
                [compiler, "-std=c99", "-Wall", "-Werror", "-O2", "-o", str(exe),
                 str(out / "bench_main.c"), str(out / "tfp_thrust.c"), "-lm"],
                check=True,
            )
            done = subprocess.run(
                [str(exe), str(int(args.calls))], check=True, capture_output=True, text=True
            )
            n, thrust_s, n_inv, inverse_s, failures, _, _ = done.stdout.split()
            rows.append(("C tfp_thrust (loop, -O2)", _rate(float(n), float(thrust_s))))
            rows.append(
                ("C tfp_throttle_for_thrust (loop)", _rate(float(n_inv), float(inverse_s)))
            )
            print(f"C: {int(n):.3g} tfp_thrust calls in {float(thrust_s):.3f} s; "
                  f"{int(n_inv):.3g} inverse calls in {float(inverse_s):.3f} s "
                  f"({failures} unreachable demands)")

        rng = np.random.default_rng(0)
        big = 1_000_000
        x1, x2 = rng.uniform(0, 1, big), rng.uniform(0, 1, big)
        v, rho = rng.uniform(0, 45, big), rng.uniform(0.9, 1.3, big)

        # --- Python ------------------------------------------------------------------------
        small = 50_000

        def scalar_loop() -> float:
            s = 0.0
            for k in range(small):
                s += total_thrust_n(prop, [float(x1[k]), float(x2[k])], float(v[k]),
                                    float(rho[k]))
            return s

        rows.append(("Python scalar loop (total_thrust_n)", _rate(small, _time(scalar_loop))))
        seconds = _time(total_thrust_n, prop, [x1, x2], v, rho)
        rows.append(("numpy vectorised (total_thrust_n)", _rate(big, seconds)))

        # --- CasADi ------------------------------------------------------------------------
        import casadi as ca

        function = ca.Function.load(str(out / "tfp_thrust.casadi"))
        casadi_calls = 20_000

        def casadi_loop() -> None:
            for k in range(casadi_calls):
                function([x1[k], x2[k]], v[k], rho[k])

        rows.append(("CasADi function, per call", _rate(casadi_calls, _time(casadi_loop))))
        batch = 100_000
        mapped = function.map(batch)
        throttle = np.vstack([x1[:batch], x2[:batch]])
        seconds = _time(mapped, throttle, v[None, :batch], rho[None, :batch])
        rows.append((f"CasADi function.map({batch})", _rate(batch, seconds)))

        # --- inverse: closed form vs a root finder -----------------------------------------
        from scipy.optimize import brentq

        demand = rng.uniform(0.0, 80.0, big)
        seconds = _time(throttle_for_thrust, prop, demand, v, rho)
        rows.append(("inverse, numpy closed form", _rate(big, seconds)))
        n_brent = 5_000

        def brent_loop() -> None:
            for k in range(n_brent):
                f = lambda t, k=k: float(total_thrust_n(prop, t, v[k], rho[k])) - demand[k]  # noqa: E731
                if f(0.0) >= 0.0 or f(1.0) < 0.0:
                    continue  # idle suffices / unreachable: no bracket
                brentq(f, 0.0, 1.0, xtol=1e-12)

        rows.append(("inverse, scipy brentq per point (naive)", _rate(n_brent, _time(brent_loop))))

    naive = dict(rows)["Python scalar loop (total_thrust_n)"]
    print(f"\n{'method':44s} {'evaluations/s':>16s} {'vs Python loop':>15s}")
    for name, rate in rows:
        print(f"{name:44s} {rate:16.4g} {rate / naive:14.1f}x")
    if "C tfp_thrust (loop, -O2)" in dict(rows):
        c_rate = dict(rows)["C tfp_thrust (loop, -O2)"]
        verdict = "meets" if c_rate >= 50e6 else "MISSES"
        print(f"\nC tfp_thrust: {c_rate / 1e6:.1f} million evaluations/s "
              f"({verdict} the 50 M/s target)")
        brent = dict(rows)["inverse, scipy brentq per point (naive)"]
        c_inv = dict(rows)["C tfp_throttle_for_thrust (loop)"]
        verdict = "meets" if c_inv >= 50e6 else "MISSES"
        print(f"C tfp_throttle_for_thrust (checked, with extrapolation flag): "
              f"{c_inv / 1e6:.1f} million calls/s ({verdict} the 50 M/s target)")
        print(f"C closed-form inverse vs scipy brentq: {c_inv / brent:.0f}x")


if __name__ == "__main__":
    main()
