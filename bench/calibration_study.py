"""Self-calibration study (issue 44): do ``check --samples``' bands hold known truths?

For each truth: a thrust law per fan and a rig are drawn, a synthetic campaign is generated
from them by the project's own generator (``scripts/generate_campaign.py``, its physics and
rig noise, with the thrust law and the rig's systematic errors replaced), fitted by
``tuflexperf fit``, and checked by the sampler ``check --samples`` runs
(:func:`tuflexperf.analysis.uncertainty.run_samples`, in this process). The truth of each
requirement is the tool's own deterministic ``check`` on the TRUE thrust law.

Thrust laws (``--generator``): ``poly22-cubic``, the generator's shipped poly22 per fan with
each coefficient off by N(0, 4 %), plus terms no poly22 holds: ``c3 x^3 + c5 x^2 (v / 30) +
c6 x (v / 30)^3`` [N], ``c3`` ~ U(-4, 4), ``c5`` ~ U(-3, 3), ``c6`` ~ N(-1, 1) (a family of
fans whose thrust falls faster at speed, one sign for most); ``momentum``, a family the
error model was not tuned to (:func:`momentum_thrust`: momentum theory on an rpm-throttle
map, a drop-off at speed and the duct's drag at low rpm). The deterministic check takes
poly22 only: for each requirement the true law is replaced by its least-squares poly22 over
the requirement's own operating region (:data:`REGIONS`, the whole domain joining at a
small weight), and that surrogate's largest error in the region is recorded.

Rigs: ``clean`` (no systematic error; ``rig_uncertainty`` declares zeros) and ``biased``
(an airspeed bias ~ N(0, 0.3 m/s) and a thrust scale ~ N(0, 2 %) per campaign, declared as
``airspeed_bias_sd_m_s: 0.3, thrust_scale_sd: 0.02``), each declared in the campaign
manifest's ``rig_uncertainty``, which ``fit`` copies into the propulsion file. The
aircraft, battery and power surfaces are the same in truth and estimate (only the thrust
model is uncertain), so the power-model and battery-fit sources are off in the study's case.

Per requirement (ground roll, trim, OEI, endurance, the test-flight mission's landing
charge): coverage of p05-p95 with its Clopper-Pearson 95 % interval, RMS z and mean z
(:mod:`tuflexperf.analysis.calibration`); P(meet) at five limits per truth set about the
sampled median (p50 + u (p95 - p05) / 3.29, u = -1.65, -0.75, 0, 0.75, 1.65) against
whether the truth met them: the 5-bin reliability diagram.

Run: ``python bench/calibration_study.py [--truths 40] [--samples 4000] [--out FILE]
[--cache DIR] [--generator momentum]``. ``--cache`` keeps each truth's fit and true values
outside the repository, so a second run with another error model samples only; ``--resume`` goes on
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
from tuflexperf.reduction.lack_of_fit import LACK_OF_FIT_P  # noqa: E402

SEED = 44
DEFAULT_OUT = ROOT / "docs" / "calibration_study.json"
RIGS: dict[str, dict[str, float]] = {
    "clean": {"airspeed_bias_sd_m_s": 0.0, "thrust_scale_sd": 0.0, "balance_zero_sd_n": 0.0,
              "voltage_sd_v": 0.0},
    "biased": {"airspeed_bias_sd_m_s": 0.3, "thrust_scale_sd": 0.02, "balance_zero_sd_n": 0.0,
               "voltage_sd_v": 0.0},
}
GENERATORS = ("poly22-cubic", "momentum")
"""The truths' thrust-law families: the first the error model was studied on, the second
(:func:`momentum_thrust`) one it was not tuned to."""
LIMIT_OFFSETS = (-1.65, -0.75, 0.0, 0.75, 1.65)
ANCHOR_WEIGHT = 1e-3  # per point of the whole domain in a truth's surrogate, against 1 inside
TRUTH_VERSION = 3  # of a cached truth (2: fits without the extrapolation bias; 1: no anchor)
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
    """The truth's thrust [N] at throttle ``x`` [-] and airspeed ``v`` [m/s] (the
    :func:`momentum_thrust` family where the law names an exit velocity ``v0``)."""
    if "v0" in c:
        return momentum_thrust(x, v, c)
    s = np.asarray(v, dtype=float) / 30.0
    return (BASE_POLY22(x, v, c) + c["c3"] * x ** 3 + c["c5"] * x * x * s
            + c["c6"] * x * s ** 3)


def momentum_thrust(x: Any, v: Any, c: dict[str, float]) -> Any:
    """A thrust law of another family than the error model was studied on [N]: momentum
    theory on an exit velocity ``v0 n`` set by the rpm fraction ``n = x^gamma`` (the ESC's
    map), ``rho A_e v0 n (v0 n - V)``, with a drop-off at speed ``1 - k (V / 40)^2`` (the
    inlet's losses) and the duct's drag ``0.5 rho A Cd V^2 (1 - n)^2`` as the fan slows."""
    x = np.maximum(np.asarray(x, dtype=float), 0.0)
    v = np.asarray(v, dtype=float)
    rho = GEN.AIR_DENSITY_KG_M3
    n = x ** c["gamma"]
    jet = c["v0"] * n
    thrust = rho * c["exit_area_m2"] * jet * (jet - v) * (1.0 - c["k"] * (v / 40.0) ** 2)
    return thrust - 0.5 * rho * GEN.FAN_AREA_M2 * c["cd"] * v * v * (1.0 - n) ** 2


def draw_truth(rng: np.random.Generator, generator: str = "poly22-cubic"
               ) -> dict[str, dict[str, float]]:
    """Per fan: the shipped poly22 off by N(0, 4 %) per coefficient, and the extra terms;
    for the ``momentum`` generator a :func:`momentum_thrust` law whose static full thrust is
    the shipped poly22's off by N(0, 4 %), exit velocity ~ U(85, 105) m/s, ``gamma`` ~
    U(0.5, 0.75), ``k`` ~ U(0, 0.15), ``Cd`` ~ U(0.2, 0.8)."""
    if generator == "momentum":
        laws = {}
        for engine, base in GEN.BASE_COEFFICIENTS.items():
            static = (base["p00"] + base["p10"] + base["p20"]) * (1.0 + rng.normal(0.0, 0.04))
            v0 = float(rng.uniform(85.0, 105.0))
            laws[engine] = {"v0": v0, "exit_area_m2": float(static / (GEN.AIR_DENSITY_KG_M3
                                                                       * v0 * v0)),
                            "gamma": float(rng.uniform(0.5, 0.75)),
                            "k": float(rng.uniform(0.0, 0.15)),
                            "cd": float(rng.uniform(0.2, 0.8))}
        return laws
    laws = {}
    for engine, base in GEN.BASE_COEFFICIENTS.items():
        law = {t: float(base[t] * (1.0 + rng.normal(0.0, 0.04))) for t in POLY22_TERMS}
        law.update(c3=float(rng.uniform(-4, 4)), c5=float(rng.uniform(-3, 3)),
                   c6=float(rng.normal(-1.0, 1.0)))
        laws[engine] = law
    return laws


def generate(folder: Path, laws: dict[str, dict[str, float]], bias_m_s: float, scale: float,
             seed: int, declared: dict[str, float] | None = None) -> Path:
    """The campaign of ``laws`` on a rig whose tunnel reads ``bias_m_s`` high and whose
    balance reads ``1 + scale`` times the force; its manifest declares the rig's errors
    ``declared`` as ``rig_uncertainty`` (``fit`` copies them into the propulsion file)."""
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
    manifest = folder / "campaign.yaml"
    if declared is not None:
        with manifest.open("a", encoding="utf-8") as out:
            out.write(yaml.safe_dump({"rig_uncertainty": dict(declared)}, sort_keys=False))
    return manifest


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
        for key in ("residual_sd_n", "extrapolation_sd_n", "extrapolation_worst_n", "rmse_n",
                    "extrapolation_bias_n_per_m_s", "extrapolation_bias_se_n_per_m_s"):
            if engine.get(key) is not None:
                engine[key] = engine[key] * factor
        engine.pop("standard_errors", None)
        lack = engine.get("lack_of_fit") or {}
        if "residuals" not in lack and (lack.get("p_value") or 1.0) < LACK_OF_FIT_P:
            lack["residuals"] = _residuals_from_table(fitted.parent, engine["name"])
        if lack.get("residuals"):
            lack["residuals"] = [[x, v, r * factor, n] for x, v, r, n in lack["residuals"]]
    if doc.get("rig_uncertainty") != dict(rig):  # the manifest's, copied by fit
        raise RuntimeError(f"{fitted}: rig_uncertainty {doc.get('rig_uncertainty')} is not "
                           f"the manifest's {rig}")
    return doc


def _residuals_from_table(folder: Path, engine: str) -> list[list[float]]:
    """The residual surface ``fit`` writes (``lack_of_fit.residuals``), from a fit kept
    before it wrote one: its holds' table, the same set points and least squares."""
    import csv

    from tuflexperf.reduction.fit_checks import set_point
    from tuflexperf.reduction.lack_of_fit import (
        hold_residuals,
        polynomial_design,
        polynomial_terms,
        set_point_groups,
    )

    with (folder / "fitted_thrust_table.csv").open(encoding="utf-8") as handle:
        rows = [r for r in csv.DictReader(handle) if r["engine"] == engine]
    x, v, y, measured = (np.array([float(r[k]) for r in rows]) for k in (
        "throttle", "airspeed_m_s", "thrust_n", "airspeed_measured_m_s"))
    design = polynomial_design(x, v, polynomial_terms(2, 2))
    residual = y - design @ np.linalg.lstsq(design, y, rcond=None)[0]
    groups = set_point_groups(x, np.array([set_point(a) for a in measured]))
    return [list(row) for row in hold_residuals(x, v, residual, groups)]


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
                        "extrapolation_distance_m_s", "extrapolation_worst_n", "lack_of_fit",
                        "extrapolation_bias_n_per_m_s", "extrapolation_bias_se_n_per_m_s"):
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


def draw_campaign(rig_name: str, index: int, generator: str = GENERATORS[0]
                  ) -> tuple[dict[str, dict[str, float]], float, float]:
    """The truth's thrust laws, airspeed bias [m/s] and thrust scale [-] (seeded by
    generator, rig and index: a truth is the same in every run)."""
    rig = RIGS[rig_name]
    stream = [SEED, list(RIGS).index(rig_name), index]
    if generator != GENERATORS[0]:
        stream.append(GENERATORS.index(generator))
    rng = np.random.default_rng(stream)
    laws = draw_truth(rng, generator)
    bias = float(rng.normal(0.0, rig["airspeed_bias_sd_m_s"])) if rig["airspeed_bias_sd_m_s"] \
        else 0.0
    scale = float(rng.normal(0.0, rig["thrust_scale_sd"])) if rig["thrust_scale_sd"] else 0.0
    return laws, bias, scale


def truth_folder(cache: Path, rig_name: str, index: int, generator: str = GENERATORS[0]
                 ) -> Path:
    """Where a truth's campaign is kept (the first generator's as the study always kept it)."""
    prefix = "" if generator == GENERATORS[0] else f"{generator}_"
    return cache / f"{prefix}{rig_name}_{index}"


def _fit_is_current(fitted: Path) -> bool:
    """Whether a kept fit holds what this study's fit writes (the extrapolation bias and the
    manifest's rig errors): an older one is fitted again."""
    if not fitted.exists():
        return False
    doc = yaml.safe_load(fitted.read_text(encoding="utf-8"))
    from tuflexperf.reduction.lack_of_fit import MODEL_FORM_TERMS

    return "rig_uncertainty" in doc and all(
        "extrapolation_bias_n_per_m_s" in e
        and len((e.get("lack_of_fit") or {}).get("model_form_shares") or MODEL_FORM_TERMS)
        == len(MODEL_FORM_TERMS) for e in doc["engines"])


def prepare(rig_name: str, index: int, folder: Path, generator: str = GENERATORS[0]
            ) -> dict[str, Any]:
    """Generate and fit the truth's campaign into ``folder`` (its propulsion file and the
    requirements' true values); kept there, a second study with another error model reuses
    it (the fit and the truths do not depend on the error model)."""
    done = folder / "truth.json"
    if done.exists():
        kept = json.loads(done.read_text(encoding="utf-8"))
        if kept.get("version") == TRUTH_VERSION and _fit_is_current(folder / "fitted.yaml"):
            return kept
    folder.mkdir(parents=True, exist_ok=True)
    laws, bias, scale = draw_campaign(rig_name, index, generator)
    if not _fit_is_current(folder / "fitted.yaml"):
        with tempfile.TemporaryDirectory(prefix="calibration_") as tmp:
            campaign = generate(Path(tmp) / "campaign", laws, bias, scale, 1000 * index + 7,
                                RIGS[rig_name])
            fit(campaign, folder / "fitted.yaml")
    doc = study_propulsion(folder / "fitted.yaml", RIGS[rig_name])
    (folder / "propulsion.yaml").write_text(yaml.safe_dump(doc, sort_keys=False),
                                            encoding="utf-8")
    truth, surrogate_error = truth_values(folder, doc, laws)
    result = {"version": TRUTH_VERSION, "bias_m_s": bias, "scale": scale, "truth": truth,
              "surrogate_error_n": surrogate_error}
    done.write_text(json.dumps(result), encoding="utf-8")
    return result


def one_truth(rig_name: str, index: int, samples: int, cache: Path | None = None,
              generator: str = GENERATORS[0]) -> dict[str, Any]:
    from tuflexperf.analysis.uncertainty import plan_for, quantiles, run_samples
    from tuflexperf.io.case import load_case

    with tempfile.TemporaryDirectory(prefix="calibration_") as tmp:
        folder = Path(tmp) if cache is None else truth_folder(cache, rig_name, index, generator)
        prepared = prepare(rig_name, index, folder, generator)
        # the propulsion file as this study's fit writes it (a kept fit's without the
        # residual surface gets it from its table)
        (folder / "propulsion.yaml").write_text(yaml.safe_dump(study_propulsion(
            folder / "fitted.yaml", RIGS[rig_name]), sort_keys=False), encoding="utf-8")
        bias, scale = prepared["bias_m_s"], prepared["scale"]
        truth, surrogate_error = prepared["truth"], prepared["surrogate_error_n"]
        case = load_case(write_case(folder, folder / "propulsion.yaml", samples, index + 1))
        plan = plan_for(case)
        drawn = run_samples(case, plan)
    out: dict[str, Any] = {"rig": rig_name, "index": index, "generator": generator,
                           "bias_m_s": bias, "scale": scale,
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


def diagnose(cache: Path, rig_name: str, indices: Any, generator: str = GENERATORS[0]
             ) -> dict[str, Any]:
    """At :data:`OPERATING_POINTS`: the fitted surface's true error less the mean the samples
    centre on there (the residual surface's posterior, where the file holds one) and the
    error model's model-form sd there, both in the lack of fit's RMS, over the cached truths'
    engines, and the correlation of the true errors between the points (the model's,
    averaged over the engines, beside it)."""
    from tuflexperf.analysis.error_model import error_model_for
    from tuflexperf.analysis.model_form_mean import residual_surfaces
    from tuflexperf.io.case import load_case

    names = list(OPERATING_POINTS)
    errors: list[list[float]] = [[] for _ in names]
    sds: list[list[float]] = [[] for _ in names]
    correlations = []
    for index in indices:
        folder = truth_folder(cache, rig_name, index, generator)
        if not (folder / "propulsion.yaml").exists():
            continue
        laws = draw_campaign(rig_name, index, generator)[0]
        case = load_case(write_case(folder, folder / "propulsion.yaml", 1, 1))
        maps = error_model_for(case, case.uncertainty.propulsion).model_form_maps
        if maps is None:
            continue
        surfaces = residual_surfaces(case.propulsion)
        for j, engine in enumerate(case.propulsion.engines):
            rms = engine.model_form_sd_n
            surface = surfaces[j]
            basis = []
            for k, (x, v) in enumerate(OPERATING_POINTS.values()):
                b = np.array([1.0, x, v, x * x, x * v, v * v])
                fitted = sum(engine.coefficients[t] * bt for t, bt in zip(POLY22_TERMS, b,
                                                                         strict=True))
                centre = 0.0 if surface is None else float(surface(x, v))
                errors[k].append(float((true_thrust(x, v, laws[engine.name]) - fitted - centre)
                                       / rms))
                sds[k].append(float(np.linalg.norm(maps[j] @ b)) / rms)
                basis.append(maps[j] @ b)
            cov = np.array(basis) @ np.array(basis).T
            correlations.append(cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov))))
    model_corr = np.mean(correlations, axis=0) if correlations else None
    table = np.array(errors)
    return {"points": OPERATING_POINTS,
            "true_error_rms": dict(zip(names, np.sqrt(np.mean(table ** 2, axis=1)).tolist(),
                                       strict=True)),
            "true_error_mean": dict(zip(names, np.mean(table, axis=1).tolist(), strict=True)),
            "model_sd": dict(zip(names, np.mean(sds, axis=1).tolist(), strict=True)),
            "true_correlation": np.corrcoef(table).round(2).tolist(),
            "model_correlation": None if model_corr is None else model_corr.round(2).tolist(),
            "engines": table.shape[1]}


def study_key(record: dict[str, Any]) -> str:
    """A record's rig, prefixed ``generator:`` for a truth family other than the first."""
    generator = record.get("generator", GENERATORS[0])
    return record["rig"] if generator == GENERATORS[0] else f"{generator}:{record['rig']}"


def _study_keys() -> list[str]:
    return [rig if g == GENERATORS[0] else f"{g}:{rig}" for g in GENERATORS for rig in RIGS]


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    summary: dict[str, Any] = {}
    for rig in _study_keys():
        mine = [r for r in records if study_key(r) == rig]
        if not mine:
            continue
        table = {}
        probabilities, met = [], []
        for name in KINDS:
            rows = [r["requirements"][name] for r in mine if name in r["requirements"]]

            def column(key: str, rows: list[dict[str, Any]] = rows,
                       missing: float = math.nan) -> list[float]:
                return [missing if row[key] is None else row[key] for row in rows]

            # a bound not attainable lies on the requirement's bad side: above for a "max"
            # requirement, below for a "min" one (the band still bounds the truth there)
            worst = math.inf if KINDS[name] == "max" else -math.inf
            result = coverage(column("truth"),
                              column("p05", missing=worst if worst < 0 else math.nan),
                              column("p50"),
                              column("p95", missing=worst if worst > 0 else math.nan))
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
    parser.add_argument("--generator", choices=GENERATORS, default=GENERATORS[0],
                        help="the truths' thrust-law family (momentum: one the error model "
                        "was not tuned to)")
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
        found = {rig: diagnose(args.cache, rig, range(args.first, args.first + args.truths),
                               args.generator) for rig in args.rigs.split(",")}
        print(json.dumps(found, indent=1))
        return
    if args.merge:
        merged: dict[tuple[str, int], dict[str, Any]] = {}
        samples, seconds = set(), 0.0
        for path in args.merge:
            done = json.loads(path.read_text(encoding="utf-8"))
            samples.add(done["samples"])
            seconds += done["seconds_this_run"]
            merged.update({(study_key(r), r["index"]): r for r in done["records"]})
        if len(samples) != 1:
            parser.error(f"--merge: the files drew different sample counts {sorted(samples)}")
        records = sorted(merged.values(),
                         key=lambda r: (r["index"], _study_keys().index(study_key(r))))
        diagnosis = None
        if args.cache is not None:  # the clean rig: the model form alone makes its bands
            indices = sorted(r["index"] for r in records if study_key(r) == "clean")
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
                prepare(rig, index, truth_folder(args.cache, rig, index, args.generator),
                        args.generator)
                print(f"prepared {rig} {index}: {time.perf_counter() - t0:.1f} s",
                      file=sys.stderr, flush=True)
        return
    records: list[dict[str, Any]] = []
    if (args.more or args.resume) and args.out.exists():
        records = json.loads(args.out.read_text(encoding="utf-8"))["records"]
    done = {(study_key(r), r["index"]) for r in records} if args.resume else set()
    started = time.perf_counter()
    # truth by truth, both rigs each time: a study stopped early holds as many of each
    for index in range(args.first, args.first + args.truths):
        for rig in args.rigs.split(","):
            key = study_key({"rig": rig, "generator": args.generator})
            if (key, index) in done:
                continue
            t0 = time.perf_counter()
            records = [r for r in records if (study_key(r), r["index"]) != (key, index)]
            records.append(one_truth(rig, index, args.samples, args.cache, args.generator))
            print(f"{key} {index}: {time.perf_counter() - t0:.1f} s", file=sys.stderr,
                  flush=True)
            _write(args.out, records, args.samples, time.perf_counter() - started)
    print(json.dumps(summarise(records), indent=1))


def _write(out: Path, records: list[dict[str, Any]], samples: int, seconds: float,
           diagnosis: dict[str, Any] | None = None) -> None:
    """The result so far (rewritten after each truth: a stopped study keeps what it did)."""
    rigs = sorted({study_key(r) for r in records}, key=_study_keys().index)
    result = {"study": "bench/calibration_study.py", "seed": SEED, "samples": samples,
              "generators": list(GENERATORS),
              "truths_per_rig": {rig: sum(study_key(r) == rig for r in records)
                                 for rig in rigs},
              "rigs": {rig: RIGS[rig.split(":")[-1]] for rig in rigs},
              "seconds_this_run": round(seconds, 1),
              "summary": summarise(records),
              **({"diagnosis": diagnosis} if diagnosis is not None else {}),
              "records": records}
    out.write_text(json.dumps(result, indent=1, default=float) + "\n", encoding="utf-8")
    print(json.dumps(result["summary"], indent=1))


if __name__ == "__main__":
    main()
