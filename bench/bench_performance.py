"""Point-performance benchmark: prints measured figures and ratios (not a test).

* building the case's CasADi rootfinders once (``PerformanceProblems``) and solving all
  of ``performance`` with them (the result memoised per case by the Study later);
* the same answers the naive SciPy way in the same run (``minimize_scalar`` for Vy, Vx and
  the OEI gradients; a scan plus ``brentq`` for the level-speed bounds; ``brentq`` on
  altitude over a ``minimize_scalar`` best rate of climb for each ceiling), as a ratio, and
  the largest difference between the two answers;
* whole-process ``tuflexperf performance`` against the floor
  ``python -c "import casadi, numpy, typer, yaml, pydantic"``.

Run: ``python bench/bench_performance.py [CASE]`` (default: a made-up case whose thrust is
lapsed with density, so both ceilings exist).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml
from timing import per_call as median_time  # noqa: E402
from timing import wall

from tuflexperf.analysis.performance import PerformanceProblems, solve_performance
from tuflexperf.io.case import load_case
from tuflexperf.models.atmosphere import isa_density_kg_m3


def naive(case, p: PerformanceProblems) -> dict[str, float]:
    """The same quantities with SciPy on the same numpy model functions."""
    from scipy.optimize import brentq, minimize_scalar

    rho = case.density_kg_m3
    opts = {"xatol": 1e-10}

    def bounds(r):
        low = float(p.least_airspeed_m_s(r))
        cap = p.speed_cap_m_s(r)
        return low, max(cap if np.isfinite(cap) else 10 * low, 1.001 * low)

    low, high = bounds(rho)
    vy = minimize_scalar(lambda v: -float(p.climb_rate(v, rho)), bounds=(low, high),
                         method="bounded", options=opts).x
    vx = minimize_scalar(lambda v: -float(p.gradient(v, rho)), bounds=(low, high),
                         method="bounded", options=opts).x
    grid = np.linspace(low, high, 1201)
    ok = np.asarray(p.excess_n(grid, rho)) >= 0
    last = int(len(ok) - 1 - np.argmax(ok[::-1]))
    v_max = brentq(lambda v: float(p.excess_n(v, rho)), grid[last], grid[last + 1], xtol=1e-12)
    out = {"vy": vy, "vx": vx, "v_max": v_max,
           "rc_max": float(p.climb_rate(vy, rho))}
    for dead in p.dead_cases[1:]:
        out[f"oei_vx_{dead}"] = minimize_scalar(
            lambda v, d=dead: -float(p.gradient(v, rho, d)), bounds=(low, high),
            method="bounded", options=opts).x

    def best_rate(h):
        r = float(isa_density_kg_m3(h, p.offset_k))
        lo, hi = bounds(r)
        res = minimize_scalar(lambda v: -float(p.climb_rate(v, r)), bounds=(lo, hi),
                              method="bounded", options=opts)
        return -res.fun

    for name, target in (("service", 0.5), ("absolute", 0.0)):
        out[name] = brentq(lambda h, t=target: best_rate(h) - t, 0.0, 20000.0, xtol=1e-6)
    return out


def made_up_case(folder: Path) -> Path:
    aircraft = {"name": "bench", "mass_kg": 20.0, "wing_area_m2": 1.0, "cd0": 0.03, "k": 0.05,
                "cl_max": 1.6, "takeoff": {"cl_ground": 0.4, "rolling_friction": 0.05}}
    engine = {"p00": 0.0, "p10": 4.0, "p01": -0.1, "p20": 36.0, "p11": -0.3, "p02": -0.002}
    propulsion = {"name": "bench fans", "model": "poly22", "tested_airspeed_m_s": [0, 40],
                  "reference_density_kg_m3": 1.225,
                  "engines": [{"name": "L", "coefficients": engine},
                              {"name": "R", "coefficients": engine}]}
    (folder / "aircraft.yaml").write_text(yaml.safe_dump(aircraft))
    (folder / "propulsion.yaml").write_text(yaml.safe_dump(propulsion))
    case = {"name": "bench", "aircraft": "aircraft.yaml", "propulsion": "propulsion.yaml",
            "requirements": {"takeoff": {"max_ground_roll_m": 80},
                             "oei": {"dead_engine": "windmilling"}}}
    path = folder / "case.yaml"
    path.write_text(yaml.safe_dump(case))
    return path


def main() -> None:
    folder = Path(tempfile.mkdtemp())
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else made_up_case(folder)
    case = load_case(path)
    build_s = median_time(lambda: PerformanceProblems(case), repeats=5)
    problems = PerformanceProblems(case)
    solve_s = median_time(lambda: solve_performance(case, problems))
    result = solve_performance(case, problems)
    naive_s = median_time(lambda: naive(case, problems), repeats=3)
    ref = naive(case, problems)
    ours = {"vy": result.best_climb_rate_speed_m_s, "vx": result.best_climb_angle_speed_m_s,
            "v_max": result.max_level_speed_m_s, "rc_max": result.max_climb_rate_m_s,
            "service": result.service_ceiling_m, "absolute": result.absolute_ceiling_m}
    for i, c in enumerate(result.oei):
        ours[f"oei_vx_{i}"] = c.max_climb_gradient_speed_m_s
    diffs = {k: abs(ours[k] - ref[k]) / abs(ref[k]) for k in ref if ours.get(k) is not None}
    print(f"case: {path}")
    print(f"build PerformanceProblems (rootfinders, once per case):  {1e3 * build_s:8.1f} ms")
    print(f"solve all point performance after build:              {1e3 * solve_s:8.1f} ms")
    print(f"naive SciPy (minimize_scalar / brentq) same answers:  {1e3 * naive_s:8.1f} ms "
          f"({naive_s / solve_s:.1f}x ours)")
    print(f"largest relative difference ours vs SciPy: {max(diffs.values()):.1e} "
          f"({max(diffs, key=diffs.get)})")
    exe = [sys.executable, "-m", "tuflexperf", "performance", "--case", str(path)]
    floor = [sys.executable, "-c", "import casadi, numpy, typer, yaml, pydantic"]
    whole, base = wall(exe), wall(floor)
    print(f"tuflexperf performance, whole process: {whole:.2f} s = {whole / base:.1f}x the "
          f"import floor ({1e3 * base:.0f} ms)")


if __name__ == "__main__":
    main()
