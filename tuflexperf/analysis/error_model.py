"""The sampler's error model: every source of error in the thrust and power models, named.

``check --samples`` draws these jointly (each sample one draw of every source) and lists
which it drew and which it could not, and why (:meth:`ErrorModel.to_dict`). Each source has
a place in a file where it is stated, and a default:

- ``covariance``: the fit's covariance of each engine's six poly22 coefficients
  (``engines[].covariance``); ``N(p, C)`` per engine. Default: none (not sampled, said).
- ``model_form``: the poly22's own shape error (``engines[].lack_of_fit.model_form_rms_n``,
  the fit's lack of fit; without it the fit's ``residual_sd_n``, an upper bound, said).
  Drawn as a random surface over the tested domain, ``sum_k z_k RMS sqrt(s_k) phi_k`` over
  the five shapes of :data:`~tuflexperf.reduction.lack_of_fit.MODEL_FORM_TERMS` (an offset,
  slopes in throttle ``u = 2x - 1`` and in airspeed ``t``, its place in the tested range on
  [-1, 1], their product, which changes sign along the throttle, and the Legendre quadratic
  ``(3t^2 - 1) / 2`` in airspeed, which changes sign twice along it), each scaled to a mean
  square of 1 over the domain, so the surface's mean square there is the lack of fit's RMS
  squared. The shares ``s_k`` say where the surface errs: ``fit`` estimates them from the
  size of its residuals along throttle and airspeed where the lack-of-fit test finds
  structure (``lack_of_fit.model_form_shares``); else a fifth each
  (:data:`MODEL_FORM_SHARES`). The RMS, not the largest residual: the largest of some 70
  holds' residuals is mostly their noise (bands twice too wide with it; docs/validation.md).
  One draw holds over every operating point of a requirement, so it does not average away
  across them (a constant offset on ``p00`` alone did, across the roll's airspeeds: issue
  44); correlated :data:`ENGINE_CORRELATION` between engines (fans of one design err alike).
  A poly22 perturbation holds no cubic: it follows a misfit's size, not its every sign.
  Where the file holds the fit's residual surface (``lack_of_fit.residuals``), the draw is
  centred on it instead: every sampled row's thrust adds the posterior mean of a Gaussian
  process over the set points' residuals (:mod:`tuflexperf.models.residual_surface`; at an
  operating point among the holds the error they show there, 0 far from them), and the
  five shapes' RMS is the posterior sd's RMS over the tested domain (what the holds leave
  open), not the lack of fit's. The deterministic check takes no mean (samples only).
- ``rig``: the test rig's systematic errors (top-level ``rig_uncertainty``, the campaign
  manifest's, copied by ``fit``): the tunnel's airspeed bias ``b`` (thrust read at ``v + b``),
  the balance's scale ``s`` (thrust x ``1 + s``) and zero (added), the pack voltage's error
  (thrust x ``(1 + dU / U)^n``, ``n`` the voltage exponent); one draw for the whole rig, the
  same for every engine. A key not stated takes :data:`RIG_DEFAULTS` (said, never zero).
- ``extrapolation``: beyond the tested airspeeds, a refit without the top tested airspeed
  errs there by ``extrapolation_worst_n`` at its worst throttle (else ``extrapolation_sd_n``,
  the RMS over its throttles), ``extrapolation_distance_m_s`` beyond the rest, by
  ``extrapolation_bias_n_per_m_s`` per m/s on average over its upper throttles (with its
  standard error): an error per m/s about that mean, shrunk by its standard error, with the
  rest of the size its sd (:func:`~tuflexperf.models.thrust.extrapolation_error_per_m_s`,
  the deterministic bound's too), drawn once per sample and engine (correlated
  :data:`ENGINE_CORRELATION` between engines) and added at each airspeed in proportion to
  its distance beyond the tested range (0 at its ends: a cruise 1 m/s beyond them carries a
  tenth of the error of a trim 10 m/s beyond).
- ``power_model``: the battery file's discharge runs (``fit.runs``) measured a power the
  power model gives otherwise; their RMS relative disagreement is drawn as a lognormal
  scale on every fan's electrical power. Not where the case is flown on the runs' measured
  power as a reading of its own (``fit.power_correction``,
  :mod:`tuflexperf.analysis.power_reading`): the samples are judged on the worse reading,
  which takes the disagreement whole; drawing it as well would count it twice.
- ``battery_fit``: the battery fit's own error, its cross-validation (``fit.cross_validation``:
  a run's time to cut-off predicted from the other's fit), drawn as a lognormal scale on
  the power (a time error of the packs is an energy error: ``t ~ E / P``).

The case's ``uncertainty.propulsion`` switches each off (``covariance``, ``model_form``,
``rig``, ``extrapolation``, ``power_model``, ``battery_fit``). The draws are vectorised over
the samples (a loop over at most a few engines, never over samples).

References
----------
Kennedy & O'Hagan (2001), "Bayesian calibration of computer models", JRSS B 63 (model
discrepancy as a correlated function, not independent noise); Coleman & Steele,
*Experimentation, Validation, and Uncertainty Analysis for Engineers*, 4th ed., ch. 3
(systematic errors of a calibration: one draw per test, not per point).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.model_form_mean import residual_surfaces
from tuflexperf.io.case import Case
from tuflexperf.io.schemas import RIG_UNCERTAINTY_DEFAULTS
from tuflexperf.models.aircraft import true_airspeed_m_s
from tuflexperf.models.thrust import (
    POLY22_TERMS,
    extrapolation_error_per_m_s,
    extrapolation_leave_out,
)
from tuflexperf.reduction.lack_of_fit import MODEL_FORM_TERMS

Array = NDArray[np.float64]

RIG_DEFAULTS: dict[str, float] = dict(RIG_UNCERTAINTY_DEFAULTS)
"""The rig errors (1 sd) drawn where ``rig_uncertainty`` does not state them (the schema's
stated defaults: a pitot-static tunnel's 0.2 m/s, a balance's 1 % and 0.05 N, 0.1 V)."""
RIG_KEYS: tuple[str, ...] = tuple(RIG_UNCERTAINTY_DEFAULTS)
"""The rig errors in the order of ``rig_uncertainty.correlation``."""
RIG_LABELS = {"airspeed_bias_sd_m_s": ("airspeed bias", "m/s"),
              "thrust_scale_sd": ("thrust scale", ""),
              "balance_zero_sd_n": ("balance zero", "N"),
              "voltage_sd_v": ("voltage", "V")}
MODEL_FORM_SHARES = (0.2, 0.2, 0.2, 0.2, 0.2)
"""The model-form mean square's shares along :data:`MODEL_FORM_TERMS` where the fit found no
structure to place it (or the file says none): none favoured."""
ENGINE_CORRELATION = 0.5
"""Correlation of the model-form error between engines (one design, not one fan)."""
NOMINAL_CELL_V = 3.7  # a LiPo cell's nominal voltage [V], where the battery gives none


@dataclass(frozen=True)
class Source:
    """One error source: its name, whether it is drawn, where it is stated, what or why."""

    name: str
    sampled: bool
    origin: str
    detail: str

    def to_dict(self) -> dict[str, Any]:
        key = "detail" if self.sampled else "why"
        return {"source": self.name, "from": self.origin, key: self.detail}


@dataclass(frozen=True)
class ErrorModel:
    """What :func:`draw_thrust` and :func:`draw_power_scale` draw, and the sources' account.

    ``covariance_roots`` per engine ``L`` with ``L L^T = C`` (None: not drawn);
    ``model_form_maps`` ``(E, 5, 6)``: the surface's five standard normals to coefficient
    changes [file units]; ``extrapolation_sd_n`` and ``extrapolation_mean_n`` ``(E,)`` [N
    per m/s beyond the tested range]; ``rig_sd`` ``(4,)`` in
    :data:`RIG_KEYS` order and ``rig_root`` its correlation's root; ``volt_fraction`` the
    thrust fraction per volt; ``power_sds`` the lognormal power scales' sds [-].
    """

    sources: tuple[Source, ...]
    covariance_roots: tuple[Array | None, ...] | None = None
    model_form_maps: Array | None = None
    extrapolation_sd_n: Array | None = None
    extrapolation_mean_n: Array | None = None
    rig_sd: Array | None = None
    rig_root: Array | None = None
    volt_fraction: float = 0.0
    power_sds: tuple[float, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {"sampled": [s.to_dict() for s in self.sources if s.sampled],
                "not_sampled": [s.to_dict() for s in self.sources if not s.sampled]}

    @property
    def sampled(self) -> list[str]:
        return [s.name for s in self.sources if s.sampled]


def psd_root(matrix: Array) -> Array:
    """``L`` with ``L L^T = M`` for a positive semi-definite ``M`` (eigen-decomposition)."""
    w, v = np.linalg.eigh(np.asarray(matrix, dtype=float))
    return v * np.sqrt(np.maximum(w, 0.0))


def _off(name: str, origin: str, switch: str) -> Source:
    return Source(name, False, origin, f"switched off (uncertainty.propulsion.{switch}: false)")


def error_model_for(case: Case, switches: Any) -> ErrorModel:
    """The case's error model under the ``uncertainty.propulsion`` ``switches``.

    Parameters
    ----------
    case : Case
        Its propulsion (covariance, lack of fit, rig, extrapolation) and battery files.
    switches : PropulsionUncertaintySchema
        Which sources the case draws.
    """
    prop = case.propulsion
    engines = prop.engines
    sources: list[Source] = []
    parts: dict[str, Any] = {}
    names = ", ".join(e.name for e in engines)

    origin = "propulsion engines[].covariance"
    with_cov = [e for e in engines if e.covariance is not None]
    if not switches.covariance:
        sources.append(_off("covariance", origin, "covariance"))
    elif not with_cov:
        sources.append(Source("covariance", False, origin,
                              f"no engine has a covariance ({names}): refit with `fit`"))
    else:
        parts["covariance_roots"] = tuple(
            psd_root(np.asarray(e.covariance)) if e.covariance is not None else None
            for e in engines)
        missing = [e.name for e in engines if e.covariance is None]
        sources.append(Source("covariance", True, origin,
                              "N(p, C) of the six coefficients of "
                              + ", ".join(e.name for e in with_cov)
                              + (f" (none for {', '.join(missing)})" if missing else "")))

    sources.append(_model_form(case, switches, parts))
    sources.append(_rig(case, switches, parts))
    sources.append(_extrapolation(case, switches, parts))
    power, battery = _power_sources(case, switches)
    sds = []
    for source, sd in (power, battery):
        sources.append(source)
        if source.sampled:
            sds.append(sd)
    parts["power_sds"] = tuple(sds)
    return ErrorModel(tuple(sources), **parts)


def _model_form(case: Case, switches: Any, parts: dict[str, Any]) -> Source:
    prop = case.propulsion
    origin = "propulsion engines[].lack_of_fit.model_form_rms_n, model_form_shares"
    if not (switches.model_form and switches.residual):
        which = "model_form" if not switches.model_form else "residual"
        return _off("model_form", origin, which)
    sds, said = [], []
    surfaces = residual_surfaces(prop)
    for e, surface in zip(prop.engines, surfaces, strict=True):
        if surface is not None:
            sds.append(surface.sd_n)
            said.append(f"{e.name} centred on the posterior mean of its {surface.points} "
                        f"set points' residuals (lack_of_fit.residuals; length scales "
                        f"{surface.length_fraction:g} of the tested span, hold-to-hold noise "
                        f"{surface.nugget_fraction:g} of the lack of fit's {e.model_form_sd_n:.3g} "
                        f"N squared, by marginal likelihood), spread its posterior sd's RMS "
                        f"{surface.sd_n:.3g} N")
            continue
        rms = e.model_form_sd_n if e.model_form_sd_n is not None else e.residual_sd_n
        if rms is None:
            sds.append(0.0)
            said.append(f"{e.name}: none (no lack_of_fit, no residual_sd_n)")
            continue
        how = (f"the lack of fit's RMS {rms:.3g} N" if e.model_form_sd_n is not None
               else f"residual_sd_n {rms:.3g} N: no lack_of_fit, an upper bound; refit to "
               "split it")
        shares = e.model_form_shares or MODEL_FORM_SHARES
        where = ("shares " + ", ".join(f"{n} {c:.2f}" for n, c in zip(MODEL_FORM_TERMS, shares,
                                                                     strict=True))
                 + (" (the fit's residuals)" if e.model_form_shares else " (equal: none "
                    "estimated)"))
        sds.append(float(rms))
        said.append(f"{e.name} {how}, {where}")
    if not any(sds):
        return Source("model_form", False, origin, "; ".join(said))
    low, high = prop.tested_airspeed_m_s
    span = high - low
    maps = np.zeros((len(prop.engines), len(MODEL_FORM_TERMS), len(POLY22_TERMS)))
    r3, r5 = math.sqrt(3.0), math.sqrt(5.0)
    a, b = 2.0 / span, -(high + low) / span  # t = a v + b
    for j, (engine, rms) in enumerate(zip(prop.engines, sds, strict=True)):
        k = engine.throttle_scale  # x = x_file / k, u = 2x - 1
        w = rms * np.sqrt(np.asarray(
            (engine.model_form_shares if surfaces[j] is None else None) or MODEL_FORM_SHARES))
        # columns p00, p10, p01, p20, p11, p02 of each shape (file units)
        maps[j, 0, 0] = w[0]  # 1
        maps[j, 1, [0, 1]] = r3 * w[1] * np.array([-1.0, 2.0 / k])  # sqrt3 u
        maps[j, 2, [0, 2]] = r3 * w[2] * np.array([b, a])  # sqrt3 t
        # 3 u t = 3 (2x/k - 1)(a v + b)
        maps[j, 3, [0, 1, 2, 4]] = 3.0 * w[3] * np.array([-b, 2.0 * b / k, -a, 2.0 * a / k])
        # sqrt5 (3 t^2 - 1) / 2
        maps[j, 4, [0, 2, 5]] = 0.5 * r5 * w[4] * np.array([3.0 * b * b - 1.0, 6.0 * a * b,
                                                            3.0 * a * a])
    parts["model_form_maps"] = maps
    return Source("model_form", True, origin,
                  "; ".join(said) + ": a random surface over throttle and airspeed (an offset, "
                  "slopes in throttle and airspeed, their product and a quadratic in airspeed, "
                  "each its share of the RMS's square, their mean square over the tested "
                  "domain the RMS's), "
                  f"correlated {ENGINE_CORRELATION:g} between engines")


def _rig(case: Case, switches: Any, parts: dict[str, Any]) -> Source:
    prop = case.propulsion
    origin = "propulsion rig_uncertainty"
    if not switches.rig:
        return _off("rig", origin, "rig")
    declared = dict(prop.rig_uncertainty or {})
    sd = np.zeros(len(RIG_KEYS))
    said = []
    for i, key in enumerate(RIG_KEYS):
        value = declared.get(key)
        label, unit = RIG_LABELS[key]
        default = value is None
        sd[i] = RIG_DEFAULTS[key] if default else float(value)
        text = (f"{100 * sd[i]:.3g} %" if key == "thrust_scale_sd" else f"{sd[i]:.3g} {unit}")
        said.append(f"{label} {text}" + (" (default: not stated)" if default else ""))
    reference = prop.reference_voltage_v
    volts_from = "reference_voltage_v"
    if reference is None and case.battery_path is not None:
        from tuflexperf.io.battery import case_battery

        battery = case_battery(case)
        reference = battery.nominal_voltage_v or battery.cells_in_series * NOMINAL_CELL_V
        volts_from = "the battery's nominal voltage"
    if reference is None:
        said[-1] += " not drawn (no reference_voltage_v and no battery to relate it to)"
        sd[3] = 0.0
        fraction = 0.0
    else:
        fraction = prop.voltage_exponent / reference
        said[-1] += f" = thrust {100 * fraction * sd[3]:.2g} % ({volts_from} {reference:g} V)"
    correlation = declared.get("correlation")
    parts["rig_sd"] = sd
    parts["rig_root"] = psd_root(np.asarray(correlation if correlation is not None
                                            else np.eye(len(RIG_KEYS)), dtype=float))
    parts["volt_fraction"] = fraction
    if not declared:
        said.append("no rig_uncertainty in the propulsion file: every rig error its default")
    return Source("rig", True, origin, "; ".join(said) + "; one draw for the whole rig")


def farthest_beyond_m_s(case: Case) -> float:
    """How far [m/s] beyond the tested airspeeds the case flies: the envelope's top above
    the range, the roll from rest below it (the least of every requirement's reach)."""
    low, high = case.propulsion.tested_airspeed_m_s
    far = 0.0
    envelope = case.requirements.envelope
    if envelope is not None:
        top = envelope.max_airspeed_m_s
        if top is None and envelope.max_airspeed_eas_m_s is not None:
            top = float(true_airspeed_m_s(envelope.max_airspeed_eas_m_s, case.density_kg_m3))
        if top is not None:
            far = max(far, float(top) - high)
    if low > 0.0 and (case.requirements.takeoff is not None
                      or case.requirements.endurance is not None):
        far = max(far, low)
    return far


def _extrapolation(case: Case, switches: Any, parts: dict[str, Any]) -> Source:
    prop = case.propulsion
    origin = "propulsion engines[].extrapolation_sd_n, extrapolation_distance_m_s"
    if not switches.extrapolation:
        return _off("extrapolation", origin, "extrapolation")
    if not any(e.extrapolation_sd_n or e.extrapolation_worst_n
               or e.extrapolation_bias_n_per_m_s for e in prop.engines):
        return Source("extrapolation", False, origin, "no engine has an extrapolation_sd_n")
    far = farthest_beyond_m_s(case)
    if far <= 0.0:
        return Source("extrapolation", False, origin,
                      "the case flies no airspeed beyond the tested range")
    low, high = prop.tested_airspeed_m_s
    sds, means, said = [], [], []
    for e in prop.engines:
        default = e.extrapolation_distance_m_s is None
        base, step = extrapolation_leave_out(e, (low, high))
        rate = extrapolation_error_per_m_s(e, (low, high))
        sds.append(rate.sd_n_per_m_s)
        means.append(rate.mean_n_per_m_s)
        said.append(f"{e.name} {rate.sd_n_per_m_s:.3g} N per m/s sd ({base:.3g} N "
                    + ("at its worst throttle" if e.extrapolation_worst_n is not None
                       else "RMS (extrapolation_sd_n)")
                    + (f" at {step:.3g} m/s" if base > 0.0 else "")
                    + (" (default: tested span / 12)" if default else "")
                    + ")" + _bias_said(e, rate.mean_n_per_m_s, low)
                    + f"; {rate.sd_n_per_m_s * far:.3g} N sd at the farthest)")
    parts["extrapolation_sd_n"] = np.asarray(sds)
    if any(means):
        parts["extrapolation_mean_n"] = np.asarray(means)
    return Source("extrapolation", True, origin,
                  f"up to {far:.3g} m/s beyond the tested {low:g}-{high:g} m/s: "
                  + "; ".join(said) + ", grown in proportion to each airspeed's distance "
                  "beyond the range")


def _bias_said(engine: Any, mean: float, low: float) -> str:
    """The extrapolation mean as drawn, or why none (the fit's, shrunk by its error)."""
    m = engine.extrapolation_bias_n_per_m_s
    if m is None:
        return ", zero mean (no extrapolation_bias_n_per_m_s)"
    if low > 0.0:
        return (f", zero mean: the fit's {m:+.3g} N per m/s was measured at the top of "
                f"the tested range, which starts at {low:g} m/s")
    se = engine.extrapolation_bias_se_n_per_m_s or 0.0
    return (f", mean {mean:+.3g} N per m/s (the fit's {m:+.3g} +- {se:.2g}, shrunk by its "
            "standard error)")


def _power_sources(case: Case, switches: Any) -> tuple[tuple[Source, float],
                                                       tuple[Source, float]]:
    """The power model against the discharge runs, and the battery fit's own error."""
    from tuflexperf.analysis.power_reading import measured_power_disputed

    power_origin, battery_origin = "battery fit.runs", "battery fit.cross_validation"
    uses_packs = any(getattr(case.requirements, name) is not None
                     for name in ("takeoff", "envelope", "oei", "endurance", "mission"))
    fitted = None
    if case.battery_path is not None and uses_packs:
        from tuflexperf.io.battery import case_battery

        fitted = case_battery(case).as_read.fitted
    if not switches.power_model:
        power = (_off("power_model", power_origin, "power_model"), 0.0)
    elif fitted is None:
        power = (Source("power_model", False, power_origin,
                        "no battery fit (no discharge runs to compare)" if uses_packs
                        else "no requirement flies on the packs"), 0.0)
    elif measured_power_disputed(case):
        # the reading is the disagreement taken whole: a spread of its size on top of it
        # would count it twice (the shipped endurance band, p05-p95, 9x as wide)
        power = (Source("power_model", False, "battery fit.power_correction",
                        "the discharge runs' measured power is flown as a reading of its own: "
                        "every sample is judged on the worse of it and the power model, so "
                        "their disagreement is not drawn again"), 0.0)
    else:
        power = _power_disagreement(case, fitted)
    if not switches.battery_fit:
        battery = (_off("battery_fit", battery_origin, "battery_fit"), 0.0)
    elif fitted is None or not fitted.cross_validation:
        battery = (Source("battery_fit", False, battery_origin,
                          "no battery fit" if fitted is None else
                          "the battery fit has no cross-validation (one run only)"), 0.0)
    else:
        errors = [c.predicted_min / c.observed_min - 1.0 for c in fitted.cross_validation
                  if c.observed_min > 0]
        sd = math.sqrt(sum(r * r for r in errors) / max(len(errors), 1))
        listed = ", ".join(f"{100 * r:+.1f} %" for r in errors)
        battery = (Source("battery_fit", True, battery_origin,
                          f"{100 * sd:.3g} % rms ({listed}): a lognormal scale on the power "
                          "the packs deliver"), sd)
    return power, battery


def _power_disagreement(case: Case, fitted: Any) -> tuple[Source, float]:
    from tuflexperf.analysis.batch_endurance import battery_side
    from tuflexperf.models.powertrain import PowerSurfaces, engine_power_w

    side = battery_side(case)
    engines = {e.name: e for e in case.propulsion.engines}
    ratios = []
    for run in fitted.runs:
        x, v = float(run.throttle), float(run.airspeed_m_s)
        if isinstance(side.power, PowerSurfaces):
            name = next((r.engine for r in side.battery.as_read.runs
                         if r.path.name == run.file.rsplit("/", 1)[-1]), None)
            engine = engines.get(name or "", case.propulsion.engines[0])
            modelled = engine_power_w(engine, x, v)
        else:
            modelled = side.power.electrical_power_w(x, v)
        modelled = float(np.asarray(modelled, dtype=float))
        if modelled > 0.0:
            ratios.append(run.mean_power_w / modelled - 1.0)
    if not ratios:
        return Source("power_model", False, "battery fit.runs",
                      "the power model gives no positive power at the runs' settings"), 0.0
    sd = math.sqrt(sum(r * r for r in ratios) / len(ratios))
    listed = ", ".join(f"{100 * r:+.0f} %" for r in ratios)
    return Source("power_model", True, "battery fit.runs",
                  f"{100 * sd:.3g} % rms (measured/modelled - 1: {listed}): a lognormal scale "
                  "on every fan's electrical power"), sd


def draw_thrust(rng: np.random.Generator, model: ErrorModel, nominal: Array,
                size: int) -> tuple[Array | None, Array | None]:
    """Each engine's coefficients ``(E, size, 6)`` [file units] and its error beyond the
    tested range ``(E, size)`` [N per m/s beyond it]; None where nothing perturbs them.

    Order of the draws: covariance (engine by engine), extrapolation, model form, rig.
    """
    count, terms = nominal.shape
    c: Array | None = None

    def coefficients() -> Array:
        nonlocal c
        if c is None:
            c = np.repeat(nominal[:, None, :], size, axis=1)
        return c

    if model.covariance_roots is not None:
        for j, root in enumerate(model.covariance_roots):
            if root is not None:
                coefficients()[j] += rng.standard_normal((size, terms)) @ root.T
    extrapolation = None
    if model.extrapolation_sd_n is not None:
        z = _between_engines(rng, (count, size))
        extrapolation = z * model.extrapolation_sd_n[:, None]
        if model.extrapolation_mean_n is not None:
            extrapolation += model.extrapolation_mean_n[:, None]
    if model.model_form_maps is not None:
        z = _between_engines(rng, (count, size, model.model_form_maps.shape[1]))
        coefficients()[...] += np.einsum("ebk,ekt->ebt", z, model.model_form_maps)
    if model.rig_sd is not None and model.rig_root is not None:
        errors = (rng.standard_normal((size, len(RIG_KEYS))) @ model.rig_root.T) * model.rig_sd
        _apply_rig(coefficients(), errors, model.volt_fraction)
    return c, extrapolation


def _between_engines(rng: np.random.Generator, shape: tuple[int, ...]) -> Array:
    """Standard normals ``shape`` (engines first), correlated :data:`ENGINE_CORRELATION`
    between engines: a part shared by all and a part each engine's own."""
    shared = rng.standard_normal((1, *shape[1:]))
    own = rng.standard_normal(shape)
    return math.sqrt(ENGINE_CORRELATION) * shared + math.sqrt(1.0 - ENGINE_CORRELATION) * own


def _apply_rig(c: Array, errors: Array, volt_fraction: float) -> None:
    """The rig's errors ``(size, 4)`` (:data:`RIG_KEYS` order) on the coefficients, in place:
    the thrust read at the tunnel's ``v + b``, scaled by the balance and the voltage, less
    the balance's zero."""
    b = errors[:, 0]
    p00, p10, p01, _, p11, p02 = (c[..., i] for i in range(6))
    # T(x, v + b) of the poly22: p00 + p01 b + p02 b^2, p10 + p11 b, p01 + 2 p02 b
    p00 += (p01 + p02 * b) * b
    p10 += p11 * b
    p01 += 2.0 * p02 * b
    scale = (1.0 + errors[:, 1]) * (1.0 + volt_fraction * errors[:, 3])
    c *= scale[None, :, None]
    c[..., 0] += errors[:, 2]


def draw_power_scale(rng: np.random.Generator, model: ErrorModel, size: int) -> Array | None:
    """Per sample the factor on every fan's electrical power [-] (lognormal), or None."""
    if not model.power_sds:
        return None
    sd = math.sqrt(sum(s * s for s in model.power_sds))
    return np.exp(rng.standard_normal(size) * sd)


def listed(sources: Sequence[Source]) -> list[str]:
    """One line per source for the terminal: what was drawn, or why not."""
    return [f"{'sampled' if s.sampled else 'not sampled'}: {s.name} ({s.origin}): {s.detail}"
            for s in sources]
