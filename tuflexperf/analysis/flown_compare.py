"""Predicted against flown: the case's level-flight power at each flown airspeed bin.

The predicted side is the project's own models, composed, no new physics: the least level
throttle (:meth:`tuflexperf.analysis.level_flight.LevelFlightRows.least_throttle`, the
one ``trim`` flies) at the bin's true airspeed, the log's density and
the case's mass (or ``--mass``), and the electrical power of that throttle from the
propulsion file's power surfaces (:func:`tuflexperf.models.powertrain.power_surfaces`) or,
without them, the battery file's fan-power law, as ``endurance`` uses them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.flown import FlownResult
from tuflexperf.io.flightlog import FlightLog
from tuflexperf.models.atmosphere import GAS_CONSTANT_J_KG_K


@dataclass(frozen=True)
class Comparison:
    """Per bin the model's power and throttle beside the flown ones, and the endurance."""

    density_kg_m3: float
    density_source: str
    mass_kg: float
    power_model: str
    bins: tuple[dict[str, Any], ...]
    predicted_endurance_s: float | None
    flown_s: float
    summary: tuple[str, ...]
    notes: tuple[str, ...]
    handoff: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"density_kg_m3": self.density_kg_m3, "density_source": self.density_source,
                "mass_kg": self.mass_kg, "power_model": self.power_model,
                "bins": list(self.bins), "predicted_endurance_s": self.predicted_endurance_s,
                "flown_s": self.flown_s, "summary": list(self.summary),
                "autopilot_handoff": self.handoff}


def log_density(log: FlightLog, flown: FlownResult, fallback: float) -> tuple[float, str]:
    """Median air density [kg/m^3] over the airborne window from baro pressure and
    temperature (ideal gas), else ``fallback`` (the case's ISA density)."""
    baro = log.baro
    if baro is not None:
        t = baro.time_s
        inside = (t >= flown.window.start_s) & (t <= flown.window.end_s)
        p = baro.column("pressure_pa")[inside]
        temp_k = baro.column("temperature_c")[inside] + 273.15
        rho = p / (GAS_CONSTANT_J_KG_K * temp_k)
        rho = rho[np.isfinite(rho) & (rho > 0.1) & (rho < 2.0)]
        if rho.size:
            return float(np.median(rho)), (f"{baro.source} pressure and temperature (median "
                                           "over the airborne window; the baro's temperature "
                                           "may read warm from the board)")
    return fallback, "the case's ISA density (the log has no baro pressure and temperature)"


def compare_with_case(case: Any, log: FlightLog, flown: FlownResult,
                      mass_kg: float | None) -> Comparison:
    """The model beside the flown bins (level-flight bins where there are any).

    Parameters
    ----------
    case : Case
        The loaded case.
    log : FlightLog
        The log (its baro gives the density).
    flown : FlownResult
        The flown side.
    mass_kg : float or None
        Mass [kg]; ``None`` takes the case's.
    """
    from tuflexperf.analysis.level_flight import LevelFlightRows
    from tuflexperf.models.aircraft import (
        stall_speed_m_s,
        true_airspeed_m_s,
    )
    from tuflexperf.models.powertrain import power_surfaces

    notes: list[str] = []
    mass = float(mass_kg if mass_kg is not None else case.aircraft.mass_kg)
    aircraft = dataclasses.replace(case.aircraft, mass_kg=mass)
    rho, rho_source = log_density(log, flown, case.density_kg_m3)
    propulsion = case.propulsion
    n = len(propulsion.engines)

    surfaces = power_surfaces(propulsion, rho)
    if surfaces is not None:
        from tuflexperf.models.powertrain import engine_power_w

        def power(x: np.ndarray, v: np.ndarray) -> np.ndarray:
            return sum(np.asarray(surfaces.density_scale * engine_power_w(e, x, v), float)
                       for e in propulsion.engines)

        model = "the propulsion file's power surfaces, summed over the engines"
    else:
        from tuflexperf.analysis.endurance import characterise_battery
        from tuflexperf.io.battery import case_battery

        if case.battery_path is None:
            notes.append("the case has neither power surfaces nor a battery file: no "
                         "predicted power")
            return Comparison(rho, rho_source, mass, "none", (), None,
                              flown.window.duration_s, (), tuple(notes))
        fan = characterise_battery(case_battery(case), case).power.model

        def power(x: np.ndarray, v: np.ndarray) -> np.ndarray:
            return n * np.asarray(fan.electrical_power_w(x, v), float)

        model = f"the battery file's fan-power law, x {n} engines"
    bins = flown.level_bins or flown.bins
    which = "level-flight" if flown.level_bins else "all-flight"
    if flown.bins and not flown.level_bins:
        notes.append("no level-flight bin holds 10 s: the model (level flight) is set beside "
                     "the all-flight bins")
    eas = np.array([b.airspeed_m_s for b in bins], dtype=float)
    v_true = np.asarray(true_airspeed_m_s(eas, rho), dtype=float)
    rows = LevelFlightRows(aircraft, propulsion, rho, None, 1)
    throttle = rows.least_throttle(v_true[None, :])[0] if eas.size else eas
    # SPEC 3: stall bounds everything; below it the model has no level flight to offer
    stall = float(stall_speed_m_s(aircraft, rho))
    below = v_true < stall
    if below.any():
        notes.append(f"bins below the model's stall speed ({stall:.1f} m/s true at the log's "
                     "density and the mass): no level flight predicted there (n/a)")
    throttle = np.where(below, np.nan, throttle)
    predicted = np.where(np.isfinite(throttle), power(np.nan_to_num(throttle), v_true), np.nan)
    rows = []
    for b, x, p, vt in zip(bins, throttle, predicted, v_true, strict=True):
        rows.append({"airspeed_m_s": b.airspeed_m_s, "true_airspeed_m_s": float(vt),
                     "flown_power_w": b.power_w, "predicted_power_w": float(p),
                     "ratio": float(b.power_w / p) if np.isfinite(p) and p > 0 else None,
                     "flown_throttle": b.throttle, "predicted_throttle": float(x),
                     "flown_current_a": b.current_a, "time_s": b.time_s, "bins": which})
    if np.any(~np.isfinite(throttle) & ~below):
        notes.append("the model holds no level flight at some flown airspeeds (beyond full "
                     "throttle): n/a there")
    endurance = None
    summary = [f"model: level flight at {rho:.4f} kg/m^3 ({rho_source}), mass {mass:g} kg, "
               f"power from {model}; {which} bins"]
    ok = np.isfinite(predicted)
    if ok.any() and flown.energy_wh is not None:
        weights = np.array([b.time_s for b in bins])[ok]
        mean_predicted = float(np.sum(weights * predicted[ok]) / np.sum(weights))
        endurance = flown.energy_wh * 3600.0 / mean_predicted
        ratios = np.array([r["ratio"] for r in rows if r["ratio"] is not None])
        summary.append(f"flown/predicted power per bin: {ratios.min():.2f} to "
                       f"{ratios.max():.2f}")
        summary.append(f"predicted endurance on the flown {flown.energy_wh:.1f} Wh at the "
                       f"flown airspeeds (time-weighted over the {int(ok.sum())} of {ok.size} "
                       f"bins the model flies): {endurance:.0f} s, against "
                       f"{flown.window.duration_s:.0f} s flown")
    elif not bins:
        notes.append("no flown bin to compare the model with")
    handoff = autopilot_handoff(case, flown, notes)
    if handoff is not None:
        line = (f"autopilot hand-off at the model's endurance airspeed "
                f"{handoff['airspeed_eas_m_s']:.1f} m/s EAS: cruise power "
                f"{handoff['model_power_w']:.0f} W, current {handoff['model_current_a']:.1f} A "
                "(full packs)")
        if handoff.get("flown_power_w") is not None:
            line += (f"; flown there: {handoff['flown_power_w']:.0f} W, "
                     f"{handoff['flown_current_a']:.1f} A")
        summary.append(line)
    return Comparison(rho, rho_source, mass, model, tuple(rows), endurance,
                      flown.window.duration_s, tuple(summary), tuple(notes), handoff)


def autopilot_handoff(case: Any, flown: FlownResult, notes: list[str]) -> dict[str, Any] | None:
    """Cruise power [W] and current [A] at the model's best-endurance airspeed, for an
    autopilot's average-current setting and a ground station's flight-time estimate; the
    flown power and current in the bin holding that airspeed, where one does.

    The model's point is ``endurance``'s best (:func:`tuflexperf.analysis.endurance.solve_best`)
    at the case's density and mass; its current is each fan's pack current summed over the
    engines (one monitor on all packs), at full-pack voltage.
    """
    from tuflexperf.analysis.endurance import solve_best
    from tuflexperf.errors import InputError, NotAttainable

    if case.battery_path is None:
        notes.append("autopilot hand-off: the case has no battery file")
        return None
    try:
        best = solve_best(case)
    except (NotAttainable, InputError) as exc:
        notes.append(f"autopilot hand-off: no best-endurance point ({exc})")
        return None
    out = handoff_point(case, best)
    held = next((b for b in flown.bins if b.airspeed_m_s == out["bin_m_s"]), None)
    if held is not None:
        out["flown_power_w"] = held.power_w
        out["flown_current_a"] = held.current_a
    return out


def handoff_point(case: Any, best: Any) -> dict[str, Any]:
    """The model's side of the hand-off from ``endurance``'s best
    (:class:`~tuflexperf.analysis.endurance.BestResult`): its airspeed as EAS [m/s] and
    true [m/s], its throttle, the power [W] and pack current [A] of all engines, and the
    1 m/s bin [m/s] that holds it (the flown side, ``None`` until a flight fills it)."""
    from tuflexperf.models.aircraft import EAS_REFERENCE_DENSITY_KG_M3

    point = best.endurance
    eas = point.airspeed_m_s * float(np.sqrt(case.density_kg_m3 / EAS_REFERENCE_DENSITY_KG_M3))
    return {
        "airspeed_eas_m_s": eas, "airspeed_true_m_s": point.airspeed_m_s,
        "throttle": point.throttle, "model_power_w": point.electrical_power_w * point.engines,
        "model_current_a": point.pack_current_a * point.engines,
        "bin_m_s": float(np.floor(eas + 0.5)), "flown_power_w": None, "flown_current_a": None,
    }
