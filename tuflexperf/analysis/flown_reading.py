"""The flown power of the case's validation flights as a reading (issue 45 item 3, 43 item 2).

A case may list flight summaries under ``validation: {flights: [...]}`` (written by
``flightlog LOG --case CASE --summary FILE``): per 1 m/s airspeed bin the flown electrical
power beside the model's at the bin's true airspeed, level-flight throttle, the log's density
and mass. Their ratio, fitted over throttle and airspeed by the same reduction as the
discharge runs' (:func:`tuflexperf.reduction.battery.fit_power_correction`), is a power
correction law; where the flown power lies further than :data:`RUN_POWER_TOLERANCE` from the
model (time-weighted over the bins), the case is flown on it as a second reading. Only the
summaries are read: no log is opened.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.battery_fit import RUN_POWER_TOLERANCE
from tuflexperf.analysis.power_reading import AFFECTS, flown_point, with_power_correction
from tuflexperf.analysis.readings import Reading
from tuflexperf.io.case import Case
from tuflexperf.io.flight_summary import load_flight_summary
from tuflexperf.reduction.battery import correction_form, fit_power_correction


def model_power_w(case: Case, throttle: np.ndarray, airspeed_m_s: np.ndarray,
                  density_kg_m3: float) -> np.ndarray:
    """The case's electrical power [W] of all its engines at ``throttle`` [-] and true airspeed
    [m/s] at ``density_kg_m3`` [kg/m^3], as ``flightlog`` compares it: the propulsion's power
    surfaces summed, else the battery file's fan-power law times the engines."""
    from tuflexperf.models.powertrain import engine_power_w, power_surfaces

    surfaces = power_surfaces(case.propulsion, density_kg_m3)
    if surfaces is not None:
        return sum(np.asarray(surfaces.density_scale * engine_power_w(e, throttle, airspeed_m_s),
                              dtype=float) for e in case.propulsion.engines)
    from tuflexperf.analysis.battery_fit import cached_case_battery, characterise_battery

    fan = characterise_battery(cached_case_battery(case), case).power.model
    return len(case.propulsion.engines) * np.asarray(fan.electrical_power_w(throttle,
                                                                           airspeed_m_s), float)


@dataclass(frozen=True)
class FlownFlight:
    """One validation flight as ``check`` and the review read it: its summary's bins, each
    beside the case's model today at the summary's level-flight throttle, true airspeed and
    density (arrays over the bins; NaN where the log had no such stream)."""

    path: Path  # the summary
    log: str
    log_sha256: str
    density_kg_m3: float
    mass_kg: float
    airborne_s: float
    energy_wh: float | None
    bins_kind: str | None  # "level-flight", "all-flight", or None (not stated)
    airspeed_m_s: NDArray[np.float64]  # calibrated, the bin's label [m/s]
    true_airspeed_m_s: NDArray[np.float64]
    time_s: NDArray[np.float64]
    flown_power_w: NDArray[np.float64]
    model_power_w: NDArray[np.float64]  # the case's model today [W]
    summary_power_w: NDArray[np.float64]  # the model's when the summary was written [W]
    model_throttle: NDArray[np.float64]
    flown_throttle: NDArray[np.float64]
    flown_current_a: NDArray[np.float64]

    @property
    def ratio(self) -> NDArray[np.float64]:
        """Flown over the model's power per bin [-]."""
        return self.flown_power_w / self.model_power_w

    @property
    def mean_ratio(self) -> float:
        """Flown over the model's power, time-weighted over the bins [-]."""
        return float(np.sum(self.time_s * self.flown_power_w)
                     / np.sum(self.time_s * self.model_power_w))

    @property
    def stale(self) -> bool:
        """Whether the case's model today gives another power than the summary's."""
        return bool(np.any(np.abs(self.model_power_w / self.summary_power_w - 1.0) > 1e-6))

    @property
    def predicted_endurance_s(self) -> float | None:
        """The flown energy [s] spent at the model's power, time-weighted over the bins as
        they were flown: the endurance the model predicts for this flight."""
        if self.energy_wh is None:
            return None
        mean = float(np.sum(self.time_s * self.model_power_w) / np.sum(self.time_s))
        return self.energy_wh * 3600.0 / mean

    @property
    def mean_power_w(self) -> float | None:
        """Flown energy over airborne time [W]."""
        if self.energy_wh is None or self.airborne_s <= 0:
            return None
        return self.energy_wh * 3600.0 / self.airborne_s


def flown_flights(case: Case) -> tuple[FlownFlight, ...]:
    """The case's validation flights (``validation.flights``), each bin beside the model."""
    out = []
    for path in case.validation_flights:
        summary = load_flight_summary(path).schema

        def column(key: str, rows: Any = summary.bins) -> NDArray[np.float64]:
            return np.array([np.nan if getattr(b, key) is None else getattr(b, key)
                             for b in rows], dtype=float)

        x, v = column("predicted_throttle"), column("true_airspeed_m_s")
        # the case's model today at the flown points (a summary from another power model
        # would otherwise carry that model's ratio)
        model = np.asarray(model_power_w(case, x, v, summary.density_kg_m3), dtype=float)
        out.append(FlownFlight(
            Path(path), summary.log, summary.log_sha256, summary.density_kg_m3,
            summary.mass_kg, summary.airborne_s, summary.energy_wh, summary.bins_kind,
            column("airspeed_m_s"), v, column("time_s"), column("flown_power_w"), model,
            column("predicted_power_w"), x, column("flown_throttle"),
            column("flown_current_a")))
    return tuple(out)


def flown_power_ratio(flights: tuple[FlownFlight, ...]) -> dict[str, Any] | None:
    """Flown over the model's power over every flight's bins, time-weighted, beside the
    endurance verdict: ``ratio`` [-], its per-bin range, the bins and flights it spans and
    whether it lies within :data:`RUN_POWER_TOLERANCE` (the reading's threshold)."""
    if not flights:
        return None
    time = np.concatenate([f.time_s for f in flights])
    flown = np.concatenate([f.flown_power_w for f in flights])
    model = np.concatenate([f.model_power_w for f in flights])
    if not np.all(model > 0):
        return None
    ratio = float(np.sum(time * flown) / np.sum(time * model))
    return {"ratio": ratio, "bin_ratio_min": float(np.min(flown / model)),
            "bin_ratio_max": float(np.max(flown / model)), "bins": int(time.size),
            "flights": [f.path.name for f in flights], "tolerance": RUN_POWER_TOLERANCE,
            "within_tolerance": bool(abs(1.0 / ratio - 1.0) <= RUN_POWER_TOLERANCE)}


def flown_power_note(ratio: dict[str, Any]) -> str:
    """The ratio in words, as ``check`` prints it beside the endurance verdict."""
    tolerance = f"{100 * ratio['tolerance']:.0f} %"
    judged = (f"within {tolerance} of the model (no reading of its own)"
              if ratio["within_tolerance"] else f"more than {tolerance} from the model: the "
              "verdicts that use the power are judged on the flown power too")
    return (f"validation flights ({', '.join(ratio['flights'])}): flown/predicted power "
            f"x{ratio['ratio']:.3f} time-weighted over {ratio['bins']} airspeed bins "
            f"(x{ratio['bin_ratio_min']:.2f} to x{ratio['bin_ratio_max']:.2f} per bin), "
            f"{judged}")


def flown_power_readings(case: Case) -> tuple[Reading, ...]:
    """The case flown on its validation flights' power, where it disagrees with the model."""
    if not case.validation_flights:
        return ()
    flights = flown_flights(case)
    # the ratio check prints beside the endurance, and its tolerance: one rule for both
    said = flown_power_ratio(flights)
    if said is None or said["within_tolerance"]:
        return ()
    rows, names = [], []
    for flight in flights:
        names.append(flight.path.name)
        for k in range(flight.time_s.size):
            at = SimpleNamespace(throttle_setting=float(flight.model_throttle[k]),
                                 airspeed_setting_m_s=float(flight.true_airspeed_m_s[k]),
                                 mean_power_w=float(flight.flown_power_w[k]), path=flight.path)
            rows.append((at, float(flight.model_power_w[k]), flight.log))
    mean_ratio = said["ratio"]
    model = np.array([r[1] for r in rows])
    law = fit_power_correction([r[0] for r in rows], model)
    worst = max(rows, key=lambda r: abs(np.log(r[0].mean_power_w / r[1])))
    stale = any(f.stale for f in flights)
    point = flown_point(case)
    flown_text = ""
    settle = "another flight over the same airspeeds"
    if point is not None:
        fx, fv = point
        outside = law.extrapolates(fx, fv, "the flown bins'")
        ratio = float(law.ratio(fx, fv))
        flown_text = f"; the cruise at throttle {fx:.2f}, {fv:.1f} m/s flies x{ratio:.3f}"
        if outside:
            flown_text += f", extrapolated ({'; '.join(outside)}: held at the flown edge)"
            settle = f"a flight holding {fv:.1f} m/s"
    files = ", ".join(names)
    evidence = (
        f"validation.flights ({files}; {correction_form(law)} over {len(rows)} airspeed bins"
        f"{', the model recomputed since the summary' if stale else ''}): {worst[2]} flew "
        f"{worst[0].mean_power_w:.0f} W at {worst[0].airspeed_setting_m_s:.1f} m/s where the "
        f"model gives {worst[1]:.0f} W; time-weighted flown/model x{mean_ratio:.3f}{flown_text}"
    )
    return (Reading(
        key="flown_power",
        label="the validation flights' flown power",
        nominal_label="the power model",
        case=with_power_correction(case, law),
        affects=AFFECTS,
        evidence=evidence,
        settle=settle,
    ),)
