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

from pathlib import Path
from types import SimpleNamespace

import numpy as np

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


def flown_power_readings(case: Case) -> tuple[Reading, ...]:
    """The case flown on its validation flights' power, where it disagrees with the model."""
    if not case.validation_flights:
        return ()
    rows, names = [], []
    for path in case.validation_flights:
        summary = load_flight_summary(path).schema
        names.append(Path(path).name)
        x = np.array([b.predicted_throttle for b in summary.bins], dtype=float)
        v = np.array([b.true_airspeed_m_s for b in summary.bins], dtype=float)
        # the case's model today at the flown points (a summary from another power model
        # would otherwise carry that model's ratio)
        model = model_power_w(case, x, v, summary.density_kg_m3)
        for b, xi, vi, mi in zip(summary.bins, x, v, model, strict=True):
            at = SimpleNamespace(throttle_setting=float(xi), airspeed_setting_m_s=float(vi),
                                    mean_power_w=b.flown_power_w, path=Path(path))
            rows.append((at, float(mi), b.time_s, b.predicted_power_w, summary.log))
    flown = np.array([r[0].mean_power_w for r in rows])
    model = np.array([r[1] for r in rows])
    weights = np.array([r[2] for r in rows])
    if not np.all(model > 0):
        return ()
    mean_ratio = float(np.sum(weights * flown) / np.sum(weights * model))
    if abs(1.0 / mean_ratio - 1.0) <= RUN_POWER_TOLERANCE:
        return ()
    law = fit_power_correction([r[0] for r in rows], model)
    worst = max(rows, key=lambda r: abs(np.log(r[0].mean_power_w / r[1])))
    stale = any(abs(r[1] / r[3] - 1.0) > 1e-6 for r in rows)
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
        f"{', the model recomputed since the summary' if stale else ''}): {worst[4]} flew "
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
