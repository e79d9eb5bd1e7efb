"""Flight summary (issue 45 item 3): a flight log reduced against a case, as a case lists it.

``tuflexperf flightlog LOG --case CASE --summary FILE`` writes it; a case names it under
``validation: {flights: [FILE]}``, and ``check`` reads it (parameters only: the log itself is
never opened again). Its keys: docs/formats.md, "Flight summary".
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from tuflexperf.io.yamlio import FileName, StrictModel, load_model

Positive = Annotated[float, Field(gt=0)]


class FlownBinSchema(StrictModel):
    airspeed_m_s: Annotated[float, Field(ge=0)]
    true_airspeed_m_s: Annotated[float, Field(ge=0)]
    time_s: Positive
    flown_power_w: Positive
    predicted_power_w: Positive
    predicted_throttle: Annotated[float, Field(ge=0, le=1)]
    # the log's own where it has them (no throttle stream, no current: absent)
    flown_throttle: Annotated[float, Field(ge=0, le=1)] | None = None
    flown_current_a: Annotated[float, Field(gt=0)] | None = None


class FlightSummarySchema(StrictModel):
    """Written by ``flightlog --summary``: the flown bins beside the case's model."""

    file_kind: ClassVar[str] = "flight summary"
    log: FileName
    log_sha256: Annotated[str, Field(min_length=64, max_length=64)]
    power_model: str
    density_kg_m3: Positive
    mass_kg: Positive
    airborne_s: Annotated[float, Field(ge=0)]
    energy_wh: Annotated[float, Field(ge=0)] | None = None
    bins_kind: Literal["level-flight", "all-flight"] | None = None
    bins: Annotated[list[FlownBinSchema], Field(min_length=1)]


@dataclass(frozen=True)
class FlightSummary:
    """A loaded flight summary (SI units)."""

    path: Path
    schema: FlightSummarySchema


# (resolved path, mtime [ns], size [B]) -> the summary parsed: ``check`` validates each at the
# case's load and reads it again for its readings and the endurance note; one parse serves all
_LOADED: dict[tuple[Path, int, int], FlightSummary] = {}
_MOST_KEPT = 64


def load_flight_summary(path: Path | str) -> FlightSummary:
    """Load and validate a flight summary; :class:`InputError` names the file and key.

    A file read before, unchanged since (its modification time and size), is not parsed
    again: its schema is frozen, so the one parse is shared. A bad file is never kept.
    """
    path = Path(path)
    resolved = path.resolve()
    try:
        stat = resolved.stat()
    except OSError:  # missing or unreadable: load_model says which, in its words
        key = None
    else:  # stat before the read: a file changed meanwhile is read again next time
        key = (resolved, stat.st_mtime_ns, stat.st_size)
        if key in _LOADED:
            return _LOADED[key]
    summary = FlightSummary(resolved, load_model(path, FlightSummarySchema))
    if key is not None:
        if len(_LOADED) >= _MOST_KEPT:
            _LOADED.pop(next(iter(_LOADED)))  # the oldest first
        _LOADED[key] = summary
    return summary


def log_digest(path: Path) -> str:
    """sha256 of a log file, or of a ulog2csv folder (its files' names and hashes, sorted)."""
    import hashlib

    from tuflexperf.io.files import sha256_of

    if not path.is_dir():
        return sha256_of(path)
    lines = "".join(f"{p.name}:{sha256_of(p)}\n" for p in sorted(path.iterdir()) if p.is_file())
    return hashlib.sha256(lines.encode("utf-8")).hexdigest()


def flight_summary_text(log_path: Path, log_sha256: str, comparison: Any,
                        airborne_s: float, energy_wh: float | None) -> str | None:
    """The summary's YAML text from a ``flightlog`` comparison; ``None`` where no bin has a
    predicted power (nothing to compare: the summary would hold no evidence)."""
    import math

    import yaml

    def logged(value: Any, low: float, high: float) -> float | None:
        # a stream the log lacks is NaN in the comparison: absent from the summary
        ok = value is not None and math.isfinite(float(value)) and low <= float(value) <= high
        return float(value) if ok else None

    bins = [{"airspeed_m_s": float(b["airspeed_m_s"]),
             "true_airspeed_m_s": float(b["true_airspeed_m_s"]),
             "time_s": float(b["time_s"]), "flown_power_w": float(b["flown_power_w"]),
             "predicted_power_w": float(b["predicted_power_w"]),
             "predicted_throttle": float(b["predicted_throttle"]),
             "flown_throttle": logged(b.get("flown_throttle"), 0.0, 1.0),
             "flown_current_a": logged(b.get("flown_current_a"), 1e-9, math.inf)}
            for b in comparison.bins
            if b.get("ratio") is not None and math.isfinite(float(b["predicted_power_w"]))
            and float(b["predicted_power_w"]) > 0 and float(b["flown_power_w"]) > 0]
    if not bins:
        return None
    bins = [{k: v for k, v in b.items() if v is not None} for b in bins]
    data = {"log": log_path.name, "log_sha256": log_sha256, "power_model": comparison.power_model,
            "density_kg_m3": float(comparison.density_kg_m3), "mass_kg": float(comparison.mass_kg),
            "airborne_s": float(airborne_s),
            "energy_wh": float(energy_wh) if energy_wh is not None else None,
            "bins_kind": comparison.bins[0]["bins"], "bins": bins}
    return ("# written by `tuflexperf flightlog --summary`: the flown power beside the case's "
            "model;\n# a case lists it under validation: {flights: [...]}\n"
            + yaml.safe_dump(data, sort_keys=False, width=100))
