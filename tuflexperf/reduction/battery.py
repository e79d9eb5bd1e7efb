"""Fits of the battery artefact: the pack's equivalent circuit and the fan's power law.

Levenberg-Marquardt least squares on 1-s block means of the discharge runs, and the fan-power
law fitted to the runs' mean power.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.discharge import DischargeRun
from tuflexperf.io.inputs import path_text
from tuflexperf.models.battery import (
    FIT_BLOCK_S,
    PARAMETER_NAMES,
    DischargeParameters,
    FanPowerModel,
    terminal_voltage_v,
)


# --- least-squares fit ----------------------------------------------------------------------
@dataclass(frozen=True)
class DischargeFit:
    """Fitted pack parameters and the fit error over the runs they were fitted to."""

    parameters: DischargeParameters
    rms_v: float
    max_abs_v: float
    n_points: int
    runs: tuple[str, ...]


def _initial_guess(cells: int, capacity_ah: float) -> np.ndarray:
    # Typical LiPo cell values (4.2 V full, ~3.7 V nominal, a few milliohm), times cells.
    return np.array(
        [4.0 * cells, 0.01 * cells * 5.0 / capacity_ah, 0.15 * cells, 15.0 / capacity_ah,
         0.02 * cells, 1.05 * capacity_ah, 0.003 * cells]
    )


def block_means(run: DischargeRun, block_s: float = FIT_BLOCK_S) -> tuple[np.ndarray, ...]:
    """Charge (Ah), current (A) and voltage (V) averaged over ``block_s``-long time blocks.

    Blocks are set in seconds, not samples (SPEC 4: the sample rate is what ``time_s``
    says). Averaging cuts the fit's size tenfold at 10 Hz and the noise with it.
    """
    index = np.floor((run.time_s - run.time_s[0]) / block_s).astype(int)
    counts = np.bincount(index)
    keep = counts > 0
    return tuple(
        np.bincount(index, weights=values)[keep] / counts[keep]
        for values in (run.charge_ah, run.current_a, run.voltage_v)
    )


def _fit_setup(
    runs: Sequence[DischargeRun], cells_in_series: int, capacity_ah: float
) -> tuple[np.ndarray, ...]:
    """Block-mean data, parameter scale, bounds and start point shared by both fit methods."""
    blocks = [block_means(r) for r in runs]
    q, i, v = (np.concatenate([b[k] for b in blocks]) for k in range(3))
    scale = _initial_guess(cells_in_series, capacity_ah)
    q_max = max(float(r.charge_ah.max()) for r in runs)
    lower = np.array([0.7, 0.0, 0.0, 0.05, 1e-6, 0.0, 0.0])
    upper = np.array([1.2, 50.0, 5.0, 20.0, 50.0, 3.0, 20.0])
    lower[5] = max(q_max * 1.001, 0.5 * capacity_ah) / scale[5]
    z0 = np.ones(len(PARAMETER_NAMES))
    z0[5] = max(z0[5], lower[5] * 1.02)
    return q, i, v, scale, lower, upper, z0


def _residual_function(scale: np.ndarray) -> Any:
    """CasADi function ``(z, q, i, v) -> (r, dr/dz)`` for one sample, in scaled parameters."""
    import casadi as ca

    z = ca.SX.sym("z", len(PARAMETER_NAMES))
    theta = z * ca.DM(scale)
    sym = SimpleNamespace(**{name: theta[k] for k, name in enumerate(PARAMETER_NAMES)})
    q, i, v = ca.SX.sym("q"), ca.SX.sym("i"), ca.SX.sym("v")
    residual = terminal_voltage_v(sym, q, i) - v
    return ca.Function("discharge_residual", [z, q, i, v], [residual, ca.jacobian(residual, z)])


def _finish_fit(
    runs: Sequence[DischargeRun], params: DischargeParameters, converged: bool, why: str
) -> DischargeFit:
    errors = np.concatenate([
        np.asarray(terminal_voltage_v(params, r.charge_ah, r.current_a), dtype=float) - r.voltage_v
        for r in runs
    ])
    if not np.all(np.isfinite(errors)) or not converged:
        names = ", ".join(r.path.name for r in runs)
        raise InputError(f"{names}: the discharge model could not be fitted ({why})")
    return DischargeFit(
        parameters=params,
        rms_v=float(np.sqrt(np.mean(errors**2))),
        max_abs_v=float(np.max(np.abs(errors))),
        n_points=int(errors.size),
        runs=tuple(r.path.name for r in runs),
    )


def fit_discharge(
    runs: Sequence[DischargeRun], cells_in_series: int, capacity_ah: float
) -> DischargeFit:
    """Fit :class:`DischargeParameters` to the runs' terminal voltage by least squares.

    ``min sum_k (V(q_k, i_k) - V_k)^2`` over 1-s block means of every run, by
    Levenberg-Marquardt (Nocedal & Wright, *Numerical Optimization*, 10.3) on scaled
    variables (each parameter over a typical LiPo value). The residual and its exact
    Jacobian are one CasADi function mapped over the samples, built once per fit; a step
    that leaves the bounds (``Q`` above the largest charge drawn, so the knee's pole stays
    outside the data; signs) is rejected like one that raises the cost. It reaches the
    same optimum as CasADi's IPOPT (tested) in a fraction of the time, which
    keeps ``tuflexperf check`` fast. The reported error (rms and max, volts) is over every
    raw sample. Raises :class:`InputError` if the runs cannot be fitted.
    """
    q, i, v, scale, lower, upper, z = _fit_setup(runs, cells_in_series, capacity_ah)
    mapped = _residual_function(scale).map(q.size)
    data = [column[None, :] for column in (q, i, v)]

    def evaluate(point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r, jac = mapped(point, *data)
        return np.asarray(r).ravel(), np.asarray(jac).reshape(len(point), q.size, order="F").T

    residual, jacobian = evaluate(z)
    cost = float(residual @ residual)
    damping, converged = 1e-3, False
    for _ in range(500):
        normal = jacobian.T @ jacobian
        gradient = jacobian.T @ residual
        if np.max(np.abs(gradient)) <= 1e-13 * max(cost, 1e-300) ** 0.5 * q.size**0.5:
            converged = True
            break
        try:
            step = np.linalg.solve(normal + damping * np.diag(np.diag(normal)), -gradient)
        except np.linalg.LinAlgError:
            damping *= 10.0
            continue
        trial = z + step
        inside = bool(np.all(trial >= lower) and np.all(trial <= upper))
        trial_residual, trial_jacobian = evaluate(trial) if inside else (residual, jacobian)
        trial_cost = float(trial_residual @ trial_residual) if inside else np.inf
        if np.isfinite(trial_cost) and trial_cost <= cost:
            small = cost - trial_cost <= 1e-15 * cost and np.max(np.abs(step)) < 1e-10
            z, residual, jacobian, cost = trial, trial_residual, trial_jacobian, trial_cost
            damping = max(damping / 3.0, 1e-12)
            if small:
                converged = True
                break
        else:
            damping *= 4.0
            if damping > 1e12:  # no descent left: stationary to working precision
                converged = True
                break
    params = DischargeParameters.from_vector(z * scale)
    return _finish_fit(runs, params, converged, "Levenberg-Marquardt did not converge")


@dataclass(frozen=True)
class PowerFit:
    """The fan power model and how well it matches the points it was fitted to."""

    model: FanPowerModel
    points: tuple[dict[str, float], ...]
    rms_log_error: float


def fit_fan_power(
    runs: Sequence[DischargeRun], static_full_throttle_w: float, jet_velocity_m_s: float
) -> PowerFit:
    """Fit ``ln P = ln P_s + n ln x + ln(1 - (V/V_j)^2)`` to the runs and the published point.

    Points: each run's mean ``V I`` at its throttle and airspeed, and the published
    full-throttle static power (``x = 1``, ``V = 0``). Linear least squares in
    ``(ln P_s, n)``, equal weights.
    """
    xs = [1.0] + [r.throttle_setting for r in runs]
    vs = [0.0] + [r.airspeed_setting_m_s for r in runs]
    ps = [static_full_throttle_w] + [r.mean_power_w for r in runs]
    labels = ["published full-throttle static"] + [r.path.name for r in runs]
    x, v, p = np.array(xs), np.array(vs), np.array(ps)
    bad = [label for label, xi, vi, pi in zip(labels, x, v, p, strict=True)
           if not (xi > 0 and vi < jet_velocity_m_s and pi > 0)]
    if bad:
        raise InputError(
            f"fan power fit: {', '.join(bad)}: needs throttle > 0, power > 0 and an airspeed "
            f"below the jet velocity {jet_velocity_m_s:g} m/s"
        )
    factor = 1.0 - (v / jet_velocity_m_s) ** 2
    design = np.column_stack([np.ones_like(x), np.log(x)])
    target = np.log(p) - np.log(factor)
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    model = FanPowerModel(float(np.exp(coef[0])), float(coef[1]), jet_velocity_m_s)
    predicted = np.asarray(model.electrical_power_w(x, v), dtype=float)
    points = tuple(
        {"source": label, "throttle": float(xi), "airspeed_m_s": float(vi),
         "power_w": float(pi), "model_w": float(mi)}
        for label, xi, vi, pi, mi in zip(labels, x, v, p, predicted, strict=True)
    )
    return PowerFit(model, points, float(np.sqrt(np.mean(np.log(predicted / p) ** 2))))


# --- the measured power correction (issue 43 item 2) ------------------------------------------
# Runs this far apart in throttle [-] / airspeed [m/s] count as two settings (a tunnel held
# at "30 m/s" measured 30.001 and 30.005 m/s: one airspeed)
DISTINCT_THROTTLE = 0.02
DISTINCT_AIRSPEED_M_S = 1.0


def fan_power_of(battery: Any, propulsion: Any, runs: Sequence[Any],
                 propulsion_file: Any = None) -> PowerFit:
    """The battery file's fan-power law (:func:`fit_fan_power`) for the runs' fan.

    The full-throttle static power is the published range interpolated at the static
    thrust of the runs' engine (the first engine when the runs name none). ``runs`` are
    discharge runs or their stored summaries. Raises :class:`InputError` naming the
    propulsion file (``propulsion_file``, else the propulsion's name).
    """
    from tuflexperf.models.battery import published_static_power_w
    from tuflexperf.models.thrust import engine_thrust_n

    engine = run_engine(battery, propulsion)
    static_n = float(engine_thrust_n(engine, 1.0, 0.0))
    if static_n <= 0:
        raise InputError(f"{propulsion_file or propulsion.name}: {engine.name}: no static "
                         "thrust at full throttle")
    static_w = published_static_power_w(
        static_n, battery.published_power_range_w, battery.published_static_thrust_range_n
    )
    return fit_fan_power(runs, static_w, battery.jet_velocity_m_s)


def run_engine(battery: Any, propulsion: Any) -> Any:
    """The engine the discharge runs name (the first one where they name none)."""
    engine_name = next((r.engine for r in battery.runs if r.engine), None)
    engines = {e.name: e for e in propulsion.engines}
    if engine_name is not None and engine_name not in engines:
        raise InputError(
            f"{battery.path}: runs: engine {engine_name!r} is not in the propulsion file "
            f"(engines: {', '.join(engines)})"
        )
    return engines[engine_name] if engine_name else propulsion.engines[0]


def run_model_power_w(battery: Any, propulsion: Any, runs: Sequence[Any],
                      fan_law: Any = None) -> tuple[np.ndarray, str]:
    """The power model [W] at each run's throttle and airspeed, and what that model is.

    The run's own fan's power surface as fitted (the test day's density, as measured) where
    every engine of ``propulsion`` has one, else the battery file's fan-power law
    (``fan_law``, fitted here when not given): what the case flies.
    """
    from tuflexperf.models.powertrain import engine_power_w, power_surfaces

    x = np.array([r.throttle_setting for r in runs], dtype=float)
    v = np.array([r.airspeed_setting_m_s for r in runs], dtype=float)
    engines = {e.name: e for e in propulsion.engines}
    if power_surfaces(propulsion, 1.0) is not None:
        chosen = [engines.get(ref.engine or "", propulsion.engines[0]) for ref in battery.runs]
        # the surface as fitted, without any correction it may already fly
        model = np.array([float(engine_power_w(_plain(e), xi, vi))
                          for e, xi, vi in zip(chosen, x, v, strict=True)])
        return model, f"{chosen[0].name}'s power surface in the propulsion file"
    law = fan_law if fan_law is not None else fan_power_of(battery, propulsion, runs).model
    law = _plain(law)
    return (np.asarray(law.electrical_power_w(x, v), dtype=float),
            "the battery file's fan-power law (fan_power)")


def _plain(model: Any) -> Any:
    """``model`` (an Engine or a fan-power law) without a power correction."""
    from dataclasses import replace

    return replace(model, power_correction=None) if model.power_correction is not None else model


def fit_power_correction(runs: Sequence[Any], model_w: Sequence[float]) -> Any:
    """Fit measured over modelled power, ``r = c0 + c_x x + c_V V``, to the runs.

    The throttle term enters with runs at two throttles or more, the airspeed term with runs
    at two airspeeds or more (each :data:`DISTINCT_THROTTLE` / :data:`DISTINCT_AIRSPEED_M_S`
    apart), and only while the runs determine it (full column rank); least squares over the
    runs' ratios, equal weights. One run gives a constant.

    Parameters
    ----------
    runs : sequence
        Discharge runs or their stored summaries (``throttle_setting`` [-],
        ``airspeed_setting_m_s`` [m/s], ``mean_power_w`` [W]).
    model_w : sequence of float
        The power model at each run's throttle and airspeed [W].

    Returns
    -------
    PowerCorrection
        The law and the runs' throttle and airspeed span.

    References
    ----------
    Issue 43 item 2 (the measured discharge power as a correction law over throttle and
    airspeed).
    """
    from tuflexperf.models.power_correction import PowerCorrection

    x = np.array([r.throttle_setting for r in runs], dtype=float)
    v = np.array([r.airspeed_setting_m_s for r in runs], dtype=float)
    measured = np.array([r.mean_power_w for r in runs], dtype=float)
    model = np.asarray(model_w, dtype=float)
    bad = [r.path.name for r, m in zip(runs, model, strict=True) if not m > 0]
    if bad:
        raise InputError(f"{', '.join(bad)}: the power model gives no positive power at the "
                         "run's throttle and airspeed; no measured power correction")
    ratio = measured / model
    columns = [np.ones_like(x)]
    wanted = [(np.ptp(x) >= DISTINCT_THROTTLE, x), (np.ptp(v) >= DISTINCT_AIRSPEED_M_S, v)]
    used = []
    for wants, column in wanted:
        trial = np.column_stack([*columns, column])
        if wants and np.linalg.matrix_rank(trial) == trial.shape[1]:
            columns.append(column)
            used.append(True)
        else:
            used.append(False)
    coef = iter(np.linalg.lstsq(np.column_stack(columns), ratio, rcond=None)[0])
    c0 = float(next(coef))
    cx = float(next(coef)) if used[0] else 0.0
    cv = float(next(coef)) if used[1] else 0.0
    return PowerCorrection(c0, cx, cv, (float(x.min()), float(x.max())),
                           (float(v.min()), float(v.max())))


def correction_form(correction: Any) -> str:
    """The law's form in words (``constant``, ``linear in throttle``, ...)."""
    terms = [name for name, c in (("throttle", correction.per_throttle),
                                  ("airspeed", correction.per_airspeed_s_m)) if c != 0.0]
    return "constant" if not terms else "linear in " + " and ".join(terms)


def power_correction_block(battery: Any, propulsion: Any, runs: Sequence[Any],
                           relative_to: Any, propulsion_path: Any) -> dict[str, Any]:
    """The ``fit.power_correction`` block: the law, its tested span and the runs it came from.

    Parameters
    ----------
    battery : Battery
        The loaded battery file.
    propulsion : Propulsion
        The propulsion whose power model the runs are compared with.
    runs : sequence
        The discharge runs, in the battery file's order.
    relative_to : Path
        Folder of the file written (the propulsion path is written relative to it).
    propulsion_path : Path
        The propulsion file read.
    """
    import os

    model, label = run_model_power_w(battery, propulsion, runs)
    law = fit_power_correction(runs, model)
    return {
        "form": correction_form(law),
        **{k: v for k, v in law.to_dict().items()},
        "model": label,
        "propulsion": os.path.relpath(propulsion_path, relative_to),
        "runs": [{"file": os.path.relpath(r.path, relative_to),
                  "model_power_w": float(m), "ratio": float(r.mean_power_w / m)}
                 for r, m in zip(runs, model, strict=True)],
    }


# --- the battery file as a fitted artefact (issue 9) -------------------------------------------
CUTOFF_TIME_TOLERANCE = 0.25
"""Largest relative miss of a run's own time to cut-off by the pack fitted to the runs
(the shipped pack: < 1 %; a capacity 100x too large: 50x)."""


def refuse_unreproduced_runs(battery: Any, parameters: Any, runs: Sequence[Any]) -> None:
    """Bad input when the pack fitted to the runs misses a run's own time to cut-off.

    The equivalent circuit fits the voltage of each run; a ``capacity_ah`` far above the
    charge the runs drew lets that fit succeed while the state of charge barely moves, and
    the pack then "lasts" many times as long as any run did (an endurance PASS from a
    misprint). ``runs`` are discharge runs or their stored summaries (``mean_power_w``,
    ``start_charge_ah``, ``time_to_cutoff_s``).

    References
    ----------
    Paper section 4 (endurance from the measured discharge); issue 10 (never an endless
    endurance from a capacity the data contradict).
    """
    from tuflexperf.models.battery import time_to_cutoff_s

    for run in runs:
        observed = float(run.time_to_cutoff_s)
        if not observed > 0:
            continue
        predicted = float(time_to_cutoff_s(parameters, run.mean_power_w,
                                           battery.cutoff_voltage_v, 1, run.start_charge_ah))
        if not abs(predicted / observed - 1.0) <= CUTOFF_TIME_TOLERANCE:
            raise InputError(
                f"{battery.path}: capacity_ah: {battery.capacity_ah:g} Ah: the pack fitted to "
                f"the runs reaches cut-off after {predicted / 60:.1f} min at {run.path.name}'s "
                f"power, which reached it after {observed / 60:.1f} min; the runs contradict "
                "the capacity (or the cut-off voltage)"
            )


def _cross_validation(runs: Sequence[DischargeRun], cells: int, capacity_ah: float,
                      cutoff_v: float) -> list[dict[str, Any]]:
    """Each run's model (fitted on it alone) predicting every other run's time to cut-off."""
    from tuflexperf.models.battery import time_to_cutoff_s

    checks: list[dict[str, Any]] = []
    for k, source in enumerate(runs):
        alone = fit_discharge([source], cells, capacity_ah).parameters
        for j, target in enumerate(runs):
            if j != k:
                predicted = time_to_cutoff_s(alone, target.mean_power_w, cutoff_v, 1,
                                             target.start_charge_ah)
                checks.append({"fitted_on": source.path.name, "predicted_run": target.path.name,
                               "observed_min": target.time_to_cutoff_s / 60.0,
                               "predicted_min": predicted / 60.0})
    return checks


CUTOFF_REACHED_TOLERANCE = 0.02
"""A discharge run whose least loaded voltage stays more than this share above the file's
cut-off never reached it (the shipped runs end within 0.01 V of it)."""


def refuse_runs_short_of_the_cutoff(battery: Any, runs: Sequence[DischargeRun]) -> None:
    """Bad input: a discharge run that stopped before the pack's cut-off voltage.

    Its time under load is stored as the time to the cut-off and its charge as what the pack
    gave there: a run stopped at 43.6 V of a 40.8 V cut-off would be taken for a pack that
    lasts 17 % less.
    """
    cutoff = battery.cutoff_voltage_v
    for run in runs:
        loaded = run.voltage_v[run.loaded]
        # a pack under load discharges: its voltage falls from the step to the cut-off. One
        # that starts at or below the cut-off and rises is a swapped column, another pack or
        # a charge log
        tenth = max(1, loaded.size // 10)
        first, last = float(np.mean(loaded[:tenth])), float(np.mean(loaded[-tenth:]))
        if first <= cutoff * (1.0 + CUTOFF_REACHED_TOLERANCE) or last > first:
            raise InputError(
                f"{battery.path}: runs: {run.path.name}: its loaded voltage goes from "
                f"{first:.2f} V (first tenth) to {last:.2f} V (last tenth); a discharge run "
                f"falls from above the cut-off {cutoff:.2f} V to it (is voltage_v the pack's?)"
            )
        least = float(np.min(loaded))
        if least > cutoff * (1.0 + CUTOFF_REACHED_TOLERANCE):
            raise InputError(
                f"{battery.path}: runs: {run.path.name}: its loaded voltage stays at or above "
                f"{least:.2f} V, short of the cut-off {cutoff:.2f} V (cells_in_series x "
                "cutoff_voltage_per_cell_v): a discharge run measures the time to the cut-off; "
                "run it there, or give the cut-off its ESC used"
            )


def fit_battery_block(battery: Any, relative_to: Any,
                      propulsion_path: Any = None) -> dict[str, Any]:
    """The ``fit:`` block of a battery file: pack model, residual, runs (sha256), validation,
    and the measured power correction against ``propulsion_path``'s power model (none
    without a propulsion file).

    ``battery`` is a loaded :class:`tuflexperf.io.battery.Battery`; run paths are written
    relative to ``relative_to`` (the folder of the file written). A capacity the runs
    contradict (a run drew more than the pack holds) is bad input.
    """
    import os

    from tuflexperf.io.battery import refuse_contradicted_capacity, refuse_label_beyond_fitted
    from tuflexperf.io.discharge import read_discharge_run
    from tuflexperf.io.files import sha256_of

    runs = [read_discharge_run(r.path) for r in battery.runs]
    refuse_runs_short_of_the_cutoff(battery, runs)
    refuse_contradicted_capacity(battery, [(r.path.name, float(r.charge_ah[-1])) for r in runs])
    fit = fit_discharge(runs, battery.cells_in_series, battery.capacity_ah)
    refuse_unreproduced_runs(battery, fit.parameters, runs)
    refuse_label_beyond_fitted(battery.path, battery.capacity_ah, fit.parameters.max_capacity_ah)
    correction: dict[str, Any] = {}
    if propulsion_path is not None:
        from tuflexperf.io.case import load_propulsion

        correction = {"power_correction": power_correction_block(
            battery, load_propulsion(propulsion_path), runs, relative_to, propulsion_path)}
    return {
        "capacity_ah": float(battery.capacity_ah),
        "cells_in_series": int(battery.cells_in_series),
        "cutoff_voltage_per_cell_v": float(battery.cutoff_voltage_per_cell_v),
        "parameters": {k: float(v) for k, v in fit.parameters.to_dict().items()},
        "rms_v": float(fit.rms_v),
        "max_abs_v": float(fit.max_abs_v),
        "n_points": int(fit.n_points),
        # what the analyses need of each run (io.discharge.RunSummary), so that a fitted
        # battery file serves check without reading its runs
        "runs": [{"file": os.path.relpath(run.path, relative_to), "sha256": sha256_of(run.path),
                  "throttle": run.throttle_setting, "airspeed_m_s": run.airspeed_setting_m_s,
                  "mean_power_w": run.mean_power_w, "mean_force_n": run.mean_force_n,
                  "start_charge_ah": run.start_charge_ah,
                  "time_to_cutoff_s": run.time_to_cutoff_s,
                  "charge_drawn_ah": float(run.charge_ah[-1])} for run in runs],
        "cross_validation": _cross_validation(runs, battery.cells_in_series,
                                              battery.capacity_ah, battery.cutoff_voltage_v)
        if len(runs) > 1 else [],
        **correction,
    }


def fitted_battery_text(battery_path: Any, out_path: Any,
                        propulsion_path: Any = None) -> tuple[str, dict[str, Any]]:
    """The battery file with its ``fit:`` block (re)written, and the block.

    Written beside the input, the file's own text (and its provenance comments) is kept and
    only the ``fit:`` block replaced; elsewhere the whole file is written anew with the run
    paths made relative to the new place. The measured power correction is fitted against
    ``propulsion_path``'s power model (default: ``propulsion.yaml`` beside the battery file,
    where there is one; else none is written).
    """
    import os
    from pathlib import Path

    import yaml

    from tuflexperf.io.battery import load_battery
    from tuflexperf.io.files import SEAL
    from tuflexperf.io.yamlio import read_yaml

    battery_path, out_path = Path(battery_path), Path(out_path)
    battery = load_battery(battery_path, refitting=True)
    folder = out_path.absolute().parent
    if propulsion_path is None and (battery_path.parent / "propulsion.yaml").is_file():
        propulsion_path = battery_path.parent / "propulsion.yaml"
    block = fit_battery_block(battery, folder,
                              Path(propulsion_path).absolute() if propulsion_path else None)
    header = ("# fit: written by `tuflexperf fit` (equivalent circuit fitted to the runs, "
              "their sha256);\n# check, endurance and report read it and never fit.\n")
    dumped = yaml.safe_dump({"fit": block}, sort_keys=False, width=100)
    if folder == battery_path.absolute().parent:
        lines = battery_path.read_text(encoding="utf-8").splitlines(keepends=True)
        kept: list[str] = []
        skipping = False
        for line in lines:
            if line.startswith(SEAL):  # an earlier fit's seal: this text gets its own
                continue
            if line.startswith("fit:") or line.startswith("# fit: written by"):
                skipping = True
                continue
            if skipping and (line.startswith((" ", "\t", "#")) or not line.strip()):
                continue
            skipping = False
            kept.append(line)
        if kept and "written by `tuflexperf fit`" in kept[0]:
            kept = kept[1:]
        # first line says who wrote it, so a later fit may replace it (SPEC 5, nothing is lost)
        text = (f"# {battery.name}: written by `tuflexperf fit` from "
                f"{path_text(battery_path.name)}\n"
                + "".join(kept).rstrip("\n") + "\n" + header + dumped)
    else:
        data = read_yaml(battery_path)
        for entry in data.get("runs", []):
            entry["file"] = os.path.relpath(battery_path.parent / entry["file"], folder)
        data["fit"] = block
        text = (f"# {battery.name}: written by `tuflexperf fit` from "
                f"{path_text(battery_path.name)}\n"
                + yaml.safe_dump(data, sort_keys=False, width=100))
    return text, block
