"""Discharge runs (SPEC 4 run format with voltage and current): read once, charge integrated.

The one reader of endurance runs; the pack model they feed lives in
:mod:`tuflexperf.models.battery` and its fit in :mod:`tuflexperf.reduction.battery`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.runs import RUN_COLUMNS, read_run
from tuflexperf.models.battery import SECONDS_PER_HOUR, SETTLE_S

DISCHARGE_COLUMNS: tuple[str, ...] = (*RUN_COLUMNS, "voltage_v", "current_a")
"""An endurance run is a run (SPEC 4) that logs the pack's voltage and current too."""


# --- discharge runs -------------------------------------------------------------------------
@dataclass(frozen=True)
class DischargeRun:
    """One endurance run (SPEC run format) with the charge drawn, integrated from the current."""

    path: Path
    time_s: np.ndarray
    force_n: np.ndarray
    airspeed_m_s: np.ndarray
    throttle: np.ndarray
    voltage_v: np.ndarray
    current_a: np.ndarray
    charge_ah: np.ndarray

    @property
    def loaded(self) -> np.ndarray:
        """Mask of the samples under load (throttle above zero)."""
        return self.throttle > 1e-6

    @property
    def load_window_s(self) -> tuple[float, float]:
        """Start and end time in s of the loaded segment (throttle on until the cut-off)."""
        t = self.time_s[self.loaded]
        return float(t[0]), float(t[-1])

    @property
    def time_to_cutoff_s(self) -> float:
        """Observed time under load from the throttle step to the cut-off, in s."""
        start, end = self.load_window_s
        return end - start

    def _settled(self) -> np.ndarray:
        start, _ = self.load_window_s
        return self.loaded & (self.time_s >= start + SETTLE_S)

    @property
    def throttle_setting(self) -> float:
        """Median throttle (fraction) under load."""
        return float(np.median(self.throttle[self._settled()]))

    @property
    def airspeed_setting_m_s(self) -> float:
        """Mean tunnel airspeed in m/s under load."""
        return float(np.mean(self.airspeed_m_s[self._settled()]))

    @property
    def mean_power_w(self) -> float:
        """Mean electrical power ``V I`` in W under load (spool-up left out)."""
        mask = self._settled()
        return float(np.mean(self.voltage_v[mask] * self.current_a[mask]))

    @property
    def mean_force_n(self) -> float:
        """Mean measured force in N under load (thrust less the rig's drag)."""
        return float(np.mean(self.force_n[self.loaded]))

    @property
    def start_charge_ah(self) -> float:
        """Charge in Ah drawn before the throttle step (idle current of the ESC)."""
        start, _ = self.load_window_s
        return float(np.interp(start, self.time_s, self.charge_ah))


def read_discharge_run(path: Path | str) -> DischargeRun:
    """Read an endurance run (.csv, .csv.gz or .mat) and integrate the charge drawn (trapezoid).

    Raises :class:`InputError` naming the file and column on missing columns, non-finite
    values, a time that does not increase, or a run with no loaded segment.
    """
    # the one run reader: .csv, .csv.gz and .mat alike, a few NaN samples repaired (noted)
    run = read_run(path, required=DISCHARGE_COLUMNS, optional=())
    columns, t, path = run.columns, run.time_s, run.path
    throttle = columns["throttle"]
    if not np.any(throttle > 1e-6):
        raise InputError(f"{path}: throttle: never above zero, no discharge under load")
    current = columns["current_a"]
    loaded = float(np.mean(current[throttle > 1e-6]))
    if not loaded > 0:  # a discharge draws current out of the pack
        raise InputError(f"{path}: current_a: mean {loaded:.3g} A under load; a discharge "
                         "draws a positive current (a sign or a unit slip?)")
    charge = np.concatenate(
        [[0.0], np.cumsum(0.5 * (current[1:] + current[:-1]) * np.diff(t))]
    ) / SECONDS_PER_HOUR
    return DischargeRun(
        path=path,
        time_s=t,
        force_n=columns["force_n"],
        airspeed_m_s=columns["airspeed_m_s"],
        throttle=throttle,
        voltage_v=columns["voltage_v"],
        current_a=current,
        charge_ah=charge,
    )


@dataclass(frozen=True)
class RunSummary:
    """What the analyses need of a discharge run, as ``fit`` stores it in the battery file.

    The same attribute names as :class:`DischargeRun`, so a fitted battery file serves
    ``check`` without reading (or fitting) its runs.
    """

    path: Path
    sha256: str
    throttle_setting: float
    airspeed_setting_m_s: float
    mean_power_w: float
    mean_force_n: float
    start_charge_ah: float
    time_to_cutoff_s: float
    charge_drawn_ah: float
