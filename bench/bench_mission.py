"""Mission speed (issue 13): the shipped 7-segment mission after the build, and solve_for,
against a naive scipy solve_ivp segment by segment (brentq throttle at every call), same run.

Run: .venv/bin/python bench/bench_mission.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from tuflexperf.analysis.mission import MissionModel
from tuflexperf.io.case import load_case
from tuflexperf.io.mission import load_mission
from tuflexperf.models.aircraft import level_flight_drag_n, true_airspeed_m_s
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.battery import current_at_power_a
from tuflexperf.models.powertrain import engine_power_w
from tuflexperf.models.thrust import density_ratio, total_thrust_n

ROOT = Path(__file__).resolve().parents[1]
MISSION = ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml"


def best_of(fn, repeat: int = 20) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def naive(model: MissionModel, q0: np.ndarray) -> float:
    """Airborne segments one by one with solve_ivp from the charges ``q0`` [Ah] after the
    take-off (the take-off itself is left out: it flatters). Returns the charge drawn."""
    case = model.case
    prop, aircraft, p, packs = case.propulsion, case.aircraft, model.params, model.packs
    q = np.array(q0, dtype=float)
    for plan in model.plans:
        if plan.kind in ("event", "takeoff"):
            continue
        dead = plan.dead

        def currents(x: float, v: float, rho: float, charge: np.ndarray, dead=dead) -> list[float]:
            out = []
            for i, e in enumerate(prop.engines):
                pw = 0.0 if i == dead else float(density_ratio(prop, rho) * engine_power_w(e, x, v))
                out.append(float(current_at_power_a(p, charge[i], pw, packs)))
            return out

        def level(t: float, y: np.ndarray, plan=plan, dead=dead) -> list[float]:
            rho = float(isa_density_kg_m3(plan.start_h, 0.0))
            v = float(true_airspeed_m_s(plan.eas, rho))
            drag = float(level_flight_drag_n(aircraft, v, rho))
            x = brentq(lambda s: float(total_thrust_n(prop, s, v, rho, dead)) - drag, 0, 1)
            return [c / 3600.0 for c in currents(x, v, rho, y)]

        def height(h: float, y: np.ndarray, plan=plan, dead=dead) -> list[float]:
            rho = float(isa_density_kg_m3(h, 0.0))
            v = float(true_airspeed_m_s(plan.eas, rho))
            excess = float(total_thrust_n(prop, plan.throttle, v, rho, dead)
                           - level_flight_drag_n(aircraft, v, rho))
            rate = excess * v / aircraft.weight_n
            return [c / 3600.0 / rate for c in currents(plan.throttle, v, rho, y)]

        if plan.kind == "time":
            q = solve_ivp(level, (0, plan.duration_s), q, rtol=1e-8).y[:, -1]
        else:
            q = solve_ivp(height, (plan.start_h, plan.end_h), q, rtol=1e-8).y[:, -1]
    return float(q.sum() - np.sum(q0))


def voltage_case(folder: Path):
    """The shipped case with the propulsion's reference voltage (the sag costs thrust)."""
    import shutil

    for name in ("requirements", "data"):
        shutil.copytree(ROOT / name, folder / name)
    prop = folder / "data" / "tuflex" / "propulsion.yaml"
    prop.write_text(prop.read_text().replace(
        "fan_area_m2:", "reference_voltage_v: 46.0\nvoltage_exponent: 2\nfan_area_m2:", 1))
    return load_case(folder / "requirements" / "tuflex.yaml")


def main() -> None:
    import tempfile
    from dataclasses import replace

    case = load_case(None)
    mission = load_mission(MISSION)
    t = time.perf_counter()
    model = MissionModel(case, mission, None)
    build = time.perf_counter() - t
    fly = best_of(model.fly)
    flown = model.fly()
    q0 = np.array(flown.segments[0].charge_ah)
    t_naive = best_of(lambda: naive(model, q0), repeat=3)
    airborne = sum(sum(s.charge_ah) for s in flown.segments if s.type != "takeoff")
    naive_ah = naive(model, q0)
    print(f"mission build (once per case and mission): {1e3 * build:.0f} ms")
    print(f"{len(mission.segments)}-segment mission after the build: {1e3 * fly:.2f} ms "
          f"(target <= 50 ms)")
    print(f"naive solve_ivp (rtol 1e-8) + brentq, airborne segments only: {1e3 * t_naive:.1f} ms "
          f"-> {t_naive / fly:.0f}x; airborne charge {airborne:.6f} vs {naive_ah:.6f} Ah")
    solve = replace(mission, solve_for=2)
    model_s = MissionModel(case, solve, None)
    model_s.solve_for()  # the rootfinder is built on first use
    t_solve = best_of(model_s.solve_for, repeat=5)
    print(f"solve_for cruise (rootfinder on the landing charge): {1e3 * t_solve:.1f} ms "
          f"(target <= 200 ms)")
    with tempfile.TemporaryDirectory() as folder:
        vcase = voltage_case(Path(folder))
        t = time.perf_counter()
        vmodel = MissionModel(vcase, mission, None)
        vbuild = time.perf_counter() - t
        vfly = best_of(vmodel.fly)
        print(f"with the pack-voltage effect (implicit loaded voltage, Newton per RK4 stage): "
              f"build {1e3 * vbuild:.0f} ms, mission {1e3 * vfly:.2f} ms")
        vsolve = MissionModel(vcase, solve, None)
        vsolve.solve_for()
        print(f"  solve_for cruise: {1e3 * best_of(vsolve.solve_for, repeat=5):.1f} ms")


if __name__ == "__main__":
    main()
