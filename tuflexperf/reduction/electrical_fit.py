"""The electrical side of a campaign fit (step 7 of :mod:`.pipeline`).

Where the step runs log voltage and current: the voltage exponent, each engine's electrical
power surface and how the thrust and power surfaces agree with momentum theory (on the disk
area). Whatever is logged: the windmilling drag from the throttle-0 holds.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.campaign import Campaign
from tuflexperf.models.powertrain import WORKING_THRUST_SHARE
from tuflexperf.models.thrust import DEFAULT_VOLTAGE_EXPONENT
from tuflexperf.reduction.poly22fit import Poly22Fit
from tuflexperf.reduction.power import (
    VoltageFit,
    WindmillingFit,
    fit_power_surface,
    fit_voltage_exponent,
    fit_windmilling,
)
from tuflexperf.reduction.step_runs import Point, StepRunResult, finite_or_none, rounded

ELECTRICAL_COLUMNS = ("voltage_v", "current_a")


# --- electrical: voltage effect, power surface, windmilling (module docstring, step 7) -------
def electrical_means(result: StepRunResult, members: tuple[int, ...]) -> tuple[float, float, float]:
    """Sample-weighted mean pack voltage (V), current (A) and ``U I`` (W) of a test point.

    ``nan`` for all three when the run does not log both columns.
    """
    data = result.data
    if not all(name in data.columns for name in ELECTRICAL_COLUMNS):
        return math.nan, math.nan, math.nan
    volts, amps = [], []
    for member in members:
        segment = result.segments[member]
        volts.append(data["voltage_v"][segment.start : segment.stop])
        amps.append(data["current_a"][segment.start : segment.stop])
    u, i = np.concatenate(volts), np.concatenate(amps)
    ok = np.isfinite(u) & np.isfinite(i)
    if not np.any(ok):
        return math.nan, math.nan, math.nan
    return (
        rounded(float(np.mean(u[ok]))),
        rounded(float(np.mean(i[ok]))),
        rounded(float(np.mean(u[ok] * i[ok]))),
    )


@dataclass
class ElectricalFits:
    """What the logged voltage and current give, per engine (empty when nothing is logged)."""

    reference_voltage_v: float | None = None
    voltage: dict[str, VoltageFit] = field(default_factory=dict)
    power: dict[str, Poly22Fit] = field(default_factory=dict)
    windmilling: dict[str, WindmillingFit] = field(default_factory=dict)
    agreement: dict[str, dict[str, Any]] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    @property
    def exponent(self) -> float | None:
        """One exponent for the file: the mean over the engines whose runs determine it
        (None if none does: then the SPEC default applies)."""
        fits = [f for f in self.voltage.values() if f.identified]
        if not fits:
            return None
        return float(np.mean([f.exponent for f in fits]))

    def summary(self) -> dict[str, Any]:
        return {
            "reference_voltage_v": self.reference_voltage_v,
            "voltage_exponent": self.exponent,
            "voltage_fits": {name: f.to_dict() for name, f in self.voltage.items()},
            "power": {
                name: {"r2": finite_or_none(f.r2), "rmse_w": finite_or_none(f.rmse_n),
                       "n_points": f.n_points}
                for name, f in self.power.items()
            },
            "windmilling": {name: f.to_dict() for name, f in self.windmilling.items()},
            "thrust_power_agreement": self.agreement,
        }


def electrical_fits(
    campaign: Campaign, engines: list[str], points: list[Point],
    pool: ThreadPoolExecutor | None = None,
) -> ElectricalFits:
    """Voltage exponent, power surface and windmilling drag per engine (module docstring, 7).

    With a determined voltage exponent every point's ``thrust_n`` is brought to the
    reference voltage in place (``T (U_ref / U)^n``), so the poly22 holds at ``U_ref``.
    The engines' exponent profiles (independent, ~300 least squares each) run on ``pool``
    when one is given.
    """
    out = ElectricalFits()
    logged = [p for p in points if math.isfinite(p.voltage_v) and p.voltage_v > 0]
    if logged:
        # the voltage the full-throttle thrust was measured at (mean over those points, to
        # 0.1 V), else over the thrusting points: where a published maximum thrust holds
        full = [p.voltage_v for p in logged if p.throttle >= 0.95]
        thrusting = [p.voltage_v for p in logged if p.thrust_n > 0]
        chosen = full or thrusting or [p.voltage_v for p in logged]
        out.reference_voltage_v = round(float(np.mean(chosen)), 1)
    reference = out.reference_voltage_v

    def voltage_fit(mine: list[Point], reference_v: float) -> VoltageFit:
        # idle points carry no thrust to scale: the exponent is fitted on thrusting ones
        fit_pts = [p for p in mine if p.throttle > 1e-3]
        return fit_voltage_exponent(
            [p.throttle for p in fit_pts],
            [p.airspeed_m_s for p in fit_pts],
            [p.thrust_n for p in fit_pts],
            [p.voltage_v for p in fit_pts],
            reference_v,
        )

    by_engine = {engine: [p for p in points if p.engine == engine] for engine in engines}
    logged_all = {
        engine: all(math.isfinite(p.voltage_v) and p.voltage_v > 0 for p in mine)
        for engine, mine in by_engine.items()
    }
    pending = {
        engine: pool.submit(voltage_fit, by_engine[engine], reference)
        for engine in engines if pool is not None and reference is not None and logged_all[engine]
    }
    unlogged: list[str] = []
    for engine in engines:
        mine = by_engine[engine]
        label = f"{campaign.path}: engine {engine}"
        with_volts = [p for p in mine if math.isfinite(p.voltage_v) and p.voltage_v > 0]
        if out.reference_voltage_v is not None and len(with_volts) == len(mine):
            out.voltage[engine] = (pending[engine].result() if engine in pending
                                   else voltage_fit(mine, out.reference_voltage_v))
        elif out.reference_voltage_v is not None:
            unlogged.append(f"engine {engine} ({len(with_volts)} of {len(mine)} points)")
        with_power = [p for p in mine if math.isfinite(p.electrical_power_w)]
        if len(with_power) >= 6:
            try:
                out.power[engine] = fit_power_surface(
                    [p.throttle for p in with_power],
                    [p.airspeed_m_s for p in with_power],
                    [p.electrical_power_w for p in with_power],
                    label=label,
                )
            except InputError as exc:
                out.warnings.append(f"no power surface: {exc}")
    if unlogged:
        # one reference voltage and exponent hold for every engine of the file: the thrust of
        # an engine whose voltage is not known everywhere cannot be brought to it
        out.warnings.append(
            f"{campaign.path}: voltage and current are not logged at every point of "
            f"{', '.join(unlogged)}: no voltage effect fitted, thrust used as measured"
        )
        out.reference_voltage_v = None
        out.voltage.clear()
    exponent = out.exponent
    for name, fit in out.voltage.items():
        if not fit.identified:
            out.warnings.append(
                f"{campaign.path}: engine {name}: voltage exponent not determined by the runs "
                f"({fit.reason}); " + (f"the other engines' {exponent:.3g} applies"
                                       if exponent is not None else
                                       f"the default {DEFAULT_VOLTAGE_EXPONENT:g} applies")
            )
    if exponent is not None and out.reference_voltage_v is not None:
        # every engine's thrust at U_ref with the one exponent the file states: an engine
        # whose own runs do not determine it takes the others' (one engine's corrupt run left
        # every engine uncorrected). Where none determines it, the thrust stays as measured:
        # the voltage then moved with the throttle, and the poly22 holds the two together
        for p in points:
            p.thrust_n = rounded(p.thrust_at_voltage_n
                                  * (out.reference_voltage_v / p.voltage_v) ** exponent)
    for engine in engines:
        mine = [p for p in points if p.engine == engine]
        wm = fit_windmilling(
            [p.throttle for p in mine],
            [p.airspeed_m_s for p in mine],
            [p.thrust_n for p in mine],
            campaign.air_density_kg_m3,
            campaign.fan_area_m2,
        )
        if wm is not None:
            out.windmilling[engine] = wm
        _agreement(campaign, engine, mine, out)
    return out


def _agreement(campaign: Campaign, engine: str, mine: list[Point], out: ElectricalFits) -> None:
    """Measured thrust against measured ``U I`` at the engine's working points (SPEC 3)."""
    from tuflexperf.models.agreement import power_agreement

    measured = [p for p in mine if math.isfinite(p.electrical_power_w)]
    if not measured:
        return
    agreed = [power_agreement(f"{campaign.path.name} test point", engine, p.throttle,
                              p.airspeed_m_s, p.thrust_at_voltage_n, p.electrical_power_w,
                              campaign.air_density_kg_m3, campaign.fan_area_m2,
                              warn_efficiency=False) for p in measured]
    for p, a in zip(measured, agreed, strict=True):  # the SPEC 3 figures in the table
        p.ideal_power_w, p.figure_of_merit, p.overall_efficiency = (
            math.nan if value is None else rounded(value)
            for value in (a.ideal_power_w, a.figure_of_merit, a.overall_efficiency))
    largest = max(p.thrust_at_voltage_n for p in measured)
    checks = [a for p, a in zip(measured, agreed, strict=True)
              if p.thrust_at_voltage_n >= WORKING_THRUST_SHARE * largest]
    merits = [c.figure_of_merit for c in checks if c.figure_of_merit is not None]
    efficiencies = [c.overall_efficiency for c in checks if c.overall_efficiency is not None]
    out.agreement[engine] = {
        "working_points": len(checks),
        "figure_of_merit_range": [min(merits), max(merits)] if merits else None,
        "overall_efficiency_range": (
            [min(efficiencies), max(efficiencies)] if efficiencies else None
        ),
    }
    out.warnings.extend(w for c in checks for w in c.warnings)
