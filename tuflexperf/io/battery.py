"""Battery file (SPEC 4, "Battery file"): the pack, its discharge runs and the mission budget.

Its keys (this project's design; the SPEC leaves them open) and an example: docs/formats.md,
"Battery file". The run files use the SPEC's run format; they are only checked to exist here,
and are read when the discharge model is fitted (:mod:`tuflexperf.reduction.battery`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field, model_validator

from tuflexperf.errors import InputError
from tuflexperf.io.files import listed_file
from tuflexperf.io.yamlio import FileName, Name, StrictModel, load_model

Positive = Annotated[float, Field(gt=0)]


class RunSchema(StrictModel):
    file: FileName
    engine: str | None = None


class FanPowerSchema(StrictModel):
    published_power_range_w: Annotated[list[Positive], Field(min_length=2, max_length=2)]
    published_static_thrust_range_n: Annotated[list[Positive], Field(min_length=2, max_length=2)]
    jet_velocity_m_s: Positive

    @model_validator(mode="after")
    def _check(self) -> FanPowerSchema:
        for key in ("published_power_range_w", "published_static_thrust_range_n"):
            low, high = getattr(self, key)
            if not low < high:
                raise ValueError(f"{key}: low {low} must be below high {high}")
        return self


class MissionSchema(StrictModel):
    pattern_altitude_m: Annotated[float, Field(ge=0, le=5000)] = 100.0
    landing_reserve_fraction: Annotated[float, Field(ge=0, lt=1)] = 0.2


class PackParametersSchema(StrictModel):
    """The fitted equivalent circuit of one pack (models.battery.DischargeParameters)."""

    # the circuit's signs, as the fit bounds them: a voltage that rises as charge is drawn
    # (exp_rate -50: e^{50 q}) "reached cut-off after 2.4e117 min" and blamed the capacity
    e0_v: Positive
    slope_v_per_ah: Annotated[float, Field(ge=0)]
    exp_amplitude_v: Annotated[float, Field(ge=0)]
    exp_rate_per_ah: Annotated[float, Field(ge=0)]
    knee_v: Annotated[float, Field(ge=0)]
    max_capacity_ah: Positive
    resistance_ohm: Annotated[float, Field(ge=0)]


class FittedRunSchema(StrictModel):
    file: FileName
    sha256: Annotated[str, Field(min_length=64, max_length=64)]
    throttle: Annotated[float, Field(gt=0, le=1)]
    airspeed_m_s: Annotated[float, Field(ge=0)]
    mean_power_w: Positive
    mean_force_n: float
    start_charge_ah: Annotated[float, Field(ge=0)]
    time_to_cutoff_s: Positive
    charge_drawn_ah: Annotated[float, Field(ge=0)]


class CrossValidationSchema(StrictModel):
    fitted_on: str
    predicted_run: str
    observed_min: float
    predicted_min: float


class CorrectionRunSchema(StrictModel):
    file: FileName
    model_power_w: Positive
    ratio: Positive


Span = Annotated[list[Annotated[float, Field(ge=0)]], Field(min_length=2, max_length=2)]


class PowerCorrectionSchema(StrictModel):
    """Measured over modelled power of the discharge runs (models.power_correction)."""

    form: Literal["constant", "linear in throttle", "linear in airspeed",
                  "linear in throttle and airspeed"]
    constant: float
    per_throttle: float = 0.0
    per_airspeed_s_m: float = 0.0
    throttle_span: Span
    airspeed_span_m_s: Span
    model: str
    propulsion: FileName
    runs: Annotated[list[CorrectionRunSchema], Field(min_length=1)]

    @model_validator(mode="after")
    def _check(self) -> PowerCorrectionSchema:
        for key in ("throttle_span", "airspeed_span_m_s"):
            low, high = getattr(self, key)
            if not low <= high:
                raise ValueError(f"{key}: low {low} must not be above high {high}")
        return self


class BatteryFitSchema(StrictModel):
    """Written by ``tuflexperf fit``: the pack model fitted to the runs (check never fits)."""

    # the file's capacity_ah the model was fitted with: a label edited after the fit is
    # refused, since a relabelled file would count its reserve on charge the pack does not
    # give, while --set flies it scaled (absent in files written before it)
    capacity_ah: Positive | None = None
    # likewise the pack's cells: the circuit is the fitted pack's, and a file relabelled 10S
    # would fly a 34 V cut-off on the 12S circuit, voltages no run measured, where fit
    # refuses it; and the cut-off its runs end at: a lower one flies the pack model
    # below what they measured, which is said (absent in files written before them)
    cells_in_series: Annotated[int, Field(ge=1)] | None = None
    cutoff_voltage_per_cell_v: Positive | None = None
    parameters: PackParametersSchema
    rms_v: Annotated[float, Field(ge=0)]
    max_abs_v: Annotated[float, Field(ge=0)]
    n_points: Annotated[int, Field(ge=1)]
    runs: Annotated[list[FittedRunSchema], Field(min_length=1)]
    cross_validation: list[CrossValidationSchema] = []
    # written by fit against the propulsion beside the battery file (issue 43 item 2)
    power_correction: PowerCorrectionSchema | None = None


MAX_CAPACITY_AH = 1000.0
"""The largest pack capacity [Ah] a battery file or a what-if may name."""


class BatterySchema(StrictModel):
    file_kind: ClassVar[str] = "battery"  # named when another kind of file is given
    name: Name
    cells_in_series: Annotated[int, Field(ge=1, le=100)]
    # no aircraft pack holds more
    capacity_ah: Annotated[float, Field(gt=0, le=MAX_CAPACITY_AH)]
    nominal_voltage_v: Positive | None = None
    max_discharge_c: Positive | None = None
    packs_in_parallel_per_engine: Annotated[int, Field(ge=1, le=20)] = 1
    cutoff_voltage_per_cell_v: Annotated[float, Field(ge=2.5, le=4.2)]
    runs: Annotated[list[RunSchema], Field(min_length=1)]
    fan_power: FanPowerSchema
    mission: MissionSchema = MissionSchema()
    fit: BatteryFitSchema | None = None

    @model_validator(mode="after")
    def _check(self) -> BatterySchema:
        if self.nominal_voltage_v is not None:
            per_cell = self.nominal_voltage_v / self.cells_in_series
            # LiPo/Li-ion nominal is 3.6-3.85 V per cell; anything else is a typo in one key.
            if not 3.0 <= per_cell <= 4.2:
                raise ValueError(
                    f"nominal_voltage_v: {self.nominal_voltage_v:.4g} V is {per_cell:.3g} V per "
                    f"cell for {self.cells_in_series} cells (expected 3.0-4.2)"
                )
        return self


@dataclass(frozen=True)
class DischargeRunRef:
    """One discharge run named by the battery file (absolute path)."""

    path: Path
    engine: str | None


@dataclass(frozen=True)
class Battery:
    """A loaded, validated battery file (SI units; charge in Ah as on the pack label)."""

    name: str
    path: Path
    cells_in_series: int
    capacity_ah: float
    packs_in_parallel_per_engine: int
    cutoff_voltage_per_cell_v: float
    runs: tuple[DischargeRunRef, ...]
    published_power_range_w: tuple[float, float]
    published_static_thrust_range_n: tuple[float, float]
    jet_velocity_m_s: float
    pattern_altitude_m: float
    landing_reserve_fraction: float
    nominal_voltage_v: float | None = None
    max_discharge_c: float | None = None
    fitted: BatteryFitSchema | None = None
    measured: Battery | None = None  # the file as read, when --set changed some keys

    @property
    def cutoff_voltage_v(self) -> float:
        """Pack cut-off voltage under load in V (cells x per-cell cut-off)."""
        return self.cells_in_series * self.cutoff_voltage_per_cell_v

    @property
    def as_read(self) -> Battery:
        """The battery file as read: its runs and pack model are checked against this one."""
        return self.measured if self.measured is not None else self

    @property
    def circuit_packs(self) -> float:
        """Measured packs in parallel per engine that fly as this battery's packs [-]
        (:func:`tuflexperf.models.battery.equivalent_packs`; the file's own count unless
        the capacity was changed)."""
        from tuflexperf.models.battery import equivalent_packs

        return float(equivalent_packs(self.packs_in_parallel_per_engine, self.capacity_ah,
                                      self.as_read.capacity_ah))

    @property
    def measured_cutoff_v(self) -> float:
        """The pack voltage [V] the discharge runs end at: the cut-off they were fitted with
        (the file's, in a fit block from before it was recorded). Below it the pack model is
        extrapolated."""
        read = self.as_read
        fitted = read.fitted.cutoff_voltage_per_cell_v if read.fitted is not None else None
        return self.cells_in_series * (fitted if fitted is not None
                                       else read.cutoff_voltage_per_cell_v)

    @property
    def title(self) -> str:
        """The pack's name, with its capacity where that is not the file's (a what-if)."""
        measured = self.as_read.capacity_ah
        if self.capacity_ah == measured:
            return self.name
        return f"{self.name}, scaled to {self.capacity_ah:g} Ah (measured {measured:g} Ah)"

    @property
    def scaled_notes(self) -> tuple[str, ...]:
        """What a results' reader must know of a capacity other than the file's (or nothing)."""
        notes: tuple[str, ...] = ()
        measured = self.as_read.capacity_ah
        if self.capacity_ah != measured:
            notes += (f"capacity_ah {self.capacity_ah:g} Ah: the measured {measured:g} Ah pack "
                      f"scaled (it flies as {self.circuit_packs:.3g} measured packs per fan: "
                      "charge x the ratio, resistance / the ratio); no run measured a pack of "
                      "this size, and the aircraft's mass is as given",)
        runs_cutoff = self.measured_cutoff_v
        if self.cutoff_voltage_v < runs_cutoff * (1.0 - 1e-9):
            notes += (f"cutoff_voltage_per_cell_v {self.cutoff_voltage_per_cell_v:g} V: the "
                      f"discharge runs were measured down to their cut-off {runs_cutoff:.2f} "
                      "V; below it the pack model is extrapolated",)
        return notes


# The battery keys that change without refitting the pack model (--set, samples, sweeps,
# margins) and the Battery fields they set; a capacity other than the file's flies the
# measured pack scaled (models.battery.equivalent_packs)
BATTERY_FIELDS = {
    "battery.capacity_ah": "capacity_ah",
    "battery.cutoff_voltage_per_cell_v": "cutoff_voltage_per_cell_v",
    "battery.mission.pattern_altitude_m": "pattern_altitude_m",
    "battery.mission.landing_reserve_fraction": "landing_reserve_fraction",
}


def with_battery_values(battery: Battery, values: Mapping[str, float]) -> Battery:
    """``battery`` with the keys of :data:`BATTERY_FIELDS` in ``values`` set (others ignored).

    The result remembers the file as read (:attr:`Battery.as_read`): its runs contradict
    neither a lower cut-off nor a larger pack that was asked for, only a misprinted file.
    """
    changed = {field: float(values[key]) for key, field in BATTERY_FIELDS.items()
               if key in values}
    if not changed:
        return battery
    return dataclasses.replace(battery, **changed, measured=battery.as_read)


def load_battery(path: Path | str, refitting: bool = False) -> Battery:
    """Load and validate a battery file; every run file it names must exist.

    ``refitting`` (``tuflexperf fit`` on the file): a ``fit:`` block whose runs are no
    longer the file's is about to be replaced, so it is not an error (it is anywhere else:
    the pack model would not be the one its runs give).

    Raises :class:`InputError` naming the file and key on any problem.
    """
    path = Path(path)
    schema = load_model(path, BatterySchema)
    runs = []
    for index, run in enumerate(schema.runs):
        target = listed_file(path, f"runs[{index}].file", run.file, [r.path for r in runs])
        if not target.name.lower().endswith((".csv", ".csv.gz", ".mat")):
            raise InputError(f"{path}: runs[{index}].file: expected a .csv, .csv.gz or .mat "
                             f"run file, got {run.file}")
        runs.append(DischargeRunRef(path=target, engine=run.engine))
    if schema.fit is not None and not refitting:
        again = f"fit it again (tuflexperf fit {path.name} --out ...)"
        fitted_with = schema.fit.capacity_ah
        if fitted_with is not None and not math.isclose(fitted_with, schema.capacity_ah,
                                                        rel_tol=1e-9):
            raise InputError(
                f"{path}: capacity_ah: {schema.capacity_ah:g} Ah, but the pack model in `fit:` "
                f"was fitted with capacity_ah {fitted_with:g} Ah; {again}, or keep "
                f"{fitted_with:g} Ah in the file and fly another size with --set "
                f"battery.capacity_ah={schema.capacity_ah:g}"
            )
        fitted_cells = schema.fit.cells_in_series
        if fitted_cells is not None and fitted_cells != schema.cells_in_series:
            raise InputError(
                f"{path}: cells_in_series: {schema.cells_in_series}, but the pack model in "
                f"`fit:` was fitted with cells_in_series {fitted_cells}; {again}")
        fitted = schema.fit.parameters.max_capacity_ah
        if not 0.5 <= fitted / schema.capacity_ah <= 2.0:  # edited after the fit
            raise InputError(
                f"{path}: capacity_ah: {schema.capacity_ah:g} Ah, but the pack model in `fit:` "
                f"holds {fitted:.3g} Ah; {again}")
        refuse_label_beyond_fitted(path, schema.capacity_ah, fitted)
        # matched by position and name (a copied file may point at its runs another way);
        # the content is then checked by sha256 where the fit is used
        stored = [Path(r.file).name for r in schema.fit.runs]
        if stored != [r.path.name for r in runs]:
            raise InputError(f"{path}: fit.runs: the fitted runs are not the file's runs; {again}")
    fan = schema.fan_power
    same = ("name", "cells_in_series", "capacity_ah", "packs_in_parallel_per_engine",
            "cutoff_voltage_per_cell_v", "nominal_voltage_v", "max_discharge_c")
    return Battery(
        **{key: getattr(schema, key) for key in same}, path=path.resolve(), runs=tuple(runs),
        published_power_range_w=tuple(fan.published_power_range_w),
        published_static_thrust_range_n=tuple(fan.published_static_thrust_range_n),
        jet_velocity_m_s=fan.jet_velocity_m_s, **schema.mission.model_dump(), fitted=schema.fit,
    )


def case_battery(case: Any, load: Callable[[Path], Battery] | None = None) -> Battery:
    """The battery a case flies: its battery file with the case's ``--set battery.*`` values.

    ``load`` reads the file (default :func:`load_battery`; e.g. a cached reader). Raises
    :class:`InputError` when the case names no battery file.
    """
    if case.battery_path is None:
        raise InputError(f"{case.path}: battery: the case names no battery file")
    read = (load or load_battery)(case.battery_path)
    return with_battery_values(read, dict(case.overrides))


CAPACITY_TOLERANCE = 1.05
"""A run may draw up to 5 % more than the rated capacity (a fresh pack's spread) per pack."""
LABEL_OVER_DRAWN = 1.5
"""Largest ``capacity_ah`` over the most charge a discharge run drew to its cut-off (the
shipped pack: 5.0 Ah against 4.77 Ah; a conservative cut-off draws ~25 % less, not half)."""


def refuse_label_beyond_fitted(path: Path, capacity_ah: float, max_capacity_ah: float) -> None:
    """Bad input when ``capacity_ah`` [Ah] exceeds the fitted circuit's full charge
    ``max_capacity_ah`` [Ah], where its voltage collapses: no discharge of that pack gives
    the label, and the landing reserve, a fraction of it, would be counted on charge the
    pack does not hold (a 5 Ah pack relabelled 6 Ah would "land with 20 %" 0.6 min before
    its cut-off)."""
    if capacity_ah > max_capacity_ah * (1.0 + 1e-9):
        raise InputError(
            f"{path}: capacity_ah: {capacity_ah:g} Ah is more than the fitted pack holds "
            f"({max_capacity_ah:.3g} Ah, where the circuit fitted to its discharge runs "
            "collapses); give what the pack holds, or fly a larger pack with --set "
            "battery.capacity_ah (the measured pack scaled)")


def refuse_contradicted_capacity(battery: Battery, drawn: Sequence[tuple[str, float]]) -> None:
    """Bad input when a discharge run drew more from one pack than the file says it holds,
    or the file says it holds more than 1.5 x what any run drew to its cut-off.

    Parameters
    ----------
    battery : Battery
        The loaded battery file (``capacity_ah`` [Ah] per pack).
    drawn : sequence of (str, float)
        Each run's file name and the charge it drew from one pack [Ah].

    Raises
    ------
    InputError
        Naming the file, the key and the run (issue 10: never an endless endurance from a
        capacity the data contradict).
    """
    for name, charge_ah in drawn:
        if charge_ah > CAPACITY_TOLERANCE * battery.capacity_ah:
            raise InputError(
                f"{battery.path}: capacity_ah: {battery.capacity_ah:g} Ah, but the discharge "
                f"run {name} drew {charge_ah:.2f} Ah from one pack; the runs contradict it"
            )
    most = max((charge_ah for _, charge_ah in drawn), default=None)
    if most is not None and battery.capacity_ah > LABEL_OVER_DRAWN * most:
        # the landing reserve and the charge left are fractions of capacity_ah: a label twice
        # what the runs drew to their cut-off let a cruise to the cut-off 'land with half the
        # charge' and pass
        raise InputError(
            f"{battery.path}: capacity_ah: {battery.capacity_ah:g} Ah is more than "
            f"{LABEL_OVER_DRAWN:g} x the most any discharge run drew to its cut-off "
            f"({most:.2f} Ah); the landing reserve would be counted on charge the pack "
            "does not give: give what the pack holds"
        )

