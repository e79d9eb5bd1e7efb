"""Performance-core benchmark: prints measured figures and ratios (not a test).

* whole-process time of ``tuflexperf check`` vs ``python -c "import casadi"`` (target <= 2.5x)
  and vs importing AeroSandbox when it is installed;
* each analysis' solve time after its CasADi functions are built (targets: take-off <= 5 ms,
  trim sweep <= 10 ms);
* the same analyses done the naive SciPy way in the same run (``solve_ivp`` with a lift-off
  event; ``brentq`` per airspeed), as ratios.

Run: ``python bench/bench_core.py``
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from timing import per_call, wall, walls  # noqa: E402

from tuflexperf.analysis.ground_roll import net_force_n
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.io.case import load_case
from tuflexperf.models.aircraft import level_flight_drag_n, liftoff_speed_m_s
from tuflexperf.models.thrust import total_thrust_n


def naive_takeoff(case) -> float:
    from scipy.integrate import solve_ivp

    ac, prop, rho = case.aircraft, case.propulsion, case.density_kg_m3
    v_lo = float(liftoff_speed_m_s(ac, rho))

    def rhs(_t, y):
        return [float(net_force_n(ac, prop, y[0], rho)) / ac.mass_kg, y[0]]

    def lift_off(_t, y):
        return y[0] - v_lo

    lift_off.terminal = True
    sol = solve_ivp(rhs, (0, 120), [0.0, 0.0], events=lift_off, rtol=1e-10, atol=1e-10)
    # the ground roll ends after rotation at the lift-off speed (Raymer 17.8.2)
    return float(sol.y_events[0][0][1]) + v_lo * ac.takeoff.rotation_time_s


def naive_trim(case, speeds: np.ndarray) -> list[float]:
    from scipy.optimize import brentq

    ac, prop, rho = case.aircraft, case.propulsion, case.density_kg_m3
    out = []
    for v in speeds:

        def excess(x, v=v):
            return float(total_thrust_n(prop, x, v, rho) - level_flight_drag_n(ac, v, rho))

        if excess(0.0) >= 0:
            out.append(0.0)
        elif excess(1.0) < 0:
            out.append(float("nan"))
        else:
            out.append(brentq(excess, 0.0, 1.0, xtol=1e-12))
    return out


USED_STACK = """
import casadi, numpy, typer, yaml, pydantic
from pydantic import BaseModel, Field
class Probe(BaseModel):
    x: float = Field(gt=0)
Probe(x=1.0)
import typer._adapters
"""

# The least a typer CLI on this stack can do: two commands, one bool option, and the same
# imports as the floor made real (typer >= 0.2x builds its parameters through pydantic
# adapters on every parse, so the parse itself imports pydantic's model machinery).
MINIMAL_TYPER_CLI = """
import sys
import casadi, numpy, yaml, typer
app = typer.Typer()
@app.command()
def check(as_json: bool = typer.Option(False, "--json")) -> None:
    print("PASS")
@app.command()
def other() -> None:
    pass
sys.argv = ["minimal", "check"]
app()
"""

VALIDATE_ONLY = """
import casadi, numpy, typer, yaml, pydantic
from tuflexperf.io.case import load_case
load_case()
"""


def main() -> None:
    exe = shutil.which("tuflexperf", path=str(Path(sys.executable).parent)) or "tuflexperf"
    measured = walls({
        "check": [exe, "check"],
        "casadi": [sys.executable, "-c", "import casadi"],
        "stack": [sys.executable, "-c", "import casadi, numpy, typer, yaml, pydantic"],
        "python": [sys.executable, "-c", "pass"],
        "used": [sys.executable, "-c", USED_STACK],
        "minimal": [sys.executable, "-c", MINIMAL_TYPER_CLI],
        "validated": [sys.executable, "-c", VALIDATE_ONLY],
    })
    check_s, casadi_s, stack_s, python_s = (measured[k] for k in ("check", "casadi", "stack",
                                                                  "python"))
    used_s, minimal_s, validated_s = (measured[k] for k in ("used", "minimal", "validated"))
    print("whole process (median of 15 rounds, the commands taking turns)")
    print(f"  python -c pass                {python_s * 1e3:8.1f} ms")
    print(f"  python -c 'import casadi'     {casadi_s * 1e3:8.1f} ms")
    print(f"  import casadi, numpy, typer, yaml, pydantic {stack_s * 1e3:8.1f} ms (the floor)")
    print(
        f"  tuflexperf check              {check_s * 1e3:8.1f} ms   "
        f"ratio to the floor {check_s / stack_s:5.2f} (issue 9 target <= 1.3)"
    )
    # What any typer + pydantic CLI pays beyond that floor: `import pydantic` is lazy, so the
    # floor holds none of pydantic's model machinery, nor typer's parser (imported on parse).
    print(
        f"  + one pydantic model validated, typer's parser {used_s * 1e3:6.1f} ms   "
        f"ratio to the floor {used_s / stack_s:5.2f} (no tuflexperf code at all)"
    )
    print(
        f"  a do-nothing typer CLI on the same imports {minimal_s * 1e3:6.1f} ms   "
        f"ratio to the floor {minimal_s / stack_s:5.2f} (the least any typer CLI here takes)"
    )
    # The input check alone: the case's four files read and validated by tuflexperf's
    # pydantic schemas (no typer, no analysis). Any check that validates its input with
    # pydantic models pays this before it computes anything.
    print(
        f"  + the shipped case read and validated (schemas only) {validated_s * 1e3:6.1f} ms   "
        f"ratio to the floor {validated_s / stack_s:5.2f} (no CLI, no analysis)"
    )
    print(
        f"  tuflexperf's own share (check - that)  {(check_s - used_s) * 1e3:6.1f} ms"
    )
    # AeroSandbox is not a dependency: pass a Python that has it (e.g. a scratch venv).
    asb_python = sys.argv[sys.argv.index("--aerosandbox-python") + 1] if (
        "--aerosandbox-python" in sys.argv
    ) else sys.executable
    probe = subprocess.run([asb_python, "-c", "import aerosandbox"], capture_output=True)
    if probe.returncode == 0:
        asb_s = wall([asb_python, "-c", "import aerosandbox"], repeats=5)
        print(
            f"  import aerosandbox            {asb_s * 1e3:8.1f} ms   "
            f"check takes {check_s / asb_s:4.2f} of it"
        )
    else:
        print("  (no AeroSandbox: pass --aerosandbox-python PYTHON to time its import)")

    case = load_case()
    start = time.perf_counter()
    solve_takeoff(case), solve_trim(case), solve_oei(case)
    build_s = time.perf_counter() - start
    takeoff_s = per_call(lambda: solve_takeoff(case))
    trim_s = per_call(lambda: solve_trim(case))
    oei_s = per_call(lambda: solve_oei(case))
    speeds = solve_trim(case).airspeed_m_s
    naive_takeoff_s = per_call(lambda: naive_takeoff(case), repeats=20)
    naive_trim_s = per_call(lambda: naive_trim(case, speeds), repeats=20)
    ours, theirs = solve_takeoff(case).ground_roll_m, naive_takeoff(case)
    print(f"\nanalyses on the shipped case (build of all three: {build_s * 1e3:.1f} ms)")
    print(
        f"  take-off solve        {takeoff_s * 1e3:8.3f} ms (target <= 5)   "
        f"naive solve_ivp+event {naive_takeoff_s * 1e3:8.3f} ms  "
        f"ratio {naive_takeoff_s / takeoff_s:6.1f}x"
    )
    print(f"     ground roll ours {ours:.6f} m, naive {theirs:.6f} m")
    print(
        f"  trim sweep ({speeds.size} pts)  {trim_s * 1e3:8.3f} ms (target <= 10)  "
        f"naive brentq per airspeed {naive_trim_s * 1e3:8.3f} ms  "
        f"ratio {naive_trim_s / trim_s:6.1f}x"
    )
    diff = np.nanmax(np.abs(solve_trim(case).throttle - np.array(naive_trim(case, speeds))))
    print(f"     largest throttle difference ours vs brentq {diff:.2e}")
    print(f"  OEI (2 dead-engine sweeps) {oei_s * 1e3:8.3f} ms")


if __name__ == "__main__":
    main()
