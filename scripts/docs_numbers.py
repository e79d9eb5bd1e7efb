"""Regenerate every number table in docs/ from the tool's own runs.

Each table sits between ``<!-- begin:NAME -->`` and ``<!-- end:NAME -->`` in a docs file and
is replaced whole. Tables without timings come from the tool's JSON output on the shipped case
and campaign (``tests/test_docs_numbers.py`` holds the docs to them); timing blocks are the
verbatim output of the ``bench/`` scripts, on this machine, with the date.

Usage::

    python scripts/docs_numbers.py              # rewrite the non-timing tables
    python scripts/docs_numbers.py --check      # exit 1 if a non-timing table is stale
    python scripts/docs_numbers.py --bench bench_core bench_mission   # rerun these benches
    python scripts/docs_numbers.py --bench all  # every bench (several minutes)
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
CAMPAIGN = ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml"
BENCHES = ("bench_backend", "bench_core", "bench_endurance", "bench_export", "bench_fit", "bench_flightlog",
           "bench_mission", "bench_mission_samples", "bench_performance", "bench_report",
           "bench_uncertainty")

# the paper's published values (Testing and modelling of a ducted fan motor for UAV
# applications, section 4 and Table 1)
PAPER_THRUST_N = {("EDF1", 0.0): 55.12, ("EDF1", 30.0): 40.02, ("EDF1", 40.0): 35.26,
                  ("EDF2", 0.0): 55.41, ("EDF2", 30.0): 41.76, ("EDF2", 40.0): 37.76}


def _json(argv: list[str]) -> dict[str, Any]:
    """One command's ``--json`` object, run in this process."""
    from typer.testing import CliRunner

    from tuflexperf.cli import app

    result = CliRunner().invoke(app, [*argv, "--json"])
    if result.exit_code not in (0, 1):
        raise RuntimeError(f"tuflexperf {' '.join(argv)}: exit {result.exit_code}: "
                           f"{result.output}")
    return json.loads(result.stdout)


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def paper_table() -> str:
    """The paper's published values beside the tool's on the shipped case."""
    from tuflexperf.io.case import load_case, shipped_case_path
    from tuflexperf.models.thrust import poly22

    case = load_case(shipped_case_path())
    rows = []
    for engine in case.propulsion.engines:
        for airspeed in (0.0, 30.0, 40.0):
            paper = PAPER_THRUST_N[(engine.name, airspeed)]
            tool = float(poly22(1.0, airspeed, engine.coefficients))
            note = " (extrapolated)" if airspeed > 30.0 else ""
            rows.append([f"{engine.name} thrust at full throttle, {airspeed:g} m/s{note}",
                         f"{paper:.2f} N", f"{tool:.2f} N", f"{tool - paper:+.2f} N"])
    takeoff = _json(["takeoff"])
    trim, oei = _json(["trim"]), _json(["oei"])
    endurance = _json(["endurance", "--throttle", "0.5"])
    # the measured-power reading (battery.yaml fit.power_correction) flown alike
    from tuflexperf.analysis.power_reading import measured_power_readings
    from tuflexperf.analysis.study import Study

    (reading,) = measured_power_readings(case)
    measured = Study(reading.case).endurance(0.5).flight_endurance_min
    rows += [
        ["take-off ground roll", "55.5 m", f"{takeoff['ground_roll_m']:.2f} m",
         f"{takeoff['ground_roll_m'] - 55.5:+.2f} m"],
        ["least trim throttle, 15-45 m/s", "0.41", f"{trim['min_throttle']:.3f}",
         f"{trim['min_throttle'] - 0.41:+.3f}"],
        ["least one-engine throttle", "0.56", f"{oei['min_throttle']:.3f}",
         f"{oei['min_throttle'] - 0.56:+.3f}"],
        [f"one pack at throttle 0.5 (tool: level flight at {endurance['airspeed_m_s']:.1f} m/s)",
         "nearly 10 min", f"{endurance['battery_endurance_min']:.2f} min",
         f"{endurance['battery_endurance_min'] - 10.0:+.2f} min"],
        ["flight at throttle 0.5, two packs per fan", "about 15 min",
         f"{endurance['flight_endurance_min']:.2f} min",
         f"{endurance['flight_endurance_min'] - 15.0:+.2f} min"],
        ["the same flight on the discharge runs' measured power", "about 15 min",
         f"{measured:.2f} min", f"{measured - 15.0:+.2f} min"],
    ]
    return _table(["quantity", "paper", "tool, shipped case", "tool - paper"], rows)


def campaign_table() -> str:
    """``fit`` on the shipped synthetic campaign against the campaign's ground truth."""
    from tuflexperf.io.case import load_propulsion
    from tuflexperf.models.thrust import poly22
    from tuflexperf.reduction.pipeline import run_fit

    truth = yaml.safe_load((CAMPAIGN.parent / "truth.yaml").read_text(encoding="utf-8"))
    with tempfile.TemporaryDirectory() as folder:
        summary = run_fit(CAMPAIGN, Path(folder) / "fitted.yaml")
        fitted = load_propulsion(Path(summary["out"]))
    # the truth's thrust holds at its own pack voltage; the fit's at the one it found
    scale = (fitted.reference_voltage_v / truth["reference_voltage_v"]) ** truth[
        "voltage_exponent"] if fitted.reference_voltage_v else 1.0
    rows = []
    for engine, true_engine in zip(fitted.engines, truth["engines"], strict=True):
        for airspeed in (0.0, 30.0):
            tool = float(poly22(1.0, airspeed, engine.coefficients))
            true = float(poly22(1.0, airspeed, true_engine["coefficients"])) * scale
            rows.append([f"{engine.name} thrust at full throttle, {airspeed:g} m/s",
                         f"{true:.2f} N", f"{tool:.2f} N", f"{tool - true:+.3f} N"])
    rows.append(["dead time", f"{truth['delay_s']:.3f} s", f"{fitted.delay_s:.3f} s",
                 f"{(fitted.delay_s - truth['delay_s']) * 1e3:+.1f} ms"])
    rows.append(["spool lag", f"{truth['spool_lag_s']:.3f} s", f"{fitted.lag_s:.3f} s",
                 f"{(fitted.lag_s - truth['spool_lag_s']) * 1e3:+.1f} ms"])
    rows.append(["voltage exponent", f"{truth['voltage_exponent']:.2f}",
                 f"{fitted.voltage_exponent:.3f}",
                 f"{fitted.voltage_exponent - truth['voltage_exponent']:+.3f}"])
    return _table(["quantity", "truth", "fitted", "fitted - truth"], rows)


CALIBRATION = DOCS / "calibration_study.json"
REQUIREMENT_LABELS = {"takeoff_ground_roll": "ground roll", "trim_throttle_max": "trim throttle",
                      "oei_min_throttle": "OEI throttle", "flight_endurance": "endurance",
                      "mission_landing_charge": "mission landing charge"}


def _study() -> dict[str, Any]:
    """The self-calibration study's stored result (bench/calibration_study.py writes it: the
    study takes minutes a truth, so it is run by hand and its JSON kept here)."""
    return json.loads(CALIBRATION.read_text(encoding="utf-8"))


def _rig_label(study: dict[str, Any], rig: str) -> str:
    declared = study["rigs"][rig]
    # "generator:rig": truths of another thrust-law family than the study's first
    generator, _, name = rig.rpartition(":")
    law = f", {generator} thrust law" if generator else ""
    if not any(declared.values()):
        return f"{name} (no systematic error{law})"
    return (f"{name} (airspeed bias sd {declared['airspeed_bias_sd_m_s']:g} m/s, thrust scale "
            f"sd {100 * declared['thrust_scale_sd']:g} %{law})")


def calibration_table() -> str:
    """Per rig and requirement: coverage of p05-p95 with its 95 % CI, RMS z and bias."""
    study = _study()
    rows = []
    for rig, summary in study["summary"].items():
        for name, r in summary["requirements"].items():
            low, high = r["coverage_ci"]
            met = (low <= 0.90 <= high) and 0.8 <= r["rms_z"] <= 1.25
            rows.append([_rig_label(study, rig), REQUIREMENT_LABELS.get(name, name),
                         f"{r['n']}", f"{r['coverage']:.2f} ({low:.2f}-{high:.2f})",
                         f"{r['above_p95']} / {r['below_p05']}", f"{r['rms_z']:.2f}",
                         f"{r['bias_z']:+.2f}", "yes" if met else "**no**"])
    return _table(["rig", "requirement", "truths", "coverage of p05-p95 (95 % CI)",
                   "above p95 / below p05", "RMS z", "bias (mean z)", "target met"], rows)


def reliability_table() -> str:
    """Per rig, the 5-bin reliability diagram of P(meet) as a table with a bar."""
    study = _study()
    rows = []
    for rig, summary in study["summary"].items():
        for b in summary["reliability"]:
            if not b["n"]:
                rows.append([_rig_label(study, rig), f"{b['low']:.1f}-{b['high']:.1f}", "0",
                             "—", "—", ""])
                continue
            low, high = b["met_ci"]
            bar = "#" * round(20 * b["met_fraction"])
            rows.append([_rig_label(study, rig), f"{b['low']:.1f}-{b['high']:.1f}",
                         f"{b['n']}", f"{b['mean_probability']:.2f}",
                         f"{b['met_fraction']:.2f} ({low:.2f}-{high:.2f})", f"`{bar:<20}`"])
    return _table(["rig", "P(meet) bin", "forecasts", "mean P(meet)",
                   "fraction met (95 % CI)", "met, as a bar"], rows)


def diagnosis_table() -> str:
    """The clean rig's thrust error at each requirement's operating point against the
    model-form sd the samples draw there, both in the lack of fit's RMS."""
    found = _study()["diagnosis"]
    rows = []
    for name, (x, v) in found["points"].items():
        true, model = found["true_error_rms"][name], found["model_sd"][name]
        rows.append([name, f"{x:g}", f"{v:g}", f"{true:.2f}", f"{found['true_error_mean'][name]:+.2f}",
                     f"{model:.2f}", f"{model / true:.1f}"])
    names = list(found["points"])
    i, j = names.index("mission cruise"), names.index("OEI and loiter")
    rows.append([f"correlation, {names[i]} and {names[j]}", "", "",
                 f"{found['true_correlation'][i][j]:+.2f}", "",
                 f"{found['model_correlation'][i][j]:+.2f}", ""])
    return _table(["operating point", "throttle", "airspeed [m/s]", "true error, RMS",
                   "true error, mean", "model-form sd", "sd / true"], rows)


TABLES: dict[str, Callable[[], str]] = {"paper": paper_table, "campaign": campaign_table,
                                        "calibration": calibration_table,
                                        "calibration-reliability": reliability_table,
                                        "calibration-diagnosis": diagnosis_table}


def bench_block(name: str) -> str:
    """One bench script's output, verbatim, with the date and machine it ran on."""
    script = ROOT / "bench" / f"{name}.py"
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                            cwd=ROOT, check=False)
    if result.returncode != 0:
        raise RuntimeError(f"{script} failed (exit {result.returncode}):\n{result.stderr}")
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    where = f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    return (f"`python bench/{name}.py`, {stamp}, {where}:\n\n```text\n"
            f"{result.stdout.rstrip()}\n```")


_BLOCK = r"<!-- begin:{name} -->\n.*?<!-- end:{name} -->"


def blocks(text: str) -> dict[str, str]:
    """Every ``<!-- begin:NAME -->`` block of a docs text: NAME -> its body."""
    pattern = re.compile(r"<!-- begin:([\w:-]+) -->\n(.*?)<!-- end:\1 -->", re.S)
    return {match.group(1): match.group(2).rstrip("\n") for match in pattern.finditer(text)}


def replace(text: str, name: str, body: str) -> str:
    pattern = re.compile(_BLOCK.format(name=re.escape(name)), re.S)
    if not pattern.search(text):
        raise KeyError(name)
    return pattern.sub(lambda m: f"<!-- begin:{name} -->\n{body}\n<!-- end:{name} -->", text)


def _docs_with(name: str) -> list[Path]:
    return [path for path in sorted(DOCS.glob("*.md"))
            if f"<!-- begin:{name} -->" in path.read_text(encoding="utf-8")]


def _write(path: Path, text: str) -> None:
    staging = path.with_name(f".{path.name}.tmp")
    staging.write_text(text, encoding="utf-8")
    os.replace(staging, path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if a table is stale")
    parser.add_argument("--bench", nargs="*", default=None, help="bench names, or 'all'")
    args = parser.parse_args(argv)
    if args.bench is not None:
        names = BENCHES if args.bench in ([], ["all"]) else tuple(args.bench)
        makers = {f"bench:{name}": (lambda name=name: bench_block(name)) for name in names}
    else:
        makers = dict(TABLES)
    stale = []
    for name, make in makers.items():  # each written as soon as it is made
        paths = _docs_with(name)
        if not paths:
            print(f"no docs file holds <!-- begin:{name} -->", file=sys.stderr)
            return 2
        body = make()
        for path in paths:
            text = path.read_text(encoding="utf-8")
            if blocks(text).get(name) == body:
                continue
            stale.append(f"{path.relative_to(ROOT)}: {name}")
            if not args.check:
                _write(path, replace(text, name, body))
    for line in stale:
        print(("stale: " if args.check else "updated: ") + line)
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
