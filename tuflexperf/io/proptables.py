"""Published propeller tables as thrust tables: UIUC Propeller Data Site and APC PER3 files.

A propeller-table manifest (docs/formats.md, "Propeller tables") is an input of
``tuflexperf fit`` like a thrust table (SPEC 4): each file becomes ``engine, throttle,
airspeed_m_s, thrust_n`` points with ``throttle = rpm / max_rpm``, which a poly22 then fits
as it fits measured data. A propeller's thrust is not an EDF's: this is for models of
propeller-driven aircraft through the same poly22 (rpm fraction as "throttle").
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator

from tuflexperf.errors import InputError
from tuflexperf.io.inputs import (
    MAX_TABLE_BYTES,
    MAX_YAML_BYTES,
    check_input_file,
    path_text,
    why_not_a_file,
)
from tuflexperf.io.runs import ThrustTable
from tuflexperf.io.vendor import LBF_N
from tuflexperf.io.yamlio import EngineName, FileName, Name, StrictModel, load_model

MPH_M_S = 0.44704  # exact (1609.344 m / 3600 s)
ISA_SEA_LEVEL_DENSITY_KG_M3 = 1.225
# the largest propellers are ~6 m across
Diameter = Annotated[float, Field(gt=0, le=10.0)]
Rpm = Annotated[float, Field(gt=0, le=500_000.0)]
AirDensity = Annotated[float, Field(gt=0, le=2.0)]  # ISA sea level 1.225
_RPM = re.compile(r"PROP\s+RPM\s*=\s*(\S*)", re.IGNORECASE)


class TableEntry(StrictModel):
    file: FileName
    format: Literal["uiuc", "apc_per3"]
    engine: EngineName
    diameter_m: Diameter | None = None
    rpm: Rpm | None = None

    @model_validator(mode="after")
    def _uiuc_needs(self) -> TableEntry:
        if self.format == "uiuc" and (self.diameter_m is None or self.rpm is None):
            raise ValueError("a uiuc table needs diameter_m and rpm (the file gives neither)")
        return self


class PropellerTablesSchema(StrictModel):
    file_kind: ClassVar[str] = "propeller-table manifest"  # named when another kind is given
    name: Annotated[Name, Field(min_length=1)]
    air_density_kg_m3: AirDensity = ISA_SEA_LEVEL_DENSITY_KG_M3
    max_rpm: dict[str, Rpm] = {}
    tables: Annotated[list[TableEntry], Field(min_length=1)]


def is_propeller_manifest(path: Path) -> bool:
    """True for a YAML file whose top level has a ``tables:`` key (cheap check, no validation).

    References
    ----------
    SPEC 4 (inputs of ``fit``); this module's docstring (the manifest).
    """
    if path.suffix.lower() not in (".yaml", ".yml") or not path.is_file():
        return False
    try:
        with path.open(encoding="utf-8") as handle:  # no more than a YAML file may hold
            text = handle.read(MAX_YAML_BYTES + 1)
    except (OSError, UnicodeDecodeError):
        return False
    return re.search(r"^tables\s*:", text, re.MULTILINE) is not None


def _numbers(line: str) -> list[float] | None:
    try:
        return [float(token) for token in line.split()]
    except ValueError:
        return None


def read_uiuc(path: Path, diameter_m: float, rpm: float, density_kg_m3: float) -> np.ndarray:
    """UIUC ``J CT CP eta`` rows -> array of (airspeed [m/s], thrust [N]).

    References
    ----------
    Brandt, Deters, Ananda & Selig, *UIUC Propeller Data Site*, vol. 1-4 (data file layout);
    McCormick, *Aerodynamics, Aeronautics and Flight Mechanics*, 2nd ed., ch. 6 (J, CT).
    """
    lines = _lines(path)
    header = lines[0][1].split() if lines else []
    if [h.lower() for h in header[:2]] != ["j", "ct"]:
        raise InputError(f"{path_text(path)}: expected the UIUC header 'J CT CP eta', found "
                         f"{[text for _, text in lines[:1]]}")
    n = rpm / 60.0
    rows = []
    previous_j = None
    for number, line in lines[1:]:
        values = _numbers(line)
        if values is None or len(values) < 2:
            raise InputError(f"{path_text(path)}: line {number}: expected numbers J CT ..., got "
                             f"{line!r}")
        j, ct = values[0], values[1]
        _refuse_row(path, number, {"J": j, "CT": ct}, "J", j, previous_j)
        previous_j = j
        rows.append((j * n * diameter_m, ct * density_kg_m3 * n * n * diameter_m**4))
    if not rows:
        raise InputError(f"{path_text(path)}: no data rows")
    return np.array(rows)


def read_apc_per3(path: Path) -> list[tuple[float, np.ndarray]]:
    """APC PER3 blocks -> list of (rpm, array of (airspeed [m/s], thrust [N])).

    References
    ----------
    APC Propellers, *Performance data* (PER3_*.dat files, one block per ``PROP RPM``).
    """
    blocks: list[tuple[float, list[tuple[float, float]]]] = []
    previous_j: float | None = None
    for number, line in _lines(path):
        found = _RPM.search(line)
        if found:
            try:
                rpm = float(found.group(1))
            except ValueError:
                rpm = math.nan
            # 'PROP RPM = .' or '= 0' is no speed
            if not (math.isfinite(rpm) and rpm > 0):
                raise InputError(f"{path_text(path)}: line {number}: 'PROP RPM = "
                                 f"{found.group(1)}' is no speed (a positive number of rpm)")
            blocks.append((rpm, []))
            previous_j = None
            continue
        values = _numbers(line)
        if not blocks or values is None or len(values) < 8:
            continue  # titles, definitions, column headers and units
        wide = len(values) >= 15  # the newer files: thrust in N (column 11)
        thrust_name, thrust = (("Thrust (N)", values[10]) if wide
                               else ("Thrust (Lbf)", values[7] * LBF_N))
        _refuse_row(path, number, {"V (mph)": values[0], "J": values[1], thrust_name: thrust},
                    "J", values[1], previous_j, airspeed=("V (mph)", values[0]))
        previous_j = values[1]
        blocks[-1][1].append((values[0] * MPH_M_S, thrust))
    blocks = [(rpm, rows) for rpm, rows in blocks if rows]
    if not blocks:
        raise InputError(f"{path_text(path)}: no 'PROP RPM =' block with data rows (not an APC "
                         "PER3 file?)")
    return [(rpm, np.array(rows)) for rpm, rows in blocks]


def _refuse_row(path: Path, number: int, used: dict[str, float], j_name: str, j: float,
                previous_j: float | None, airspeed: tuple[str, float] | None = None) -> None:
    """Bad input naming the file, line and column: a NaN or infinity in a column used, a
    negative airspeed or advance ratio, or an advance ratio below the row before it in
    the same rpm block (a negative J flips the coefficients' signs)."""
    where = f"{path_text(path)}: line {number}"
    for name, value in used.items():
        if not math.isfinite(value):
            raise InputError(f"{where}: column {name}: {value} is no number")
    if airspeed is not None and airspeed[1] < 0:
        raise InputError(f"{where}: column {airspeed[0]}: negative airspeed {airspeed[1]:g}")
    if j < 0:
        raise InputError(f"{where}: column {j_name}: negative advance ratio {j:g}")
    if previous_j is not None and j < previous_j:
        raise InputError(f"{where}: column {j_name}: advance ratio {j:g} below the row "
                         f"before ({previous_j:g}); J must increase down one rpm block")


def _lines(path: Path) -> list[tuple[int, str]]:
    """The file's non-blank lines, stripped, with their line numbers (1-based)."""
    check_input_file(path, "propeller table", MAX_TABLE_BYTES)
    try:
        text = path.read_text(encoding="latin-1")
    except OSError as exc:
        raise InputError(f"{path_text(path)}: cannot read: {exc.strerror}") from None
    return [(number, line.strip()) for number, line in enumerate(text.splitlines(), start=1)
            if line.strip()]


def read_propeller_tables(path: Path | str) -> ThrustTable:
    """A propeller-table manifest -> one :class:`ThrustTable` (module docstring).

    Parameters
    ----------
    path : Path
        The manifest (YAML with ``tables:``); file paths in it are relative to it.

    Returns
    -------
    ThrustTable
        Points per engine: throttle = rpm / max rpm [-], airspeed [m/s], thrust [N].

    References
    ----------
    UIUC Propeller Data Site (Brandt, Deters, Ananda & Selig); APC Propellers performance data.
    """
    path = Path(path)
    schema = load_model(path, PropellerTablesSchema)
    points: list[tuple[str, float, float, float]] = []  # engine, rpm, airspeed, thrust
    for index, entry in enumerate(schema.tables):
        file = (path.parent / entry.file).resolve()
        if not file.is_file():
            raise InputError(f"{path}: tables[{index}].file: {why_not_a_file(file)}: "
                             f"{entry.file}")
        if entry.format == "uiuc":
            assert entry.diameter_m is not None and entry.rpm is not None  # validated
            rows = read_uiuc(file, entry.diameter_m, entry.rpm, schema.air_density_kg_m3)
            points += [(entry.engine, entry.rpm, v, t) for v, t in rows]
        else:
            for rpm, rows in read_apc_per3(file):
                points += [(entry.engine, rpm, v, t) for v, t in rows]
    engines = list(dict.fromkeys(p[0] for p in points))
    unknown = sorted(set(schema.max_rpm) - set(engines))
    if unknown:
        raise InputError(f"{path}: max_rpm: no table for engine {unknown[0]!r}")
    top = {e: schema.max_rpm.get(e, max(p[1] for p in points if p[0] == e)) for e in engines}
    for engine, rpm, _, _ in points:
        if rpm > top[engine] * (1 + 1e-9):
            raise InputError(
                f"{path}: max_rpm: {engine} is tabulated at {rpm:g} rpm, above max_rpm "
                f"{top[engine]:g}"
            )
    bad = [p for p in points if not all(math.isfinite(x) for x in p[1:])]
    if bad:
        raise InputError(f"{path}: non-finite value in the table of {bad[0][0]}")
    return ThrustTable(
        path=path,
        engine=tuple(p[0] for p in points),
        throttle=np.array([p[1] / top[p[0]] for p in points]),
        airspeed_m_s=np.array([p[2] for p in points]),
        thrust_n=np.array([p[3] for p in points]),
    )
