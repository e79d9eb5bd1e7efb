"""From a fan's and a pack's datasheet to a starter propulsion model and pack circuit.

A datasheet gives static numbers only: the full-throttle static thrust ``T0`` [N] and
electrical power ``Pmax`` [W] of one fan, its diameter ``D`` [m], and the pack's cells,
capacity [Ah], C rating and (seldom) internal resistance. From these:

* **thrust** by momentum theory at a jet velocity proportional to the fan's speed: the jet
  leaves the duct (area ``A = pi D^2 / 4``) at ``x V_j`` at throttle ``x``, with the static
  jet velocity ``V_j = sqrt(T0 / (rho A))`` (``T0 = rho A V_j^2``), so
  ``T(x, V) = rho A x V_j (x V_j - V) = T0 x^2 - (T0 / V_j) x V``: a poly22 exactly
  (McCormick, *Aerodynamics, Aeronautics and Flight Mechanics*, ch. 6; the ram drag term);
* **electrical power** by the fan affinity laws (thrust ~ speed^2, power ~ speed^3) and the
  same momentum theory in airspeed: ``P(x, V) = Pmax x^3 (1 - (V / V_j)^2)`` (the form
  :class:`tuflexperf.models.battery.FanPowerModel` flies), fitted by a poly22 with
  ``P(0, 0) = 0`` and ``P(1, 0) = Pmax`` held exactly;
* **the pack** as the equivalent circuit of :mod:`tuflexperf.models.battery`, its cell
  shape the one the shipped TU-Flex pack was reconstructed from (scripts/generate_discharge.py:
  a 5 Ah 40C LiPo cell), scaled to the capacity; discharge runs of it at constant power
  stand in for the tunnel's, so that ``fit`` and ``endurance`` read them as measured ones.

Nothing here is measured: every file written from it says so, and the thrust model carries
a stated uncertainty (:data:`THRUST_SD_FRACTION`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated

import numpy as np
from pydantic import Field

from tuflexperf.io.yamlio import Name, StrictModel
from tuflexperf.models.atmosphere import SEA_LEVEL_DENSITY_KG_M3
from tuflexperf.models.battery import DischargeParameters, current_at_power_a, terminal_voltage_v

Positive = Annotated[float, Field(gt=0)]

# 1 sd of the datasheet thrust model as a fraction of the static thrust: a datasheet's own
# range is about +-18 % around its middle (the shipped fan's 41-59 N), some two sd
THRUST_SD_FRACTION = 0.10
# the shipped pack's fitted resistance per cell, leads included (data/tuflex/battery.yaml:
# 50.3 mOhm for 12 cells of 5 Ah), scaled as 1 / capacity for another cell size [Ohm Ah]
DEFAULT_RESISTANCE_OHM_AH_PER_CELL = 0.0503 / 12 * 5.0
RESISTANCE_SOURCE = ("the shipped TU-Flex pack's fitted circuit, 50.3 mOhm for 12 cells of "
                     "5 Ah with leads (data/tuflex/battery.yaml), per cell and scaled as "
                     "1/capacity")
# the cell shape (per cell, at 5 Ah) of scripts/generate_discharge.py's "true" pack
CELL_E0_V, CELL_SLOPE_V_PER_AH_5AH, CELL_EXP_V, CELL_EXP_RATE_PER_AH_5AH = 4.05, 0.06, 0.12, 3.0
CELL_KNEE_V, CELL_FULL_CAPACITY_FRACTION = 0.02, 1.05
CUTOFF_V_PER_CELL = 3.4  # the usual ESC low-voltage cut-off under load (the shipped pack's)
RUN_THROTTLES = (0.5, 0.75)  # throttles of the stand-in discharge runs
RUN_STEP_S, IDLE_BEFORE_S, IDLE_AFTER_S, IDLE_CURRENT_A = 0.1, 10.0, 20.0, 0.25
POWER_FIT_TOP = 0.6  # the power poly22 is fitted over airspeeds up to this x V_j


class DatasheetSchema(StrictModel):
    """A fan's and a pack's datasheet numbers (per fan and per pack), as ``init`` reads them."""

    name: Name = "my fan"
    static_thrust_n: Annotated[float, Field(gt=0, le=1e5)]
    max_power_w: Annotated[float, Field(gt=0, le=1e7)]
    fan_diameter_m: Annotated[float, Field(gt=0.01, le=3.0)]
    engines: Annotated[int, Field(ge=1, le=8)] = 2
    cells: Annotated[int, Field(ge=1, le=100)]
    capacity_ah: Annotated[float, Field(gt=0, le=1000)]
    c_rating: Annotated[float, Field(gt=0, le=500)]
    internal_resistance_ohm_per_cell: Annotated[float, Field(gt=0, le=1.0)] | None = None


DATASHEET_KEYS = tuple(DatasheetSchema.model_fields)

TYPICAL = {  # a 70 mm 6S fan and a 5 Ah 6S 40C pack per fan: the starter's editable values
    "name": "70 mm EDF (typical values: edit)", "static_thrust_n": 25.0, "max_power_w": 1800.0,
    "fan_diameter_m": 0.07, "engines": 2, "cells": 6, "capacity_ah": 5.0, "c_rating": 40.0,
}


@dataclass(frozen=True)
class StarterModel:
    """The propulsion surfaces and pack circuit a datasheet gives, with what they rest on."""

    sheet: DatasheetSchema
    density_kg_m3: float
    fan_area_m2: float
    jet_velocity_m_s: float
    figure_of_merit: float  # ideal (momentum) static power over the datasheet's electrical
    thrust: dict[str, float]  # poly22 [N] in throttle fraction and airspeed [m/s]
    power: dict[str, float]  # poly22 [W]
    power_rmse_w: float  # of the power poly22 against the affinity-law surface
    thrust_sd_n: float
    pack: DischargeParameters
    resistance_per_cell_ohm: float
    resistance_source: str
    packs_in_parallel: int

    @property
    def power_fit_top_m_s(self) -> float:
        """Highest airspeed [m/s] the power poly22 was fitted over."""
        return POWER_FIT_TOP * self.jet_velocity_m_s


def poly22(c: dict[str, float], x: np.ndarray | float, v: np.ndarray | float) -> np.ndarray:
    """A poly22 surface ``p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2``."""
    return (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x * x + c["p11"] * x * v
            + c["p02"] * v * v)


def starter_model(sheet: DatasheetSchema,
                  density_kg_m3: float = SEA_LEVEL_DENSITY_KG_M3) -> StarterModel:
    """The thrust and power surfaces and the pack circuit of ``sheet`` (module docstring).

    Parameters
    ----------
    sheet : DatasheetSchema
        The datasheet numbers (static thrust [N], power [W], diameter [m], pack).
    density_kg_m3 : float
        Air density of the datasheet's static test [kg/m^3] (ISA sea level).
    """
    t0, p_max = sheet.static_thrust_n, sheet.max_power_w
    area = math.pi * sheet.fan_diameter_m**2 / 4.0
    v_j = math.sqrt(t0 / (density_kg_m3 * area))
    thrust = {"p00": 0.0, "p10": 0.0, "p01": 0.0, "p20": t0, "p11": -t0 / v_j, "p02": 0.0}
    # P/Pmax = a10 x + a20 x^2 + a01 v + a11 x v + a02 v^2 with a10 = 1 - a20: P(1, 0) = Pmax
    x, v = (g.ravel() for g in np.meshgrid(np.linspace(0.0, 1.0, 21),
                                           np.linspace(0.0, POWER_FIT_TOP * v_j, 21)))
    target = x**3 * (1.0 - (v / v_j) ** 2)
    basis = np.column_stack([x * x - x, v, x * v, v * v])
    (a20, a01, a11, a02), *_ = np.linalg.lstsq(basis, target - x, rcond=None)
    power = {"p00": 0.0, "p10": p_max * (1.0 - a20), "p01": p_max * a01, "p20": p_max * a20,
             "p11": p_max * a11, "p02": p_max * a02}
    rmse = float(np.sqrt(np.mean((poly22(power, x, v) - p_max * target) ** 2)))
    ideal = t0**1.5 / math.sqrt(4.0 * density_kg_m3 * area)  # T0 V_j / 2: the jet's power
    per_cell = sheet.internal_resistance_ohm_per_cell
    source = "datasheet"
    if per_cell is None:
        per_cell, source = DEFAULT_RESISTANCE_OHM_AH_PER_CELL / sheet.capacity_ah, \
            RESISTANCE_SOURCE
    n, scale = sheet.cells, 5.0 / sheet.capacity_ah
    pack = DischargeParameters(
        e0_v=n * CELL_E0_V, slope_v_per_ah=n * CELL_SLOPE_V_PER_AH_5AH * scale,
        exp_amplitude_v=n * CELL_EXP_V, exp_rate_per_ah=CELL_EXP_RATE_PER_AH_5AH * scale,
        knee_v=n * CELL_KNEE_V, max_capacity_ah=CELL_FULL_CAPACITY_FRACTION * sheet.capacity_ah,
        resistance_ohm=n * per_cell,
    )
    # packs per fan so that the full-power current stays within the C rating
    current = p_max / (n * CUTOFF_V_PER_CELL)
    packs = max(1, math.ceil(current / (sheet.c_rating * sheet.capacity_ah)))
    return StarterModel(sheet, density_kg_m3, area, v_j, ideal / p_max, thrust, power, rmse,
                        THRUST_SD_FRACTION * t0, pack, per_cell, source, packs)


def discharge_run_csv(model: StarterModel, throttle: float) -> str:
    """A stand-in discharge run of one pack on the static stand at ``throttle``: constant
    electrical power (the power surface at V = 0) from full to the cut-off, 10 s idle
    before and 20 s after, sampled at 10 Hz without noise, in the run format of
    :mod:`tuflexperf.io.runs` (``time_s, force_n, airspeed_m_s, throttle, voltage_v,
    current_a``)."""
    power = float(poly22(model.power, throttle, 0.0))
    force = float(poly22(model.thrust, throttle, 0.0))
    cutoff = model.sheet.cells * CUTOFF_V_PER_CELL
    rows = ["time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a"]
    t, q, cut_at = 0.0, 0.0, None
    limit_s = 10.0 * 3600.0
    while cut_at is None or t < cut_at + IDLE_AFTER_S:
        on = cut_at is None and t >= IDLE_BEFORE_S
        current = (float(current_at_power_a(model.pack, q, power)) if on else 0.0) \
            + IDLE_CURRENT_A
        voltage = float(terminal_voltage_v(model.pack, q, current))
        rows.append(f"{t:.1f},{force if on else 0.0:.3f},0.000,{throttle if on else 0.0:.3f},"
                    f"{voltage:.4f},{current:.4f}")
        if on and voltage <= cutoff:
            cut_at = t
        if t > limit_s:
            raise ValueError(f"a run at throttle {throttle:g} does not reach the cut-off")
        q += current * RUN_STEP_S / 3600.0
        t = round(t + RUN_STEP_S, 6)
    return "\n".join(rows) + "\n"
