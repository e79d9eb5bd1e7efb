"""Endurance benchmark: prints measured figures and ratios (not a test).

* build time of the endurance model (battery fit + cross-validation + CasADi functions);
* solve time per throttle after the build (target <= 20 ms), median over many calls;
* the same answers the naive SciPy way in the same run -- ``brentq`` for the level-flight
  airspeed, ``solve_ivp`` in time with a terminal cut-off event for the pack, and again for
  the flight from the launch charge to the reserve -- as a ratio, with the agreement.

Run: ``python bench/bench_endurance.py [CASE]`` (default: the shipped case; when it has no
battery yet, the shipped case plus ``data/tuflex/battery.yaml``).
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from tuflexperf.analysis.endurance import endurance_model, solve_endurance
from tuflexperf.io.case import load_case, shipped_case_path
from tuflexperf.models.aircraft import level_flight_drag_n
from tuflexperf.models.battery import (
    current_at_power_a,
    terminal_voltage_v,
)
from tuflexperf.models.thrust import total_thrust_n

ROOT = Path(__file__).resolve().parent.parent
THROTTLES = np.linspace(0.45, 0.95, 11)


def case_path() -> Path:
    if len(sys.argv) > 1:
        return Path(sys.argv[1])
    shipped = shipped_case_path()
    data = yaml.safe_load(shipped.read_text())
    if data.get("battery"):
        return shipped
    for key in ("aircraft", "propulsion"):
        data[key] = str((shipped.parent / data[key]).resolve())
    data["battery"] = str(ROOT / "data" / "tuflex" / "battery.yaml")
    path = Path(tempfile.mkdtemp()) / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def naive(model, throttle: float) -> tuple[float, float, float]:
    """Airspeed (m/s), pack and flight endurance (min) with brentq + solve_ivp."""
    case, p, packs = model.case, model.params, model.packs
    rho = case.density_kg_m3

    def excess(v: float) -> float:
        return float(total_thrust_n(case.propulsion, throttle, v, rho)
                     - level_flight_drag_n(case.aircraft, v, rho))

    high = model.min_throttle_airspeed
    while excess(high) >= 0:
        high *= 1.5
    speed = brentq(excess, model.min_throttle_airspeed, high, xtol=1e-12)
    power = float(model.power.electrical_power_w(throttle, speed))

    def discharge(q0: float, n: int, stop_ah: float) -> float:
        def rate(_t, y):
            return [float(current_at_power_a(p, y[0], power, n)) / 3600.0]

        def cutoff(_t, y):
            i = current_at_power_a(p, y[0], power, n)
            return float(terminal_voltage_v(p, y[0], i, n)) - model.cutoff_v

        def reserve(_t, y):
            return stop_ah - y[0]

        cutoff.terminal = reserve.terminal = True
        sol = solve_ivp(rate, (0.0, 1e5), [q0], events=[cutoff, reserve], rtol=1e-9, atol=1e-12)
        return float(sol.t[-1])

    pack_s = discharge(0.0, 1, np.inf)
    cruise_s = discharge(model.launch.charge_ah, packs, model.reserve_ah)
    return speed, pack_s / 60.0, (cruise_s + model.launch.climb_time_s) / 60.0


def main() -> None:
    case = load_case(case_path())
    start = time.perf_counter()
    model = endurance_model(case)
    build_s = time.perf_counter() - start
    print(f"build (3 battery fits, launch, CasADi functions): {build_s * 1e3:.0f} ms")

    times, naive_times, worst = [], [], [0.0, 0.0, 0.0]
    for x in THROTTLES:
        for _ in range(20):
            t0 = time.perf_counter()
            result = solve_endurance(case, float(x))
            times.append(time.perf_counter() - t0)
        for _ in range(3):
            t0 = time.perf_counter()
            ref = naive(model, float(x))
            naive_times.append(time.perf_counter() - t0)
        ours = (result.airspeed_m_s, result.battery_endurance_min, result.flight_endurance_min)
        worst = [max(w, abs(a - b)) for w, a, b in zip(worst, ours, ref, strict=True)]
    ours_ms = statistics.median(times) * 1e3
    naive_ms = statistics.median(naive_times) * 1e3
    print(f"endurance solve after build: median {ours_ms:.2f} ms  (target <= 20 ms: "
          f"{'met' if ours_ms <= 20 else 'NOT met'})")
    print(f"naive SciPy (brentq + solve_ivp with cut-off event): median {naive_ms:.2f} ms")
    print(f"ratio naive / ours: {naive_ms / ours_ms:.1f}x")
    print(f"agreement over {len(THROTTLES)} throttles 0.45-0.95: airspeed {worst[0]:.2e} m/s, "
          f"pack {worst[1] * 60:.2e} s, flight {worst[2] * 60:.2e} s")


if __name__ == "__main__":
    main()
