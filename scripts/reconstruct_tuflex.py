"""Reconstruct the shipped TU-Flex data (data/tuflex/propulsion.yaml, aircraft.yaml) from the paper.

One over-determined weighted least-squares problem in CasADi (IPOPT), more published facts
than knobs, every knob either free or pulled towards a published estimate (a prior):

Knobs (10): mass; ``cd0``; Oswald ``e`` (-> ``k = 1/(pi e AR)``); ``cl_max``;
``liftoff_speed_factor``; ``rotation_time_s``; the throttle shape ``s`` of the thrust
(static thrust ``a (s x + (1 - s) x^2)``, ``s < 0`` an ESC dead band up to
``x0 = -s/(1 - s)``); the windmilling drag coefficient ``Cd_wm``; the fan's electrical
model ``P_el = P_i / eta + L x`` (momentum-theory ideal power over an efficiency, plus the
motor's no-load power growing with rpm); the jet area ``A`` of momentum theory.

Published facts (each a residual over its stated tolerance; SPEC 6 / paper):
ground roll 55.5 m; least trim throttle 41 %; least one-engine throttle 56 %; one pack
"nearly 10 min" at 50 % and 30 m/s (tunnel); "about 15 min" of flight; 15 m/s "slightly
below the take-off speed"; Table 1: power 2.4-4.1 kW for 41-59 N static (interpolated at
this fan's static thrust), exit velocity 82-98 m/s (likewise), efficiency 70-71 %
(``T v_e / 2 / P_el`` at full static thrust).

Priors (estimates with a spread, also residuals): Oswald ``e`` from Raymer's
``1.78 (1 - 0.045 AR^0.68) - 0.64`` (*Aircraft Design*, eq. 12.48) +- 0.05; ``cd0`` 0.030
+- 0.008 (twin-EDF demonstrator with gear); ``cl_max`` 1.4 +- 0.15; lift-off 1.1-1.2 x
stall (Raymer 17.8.1) as 1.15 +- 0.03; rotation 1 +- 0.5 s (Raymer 17.8.2: about 1 s for
a small aircraft); ``Cd_wm`` 0.5 +- 0.2 on the jet area (a windmilling fan is a porous
disk, Hoerner ch. 3; written on the disk area, the same drag); no-load power ``L`` 100 +- 50 W (motor no-load current ~2 A at 45 V).

Derived, not knobs: the full-throttle thrust curve through the paper's 0, 30 and 40 m/s
values per fan (exact, three points and three unknowns), ``p00 = 0``, ``p01`` estimated.

Constraint: the published envelope's 15 m/s stays above the stall speed up to an ISA+20 K
day at sea level (summer in Berlin): stall at ISA sea level <= 15 sqrt(288.15/308.15) =
14.50 m/s. The trim and one-engine least throttles are exact in the problem: decision variables
``(x, V)`` with the excess thrust zero at ``V`` and at most zero at every envelope grid
speed (so ``x`` is the least throttle over the grid). The ground roll is a 32-point
Gauss-Legendre quadrature of ``m V / F(V)`` (the landed analysis integrates the same
equation with CVODES); the pack time is the battery model's constant-power discharge to
the cut-off (cut-off charge a decision variable). The launch charge and the climb time of
the flight endurance are taken from the landed endurance analysis and the problem is
solved again until they stop changing.

Afterwards every published number is recomputed by the landed analyses (``takeoff``,
``trim``, ``oei``, ``endurance``) from the written files, and the residual table printed
(and pasted into data/README.md). Run: ``.venv/bin/python scripts/reconstruct_tuflex.py``
(about 3 s; rewrites both files); ``... --without NAME[,NAME]`` solves without those
facts and prints the result (writes nothing).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from tuflexperf.models.aircraft import Aircraft, TakeoffConfig, ground_roll_net_force_n
from tuflexperf.models.battery import (
    cutoff_residual_v,
    discharge_time_s,
    published_static_power_w,
)
from tuflexperf.models.powertrain import exit_velocity_m_s, ideal_power_w
from tuflexperf.models.thrust import poly22
from tuflexperf.reduction.uncertainty import published_grid_uncertainty

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "data" / "tuflex"
G0 = 9.80665
RHO_SL = 1.225

# --- published (paper section 4 / Table 1; SPEC 6) --------------------------------------------
PUBLISHED_FULL_THROTTLE_N = {"EDF1": (55.12, 40.02, 35.26), "EDF2": (55.41, 41.76, 37.76)}
PUBLISHED_AIRSPEEDS_M_S = (0.0, 30.0, 40.0)
# largest published model error at 30 m/s (paper section 4): -0.73 N EDF1, +0.50 N EDF2
PUBLISHED_EDGE_ERROR_N = {"EDF1": 0.73, "EDF2": 0.50}
POWER_RANGE_W = (2400.0, 4100.0)
STATIC_THRUST_RANGE_N = (41.0, 59.0)
EXIT_VELOCITY_RANGE_M_S = (82.0, 98.0)
ENVELOPE_M_S = (15.0, 45.0)
FAN_DIAMETER_M = 0.093  # Table 1: the DS-51's 93 mm fan
FAN_AREA_M2 = math.pi * FAN_DIAMETER_M**2 / 4.0  # its disk area, the file's fan_area_m2
HOT_DAY_OFFSET_K = 20.0  # the envelope's 15 m/s must be above stall up to ISA+20 (summer)
# (value, tolerance): each residual is (model - value) / tolerance
TARGETS = {
    "ground_roll_m": (55.5, 0.5),
    "trim_min_throttle": (0.41, 0.005),
    "oei_min_throttle": (0.56, 0.005),
    "pack_minutes_50pct_30ms": (9.5, 0.5),  # "nearly up to 10 min"
    "flight_minutes": (15.0, 1.0),  # "a flight time of 15 minutes can be estimated"
    "liftoff_eas_m_s": (16.5, 0.75),  # 15 m/s "slightly below the take-off speed"
    "static_power_w": (None, 200.0),  # Table 1 interpolated at the fan's static thrust
    "static_exit_velocity_m_s": (None, 3.0),  # likewise
    "static_efficiency": (0.705, 0.01),  # Table 1 "70-71 %"
}

# --- estimated (fixed) -----------------------------------------------------------------------
SPAN_M = 4.0
WING_AREA_M2 = 1.2
ASPECT_RATIO = SPAN_M**2 / WING_AREA_M2
CL_GROUND = 0.5
ROLLING_FRICTION = 0.07
P01_N_PER_M_S = -0.13
# Test-day density: an indoor open-jet tunnel in Berlin (~35 m), 20 C, 1013 hPa.
REFERENCE_DENSITY_KG_M3 = round(101325.0 / (287.05 * 293.15), 3)
RAYMER_OSWALD = 1.78 * (1.0 - 0.045 * ASPECT_RATIO**0.68) - 0.64

# knob: (initial, lower, upper, prior mean or None, prior sd)
KNOBS = {
    "mass_kg": (22.0, 10.0, 45.0, None, None),
    "cd0": (0.03, 0.008, 0.08, 0.030, 0.008),
    "oswald_e": (RAYMER_OSWALD, 0.4, 1.0, RAYMER_OSWALD, 0.05),
    "cl_max": (1.4, 0.8, 2.2, 1.4, 0.15),
    "liftoff_speed_factor": (1.15, 1.0, 1.6, 1.15, 0.03),
    "rotation_time_s": (1.0, 0.0, 4.0, 1.0, 0.5),
    "throttle_shape": (0.0, -0.6, 1.0, None, None),
    "windmilling_cd": (0.5, 0.2, 2.0, 0.5, 0.2),
    "fan_efficiency": (0.7, 0.2, 1.0, None, None),
    "no_load_power_w": (100.0, 0.0, 2000.0, 100.0, 50.0),
    "jet_area_m2": (0.005, 0.002, 0.01, None, None),
}
NAMES = list(KNOBS)


def full_throttle_curve(points_n: tuple[float, float, float]) -> tuple[float, float, float]:
    """``(a, b, c)`` of ``T(1, v) = a + b v + c v^2`` through the three published points."""
    vandermonde = np.array([[1.0, v, v * v] for v in PUBLISHED_AIRSPEEDS_M_S])
    a, b, c = np.linalg.solve(vandermonde, np.array(points_n))
    return float(a), float(b), float(c)


def coefficients(points_n: tuple[float, float, float], shape: Any) -> dict[str, Any]:
    """poly22 with the published full-throttle curve and static thrust ``a (s x + (1-s) x^2)``."""
    a, b, c = full_throttle_curve(points_n)
    return {
        "p00": 0.0,
        "p10": shape * a,
        "p01": P01_N_PER_M_S,
        "p20": (1.0 - shape) * a,
        "p11": b - P01_N_PER_M_S,
        "p02": c,
    }


def electrical_power(thrust: Any, airspeed: Any, throttle: Any, k: dict[str, Any]) -> Any:
    """``P_el = P_i(T, V) / eta + L x`` at the test day's density [W]."""
    ideal = ideal_power_w(thrust, airspeed, REFERENCE_DENSITY_KG_M3, k["jet_area_m2"])
    return ideal / k["fan_efficiency"] + k["no_load_power_w"] * throttle


def aircraft_of(k: dict[str, Any]) -> Aircraft:
    return Aircraft(
        name="TU-Flex",
        mass_kg=k["mass_kg"],
        wing_area_m2=WING_AREA_M2,
        cd0=k["cd0"],
        k=1.0 / (math.pi * k["oswald_e"] * ASPECT_RATIO),
        cl_max=k["cl_max"],
        takeoff=TakeoffConfig(
            cl_ground=CL_GROUND,
            rolling_friction=ROLLING_FRICTION,
            liftoff_speed_factor=k["liftoff_speed_factor"],
            rotation_time_s=k["rotation_time_s"],
        ),
    )


def drag_n(k: dict[str, Any], v: Any) -> Any:
    """Level-flight drag at sea level [N] (Anderson eq. 2.47 with ``L = W``)."""
    q_s = 0.5 * RHO_SL * v * v * WING_AREA_M2
    cl = k["mass_kg"] * G0 / q_s
    return q_s * (k["cd0"] + cl * cl / (math.pi * k["oswald_e"] * ASPECT_RATIO))


def battery_parameters() -> tuple[Any, Any]:
    """The shipped battery file's fitted discharge model and the battery itself."""
    from tuflexperf.analysis.battery_fit import characterise_battery
    from tuflexperf.io.battery import load_battery
    from tuflexperf.io.case import load_case

    case = load_case(ROOT / "requirements" / "tuflex.yaml")
    battery = load_battery(case.battery_path)
    return characterise_battery(battery, case).fit.parameters, battery


def build_problem(launch_ah: float, climb_min: float) -> tuple[Any, Any, dict[str, Any]]:
    """The weighted least-squares NLP and a function of the named outputs."""
    w = ca.SX.sym("w", len(NAMES))
    k = {name: w[i] for i, name in enumerate(NAMES)}
    aircraft = aircraft_of(k)
    ratio = RHO_SL / REFERENCE_DENSITY_KG_M3
    coef = {e: coefficients(p, k["throttle_shape"]) for e, p in PUBLISHED_FULL_THROTTLE_N.items()}

    def thrust(engine: str, x: Any, v: Any, scale: Any = ratio) -> Any:
        return scale * poly22(x, v, coef[engine])

    extra, g, lbg, ubg, x0, lbx, ubx = [], [], [], [], [], [], []

    def variable(name: str, init: float, low: float, high: float) -> Any:
        sym = ca.SX.sym(name)
        extra.append(sym)
        x0.append(init)
        lbx.append(low)
        ubx.append(high)
        return sym

    def equal(expr: Any) -> None:
        g.append(expr)
        lbg.append(0.0)
        ubg.append(0.0)

    grid = np.arange(ENVELOPE_M_S[0], ENVELOPE_M_S[1] + 1e-9, 0.5)
    # least trim throttle: excess(x, V) <= 0 on the grid, = 0 at V (both engines)
    x_t = variable("x_trim", 0.41, 0.0, 1.0)
    v_t = variable("v_trim", 15.0, *ENVELOPE_M_S)

    def excess_trim(x: Any, v: Any) -> Any:
        return thrust("EDF1", x, v) + thrust("EDF2", x, v) - drag_n(k, v)

    equal(excess_trim(x_t, v_t))
    for v in grid:
        g.append(excess_trim(x_t, v))
        lbg.append(-ca.inf)
        ubg.append(0.0)
    # least one-engine throttle, EDF2 dead and windmilling (EDF1, the weaker, flies)
    x_o = variable("x_oei", 0.56, 0.0, 1.0)
    v_o = variable("v_oei", 20.0, *ENVELOPE_M_S)

    def excess_oei(x: Any, v: Any) -> Any:
        windmill = k["windmilling_cd"] * 0.5 * RHO_SL * v * v * k["jet_area_m2"]
        return thrust("EDF1", x, v) - windmill - drag_n(k, v)

    equal(excess_oei(x_o, v_o))
    for v in grid:
        g.append(excess_oei(x_o, v))
        lbg.append(-ca.inf)
        ubg.append(0.0)
    # ground roll: lift-off EAS = factor x stall (sea level: TAS = EAS), then rotation
    stall = ca.sqrt(2.0 * k["mass_kg"] * G0 / (RHO_SL * WING_AREA_M2 * k["cl_max"]))
    v_lo = k["liftoff_speed_factor"] * stall
    # published envelope 15-45 m/s: level flight at 15 m/s (true airspeed) stays above the
    # stall speed on a hot day too (ISA+20 K at sea level: stall TAS 3.5 % above ISA's)
    g.append(stall)
    lbg.append(0.0)
    ubg.append(ENVELOPE_M_S[0] * math.sqrt(288.15 / (288.15 + HOT_DAY_OFFSET_K)))
    nodes, weights = np.polynomial.legendre.leggauss(32)
    u = 0.5 * (nodes + 1.0)
    roll = 0.0
    for ui, wi in zip(u, weights, strict=True):
        v = ui * v_lo
        force = ground_roll_net_force_n(
            aircraft, thrust("EDF1", 1.0, v) + thrust("EDF2", 1.0, v), v, RHO_SL
        )
        roll = roll + 0.5 * wi * k["mass_kg"] * v * v_lo / force
    roll = roll + v_lo * k["rotation_time_s"]
    # one pack at 50 % and 30 m/s in the tunnel (test-day density: thrust as measured)
    params, battery = battery_parameters()
    p_tunnel = electrical_power(thrust("EDF1", 0.5, 30.0, 1.0), 30.0, 0.5, k)
    q_cut = variable("q_cut", 4.0, 0.05, params.max_capacity_ah * (1 - 1e-6))
    equal(cutoff_residual_v(params, q_cut, p_tunnel, battery.cutoff_voltage_v, 1))
    pack_min = discharge_time_s(params, p_tunnel, 0.0, q_cut, 1) / 60.0
    # flight at 50 %: the faster level-flight root, each fan on its packs to the reserve
    v_c = variable("v_cruise", 26.0, 18.0, 60.0)
    equal(excess_trim(0.5, v_c))
    g.append(ca.jacobian(excess_trim(0.5, v_c), v_c))  # front side: excess falls with speed
    lbg.append(-ca.inf)
    ubg.append(0.0)
    packs = battery.packs_in_parallel_per_engine
    reserve_ah = packs * battery.capacity_ah * (1.0 - battery.landing_reserve_fraction)
    p_cruise = 0.5 * sum(
        electrical_power(thrust(e, 0.5, v_c), v_c, 0.5, k) for e in PUBLISHED_FULL_THROTTLE_N
    )
    flight_min = discharge_time_s(params, p_cruise, launch_ah, reserve_ah, packs) / 60.0 + climb_min
    # Table 1 at this fan's static thrust (EDF1, test day)
    static_n = thrust("EDF1", 1.0, 0.0, 1.0)
    p_static = electrical_power(static_n, 0.0, 1.0, k)
    v_exit = exit_velocity_m_s(static_n, 0.0, REFERENCE_DENSITY_KG_M3, k["jet_area_m2"])
    efficiency = ideal_power_w(static_n, 0.0, REFERENCE_DENSITY_KG_M3, k["jet_area_m2"]) / p_static

    a_static = full_throttle_curve(PUBLISHED_FULL_THROTTLE_N["EDF1"])[0]
    published_power = published_static_power_w(a_static, POWER_RANGE_W, STATIC_THRUST_RANGE_N)
    t_low, t_high = STATIC_THRUST_RANGE_N
    v_low, v_high = EXIT_VELOCITY_RANGE_M_S
    published_exit = v_low + (a_static - t_low) / (t_high - t_low) * (v_high - v_low)
    targets = dict(TARGETS)
    targets["static_power_w"] = (published_power, TARGETS["static_power_w"][1])
    targets["static_exit_velocity_m_s"] = (published_exit, TARGETS["static_exit_velocity_m_s"][1])
    outputs = {
        "ground_roll_m": roll,
        "trim_min_throttle": x_t,
        "oei_min_throttle": x_o,
        "pack_minutes_50pct_30ms": pack_min,
        "flight_minutes": flight_min,
        "liftoff_eas_m_s": v_lo,
        "static_power_w": p_static,
        "static_exit_velocity_m_s": v_exit,
        "static_efficiency": efficiency,
        "tunnel_power_50pct_30ms_w": p_tunnel,
        "cruise_power_w": p_cruise,
        "cruise_airspeed_m_s": v_c,
        "stall_m_s": stall,
    }
    residuals = [(outputs[n] - value) / tol for n, (value, tol) in targets.items()]
    for name, (_, _, _, mean, sd) in KNOBS.items():
        if mean is not None:
            residuals.append((k[name] - mean) / sd)
    r = ca.vertcat(*residuals)
    z = ca.vertcat(w, *extra)
    nlp = {"x": z, "f": 0.5 * ca.dot(r, r), "g": ca.vertcat(*g)}
    solver = ca.nlpsol(
        "reconstruct", "ipopt", nlp,
        {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-10,
         "ipopt.max_iter": 3000},
    )
    report = ca.Function("report", [z], [ca.vertcat(*outputs.values()), r])
    start = [KNOBS[n][0] for n in NAMES] + x0
    bounds = (
        [KNOBS[n][1] for n in NAMES] + lbx,
        [KNOBS[n][2] for n in NAMES] + ubx,
    )
    return solver, report, {
        "start": start, "bounds": bounds, "lbg": lbg, "ubg": ubg, "outputs": list(outputs),
        "targets": targets,
    }


def solve(launch_ah: float, climb_min: float, start: list[float] | None = None):
    solver, report, meta = build_problem(launch_ah, climb_min)
    sol = solver(x0=start or meta["start"], lbx=meta["bounds"][0], ubx=meta["bounds"][1],
                 lbg=meta["lbg"], ubg=meta["ubg"])
    status = solver.stats()["return_status"]
    if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
        raise SystemExit(f"reconstruction did not converge: {status}")
    z = np.asarray(sol["x"]).ravel()
    values, residuals = (np.asarray(v).ravel() for v in report(z))
    knobs = dict(zip(NAMES, z[: len(NAMES)], strict=True))
    return knobs, dict(zip(meta["outputs"], values, strict=True)), residuals, meta, list(z)


# --- the power surface shipped in the propulsion file ------------------------------------------
def power_surface(engine: str, knobs: dict[str, float]) -> dict[str, float]:
    """poly22 in (throttle, airspeed) least-squares fitted to the electrical model [W].

    Fitted on the paper's test grid (0-30 m/s, throttle 0.1-1), as ``fit`` would from logs.
    """
    x, v = np.meshgrid(np.linspace(0.1, 1.0, 10), [0.0, 15.0, 20.0, 22.5, 25.0, 27.5, 30.0])
    x, v = x.ravel(), v.ravel()
    thrust = poly22(x, v, coefficients(PUBLISHED_FULL_THROTTLE_N[engine], knobs["throttle_shape"]))
    power = np.asarray(electrical_power(thrust, v, x, knobs), dtype=float)
    design = np.column_stack([np.ones_like(x), x, v, x * x, x * v, v * v])
    beta, *_ = np.linalg.lstsq(design, power, rcond=None)
    rms = float(np.sqrt(np.mean((design @ beta - power) ** 2)))
    names = ("p00", "p10", "p01", "p20", "p11", "p02")
    return {**{n: float(b) for n, b in zip(names, beta, strict=True)}, "_rms_w": rms}


def windmilling_on_disk(knobs: dict[str, float]) -> float:
    """The reconstructed ``Cd_wm`` (on the jet area) on the disk area: the same drag in N."""
    return knobs["windmilling_cd"] * knobs["jet_area_m2"] / FAN_AREA_M2


def render_propulsion(knobs: dict[str, float]) -> str:
    shape = knobs["throttle_shape"]
    dead_band = max(-shape / (1.0 - shape), 0.0)
    lines = [
        "# Reconstructed TU-Flex propulsion model; written by scripts/reconstruct_tuflex.py.",
        "# Provenance of every number: data/README.md. Full-throttle curve derived from the",
        "# paper's published points; p00, p01 estimated; the throttle shape",
        f"# (static thrust a (s x + (1 - s) x^2), s = {shape:.4f}"
        + (f", dead band to x = {dead_band:.3f}" if dead_band > 0 else "")
        + ") and the power model are from the over-determined least squares.",
        "name: Schuebeler DS-51-DIA HST",
        "model: poly22      # T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2 (x fraction, v m/s)",
        "tested_airspeed_m_s: [0, 30]   # published: tunnel limit 30 m/s",
        "delay_s: 0.05                  # published: sine sweep, paper section 4",
        f"reference_density_kg_m3: {REFERENCE_DENSITY_KG_M3}  # estimated test day: indoor tunnel, "
        "20 C, 1013 hPa",
        "format: 2                     # fan_area_m2 the disk area, jet_area_m2 the jet's",
        f"fan_area_m2: {FAN_AREA_M2:.6f}         # published: the 93 mm fan's disk (Table 1)",
        f"jet_area_m2: {knobs['jet_area_m2']:.6f}         # reconstructed jet area of momentum "
        "theory (Table 1 exit velocity)",
        "engines:",
    ]
    for engine, points in PUBLISHED_FULL_THROTTLE_N.items():
        c = coefficients(points, shape)
        surface = power_surface(engine, knobs)
        lines += [f"  - name: {engine}", "    coefficients:"]
        lines += [f"      {t}: {float(c[t]):.10g}" for t in ("p00", "p10", "p01", "p20", "p11", "p02")]
        grid = published_grid_uncertainty(0.5, PUBLISHED_EDGE_ERROR_N[engine])
        lines += ["    # derived: sigma^2 (X^T X)^-1 on the paper's 7 x 10 test grid, sigma = 0.5 N",
                  "    covariance:"]
        lines += [
            "      - [" + ", ".join(f"{c:.6g}" for c in row) + "]" for row in grid.covariance
        ]
        lines += [
            "    residual_sd_n: 0.5   # published accuracy +-0.5 N",
            f"    extrapolation_sd_n: {grid.extrapolation_sd_n:.4g}   # derived: max(leave-30-m/s-"
            f"out error, published error at 30 m/s {PUBLISHED_EDGE_ERROR_N[engine]:g} N)",
            # the knob is on the jet area; the file's coefficient is on the disk, same drag
            f"    windmilling_drag_coefficient: {windmilling_on_disk(knobs):.5f}   # reconstructed "
            f"{knobs['windmilling_cd']:.4f} on the jet area, restated on the disk",
            "    power:                       # W; P_i/eta + L x sampled on the test grid, poly22",
            "      model: poly22",
            f"      rmse_w: {surface['_rms_w']:.3f}",
            "      coefficients:",
        ]
        lines += [
            f"        {t}: {surface[t]:.10g}" for t in ("p00", "p10", "p01", "p20", "p11", "p02")
        ]
    return "\n".join(lines) + "\n"


def render_aircraft(knobs: dict[str, float], outputs: dict[str, float]) -> str:
    k = 1.0 / (math.pi * knobs["oswald_e"] * ASPECT_RATIO)
    return "\n".join([
        "# Reconstructed TU-Flex aircraft; written by scripts/reconstruct_tuflex.py.",
        "# Unpublished in the paper: every number is estimated or reconstructed (data/README.md).",
        "name: TU-Flex",
        f"mass_kg: {knobs['mass_kg']:.4f}          # reconstructed (least squares)",
        f"wing_area_m2: {WING_AREA_M2:g}            # estimated: 4 m span, AR {ASPECT_RATIO:.1f}",
        f"cd0: {knobs['cd0']:.5f}                 # reconstructed, prior 0.030 +- 0.008",
        f"k: {k:.6f}                  # 1/(pi e AR), e = {knobs['oswald_e']:.4f} reconstructed "
        f"(Raymer prior {RAYMER_OSWALD:.3f})",
        f"cl_max: {knobs['cl_max']:.4f}              # reconstructed, prior 1.4 +- 0.15; stall "
        f"{outputs['stall_m_s']:.2f} m/s at ISA SL",
        "takeoff:",
        f"  cl_ground: {CL_GROUND:g}               # estimated: ground attitude",
        f"  rolling_friction: {ROLLING_FRICTION:g}       # estimated: soft turf (Raymer Table 17.1)",
        f"  liftoff_speed_factor: {knobs['liftoff_speed_factor']:.4f}  # reconstructed, prior "
        "1.1-1.2 (Raymer 17.8.1)",
        f"  rotation_time_s: {knobs['rotation_time_s']:.4f}       # reconstructed, prior 1 +- 0.5 s",
    ]) + "\n"


# --- the landed analyses on the written files --------------------------------------------------
def landed_values() -> dict[str, float]:
    """Every published number recomputed by the tool's own analyses from the shipped files."""
    from tuflexperf.analysis.endurance import solve_endurance
    from tuflexperf.analysis.oei import solve_oei
    from tuflexperf.analysis.takeoff import solve_takeoff
    from tuflexperf.analysis.trim import solve_trim
    from tuflexperf.io.case import load_case
    from tuflexperf.models.agreement import power_agreement
    from tuflexperf.models.battery import time_to_cutoff_s
    from tuflexperf.models.powertrain import engine_power_w
    from tuflexperf.models.thrust import engine_thrust_n

    case = load_case(ROOT / "requirements" / "tuflex.yaml")
    takeoff = solve_takeoff(case)
    endurance = solve_endurance(case, 0.5)
    params, battery = battery_parameters()
    edf1 = case.propulsion.engines[0]
    # the tunnel run: EDF1's power surface at 50 %, 30 m/s (test day) on one pack
    tunnel_w = float(engine_power_w(edf1, 0.5, 30.0))
    pack_min = time_to_cutoff_s(params, tunnel_w, battery.cutoff_voltage_v, 1) / 60.0
    static = power_agreement(
        "static", edf1.name, 1.0, 0.0, float(engine_thrust_n(edf1, 1.0, 0.0)),
        float(engine_power_w(edf1, 1.0, 0.0)), REFERENCE_DENSITY_KG_M3,
        case.propulsion.jet_area_m2,  # Table 1's efficiency T v_e / 2 / P_el is on the jet
    )
    return {
        "pack_minutes_50pct_30ms": pack_min,
        "static_power_w": static.electrical_power_w,
        "static_exit_velocity_m_s": static.exit_velocity_m_s,
        "static_efficiency": static.figure_of_merit,
        "ground_roll_m": takeoff.ground_roll_m,
        "trim_min_throttle": float(solve_trim(case).min_throttle),
        "oei_min_throttle": float(solve_oei(case).critical.min_throttle),
        "flight_minutes": endurance.flight_endurance_min,
        "liftoff_eas_m_s": takeoff.liftoff_speed_eas_m_s,
        "launch_charge_ah": endurance.launch.charge_ah,
        "climb_min": endurance.launch.climb_time_s / 60.0,
        "endurance_power_w": endurance.electrical_power_w,
        "endurance_airspeed_m_s": endurance.airspeed_m_s,
        "endurance_warnings": list(endurance.warnings),
    }


def leave_out(names: list[str]) -> None:
    """Solve without the named published facts (tolerance x 1000) and print what follows.

    Shows which facts pull against which (data/README.md); writes nothing.
    """
    for name in names:
        value, tol = TARGETS[name]
        TARGETS[name] = (value, 1000.0 * tol)
    knobs, outputs, residuals, meta, _ = solve(0.31, 0.18)
    print(f"without {', '.join(names)}:")
    for i, (name, (value, _)) in enumerate(meta["targets"].items()):
        print(f"  {name:26s} {value:9.4g} {outputs[name]:10.4g} {residuals[i]:+9.2f}")
    print("  " + ", ".join(f"{n} {v:.4g}" for n, v in knobs.items()))


def main() -> None:
    import sys

    if len(sys.argv) > 2 and sys.argv[1] == "--without":
        leave_out(sys.argv[2].split(","))
        return
    launch_ah, climb_min = 0.31, 0.18
    start = None
    for _ in range(4):
        knobs, outputs, residuals, meta, start = solve(launch_ah, climb_min, start)
        (DATA / "propulsion.yaml").write_text(render_propulsion(knobs), "utf-8")
        (DATA / "aircraft.yaml").write_text(render_aircraft(knobs, outputs), "utf-8")
        landed = landed_values()
        moved = abs(landed["launch_charge_ah"] - launch_ah) + abs(landed["climb_min"] - climb_min)
        launch_ah, climb_min = landed["launch_charge_ah"], landed["climb_min"]
        if moved < 1e-4:
            break
    print("knobs:")
    for name, value in knobs.items():
        prior, sd = KNOBS[name][3], KNOBS[name][4]
        note = (f"(prior {prior:g} +- {sd:g}, residual {(value - prior) / sd:+.2f} sd)"
                if prior is not None else "(free)")
        print(f"  {name:22s} {value:10.4f} {note}")
    print(f"  reference density {REFERENCE_DENSITY_KG_M3} kg/m^3, Raymer e {RAYMER_OSWALD:.4f}")
    print("published value | tolerance | least squares | landed tool | residual (sd)")
    for i, (name, (value, tol)) in enumerate(meta["targets"].items()):
        tool = landed.get(name)
        tool_text = f"{tool:.4g}" if isinstance(tool, float) else "-"
        print(f"  {name:26s} {value:9.4g} {tol:7.3g} {outputs[name]:10.4g} {tool_text:>10s} "
              f"{residuals[i]:+7.2f}")
    print(f"  tunnel power at 50 %, 30 m/s: {outputs['tunnel_power_50pct_30ms_w']:.0f} W; cruise "
          f"{outputs['cruise_power_w']:.0f} W at {outputs['cruise_airspeed_m_s']:.2f} m/s")
    print(f"  landed endurance: {landed['endurance_power_w']:.0f} W at "
          f"{landed['endurance_airspeed_m_s']:.2f} m/s, warnings {landed['endurance_warnings']}")
    print(f"  cost {0.5 * float(np.dot(residuals, residuals)):.3f} over {len(residuals)} residuals, "
          f"{len(NAMES)} knobs")


if __name__ == "__main__":
    main()
