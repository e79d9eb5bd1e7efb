"""Thrust-stand exports (``format: rcbenchmark``): units, sign, ESC pulse, airspeed; end to end.

The equivalence test writes ONE data set twice, independently of :mod:`tuflexperf.io.vendor`:
as the vendor's CSV (thrust in kgf logged negative, ESC pulse in microseconds, an airspeed
column) and in the project's run format (SPEC 4), and requires both fits to give the same
coefficients.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from tuflexperf.cli import app
from tuflexperf.errors import InputError
from tuflexperf.io.campaign import load_campaign
from tuflexperf.io.case import load_propulsion
from tuflexperf.io.runs import read_run

runner = CliRunner()
ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "data" / "samples" / "rcbenchmark" / "campaign.yaml"
KGF_N = 9.80665
TRUTH = {"p00": 0.3, "p10": 4.0, "p01": -0.08, "p20": 25.0, "p11": -0.3, "p02": 0.0006}


def _data(airspeed: float, seed: int) -> dict[str, np.ndarray]:
    """Throttle steps at one tunnel speed, 25 Hz, with noise (no dynamics needed here)."""
    rng = np.random.default_rng(seed)
    throttle = np.repeat([0.0, 0.25, 0.5, 0.75, 1.0, 0.5, 0.0], 75)
    t = np.arange(throttle.size) * 0.04
    c = TRUTH
    v = np.full(t.size, airspeed) + (rng.normal(0, 0.03, t.size) if airspeed else 0.0)
    force = (c["p00"] + c["p10"] * throttle + c["p01"] * v + c["p20"] * throttle**2
             + c["p11"] * throttle * v + c["p02"] * v**2) + rng.normal(0, 0.05, t.size)
    volts = 22.2 - 0.3 * throttle + rng.normal(0, 0.02, t.size)
    amps = 0.5 + 40 * throttle**1.5 + rng.normal(0, 0.1, t.size)
    return {"t": t, "x": throttle, "v": v, "f": force, "u": volts, "i": amps,
            "rpm": 25000 * np.sqrt(throttle)}


def _write_vendor(path: Path, d: dict[str, np.ndarray]) -> None:
    """As the vendor software writes it: kgf, pulled negative, microseconds, text columns."""
    d = {key: value.tolist() for key, value in d.items()}  # Python floats: repr round-trips
    lines = ["Time (s),ESC signal (µs),Servo 1 (µs),Torque (N·m),Thrust (kgf),Voltage (V),"
             "Current (A),Motor Electrical Speed (RPM),Electrical Power (W),App message,"
             "Airspeed (m/s)"]
    for k in range(len(d["t"])):
        pulse = 1000.0 + 1000.0 * d["x"][k]
        lines.append(
            f"{d['t'][k]!r},{pulse!r},1500,0.01,{-d['f'][k] / KGF_N!r},{d['u'][k]!r},"
            f"{d['i'][k]!r},{d['rpm'][k]!r},{d['u'][k] * d['i'][k]!r},,{d['v'][k]!r}"
        )
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _write_run(path: Path, d: dict[str, np.ndarray]) -> None:
    d = {key: value.tolist() for key, value in d.items()}
    lines = ["time_s,force_n,airspeed_m_s,throttle,voltage_v,current_a"]
    for k in range(len(d["t"])):
        lines.append(f"{d['t'][k]!r},{d['f'][k]!r},{d['v'][k]!r},{d['x'][k]!r},"
                     f"{d['u'][k]!r},{d['i'][k]!r}")
    path.write_text("\n".join(lines) + "\n")


def _manifest(folder: Path, runs: list[dict], **top: object) -> Path:
    doc = {"name": "stand", "fan_area_m2": 0.005, "tunnel_area_m2": 0.25,
           "air_density_kg_m3": 1.2, **top, "runs": runs}
    path = folder / "campaign.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False, allow_unicode=True))
    return path


def _fit(manifest: Path, out: Path) -> dict:
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_vendor_csv_fits_to_the_same_coefficients_as_our_run_format(tmp_path: Path) -> None:
    vendor_dir, run_dir = tmp_path / "vendor", tmp_path / "run"
    vendor_dir.mkdir()
    run_dir.mkdir()
    vendor_runs, own_runs = [], []
    for seed, v in enumerate((0.0, 8.0, 16.0, 24.0)):
        d = _data(v, seed)
        _write_vendor(vendor_dir / f"v{seed}.csv", d)
        _write_run(run_dir / f"v{seed}.csv", d)
        vendor_runs.append({"file": f"v{seed}.csv", "engine": "E", "kind": "throttle_steps"})
        own_runs.append({"file": f"v{seed}.csv", "engine": "E", "kind": "throttle_steps"})
    vendor = _fit(_manifest(vendor_dir, vendor_runs, format="rcbenchmark",
                            esc_pulse_us=[1000, 2000], thrust_sign=-1), tmp_path / "a.yaml")
    own = _fit(_manifest(run_dir, own_runs), tmp_path / "b.yaml")
    a, b = vendor["engines"][0]["coefficients"], own["engines"][0]["coefficients"]
    for term in TRUTH:
        assert a[term] == pytest.approx(b[term], rel=1e-9, abs=1e-12), term
        # and the fit is the truth to the noise (so the sign and units were right)
        assert a[term] == pytest.approx(TRUTH[term], rel=0.05, abs=0.01), term
    assert load_propulsion(tmp_path / "a.yaml").engines[0].coefficients["p20"] == pytest.approx(
        b["p20"], rel=1e-9)


@pytest.mark.parametrize(("unit", "factor"), [("N", 1.0), ("kgf", KGF_N), ("gf", KGF_N / 1000),
                                              ("lbf", 4.4482216152605)])
def test_thrust_units_sign_pulse_and_manifest_airspeed(tmp_path: Path, unit: str,
                                                       factor: float) -> None:
    rows = [f"Time (s),ESC signal (us),Thrust ({unit}),Voltage (V)"]
    for k in range(20):
        rows.append(f"{0.1 * k},{1100 + 40 * k},{-2.0 * k / factor!r},16.0")
    (tmp_path / "r.csv").write_text("\n".join(rows) + "\n")
    manifest = _manifest(tmp_path, [{"file": "r.csv", "engine": "E", "kind": "throttle_steps",
                                     "format": "rcbenchmark", "esc_pulse_us": [1100, 1900],
                                     "thrust_sign": -1, "airspeed_m_s": 12.5}])
    run = load_campaign(manifest).runs[0]
    data = read_run(run.path, vendor=run.vendor)
    k = np.arange(20)
    np.testing.assert_allclose(data["force_n"], 2.0 * k, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(data["throttle"], (40 * k) / 800, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(data["airspeed_m_s"], 12.5)
    np.testing.assert_allclose(data["voltage_v"], 16.0)


def test_wrong_thrust_sign_is_refused_not_fitted(tmp_path: Path) -> None:
    """The shipped sample logs pull as negative; with thrust_sign: 1 the fit would be upside
    down, so reading refuses and names the key to change."""
    manifest = _manifest(tmp_path, [{"file": str(SAMPLE.parent / "stand_v10.csv"), "engine": "E",
                                     "kind": "throttle_steps"}], format="rcbenchmark",
                         thrust_sign=1)
    result = runner.invoke(app, ["fit", str(manifest), "--out", str(tmp_path / "o.yaml")])
    assert result.exit_code == 2
    assert "set thrust_sign: -1" in result.stderr and "stand_v10.csv" in result.stderr
    assert not (tmp_path / "o.yaml").exists()


def _read_vendor_rows(folder: Path, rows: list[str]) -> dict[str, np.ndarray]:
    """One RCbenchmark CSV of ``rows`` in a manifest of its own, read as fit reads it."""
    (folder / "r.csv").write_text("\n".join(rows) + "\n")
    manifest = _manifest(folder, [{"file": "r.csv", "engine": "E", "kind": "throttle_steps"}],
                         format="rcbenchmark")
    run = load_campaign(manifest).runs[0]
    return read_run(run.path, vendor=run.vendor)


def test_one_thrust_logged_in_two_units_is_read_once(tmp_path: Path) -> None:
    rows = ["Time (s),ESC signal (µs),Thrust (kgf),Thrust (N),Airspeed (m/s)"]
    rows += [f"{0.1 * k},1500,{0.1 * k:.4f},{0.1 * k * KGF_N:.4f},3" for k in range(12)]
    force = _read_vendor_rows(tmp_path, rows)["force_n"]
    np.testing.assert_allclose(force, 0.1 * np.arange(12) * KGF_N, rtol=1e-3)


def test_airspeed_column_units(tmp_path: Path) -> None:
    rows = ["Time (s),ESC signal (µs),Thrust (N),Airspeed (km/h)"]
    rows += [f"{0.1 * k},1500,1.0,36" for k in range(12)]
    np.testing.assert_allclose(_read_vendor_rows(tmp_path, rows)["airspeed_m_s"], 10.0)


@pytest.mark.parametrize(
    ("header", "row", "entry", "message"),
    [
        ("Time (s),ESC signal (µs),Thrust (kgf)", "{t},1500,0.1", {},
         "no airspeed column"),
        ("Time (s),ESC signal (µs),Airspeed (m/s)", "{t},1500,3", {}, "missing column 'Thrust"),
        ("Time (s),Thrust (kgf),Airspeed (m/s)", "{t},0.1,3", {}, "missing column 'ESC signal"),
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s)", "{t},2500,0.1,3", {},
         r"outside esc_pulse_us \[1000, 2000\]"),
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (furlong/s)", "{t},1500,0.1,3", {},
         "unknown airspeed unit"),
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s)", "{t},1500,abc,3", {},
         "non-numeric value"),
        # the second thrust column was dropped and the first fitted, unremarked
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s),Thrust (kgf)",
         "{t},1500,0.1,3,0.2", {}, r"'Thrust \(kgf\)' appears more than once"),
        # the manifest's tunnel speed against the run's own column: it was dropped unsaid
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s)", "{t},1500,0.1,20",
         {"airspeed_m_s": 25}, r"gives 20 m/s \(median\), the manifest's airspeed_m_s 25 m/s"),
        # one thrust in kgf, another in N that says something else: which is the thrust?
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s),Thrust (N)",
         "{t},1500,0.1,3,0.2", {}, r"'Thrust \(kgf\)' and 'Thrust \(N\)' both give the "
         r"thrust and they disagree \(by up to 0.781 in SI units\)"),  # it said "inf"
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s),Thrust (N)",
         "{t},1500,0.1,3,", {}, r"'Thrust \(kgf\)' and 'Thrust \(N\)' both give the "
         r"thrust and one is empty where the other is not"),
        ("Time (s),ESC signal (µs),Thrust (kgf),Airspeed (m/s),Airspeed (km/h)",
         "{t},1500,0.1,3,36", {}, r"'Airspeed \(m/s\)' and 'Airspeed \(km/h\)' both give"),
    ],
)
def test_bad_vendor_files_name_file_and_column(tmp_path: Path, header: str, row: str,
                                               entry: dict, message: str) -> None:
    rows = [header] + [row.format(t=0.1 * k) for k in range(12)]
    (tmp_path / "r.csv").write_text("\n".join(rows) + "\n")
    manifest = _manifest(tmp_path, [{"file": "r.csv", "engine": "E", "kind": "throttle_steps",
                                     **entry}], format="rcbenchmark")
    run = load_campaign(manifest).runs[0]
    with pytest.raises(InputError, match=message) as info:
        read_run(run.path, vendor=run.vendor)
    assert "r.csv" in str(info.value)


def test_manifest_keys_are_validated(tmp_path: Path) -> None:
    (tmp_path / "r.csv").write_text("time_s\n")
    entry = {"file": "r.csv", "engine": "E", "kind": "throttle_steps"}
    bad = [
        ({"format": "rcbench"}, "format"),
        ({"format": "rcbenchmark", "esc_pulse_us": [2000, 1000]}, "esc_pulse_us"),
        ({"format": "rcbenchmark", "thrust_sign": 2}, "thrust_sign"),
        ({"esc_pulse_us": [1000, 2000]}, "only for a thrust-stand format"),
    ]
    for extra, key in bad:
        manifest = _manifest(tmp_path, [{**entry, **extra}])
        with pytest.raises(InputError, match=key):
            load_campaign(manifest)
    result = runner.invoke(app, ["fit", str(_manifest(tmp_path, [{**entry, "format": "x"}]))])
    assert result.exit_code == 2 and "format" in result.stderr


def test_shipped_sample_fit_then_check(tmp_path: Path) -> None:
    """The shipped sample end to end: fit it, fly the fitted model in a small case, check."""
    summary = _fit(SAMPLE, tmp_path / "propulsion.yaml")
    c = summary["engines"][0]["coefficients"]
    truth = {"p00": 0.1, "p10": 2.0, "p01": -0.05, "p20": 11.0, "p11": -0.12, "p02": 0.0003}
    for term, value in truth.items():  # scripts/make_rcbenchmark_sample.py's thrust law
        assert c[term] == pytest.approx(value, rel=0.1, abs=0.01), term
    aircraft = {"name": "Small EDF jet", "mass_kg": 1.2, "wing_area_m2": 0.25, "cd0": 0.03,
                "k": 0.05, "cl_max": 1.3, "takeoff": {"cl_ground": 0.4, "rolling_friction": 0.04}}
    (tmp_path / "aircraft.yaml").write_text(yaml.safe_dump(aircraft))
    case = {"name": "sample", "aircraft": "aircraft.yaml", "propulsion": "propulsion.yaml",
            "requirements": {"takeoff": {"max_ground_roll_m": 30},
                             "envelope": {"min_airspeed_m_s": 12, "max_airspeed_m_s": 18}}}
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(case))
    result = runner.invoke(app, ["check", str(tmp_path / "case.yaml"), "--json"])
    assert result.exit_code == 0, result.output
    verdict = json.loads(result.stdout)
    assert verdict["passed"] is True
    assert {r["name"] for r in verdict["results"]} >= {"takeoff", "envelope"} or len(
        verdict["results"]) >= 2
    assert all(math.isfinite(r["value"]) for r in verdict["results"])
