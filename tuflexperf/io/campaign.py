"""The test-campaign manifest (``campaign.yaml``, SPEC 4), the input of ``tuflexperf fit``.

Its keys, the run kinds and a full example: docs/formats.md, "Campaign manifest". Paths are
relative to the manifest; unknown keys are errors.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, ClassVar, Literal

from pydantic import Field, model_validator

from tuflexperf.errors import InputError
from tuflexperf.io.files import listed_file
from tuflexperf.io.schemas import RigUncertaintySchema
from tuflexperf.io.vendor import VendorSettings
from tuflexperf.io.yamlio import EngineName, FileName, Name, StrictModel, load_model
from tuflexperf.models.thrust import MAX_FAN_AREA_M2, MIN_FAN_AREA_M2

Positive = Annotated[float, Field(gt=0)]
RunKind = Literal["throttle_steps", "sine_sweep", "drag_sweep", "endurance"]
#: ``run``: the project's own columns (SPEC 4); the others: :mod:`tuflexperf.io.vendor`.
RunFormat = Literal["run", "rcbenchmark"]
ISA_SEA_LEVEL_DENSITY_KG_M3 = 1.225


class ThrustStandKeys(StrictModel):
    """Keys of a thrust-stand export (``format:`` other than ``run``), per run or for all runs."""

    format: RunFormat | None = None
    esc_pulse_us: Annotated[list[Positive], Field(min_length=2, max_length=2)] | None = None
    thrust_sign: Literal[1, -1] | None = None
    airspeed_m_s: Annotated[float, Field(ge=0)] | None = None

    @model_validator(mode="after")
    def _pulses(self) -> ThrustStandKeys:
        if self.esc_pulse_us is not None and not self.esc_pulse_us[0] < self.esc_pulse_us[1]:
            raise ValueError(
                f"esc_pulse_us: idle {self.esc_pulse_us[0]:g} must be below full "
                f"{self.esc_pulse_us[1]:g}"
            )
        return self


class RunEntry(ThrustStandKeys):
    file: FileName
    kind: RunKind
    engine: EngineName | None = None

    @model_validator(mode="after")
    def _engine_needed(self) -> RunEntry:
        # the fit needs to know whose thrust or delay a run measures; drag sweeps
        # have no fan and endurance runs are not the fit's (it ignores them)
        if self.kind in ("throttle_steps", "sine_sweep") and self.engine is None:
            raise ValueError(f"engine: required for a {self.kind} run")
        return self


MAX_FILTER_WINDOW_S = 10.0
"""The longest filter window [s]: the paper's are 2 s and 0.1 s, its plateaus a few seconds."""


class FilterSettings(StrictModel):
    """Filter windows in seconds (never samples) and the outlier threshold (paper section 4)."""

    # a window as long as a throttle plateau (seconds) averages across the steps
    outlier_window_s: Annotated[float, Field(gt=0, le=MAX_FILTER_WINDOW_S)] = 2.0
    outlier_threshold: Annotated[float, Field(gt=0, le=100)] = 1.5
    median_window_s: Annotated[float, Field(gt=0, le=MAX_FILTER_WINDOW_S)] = 0.1


class CampaignSchema(ThrustStandKeys):
    file_kind: ClassVar[str] = "campaign"  # named when another kind of file is given
    name: Annotated[Name, Field(min_length=1)]
    # a fan of 3.6 mm to a tunnel of 100 m x 100 m
    fan_area_m2: Annotated[float, Field(ge=MIN_FAN_AREA_M2, le=MAX_FAN_AREA_M2)]
    # a static thrust stand has no tunnel: no blockage to correct, nothing to give
    tunnel_area_m2: Annotated[float, Field(ge=MIN_FAN_AREA_M2, le=1.0e4)] | None = None
    # a tunnel's air: from a hot day at altitude to a cold pressurised one (0.01 scaled
    # the fitted thrust x122 as the reference density and let everything pass)
    air_density_kg_m3: Annotated[float, Field(ge=0.3, le=2.0)] | None = None
    filters: FilterSettings = FilterSettings()
    # the rig's systematic errors (standard deviations); fit writes them into the propulsion
    # file, a key left out there with its stated default
    rig_uncertainty: RigUncertaintySchema | None = None
    runs: Annotated[list[RunEntry], Field(min_length=1)]

    @model_validator(mode="after")
    def _check(self) -> CampaignSchema:
        if self.tunnel_area_m2 is not None and not self.fan_area_m2 < self.tunnel_area_m2:
            raise ValueError(
                f"fan_area_m2 ({self.fan_area_m2}) must be smaller than "
                f"tunnel_area_m2 ({self.tunnel_area_m2})"
            )
        return self


@dataclass(frozen=True)
class CampaignRun:
    """One manifest entry with its file resolved against the manifest's folder."""

    index: int
    file: str
    path: Path
    kind: str
    engine: str | None
    vendor: VendorSettings | None = None  # a thrust-stand export: how to read it


def _vendor(schema: CampaignSchema, entry: RunEntry, index: int) -> VendorSettings | None:
    """The run's thrust-stand settings: its own keys, else the manifest's, else the defaults."""
    fmt = entry.format or schema.format or "run"
    if fmt == "run":
        for key in ("esc_pulse_us", "thrust_sign", "airspeed_m_s"):
            if getattr(entry, key) is not None:
                raise InputError(
                    f"runs[{index}].{key}: only for a thrust-stand format "
                    f"(format: rcbenchmark), this run is format: run"
                )
        return None
    pulses = entry.esc_pulse_us or schema.esc_pulse_us or [1000.0, 2000.0]
    sign = entry.thrust_sign or schema.thrust_sign or 1
    airspeed = entry.airspeed_m_s if entry.airspeed_m_s is not None else schema.airspeed_m_s
    return VendorSettings(
        format=fmt,
        esc_pulse_us=(float(pulses[0]), float(pulses[1])),
        thrust_sign=float(sign),
        airspeed_m_s=airspeed,
        where=f"manifest runs[{index}]",
    )


@dataclass(frozen=True)
class Campaign:
    """A validated manifest: settings plus the runs ``fit`` uses (endurance runs are kept
    in ``ignored`` so the caller can report them)."""

    path: Path
    name: str
    fan_area_m2: float
    tunnel_area_m2: float | None  # None: a static stand, no tunnel
    air_density_kg_m3: float
    density_given: bool
    filters: FilterSettings
    runs: tuple[CampaignRun, ...]
    ignored: tuple[CampaignRun, ...]
    rig_uncertainty: RigUncertaintySchema | None = None  # None: the rig declares none

    def of_kind(self, kind: str) -> list[CampaignRun]:
        return [run for run in self.runs if run.kind == kind]


def load_campaign(path: Path | str) -> Campaign:
    """Load and validate a campaign manifest; run files must exist (endurance runs excepted).

    Raises
    ------
    InputError
        Naming the manifest and the key (``runs[3].file``) for any problem.
    """
    path = Path(path)
    schema = load_model(path, CampaignSchema)
    used: list[CampaignRun] = []
    ignored: list[CampaignRun] = []
    for index, entry in enumerate(schema.runs):
        resolved = (path.parent / entry.file).resolve()
        try:
            vendor = _vendor(schema, entry, index)
        except InputError as exc:
            raise InputError(f"{path}: {exc}") from None
        run = CampaignRun(index, entry.file, resolved, entry.kind, entry.engine, vendor)
        if entry.kind == "endurance":
            ignored.append(run)  # battery runs belong to the endurance model, not the fit
            continue
        # a run listed twice would count its points twice (and shrink the covariance)
        listed_file(path, f"runs[{index}].file", entry.file,
                    [earlier.path for earlier in used if earlier.kind == run.kind],
                    f" as {entry.kind}")
        used.append(run)
    if not any(run.kind == "throttle_steps" for run in used):
        raise InputError(f"{path}: runs: no throttle_steps run, nothing to fit")
    if not any(run.vendor is not None for run in (*used, *ignored)):
        # a run's own such key is refused, and the manifest's is not ignored unsaid
        for key in ("esc_pulse_us", "thrust_sign", "airspeed_m_s"):
            if getattr(schema, key) is not None:
                raise InputError(f"{path}: {key}: only for a thrust-stand format (format: "
                                 "rcbenchmark), and no run of this manifest has one")
    return Campaign(
        path=path,
        name=schema.name,
        fan_area_m2=schema.fan_area_m2,
        tunnel_area_m2=schema.tunnel_area_m2,
        air_density_kg_m3=schema.air_density_kg_m3 or ISA_SEA_LEVEL_DENSITY_KG_M3,
        density_given=schema.air_density_kg_m3 is not None,
        filters=schema.filters,
        runs=tuple(used),
        ignored=tuple(ignored),
        rig_uncertainty=schema.rig_uncertainty,
    )
