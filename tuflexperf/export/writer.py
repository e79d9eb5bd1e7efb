"""``tuflexperf export``: write the model as CasADi functions, C99 source and JSON, atomically.

Everything is built in a temporary directory beside ``--out`` and moved into place only when
all requested files exist, so a failure never leaves partial output (SPEC 5).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tuflexperf.errors import InputError
from tuflexperf.export.model import (
    STEP_SAMPLE_TIME_S,
    ExportModel,
    inverse_function,
    load_export_model,
    model_description,
    model_notes,
    thrust_function,
    thrust_step_function,
)
from tuflexperf.io.files import check_output_dir, staged_directory

if TYPE_CHECKING:
    from tuflexperf.io.case import Case

FORMATS: tuple[str, ...] = ("c", "casadi", "json", "jsbsim", "fmu")

#: The files each format writes (fixed names, so flight-software builds can rely on them).
FILES: dict[str, tuple[str, ...]] = {
    "c": ("tfp_thrust.c", "tfp_thrust.h"),
    "casadi": ("tfp_thrust.casadi", "tfp_throttle_for_thrust.casadi", "tfp_thrust_step.casadi"),
    "json": ("tfp_thrust.json",),
    "jsbsim": ("tfp_thrust_system.xml", "tfp_thrust_reactions.xml"),
    "fmu": ("tfp_thrust.fmu",),
}


@dataclass(frozen=True)
class ExportResult:
    """What ``export`` wrote."""

    out_dir: Path
    formats: tuple[str, ...]
    files: tuple[Path, ...]
    model: ExportModel

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary for ``--json``."""
        prop = self.model.propulsion
        return {
            "out": str(self.out_dir),
            "formats": list(self.formats),
            "files": [str(f) for f in self.files],
            "model": prop.name,
            "n_engines": self.model.n_engines,
            "delay_s": prop.delay_s,
            "reference_density_kg_m3": prop.reference_density_kg_m3,
            "tested_airspeed_m_s": list(prop.tested_airspeed_m_s),
            "propulsion_sha256": self.model.propulsion_sha256,
            "lag_s": prop.lag_s,
            "notes": model_notes(prop),
        }


def parse_formats(text: str) -> tuple[str, ...]:
    """``"c,json"`` -> ``("c", "json")`` in canonical order; unknown or empty -> InputError."""
    requested = [part.strip().lower() for part in str(text).split(",") if part.strip()]
    if not requested:
        raise InputError(f"--format: no format given (choose from {', '.join(FORMATS)})")
    unknown = [part for part in requested if part not in FORMATS]
    if unknown:
        raise InputError(
            f"--format: unknown format {unknown[0]!r} (choose from {', '.join(FORMATS)})"
        )
    return tuple(f for f in FORMATS if f in requested)


def _save_function(function: Any, path: Path) -> None:
    """``function.save`` to ``path``, by way of a plain temporary name: CasADi opens the file
    itself, and a path of bytes that are no UTF-8 reaches it as ''."""
    from tuflexperf.io import swap

    with swap.scratch("export") as scratch:
        plain = Path(scratch) / "function.casadi"
        function.save(str(plain))
        path.write_bytes(plain.read_bytes())


def _write_format(model: ExportModel, fmt: str, directory: Path) -> None:
    """Write one format's files into ``directory``."""
    if fmt == "c":
        from tuflexperf.export.c_code import header_text, source_text

        source, header = FILES["c"]
        (directory / header).write_text(header_text(model), encoding="ascii")
        (directory / source).write_text(source_text(model), encoding="ascii")
    elif fmt == "casadi":
        thrust_file, inverse_file, step_file = FILES["casadi"]
        step = thrust_step_function(model.propulsion, STEP_SAMPLE_TIME_S)
        for function, name in ((thrust_function(model.propulsion), thrust_file),
                               (inverse_function(model.propulsion), inverse_file),
                               (step, step_file)):
            _save_function(function, directory / name)
    elif fmt == "json":
        text = json.dumps(model_description(model), indent=2, allow_nan=False) + "\n"
        (directory / FILES["json"][0]).write_text(text, encoding="utf-8")
    elif fmt == "jsbsim":
        from tuflexperf.export.jsbsim import reactions_text, system_text

        system_file, reactions_file = FILES["jsbsim"]
        (directory / system_file).write_text(system_text(model), encoding="ascii")
        (directory / reactions_file).write_text(reactions_text(model), encoding="ascii")
    elif fmt == "fmu":
        from tuflexperf.export.fmu import build_fmu

        build_fmu(model, directory / FILES["fmu"][0])
    else:  # parse_formats guards this
        raise InputError(f"--format: unknown format {fmt!r}")


def export_model(
    case_path: Case | Path | str | None, formats: tuple[str, ...], out_dir: Path | str
) -> ExportResult:
    """Export the case's propulsion model in ``formats`` into ``out_dir``.

    Validates every input first (case, formats, ``--out``), builds all files in a temporary
    sibling directory, then moves it into place whole (SPEC 5, "Nothing is lost": an existing
    ``out_dir`` is replaced only if an earlier ``export`` wrote it). Raises
    :class:`InputError` on bad input, leaving nothing behind.
    """
    out_dir = Path(out_dir)
    unknown = [f for f in formats if f not in FORMATS]
    if unknown or not formats:
        raise InputError(f"--format: unknown format {(unknown or [''])[0]!r}")
    check_output_dir(out_dir, "export")
    names = [name for fmt in formats for name in FILES[fmt]]
    model = load_export_model(case_path)
    # the staging checks the folder again, against the model's files
    with staged_directory(out_dir, "export", [f.path for f in model.files]) as staging:
        for fmt in formats:
            _write_format(model, fmt, staging)
    return ExportResult(
        out_dir=out_dir,
        formats=formats,
        files=tuple(out_dir / name for name in names),
        model=model,
    )
