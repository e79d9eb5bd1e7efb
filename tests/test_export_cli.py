"""`tuflexperf export`: files written, their content, bad input -> exit 2 with nothing left."""

from __future__ import annotations

import copy
import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tests.c_model import CThrustModel, compile_shared
from tests.conftest import MADE_UP_PROPULSION, write_case
from tuflexperf.cli import app
from tuflexperf.export import FILES
from tuflexperf.export.cbuild import find_compiler
from tuflexperf.io.case import load_propulsion
from tuflexperf.io.files import MARKER
from tuflexperf.models.thrust import total_thrust_n

ROOT = Path(__file__).resolve().parent.parent
# the default --format (jsbsim and fmu are asked for by name)
ALL_FILES = sorted(name for fmt in ("c", "casadi", "json") for name in FILES[fmt])
runner = CliRunner()


def _export(*args: str) -> object:
    return runner.invoke(app, ["export", *args])


def test_export_all_formats(made_up_case: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = _export("--case", str(made_up_case), "--out", str(out))
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir() if p.name != MARKER) == ALL_FILES
    for name in ALL_FILES:
        assert str(out / name) in result.output


def test_export_json_listing_and_model_file(made_up_case: Path, tmp_path: Path) -> None:
    out = tmp_path / "j"
    result = _export("--case", str(made_up_case), "--format", "json", "--out", str(out), "--json")
    assert result.exit_code == 0, result.output
    listing = json.loads(result.stdout)
    assert listing["files"] == [str(out / "tfp_thrust.json")]
    assert listing["formats"] == ["json"]
    assert [p.name for p in out.iterdir() if p.name != MARKER] == ["tfp_thrust.json"]
    doc = json.loads((out / "tfp_thrust.json").read_text())
    propulsion_file = made_up_case.parent / "propulsion.yaml"
    prop = load_propulsion(propulsion_file)
    assert [e["name"] for e in doc["engines"]] == [e.name for e in prop.engines]
    for entry, engine in zip(doc["engines"], prop.engines, strict=True):
        assert entry["coefficients"] == dict(engine.coefficients)
    assert doc["delay_s"] == prop.delay_s
    assert doc["reference_density_kg_m3"] is None
    assert doc["throttle_unit"] == "fraction"
    assert doc["validity"]["tested_airspeed_m_s"] == list(prop.tested_airspeed_m_s)
    assert doc["validity"]["throttle"] == [0.0, 1.0]
    assert "extrapolat" in doc["validity"]["extrapolation_warning"]
    digests = {f["role"]: f["sha256"] for f in doc["provenance"]["files"]}
    assert digests["propulsion"] == hashlib.sha256(propulsion_file.read_bytes()).hexdigest()
    assert digests["case"] == hashlib.sha256(made_up_case.read_bytes()).hexdigest()
    assert listing["propulsion_sha256"] == digests["propulsion"]


def test_casadi_files_load_and_match_the_model(tmp_path: Path) -> None:
    import casadi as ca

    data = copy.deepcopy(MADE_UP_PROPULSION)
    data["reference_density_kg_m3"] = 1.1
    case = write_case(tmp_path / "case", propulsion=data)
    out = tmp_path / "cas"
    result = _export("--case", str(case), "--format", "casadi", "--out", str(out))
    assert result.exit_code == 0, result.output
    prop = load_propulsion(case.parent / "propulsion.yaml")
    thrust = ca.Function.load(str(out / "tfp_thrust.casadi"))
    inverse = ca.Function.load(str(out / "tfp_throttle_for_thrust.casadi"))
    assert thrust.name_in() == ["throttle", "airspeed_m_s", "density_kg_m3"]
    assert thrust.name_out() == ["thrust_n", "total_thrust_n"]
    rng = np.random.default_rng(2)
    for _ in range(200):
        x = rng.uniform(0, 1, 2)
        v, rho = rng.uniform(0, 45), rng.uniform(0.9, 1.3)
        per_engine, total = thrust(x, v, rho)
        assert float(total) == pytest.approx(
            total_thrust_n(prop, list(x), v, rho), abs=1e-9
        )
        demand = float(total_thrust_n(prop, x[0], v, rho))
        throttle, reached = inverse(demand, v, rho)
        assert float(reached) == 1.0
        got = float(total_thrust_n(prop, float(throttle), v, rho))
        if float(throttle) == 0.0:  # idle already reaches the demand
            assert got >= demand
        else:
            assert got == pytest.approx(demand, abs=1e-9)


@pytest.mark.parametrize("formats", ["c,xml", "", "pdf", " , "])
def test_bad_format_exit_2_nothing_written(
    made_up_case: Path, tmp_path: Path, formats: str
) -> None:
    out = tmp_path / "never"
    result = _export("--case", str(made_up_case), "--format", formats, "--out", str(out))
    assert result.exit_code == 2
    assert "--format" in result.output
    assert not out.exists()
    assert list(tmp_path.iterdir()) == [made_up_case.parent]


def test_bad_case_exit_2_nothing_written(tmp_path: Path) -> None:
    data = copy.deepcopy(MADE_UP_PROPULSION)
    data["engines"][0]["coefficients"]["p12"] = 1.0  # misspelt key
    case = write_case(tmp_path / "case", propulsion=data)
    out = tmp_path / "never"
    result = _export("--case", str(case), "--out", str(out))
    assert result.exit_code == 2
    assert "propulsion.yaml" in result.output and "p12" in result.output
    assert not out.exists()
    missing = _export("--case", str(tmp_path / "nope.yaml"), "--out", str(out))
    assert missing.exit_code == 2 and not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case"]  # no staging dir left


def test_out_is_a_file_exit_2(made_up_case: Path, tmp_path: Path) -> None:
    target = tmp_path / "file.txt"
    target.write_text("keep")
    result = _export("--case", str(made_up_case), "--out", str(target))
    assert result.exit_code == 2 and "--out" in result.output
    assert target.read_text() == "keep"


def test_foreign_folder_is_refused_and_an_earlier_export_is_replaced(
    made_up_case: Path, tmp_path: Path
) -> None:
    """SPEC 5, "Nothing is lost": only a folder an earlier export wrote may be replaced."""
    out = tmp_path / "existing"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / "tfp_thrust.json").write_text("old")
    result = _export("--case", str(made_up_case), "--format", "json,c", "--out", str(out))
    assert result.exit_code == 2
    assert "--out" in result.stderr and "did not write" in result.stderr
    assert (out / "notes.txt").read_text() == "mine"
    assert (out / "tfp_thrust.json").read_text() == "old"
    fresh = tmp_path / "fresh"
    assert _export("--case", str(made_up_case), "--format", "json,c", "--out",
                   str(fresh)).exit_code == 0
    again = _export("--case", str(made_up_case), "--format", "json", "--out", str(fresh))
    assert again.exit_code == 0, again.output
    assert sorted(p.name for p in fresh.iterdir() if p.name != MARKER) == ["tfp_thrust.json"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_failure_mid_build_leaves_nothing(
    made_up_case: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import tuflexperf.export.writer as writer

    real = writer._write_format

    def flaky(model: object, fmt: str, directory: Path) -> None:
        if fmt == "json":
            raise RuntimeError("disk full")
        real(model, fmt, directory)

    monkeypatch.setattr(writer, "_write_format", flaky)
    out = tmp_path / "out"
    result = _export("--case", str(made_up_case), "--out", str(out))
    assert result.exit_code != 0
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [made_up_case.parent.name]


@pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) installed")
def test_console_script_exports_shipped_model_that_compiles(tmp_path: Path) -> None:
    """The real `tuflexperf` script on the shipped case; the C built with the contract's flags."""
    script = Path(sys.executable).parent / "tuflexperf"
    out = tmp_path / "shipped"
    done = subprocess.run(
        [str(script), "export", "--out", str(out), "--json"],
        capture_output=True, text=True, check=False,
    )
    assert done.returncode == 0, done.stderr
    assert sorted(Path(f).name for f in json.loads(done.stdout)["files"]) == ALL_FILES
    library = compile_shared(
        [out / "tfp_thrust.c"], tmp_path / "lib.so",
        cflags=("-O2", "-std=c99", "-Wall", "-Werror"),
    )
    c = CThrustModel(library, 2)
    prop = load_propulsion(ROOT / "data" / "tuflex" / "propulsion.yaml")
    code, (t1, t2) = c.thrust([1.0, 0.5], 30.0, 1.225)
    assert code == 0
    assert t1 + t2 == pytest.approx(total_thrust_n(prop, [1.0, 0.5], 30.0, 1.225), abs=1e-9)
    header = (out / "tfp_thrust.h").read_text()
    digest = hashlib.sha256((ROOT / "data" / "tuflex" / "propulsion.yaml").read_bytes()).hexdigest()
    assert digest in header and "WARNING" in header and "TFP_DELAY_S" in header


def test_every_format_says_what_its_functions_leave_out(tmp_path: Path) -> None:
    """The voltage effect and a dead engine's windmilling drag were in no C, CasADi, FMU or
    JSBSim file (outside audit): each format now states both, the JSON with the numbers."""
    import zipfile

    propulsion = copy.deepcopy(MADE_UP_PROPULSION)
    propulsion.update(reference_voltage_v=44.4, voltage_exponent=1.7, fan_area_m2=0.0068,
                      format=2)
    propulsion["engines"][0]["windmilling_drag_coefficient"] = 0.3
    case = write_case(tmp_path / "case", propulsion=propulsion)
    out = tmp_path / "exp"
    result = runner.invoke(app, ["export", "--case", str(case), "--format",
                                 "c,casadi,json,jsbsim,fmu", "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    notes = json.loads(result.stdout)["notes"]
    assert any("(U / 44.4)^1.7" in n for n in notes)
    assert any("-Cd_wm q A_fan" in n and "A_fan = 0.0068" in n for n in notes)
    header = (out / "tfp_thrust.h").read_text()
    system = (out / "tfp_thrust_system.xml").read_text()
    fmu = next(out.glob("*.fmu"))
    with zipfile.ZipFile(fmu) as archive:
        description = archive.read("modelDescription.xml").decode()
    for text in (header, system, description):
        assert "44.4" in text and "windmilling drag" in text
    data = json.loads((out / "tfp_thrust.json").read_text())
    engine = propulsion["engines"][0]["name"]
    assert data["dead_engine"]["windmilling_drag_coefficient"] == {engine: 0.3}
    assert data["dead_engine"]["fan_area_m2"] == 0.0068


def test_provenance_json_cannot_hold_is_written_as_text(tmp_path: Path) -> None:
    """A date, a timestamp, bytes, a set or a NaN in the propulsion's free-form `source:`
    ended the export in a traceback (outside re-audit)."""
    from tests.conftest import copy_shipped_case

    case = copy_shipped_case(tmp_path)
    propulsion = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    propulsion.write_text(propulsion.read_text() + "source:\n  date: 2024-05-01\n"
                          "  blob: !!binary aGVsbG8=\n  tags: !!set {a, b}\n  n: .nan\n")
    result = runner.invoke(app, ["export", "--case", str(case), "--format", "json",
                                 "--out", str(tmp_path / "ex")])
    assert result.exit_code == 0, result.output
    model = json.loads((tmp_path / "ex" / "tfp_thrust.json").read_text())
    assert model["provenance"]["source"] == {"date": "2024-05-01", "blob": "68656c6c6f",
                                             "tags": ["a", "b"], "n": "nan"}


def test_odd_file_and_engine_names_still_give_files_their_clients_read(tmp_path: Path) -> None:
    """A propulsion file named with ``---`` and a control byte, an engine named ``X???/``:
    every XML still parses and the C compiles with -Werror (outside audit: ``---`` became
    ``--`` in the FMU's comment, the byte went raw into JSBSim's and FMI's XML, and ``???``
    kept a ``??/`` trigraph)."""
    import xml.etree.ElementTree as ElementTree
    import zipfile

    import yaml

    if find_compiler() is None:
        pytest.skip("no C compiler")
    propulsion = copy.deepcopy(MADE_UP_PROPULSION)
    propulsion["engines"][1]["name"] = "X???/"
    folder = tmp_path / "case"
    case = write_case(folder)
    odd = "prop---v2\x01.yaml"
    (folder / odd).write_text(yaml.safe_dump(propulsion))
    text = case.read_text().replace("propulsion: propulsion.yaml", f'propulsion: "{odd}"'
                                    .replace("\x01", "\\x01"))
    case.write_text(text)
    out = tmp_path / "out"
    result = _export("--case", str(case), "--format", "c,jsbsim,fmu", "--out", str(out))
    assert result.exit_code == 0, result.stderr
    for name in ("tfp_thrust_system.xml", "tfp_thrust_reactions.xml"):
        ElementTree.parse(out / name)
    with zipfile.ZipFile(out / "tfp_thrust.fmu") as fmu:
        description = fmu.read("modelDescription.xml")
    ElementTree.fromstring(description)
    assert b"prop-v2\\x01.yaml" in description
    compile_shared([out / "tfp_thrust.c"], tmp_path / "lib.so",
                   cflags=("-O2", "-std=c99", "-Wall", "-Wextra", "-Werror"))
