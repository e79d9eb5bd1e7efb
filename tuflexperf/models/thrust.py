"""Electric ducted fan thrust: the paper's 2x2 polynomial per engine and the n-engine sum.

Paper section 4: ``T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2`` with
``x`` the throttle and ``v`` the airspeed in m/s (MATLAB ``fit(..., 'poly22')``).
Every function takes floats, numpy arrays or CasADi symbols.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from tuflexperf.models._math import Vectorizable, fmax, fmin, sqrt, where
from tuflexperf.models.atmosphere import SEA_LEVEL_DENSITY_KG_M3

_LARGEST = 1.7976931348623157e308  # the largest float

POLY22_TERMS: tuple[str, ...] = ("p00", "p10", "p01", "p20", "p11", "p02")
MAX_DELAY_S = 1.0
"""The longest dead time (and spool lag) a fan's model holds [s]: an EDF answers within tens
of ms (the paper's 0.05 s), and the shortest throttle plateau a run may hold is half a second."""
MAX_FAN_AREA_M2 = 10.0
"""The largest fan (or rotor disc) area [m^2] a model may name: a 3.5 m rotor; 4342 was an
area in mm^2 (outside audit)."""
MIN_FAN_AREA_M2 = 1.0e-5
"""The smallest fan area [m^2] a model or campaign may name: a 3.6 mm fan (1e-300 gave a
figure of merit 130 digits long; outside audit)."""
DeadEngineMode = Literal["windmilling", "zero"]


def poly22(x: Vectorizable, v: Vectorizable, coefficients: Mapping[str, float]) -> Vectorizable:
    """Evaluate ``p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2`` (paper section 4)."""
    c = coefficients
    return (
        c["p00"]
        + c["p10"] * x
        + c["p01"] * v
        + c["p20"] * x * x
        + c["p11"] * x * v
        + c["p02"] * v * v
    )


@dataclass(frozen=True)
class Engine:
    """One fan's thrust model.

    ``throttle_scale`` maps the interface throttle fraction to the variable the
    coefficients were fitted against (1 for a fraction, 100 for percent).
    ``covariance`` (6x6, :data:`POLY22_TERMS` order, N^2 in the coefficients' units),
    ``residual_sd_n`` and ``extrapolation_sd_n`` (N) are the fit's uncertainty, when known.
    """

    name: str
    coefficients: Mapping[str, float]
    throttle_scale: float = 1.0
    covariance: tuple[tuple[float, ...], ...] | None = None
    residual_sd_n: float | None = None
    extrapolation_sd_n: float | None = None
    # [m/s] beyond the rest of the tested airspeeds the left-out top one lay (the distance
    # extrapolation_sd_n is the error at), and the poly22's shape error [N] (lack of fit)
    extrapolation_distance_m_s: float | None = None
    extrapolation_worst_n: float | None = None  # the largest of those errors [N]
    # the signed mean of those errors (measured minus extrapolated) per m/s and its standard
    # error [N per m/s]; None: zero-mean (the fit gave none)
    extrapolation_bias_n_per_m_s: float | None = None
    extrapolation_bias_se_n_per_m_s: float | None = None
    model_form_sd_n: float | None = None
    # the lack of fit's shares of its mean square (offset, throttle, airspeed, throttle x
    # airspeed, airspeed squared; analysis.error_model); None: equal shares
    model_form_shares: tuple[float, ...] | None = None
    # the lack of fit's residual surface (throttle [file units], airspeed [m/s], mean residual
    # [N], holds) and one hold mean's pure error [N]; read by the sampler only
    model_form_residuals: tuple[tuple[float, float, float, int], ...] | None = None
    model_form_noise_n: float | None = None
    # a thrust added to the surface [N] (throttle fraction, airspeed): the sampled rows' mean
    # model-form error (analysis.error_model); None in the deterministic check
    thrust_offset: Callable[[Any, Any], Any] | None = None
    # C_d,wm on the propulsion's fan_area_m2, the disk (SPEC 3); None: min(T(0, V), 0)
    windmilling_drag_coefficient: float | None = None
    # poly22 electrical power surface in W (throttle fraction, airspeed m/s); None if unknown
    power_coefficients: Mapping[str, float] | None = None
    # (tested low [m/s], tested high [m/s], slope [N per m/s]): the thrust beyond the tested
    # airspeeds moved in proportion to the distance (the extrapolation reading's bound);
    # None: the polynomial as fitted
    extrapolation_offset: tuple[float, float, float] | None = None
    # measured over modelled power (models.power_correction.PowerCorrection), multiplying
    # the power surface; None: the surface as fitted
    power_correction: Any = None


# SPEC 3: rpm follows duty cycle times voltage, thrust rpm^2
DEFAULT_VOLTAGE_EXPONENT = 2.0


@dataclass(frozen=True)
class Propulsion:
    """The aircraft's engines and what their model is valid for.

    ``tested_airspeed_m_s`` is the (low, high) airspeed range the model was
    fitted on; beyond it the polynomial extrapolates. ``reference_density_kg_m3``
    is the test day's density, or ``None`` when thrust is used as measured.
    """

    name: str
    engines: tuple[Engine, ...]
    tested_airspeed_m_s: tuple[float, float]
    delay_s: float = 0.0
    reference_density_kg_m3: float | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)
    # the fan's disk area: momentum theory's least (ideal) power, the windmilling drag (SPEC 3)
    fan_area_m2: float | None = None
    # the jet (exit) area: the jet velocity; None: the disk area's (a jet no wider than it)
    jet_area_m2: float | None = None
    reference_voltage_v: float | None = None  # the tests' pack voltage (SPEC 3)
    voltage_exponent: float = DEFAULT_VOLTAGE_EXPONENT  # thrust ~ (U / U_ref)^n
    # first-order spool lag (s) on thrust after the dead time delay_s; 0 = the paper's pure delay
    lag_s: float = 0.0
    # the rig's systematic errors, 1 sd each (io.schemas.RigUncertaintySchema); None: undeclared
    rig_uncertainty: Mapping[str, Any] | None = None


def thrust_part(propulsion: Propulsion) -> Propulsion:
    """``propulsion`` with each engine's power correction left out: what its thrust reads,
    so the key of a problem built on the thrust alone (a reading of the case that moves
    only the fans' power shares that problem)."""
    return dataclasses.replace(propulsion, engines=tuple(
        dataclasses.replace(e, power_correction=None) for e in propulsion.engines))


def density_ratio(propulsion: Propulsion, density_kg_m3: Vectorizable) -> Vectorizable:
    """Thrust scale ``rho / rho_ref`` (1 when the model has no reference density)."""
    if propulsion.reference_density_kg_m3 is None:
        return 1.0
    return density_kg_m3 / propulsion.reference_density_kg_m3


def reference_basis_scale(propulsion: Propulsion, density_kg_m3: float | None) -> float:
    """Factor ``rho_ref / rho`` that brings a force measured at ``density_kg_m3`` onto the
    propulsion file's reference density [-] (1 when either density is unknown).

    Thrust and the structure's drag both scale with density, so a balance force, a thrust
    point and a drag are all carried onto the model's own basis by this one factor.

    Parameters
    ----------
    propulsion : Propulsion
        The model whose ``reference_density_kg_m3`` is the basis.
    density_kg_m3 : float or None
        Air density the force was measured at [kg/m^3].
    """
    if density_kg_m3 is None or propulsion.reference_density_kg_m3 is None:
        return 1.0
    return float(propulsion.reference_density_kg_m3 / density_kg_m3)


def unlapsed_density_warning(propulsion: Propulsion, density_kg_m3: float) -> str | None:
    """A warning when a model without reference density is used away from ISA sea level.

    Thrust scales with ``rho / rho_ref`` only where the propulsion file gives the
    test day's ``reference_density_kg_m3`` (SPEC 3); without it thrust is used as
    measured, which is only right near the density it was measured at. ISA sea
    level (1.225 kg/m^3) is taken as that density; beyond 0.5 % off it, say so.

    References
    ----------
    Raymer, *Aircraft Design*, section 13.3 (installed thrust varies with density ratio).
    """
    if propulsion.reference_density_kg_m3 is not None:
        return None
    change = density_kg_m3 / SEA_LEVEL_DENSITY_KG_M3 - 1.0
    if abs(change) <= 0.005:
        return None
    return (
        f"propulsion model {propulsion.name!r} gives no reference_density_kg_m3: thrust is used "
        f"as measured at {density_kg_m3:.3f} kg/m^3 ({100 * change:+.0f} % vs ISA sea level), "
        "not scaled with density"
    )


def reference_voltage_note(propulsion: Propulsion, what: str) -> str | None:
    """Say that ``what`` (take-off, trim, OEI) takes the thrust at the file's reference
    voltage: the pack sags below it in flight, and thrust with it (SPEC 3); the mission and
    the endurance fly the loaded voltage, these point analyses do not (outside audit)."""
    if propulsion.reference_voltage_v is None:
        return None
    return (f"{what} takes the thrust at the reference voltage {propulsion.reference_voltage_v:g}"
            f" V (x (U/U_ref)^{propulsion.voltage_exponent:g}); the pack's loaded voltage falls "
            "below it as it discharges: the mission flies it")


def engine_thrust_n(
    engine: Engine,
    throttle: Vectorizable,
    airspeed_m_s: Vectorizable,
    density_scale: Vectorizable = 1.0,
) -> Vectorizable:
    """Thrust of one engine in N at ``throttle`` (fraction) and ``airspeed_m_s`` (m/s).

    ``density_scale`` is ``rho / rho_ref`` (see :func:`density_ratio`). Beyond the tested
    airspeeds an engine's ``extrapolation_offset`` moves it (:func:`extrapolation_offset_n`).
    """
    thrust = poly22(throttle * engine.throttle_scale, airspeed_m_s, engine.coefficients)
    if engine.extrapolation_offset is not None:
        thrust = thrust + extrapolation_offset_n(engine, airspeed_m_s)
    if engine.thrust_offset is not None:
        thrust = thrust + engine.thrust_offset(throttle, airspeed_m_s)
    return density_scale * thrust


SPAN_PER_LEFT_OUT_STEP = 12.0
"""Without ``extrapolation_distance_m_s``: the left-out step taken as the tested span / 12
(the paper's 2.5 m/s top step of 0-30 m/s)."""


def extrapolation_leave_out(engine: Engine, tested_airspeed_m_s: tuple[float, float]
                            ) -> tuple[float, float]:
    """The thrust's leave-out error [N] (``extrapolation_worst_n`` where the fit gave it,
    else ``extrapolation_sd_n``; 0 for an engine that states neither) and the distance [m/s]
    it was measured at (``extrapolation_distance_m_s``, else the tested span /
    :data:`SPAN_PER_LEFT_OUT_STEP`)."""
    low, high = tested_airspeed_m_s
    step = engine.extrapolation_distance_m_s
    step = (high - low) / SPAN_PER_LEFT_OUT_STEP if step is None else float(step)
    base = engine.extrapolation_worst_n
    base = float(engine.extrapolation_sd_n or 0.0) if base is None else float(base)
    return base, step


@dataclass(frozen=True)
class ExtrapolationRate:
    """An engine's thrust error beyond its tested airspeeds, per m/s beyond them: its mean
    (the thrust the extrapolated surface misses, negative for a fan that loses thrust faster
    at speed) and its sd about that mean [N per m/s]."""

    mean_n_per_m_s: float
    sd_n_per_m_s: float

    def bound_n_per_m_s(self, z: float) -> float:
        """The rate at ``z`` sds below the mean [N per m/s] (the ``z`` lower bound)."""
        return self.mean_n_per_m_s - z * self.sd_n_per_m_s


def extrapolation_error_per_m_s(engine: Engine, tested_airspeed_m_s: tuple[float, float]
                                ) -> ExtrapolationRate:
    """The thrust's extrapolation error [N per m/s beyond the tested airspeeds].

    Its size is the :func:`extrapolation_leave_out` error over the distance it was measured
    at. Of that size the mean the fit measured (``extrapolation_bias_n_per_m_s``, measured
    minus extrapolated) counts only as far as its standard error supports it: shrunk to
    ``m (1 - se^2 / m^2)`` (0 where ``|m| <= se``: the positive-part James-Stein estimate of
    a mean measured once with error ``se``), the rest of the size is the sd about it, with
    the shrunk mean's own uncertainty ``se^2 (1 - se^2 / m^2)`` added. The mean was measured
    at the top of the tested range: where that range starts above 0 the same scalar would
    move the thrust below it too, so there it is not used (zero mean, the whole size sd).

    One rate for the samples' error (:mod:`tuflexperf.analysis.error_model`) and the
    deterministic bound (:mod:`tuflexperf.analysis.extrapolation_reading`), so the two judge
    the same extrapolation; the calibration study measured its coverage (docs/validation.md).
    """
    base, step = extrapolation_leave_out(engine, tested_airspeed_m_s)
    size = base / step if step > 0.0 else 0.0
    mean, extra = shrunk_extrapolation_bias(engine, tested_airspeed_m_s)
    return ExtrapolationRate(mean, math.sqrt(max(size * size - mean * mean, 0.0) + extra))


def shrunk_extrapolation_bias(engine: Engine, tested_airspeed_m_s: tuple[float, float]
                              ) -> tuple[float, float]:
    """The fit's extrapolation mean shrunk by its standard error [N per m/s] and the shrunk
    mean's variance [(N per m/s)^2] (:func:`extrapolation_error_per_m_s`); (0, 0) without a
    mean or where the tested airspeeds start above 0."""
    m = engine.extrapolation_bias_n_per_m_s
    if m is None or m == 0.0 or tested_airspeed_m_s[0] > 0.0:
        return 0.0, 0.0
    se = float(engine.extrapolation_bias_se_n_per_m_s or 0.0)
    keep = max(1.0 - se * se / (m * m), 0.0)
    return float(m) * keep, se * se * keep


def distance_beyond_m_s(tested_airspeed_m_s: tuple[float, float],
                        airspeed_m_s: Vectorizable) -> Vectorizable:
    """How far [m/s] airspeeds (a float, numpy array or CasADi expression) lie outside the
    tested airspeeds ``(low, high)``: 0 inside them, the distance below ``low`` or above
    ``high`` beyond them."""
    low, high = tested_airspeed_m_s
    return fmax(low - airspeed_m_s, 0.0) + fmax(airspeed_m_s - high, 0.0)


def extrapolation_offset_n(engine: Engine, airspeed_m_s: Vectorizable) -> Vectorizable:
    """The thrust offset [N] of ``engine`` at ``airspeed_m_s`` [m/s]: 0 inside its tested
    airspeeds, its ``extrapolation_offset`` slope [N per m/s] times the distance beyond them
    (continuous, so a level flight at a fixed throttle keeps its root near the tested edge),
    0 for an engine without one.

    The one place the offset is made: the single case (CasADi), the batches' rows and the
    mission's chained function all take it from here. Backend-neutral.
    """
    if engine.extrapolation_offset is None:
        return 0.0
    low, high, slope = engine.extrapolation_offset
    return slope * distance_beyond_m_s((low, high), airspeed_m_s)


def windmilling_thrust_n(
    engine: Engine,
    airspeed_m_s: Vectorizable,
    density_scale: Vectorizable = 1.0,
    density_kg_m3: Vectorizable = None,
    fan_area_m2: float | None = None,
) -> Vectorizable:
    """A dead engine's contribution in N, a drag and never a thrust (SPEC 3).

    With the engine's ``windmilling_drag_coefficient`` and the propulsion's ``fan_area_m2``
    (and the density): ``-Cd_wm q A_fan``; otherwise ``min(T(0, V), 0)`` of its own model.

    References
    ----------
    SPEC 3 (one engine inoperative, windmilling drag); Hoerner, *Fluid-Dynamic Drag*, ch. 3.
    """
    cd = engine.windmilling_drag_coefficient
    if cd is not None and fan_area_m2 is not None and density_kg_m3 is not None:
        return -abs(cd) * 0.5 * density_kg_m3 * airspeed_m_s * airspeed_m_s * fan_area_m2
    return fmin(engine_thrust_n(engine, 0.0, airspeed_m_s, density_scale), 0.0)


def total_thrust_n(
    propulsion: Propulsion,
    throttle: Vectorizable | Sequence[Vectorizable],
    airspeed_m_s: Vectorizable,
    density_kg_m3: Vectorizable,
    dead_engine: int | None = None,
    dead_engine_mode: DeadEngineMode = "windmilling",
) -> Vectorizable:
    """Sum of all engines' thrust in N, optionally with engine ``dead_engine`` inoperative.

    ``throttle`` is one value for all engines or a sequence with one per engine.
    A ``windmilling`` dead engine adds :func:`windmilling_thrust_n`; a ``zero`` one adds nothing.
    """
    engines = propulsion.engines
    throttles = list(throttle) if isinstance(throttle, (list, tuple)) else [throttle] * len(engines)
    if len(throttles) != len(engines):
        raise ValueError(f"{len(throttles)} throttles for {len(engines)} engines")
    scale = density_ratio(propulsion, density_kg_m3)
    total: Vectorizable = 0.0
    for index, (engine, x) in enumerate(zip(engines, throttles, strict=True)):
        if index == dead_engine:
            if dead_engine_mode == "windmilling":
                total = total + windmilling_thrust_n(
                    engine, airspeed_m_s, scale, density_kg_m3, propulsion.fan_area_m2
                )
        else:
            total = total + engine_thrust_n(engine, x, airspeed_m_s, scale)
    return total


def outside_tested_range(propulsion: Propulsion, airspeed_m_s: Any) -> Any:
    """Where airspeeds [m/s] (a float or a numpy array) lie outside the model's tested
    airspeed range, 1e-9 m/s of slack keeping a tested end inside (a bool or bool array).

    References
    ----------
    SPEC 3 (extrapolation is said); paper section 4 (tunnel limit 30 m/s).
    """
    return outside_tested_span(propulsion, airspeed_m_s, airspeed_m_s)


def outside_tested_span(propulsion: Propulsion, slowest_m_s: Any, fastest_m_s: Any) -> Any:
    """Where airspeeds flown continuously from ``slowest_m_s`` to ``fastest_m_s`` [m/s]
    (floats or numpy arrays) leave the model's tested airspeed range: the span reaches
    below its low end or above its high end (1e-9 m/s of slack, as
    :func:`outside_tested_range`). A ground roll from rest flies every airspeed up to the
    lift-off's: a model tested from 15 m/s up is extrapolated there, whatever the lift-off.

    References
    ----------
    SPEC 3 (extrapolation is said).
    """
    low, high = propulsion.tested_airspeed_m_s
    return (slowest_m_s < low - 1e-9) | (fastest_m_s > high + 1e-9)


def beyond_tested_m_s(propulsion: Propulsion, airspeed_m_s: Vectorizable) -> Vectorizable:
    """How far [m/s] airspeeds lie outside the model's tested airspeed range
    (:func:`distance_beyond_m_s`; the samples' extrapolation error grows in proportion to it).

    References
    ----------
    SPEC 3 (extrapolation is said); issue 44 (an extrapolation error that grows with the
    distance beyond the tested range).
    """
    return distance_beyond_m_s(propulsion.tested_airspeed_m_s, airspeed_m_s)


def is_extrapolated(propulsion: Propulsion, airspeed_m_s: float) -> bool:
    """True when ``airspeed_m_s`` lies outside the model's tested airspeed range."""
    return bool(outside_tested_range(propulsion, airspeed_m_s))


def least_throttle_reaching(
    a: Vectorizable, b: Vectorizable, c: Vectorizable
) -> tuple[Vectorizable, Vectorizable]:
    """Least ``x`` in [0, 1] with ``a x^2 + b x + c >= 0``, and whether one exists.

    Backend-neutral (floats, numpy arrays, CasADi SX). ``x = 0`` when ``c >= 0`` (idle suffices).
    Otherwise ``f(0) < 0`` and the answer is the least root in (0, 1]: the roots come from the
    cancellation-free form ``q = -(b + sign(b) sqrt(b^2 - 4ac)) / 2``, ``x = c / q`` and ``q / a``
    (Press et al., Numerical Recipes, 3rd ed., section 5.6), which stays accurate as ``a -> 0``
    (the linear case) and handles non-monotonic ``f`` (both roots are candidates). When no
    throttle reaches it, ``x`` is the throttle of the most thrust in [0, 1] and ``reached`` is 0.
    The export's generated C (``tuflexperf.export.c_code``) runs the same steps; the
    endurance analysis uses it for the least throttle of level flight.
    """
    disc = b * b - 4.0 * a * c
    root_disc = sqrt(where(disc > 0.0, disc, 0.0))
    q = -0.5 * (b + where(b >= 0.0, root_disc, -root_disc))
    r_near = where(q != 0.0, c / where(q != 0.0, q, 1.0), math.inf)
    r_far = where(a != 0.0, q / where(a != 0.0, a, 1.0), math.inf)

    def candidate(r: Vectorizable) -> Vectorizable:
        return where(disc >= 0.0, where(r > 0.0, where(r <= 1.0, r, math.inf), math.inf), math.inf)

    root = fmin(candidate(r_near), candidate(r_far))
    f_full = a + b + c
    # most thrust in [0, 1]: the vertex of a concave f if inside, else the better end
    vertex = -b / where(a != 0.0, 2.0 * a, 1.0)
    best_end = where(f_full > c, 1.0, 0.0)
    best = where(
        a < 0.0, where(vertex > 0.0, where(vertex < 1.0, vertex, best_end), best_end), best_end
    )
    # f(1) >= 0 with no root <= 1 only happens by rounding when the demand is T(1) itself
    # within rounding of zero (1e-12 of the terms) the demand is T(1) itself (as the export's C)
    # (a finite tolerance: an infinite demand, drag of a 1e308 C_D0, is never met at full)
    full_ok = f_full >= -1e-12 * fmin(abs(a) + abs(b) + abs(c), _LARGEST)
    throttle = where(c >= 0.0, 0.0, where(root <= 1.0, root, where(full_ok, 1.0, best)))
    reached = where(c >= 0.0, 1.0, where(root <= 1.0, 1.0, where(full_ok, 1.0, 0.0)))
    return throttle, reached


def least_throttle_of(excess: Callable[[float], Vectorizable]) -> tuple[Vectorizable, Vectorizable]:
    """Least throttle with ``excess(x) >= 0`` (``excess`` quadratic in ``x``), and if one exists.

    Poly22 thrust is quadratic in the throttle, and so is any sum of engines minus a drag
    that does not depend on it; three evaluations (``x = 0, 1/2, 1``) give its
    coefficients exactly, and :func:`least_throttle_reaching` the root. The one solver
    of the least level-flight throttle: trim, OEI, endurance, missions, batches and the
    export's inverse all come here (issue 9). Backend-neutral.

    Parameters
    ----------
    excess : callable
        ``excess(x)`` [N] at throttle ``x`` [fraction]: thrust minus the force to balance.

    Returns
    -------
    throttle, reached
        As :func:`least_throttle_reaching`.
    """
    e0, e_half, e1 = excess(0.0), excess(0.5), excess(1.0)
    return least_throttle_reaching(2.0 * (e1 + e0) - 4.0 * e_half, 4.0 * e_half - e1 - 3.0 * e0, e0)


def delay_samples(delay_s: float, sample_time_s: float) -> int:
    """Dead time in whole samples: ``round(delay_s / sample_time_s)``, half away from zero.

    Parameters
    ----------
    delay_s : float
        Throttle-to-thrust dead time [s].
    sample_time_s : float
        Sample time of the discrete simulation [s], > 0.

    Returns
    -------
    int
        Samples by which a throttle command is held back (the exported C uses the same rule).

    References
    ----------
    Paper section 4 (delay measured with a sine sweep).
    """
    if not (math.isfinite(sample_time_s) and sample_time_s > 0):
        raise ValueError(f"sample time must be a finite number > 0, got {sample_time_s}")
    return int(math.floor(delay_s / sample_time_s + 0.5))


def lag_factor(lag_s: float, sample_time_s: float) -> float:
    """Pole ``a = exp(-dt / lag_s)`` of the exact discrete first-order lag (0 for no lag).

    Parameters
    ----------
    lag_s : float
        Time constant of the spool lag [s]; 0 means none (the paper's pure delay).
    sample_time_s : float
        Sample time [s], > 0.

    Returns
    -------
    float
        ``a`` in ``y_k = a y_(k-1) + (1 - a) u_k`` [-].

    References
    ----------
    Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, 3rd ed., section 4.3.3
    (zero-order-hold equivalent of ``1 / (tau s + 1)``); the same recursion as the reduction's
    lag (``tuflexperf.reduction.delay``).
    """
    if not (math.isfinite(sample_time_s) and sample_time_s > 0):
        raise ValueError(f"sample time must be a finite number > 0, got {sample_time_s}")
    return math.exp(-sample_time_s / lag_s) if lag_s > 0 else 0.0


def lag_step(previous: Vectorizable, target: Vectorizable, factor: Vectorizable) -> Vectorizable:
    """One step of the spool lag: ``factor * previous + (1 - factor) * target``.

    Parameters
    ----------
    previous : float, array or CasADi
        Lagged thrust at the previous sample [N].
    target : float, array or CasADi
        Static thrust at this sample's delayed throttle [N].
    factor : float
        :func:`lag_factor` [-].

    Returns
    -------
    float, array or CasADi
        Lagged thrust at this sample [N]; equal to ``target`` when there is no lag.

    References
    ----------
    See :func:`lag_factor`.
    """
    return factor * previous + (1.0 - factor) * target


#: The model is refused above this many times its top tested airspeed, even where the polynomial
#: still looks physical (an extrapolation that far is no model).
AIRSPEED_CAP_FACTOR = 4.0


def max_model_airspeed_m_s(propulsion: Propulsion) -> float:
    """Airspeed above which the poly22 is no longer a fan's thrust law [m/s].

    A fan's thrust falls with airspeed (momentum theory, ``T = mdot (v_e - V)``); a poly22 with
    ``p02 > 0`` turns back up beyond the vertex of its ``v^2`` term and reports absurd thrust
    there (e.g. ~100 N "idle thrust" at 300 m/s). The limit is the least airspeed at which any
    engine's ``dT/dV = p01 + p11 x + 2 p02 V`` reaches 0 at throttle 0 or 1 (linear in ``x``,
    so the ends bound it), never below the top tested airspeed and never above
    :data:`AIRSPEED_CAP_FACTOR` times it.

    Parameters
    ----------
    propulsion : Propulsion
        The engines' poly22 models and their tested airspeed range.

    Returns
    -------
    float
        The limit [m/s].

    References
    ----------
    Paper section 4 (poly22, tested 0-30 m/s); Anderson, *Aircraft Performance and Design*,
    section 3.3 (momentum theory: thrust falls with flight speed).
    """
    high = float(propulsion.tested_airspeed_m_s[1])
    limit = AIRSPEED_CAP_FACTOR * high
    for engine in propulsion.engines:
        c = engine.coefficients
        curvature = 2.0 * float(c["p02"])
        if curvature <= 0.0:
            continue
        for x in (0.0, engine.throttle_scale):  # throttle 0 and 1 in the coefficients' unit
            slope_at_zero = float(c["p01"]) + float(c["p11"]) * x
            limit = min(limit, max(-slope_at_zero / curvature, high))
    return limit
