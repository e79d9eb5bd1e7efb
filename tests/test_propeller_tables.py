"""Published propeller tables (UIUC, APC PER3) as thrust tables, with rows typed from real files.

Sources of the typed rows (kept verbatim, spacing included):
- APC PER3: ``PER3_10x7E.dat`` (APC performance data dated 12/19/14) as stored in the public
  repository JARC99/apc-prop-analyzer, ``apc_data/performance/PER3_10x7E.dat``: the first rows
  of the 1000, 2000 and 3000 rpm blocks.
- UIUC Propeller Data Site: ``apcsf_9x4.7_kt1033_4008.txt`` (APC Slow Flyer 9x4.7 at 4008 rpm)
  as stored in jemoster/aerospace-design-toolbox, ``sampleData/``: its first four rows.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from tuflexperf.cli import app
from tuflexperf.errors import InputError
from tuflexperf.io.proptables import read_apc_per3, read_propeller_tables, read_uiuc

runner = CliRunner()
MPH = 0.44704
LBF = 4.4482216152605

APC_10X7E = """\
         10x7E                    (10x7E.dat)                                  12/19/14

         ====== PERFORMANCE DATA (versus advance ratio and MPH) ======

         DEFINITIONS:
         J=V/nD (advance ratio)
         Ct=T/(rho * n**2 * D**4) (thrust coef.)

         PROP RPM =       1000

         V          J           Pe         Ct          Cp          PWR         Torque      Thrust
       (mph)     (Adv Ratio)                                       (Hp)        (In-Lbf)     (Lbf)
         0.0        0.00      0.0000      0.1159      0.0546       0.000       0.028       0.037
         0.3        0.03      0.0659      0.1157      0.0556       0.000       0.028       0.037
         3.0        0.32      0.5330      0.1045      0.0621       0.000       0.032       0.033
         6.0        0.63      0.7624      0.0574      0.0477       0.000       0.024       0.018

         PROP RPM =       2000

         V          J           Pe         Ct          Cp          PWR         Torque      Thrust
       (mph)     (Adv Ratio)                                       (Hp)        (In-Lbf)     (Lbf)
         0.0        0.00      0.0000      0.1159      0.0547       0.004       0.111       0.148
         6.0        0.32      0.5326      0.1046      0.0622       0.004       0.126       0.133
        12.0        0.63      0.7624      0.0575      0.0478       0.003       0.097       0.073
        15.0        0.79      0.7684      0.0266      0.0274       0.002       0.056       0.034

         PROP RPM =       3000

         V          J           Pe         Ct          Cp          PWR         Torque      Thrust
       (mph)     (Adv Ratio)                                       (Hp)        (In-Lbf)     (Lbf)
         0.0        0.00      0.0000      0.1160      0.0547       0.012       0.249       0.333
         0.9        0.03      0.0658      0.1158      0.0557       0.012       0.254       0.332
         1.8        0.06      0.1289      0.1155      0.0567       0.012       0.259       0.331
"""

UIUC_9X47_4008 = """\
J       CT       CP       eta
0.162   0.0936   0.0465   0.327
0.200   0.0875   0.0455   0.385
0.243   0.0809   0.0447   0.440
0.283   0.0742   0.0436   0.482
"""


def test_apc_per3_blocks_units_and_apcs_own_coefficients(tmp_path: Path) -> None:
    path = tmp_path / "PER3_10x7E.dat"
    path.write_text(APC_10X7E)
    blocks = read_apc_per3(path)
    assert [rpm for rpm, _ in blocks] == [1000.0, 2000.0, 3000.0]
    rpm, rows = blocks[1]
    np.testing.assert_allclose(rows[:, 0], np.array([0.0, 6.0, 12.0, 15.0]) * MPH)
    np.testing.assert_allclose(rows[:, 1], np.array([0.148, 0.133, 0.073, 0.034]) * LBF)
    # cross-check our units with APC's own Ct at 2000 rpm, V = 0: T = Ct rho n^2 D^4 (D = 10 in)
    n, d = 2000 / 60, 10 * 0.0254
    assert rows[0, 1] == pytest.approx(0.1159 * 1.225 * n**2 * d**4, rel=0.005)


def test_uiuc_rows_to_airspeed_and_thrust(tmp_path: Path) -> None:
    path = tmp_path / "apcsf_9x4.7_kt1033_4008.txt"
    path.write_text(UIUC_9X47_4008)
    rows = read_uiuc(path, diameter_m=9 * 0.0254, rpm=4008, density_kg_m3=1.225)
    n, d = 4008 / 60, 9 * 0.0254
    np.testing.assert_allclose(rows[:, 0], np.array([0.162, 0.200, 0.243, 0.283]) * n * d)
    np.testing.assert_allclose(rows[:, 1],
                               np.array([0.0936, 0.0875, 0.0809, 0.0742]) * 1.225 * n**2 * d**4)
    assert rows[0, 0] == pytest.approx(2.4739, abs=1e-4)  # by hand: 0.162 x 66.8 x 0.2286
    assert rows[0, 1] == pytest.approx(1.3972, abs=1e-4)


def _manifest(folder: Path, **extra: object) -> Path:
    (folder / "PER3_10x7E.dat").write_text(APC_10X7E)
    (folder / "apcsf_9x4.7_kt1033_4008.txt").write_text(UIUC_9X47_4008)
    doc = {
        "name": "APC props",
        "tables": [
            {"file": "PER3_10x7E.dat", "format": "apc_per3", "engine": "P1"},
            {"file": "apcsf_9x4.7_kt1033_4008.txt", "format": "uiuc", "engine": "P2",
             "diameter_m": 0.2286, "rpm": 4008},
        ],
        **extra,
    }
    path = folder / "props.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def test_manifest_to_thrust_table_throttle_is_rpm_fraction(tmp_path: Path) -> None:
    table = read_propeller_tables(_manifest(tmp_path, max_rpm={"P2": 8016}))
    assert table.engines() == ["P1", "P2"]
    x1, v1, t1 = table.select("P1")
    np.testing.assert_allclose(sorted(set(x1)), [1 / 3, 2 / 3, 1.0])
    assert t1[x1 == 1.0].max() == pytest.approx(0.333 * LBF)
    x2, _, _ = table.select("P2")
    np.testing.assert_allclose(x2, 0.5)  # 4008 of max_rpm 8016


def test_fit_accepts_a_propeller_manifest(tmp_path: Path) -> None:
    manifest = _manifest(tmp_path)
    doc = yaml.safe_load(manifest.read_text())
    doc["tables"] = doc["tables"][:1]  # APC: three rpm, many airspeeds, enough for a poly22
    manifest.write_text(yaml.safe_dump(doc))
    out = tmp_path / "prop.yaml"
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    fit = json.loads(result.stdout)["engines"][0]
    assert fit["name"] == "P1" and fit["r2"] > 0.99
    # static thrust ~ rpm^2: the fit carries that (p20 dominant at V = 0)
    c = fit["coefficients"]
    static = c["p00"] + c["p10"] + c["p20"]
    assert static == pytest.approx(0.333 * LBF, rel=0.03)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"tables": [{"file": "x.txt", "format": "uiuc", "engine": "E"}]}, "diameter_m and rpm"),
        ({"tables": [{"file": "missing.dat", "format": "apc_per3", "engine": "E"}]},
         "file not found"),
        ({"max_rpm": {"P1": 1500}}, "above max_rpm"),
        ({"max_rpm": {"nobody": 1500}}, "no table for engine"),
        # 1e100 m overflowed into a message naming no file or key (outside audit)
        ({"tables": [{"file": "x.txt", "format": "uiuc", "engine": "E", "diameter_m": 1e100,
                      "rpm": 4000}]}, "diameter_m"),
        ({"air_density_kg_m3": 1e300}, "air_density_kg_m3"),
        # the engine names a thrust table's CSV columns, as in a campaign
        ({"tables": [{"file": "x.txt", "format": "apc_per3", "engine": "=1+1"}]},
         "fills CSV cells"),
    ],
)
def test_bad_propeller_manifests(tmp_path: Path, change: dict, message: str) -> None:
    manifest = _manifest(tmp_path)
    doc = yaml.safe_load(manifest.read_text())
    doc.update(change)
    manifest.write_text(yaml.safe_dump(doc))
    with pytest.raises(InputError, match=message):
        read_propeller_tables(manifest)
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "o.yaml")])
    assert result.exit_code == 2 and message.split()[0] in result.stderr


@pytest.mark.parametrize("rpm", [".", "0", "1.2.3", "-5", "nan", ""])
def test_an_rpm_line_that_is_no_speed_is_bad_input(tmp_path: Path, rpm: str) -> None:
    """'PROP RPM = .' gave a ValueError traceback and '= 0' a ZeroDivisionError (outside
    audit)."""
    from tuflexperf.errors import InputError

    path = tmp_path / "PER3_10x7E.dat"
    path.write_text(APC_10X7E.replace("PROP RPM =       2000", f"PROP RPM = {rpm}"))
    with pytest.raises(InputError, match="is no speed"):
        read_apc_per3(path)


def test_report_draws_a_propeller_manifest_as_measured_points(tmp_path: Path) -> None:
    """``report --campaign props.yaml`` (or a propulsion file fitted from one): its points."""
    from tuflexperf.io.case import load_case
    from tuflexperf.report.data import load_measured

    manifest = _manifest(tmp_path)
    case = load_case(Path("requirements/tuflex.yaml"))
    measured = load_measured(case, manifest)
    assert measured.kind == "table" and measured.points is not None
    table = read_propeller_tables(manifest)
    np.testing.assert_array_equal(measured.points.thrust_n, table.thrust_n)
    assert "propeller tables" in measured.notes[0]


# Each was accepted silently (a negative J flipped the coefficients' signs and the fit went
# on) or named the manifest, not the table (a NaN): issue 46
_APC_ROW_2000 = ("         6.0        0.32      0.5326      0.1046      0.0622       0.004"
                 "       0.126       0.133")


@pytest.mark.parametrize(("row", "after", "column"), [
    (_APC_ROW_2000.replace("6.0 ", "-6.0 ", 1), 0, "V (mph)"),
    (_APC_ROW_2000.replace("0.32", "-0.32", 1), 0, "J"),
    (_APC_ROW_2000.replace("0.32", "0.90", 1), 1, "J"),  # then 0.63 follows: J falls
    (_APC_ROW_2000.replace("0.133", "nan", 1), 0, "Thrust (Lbf)"),
    (_APC_ROW_2000.replace("0.32", "nan", 1), 0, "J"),
])
def test_an_apc_row_with_a_bad_sign_order_or_nan_is_refused_by_line_and_column(
        tmp_path: Path, row: str, after: int, column: str) -> None:
    line = APC_10X7E.splitlines().index(_APC_ROW_2000) + 1 + after
    manifest = _manifest(tmp_path)
    table = tmp_path / "PER3_10x7E.dat"
    text = APC_10X7E.replace(_APC_ROW_2000, row)
    assert text != APC_10X7E
    table.write_text(text)
    with pytest.raises(InputError) as caught:
        read_apc_per3(table)
    assert str(caught.value).startswith(f"{table}: line {line}: column {column}: ")
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "o.yaml")])
    assert result.exit_code == 2
    assert f"PER3_10x7E.dat: line {line}: column {column}" in result.stderr
    assert not (tmp_path / "o.yaml").exists()


@pytest.mark.parametrize(("row", "line", "column"), [
    ("-0.162   0.0936   0.0465   0.327", 2, "J"),
    ("0.262   0.0936   0.0465   0.327", 3, "J"),  # then 0.200: J falls
    ("0.162   nan   0.0465   0.327", 2, "CT"),
    ("inf   0.0936   0.0465   0.327", 2, "J"),
])
def test_a_uiuc_row_with_a_bad_sign_order_or_nan_is_refused_by_line_and_column(
        tmp_path: Path, row: str, line: int, column: str) -> None:
    table = tmp_path / "apcsf_9x4.7_kt1033_4008.txt"
    table.write_text(UIUC_9X47_4008.replace("0.162   0.0936   0.0465   0.327", row))
    with pytest.raises(InputError) as caught:
        read_uiuc(table, diameter_m=9 * 0.0254, rpm=4008, density_kg_m3=1.225)
    assert str(caught.value).startswith(f"{table}: line {line}: column {column}: ")


def test_line_numbers_count_blank_lines(tmp_path: Path) -> None:
    table = tmp_path / "t.txt"
    table.write_text("J CT CP eta\n\n0.1 0.09 0.04 0.3\n\n0.05 0.09 0.04 0.3\n")
    with pytest.raises(InputError, match=r"t\.txt: line 5: column J: advance ratio 0.05"):
        read_uiuc(table, diameter_m=0.2, rpm=4000, density_kg_m3=1.225)


def test_j_starts_again_in_each_rpm_block(tmp_path: Path) -> None:
    """Each block of an APC file runs from J = 0 again: no fall across a block's start."""
    table = tmp_path / "PER3_10x7E.dat"
    table.write_text(APC_10X7E)
    assert len(read_apc_per3(table)) == 3
