"""docs/formats.md is the users' file-format guide: every schema key is in it, with the
schema's required/default, and its minimal examples load with the tool's own loaders.

The keys are walked from the pydantic schemas themselves (``model_fields``, recursively) and
from the column lists the readers use, so a key added to a schema without a line in the guide
fails here, naming the key and the guide's section.
"""

from __future__ import annotations

import re
import types
import typing
from pathlib import Path
from typing import Any, Literal

import pytest
import yaml
from pydantic import BaseModel
from pydantic_core import PydanticUndefined

from tuflexperf.io import runs as run_columns
from tuflexperf.io import vendor
from tuflexperf.io.battery import BatterySchema, load_battery
from tuflexperf.io.campaign import CampaignSchema, load_campaign
from tuflexperf.io.case import AircraftSchema, CaseSchema, PropulsionSchema, load_case
from tuflexperf.io.datasheet import DatasheetSchema
from tuflexperf.io.discharge import DISCHARGE_COLUMNS
from tuflexperf.io.flight_summary import FlightSummarySchema
from tuflexperf.io.mission import _ALLOWED, MissionFileSchema, load_mission
from tuflexperf.io.proptables import PropellerTablesSchema, read_propeller_tables
from tuflexperf.io.yamlio import load_model

GUIDE = Path(__file__).resolve().parent.parent / "docs" / "formats.md"


def _text() -> str:
    return GUIDE.read_text(encoding="utf-8")


def sections(text: str) -> dict[str, str]:
    """The guide cut at its ``<!-- schema: NAME -->`` markers: NAME -> its text."""
    parts = re.split(r"<!--\s*schema:\s*(\S+)\s*-->", text)
    return {parts[i]: parts[i + 1] for i in range(1, len(parts) - 1, 2)}


def _unwrap(annotation: Any) -> list[Any]:
    """The types inside Optional / Annotated / unions (not inside lists or dicts)."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _unwrap(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [t for arg in typing.get_args(annotation) for t in _unwrap(arg)]
    return [annotation]


def _models_in(annotation: Any) -> list[tuple[str, type[BaseModel]]]:
    """(path suffix, model) for each model a field holds: ``""`` itself, ``[]`` in a list,
    ``.<key>`` as the values of a mapping."""
    found: list[tuple[str, type[BaseModel]]] = []
    for kind in _unwrap(annotation):
        origin = typing.get_origin(kind)
        if isinstance(kind, type) and issubclass(kind, BaseModel):
            found.append(("", kind))
        elif origin is list:
            found += [("[]" + s, m) for s, m in _models_in(typing.get_args(kind)[0])]
        elif origin is dict:
            found += [(".<key>" + s, m) for s, m in _models_in(typing.get_args(kind)[1])]
    return found


def _literals(annotation: Any) -> list[Any]:
    return [value for kind in _unwrap(annotation) if typing.get_origin(kind) is Literal
            for value in typing.get_args(kind)]


def _field_model(model: type[BaseModel], name: str) -> type[BaseModel]:
    """The model a field holds (found from the schema, wherever the module defines it)."""
    return _models_in(model.model_fields[name].annotation)[0][1]


UncertaintySchema = _field_model(CaseSchema, "uncertainty")
Poly22Schema = _field_model(_field_model(PropulsionSchema, "engines"), "coefficients")

# each schema that has a section of its own; a field of one of these types is documented in
# its own section, the field itself in the section that holds it
SECTIONS: dict[type[BaseModel], str] = {
    CaseSchema: "case",
    UncertaintySchema: "uncertainty",
    AircraftSchema: "aircraft",
    PropulsionSchema: "propulsion",
    Poly22Schema: "poly22",
    BatterySchema: "battery",
    MissionFileSchema: "mission",
    CampaignSchema: "campaign",
    PropellerTablesSchema: "proptables",
    DatasheetSchema: "datasheet",
    FlightSummarySchema: "flight-summary",
}


class Key(typing.NamedTuple):
    section: str
    path: str
    required: bool
    default: Any
    literals: tuple[Any, ...]


def schema_keys() -> list[Key]:
    """Every key of every file schema, as (section, dotted path, required, default)."""
    keys: list[Key] = []

    def walk(model: type[BaseModel], section: str, prefix: str) -> None:
        for name, field in model.model_fields.items():
            path = prefix + name
            default = None if field.is_required() else field.default
            default = None if default is PydanticUndefined else default
            keys.append(Key(section, path, field.is_required(), default,
                            tuple(_literals(field.annotation))))
            for suffix, sub in _models_in(field.annotation):
                if sub in SECTIONS:
                    walk(sub, SECTIONS[sub], "")
                else:
                    walk(sub, section, f"{path}{suffix}.")

    for model in (CaseSchema, AircraftSchema, PropulsionSchema, BatterySchema,
                  MissionFileSchema, CampaignSchema, PropellerTablesSchema, DatasheetSchema,
                  FlightSummarySchema):
        walk(model, SECTIONS[model], "")
    unique: dict[tuple[str, str], Key] = {}
    for key in keys:
        unique.setdefault((key.section, key.path), key)
    return list(unique.values())


def _row(section_text: str, path: str) -> list[str] | None:
    """The cells of the table row whose first cell names ``path`` in backticks."""
    for line in section_text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.lstrip().startswith("|") and f"`{path}`" in cells[0]:
            return cells
    return None


def _header(section_text: str) -> list[str]:
    for line in section_text.splitlines():
        if line.lstrip().startswith("| key"):
            return [c.strip() for c in line.strip().strip("|").split("|")]
    return []


def _default_texts(value: Any) -> list[str]:
    if isinstance(value, bool):
        return [str(value).lower()]
    if isinstance(value, (int, float)):
        return [repr(value), f"{value:g}"]
    return [str(value)]


def test_the_walk_finds_the_keys_it_must() -> None:
    # the walk itself can fail: nested, listed, mapped and sectioned keys all come out
    paths = {(k.section, k.path) for k in schema_keys()}
    for expected in [("case", "requirements.takeoff.max_ground_roll_m"),
                     ("uncertainty", "parameters.<key>.truncated_normal"),
                     ("propulsion", "engines[].power.rmse_w"), ("poly22", "p11"),
                     ("battery", "fit.runs[].sha256"), ("mission", "segments[].engine"),
                     ("campaign", "runs[].esc_pulse_us"), ("proptables", "tables[].rpm")]:
        assert expected in paths
    assert ("case", "uncertainty.samples") not in paths  # documented in its own section


def test_every_schema_key_is_in_the_guide() -> None:
    parts = sections(_text())
    missing = [f"docs/formats.md section '{k.section}' lacks key `{k.path}`"
               for k in schema_keys()
               if k.section not in parts or _row(parts[k.section], k.path) is None]
    assert not missing, "\n".join(missing)


def test_required_and_default_agree_with_the_schema() -> None:
    parts = sections(_text())
    wrong = []
    for key in schema_keys():
        text = parts.get(key.section, "")
        row, header = _row(text, key.path), _header(text)
        if row is None or "required" not in header:
            continue  # the test above names it
        required = row[header.index("required")]
        if required.startswith("yes") != key.required:
            wrong.append(f"section '{key.section}', `{key.path}`: required is "
                         f"{key.required} in the schema, the guide says '{required}'")
        if key.default is not None and isinstance(key.default, (bool, int, float, str)):
            cell = row[header.index("default")]
            if not any(t in cell for t in _default_texts(key.default)):
                wrong.append(f"section '{key.section}', `{key.path}`: default is "
                             f"{key.default!r} in the schema, the guide says '{cell}'")
        for value in key.literals:
            if isinstance(value, str) and f"`{value}`" not in text:
                wrong.append(f"section '{key.section}', `{key.path}`: value `{value}` "
                             "is not described")
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize(("section", "names"), [
    ("runs", (*run_columns.RUN_COLUMNS, *run_columns.KNOWN_OPTIONAL, *DISCHARGE_COLUMNS)),
    ("table", (*run_columns.TABLE_COLUMNS, *run_columns.TABLE_EXTRA_COLUMNS,
               *run_columns.REFIT_TABLE_EXTRA_COLUMNS)),
    ("vendor", (*vendor.THRUST_UNITS_N, *vendor.SPEED_UNITS_M_S, *vendor.TIME_UNITS_S)),
    ("mission", (*_ALLOWED, *(k for keys in _ALLOWED.values() for k in keys))),
])
def test_every_column_and_unit_is_in_the_guide(section: str, names: tuple[str, ...]) -> None:
    text = sections(_text()).get(section, "")
    missing = [n for n in names if f"`{n}`".lower() not in text.lower()]
    assert not missing, f"docs/formats.md section '{section}' lacks {missing}"


def examples(text: str) -> dict[str, str]:
    """``<!-- example: NAME KIND -->`` followed by a fenced block: 'NAME KIND' -> its body."""
    pattern = re.compile(r"<!--\s*example:\s*([\w-]+ \w+)\s*-->\s*```\w*\n(.*?)```", re.S)
    return {match.group(1): match.group(2) for match in pattern.finditer(text)}


def test_every_file_has_a_minimal_and_a_full_example() -> None:
    found = examples(_text())
    for name in ("case", "uncertainty", "aircraft", "propulsion", "battery", "mission",
                 "campaign", "run", "table", "vendor", "proptables", "datasheet"):
        for kind in ("minimal", "full"):
            assert f"{name} {kind}" in found, f"docs/formats.md: no example '{name} {kind}'"


@pytest.mark.parametrize(("name", "schema"), [
    ("case", CaseSchema), ("aircraft", AircraftSchema), ("propulsion", PropulsionSchema),
    ("battery", BatterySchema), ("mission", MissionFileSchema), ("campaign", CampaignSchema),
    ("proptables", PropellerTablesSchema), ("datasheet", DatasheetSchema),
])
@pytest.mark.parametrize("kind", ["minimal", "full"])
def test_yaml_examples_validate(tmp_path: Path, name: str, schema: type[BaseModel],
                                kind: str) -> None:
    path = tmp_path / f"{name}.yaml"
    path.write_text(examples(_text())[f"{name} {kind}"], encoding="utf-8")
    load_model(path, schema)  # raises InputError naming the key


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_minimal_case_loads_with_its_minimal_files(tmp_path: Path) -> None:
    found = examples(_text())
    _write(tmp_path, "aircraft.yaml", found["aircraft minimal"])
    _write(tmp_path, "propulsion.yaml", found["propulsion minimal"])
    case = load_case(_write(tmp_path, "case.yaml", found["case minimal"]))
    assert case.requirements.takeoff is not None
    block = yaml.safe_load(found["uncertainty minimal"])
    data = yaml.safe_load(found["case minimal"]) | block
    with_block = load_case(_write(tmp_path, "with_block.yaml", yaml.safe_dump(data)))
    assert with_block.uncertainty is not None
    full = yaml.safe_load(found["case minimal"]) | yaml.safe_load(found["uncertainty full"])
    for key in full["uncertainty"]["parameters"]:
        assert key.split(".")[0] in ("aircraft", "atmosphere")
    assert load_case(_write(tmp_path, "full.yaml", yaml.safe_dump(full))).uncertainty


def test_minimal_battery_mission_and_campaign_load(tmp_path: Path) -> None:
    found = examples(_text())
    battery = _write(tmp_path, "battery.yaml", found["battery minimal"])
    for run in yaml.safe_load(found["battery minimal"])["runs"]:
        _write(tmp_path, run["file"], found["run full"])
    assert load_battery(battery).cells_in_series >= 1
    assert load_mission(_write(tmp_path, "mission.yaml", found["mission minimal"])).segments
    manifest = _write(tmp_path, "campaign.yaml", found["campaign minimal"])
    for run in yaml.safe_load(found["campaign minimal"])["runs"]:
        _write(tmp_path, run["file"], found["run minimal"])
    assert load_campaign(manifest).runs


def test_csv_examples_read(tmp_path: Path) -> None:
    found = examples(_text())
    run = run_columns.read_run(_write(tmp_path, "run.csv", found["run minimal"]))
    assert run.time_s.size >= 10
    discharge = run_columns.read_run(_write(tmp_path, "discharge.csv", found["run full"]),
                                     required=DISCHARGE_COLUMNS)
    assert "voltage_v" in discharge.columns
    for kind in ("minimal", "full"):
        table = run_columns.read_thrust_table(_write(tmp_path, f"t_{kind}.csv",
                                                     found[f"table {kind}"]))
        assert len(table.thrust_n) >= 4
        # the minimal stand is static: its airspeed comes from the manifest
        settings = vendor.VendorSettings(format="rcbenchmark",
                                         airspeed_m_s=0.0 if kind == "minimal" else None)
        stand = run_columns.read_run(_write(tmp_path, f"stand_{kind}.csv", found[f"vendor {kind}"]),
                                     vendor=settings)
        assert float(stand.columns["throttle"][-1]) == pytest.approx(1.0)


def test_propeller_table_example_reads(tmp_path: Path) -> None:
    found = examples(_text())
    manifest = _write(tmp_path, "props.yaml", found["proptables minimal"])
    for entry in yaml.safe_load(found["proptables minimal"])["tables"]:
        _write(tmp_path, entry["file"], found["uiuc minimal"])
    table = read_propeller_tables(manifest)
    assert len(table.thrust_n) == 3


def test_minimal_case_passes_check(tmp_path: Path) -> None:
    # the README's tutorial runs `check` on these three examples: it must answer, and pass
    from typer.testing import CliRunner

    from tuflexperf.cli import app

    found = examples(_text())
    _write(tmp_path, "aircraft.yaml", found["aircraft minimal"])
    _write(tmp_path, "propulsion.yaml", found["propulsion minimal"])
    case = _write(tmp_path, "case.yaml", found["case minimal"])
    result = CliRunner().invoke(app, ["check", str(case), "--json"])
    assert result.exit_code == 0, result.output
    assert "takeoff_ground_roll" in result.stdout
