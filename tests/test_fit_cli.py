"""`tuflexperf fit` through typer's CliRunner and one real subprocess run."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from tuflexperf.cli import app
from tuflexperf.io.case import load_propulsion
from tuflexperf.models.thrust import poly22

runner = CliRunner()
SHIPPED_CAMPAIGN = Path(__file__).resolve().parents[1] / "data" / "tuflex" / "campaign"


def campaign_copy(tmp_path: Path) -> Path:
    """A copy of the shipped campaign (manifest and runs) in ``tmp_path / "campaign"``."""
    folder = tmp_path / "campaign"
    shutil.copytree(SHIPPED_CAMPAIGN, folder)
    return folder
# runs written back at gzip level 1: the same bytes once read, a quarter of the time
FAST = {"method": "infer", "compresslevel": 1}
COEFFICIENTS = {"p00": 0.2, "p10": 5.0, "p01": -0.12, "p20": 40.0, "p11": -0.3, "p02": 0.0007}


def write_table(path: Path, scale: float = 1.0) -> Path:
    rows = ["engine,throttle,airspeed_m_s,thrust_n"]
    rng = np.random.default_rng(0)
    for engine in ("L", "R"):
        for v in (0.0, 10.0, 20.0, 30.0):
            for x in np.round(np.arange(0.1, 1.01, 0.1), 1):
                thrust = poly22(x, v, COEFFICIENTS) + rng.normal(0, 0.2)
                rows.append(f"{engine},{float(x * scale)!r},{v!r},{float(thrust)!r}")
    path.write_text("\n".join(rows) + "\n")
    return path


def test_table_fit_json_keys_and_files(tmp_path: Path) -> None:
    table = write_table(tmp_path / "table.csv")
    out = tmp_path / "fit.yaml"
    result = runner.invoke(app, ["fit", str(table), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["delay_s"] is None
    assert [e["name"] for e in data["engines"]] == ["L", "R"]
    for engine in data["engines"]:
        assert set(engine) >= {"name", "coefficients", "r2", "rmse_n"}
        assert engine["coefficients"]["p20"] == pytest.approx(40.0, abs=2.0)
    model = load_propulsion(out)  # the schema `check` uses
    assert model.delay_s == 0.0 and model.tested_airspeed_m_s == (0.0, 30.0)
    assert data["table"] is None and not list(tmp_path.glob("*_thrust_table.csv"))


def test_delay_flag_and_human_output(tmp_path: Path) -> None:
    table = write_table(tmp_path / "table.csv")
    out = tmp_path / "fit.yaml"
    result = runner.invoke(app, ["fit", str(table), "--out", str(out), "--delay-s", "0.04"])
    assert result.exit_code == 0, result.stderr
    assert "R^2" in result.stdout and "wrote" in result.stdout
    assert yaml.safe_load(out.read_text())["delay_s"] == 0.04


def test_default_out_is_propulsion_fit_yaml_in_the_current_directory(tmp_path: Path) -> None:
    table = write_table(tmp_path / "table.csv")
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        result = runner.invoke(app, ["fit", "table.csv"])
    finally:
        os.chdir(cwd)
    assert result.exit_code == 0, result.stderr
    assert (tmp_path / "propulsion_fit.yaml").is_file()
    assert table.is_file()


def broken_campaign(folder: Path) -> Path:
    """A campaign whose step run lacks the force column: must fail before writing."""
    folder.mkdir()
    t = np.arange(0, 5, 0.01)
    rows = ["time_s,airspeed_m_s,throttle"] + [f"{x},10,0.5" for x in t]
    (folder / "run.csv").write_text("\n".join(rows) + "\n")
    manifest = {
        "name": "broken",
        "fan_area_m2": 0.0068,
        "tunnel_area_m2": 0.16,
        "runs": [{"file": "run.csv", "engine": "E", "kind": "throttle_steps"}],
    }
    path = folder / "campaign.yaml"
    path.write_text(yaml.safe_dump(manifest))
    return path


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nope.yaml"], "nope.yaml: file not found"),
        (["{percent}"], "percent"),
        (["{table}", "--glauert"], "--glauert"),
        (["{table}", "--delay-s", "-1"], "--delay-s"),
        # longer than any throttle plateau: it blamed the airspeed coverage of the runs
        (["{table}", "--delay-s", "5"], "--delay-s: 5 s is beyond 1 s"),
        # it wrote files named "-" and "-_thrust_table.csv" (outside audit)
        (["{table}", "--out", "-"], "--out: '-' (stdout) is no file name"),
        (["{table}", "--out", "{tmp}"], "--out"),
        (["{campaign}"], "missing column 'force_n'"),
    ],
)
def test_bad_input_exit_2_one_line_no_output(tmp_path: Path, args: list[str], message: str) -> None:
    table = write_table(tmp_path / "table.csv")
    percent = write_table(tmp_path / "percent.csv", scale=100.0)
    campaign = broken_campaign(tmp_path / "camp")
    out = tmp_path / "out" / "fit.yaml"
    names = {"table": table, "percent": percent, "campaign": campaign, "tmp": tmp_path}
    argv = ["fit", *[a.format(**names) for a in args]]
    if "--out" not in argv:
        argv += ["--out", str(out)]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2
    assert message in result.stderr
    assert result.stderr.strip().count("\n") == 0 and "Traceback" not in result.output
    assert result.stdout == ""
    assert not (tmp_path / "out").exists()  # no partial output


def test_installed_script_fits_a_table(tmp_path: Path) -> None:
    script = shutil.which("tuflexperf", path=str(Path(sys.executable).parent))
    if script is None:
        pytest.skip("console script not installed")
    write_table(tmp_path / "table.csv")
    done = subprocess.run(
        [script, "fit", "table.csv", "--out", "p.yaml", "--json"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["engines"][0]["name"] == "L"
    assert done.stderr == ""  # no progress bar or notes outside a terminal
    bad = subprocess.run(
        [script, "fit", "missing.csv"], cwd=tmp_path, capture_output=True, text=True
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "missing.csv" in bad.stderr


def test_one_run_without_voltage_fits_without_the_voltage_effect(tmp_path: Path) -> None:
    """One engine's run lost its voltage and current columns: the file's one reference
    voltage and exponent cannot hold for that engine, so no voltage effect is fitted (a
    warning names the engine) and the fit completes. It stopped with "the fitted propulsion
    file would not be valid: p00 None": the other engine's exponent scaled the thrust of
    points whose voltage is unknown to NaN."""
    import pandas as pd

    folder = campaign_copy(tmp_path)
    run = folder / "runs" / "edf1_v20p0.csv.gz"
    pd.read_csv(run).drop(columns=["voltage_v", "current_a"]).to_csv(run, index=False,
                                                                     compression=FAST)
    out = tmp_path / "fitted.yaml"
    result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out", str(out),
                                      "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert any("not logged at every point of engine EDF1" in w
               for w in summary["warnings"]), summary["warnings"]
    model = load_propulsion(out)
    assert model.reference_voltage_v is None
    for engine in model.engines:
        assert all(np.isfinite(list(engine.coefficients.values())))


# (files, column, factor, message): a fit no rig gives is bad input
UNPHYSICAL = [
    # the drag sweep logged in mN: 3058 N of "structure drag" added to every point, and
    # check then passed at trim throttle 0 (outside audit)
    ("structure_drag.csv", "force_n", 1000.0, "in other units (mN)"),
    ("structure_drag.csv", "force_n", -1.0, "force sign of the drag sweep"),
    # EDF1's balance wired the other way: fit wrote T(1,0) = -54.7 N, which check refuses
    ("edf1_v*.csv.gz", "force_n", -1.0, "engine EDF1: the fitted full-throttle static"),
    # one run's balance wired the other way: R^2 0.43, written with no word (outside audit)
    ("edf1_v15p0.csv.gz", "force_n", -1.0, "explains only R^2 = 0.4"),
    # EDF1's pack logged in mV: a 24 kV reference voltage and 1e7 N for EDF2, exit 0
    ("edf1_v*.csv.gz", "voltage_v", 1000.0, "voltage_v: median"),
    ("edf1_v15p0.csv.gz", "voltage_v", 1e-200, "no pack voltage"),  # crashed the SVD
]


@pytest.mark.parametrize(("pattern", "column", "factor", "message"), UNPHYSICAL)
def test_a_fit_no_rig_gives_is_refused(tmp_path: Path, pattern: str, column: str,
                                       factor: float, message: str) -> None:
    import pandas as pd

    folder = campaign_copy(tmp_path)
    for run in (folder / "runs").glob(pattern):
        frame = pd.read_csv(run)
        frame[column] *= factor
        frame.to_csv(run, index=False, compression=FAST)
    out = tmp_path / "fitted.yaml"
    result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out", str(out)])
    assert result.exit_code == 2, result.output
    assert message in result.stderr and result.stderr.count("\n") == 1, result.stderr
    assert not out.exists() and not (tmp_path / "fitted_thrust_table.csv").exists()


def test_a_run_that_gives_no_test_point_is_named_and_a_backwards_wind_refused(
        tmp_path: Path) -> None:
    """A 50-row step run and one with its time in microseconds were dropped without a word
    (66 of 77 points fitted); a step run with its airspeed sign flipped was fitted, where the
    same values in a table are refused (outside audit)."""
    import pandas as pd

    folder = campaign_copy(tmp_path)
    runs = folder / "runs"
    pd.read_csv(runs / "edf1_v20p0.csv.gz").iloc[:50].to_csv(runs / "edf1_v20p0.csv.gz",
                                                             index=False, compression=FAST)
    micro = pd.read_csv(runs / "edf1_v25p0.csv.gz")
    micro["time_s"] *= 1e-6
    micro.to_csv(runs / "edf1_v25p0.csv.gz", index=False, compression=FAST)
    result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                      str(tmp_path / "fitted.yaml"), "--json"])
    assert result.exit_code == 0, result.output
    warnings = json.loads(result.stdout)["warnings"]
    for name in ("edf1_v20p0.csv.gz", "edf1_v25p0.csv.gz"):
        assert any(name in w and "no test point" in w for w in warnings), warnings
    # a pitot's zero offset at rest (-0.6 m/s on a real rig) is no flipped sign
    offset = pd.read_csv(runs / "edf1_v00p0.csv.gz")
    offset["airspeed_m_s"] = offset["airspeed_m_s"] - 0.6
    offset.to_csv(runs / "edf1_v00p0.csv.gz", index=False, compression=FAST)
    result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                      str(tmp_path / "offset.yaml")])
    assert result.exit_code == 0, result.output
    backwards = pd.read_csv(runs / "edf1_v30p0.csv.gz")
    backwards["airspeed_m_s"] *= -1
    backwards.to_csv(runs / "edf1_v30p0.csv.gz", index=False, compression=FAST)
    result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                      str(tmp_path / "again.yaml")])
    assert result.exit_code == 2 and "edf1_v30p0.csv.gz: column airspeed_m_s" in result.stderr


def test_sweeps_without_response_or_shifted_and_a_dead_load_cell_are_said(
        tmp_path: Path) -> None:
    """Noise-only sine sweeps entered the delay (0.087 and 0.49 s into the mean, no note); a
    sweep shifted by 0.2 s moved the written delay silently; a load cell stuck at 1 N gave
    a run of points with no word (outside audit)."""
    import pandas as pd

    folder = campaign_copy(tmp_path)
    runs = folder / "runs"
    rng = np.random.default_rng(0)
    for name in ("edf2_sweep_v00.csv.gz", "edf2_sweep_v30.csv.gz"):
        frame = pd.read_csv(runs / name)
        frame["force_n"] = rng.normal(0.0, 0.3, len(frame))
        frame.to_csv(runs / name, index=False, compression=FAST)
    stuck = pd.read_csv(runs / "edf1_v20p0.csv.gz")
    stuck["force_n"] = 1.0
    stuck.to_csv(runs / "edf1_v20p0.csv.gz", index=False, compression=FAST)

    def fit(name: str) -> dict:
        result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                          str(tmp_path / name), "--json"])
        assert result.exit_code == 0, result.output
        return json.loads(result.stdout)

    summary = fit("noise.yaml")
    warnings = summary["warnings"]
    for name in ("edf2_sweep_v00.csv.gz", "edf2_sweep_v30.csv.gz"):
        assert any(name in w and "does not follow the sine sweep" in w for w in warnings)
    assert any("EDF2: no sine sweep of its own" in w for w in warnings)
    assert any("edf1_v20p0.csv.gz" in w and "dead load cell" in w for w in warnings)
    assert summary["delay_s"] == pytest.approx(0.050, abs=0.002)  # EDF1's sweeps alone
    shutil.copy(SHIPPED_CAMPAIGN / "runs" / "edf2_sweep_v30.csv.gz", runs / "edf2_sweep_v30.csv.gz")
    shifted = pd.read_csv(SHIPPED_CAMPAIGN / "runs" / "edf2_sweep_v00.csv.gz")
    shifted["force_n"] = np.roll(shifted["force_n"].to_numpy(), 200)  # 0.2 s at 1 kHz
    shifted.to_csv(runs / "edf2_sweep_v00.csv.gz", index=False, compression=FAST)
    warnings = fit("shifted.yaml")["warnings"]
    assert any("EDF2: its sine sweeps disagree on the delay" in w for w in warnings), warnings
    # a time base logged in tenths of its seconds: 45 ms off, under the old 0.05 s spread
    shutil.copy(SHIPPED_CAMPAIGN / "runs" / "edf2_sweep_v00.csv.gz", runs / "edf2_sweep_v00.csv.gz")
    scaled = pd.read_csv(SHIPPED_CAMPAIGN / "runs" / "edf2_sweep_v30.csv.gz")
    scaled["time_s"] = scaled["time_s"] * 0.1
    scaled.to_csv(runs / "edf2_sweep_v30.csv.gz", index=False, compression=FAST)
    warnings = fit("scaled.yaml")["warnings"]
    assert any("EDF2: its sine sweeps disagree on the delay" in w for w in warnings), warnings


def test_one_engines_undetermined_voltage_exponent_leaves_the_other_engine_alone(
        tmp_path: Path) -> None:
    """A stuck load cell in one EDF1 run left EDF1's voltage exponent undetermined, and with
    it every engine's thrust went uncorrected to the reference voltage still written: the
    untouched EDF2's static thrust moved by 3.6 % (outside audit). Now the determined
    engines' exponent serves the file and EDF2 stays as fitted from clean runs."""
    import pandas as pd

    folder = campaign_copy(tmp_path)
    stuck = pd.read_csv(folder / "runs" / "edf1_v20p0.csv.gz")
    stuck["force_n"] = 1.0
    stuck.to_csv(folder / "runs" / "edf1_v20p0.csv.gz", index=False, compression=FAST)

    def edf2(manifest: Path, name: str) -> tuple[dict, list[str]]:
        result = CliRunner().invoke(app, ["fit", str(manifest), "--out", str(tmp_path / name),
                                          "--json"])
        assert result.exit_code == 0, result.output
        summary = json.loads(result.stdout)
        engine = next(e for e in summary["engines"] if e["name"] == "EDF2")
        return engine["coefficients"], summary["warnings"]

    clean, _ = edf2(SHIPPED_CAMPAIGN / "campaign.yaml", "clean.yaml")
    corrupt, warnings = edf2(folder / "campaign.yaml", "corrupt.yaml")
    # the stuck run is now left out of the fit (a dead load cell), so EDF1's exponent is
    # determined from its clean runs; either way EDF2 keeps its clean fit
    assert any("edf1_v20p0.csv.gz" in w and "left out of the fit" in w for w in warnings)
    assert not any("engine EDF1: voltage exponent not determined" in w for w in warnings)
    static = {name: c["p00"] + c["p10"] + c["p20"] for name, c in (("clean", clean),
                                                                   ("corrupt", corrupt))}
    assert static["corrupt"] == pytest.approx(static["clean"], rel=2e-3)


def test_a_misspelt_battery_key_is_named_with_the_closest_one(tmp_path: Path) -> None:
    """`fit battery.yaml` with `cells_in_seires`: the file was taken for a campaign manifest
    ("unknown key ... and 12 more problems", no hint); check named the right key."""
    shipped = Path(__file__).resolve().parents[1] / "data" / "tuflex"
    shutil.copy(shipped / "battery.yaml", tmp_path / "battery.yaml")
    shutil.copytree(shipped / "endurance", tmp_path / "endurance")
    path = tmp_path / "battery.yaml"
    path.write_text(path.read_text().replace("cells_in_series:", "cells_in_seires:"))
    result = CliRunner().invoke(app, ["fit", str(path), "--out", str(tmp_path / "b.yaml")])
    assert result.exit_code == 2
    assert "did you mean 'cells_in_series'?" in result.stderr, result.stderr


def test_two_runs_of_one_engine_at_one_airspeed_are_said(tmp_path: Path) -> None:
    """An EDF2 run labelled EDF1 gave EDF1 two runs at 30 m/s (88 points) without a word
    (outside audit); repeats are legitimate, so it is a note naming both runs."""
    folder = campaign_copy(tmp_path)
    manifest = folder / "campaign.yaml"
    manifest.write_text(manifest.read_text().replace(
        "{file: runs/edf2_v30p0.mat, engine: EDF2", "{file: runs/edf2_v30p0.mat, engine: EDF1"))
    result = CliRunner().invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "f.yaml"),
                                      "--json"])
    assert result.exit_code == 0, result.output
    warnings = json.loads(result.stdout)["warnings"]
    assert any("EDF1: 2 throttle-step runs at 30 m/s" in w and "edf2_v30p0.mat" in w
               for w in warnings), warnings


def test_a_campaigns_endurance_runs_are_named_not_dropped(tmp_path: Path) -> None:
    """SPEC 4 lists kind: endurance runs in a campaign; fit left them out with nothing said
    but a JSON key (outside audit): now each is named with the fit that takes it."""
    root = Path(__file__).resolve().parent.parent
    campaign = tmp_path / "campaign"
    shutil.copytree(root / "data/tuflex/campaign", campaign)
    shutil.copy(root / "data/tuflex/endurance/edf1_endurance_50.csv", campaign / "runs")
    manifest = campaign / "campaign.yaml"
    manifest.write_text(manifest.read_text()
                        + "  - {file: runs/edf1_endurance_50.csv, engine: EDF1, kind: endurance}\n")
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "p.yaml"),
                                 "--json"])
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    said = [w for w in data["warnings"] if "edf1_endurance_50.csv" in w]
    assert said and "tuflexperf fit BATTERY.yaml" in said[0]
    assert data["ignored_runs"] == [{"file": "runs/edf1_endurance_50.csv", "kind": "endurance",
                                     "engine": "EDF1"}]


def test_a_table_whose_thrust_never_changes_is_refused(tmp_path: Path) -> None:
    """Thrust 5 N at every throttle and airspeed was written as "T = 5 N" (outside audit)."""
    rows = ["engine,throttle,airspeed_m_s,thrust_n"] + [
        f"E,{x},{v},5.0" for x in (0.2, 0.5, 0.8, 1.0) for v in (0.0, 10.0, 20.0, 30.0)]
    table = tmp_path / "const.csv"
    table.write_text("\n".join(rows) + "\n")
    result = runner.invoke(app, ["fit", str(table), "--out", str(tmp_path / "p.yaml")])
    assert result.exit_code == 2 and "neither throttle nor airspeed" in result.stderr
    assert not (tmp_path / "p.yaml").exists()


def test_a_nul_in_a_run_name_and_an_absurd_filter_window_are_bad_input(tmp_path: Path) -> None:
    folder = campaign_copy(tmp_path)
    manifest = folder / "campaign.yaml"
    text = manifest.read_text()
    for edited, key in (
        (text.replace("runs/structure_drag.csv", '"runs/structure_drag.csv\\0"', 1),
         "file: a file name cannot hold a NUL"),  # a traceback (outside audit)
        (text + "filters: {outlier_window_s: 1e308}\n", "filters.outlier_window_s"),
        # ignored unsaid, where the same key on a run is refused (outside audit)
        (text + "thrust_sign: -1\n", "thrust_sign: only for a thrust-stand format"),
    ):
        manifest.write_text(edited)
        result = runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "p.yaml")])
        assert result.exit_code == 2 and key in result.stderr, result.output
        assert result.stderr.count("\n") == 1


def test_a_drag_sweep_of_constant_force_adds_no_drag_and_says_so(tmp_path: Path) -> None:
    import pandas as pd

    folder = campaign_copy(tmp_path)
    run = folder / "runs" / "structure_drag.csv"
    frame = pd.read_csv(run)
    frame["force_n"] = 0.0
    frame.to_csv(run, index=False, compression=FAST)
    result = runner.invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                 str(tmp_path / "p.yaml"), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert any("dead load cell" in w and "structure_drag.csv" in w
               for w in summary["warnings"]), summary["warnings"]


def test_a_force_change_without_a_step_is_said_and_the_filters_own_are_not(
        tmp_path: Path) -> None:
    """The outlier fill's 2 s window reaches a second ahead of each step: the shipped runs
    had 8 "force changes without a throttle step" 0.85-0.94 s before real steps (outside
    audit). Those are gone; a real jump of the balance mid-plateau is still said."""
    import pandas as pd

    clean = runner.invoke(app, ["fit", str(SHIPPED_CAMPAIGN / "campaign.yaml"), "--out",
                                str(tmp_path / "clean.yaml"), "--json"])
    assert not any("without a throttle step" in w
                   for w in json.loads(clean.stdout)["warnings"])
    folder = campaign_copy(tmp_path)
    run = folder / "runs" / "edf1_v30p0.csv.gz"
    frame = pd.read_csv(run)
    frame.loc[frame["time_s"] >= 7.4, "force_n"] += 3.0  # mid-plateau (steps 5.35, 9.4 s)
    frame.to_csv(run, index=False, compression=FAST)
    jumped = runner.invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                 str(tmp_path / "jumped.yaml"), "--json"])
    notes = [w for w in json.loads(jumped.stdout)["warnings"] if "without a throttle step" in w]
    assert any("edf1_v30p0.csv.gz: force changes at 7.4" in w for w in notes), notes


def test_a_small_fan_beside_a_big_one_a_voltage_dropout_and_a_tiny_sweep_are_fitted(
        tmp_path: Path) -> None:
    """Outside review of the fit's new refusals: a fan of 1.5 % the other's thrust was taken
    for a dead load cell and refused; one 0 V logger sample refused its run; a 12-sample
    sine sweep crashed the delay grid."""
    import pandas as pd

    folder = campaign_copy(tmp_path)
    manifest = folder / "campaign.yaml"
    text = manifest.read_text()
    extra = []
    for run in sorted((folder / "runs").glob("edf1_v*.csv.gz")):
        small = pd.read_csv(run)
        small["force_n"] *= 0.015
        name = run.name.replace("edf1", "small")
        small.to_csv(run.with_name(name), index=False, compression=FAST)
        extra.append(f"  - {{file: runs/{name}, engine: SMALL, kind: throttle_steps}}")
    dropout = pd.read_csv(folder / "runs" / "edf1_v15p0.csv.gz")
    dropout.loc[100, "voltage_v"] = 0.0
    dropout.to_csv(folder / "runs" / "edf1_v15p0.csv.gz", index=False, compression=FAST)
    sweep = pd.read_csv(folder / "runs" / "edf2_sweep_v30.csv.gz").head(12)
    sweep.to_csv(folder / "runs" / "tiny_sweep.csv", index=False, compression=FAST)
    extra.append("  - {file: runs/tiny_sweep.csv, engine: EDF2, kind: sine_sweep}")
    head, tail = text.split("runs:\n", 1)
    manifest.write_text(head + "runs:\n" + "\n".join(extra) + "\n" + tail)
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "p.yaml"),
                                 "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    small = next(e for e in summary["engines"] if e["name"] == "SMALL")
    assert small["full_throttle_thrust_n"]["0"] == pytest.approx(0.015 * 54.9, rel=0.03)
    warnings = summary["warnings"]
    assert any("edf1_v15p0.csv.gz" in w and "at or below 0 V taken as missing" in w
               for w in warnings), warnings
    assert any("tiny_sweep.csv" in w and "left out of the delay" in w for w in warnings)
    assert not any("dead load cell" in w for w in warnings)


def test_a_small_fans_noisy_table_is_fitted_with_a_note_not_refused(tmp_path: Path) -> None:
    """R^2 0.89 from a 3 N fan measured with 0.3 N of noise was refused as a wrong sign
    (outside review): between 0.5 and 0.9 the fit is written and the R^2 said."""
    from tuflexperf.reduction.poly22fit import fit_poly22

    grid = [(x, v) for x in (0.4, 0.7, 1.0) for v in (0.0, 15.0, 30.0)]
    for seed in range(200):  # a noise draw whose surface explains 0.5 .. 0.9 of the points
        rng = np.random.default_rng(seed)
        thrust = [0.05 * poly22(x, v, COEFFICIENTS) + rng.normal(0, 0.3) for x, v in grid]
        r2 = fit_poly22(*zip(*grid, strict=True), thrust).r2
        if 0.5 < r2 < 0.9:
            break
    else:
        pytest.fail("no noise draw in range")
    table = tmp_path / "small.csv"
    table.write_text("engine,throttle,airspeed_m_s,thrust_n\n" + "".join(
        f"S,{x},{v},{t!r}\n" for (x, v), t in zip(grid, thrust, strict=True)))
    result = runner.invoke(app, ["fit", str(table), "--out", str(tmp_path / "p.yaml"), "--json"])
    assert result.exit_code == 0, result.output
    assert any("explains only R^2" in w for w in json.loads(result.stdout)["warnings"])


def test_a_discharge_run_stopped_before_the_cut_off_is_bad_input(tmp_path: Path) -> None:
    """A run stopped at 43.6 V of a 40.8 V cut-off was stored as the pack's time to the
    cut-off, silently (outside audit with a known pack)."""
    import pandas as pd

    root = Path(__file__).resolve().parents[1] / "data" / "tuflex"
    shutil.copytree(root / "endurance", tmp_path / "endurance")
    shutil.copy(root / "battery.yaml", tmp_path / "battery.yaml")
    run = tmp_path / "endurance" / "edf1_endurance_50.csv"
    frame = pd.read_csv(run)
    stop = frame["time_s"].iloc[0] + 0.7 * (frame["time_s"].iloc[-1] - frame["time_s"].iloc[0])
    frame = frame[frame["time_s"] <= stop]
    frame.to_csv(run, index=False, compression=FAST)
    result = runner.invoke(app, ["fit", str(tmp_path / "battery.yaml"), "--out",
                                 str(tmp_path / "fitted.yaml")])
    assert result.exit_code == 2, result.output
    assert "edf1_endurance_50.csv" in result.stderr and "short of the cut-off" in result.stderr
    assert result.stderr.count("\n") == 1
    assert not (tmp_path / "fitted.yaml").exists()


def test_a_run_in_another_unit_is_refused_and_deaf_runs_give_no_set_point(
        tmp_path: Path) -> None:
    """One EDF1 run logged in mN made the six good ones look "deaf" (by the largest force of
    all), and the fit took its 11 points at one airspeed alone: a 1.5 MN fan, R^2 1, exit 0
    (outside audit). The run is now refused by name; and runs left out as deaf give no set
    point to the three a surface needs."""
    import pandas as pd

    folder = campaign_copy(tmp_path)
    runs = folder / "runs"
    out = tmp_path / "p.yaml"
    # one run in mN, then four of seven (by a median, the typical run was in mN: a 55 kN fan
    # was written; outside re-audit)
    milli_runs = ["edf1_v15p0", "edf1_v00p0", "edf1_v20p0", "edf1_v22p5"]
    kept = {name: pd.read_csv(runs / f"{name}.csv.gz") for name in milli_runs}
    for count in (1, 4):
        for name in milli_runs[:count]:
            milli = kept[name].copy()
            milli["force_n"] = milli["force_n"] * 1000.0
            milli.to_csv(runs / f"{name}.csv.gz", index=False, compression=FAST)
        result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out",
                                          str(out)])
        assert result.exit_code == 2, result.output
        assert "EDF1: runs/edf1_v" in result.stderr and "mN" in result.stderr, result.stderr
        assert result.stderr.count("\n") == 1 and not out.exists()
    for name, frame in kept.items():
        frame.to_csv(runs / f"{name}.csv.gz", index=False, compression=FAST)
    # five of EDF1's seven step runs on a stuck cell: two set points are left
    for name in ("edf1_v00p0", "edf1_v15p0", "edf1_v20p0", "edf1_v22p5", "edf1_v25p0"):
        stuck = pd.read_csv(runs / f"{name}.csv.gz")
        stuck["force_n"] = 1.0
        stuck.to_csv(runs / f"{name}.csv.gz", index=False, compression=FAST)
    result = CliRunner().invoke(app, ["fit", str(folder / "campaign.yaml"), "--out", str(out)])
    assert result.exit_code == 2, result.output
    assert "EDF1: the throttle-step runs cover only 2 airspeed set point" in result.stderr
    assert not out.exists()


def test_engines_whose_delays_disagree_are_said(tmp_path) -> None:
    """EDF2's sine sweeps logged on a tenth of their time base: the model's one delay_s, the
    engines' mean 0.289 s, fitted neither (0.049 and 0.529 s), unsaid (outside audit)."""
    import gzip

    campaign = tmp_path / "campaign"
    shutil.copytree(Path(__file__).resolve().parent.parent / "data" / "tuflex" / "campaign",
                    campaign)
    for name in ("edf2_sweep_v30", "edf2_sweep_v00"):
        path = campaign / "runs" / f"{name}.csv.gz"
        lines = gzip.open(path, "rt").read().splitlines()
        scaled = [",".join([repr(round(float(row.split(",")[0]) * 10, 4)), *row.split(",")[1:]])
                  for row in lines[1:]]
        with gzip.open(path, "wt", compresslevel=1) as handle:
            handle.write("\n".join([lines[0], *scaled]) + "\n")
    result = runner.invoke(app, ["fit", str(campaign / "campaign.yaml"), "--out",
                                 str(tmp_path / "model.yaml")])
    assert result.exit_code == 0, result.stderr
    assert "the engines disagree on the delay (EDF1 0.049 s, EDF2 0.529 s" in result.stdout
    # the shipped campaign's engines agree: nothing said
    shipped = runner.invoke(app, ["fit", str(Path(__file__).resolve().parent.parent / "data"
                                             / "tuflex" / "campaign" / "campaign.yaml"),
                                  "--out", str(tmp_path / "shipped.yaml")])
    assert shipped.exit_code == 0 and "disagree on the delay" not in shipped.stdout


@pytest.mark.parametrize("flag", [["--delay-s", "0.1"], ["--glauert"], ["--table", "t.csv"]])
def test_a_flag_the_pack_fit_has_no_use_for_is_refused(tmp_path: Path, flag) -> None:
    """`fit battery.yaml --delay-s 0.1` fitted and wrote the pack, the delay silently dropped
    (outside audit); like --table and --glauert it is refused, and nothing is written."""
    shipped = Path(__file__).resolve().parents[1] / "data" / "tuflex"
    shutil.copytree(shipped / "endurance", tmp_path / "endurance")
    shutil.copy(shipped / "battery.yaml", tmp_path / "battery.yaml")
    flag = [str(tmp_path / f) if f == "t.csv" else f for f in flag]
    result = runner.invoke(app, ["fit", str(tmp_path / "battery.yaml"), "--out",
                                 str(tmp_path / "b.yaml"), *flag])
    assert result.exit_code == 2
    assert f"{flag[0]}: not for a battery file" in result.stderr
    assert not (tmp_path / "b.yaml").exists() and not (tmp_path / "t.csv").exists()


def test_a_run_without_a_test_point_counts_as_no_airspeed(tmp_path: Path) -> None:
    """EDF1 at 15 and 30 m/s and a 27.5 m/s run whose clock is in ks (no 0.5 s plateau): the
    empty run counted as a set point at 0 m/s, so the 3-airspeed rule passed and a surface
    with the wrong curvature in airspeed was written (outside audit)."""
    import gzip

    campaign = tmp_path / "campaign"
    shutil.copytree(Path(__file__).resolve().parents[1] / "data" / "tuflex" / "campaign",
                    campaign)
    kept = [line for line in (campaign / "campaign.yaml").read_text().splitlines()
            if not any(s in line for s in ("edf2", "edf1_v00p", "edf1_v20p", "edf1_v22p",
                                           "edf1_v25p"))]
    (campaign / "campaign.yaml").write_text("\n".join(kept) + "\n")
    run = campaign / "runs" / "edf1_v27p5.csv.gz"
    lines = gzip.open(run, "rt").read().splitlines()
    slowed = [lines[0]] + [f"{float(line.split(',', 1)[0]) / 1000},{line.split(',', 1)[1]}"
                           for line in lines[1:]]
    with gzip.open(run, "wt", compresslevel=1) as handle:
        handle.write("\n".join(slowed) + "\n")
    import re

    result = runner.invoke(app, ["fit", str(campaign / "campaign.yaml"), "--out",
                                 str(tmp_path / "p.yaml")])
    assert result.exit_code == 2, result.output
    assert "cover only 2 airspeed set point(s)" in result.stderr
    assert "edf1_v27p5.csv.gz gave no test point" in result.stderr
    assert not re.search(r"\b0 m/s", result.stderr) and not (tmp_path / "p.yaml").exists()


def _two_engine_table(path, speeds_by_engine) -> None:
    """A thrust table of a known quadratic surface, each engine at its own airspeeds."""
    rows = ["engine,throttle,airspeed_m_s,thrust_n"]
    for engine, speeds in speeds_by_engine.items():
        for v in speeds:
            for x in np.arange(0.0, 1.01, 0.1):
                rows.append(f"{engine},{x:.2f},{v},{33.6 * x + 21.5 * x * x - 0.39 * x * v:.6f}")
    path.write_text("\n".join(rows) + "\n")


def test_the_tested_range_is_the_one_every_engine_shares(tmp_path) -> None:
    # EDF1 tested to 20 m/s beside EDF2 to 40: the file said 0-40, so EDF1's model was flown
    # to 40 m/s with no extrapolation said (outside audit)
    table = tmp_path / "table.csv"
    _two_engine_table(table, {"EDF1": [0, 10, 20], "EDF2": [0, 10, 20, 30, 40]})
    out = tmp_path / "fitted.yaml"
    done = runner.invoke(app, ["fit", str(table), "--out", str(out), "--json"])
    assert done.exit_code == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["tested_airspeed_m_s"] == [0.0, 20.0]
    assert load_propulsion(out).tested_airspeed_m_s == (0.0, 20.0)
    assert any("EDF1 0-20 m/s, EDF2 0-40 m/s" in w for w in summary["warnings"])


@pytest.mark.parametrize("second", [[20, 30, 40], [10, 20, 30]])  # apart, or touching at 10
def test_engines_tested_at_no_common_airspeed_are_bad_input(tmp_path, second) -> None:
    table = tmp_path / "table.csv"
    _two_engine_table(table, {"EDF1": [0, 5, 10], "EDF2": second})
    out = tmp_path / "fitted.yaml"
    done = runner.invoke(app, ["fit", str(table), "--out", str(out)])
    assert done.exit_code == 2
    assert "table.csv: the engines were tested at no airspeed range in common" in done.stderr
    assert not out.exists()
