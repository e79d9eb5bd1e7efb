"""A made-up fixed-wing flight as pyulog's ``ulog2csv`` writes it (no public, permissively
licensed fixed-wing log with airspeed and battery current was found to ship; see
tests/data/flightlogs/README.md). Each topic on its own clock, as a real log has them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

LEGS_M_S = (17.0, 20.0, 23.0, 26.0, 29.0)  # level legs, calibrated airspeed [m/s]
LEG_S = 60.0
TAKEOFF_S, CLIMB_S, DESCENT_S = 20.0, 15.0, 20.0  # on the ground before, climb, descent


def flown_power_w(v: np.ndarray) -> np.ndarray:
    """The made-up flight's electrical power [W] at calibrated airspeed ``v`` [m/s]."""
    return 1350.0 + 60.0 * (v - 18.0) + 9.0 * (v - 18.0) ** 2


def write_flight(folder: Path, seed: int = 7) -> Path:
    """Write the flight's CSVs into ``folder``: airspeed at 10 Hz, battery at 4.7 Hz (another
    clock), baro at 8 Hz, throttle at 20 Hz, land detector events; returns ``folder``."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    end = TAKEOFF_S + CLIMB_S + LEG_S * len(LEGS_M_S) + DESCENT_S + 15.0

    def speed(t: np.ndarray) -> np.ndarray:
        legs = np.interp(t, [TAKEOFF_S, TAKEOFF_S + CLIMB_S], [0.0, LEGS_M_S[0]])
        for k, v in enumerate(LEGS_M_S):
            start = TAKEOFF_S + CLIMB_S + k * LEG_S
            legs = np.where((t >= start) & (t < start + LEG_S), v, legs)
        down = TAKEOFF_S + CLIMB_S + len(LEGS_M_S) * LEG_S
        return np.where(t >= down, np.interp(t, [down, down + DESCENT_S], [LEGS_M_S[-1], 0.0]),
                        legs)

    def height(t: np.ndarray) -> np.ndarray:
        down = TAKEOFF_S + CLIMB_S + len(LEGS_M_S) * LEG_S
        return np.interp(t, [TAKEOFF_S, TAKEOFF_S + CLIMB_S, down, down + DESCENT_S],
                         [0.0, 60.0, 60.0, 0.0])

    def save(topic: str, frame: pd.DataFrame) -> None:
        frame.to_csv(folder / f"made_up_{topic}_0.csv", index=False)

    ta = np.arange(0.0, end, 0.1)
    va = speed(ta) + rng.normal(0.0, 0.2, ta.size)
    save("airspeed_validated", pd.DataFrame({"timestamp": (ta * 1e6).astype(np.int64),
                                             "calibrated_airspeed_m_s": va}))
    tb = np.arange(0.05, end, 1 / 4.7)
    power = np.where(speed(tb) > 1.0, flown_power_w(speed(tb)), 15.0)
    power = power + rng.normal(0.0, 20.0, tb.size)
    volts = 46.0 - 4.0 * tb / end
    current = power / volts
    save("battery_status", pd.DataFrame({
        "timestamp": (tb * 1e6).astype(np.int64), "voltage_v": volts, "current_a": current,
        "discharged_mah": 120.0 + np.cumsum(current) / 4.7 / 3.6}))
    tp = np.arange(0.02, end, 0.125)
    altitude = 80.0 + height(tp) + rng.normal(0.0, 0.1, tp.size)
    save("vehicle_air_data", pd.DataFrame({
        "timestamp": (tp * 1e6).astype(np.int64), "baro_alt_meter": altitude,
        "baro_pressure_pa": 101325.0 * (1 - 2.25577e-5 * altitude) ** 5.25588,
        "baro_temp_celcius": np.full(tp.size, 18.0)}))
    tt = np.arange(0.01, end, 0.05)
    throttle = np.clip(np.where(speed(tt) > 1.0, 0.2 + 0.012 * speed(tt), 0.0)
                       + rng.normal(0.0, 0.01, tt.size), 0.0, 1.0)
    save("actuator_controls_0", pd.DataFrame({"timestamp": (tt * 1e6).astype(np.int64),
                                              "control[3]": throttle}))
    down = TAKEOFF_S + CLIMB_S + len(LEGS_M_S) * LEG_S + DESCENT_S
    save("vehicle_land_detected", pd.DataFrame({
        "timestamp": (np.array([0.0, TAKEOFF_S + 3.0, down - 1.0]) * 1e6).astype(np.int64),
        "landed": [1, 0, 1]}))
    return folder
