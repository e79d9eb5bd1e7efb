"""Schemas of the case (requirement file), aircraft and propulsion files (SPEC 4), the loaded
:class:`Case`, and the checks that need a whole case. Read by :mod:`tuflexperf.io.case` (the
loader) and :mod:`tuflexperf.io.dotted` (``--set`` keys) alike."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import (
    BeforeValidator,
    Field,
    ValidationInfo,
    field_validator,
    model_validator,
)

from tuflexperf.errors import InputError
from tuflexperf.io.yamlio import EngineName, FileName, Name, StrictModel, count_values
from tuflexperf.models._math import Vectorizable, is_symbolic
from tuflexperf.models.aircraft import (
    DEFAULT_LIFTOFF_SPEED_FACTOR,
    DEFAULT_OBSTACLE_HEIGHT_M,
    DEFAULT_TRANSITION_LOAD_FACTOR,
    EAS_REFERENCE_DENSITY_KG_M3,
    MAX_AIRSPEED_M_S,
    Aircraft,
    TakeoffConfig,
    true_airspeed_m_s,
)
from tuflexperf.models.atmosphere import G0_M_S2, isa_density_kg_m3
from tuflexperf.models.thrust import (
    DEFAULT_VOLTAGE_EXPONENT,
    MAX_DELAY_S,
    MAX_FAN_AREA_M2,
    MIN_FAN_AREA_M2,
    POLY22_TERMS,
    Engine,
    Propulsion,
)

Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
Fraction = Annotated[float, Field(ge=0, le=1)]


# Most Monte Carlo samples one check draws (block or --samples): ~1e8 already takes hours
MAX_SAMPLES = 100_000_000

# --- aircraft -------------------------------------------------------------------------------
# Highest cl_max a wing reaches (flapped and slotted ~3; beyond 5 only blown lift, which the
# drag polar does not model)
MAX_CL_MAX = 5.0
# Highest obstacle of the take-off [m]: the climb to it is flown at the field's density and
# gradient (FAR 23/25: 15 m or 10.7 m)
MAX_OBSTACLE_HEIGHT_M = 100.0
# Highest pack voltage [V] a propulsion file may name (electric aircraft run up to ~800 V)
MAX_REFERENCE_VOLTAGE_V = 1000.0
# beyond any subsonic airframe's speed (a textbook jet's table may reach past Mach 1 at
# altitude's lower speed of sound, so not MAX_AIRSPEED_M_S)
MAX_TESTED_AIRSPEED_M_S = 1000.0
MAX_THRUST_SD_N = 1.0e5
# a lack of fit's model_form_shares: offset, throttle, airspeed, throttle x airspeed, airspeed^2
MODEL_FORM_SHARE_COUNT = 5
MIN_RESIDUAL_ROWS = 7  # a lack of fit's residual surface: more set points than poly22's terms
"""The largest thrust error [N] (1 sd) a file may state: ten tonnes, no ducted fan's."""
# Largest exponent of thrust on the voltage ratio, either sign (2 by rpm ~ U; fit searches
# -2..6)
MAX_VOLTAGE_EXPONENT = 10.0

class TakeoffSchema(StrictModel):
    # the ground-roll attitude's lift coefficient is below the wing's most (cl_max's bound)
    cl_ground: Annotated[float, Field(ge=0, le=MAX_CL_MAX)]
    rolling_friction: Annotated[float, Field(ge=0, le=1)] = 0.04
    liftoff_speed_m_s: Positive | None = None  # EAS; replaces the factor
    liftoff_speed_factor: Annotated[float, Field(ge=1, le=3)] = DEFAULT_LIFTOFF_SPEED_FACTOR
    rotation_time_s: Annotated[float, Field(ge=0, le=30)] = 0.0
    # above 1.15^2 the arc is beyond cl_max: the obstacle distance says so (not attainable)
    transition_load_factor: Annotated[float, Field(gt=1, le=5)] = DEFAULT_TRANSITION_LOAD_FACTOR
    cd0_ground: Positive | None = None
    k_ground: NonNegative | None = None


# a thousand tonnes: beyond any aircraft a ducted fan flies (from ~1e154 kg the weight's
# square overflows)
MAX_MASS_KG = 1.0e6


MAX_WING_AREA_M2 = 1.0e4  # ten times an A380's: a 1e300 m^2 wing lifted off at 0 m/s


class AircraftSchema(StrictModel):
    file_kind: ClassVar[str] = "aircraft"  # named when another kind of file is given
    name: Name
    mass_kg: Annotated[float, Field(gt=0, le=MAX_MASS_KG)]
    wing_area_m2: Annotated[float, Field(gt=0, le=MAX_WING_AREA_M2)]
    cd0: Positive
    k: Positive
    cl_max: Annotated[float, Field(gt=0, le=MAX_CL_MAX)]
    takeoff: TakeoffSchema
    launch: Literal["runway", "catapult"] = "runway"
    # EAS at the end of the catapult stroke; below Mach 1
    launch_speed_m_s: Annotated[float, Field(gt=0, le=MAX_AIRSPEED_M_S)] | None = None
    launch_energy_j: Annotated[float, Field(ge=0)] | None = None  # from ground equipment

    @model_validator(mode="after")
    def _check(self) -> AircraftSchema:
        stall_eas = math.sqrt(
            2.0 * self.mass_kg * G0_M_S2
            / (EAS_REFERENCE_DENSITY_KG_M3 * self.wing_area_m2 * self.cl_max)
        )
        if stall_eas > MAX_AIRSPEED_M_S:  # a 1e-300 m^2 wing would "fly" at 1e150 m/s
            raise ValueError(
                f"stall speed {stall_eas:.3g} m/s EAS is beyond the speed of sound: check "
                "mass_kg, wing_area_m2 and cl_max"
            )
        if self.launch == "catapult":
            if self.launch_speed_m_s is None:
                raise ValueError("launch_speed_m_s: required with launch: catapult (EAS)")
            if self.launch_speed_m_s < stall_eas:
                raise ValueError(
                    f"launch_speed_m_s: {self.launch_speed_m_s:g} m/s (EAS) is below the stall "
                    f"speed {stall_eas:.2f} m/s EAS; a catapult must launch at or above stall"
                )
        elif self.launch_speed_m_s is not None or self.launch_energy_j is not None:
            raise ValueError("launch_speed_m_s/launch_energy_j: only with launch: catapult")
        elif self.takeoff.cl_ground > self.cl_max:  # it would hold the weight below stall
            raise ValueError(
                f"takeoff.cl_ground: {self.takeoff.cl_ground:g} is above cl_max "
                f"{self.cl_max:g}; on the runway too the wing lifts at most cl_max"
            )
        # the stall EAS is the same at every density, so the check belongs to the file
        liftoff = self.takeoff.liftoff_speed_m_s
        if liftoff is not None and liftoff < stall_eas:
            raise ValueError(
                f"takeoff.liftoff_speed_m_s: {liftoff:g} m/s (EAS) is below the stall speed "
                f"{stall_eas:.2f} m/s EAS (mass_kg, wing_area_m2, cl_max); lift-off needs >= stall"
            )
        return self


# --- propulsion -----------------------------------------------------------------------------
class Poly22Schema(StrictModel):
    p00: float
    p10: float
    p01: float
    p20: float
    p11: float
    p02: float


class PowerSurfaceSchema(StrictModel):
    """Electrical power of one fan, W, vs throttle fraction and airspeed (SPEC 4)."""

    model: Literal["poly22"]
    coefficients: Poly22Schema
    r2: float | None = None
    rmse_w: NonNegative | None = None
    n_points: Annotated[int, Field(ge=0)] | None = None


Probability = Annotated[float, Field(ge=0, le=1)]
Count = Annotated[int, Field(ge=0)]


class BestAlternativeSchema(StrictModel):
    """The form that fits the data best among those `fit` compares (not poly22)."""

    form: Name
    f_statistic: NonNegative | None = None
    p_value: Probability | None = None
    model_form_rms_n: NonNegative | None = None
    in_propulsion_file: bool = False


class LackOfFitSchema(StrictModel):
    """`fit`'s lack-of-fit test of an engine's surface (issue 43 item 4)."""

    f_statistic: NonNegative | None = None
    p_value: Probability | None = None
    model_form_rms_n: NonNegative | None = None  # the surface's bias beyond the holds' noise
    pure_error_rms_n: NonNegative | None = None  # one hold mean's repeatability
    dof_lack_of_fit: Count
    dof_pure_error: Count
    worst_throttle: Annotated[float, Field(ge=0)] | None = None
    # a set point: a static hold whose pitot reads a little below 0 may be at -0.5 m/s
    worst_airspeed_m_s: Annotated[float, Field(ge=-MAX_AIRSPEED_M_S,
                                               le=MAX_AIRSPEED_M_S)] | None = None
    worst_residual_n: float | None = None
    pure_error_basis: Literal["replicate_holds", "within_hold"] = "within_hold"
    best_alternative: BestAlternativeSchema | None = None
    # where the surface errs (offset, throttle, airspeed, throttle x airspeed, airspeed
    # squared): shares of its mean square, written by `fit` where the test finds structure
    model_form_shares: list[Probability] | None = None
    # the residual surface where the test finds structure, per set point: throttle (file
    # units), airspeed [m/s], mean residual measured minus surface [N], count of holds
    residuals: list[list[float]] | None = None

    @field_validator("residuals")
    @classmethod
    def _check_residuals(cls, rows: list[list[float]] | None) -> list[list[float]] | None:
        bad = [i for i, r in enumerate(rows or []) if len(r) != 4
               or not all(map(math.isfinite, r)) or r[0] < 0 or abs(r[1]) > MAX_AIRSPEED_M_S
               or r[3] < 1 or r[3] != int(r[3])]
        if rows is not None and (len(rows) < MIN_RESIDUAL_ROWS or bad):
            raise ValueError(f"must be at least {MIN_RESIDUAL_ROWS} rows [throttle >= 0, "
                             f"airspeed_m_s, residual_n, count >= 1 whole], finite; rows {bad}")
        return rows

    @field_validator("model_form_shares")
    @classmethod
    def _check_shares(cls, shares: list[float] | None) -> list[float] | None:
        if shares is not None and (len(shares) != MODEL_FORM_SHARE_COUNT
                                   or abs(sum(shares) - 1.0) > 1e-3):
            raise ValueError(f"must be {MODEL_FORM_SHARE_COUNT} shares (offset, throttle, "
                             "airspeed, throttle x airspeed, airspeed squared) summing to 1")
        return shares


class EngineSchema(StrictModel):
    name: EngineName
    coefficients: Poly22Schema
    r2: float | None = None
    rmse_n: NonNegative | None = None
    standard_errors: Poly22Schema | None = None
    n_points: Annotated[int, Field(ge=0)] | None = None
    covariance: list[list[float]] | None = None  # of p00..p02 (POLY22_TERMS order) [N^2]
    residual_sd_n: NonNegative | None = None
    extrapolation_sd_n: NonNegative | None = None
    # how far beyond the rest the left-out top airspeed lay [m/s]: extrapolation_sd_n is
    # the error at that distance, the sampler grows it with the distance flown beyond
    extrapolation_distance_m_s: Annotated[float, Field(gt=0, le=MAX_TESTED_AIRSPEED_M_S)] | \
        None = None
    # the largest of those errors over the left-out airspeed's throttles [N]
    extrapolation_worst_n: Annotated[float, Field(ge=0, le=MAX_THRUST_SD_N)] | None = None
    # the signed mean of those errors (measured minus extrapolated) per m/s of that distance
    # [N per m/s] and its standard error: the thrust a fan loses faster (or slower) at speed
    extrapolation_bias_n_per_m_s: Annotated[float, Field(ge=-MAX_THRUST_SD_N,
                                                         le=MAX_THRUST_SD_N)] | None = None
    extrapolation_bias_se_n_per_m_s: Annotated[float, Field(ge=0, le=MAX_THRUST_SD_N)] | \
        None = None

    @model_validator(mode="after")
    def _check_bias(self) -> EngineSchema:
        if self.extrapolation_bias_se_n_per_m_s is not None \
                and self.extrapolation_bias_n_per_m_s is None:
            raise ValueError("extrapolation_bias_se_n_per_m_s: given without "
                             "extrapolation_bias_n_per_m_s, the mean it is the error of")
        return self

    @model_validator(mode="after")
    def _check_covariance(self) -> EngineSchema:
        if self.covariance is None:
            return self
        matrix = self.covariance
        if len(matrix) != len(POLY22_TERMS) or any(len(r) != len(POLY22_TERMS) for r in matrix):
            raise ValueError("covariance: must be a 6x6 matrix (p00, p10, p01, p20, p11, p02)")
        values = [v for row in matrix for v in row]
        if not all(math.isfinite(v) for v in values):
            raise ValueError("covariance: must be finite")
        array = np.asarray(matrix, dtype=float)
        scale = max(float(np.abs(array).max()), 1e-300)
        if not np.allclose(array, array.T, rtol=1e-6, atol=1e-9 * scale):
            raise ValueError("covariance: must be symmetric")
        if float(np.linalg.eigvalsh(array).min()) < -1e-9 * scale:
            raise ValueError("covariance: must be positive semi-definite")
        return self
    windmilling_drag_coefficient: NonNegative | None = None
    power: PowerSurfaceSchema | None = None
    lack_of_fit: LackOfFitSchema | None = None


# --- rig systematic errors (issue 44) ---------------------------------------------------------
# Stated defaults for a rig that declares none (standard deviations; docs/formats.md says why):
# a pitot-static tunnel speed calibrated to ~1 % of 20-30 m/s; a load cell calibrated with dead
# weights to ~0.5 % plus ~0.5-1 % from the balance's mounting; a balance zero that drifts by a
# few hundredths of a newton between tare and run; a pack voltage read by an ADC to ~0.2 %.
RIG_UNCERTAINTY_DEFAULTS: dict[str, float] = {
    "airspeed_bias_sd_m_s": 0.2,
    "thrust_scale_sd": 0.01,
    "balance_zero_sd_n": 0.05,
    "voltage_sd_v": 0.1,
}
# Beyond these a standard deviation is no calibrated rig's but a typo (or the wrong unit):
# a tunnel speed off by 5 m/s, a balance off by a quarter of its reading
MAX_AIRSPEED_BIAS_SD_M_S = 5.0
MAX_THRUST_SCALE_SD = 0.25
MAX_BALANCE_ZERO_SD_N = 100.0
MAX_VOLTAGE_SD_V = 50.0


class RigUncertaintySchema(StrictModel):
    """Systematic errors of the test rig, standard deviations (issue 44): the tunnel's airspeed
    calibration [m/s], the balance's scale (a fraction of the thrust) and zero [N], and the
    pack voltage [V]. A key left out takes :data:`RIG_UNCERTAINTY_DEFAULTS` (stated, never 0)."""

    airspeed_bias_sd_m_s: Annotated[float, Field(ge=0, le=MAX_AIRSPEED_BIAS_SD_M_S)] | None = None
    thrust_scale_sd: Annotated[float, Field(ge=0, le=MAX_THRUST_SCALE_SD)] | None = None
    balance_zero_sd_n: Annotated[float, Field(ge=0, le=MAX_BALANCE_ZERO_SD_N)] | None = None
    voltage_sd_v: Annotated[float, Field(ge=0, le=MAX_VOLTAGE_SD_V)] | None = None
    # where two errors share a cause (4x4, the order of RIG_UNCERTAINTY_DEFAULTS); None: none
    correlation: list[list[float]] | None = None

    @field_validator("correlation")
    @classmethod
    def _check_correlation(cls, matrix: list[list[float]] | None) -> list[list[float]] | None:
        if matrix is None:
            return matrix
        n = len(RIG_UNCERTAINTY_DEFAULTS)
        if len(matrix) != n or any(len(row) != n for row in matrix):
            raise ValueError(f"must be a {n}x{n} matrix ({', '.join(RIG_UNCERTAINTY_DEFAULTS)})")
        array = np.asarray(matrix, dtype=float)
        if not np.all(np.isfinite(array)) or np.any(np.abs(array) > 1.0):
            raise ValueError("every entry must be finite and within [-1, 1]")
        if not np.allclose(np.diag(array), 1.0):
            raise ValueError("the diagonal must be 1")
        if not np.allclose(array, array.T, atol=1e-12):
            raise ValueError("must be symmetric")
        if float(np.linalg.eigvalsh(array).min()) < -1e-9:
            raise ValueError("must be positive semi-definite (no set of errors has these "
                             "correlations)")
        return matrix

    def resolved(self) -> dict[str, float]:
        """Every key's standard deviation: the stated one, else the default."""
        return {key: (RIG_UNCERTAINTY_DEFAULTS[key] if getattr(self, key) is None
                      else float(getattr(self, key))) for key in RIG_UNCERTAINTY_DEFAULTS}

    def declared(self) -> tuple[str, ...]:
        """The keys the file states (the others are defaults)."""
        return tuple(key for key in RIG_UNCERTAINTY_DEFAULTS if getattr(self, key) is not None)


def rig_uncertainty_problems(
    rig: RigUncertaintySchema, largest_airspeed_m_s: float | None,
    largest_thrust_n: float | None, voltage_v: float | None,
) -> list[str]:
    """Where a stated systematic error is larger than the quantity it is an error of [one line
    each, naming the key]: the highest airspeed [m/s], the largest thrust [N], the pack
    voltage [V] (None: not known here, not checked)."""
    values = rig.resolved()
    declared = rig.declared()  # a default is never the user's mistake to be named
    problems = []
    for key, quantity, what in (
        ("airspeed_bias_sd_m_s", largest_airspeed_m_s, "the highest airspeed tested"),
        ("balance_zero_sd_n", largest_thrust_n, "the largest thrust"),
        ("voltage_sd_v", voltage_v, "the pack voltage"),
    ):
        if key in declared and quantity is not None and quantity > 0 and \
                values[key] >= quantity:
            problems.append(f"rig_uncertainty.{key}: {values[key]:g} is not below {what} "
                            f"({quantity:.4g}): a systematic error larger than the quantity")
    return problems


# fit's own provenance holds ~9 values per run (~150 for the shipped campaign): a million is
# a campaign of 100,000 runs, and far below what an alias bomb expands to (9^10)
MAX_SOURCE_VALUES = 1_000_000




# A file without ``format: 2`` that gives an area is in the old form: the number may be the
# jet area (the earlier shipped TU-Flex file) or the disk area (`fit`, `init`); no guess.
OLD_AREA_FORM = (
    "the file is in the old form (no 'format: 2'), where fan_area_m2 held the jet "
    "area or the disk area; now fan_area_m2 is the fan's disk area (pi d^2 / 4) and the jet "
    "(exit) area has its own key jet_area_m2. If the number is the jet area (the earlier "
    "shipped TU-Flex file's 0.004342), rename the key to jet_area_m2, give the disk area as "
    "fan_area_m2 and multiply each windmilling_drag_coefficient by jet/disk area; if it is "
    "the disk area (as `fit` and `init` wrote it), keep it. Then add 'format: 2'"
)


class PropulsionSchema(StrictModel):
    file_kind: ClassVar[str] = "propulsion"  # named when another kind of file is given
    name: Name
    model: Literal["poly22"]
    # airspeeds tested in the tunnel: none negative (a range of [-30, 30] was taken)
    tested_airspeed_m_s: Annotated[list[Annotated[float, Field(ge=0)]],
                                   Field(min_length=2, max_length=2)]
    # a dead time or lag beyond MAX_DELAY_S is no fan's
    delay_s: Annotated[float, Field(ge=0.0, le=MAX_DELAY_S)] = 0.0
    lag_s: Annotated[float, Field(ge=0.0, le=MAX_DELAY_S)] = 0.0  # spool lag after delay_s
    # the test day's air: a test stand or tunnel is on the ground (ISA 11 km is 0.36; the
    # coldest sea-level air ~1.5); 1e-9 would scale the thrust 1e9-fold into a PASS
    reference_density_kg_m3: Annotated[float, Field(ge=0.3, le=2.0)] | None = None
    # a pack of any aircraft a ducted fan flies, and thrust ~ U^2 (rpm ~ U); beyond these the
    # powers of the voltage ratio overflow with a message naming no key
    reference_voltage_v: Annotated[float, Field(gt=0, le=MAX_REFERENCE_VOLTAGE_V)] | None = None
    voltage_exponent: Annotated[float, Field(ge=-MAX_VOLTAGE_EXPONENT, le=MAX_VOLTAGE_EXPONENT)] = \
        DEFAULT_VOLTAGE_EXPONENT
    # format 2 (issue 43): fan_area_m2 is the fan's disk area, the jet/exit area jet_area_m2;
    # before it fan_area_m2 held either (the shipped file the jet area, fit the disk area)
    format: Literal[2] | None = None
    fan_area_m2: Annotated[float, Field(ge=MIN_FAN_AREA_M2, le=MAX_FAN_AREA_M2)] | None = None
    jet_area_m2: Annotated[float, Field(ge=MIN_FAN_AREA_M2, le=MAX_FAN_AREA_M2)] | None = None
    throttle_unit: Literal["fraction", "percent"] = "fraction"
    engines: Annotated[list[EngineSchema], Field(min_length=1)]
    source: dict[str, Any] | None = None  # free-form provenance written by `fit`
    # the rig's systematic errors (issue 44): written by `fit`, sampled by --samples
    rig_uncertainty: RigUncertaintySchema | None = None

    @field_validator("fan_area_m2", "jet_area_m2")
    @classmethod
    def _stated_form(cls, value: float | None, info: ValidationInfo) -> float | None:
        # format precedes the areas: an area without it is the old form (OLD_AREA_FORM)
        if value is not None and info.data.get("format") is None:
            raise ValueError(OLD_AREA_FORM if info.field_name == "fan_area_m2" else
                             "needs 'format: 2' (fan_area_m2 the disk area, jet_area_m2 the "
                             "jet's; docs/formats.md, Fan and jet area)")
        return value

    @field_validator("source", mode="before")
    @classmethod
    def _bounded_source(cls, value: Any) -> Any:
        # YAML aliases share one object many times: nine levels of nine expand to 4e8 values
        # that the exports would write out until memory ran out; count, then stop
        if count_values(value, MAX_SOURCE_VALUES) > MAX_SOURCE_VALUES:
            raise ValueError(f"more than {MAX_SOURCE_VALUES} values once its aliases are "
                             "expanded: write the provenance out plainly")
        return value

    @model_validator(mode="after")
    def _check(self) -> PropulsionSchema:
        low, high = self.tested_airspeed_m_s
        if not low < high:
            raise ValueError(f"tested_airspeed_m_s: low {low} must be below high {high}")
        if not (-MAX_TESTED_AIRSPEED_M_S <= low and high <= MAX_TESTED_AIRSPEED_M_S):
            # [0, 1e308] silenced every extrapolation note and the exports' airspeed clip
            raise ValueError(f"tested_airspeed_m_s: [{low:g}, {high:g}] m/s is no range a "
                             f"thrust model was measured over (at most "
                             f"{MAX_TESTED_AIRSPEED_M_S:g} m/s)")
        names = [engine.name for engine in self.engines]
        if len(set(names)) != len(names):
            raise ValueError(f"engines: duplicate engine names {names}")
        for engine in self.engines:
            if engine.windmilling_drag_coefficient is not None and self.fan_area_m2 is None:
                raise ValueError(
                    f"engines: {engine.name}: windmilling_drag_coefficient needs fan_area_m2"
                )
        if self.rig_uncertainty is not None:
            full = 100.0 if self.throttle_unit == "percent" else 1.0  # full throttle, static
            static = min(c.p00 + c.p10 * full + c.p20 * full * full
                         for c in (engine.coefficients for engine in self.engines))
            problems = rig_uncertainty_problems(self.rig_uncertainty, high, static,
                                                self.reference_voltage_v)
            if problems:
                raise ValueError("; ".join(problems))
        return self


# --- case -----------------------------------------------------------------------------------
class AtmosphereSchema(StrictModel):
    altitude_m: Annotated[float, Field(ge=-1000, le=20000)] = 0.0
    temperature_offset_k: Annotated[float, Field(ge=-80, le=80)] = 0.0


class TakeoffRequirement(StrictModel):
    max_ground_roll_m: Positive | None = None
    max_distance_to_obstacle_m: Positive | None = None
    obstacle_height_m: Annotated[
        float, Field(gt=0, le=MAX_OBSTACLE_HEIGHT_M)
    ] = DEFAULT_OBSTACLE_HEIGHT_M  # FAR 23: 50 ft

    @model_validator(mode="after")
    def _check(self) -> TakeoffRequirement:
        if self.max_ground_roll_m is None and self.max_distance_to_obstacle_m is None:
            raise ValueError(
                "give max_ground_roll_m and/or max_distance_to_obstacle_m (nothing to check)"
            )
        return self


Airspeed = Annotated[float, Field(gt=0, le=MAX_AIRSPEED_M_S)]  # below Mach 1: poly22 at low speed


class EnvelopeRequirement(StrictModel):
    """The airspeeds trim and OEI are solved over: each bound a true airspeed (``..._m_s``)
    or an equivalent one (``..._eas_m_s``, SPEC 3: true airspeed unless a key says ``_eas``)."""

    min_airspeed_m_s: Positive | None = None
    max_airspeed_m_s: Airspeed | None = None
    min_airspeed_eas_m_s: Positive | None = None
    max_airspeed_eas_m_s: Airspeed | None = None
    max_trim_throttle: Fraction = 1.0
    stall_margin: Annotated[float, Field(ge=1, le=3)] = 1.0  # level flight needs V >= this x stall

    @model_validator(mode="after")
    def _check(self) -> EnvelopeRequirement:
        for end in ("min", "max"):
            true, equivalent = (getattr(self, f"{end}_airspeed_m_s"),
                                getattr(self, f"{end}_airspeed_eas_m_s"))
            if (true is None) == (equivalent is None):
                raise ValueError(
                    f"give {end}_airspeed_m_s (true airspeed) or {end}_airspeed_eas_m_s "
                    f"(equivalent airspeed), {'not both' if true is not None else 'one of them'}"
                )
        for suffix in ("m_s", "eas_m_s"):  # bounds of one kind compare at any density
            low = getattr(self, f"min_airspeed_{suffix}")
            high = getattr(self, f"max_airspeed_{suffix}")
            if low is not None and high is not None and not low < high:
                raise ValueError(f"min_airspeed_{suffix} ({low}) must be below "
                                 f"max_airspeed_{suffix} ({high})")
        return self

    @property
    def in_eas(self) -> bool:
        """Whether a bound is an equivalent airspeed (its true airspeed follows the density)."""
        return self.min_airspeed_eas_m_s is not None or self.max_airspeed_eas_m_s is not None

    def bounds_m_s(self, density_kg_m3: Vectorizable) -> tuple[Any, Any]:
        """The envelope's (least, greatest) true airspeed [m/s] at ``density_kg_m3`` [kg/m^3].

        Floats for a float density; a symbolic density (CasADi, the sensitivities) gives an
        equivalent-airspeed bound as the expression that moves with it.

        References
        ----------
        SPEC 3 (airspeeds the pilot sets are EAS; envelope bounds true unless ``_eas``).
        """
        def true(tas: float | None, eas: float | None) -> Any:
            if tas is not None:
                return float(tas)
            speed = true_airspeed_m_s(float(eas), density_kg_m3)  # type: ignore[arg-type]
            return speed if is_symbolic(speed) else float(speed)

        return (true(self.min_airspeed_m_s, self.min_airspeed_eas_m_s),
                true(self.max_airspeed_m_s, self.max_airspeed_eas_m_s))


class OeiRequirement(StrictModel):
    dead_engine: Literal["windmilling", "zero"] = "windmilling"
    max_throttle: Fraction = 1.0


class EnduranceRequirement(StrictModel):
    throttle: Fraction
    min_flight_time_min: Positive


class MissionRequirement(StrictModel):
    """A mission file (path relative to the case) and the charge to land with (SPEC 4)."""

    file: FileName
    min_landing_charge_fraction: Annotated[float, Field(ge=0, lt=1)] = 0.2


def refuse_null_block(value: Any, what: str, hint: str) -> Any:
    """``value`` unless it is null (a bare ``key:``), which drops a block without a word."""
    if value is None:
        raise ValueError(f"{what} is empty (null): leave it out, or give its keys{hint}")
    return value


EXTRAPOLATION_REQUIRED_PROBABILITY = 0.9
"""The least P(met) of a requirement that rests on thrust beyond the tested airspeeds, where
the case states none (issue 43: below it the verdict is UNPROVEN)."""


class ExtrapolationRequirement(StrictModel):
    """How sure a requirement resting on extrapolated thrust must be (the band of the
    propulsion file's ``extrapolation_sd_n``)."""

    # below 1: a normal band has no bound at P = 1
    required_probability: Annotated[float, Field(gt=0.5, lt=1)] = (
        EXTRAPOLATION_REQUIRED_PROBABILITY)


class Requirements(StrictModel):
    takeoff: TakeoffRequirement | None = None
    envelope: EnvelopeRequirement | None = None
    oei: OeiRequirement | None = None
    endurance: EnduranceRequirement | None = None
    mission: MissionRequirement | None = None
    # always there (its default): --set may change it in a case that does not state it
    extrapolation: ExtrapolationRequirement = ExtrapolationRequirement()

    @field_validator("*", mode="before")
    @classmethod
    def _no_null_block(cls, value: Any) -> Any:
        # `takeoff: null` (or a bare `takeoff:`) would drop the requirement without a word:
        # leave a block out, or give its keys
        return refuse_null_block(value, "the requirement block", "")


class DistributionSchema(StrictModel):
    """Exactly one of: ``normal: [mean, sd]``, ``uniform: [low, high]``,
    ``truncated_normal: [mean, sd, low, high]``."""

    normal: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    uniform: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    truncated_normal: Annotated[list[float], Field(min_length=4, max_length=4)] | None = None

    @model_validator(mode="after")
    def _check(self) -> DistributionSchema:
        given = [k for k in ("normal", "uniform", "truncated_normal") if getattr(self, k)]
        if len(given) != 1:
            raise ValueError("give exactly one of normal, uniform, truncated_normal")
        values = getattr(self, given[0])
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"{given[0]}: values must be finite")
        if given[0] == "normal" and values[1] < 0:
            raise ValueError("normal: [mean, sd] needs sd >= 0")
        if given[0] == "uniform" and not values[0] <= values[1]:
            raise ValueError("uniform: [low, high] needs low <= high")
        if given[0] == "truncated_normal" and not (values[1] > 0 and values[2] < values[3]):
            raise ValueError("truncated_normal: [mean, sd, low, high] needs sd > 0, low < high")
        return self

    @property
    def kind(self) -> str:
        return next(k for k in ("normal", "uniform", "truncated_normal") if getattr(self, k))

    @property
    def arguments(self) -> list[float]:
        return list(getattr(self, self.kind))


class PropulsionUncertaintySchema(StrictModel):
    covariance: bool = True
    extrapolation: bool = True
    # the fit's residual_sd_n as the model's own error at a point (the paper's +-0.5 N):
    # the coefficients' covariance is the mean surface's uncertainty alone. The older name
    # of model_form: either false leaves the model-form surface out
    residual: bool = True
    model_form: bool = True  # the poly22's shape error, a correlated surface (lack_of_fit)
    rig: bool = True  # the rig's systematic errors (rig_uncertainty, else stated defaults)
    power_model: bool = True  # the power model against the battery's discharge runs
    battery_fit: bool = True  # the battery fit's own error (its cross-validation)


def _whole_number(value: Any) -> Any:
    """``1e5`` is how a count is often written, and YAML reads it as a float: a whole one is
    the integer (``1e9`` then names the cap, not "not a valid integer"); 2.5 stays refused."""
    if isinstance(value, float) and value.is_integer() and abs(value) < 2.0 ** 63:
        return int(value)
    return value


class UncertaintySchema(StrictModel):
    samples: Annotated[int, BeforeValidator(_whole_number), Field(ge=1, le=MAX_SAMPLES)] = 10_000
    seed: Annotated[int, BeforeValidator(_whole_number), Field(ge=0)] = 1
    # below 1: the lower confidence bound of P(met) never reaches 1 with finite samples
    required_probability: Annotated[float, Field(gt=0, lt=1)] = 0.95
    propulsion: PropulsionUncertaintySchema = PropulsionUncertaintySchema()
    parameters: dict[str, DistributionSchema] = {}


class ValidationSchema(StrictModel):
    """Flown evidence the case is held to (issue 45 item 3)."""

    # flight summaries written by `flightlog LOG --case CASE --summary FILE`, relative to
    # the case file: check reads them and never the logs
    flights: Annotated[list[FileName], Field(min_length=1)]


class CaseSchema(StrictModel):
    file_kind: ClassVar[str] = "case"  # named when another kind of file is given
    name: Name
    aircraft: FileName
    propulsion: FileName
    battery: FileName | None = None
    atmosphere: AtmosphereSchema = AtmosphereSchema()
    requirements: Requirements = Requirements()
    uncertainty: UncertaintySchema | None = None
    validation: ValidationSchema | None = None

    @field_validator("uncertainty", mode="before")
    @classmethod
    def _no_null_uncertainty(cls, value: Any) -> Any:
        # a bare `uncertainty:` would turn the probabilistic check off without a word
        return refuse_null_block(value, "the uncertainty block", " ({} for the defaults)")


# --- loaded objects -------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    """A loaded, validated case: the model objects plus the requirement blocks."""

    name: str
    path: Path
    aircraft: Aircraft
    propulsion: Propulsion
    atmosphere: AtmosphereSchema
    requirements: Requirements
    aircraft_path: Path
    propulsion_path: Path
    battery_path: Path | None
    uncertainty: UncertaintySchema | None = None
    # the validated file behind ``propulsion`` (fit statistics, provenance) for the exports
    propulsion_schema: PropulsionSchema | None = None
    # keys changed for this run by ``--set`` (dotted key, value): the files say otherwise
    overrides: tuple[tuple[str, float], ...] = ()
    # the files a flag replaced for this run (--aircraft, --propulsion, --battery): their keys
    replaced: tuple[str, ...] = ()
    # flight summaries under validation.flights (absolute paths; io.flight_summary)
    validation_flights: tuple[Path, ...] = ()

    @property
    def density_kg_m3(self) -> float:
        """ISA density at the case's altitude and temperature offset."""
        return float(
            isa_density_kg_m3(self.atmosphere.altitude_m, self.atmosphere.temperature_offset_k)
        )


def aircraft_from_schema(schema: AircraftSchema) -> Aircraft:
    """The model's aircraft of a validated file (its keys are the dataclasses' fields)."""
    return Aircraft(**{**dict(schema), "takeoff": TakeoffConfig(**dict(schema.takeoff))})


def propulsion_from_schema(schema: PropulsionSchema) -> Propulsion:
    scale = 100.0 if schema.throttle_unit == "percent" else 1.0
    engines = tuple(
        Engine(
            name=e.name,
            coefficients=e.coefficients.model_dump(),
            throttle_scale=scale,
            covariance=(None if e.covariance is None
                        else tuple(tuple(float(c) for c in row) for row in e.covariance)),
            residual_sd_n=e.residual_sd_n,
            extrapolation_sd_n=e.extrapolation_sd_n,
            extrapolation_distance_m_s=e.extrapolation_distance_m_s,
            extrapolation_worst_n=e.extrapolation_worst_n,
            extrapolation_bias_n_per_m_s=e.extrapolation_bias_n_per_m_s,
            extrapolation_bias_se_n_per_m_s=e.extrapolation_bias_se_n_per_m_s,
            model_form_shares=None if e.lack_of_fit is None or e.lack_of_fit.model_form_shares
            is None else tuple(float(c) for c in e.lack_of_fit.model_form_shares),
            model_form_sd_n=None if e.lack_of_fit is None else e.lack_of_fit.model_form_rms_n,
            model_form_residuals=None if e.lack_of_fit is None or e.lack_of_fit.residuals
            is None else tuple((float(x), float(v), float(r), int(n))
                               for x, v, r, n in e.lack_of_fit.residuals),
            model_form_noise_n=None if e.lack_of_fit is None
            else e.lack_of_fit.pure_error_rms_n,
            windmilling_drag_coefficient=e.windmilling_drag_coefficient,
            power_coefficients=None if e.power is None else e.power.coefficients.model_dump(),
        )
        for e in schema.engines
    )
    low, high = schema.tested_airspeed_m_s
    return Propulsion(
        name=schema.name,
        engines=engines,
        tested_airspeed_m_s=(low, high),
        delay_s=schema.delay_s,
        lag_s=schema.lag_s,
        reference_density_kg_m3=schema.reference_density_kg_m3,
        metadata={"source": schema.source} if schema.source else {},
        fan_area_m2=schema.fan_area_m2,
        jet_area_m2=schema.jet_area_m2,
        reference_voltage_v=schema.reference_voltage_v,
        voltage_exponent=schema.voltage_exponent,
        rig_uncertainty=(None if schema.rig_uncertainty is None
                         else schema.rig_uncertainty.model_dump()),
    )


# Static thrust beyond this many times the aircraft's weight per engine is no fan for this
# aircraft: most likely coefficients read in the wrong throttle unit (fraction vs percent).
ABSURD_THRUST_TO_WEIGHT = 10.0


def refuse_absurd_propulsion(case: Case) -> None:
    """Bad input: a model whose full-throttle static thrust, at the case's air density (as
    every analysis scales it), is not positive or absurd."""
    from tuflexperf.models.thrust import density_ratio, engine_thrust_n

    weight = case.aircraft.weight_n
    scale = density_ratio(case.propulsion, case.density_kg_m3)
    low, high = case.propulsion.tested_airspeed_m_s
    throttle, airspeed = np.meshgrid(np.linspace(0.0, 1.0, 11), np.linspace(low, high, 13))
    for index, engine in enumerate(case.propulsion.engines):
        static = float(engine_thrust_n(engine, 1.0, 0.0, scale))
        where = f"{case.propulsion_path}: engines[{index}] ({engine.name})"
        if not static > 0:
            raise InputError(f"{where}: full-throttle static thrust {static:.3g} N is not "
                             "positive; check the coefficients and throttle_unit")
        if static > ABSURD_THRUST_TO_WEIGHT * weight:
            raise InputError(
                f"{where}: full-throttle static thrust {static:.4g} N is {static / weight:.3g} "
                f"x the aircraft's weight ({weight:.3g} N): physically absurd; is throttle_unit "
                "right (fraction vs percent)?"
            )
        # inside the tested range the model is the measurement (a p02 of 1e300 is none)
        with np.errstate(over="ignore", invalid="ignore"):
            thrust = np.asarray(engine_thrust_n(engine, throttle, airspeed, scale), dtype=float)
        worst = np.unravel_index(np.argmax(np.abs(np.nan_to_num(thrust, nan=np.inf))),
                                 thrust.shape)
        if not abs(thrust[worst]) <= ABSURD_THRUST_TO_WEIGHT * weight:
            raise InputError(
                f"{where}: thrust {thrust[worst]:.4g} N at throttle {throttle[worst]:.1f}, "
                f"{airspeed[worst]:.3g} m/s (inside the tested range) is beyond "
                f"{ABSURD_THRUST_TO_WEIGHT:g} x the aircraft's weight: check the coefficients")
