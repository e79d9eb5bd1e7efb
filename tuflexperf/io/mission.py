"""Mission file (SPEC 4, "Mission file"): segments flown in order from a full battery.

Every airspeed in a mission file is an equivalent airspeed (EAS, SPEC 3); altitudes are
heights above the airfield of the case's atmosphere block. A cruise or loiter may give a
``throttle`` instead of an airspeed (with ``time_min``): it is then flown level at that
throttle and its airspeed follows (the fast root of ``T = D``, falling as the packs sag).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field, model_validator

from tuflexperf.io.yamlio import Name, StrictModel, load_model
from tuflexperf.models.aircraft import MAX_AIRSPEED_M_S

# upper bounds keep absurd numbers (1e300) out of the integrator as bad input (a cut-off inside
# a 1e300-min segment cannot be located: 60 bisections of a 1e298 s step), yet far beyond any
# flight of a battery aircraft, which the cut-off ends: below Mach 1 (as the envelope), about
# two years, 1e7 km, 100 m/s
Airspeed = Annotated[float, Field(gt=0, le=MAX_AIRSPEED_M_S)]
Minutes = Annotated[float, Field(gt=0, le=1e6)]
Kilometres = Annotated[float, Field(gt=0, le=1e7)]
Rate = Annotated[float, Field(gt=0, le=100)]
Height = Annotated[float, Field(ge=0, le=10000)]
Fraction = Annotated[float, Field(ge=0, le=1)]
SegmentType = Literal["takeoff", "climb", "cruise", "loiter", "descent", "engine_failure"]

# which optional keys each segment type takes; exactly-one-of groups are checked below
_ALLOWED: dict[str, frozenset[str]] = {
    "takeoff": frozenset(),
    "climb": frozenset({"to_altitude_m", "airspeed_m_s", "throttle", "climb_rate_m_s"}),
    "cruise": frozenset({"airspeed_m_s", "time_min", "distance_km", "throttle"}),
    "loiter": frozenset({"airspeed_m_s", "time_min", "throttle"}),
    "descent": frozenset({"to_altitude_m", "airspeed_m_s", "throttle", "descent_rate_m_s"}),
    "engine_failure": frozenset({"engine"}),
}
_KEYS = ("to_altitude_m", "airspeed_m_s", "throttle", "climb_rate_m_s", "descent_rate_m_s",
         "time_min", "distance_km", "engine")


class SegmentSchema(StrictModel):
    """One segment; which keys it takes depends on ``type`` (see :data:`_ALLOWED`)."""

    type: SegmentType
    to_altitude_m: Height | None = None
    airspeed_m_s: Airspeed | None = None
    throttle: Fraction | None = None
    climb_rate_m_s: Rate | None = None
    descent_rate_m_s: Rate | None = None
    time_min: Minutes | None = None
    distance_km: Kilometres | None = None
    engine: Annotated[str, Field(min_length=1)] | None = None

    @model_validator(mode="after")
    def _check(self) -> SegmentSchema:
        given = {key for key in _KEYS if getattr(self, key) is not None}
        extra = sorted(given - _ALLOWED[self.type])
        if extra:
            allowed = ", ".join(sorted(_ALLOWED[self.type])) or "no other key"
            raise ValueError(f"{self.type} takes {allowed}, not {', '.join(extra)}")

        def need(*keys: str) -> None:
            missing = [k for k in keys if getattr(self, k) is None]
            if missing:
                raise ValueError(f"{self.type} needs {', '.join(missing)}")

        def one_of(a: str, b: str) -> None:
            if (getattr(self, a) is None) == (getattr(self, b) is None):
                raise ValueError(f"{self.type} takes exactly one of {a} or {b}")

        if self.type == "climb":
            need("to_altitude_m", "airspeed_m_s")
            one_of("throttle", "climb_rate_m_s")
        elif self.type == "descent":
            need("to_altitude_m", "airspeed_m_s")
            one_of("throttle", "descent_rate_m_s")
        elif self.type == "cruise":
            one_of("airspeed_m_s", "throttle")
            if self.throttle is not None:
                need("time_min")  # at a throttle the airspeed is an outcome: time, not distance
            else:
                one_of("time_min", "distance_km")
        elif self.type == "loiter":
            need("time_min")
            if self.throttle is not None and self.airspeed_m_s is not None:
                raise ValueError("loiter takes at most one of airspeed_m_s or throttle")
        elif self.type == "engine_failure":
            need("engine")
        return self


class MissionFileSchema(StrictModel):
    """A mission: its name, the segments and optionally the segment to solve for."""

    file_kind: ClassVar[str] = "mission"

    name: Name
    segments: Annotated[list[SegmentSchema], Field(min_length=1, max_length=200)]
    solve_for: str | None = None


@dataclass(frozen=True)
class MissionFile:
    """A loaded, validated mission file; ``solve_for`` is the index of that segment."""

    name: str
    path: Path
    segments: tuple[SegmentSchema, ...]
    solve_for: int | None


def load_mission(path: Path | str) -> MissionFile:
    """Read and validate a mission file; errors name the file and key (exit 2).

    ``solve_for`` names a segment type that occurs exactly once among the time- or
    distance-based segments (``cruise`` or ``loiter``).

    References
    ----------
    SPEC 4 ("Mission file"), SPEC 5 (exit 2 naming the file and key).
    """
    from tuflexperf.errors import InputError

    path = Path(path)
    schema = load_model(path, MissionFileSchema)
    segments = tuple(schema.segments)
    solve_index = None
    if schema.solve_for is not None:
        matches = [i for i, s in enumerate(segments) if s.type == schema.solve_for]
        if schema.solve_for not in ("cruise", "loiter") or len(matches) != 1:
            raise InputError(
                f"{path}: solve_for: must name a cruise or loiter segment that occurs exactly "
                f"once, got {schema.solve_for!r}"
            )
        solve_index = matches[0]
    return MissionFile(schema.name, path, segments, solve_index)


def mission_path(case: Any) -> Path:
    """The case's mission file (a :class:`tuflexperf.io.case.Case`'s ``requirements.mission.file``),
    resolved relative to the case file (SPEC 4)."""
    from tuflexperf.io.files import listed_file

    return listed_file(case.path, "requirements.mission.file", case.requirements.mission.file)
