"""The rig's systematic errors (issue 44 item 1) as ``fit`` writes them: declared, estimated
from the campaign's repeated holds, or the stated defaults.

What repeated holds can tell: each throttle-step run holds throttle 0 at its start and at its
end (paper section 3); their difference is how far the balance's zero moved during the run, so
``balance_zero_sd_n`` is estimated as ``rms(end - start) / sqrt(2)`` over the runs (the holds'
own noise included: an upper bound of the drift, never 0), after taking off what the fitted
model expects between the two holds from their airspeed and pack voltage (a windmilling fan's
drag moves with both). The tunnel's airspeed calibration,
the balance's scale and the voltmeter's calibration are common to every hold of a campaign:
no repeat measures them, so they are declared or take the defaults (said which).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.schemas import (
    RIG_UNCERTAINTY_DEFAULTS,
    RigUncertaintySchema,
    rig_uncertainty_problems,
)

# Fewest runs with an idle hold at both ends that estimate the zero's drift (two runs give
# one number per run: a standard deviation of two values is no estimate)
MIN_ZERO_DRIFT_RUNS = 3
# Idle throttle [fraction]: a hold at or below this is the balance's zero
IDLE_THROTTLE = 0.005
# A declared sd this many times below the one the runs measure is probably too small: said
DECLARED_BELOW_MEASURED = 3.0


@dataclass(frozen=True)
class RigUncertainty:
    """The four standard deviations ``fit`` writes, where each came from, and the estimates."""

    values: dict[str, float]
    basis: dict[str, str]  # key -> "declared" | "estimated" | "default"
    estimates: dict[str, dict[str, Any]]  # key -> {"value", "runs"}: what the runs measured
    notes: tuple[str, ...]
    correlation: list[list[float]] | None = None  # as declared (None: independent)

    def document(self) -> dict[str, Any]:
        """The propulsion file's ``rig_uncertainty`` block."""
        block: dict[str, Any] = {key: float(value) for key, value in self.values.items()}
        if self.correlation is not None:
            block["correlation"] = [[float(c) for c in row] for row in self.correlation]
        return block

    def summary(self) -> dict[str, Any]:
        return {"values": dict(self.values), "basis": dict(self.basis),
                "estimates": dict(self.estimates),
                "defaults": dict(RIG_UNCERTAINTY_DEFAULTS)}


def zero_drift_n(drifts: Sequence[float]) -> tuple[float, int]:
    """``rms(drift) / sqrt(2)`` [N] of the runs' idle-hold drifts (end minus start, less the
    model's expected change; module docstring) and the number of runs (NaN, 0: fewer than
    :data:`MIN_ZERO_DRIFT_RUNS`)."""
    if len(drifts) < MIN_ZERO_DRIFT_RUNS:
        return math.nan, 0
    return float(np.sqrt(np.mean(np.square(drifts)) / 2.0)), len(drifts)


def rig_uncertainty(
    where: str, declared: RigUncertaintySchema | None,
    idle_drifts_n: Sequence[float], largest_airspeed_m_s: float,
    largest_thrust_n: float, voltage_v: float | None,
) -> RigUncertainty:
    """The campaign's rig block (module docstring).

    Raises
    ------
    InputError
        Where a declared sd is larger than the quantity it is an error of (naming the key).
    """
    rig = declared or RigUncertaintySchema()
    problems = rig_uncertainty_problems(rig, largest_airspeed_m_s, largest_thrust_n, voltage_v)
    if problems:
        raise InputError("\n".join(f"{where}: {p}" for p in problems))
    values = rig.resolved()
    basis = {key: "declared" if key in rig.declared() else "default" for key in values}
    estimates: dict[str, dict[str, Any]] = {}
    notes: list[str] = []
    drift, runs = zero_drift_n(idle_drifts_n)
    if runs:
        estimates["balance_zero_sd_n"] = {"value": drift, "runs": runs}
        if basis["balance_zero_sd_n"] == "default":
            values["balance_zero_sd_n"] = drift
            basis["balance_zero_sd_n"] = "estimated"
        elif values["balance_zero_sd_n"] * DECLARED_BELOW_MEASURED < drift:
            notes.append(f"{where}: rig_uncertainty.balance_zero_sd_n: declared "
                         f"{values['balance_zero_sd_n']:g} N, but the balance's zero moved by "
                         f"{drift:.3g} N rms during the runs ({runs} runs' idle holds)")
    defaulted = [key for key, b in basis.items() if b == "default"]
    if defaulted:
        notes.append("rig uncertainty not declared in the manifest, stated defaults used: "
                     + ", ".join(f"{key} {values[key]:g}" for key in defaulted)
                     + " (docs/formats.md, campaign manifest)")
    return RigUncertainty(values, basis, estimates, tuple(notes), rig.correlation)
