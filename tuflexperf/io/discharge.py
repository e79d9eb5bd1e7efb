"""Discharge runs (SPEC 4 run format with voltage and current): read once, charge integrated.

The one reader of endurance runs; the pack model they feed lives in
:mod:`tuflexperf.models.battery` and its fit in :mod:`tuflexperf.reduction.battery`.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.models.battery import (
    RUN_COLUMNS,
    SECONDS_PER_HOUR,
    SETTLE_S,
)


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


def _read_columns(path: Path) -> dict[str, np.ndarray]:
    if path.suffix.lower() == ".mat":
        from scipy.io import loadmat  # lazy: only .mat runs need SciPy

        try:
            raw = loadmat(path, squeeze_me=True)
        except Exception as exc:  # noqa: BLE001 - any reader failure is bad input
            raise InputError(f"{path}: cannot read MATLAB file: {exc}") from None
        columns: dict[str, np.ndarray] = {}
        for key, value in raw.items():
            if key.startswith("__") or key not in RUN_COLUMNS:
                continue
            try:
                columns[key] = np.atleast_1d(np.asarray(value, dtype=float))
            except (TypeError, ValueError):
                raise InputError(f"{path}: {key}: not numbers (a text column?)") from None
        return columns
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            header = next(csv.reader(handle), None)
            if header is None:
                raise InputError(f"{path}: empty file, expected a header row")
            data = np.loadtxt(handle, delimiter=",", ndmin=2)
    except InputError:
        raise
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read run data: {str(exc).splitlines()[0]}") from None
    names = [h.strip() for h in header]
    if data.shape[1] != len(names):
        raise InputError(f"{path}: {data.shape[1]} columns of data for {len(names)} header names")
    return {name: data[:, j] for j, name in enumerate(names)}


def read_discharge_run(path: Path | str) -> DischargeRun:
    """Read an endurance run (CSV or MATLAB v5) and integrate the charge drawn (trapezoid).

    Raises :class:`InputError` naming the file and column on missing columns, non-finite
    values, a time that does not increase, or a run with no loaded segment.
    """
    from tuflexperf.io.files import MAX_RUN_BYTES, check_input_file

    path = check_input_file(path, "run file", MAX_RUN_BYTES)
    columns = _read_columns(path)
    missing = [c for c in RUN_COLUMNS if c not in columns]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)} (endurance run)")
    n = columns["time_s"].size
    for name in RUN_COLUMNS:
        values = columns[name]
        if values.size != n:
            raise InputError(f"{path}: {name}: {values.size} values for {n} times")
        if not np.all(np.isfinite(values)):
            raise InputError(f"{path}: {name}: contains NaN or infinite values")
    if n < 10:
        raise InputError(f"{path}: only {n} samples; an endurance run needs more")
    t = columns["time_s"]
    if np.any(np.diff(t) <= 0):
        raise InputError(f"{path}: time_s: must increase strictly")
    throttle = columns["throttle"]
    if np.any((throttle < 0) | (throttle > 1)):
        raise InputError(f"{path}: throttle: values outside [0, 1] (fractions expected)")
    if not np.any(throttle > 1e-6):
        raise InputError(f"{path}: throttle: never above zero, no discharge under load")
    if np.any(columns["voltage_v"] <= 0):
        raise InputError(f"{path}: voltage_v: must be positive")
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

    def to_dict(self, relative_to: Path) -> dict[str, object]:
        import os

        return {
            "file": os.path.relpath(self.path, relative_to),
            "sha256": self.sha256,
            "throttle": self.throttle_setting,
            "airspeed_m_s": self.airspeed_setting_m_s,
            "mean_power_w": self.mean_power_w,
            "mean_force_n": self.mean_force_n,
            "start_charge_ah": self.start_charge_ah,
            "time_to_cutoff_s": self.time_to_cutoff_s,
            "charge_drawn_ah": self.charge_drawn_ah,
        }


def summarise_run(run: DischargeRun) -> RunSummary:
    """The stored summary of a discharge run (with its file's sha256)."""
    from tuflexperf.io.files import sha256_of

    return RunSummary(
        path=run.path, sha256=sha256_of(run.path), throttle_setting=run.throttle_setting,
        airspeed_setting_m_s=run.airspeed_setting_m_s, mean_power_w=run.mean_power_w,
        mean_force_n=run.mean_force_n, start_charge_ah=run.start_charge_ah,
        time_to_cutoff_s=run.time_to_cutoff_s, charge_drawn_ah=float(run.charge_ah[-1]),
    )
