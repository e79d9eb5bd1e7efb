"""Self-calibration study (issue 44): do ``check --samples``' bands hold known truths?

For each truth: a thrust law per fan and a rig are drawn, a synthetic campaign is generated
from them by the project's own generator (``scripts/generate_campaign.py``, its physics and
rig noise, with the thrust law and the rig's systematic errors replaced), fitted by
``tuflexperf fit``, and checked by the sampler ``check --samples`` runs
(:func:`tuflexperf.analysis.uncertainty.run_samples`, in this process). The truth of each
requirement is the tool's own deterministic ``check`` on the TRUE thrust law.

Thrust laws: the generator's shipped poly22 per fan with each coefficient off by N(0, 4 %),
plus terms no poly22 holds: ``c3 x^3 + c5 x^2 (v / 30) + c6 x (v / 30)^3`` [N], ``c3`` ~
U(-4, 4), ``c5`` ~ U(-3, 3), ``c6`` ~ N(-1, 1) (a family of fans whose thrust falls faster
at speed, one sign for most). The deterministic check takes poly22 only: for each
requirement the true law is replaced by its least-squares poly22 over the requirement's own
operating region (:data:`REGIONS`, the whole domain joining at a small weight), and that
surrogate's largest error in the region is recorded.

Rigs: ``clean`` (no systematic error; ``rig_uncertainty`` declares zeros) and ``biased``
(an airspeed bias ~ N(0, 0.3 m/s) and a thrust scale ~ N(0, 2 %) per campaign, declared as
``airspeed_bias_sd_m_s: 0.3, thrust_scale_sd: 0.02``). The aircraft, battery and power
surfaces are the same in truth and estimate (only the thrust model is uncertain), so the
power-model and battery-fit sources are off in the study's case.

Per requirement (ground roll, trim, OEI, endurance, the test-flight mission's landing
charge): coverage of p05-p95 with its Clopper-Pearson 95 % interval, RMS z and mean z
(:mod:`tuflexperf.analysis.calibration`); P(meet) at five limits per truth set about the
sampled median (p50 + u (p95 - p05) / 3.29, u = -1.65, -0.75, 0, 0.75, 1.65) against
whether the truth met them: the 5-bin reliability diagram.

Run: ``python bench/calibration_study.py [--truths 40] [--samples 4000] [--out FILE]
[--cache DIR]``. ``--cache`` keeps each truth's fit and true values outside the
repository, so a second run with another error model samples only; ``--resume`` goes on
where a stopped run left ``--out``; ``--merge`` joins result files (e.g. one per rig, run
side by side) and, with ``--cache``, adds the clean rig's :func:`diagnose` table;
``--diagnose`` prints it alone. The result JSON (default ``docs/calibration_study.json``) is
what ``scripts/docs_numbers.py`` renders into docs/validation.md.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tuflexperf.analysis.calibration import coverage, probability_met, reliability  # noqa: E402
from tuflexperf.models.thrust import POLY22_TERMS  # noqa: E402

SEED = 44
DEFAULT_OUT = ROOT / "docs" / "calibration_study.json"
RIGS: dict[str, dict[str, float]] = {
    "clean": {"airspeed_bias_sd_m_s": 0.0, "thrust_scale_sd": 0.0, "balance_zero_sd_n": 0.0,
              "voltage_sd_v": 0.0},
    "biased": {"airspeed_bias_sd_m_s": 0.3, "thrust_scale_sd": 0.02, "balance_zero_sd_n": 0.0,
               "voltage_sd_v": 0.0},
}
LIMIT_OFFSETS = (-1.65, -0.75, 0.0, 0.75, 1.65)
ANCHOR_WEIGHT = 1e-3  # per point of the whole domain in a truth's surrogate, against 1 inside
TRUTH_VERSION = 2  # of the true values kept in a cache (1: surrogates without the anchor)
ENVELOPE_TOP_M_S = 40.0  # beyond the tested 30 m/s (extrapolated), within what the fans fly
# each requirement's operating region: boxes of (throttle, airspeed [m/s]) the surrogate fits
# (a dead engine windmills at throttle 0; the mission's phases: the roll and climb at full
# throttle, the cruise, the one-engine loiter and the descents at throttle 0.1)
REGIONS: dict[str, list[tuple[tuple[float, float], tuple[float, float]]]] = {
    "takeoff_ground_roll": [((0.95, 1.0), (0.0, 20.0))],
    "trim_throttle_max": [((0.75, 1.0), (ENVELOPE_TOP_M_S - 6.0, ENVELOPE_TOP_M_S))],
    "oei_min_throttle": [((0.5, 0.75), (15.0, 22.0)), ((0.0, 0.0), (15.0, 22.0))],
    "flight_endurance": [((0.45, 0.55), (22.0, 34.0)), ((0.95, 1.0), (0.0, 25.0))],
    "mission_landing_charge": [((0.95, 1.0), (0.0, 22.0)), ((0.3, 0.7), (18.0, 28.0)),
                               ((0.0, 0.15), (15.0, 22.0))],
}
KINDS = {"takeoff_ground_roll": "max", "trim_throttle_max": "max", "oei_min_throttle": "max",
         "flight_endurance": "min", "mission_landing_charge": "min"}


def _generator() -> Any:
    spec = importlib.util.spec_from_file_location("generate_campaign",
                                                  ROOT / "scripts" / "generate_campaign.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


GEN = _generator()
BASE_POLY22 = GEN.poly22


def true_thrust(x: Any, v: Any, c: dict[str, float]) -> Any:
    """The truth's thrust [N] at throttle ``x`` [-] and airspeed ``v`` [m/s]."""
    s = np.asarray(v, dtype=float) / 30.0
    return (BASE_POLY22(x, v, c) + c["c3"] * x ** 3 + c["c5"] * x * x * s
            + c["c6"] * x * s ** 3)


def draw_truth(rng: np.random.Generator) -> dict[str, dict[str, float]]:
    """Per fan: the shipped poly22 off by N(0, 4 %) per coefficient, and the extra terms."""
    laws = {}
    for engine, base in GEN.BASE_COEFFICIENTS.items():
        law = {t: float(base[t] * (1.0 + rng.normal(0.0, 0.04))) for t in POLY22_TERMS}
        law.update(c3=float(rng.uniform(-4, 4)), c5=float(rng.uniform(-3, 3)),
                   c6=float(rng.normal(-1.0, 1.0)))
        laws[engine] = law
    return laws


def generate(folder: Path, laws: dict[str, dict[str, float]], bias_m_s: float, scale: float,
             seed: int) -> Path:
    """The campaign of ``laws`` on a rig whose tunnel reads ``bias_m_s`` high and whose
    balance reads ``1 + scale`` times the force."""
    if folder.resolve().is_relative_to(ROOT):
        raise ValueError(f"{folder}: a study's campaign is written outside the repository")
    quantise = GEN.quantise

    def on_the_rig(columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        columns = dict(columns)
        columns["force_n"] = columns["force_n"] * (1.0 + scale)
        columns["airspeed_m_s"] = columns["airspeed_m_s"] + bias_m_s
        return quantise(columns)

    saved = (GEN.OUT, GEN.SEED, GEN.poly22, GEN.truth_coefficients, GEN.quantise)
    GEN.OUT, GEN.SEED, GEN.poly22 = folder, seed, true_thrust
    GEN.truth_coefficients, GEN.quantise = (lambda: laws), on_the_rig
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            # the folder and seed given, never the defaults: those write the shipped campaign
            GEN.main(out=folder, seed=seed)
    finally:
        GEN.OUT, GEN.SEED, GEN.poly22, GEN.truth_coefficients, GEN.quantise = saved
    return folder / "campaign.yaml"


def fit(campaign: Path, out: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "tuflexperf", "fit", str(campaign), "--out",
                           str(out)], capture_output=True, text=True, env=env, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"fit failed: {done.stdout[-500:]} {done.stderr[-500:]}")


def study_propulsion(fitted: Path, rig: dict[str, float]) -> dict[str, Any]:
    """The fitted file at the truth's reference voltage (its voltage law dropped: the study
    flies no sagging packs, as the shipped case) with the rig's declared errors."""
    doc = yaml.safe_load(fitted.read_text(encoding="utf-8"))
    u_fit = doc.pop("reference_voltage_v", None)
    exponent = doc.pop("voltage_exponent", 2.0)
    factor = (GEN.REFERENCE_VOLTAGE_V / u_fit) ** exponent if u_fit else 1.0
    for engine in doc["engines"]:
        engine["coefficients"] = {t: v * factor for t, v in engine["coefficients"].items()}
        if engine.get("covariance") is not None:
            engine["covariance"] = [[c * factor * factor for c in row]
                                    for row in engine["covariance"]]
        for key in ("residual_sd_n", "extrapolation_sd_n", "extrapolation_worst_n", "rmse_n"):
            if engine.get(key) is not None:
                engine[key] = engine[key] * factor
        engine.pop("standard_errors", None)
    doc["rig_uncertainty"] = dict(rig)
    return doc


def surrogate(law: dict[str, float], boxes: list[Any]) -> tuple[dict[str, float], float]:
    """The least-squares poly22 of ``law`` over ``boxes`` and its largest error there [N].

    The whole flown domain (throttle 0-1, 0 to the envelope's top) joins the fit at
    :data:`ANCHOR_WEIGHT`: a surface fitted to one corner alone may turn absurd elsewhere
    (a figure of merit above 1 at low throttle) and the tool then refuses the whole case,
    leaving the truth unknown.
    """
    xs, vs, ws = [], [], []
    for (x0, x1), (v0, v1) in boxes:
        x, v = np.meshgrid(np.linspace(x0, x1, 21), np.linspace(v0, v1, 21))
        xs.append(x.ravel())
        vs.append(v.ravel())
        ws.append(np.ones(x.size))
    inside = sum(w.size for w in ws)
    x, v = np.meshgrid(np.linspace(0.0, 1.0, 11), np.linspace(0.0, ENVELOPE_TOP_M_S, 11))
    xs.append(x.ravel())
    vs.append(v.ravel())
    ws.append(np.full(x.size, ANCHOR_WEIGHT))
    x, v, w = np.concatenate(xs), np.concatenate(vs), np.sqrt(np.concatenate(ws))
    design = np.stack([x ** 0, x, v, x * x, x * v, v * v], axis=1)
    target = true_thrust(x, v, law)
    coefficients = np.linalg.lstsq(design * w[:, None], target * w, rcond=None)[0]
    error = float(np.max(np.abs(design[:inside] @ coefficients - target[:inside])))
    return dict(zip(POLY22_TERMS, (float(c) for c in coefficients), strict=True)), error


def study_battery(folder: Path) -> Path:
    """The shipped battery without its measured power correction: in the study the power
    surfaces are the truth's own (only the thrust is uncertain), so the discharge runs' 25 %
    disagreement with them is no evidence here and its reading would only shift the bands."""
    data = ROOT / "data" / "tuflex"
    doc = yaml.safe_load((data / "battery.yaml").read_text(encoding="utf-8"))
    doc["fit"].pop("power_correction", None)
    for run in doc.get("runs", []):
        run["file"] = str(data / run["file"])
    for run in doc["fit"].get("runs", []):
        run["file"] = str(data / run["file"])
    path = folder / "battery.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def write_case(folder: Path, propulsion: Path, samples: int, seed: int) -> Path:
    data = ROOT / "data" / "tuflex"
    battery = folder / "battery.yaml"
    case = {
        "name": "calibration study",
        "aircraft": str(data / "aircraft.yaml"),
        "propulsion": str(propulsion),
        "battery": str(battery if battery.exists() else study_battery(folder)),
        "atmosphere": {"altitude_m": 0, "temperature_offset_k": 0},
        "requirements": {
            "takeoff": {"max_ground_roll_m": 60},
            "envelope": {"min_airspeed_m_s": 15, "max_airspeed_m_s": ENVELOPE_TOP_M_S,
                         "max_trim_throttle": 1.0},
            "oei": {"dead_engine": "windmilling", "max_throttle": 1.0},
            "endurance": {"throttle": 0.5, "min_flight_time_min": 15},
            "mission": {"file": str(data / "missions" / "test_flight.yaml"),
                        "min_landing_charge_fraction": 0.2},
        },
        "uncertainty": {"samples": samples, "seed": seed,
                        "propulsion": {"power_model": False, "battery_fit": False}},
    }
    path = folder / f"case_{propulsion.stem}.yaml"
    path.write_text(yaml.safe_dump(case, sort_keys=False), encoding="utf-8")
    return path


def truth_values(folder: Path, doc: dict[str, Any], laws: dict[str, dict[str, float]]
                 ) -> tuple[dict[str, float], dict[str, float]]:
    """Each requirement's value on the true law (its surrogate), and the surrogate's error."""
    from tuflexperf.analysis.requirements import check_case
    from tuflexperf.io.case import load_case

    values, errors = {}, {}
    for name, boxes in REGIONS.items():
        truth = json.loads(json.dumps(doc))
        worst = 0.0
        for engine in truth["engines"]:
            engine["coefficients"], error = surrogate(laws[engine["name"]], boxes)
            worst = max(worst, error)
            for key in ("covariance", "residual_sd_n", "extrapolation_sd_n",
                        "extrapolation_distance_m_s", "extrapolation_worst_n", "lack_of_fit"):
                engine.pop(key, None)
        path = folder / f"truth_{name}.yaml"
        path.write_text(yaml.safe_dump(truth, sort_keys=False), encoding="utf-8")
        case = load_case(write_case(folder, path, 1, 1))
        # the truth is the aircraft as it is: the nominal reading (the first), not the
        # worse of the disputed evidence a verdict is judged on
        found = {v.name: v.readings[0].value if v.readings else v.value
                 for v in check_case(case)}
        value = found.get(name)
        values[name] = math.nan if value is None else float(value)
        errors[name] = worst
    return values, errors


def draw_campaign(rig_name: str, index: int) -> tuple[dict[str, dict[str, float]], float, float]:
    """The truth's thrust laws, airspeed bias [m/s] and thrust scale [-] (seeded by rig and
    index: a truth is the same in every run)."""
    rig = RIGS[rig_name]
    rng = np.random.default_rng([SEED, list(RIGS).index(rig_name), index])
    laws = draw_truth(rng)
    bias = float(rng.normal(0.0, rig["airspeed_bias_sd_m_s"])) if rig["airspeed_bias_sd_m_s"] \
        else 0.0
    scale = float(rng.normal(0.0, rig["thrust_scale_sd"])) if rig["thrust_scale_sd"] else 0.0
    return laws, bias, scale


def prepare(rig_name: str, index: int, folder: Path) -> dict[str, Any]:
    """Generate and fit the truth's campaign into ``folder`` (its propulsion file and the
    requirements' true values); kept there, a second study with another error model reuses
    it (the fit and the truths do not depend on the error model)."""
    done = folder / "truth.json"
    if done.exists():
        kept = json.loads(done.read_text(encoding="utf-8"))
        if kept.get("version") == TRUTH_VERSION:
            return kept
    folder.mkdir(parents=True, exist_ok=True)
    laws, bias, scale = draw_campaign(rig_name, index)
    if not (folder / "fitted.yaml").exists():
        with tempfile.TemporaryDirectory(prefix="calibration_") as tmp:
            campaign = generate(Path(tmp) / "campaign", laws, bias, scale, 1000 * index + 7)
            fit(campaign, folder / "fitted.yaml")
    doc = study_propulsion(folder / "fitted.yaml", RIGS[rig_name])
    (folder / "propulsion.yaml").write_text(yaml.safe_dump(doc, sort_keys=False),
                                            encoding="utf-8")
    truth, surrogate_error = truth_values(folder, doc, laws)
    result = {"version": TRUTH_VERSION, "bias_m_s": bias, "scale": scale, "truth": truth,
              "surrogate_error_n": surrogate_error}
    done.write_text(json.dumps(result), encoding="utf-8")
    return result


def one_truth(rig_name: str, index: int, samples: int, cache: Path | None = None
              ) -> dict[str, Any]:
    from tuflexperf.analysis.uncertainty import plan_for, quantiles, run_samples
    from tuflexperf.io.case import load_case

    with tempfile.TemporaryDirectory(prefix="calibration_") as tmp:
        folder = Path(tmp) if cache is None else cache / f"{rig_name}_{index}"
        prepared = prepare(rig_name, index, folder)
        bias, scale = prepared["bias_m_s"], prepared["scale"]
        truth, surrogate_error = prepared["truth"], prepared["surrogate_error_n"]
        case = load_case(write_case(folder, folder / "propulsion.yaml", samples, index + 1))
        plan = plan_for(case)
        drawn = run_samples(case, plan)
    out: dict[str, Any] = {"rig": rig_name, "index": index, "bias_m_s": bias, "scale": scale,
                           "sampled": plan.errors.sampled if plan.errors else [],
                           "requirements": {}}
    for name, kind in KINDS.items():
        values = drawn.values.get(name)
        if values is None:
            continue
        p05, p50, p95 = quantiles(values, kind)
        record: dict[str, Any] = {"truth": truth[name], "p05": p05, "p50": p50, "p95": p95,
                                  "surrogate_error_n": surrogate_error[name], "limits": []}
        if None not in (p05, p50, p95) and p95 > p05:
            sd = (p95 - p05) / 3.29
            for u in LIMIT_OFFSETS:
                # a "min" requirement meets above its limit: the offsets mirror
                limit = p50 + (u if kind == "max" else -u) * sd
                met = (truth[name] <= limit) if kind == "max" else (truth[name] >= limit)
                record["limits"].append({"limit": limit,
                                         "p_meet": probability_met(values, limit, kind),
                                         "truth_met": bool(met and math.isfinite(truth[name]))})
        out["requirements"][name] = record
    return out


# where the study's requirements fly their live engines (throttle [-], true airspeed [m/s])
OPERATING_POINTS = {"roll": (1.0, 10.0), "climb": (1.0, 20.0), "OEI and loiter": (0.63, 17.0),
                    "mission cruise": (0.47, 26.0), "endurance cruise": (0.5, 27.6),
                    "descent": (0.1, 20.0)}


def diagnose(cache: Path, rig_name: str, indices: Any) -> dict[str, Any]:
    """At :data:`OPERATING_POINTS`: the fitted surface's true error and the error model's
    model-form sd there, both in the lack of fit's RMS, over the cached truths' engines, and
    the correlation of the true errors between the points (the model's, beside it)."""
    from tuflexperf.analysis.error_model import error_model_for
    from tuflexperf.io.case import load_case

    names = list(OPERATING_POINTS)
    errors: list[list[float]] = [[] for _ in names]
    sds: list[list[float]] = [[] for _ in names]
    model_corr = None
    for index in indices:
        folder = cache / f"{rig_name}_{index}"
        laws = draw_campaign(rig_name, index)[0]
        case = load_case(write_case(folder, folder / "propulsion.yaml", 1, 1))
        maps = error_model_for(case, case.uncertainty.propulsion).model_form_maps
        if maps is None:
            continue
        for j, engine in enumerate(case.propulsion.engines):
            rms = engine.model_form_sd_n
            basis = []
            for k, (x, v) in enumerate(OPERATING_POINTS.values()):
                b = np.array([1.0, x, v, x * x, x * v, v * v])
                fitted = sum(engine.coefficients[t] * bt for t, bt in zip(POLY22_TERMS, b,
                                                                         strict=True))
                errors[k].append(float((true_thrust(x, v, laws[engine.name]) - fitted) / rms))
                sds[k].append(float(np.linalg.norm(maps[j] @ b)) / rms)
                basis.append(maps[j] @ b)
            cov = np.array(basis) @ np.array(basis).T
            model_corr = cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov)))
    table = np.array(errors)
    return {"points": OPERATING_POINTS,
            "true_error_rms": dict(zip(names, np.sqrt(np.mean(table ** 2, axis=1)).tolist(),
                                       strict=True)),
            "true_error_mean": dict(zip(names, np.mean(table, axis=1).tolist(), strict=True)),
            "model_sd": dict(zip(names, np.mean(sds, axis=1).tolist(), strict=True)),
            "true_correlation": np.corrcoef(table).round(2).tolist(),
            "model_correlation": None if model_corr is None else model_corr.round(2).tolist(),
            "engines": table.shape[1]}


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    summary: dict[str, Any] = {}
    for rig in RIGS:
        mine = [r for r in records if r["rig"] == rig]
        if not mine:
            continue
        table = {}
        probabilities, met = [], []
        for name in KINDS:
            rows = [r["requirements"][name] for r in mine if name in r["requirements"]]

            def column(key: str, rows: list[dict[str, Any]] = rows) -> list[float]:
                return [math.nan if row[key] is None else row[key] for row in rows]

            result = coverage(column("truth"), column("p05"), column("p50"), column("p95"))
            table[name] = {**result.to_dict(), "truths": len(rows),
                           "largest_surrogate_error_n": max(column("surrogate_error_n"),
                                                            default=math.nan)}
            for row in rows:
                for limit in row["limits"]:
                    probabilities.append(limit["p_meet"])
                    met.append(limit["truth_met"])
        summary[rig] = {"truths": len(mine), "requirements": table,
                        "reliability": [b.to_dict() for b in reliability(probabilities, met)]}
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--truths", type=int, default=40)
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--rigs", default=",".join(RIGS))
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--first", type=int, default=0,
                        help="first truth's index; with --more, the records already in --out "
                        "are kept and these added")
    parser.add_argument("--more", action="store_true")
    parser.add_argument("--cache", type=Path, default=None,
                        help="folder (outside the repository) that keeps each truth's fitted "
                        "campaign and true values for the next run")
    parser.add_argument("--prepare-only", action="store_true",
                        help="generate and fit the truths into --cache, sample none")
    parser.add_argument("--resume", action="store_true",
                        help="keep the records in --out and skip the truths they hold (a "
                        "stopped study goes on where it stopped)")
    parser.add_argument("--merge", type=Path, nargs="+", default=None,
                        help="write --out from these result files' records (e.g. one per rig, "
                        "run side by side), sampling nothing")
    parser.add_argument("--diagnose", action="store_true",
                        help="with --cache: the surface's true error against the model-form "
                        "sd at the requirements' operating points (JSON), sampling nothing")
    args = parser.parse_args()
    if args.diagnose:
        if args.cache is None:
            parser.error("--diagnose needs --cache")
        found = {rig: diagnose(args.cache, rig, range(args.first, args.first + args.truths))
                 for rig in args.rigs.split(",")}
        print(json.dumps(found, indent=1))
        return
    if args.merge:
        merged: dict[tuple[str, int], dict[str, Any]] = {}
        samples, seconds = set(), 0.0
        for path in args.merge:
            done = json.loads(path.read_text(encoding="utf-8"))
            samples.add(done["samples"])
            seconds += done["seconds_this_run"]
            merged.update({(r["rig"], r["index"]): r for r in done["records"]})
        if len(samples) != 1:
            parser.error(f"--merge: the files drew different sample counts {sorted(samples)}")
        records = sorted(merged.values(), key=lambda r: (r["index"], list(RIGS).index(r["rig"])))
        diagnosis = None
        if args.cache is not None:  # the clean rig: the model form alone makes its bands
            indices = sorted(r["index"] for r in records if r["rig"] == "clean")
            diagnosis = diagnose(args.cache, "clean", indices)
        _write(args.out, records, samples.pop(), seconds, diagnosis)
        return
    if args.cache is not None and args.cache.resolve().is_relative_to(ROOT):
        parser.error(f"--cache {args.cache}: keep the campaigns outside the repository")
    if args.prepare_only:
        if args.cache is None:
            parser.error("--prepare-only needs --cache")
        for index in range(args.first, args.first + args.truths):
            for rig in args.rigs.split(","):
                t0 = time.perf_counter()
                prepare(rig, index, args.cache / f"{rig}_{index}")
                print(f"prepared {rig} {index}: {time.perf_counter() - t0:.1f} s",
                      file=sys.stderr, flush=True)
        return
    records: list[dict[str, Any]] = []
    if (args.more or args.resume) and args.out.exists():
        records = json.loads(args.out.read_text(encoding="utf-8"))["records"]
    done = {(r["rig"], r["index"]) for r in records} if args.resume else set()
    started = time.perf_counter()
    # truth by truth, both rigs each time: a study stopped early holds as many of each
    for index in range(args.first, args.first + args.truths):
        for rig in args.rigs.split(","):
            if (rig, index) in done:
                continue
            t0 = time.perf_counter()
            records = [r for r in records if (r["rig"], r["index"]) != (rig, index)]
            records.append(one_truth(rig, index, args.samples, args.cache))
            print(f"{rig} {index}: {time.perf_counter() - t0:.1f} s", file=sys.stderr,
                  flush=True)
            _write(args.out, records, args.samples, time.perf_counter() - started)
    print(json.dumps(summarise(records), indent=1))


def _write(out: Path, records: list[dict[str, Any]], samples: int, seconds: float,
           diagnosis: dict[str, Any] | None = None) -> None:
    """The result so far (rewritten after each truth: a stopped study keeps what it did)."""
    rigs = sorted({r["rig"] for r in records}, key=list(RIGS).index)
    result = {"study": "bench/calibration_study.py", "seed": SEED, "samples": samples,
              "truths_per_rig": {rig: sum(r["rig"] == rig for r in records) for rig in rigs},
              "rigs": {rig: RIGS[rig] for rig in rigs}, "seconds_this_run": round(seconds, 1),
              "summary": summarise(records),
              **({"diagnosis": diagnosis} if diagnosis is not None else {}),
              "records": records}
    out.write_text(json.dumps(result, indent=1, default=float) + "\n", encoding="utf-8")
    print(json.dumps(result["summary"], indent=1))


if __name__ == "__main__":
    main()
