"""Write the shipped thrust-stand sample (data/samples/rcbenchmark/): SYNTHETIC data.

A small EDF on an RCbenchmark-style stand in a wind tunnel, logged at 20 Hz as the vendor's
software writes its CSV (``Time (s)``, ``ESC signal (µs)``, ``Thrust (kgf)`` logged with the
stand mounted backwards, i.e. negative, voltage, current, electrical rpm, power, text columns)
plus a hand-added ``Airspeed (m/s)`` column. Three runs at 0, 10 and 20 m/s, throttle steps of
0.2 held 3 s each. The thrust law, noise, dead time (0.05 s) and spool lag (0.08 s) are below;
nothing here is measured. Run: ``python scripts/make_rcbenchmark_sample.py``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "data" / "samples" / "rcbenchmark"
G0 = 9.80665
TRUTH = {"p00": 0.1, "p10": 2.0, "p01": -0.05, "p20": 11.0, "p11": -0.12, "p02": 0.0003}
RATE_HZ = 20.0
DELAY_S, LAG_S = 0.05, 0.08
HEADER = (
    "Time (s),ESC signal (µs),Servo 1 (µs),AccX (g),Torque (N·m),Thrust (kgf),Voltage (V),"
    "Current (A),Motor Electrical Speed (RPM),Electrical Power (W),Mechanical Power (W),"
    "App message,Airspeed (m/s)"
)


def thrust_n(x: np.ndarray, v: float) -> np.ndarray:
    c = TRUTH
    return c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x**2 + c["p11"] * x * v + c[
        "p02"] * v**2


def run(airspeed: float, seed: int) -> str:
    rng = np.random.default_rng(seed)
    levels = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 0.0]
    hold = int(3 * RATE_HZ)
    throttle = np.repeat(levels, hold)
    t = np.arange(throttle.size) / RATE_HZ
    # 1 kHz internal simulation of dead time + lag, sampled at the logging rate
    fine = 50
    xs = np.repeat(throttle, fine)
    dt = 1 / (RATE_HZ * fine)
    shift = round(DELAY_S / dt)
    delayed = np.concatenate([np.full(shift, xs[0]), xs[:-shift]])
    static = thrust_n(delayed, airspeed)
    a = math.exp(-dt / LAG_S)
    y = np.empty_like(static)
    acc = static[0]
    for k, s in enumerate(static):
        acc = a * acc + (1 - a) * s
        y[k] = acc
    force = y[::fine] + rng.normal(0, 0.03, t.size)
    v = airspeed + rng.normal(0, 0.05, t.size) if airspeed > 0 else np.zeros(t.size)
    volts = 16.6 - 0.0005 * t - 0.15 * throttle + rng.normal(0, 0.01, t.size)
    amps = 0.3 + 38 * throttle**1.6 + rng.normal(0, 0.05, t.size)
    rpm = 30000 * np.sqrt(throttle)
    lines = [HEADER]
    for k in range(t.size):
        kgf = -force[k] / G0  # the stand logs pull as negative
        lines.append(
            f"{t[k]:.3f},{1000 + 1000 * throttle[k]:.0f},1500,{rng.normal(0, .02):.4f},"
            f"{-0.01 * force[k]:.5f},{kgf:.6f},{volts[k]:.3f},{amps[k]:.3f},{rpm[k]:.0f},"
            f"{volts[k] * amps[k]:.2f},,{'Tare done' if k == 0 else ''},{v[k]:.3f}"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for seed, airspeed in enumerate((0.0, 10.0, 20.0)):
        (OUT / f"stand_v{airspeed:02.0f}.csv").write_text(run(airspeed, seed), encoding="utf-8")


if __name__ == "__main__":
    main()
