"""Reconstruct the TU-Flex battery discharge runs (data/tuflex/endurance/*.csv).

The paper (section 3 and 4) ran one SLS Quantum 12S 5000 mAh pack on EDF1 in the
tunnel at 30 m/s, at 50 % and at 75 % throttle, "until a fully charged battery was
discharged", and reports only that a pack "lasts nearly up to 10 min" at 50 %.
The logs are not published, so they are simulated here from a documented "true"
pack and fan, seeded, at 10 Hz (a 10-minute run is ~6000 rows):

Pack (per cell, x12 in series; typical 5 Ah, 40C LiPo values, estimated):
    open-circuit voltage ``E0 - G q + A exp(-B q) - K q/(Q - q)`` with
    E0 = 4.05 V, G = 0.06 V/Ah, A = 0.12 V, B = 3.0 /Ah, K = 0.02 V, Q = 5.25 Ah
    (4.17 V full, ~3.88 V at half charge, knee below ~10 % left);
    ohmic resistance 2.5 mOhm per cell + 10 mOhm leads and connectors, rising by up
    to 30 % near empty (``R (1 + 0.3 (q/Q)^3)``), and one RC polarisation branch
    (12 mOhm, 30 s) that the fitted model does not have -- so the fit error is real.
Fan: an rpm-governed ESC holds the fan's electrical power at a throttle setting,
    ``P = P_s x^n (1 - (V/V_j)^2)`` (see tuflexperf.models.battery.FanPowerModel),
    ``P_s`` from the published 2.4-4.1 kW / 41-59 N range at EDF1's modelled static
    thrust; ``n`` is *calibrated* so the 50 % run reaches the cut-off after 9.7 min
    ("nearly 10 min"), and the 75 % run follows the same law. The ESC draws 0.25 A
    idle; power follows a throttle step with a 0.2 s lag.
Run: 10 s idle, throttle step, run until the loaded voltage reaches the cut-off of
    battery.yaml (3.4 V/cell), throttle cut, 20 s idle (voltage recovery).
Force: the shipped propulsion model (EDF1) at the throttle and airspeed minus the
    test structure's drag ``0.5 rho V^2 CdA``, CdA = 0.0015 m^2 (estimated, ~0.8 N at
    30 m/s), rho = 1.225 kg/m^3.
Noise (Gaussian, seeded): force 0.4 N (vibration), airspeed 0.1 m/s, voltage 0.02 V,
    current 0.2 A.

Run: ``.venv/bin/python scripts/generate_discharge.py`` (rewrites the CSV files and
prints the calibration).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from tuflexperf.io.battery import BatterySchema
from tuflexperf.io.case import load_propulsion
from tuflexperf.io.files import atomic_write_text
from tuflexperf.io.yamlio import load_model
from tuflexperf.models.battery import (
    FanPowerModel,
    published_static_power_w,
)
from tuflexperf.models.thrust import engine_thrust_n

ROOT = Path(__file__).resolve().parent.parent
BATTERY = ROOT / "data" / "tuflex" / "battery.yaml"
PROPULSION = ROOT / "data" / "tuflex" / "propulsion.yaml"
OUT = ROOT / "data" / "tuflex" / "endurance"

SEED = 20230509
SAMPLE_RATE_HZ = 10.0
SIM_STEP_S = 0.01
AIRSPEED_M_S = 30.0
RUN_THROTTLES = (0.50, 0.75)
TARGET_50_S = 9.7 * 60.0  # "nearly 10 min" (paper section 4)
IDLE_BEFORE_S = 10.0
IDLE_AFTER_S = 20.0
IDLE_CURRENT_A = 0.25
SPOOL_LAG_S = 0.2
RHO_KG_M3 = 1.225
STRUCTURE_CDA_M2 = 0.0015
NOISE = {"force_n": 0.4, "airspeed_m_s": 0.1, "voltage_v": 0.02, "current_a": 0.2}

# "True" pack, per cell (see docstring).
CELL = {"e0": 4.05, "g": 0.06, "a": 0.12, "b": 3.0, "k": 0.02, "q": 5.25}
R_CELL_OHM, R_LEADS_OHM, R_RISE = 0.0025, 0.010, 0.3
RC_OHM, RC_TAU_S = 0.012, 30.0


def true_ocv_v(q_ah: float, cells: int) -> float:
    c = CELL
    per_cell = c["e0"] - c["g"] * q_ah + c["a"] * math.exp(-c["b"] * q_ah) - c["k"] * q_ah / (
        c["q"] - q_ah
    )
    return cells * per_cell


def true_resistance_ohm(q_ah: float, cells: int) -> float:
    return (cells * R_CELL_OHM + R_LEADS_OHM) * (1.0 + R_RISE * (q_ah / CELL["q"]) ** 3)


def simulate(power_w: float, cells: int, cutoff_v: float, max_s: float = 3600.0) -> dict:
    """Noise-free run at constant loaded power; returns fine-step histories."""
    t, q, v_rc, p_now = 0.0, 0.0, 0.0, 0.0
    out = {k: [] for k in ("t", "v", "i", "p", "on")}
    loaded, cut_time = True, None
    while True:
        on = loaded and t >= IDLE_BEFORE_S
        target = power_w if on else 0.0
        p_now += (target - p_now) * min(1.0, SIM_STEP_S / SPOOL_LAG_S)
        ocv, r = true_ocv_v(q, cells) - v_rc, true_resistance_ohm(q, cells)
        if on:
            disc = max(ocv * ocv - 4.0 * r * p_now, 0.0)
            i = 2.0 * p_now / (ocv + math.sqrt(disc)) + IDLE_CURRENT_A
        else:
            i = IDLE_CURRENT_A
        v = ocv - r * i
        for key, value in zip(("t", "v", "i", "p", "on"), (t, v, i, p_now, on), strict=True):
            out[key].append(value)
        if on and t > IDLE_BEFORE_S + 1.0 and v <= cutoff_v:
            loaded, cut_time = False, t  # the ESC's low-voltage cut-off trips
        if cut_time is not None and t >= cut_time + IDLE_AFTER_S:
            break
        if t > max_s:
            raise RuntimeError("run did not reach the cut-off")
        q += i * SIM_STEP_S / 3600.0
        v_rc += (RC_OHM * i - v_rc) * SIM_STEP_S / RC_TAU_S
        t += SIM_STEP_S
    hist = {k: np.array(v) for k, v in out.items()}
    hist["cut_time_s"] = cut_time
    return hist


def loaded_time_s(power_w: float, cells: int, cutoff_v: float) -> float:
    return simulate(power_w, cells, cutoff_v)["cut_time_s"] - IDLE_BEFORE_S


def render(throttle: float, hist: dict, engine, rng: np.random.Generator) -> str:
    step = int(round(1.0 / (SAMPLE_RATE_HZ * SIM_STEP_S)))
    t = hist["t"][::step]
    on = hist["on"][::step]
    throttle_col = np.where(on, throttle, 0.0)
    airspeed = AIRSPEED_M_S + rng.normal(0.0, NOISE["airspeed_m_s"], t.size)
    # Force follows the commanded throttle through the same 0.2 s lag as the power.
    lagged = np.interp(t, hist["t"], hist["p"]) / max(hist["p"].max(), 1e-9) * throttle
    thrust = np.asarray(engine_thrust_n(engine, lagged, AIRSPEED_M_S), dtype=float)
    drag = 0.5 * RHO_KG_M3 * AIRSPEED_M_S**2 * STRUCTURE_CDA_M2
    force = thrust - drag + rng.normal(0.0, NOISE["force_n"], t.size)
    voltage = hist["v"][::step] + rng.normal(0.0, NOISE["voltage_v"], t.size)
    current = hist["i"][::step] + rng.normal(0.0, NOISE["current_a"], t.size)
    lines = ["time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a"]
    for row in zip(t, force, airspeed, throttle_col, voltage, current, strict=True):
        lines.append("{:.1f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f}".format(*row))
    return "\n".join(lines) + "\n"


def main() -> None:
    # The schema only: the run files this script writes need not exist yet.
    battery = load_model(BATTERY, BatterySchema)
    fan = battery.fan_power
    engine = load_propulsion(PROPULSION).engines[0]  # EDF1
    cells = battery.cells_in_series
    cutoff_v = cells * battery.cutoff_voltage_per_cell_v
    static_n = float(engine_thrust_n(engine, 1.0, 0.0))
    p_static = published_static_power_w(
        static_n, tuple(fan.published_power_range_w), tuple(fan.published_static_thrust_range_n)
    )
    factor = 1.0 - (AIRSPEED_M_S / fan.jet_velocity_m_s) ** 2
    p50 = brentq(lambda p: loaded_time_s(p, cells, cutoff_v) - TARGET_50_S, 300.0, 3000.0,
                 xtol=0.01)
    exponent = math.log(p50 / (p_static * factor)) / math.log(0.5)
    law = FanPowerModel(p_static, exponent, fan.jet_velocity_m_s)
    print(f"EDF1 static thrust {static_n:.2f} N -> full-throttle static power {p_static:.0f} W")
    print(f"50 % power calibrated to {p50:.1f} W -> throttle exponent n = {exponent:.4f}")
    OUT.mkdir(parents=True, exist_ok=True)
    for index, throttle in enumerate(RUN_THROTTLES):
        power = float(law.electrical_power_w(throttle, AIRSPEED_M_S))
        hist = simulate(power, cells, cutoff_v)
        rng = np.random.default_rng(SEED + index)
        path = OUT / f"edf1_endurance_{round(throttle * 100):d}.csv"
        atomic_write_text(path, render(throttle, hist, engine, rng))
        loaded = hist["cut_time_s"] - IDLE_BEFORE_S
        print(f"{path.relative_to(ROOT)}: {throttle:.2f} throttle, {power:.1f} W, "
              f"cut-off after {loaded:.1f} s ({loaded / 60:.2f} min)")


if __name__ == "__main__":
    main()
