"""Generate the shipped synthetic test campaign (data/tuflex/campaign/).

The paper's raw logs are not published, so the campaign that ``tuflexperf fit``
ships with is synthetic, built from a *known* ground truth so the reduction can
be checked against it (tests/validation/test_fit_campaign.py). Everything is
seeded (:data:`SEED`); running the script again rewrites identical files.

Ground truth (written to ``truth.yaml``):

* thrust per fan: the shipped poly22 (data/tuflex/propulsion.yaml, reconstructed
  from the paper's published thrusts; frozen in :data:`BASE_COEFFICIENTS`) with
  small perturbations (:data:`PERTURBATION`) so the fit cannot just echo the
  shipped file;
* structure drag ``D = 0.5 rho CdA V^2`` with ``CdA = 0.0055 m^2`` (about 3 N at
  30 m/s: the fairing and rods of the paper's Fig. 5/6 rig, estimated);
* throttle-to-force dead time 0.05 s (published, section 4) and a first-order
  spool-up lag of 0.08 s (estimated: "responds nearly instantaneous");
* pack voltage: thrust ``T = T_ref(x, V) (U / U_ref)^2`` (SPEC 3's voltage law, exponent 2:
  rpm ~ duty x voltage, thrust ~ rpm^2) with ``U`` the loaded voltage of the pack feeding
  the fan (the paper saw thrust change with the battery). Each fan runs its step runs on
  one pair of fresh 12S 5 Ah packs in parallel (as in flight) from 0 to 27.5 m/s, and
  the 30 m/s run on a fresh pair ("the battery needed to be changed due to low voltage",
  paper section 4); open-circuit voltage per cell ``4.05 - 0.06 q + 0.12 exp(-3 q) -
  0.02 q / (5.25 - q)`` (q Ah drawn per pack, as scripts/generate_discharge.py), 40 mOhm
  per pack (20 mOhm for the pair);
* electrical power consistent with the thrust by momentum theory:
  ``P_el = T (V + v_e) / 2 / eta + P_idle`` with ``T = rho A_jet v_e (v_e - V)``,
  ``A_jet`` = 0.0050 m^2 (derived from Table 1: 41-59 N at 82-98 m/s exit velocity),
  ``eta`` = 0.70 (Table 1's 70-71 % "efficiency" is exactly ``T v_e / 2 / P_el`` of its
  own figures), ``P_idle`` 0.25 A at the pack (ESC idle); the step runs log ``voltage_v``
  and ``current_a = P_el / U``.

What a real rig adds (all estimated, to exercise the reduction):

* 1 kHz log (the paper's rate), tunnel speed a little off its set point with a
  slow 0.3 % drift and 0.05 m/s pitot noise;
* vibration noise growing with throttle: Gaussian 0.12 + 0.9 x N plus an
  aliased blade-passing tone of 0.6 x N;
* isolated spikes (about one per 2 s, 4-12 N) and two bursts of spikes per run;
* a few NaN samples (dropped RS232 frames) in some runs;
* values rounded to the logger's resolution: 1 ms, 0.01 N, 0.01 m/s, 0.001 throttle.

Runs: for each fan, throttle steps from 100 % down to 10 % in 10 % steps (then 0)
at 0, 15, 20, 22.5, 25, 27.5 and 30 m/s (about 4 s per step, varied by +-0.4 s);
a linear sine sweep of the throttle between 25 % and 75 % rising from 0.2 to
5 Hz at 0 and 30 m/s; one velocity sweep 0-30 m/s of the bare structure.

To keep the repository small, EDF1's step runs and EDF2's sweeps are gzip CSV
(``.csv.gz``), EDF2's step runs and EDF1's sweeps MATLAB v5 files compressed
with ``scipy.io.savemat(..., do_compression=True)``, the drag sweep a plain
``.csv``: every reader path is exercised.

Run: ``.venv/bin/python scripts/generate_campaign.py`` (about 10 s).
"""

from __future__ import annotations

import gzip
import io
from pathlib import Path

import numpy as np
import scipy.io
import yaml
from scipy.signal import lfilter

from tuflexperf.models.thrust import poly22

SEED = 20240531
ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "data" / "tuflex" / "campaign"

SAMPLE_RATE_HZ = 1000.0
AIR_DENSITY_KG_M3 = 1.225
FAN_AREA_M2 = float(np.pi * 0.093**2 / 4)  # 93 mm fan (paper Table 1)
TUNNEL_AREA_M2 = 0.16  # 400 mm x 400 mm open jet (paper 2.1)
STRUCTURE_CDA_M2 = 0.0055
DELAY_S = 0.05
SPOOL_LAG_S = 0.08
REFERENCE_VOLTAGE_V = 47.5  # U_ref of the thrust truth: mid of the loaded full-throttle voltages
VOLTAGE_EXPONENT = 2.0
CELLS = 12
PACKS_IN_PARALLEL = 2
PACK_RESISTANCE_OHM = 0.040
JET_AREA_M2 = 0.0050
FAN_EFFICIENCY = 0.70
IDLE_CURRENT_A = 0.25
ELECTRICAL_NOISE = {"voltage_v": 0.02, "current_a": 0.2}
AIRSPEEDS_M_S = (0.0, 15.0, 20.0, 22.5, 25.0, 27.5, 30.0)
SWEEP_AIRSPEEDS_M_S = (0.0, 30.0)
STEP_S = 4.0
PACK_CHANGE_AIRSPEED_M_S = 30.0
SWEEP_CHARGE_AH = 0.5  # the sweeps run on a pair of packs 0.5 Ah into their charge
# data/tuflex/propulsion.yaml as reconstructed (scripts/reconstruct_tuflex.py) when the
# campaign was generated, frozen here so the campaign does not change when that
# reconstruction is re-calibrated (the shipped file also carries a reference density and
# power surfaces; the campaign's truth is thrust at 1.225 kg/m^3 and 47.5 V).
BASE_COEFFICIENTS = {
    "EDF1": {
        "p00": 0.0,
        "p10": 33.75422882,
        "p01": -0.13,
        "p20": 21.36577118,
        "p11": -0.3938333333,
        "p02": 0.0006833333333,
    },
    "EDF2": {
        "p00": 0.0,
        "p10": 33.9318182,
        "p01": -0.13,
        "p20": 21.4781818,
        "p11": -0.36625,
        "p02": 0.001375,
    },
}
# Relative change of the shipped coefficients -> ground truth. Small enough that the
# shipped model stays within the paper's +-0.5 N accuracy goal of the campaign's points
# (0.30 N at worst over the test grid), large enough that a fit that only
# echoed the shipped file would miss the truth by more than its standard errors.
PERTURBATION = {
    "EDF1": {"p10": +0.01, "p20": -0.006, "p01": +0.03, "p11": -0.015, "p02": +0.05},
    "EDF2": {"p10": -0.01, "p20": +0.012, "p01": -0.03, "p11": +0.015, "p02": -0.05},
}
MAT_HEADER = "MATLAB 5.0 MAT-file, written by tuflexperf scripts/generate_campaign.py"
RESOLUTION = {
    "time_s": 1e-3,
    "force_n": 0.01,
    "airspeed_m_s": 0.01,
    "throttle": 1e-3,
    "voltage_v": 0.01,
    "current_a": 0.1,
}


def truth_coefficients() -> dict[str, dict[str, float]]:
    """:data:`BASE_COEFFICIENTS` with :data:`PERTURBATION` applied (relative)."""
    return {
        engine: {
            term: round(value * (1.0 + PERTURBATION[engine].get(term, 0.0)), 6)
            for term, value in base.items()
        }
        for engine, base in BASE_COEFFICIENTS.items()
    }


def structure_drag_n(v: np.ndarray) -> np.ndarray:
    return 0.5 * AIR_DENSITY_KG_M3 * STRUCTURE_CDA_M2 * v * v


def tunnel_airspeed(rng: np.random.Generator, nominal: np.ndarray | float, t: np.ndarray):
    """True and measured tunnel speed: set-point error, slow drift, pitot noise."""
    nominal = np.broadcast_to(np.asarray(nominal, dtype=float), t.shape)
    offset = rng.normal(0.0, 0.05) if np.any(nominal > 0) else 0.0
    drift = 0.003 * np.sin(2 * np.pi * 0.05 * t + rng.uniform(0, 2 * np.pi))
    true = np.where(nominal > 0, (nominal + offset) * (1 + drift), 0.0)
    measured = true + rng.normal(0.0, 0.05, t.size)
    return true, measured


def open_circuit_voltage_v(charge_ah: np.ndarray | float) -> np.ndarray:
    """Open-circuit voltage of the packs (V) after ``charge_ah`` drawn from each pack."""
    q = np.asarray(charge_ah, dtype=float)
    cell = 4.05 - 0.06 * q + 0.12 * np.exp(-3.0 * q) - 0.02 * q / (5.25 - q)
    return CELLS * cell


def electrical_power_w(thrust_n: np.ndarray, airspeed: np.ndarray, volts: np.ndarray) -> np.ndarray:
    """Momentum-theory power of the thrust over the fan's efficiency, plus the ESC's idle draw."""
    t = np.maximum(thrust_n, 0.0)
    v_exit = 0.5 * (airspeed + np.sqrt(airspeed**2 + 4 * t / (AIR_DENSITY_KG_M3 * JET_AREA_M2)))
    return t * (airspeed + v_exit) / 2.0 / FAN_EFFICIENCY + IDLE_CURRENT_A * volts


def powertrain(
    t: np.ndarray, lagged: np.ndarray, airspeed: np.ndarray, coefficients: dict[str, float],
    start_charge_ah: float, throttle_curve: float = 1.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Thrust (N), pack voltage (V) and current (A) per sample, and the charge at the end.

    The pack's loaded voltage sets the thrust (``(U/U_ref)^2``), the thrust the power and
    the power the current: a fixed point, converged in a few passes. ``throttle_curve`` != 1:
    the ESC's rpm goes as ``x^throttle_curve``, a thrust law no poly22 fits exactly (a harsh
    campaign, issue 43 item 4).
    """
    dt = 1.0 / SAMPLE_RATE_HZ
    shaped = lagged if throttle_curve == 1.0 else np.maximum(lagged, 0.0) ** throttle_curve
    thrust_ref = poly22(shaped, airspeed, coefficients)
    resistance = PACK_RESISTANCE_OHM / PACKS_IN_PARALLEL
    charge = np.full(t.size, start_charge_ah)
    volts = open_circuit_voltage_v(charge)
    for _ in range(6):
        thrust = thrust_ref * (volts / REFERENCE_VOLTAGE_V) ** VOLTAGE_EXPONENT
        power = electrical_power_w(thrust, airspeed, volts)
        ocv = open_circuit_voltage_v(charge)
        # terminal voltage at constant power: U = (E + sqrt(E^2 - 4 R P)) / 2
        volts = 0.5 * (ocv + np.sqrt(ocv**2 - 4.0 * resistance * power))
        amps = power / volts
        charge = start_charge_ah + np.cumsum(amps) * dt / 3600.0 / PACKS_IN_PARALLEL
    return thrust, volts, amps, float(charge[-1])


def rig_response(
    rng: np.random.Generator,
    t: np.ndarray,
    throttle_cmd: np.ndarray,
    true_airspeed: np.ndarray,
    coefficients: dict[str, float],
    start_charge_ah: float = 0.0,
    throttle_curve: float = 1.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Measured force (thrust minus structure drag, plus rig noise), voltage, current, charge."""
    dt = 1.0 / SAMPLE_RATE_HZ
    delayed = np.interp(t - DELAY_S, t, throttle_cmd, left=throttle_cmd[0])
    alpha = np.exp(-dt / SPOOL_LAG_S)
    lagged = lfilter([1 - alpha], [1, -alpha], delayed, zi=[alpha * delayed[0]])[0]
    thrust, volts, amps, end_charge = powertrain(
        t, lagged, true_airspeed, coefficients, start_charge_ah, throttle_curve
    )
    force = thrust - structure_drag_n(true_airspeed)
    tone_hz = 50.0 + 130.0 * lagged
    phase = 2 * np.pi * np.cumsum(tone_hz) * dt
    noise = rng.normal(0.0, 1.0, t.size) * (0.12 + 0.9 * lagged) + 0.6 * lagged * np.sin(phase)
    return force + noise + spikes(rng, t.size), volts, amps, end_charge


def spikes(rng: np.random.Generator, n: int) -> np.ndarray:
    """Isolated spikes (about one per 2 s) and two bursts of 30-60 ms."""
    out = np.zeros(n)
    count = rng.poisson(n / SAMPLE_RATE_HZ / 2.0)
    where = rng.integers(0, n, count)
    out[where] = rng.choice([-1.0, 1.0], count) * rng.uniform(4.0, 12.0, count)
    for _ in range(2):
        length = int(rng.uniform(0.03, 0.06) * SAMPLE_RATE_HZ)
        start = int(rng.integers(0, max(n - length, 1)))
        hit = rng.random(length) < 0.3
        out[start : start + length][hit] += rng.normal(0.0, 8.0, int(hit.sum()))
    return out


def add_nans(rng: np.random.Generator, columns: dict[str, np.ndarray], count: int) -> None:
    """A few dropped samples, as a logger's missed serial frames."""
    n = columns["force_n"].size
    for name in ("force_n", "airspeed_m_s")[: 1 + (count > 3)]:
        columns[name][rng.integers(1, n - 1, count)] = np.nan


def quantise(columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {
        name: np.round(values / RESOLUTION[name]) * RESOLUTION[name]
        for name, values in columns.items()
    }


def step_run(
    rng: np.random.Generator, airspeed: float, coefficients: dict[str, float], charge_ah: float,
    throttle_curve: float = 1.0,
):
    """Throttle 0 -> 100 % then down in 10 % steps to 10 %, then 0 (paper section 3).

    Returns the columns and the charge drawn from each pack by the end of the run.
    """
    levels = [0.0, *np.round(np.arange(1.0, 0.05, -0.1), 1), 0.0]
    durations = [1.5, *(STEP_S + rng.uniform(-0.4, 0.4, len(levels) - 2)), 2.0]
    edges = np.concatenate(([0.0], np.cumsum(durations)))
    t = np.arange(0.0, edges[-1], 1.0 / SAMPLE_RATE_HZ)
    throttle = np.asarray(levels)[np.searchsorted(edges, t, side="right") - 1]
    true_v, measured_v = tunnel_airspeed(rng, airspeed, t)
    force, volts, amps, charge_ah = rig_response(
        rng, t, throttle, true_v, coefficients, charge_ah, throttle_curve
    )
    volts = volts + rng.normal(0.0, ELECTRICAL_NOISE["voltage_v"], t.size)
    amps = amps + rng.normal(0.0, ELECTRICAL_NOISE["current_a"], t.size)
    columns = {
        "time_s": t,
        "force_n": force,
        "airspeed_m_s": measured_v,
        "throttle": throttle,
        "voltage_v": volts,
        "current_a": amps,
    }
    return columns, charge_ah


def sweep_run(rng: np.random.Generator, airspeed: float, coefficients: dict[str, float]):
    """Throttle sine sweep 25-75 %, frequency rising linearly from 0.2 to 5 Hz (section 3)."""
    lead, sweep, tail = 3.0, 30.0, 2.0
    t = np.arange(0.0, 1.0 + lead + sweep + tail, 1.0 / SAMPLE_RATE_HZ)
    f0, f1 = 0.2, 5.0
    ts = np.clip(t - 1.0 - lead, 0.0, sweep)
    phase = 2 * np.pi * (f0 * ts + 0.5 * (f1 - f0) / sweep * ts * ts)
    throttle = np.where(t < 1.0, 0.0, 0.5 + 0.25 * np.sin(phase))
    throttle[t > 1.0 + lead + sweep] = 0.5
    true_v, measured_v = tunnel_airspeed(rng, airspeed, t)
    force = rig_response(rng, t, throttle, true_v, coefficients, SWEEP_CHARGE_AH)[0]
    return {"time_s": t, "force_n": force, "airspeed_m_s": measured_v, "throttle": throttle}


def drag_run(rng: np.random.Generator):
    """Bare structure (no fan): tunnel speed held at 0, ramped to 30 m/s, held."""
    t = np.arange(0.0, 18.0, 1.0 / SAMPLE_RATE_HZ)
    nominal = np.clip((t - 3.0) / 12.0, 0.0, 1.0) * 30.0
    true_v, measured_v = tunnel_airspeed(rng, nominal, t)
    force = -structure_drag_n(true_v) + rng.normal(0.0, 0.08, t.size) + 0.3 * spikes(rng, t.size)
    return {"time_s": t, "force_n": force, "airspeed_m_s": measured_v, "throttle": 0.0 * t}


def write_run(path: Path, columns: dict[str, np.ndarray]) -> None:
    columns = quantise(columns)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".mat":
        scipy.io.savemat(path, columns, do_compression=True, oned_as="column")
        # the v5 header's 116 text bytes carry a creation date: fix them, for
        # byte-identical files on every run
        data = bytearray(path.read_bytes())
        data[:116] = MAT_HEADER.ljust(116).encode("ascii")
        path.write_bytes(bytes(data))
        return
    text = io.StringIO()
    text.write(",".join(columns) + "\n")
    digits = {
        "time_s": 3, "force_n": 2, "airspeed_m_s": 2, "throttle": 3, "voltage_v": 2,
        "current_a": 1,
    }
    matrix = np.column_stack(list(columns.values()))
    formats = [f"%.{digits[name]}f" for name in columns]
    np.savetxt(text, matrix, fmt=formats, delimiter=",")
    data = text.getvalue().replace("nan", "NaN").encode()
    if path.name.endswith(".gz"):
        path.write_bytes(gzip.compress(data, compresslevel=9, mtime=0))
    else:
        path.write_bytes(data)


def main(out: Path = OUT, seed: int = SEED, throttle_curve: dict[str, float] | None = None,
         steps_only: bool = False) -> None:
    """Write the campaign to ``out``. The shipped one: the defaults. ``throttle_curve`` per
    engine (rpm ~ x^curve) and ``steps_only`` (no sweeps, no drag run) make the harsh
    campaigns the tests fit (issue 43 item 4)."""
    curves = throttle_curve or {}
    truth = truth_coefficients()
    runs: list[dict[str, str]] = []
    counter = 0

    def rng_for() -> np.random.Generator:
        nonlocal counter
        counter += 1
        return np.random.default_rng([seed, counter])

    charge_log: dict[str, list[float]] = {}
    for engine, ext in (("EDF1", ".csv.gz"), ("EDF2", ".mat")):
        charge = 0.0
        for v in AIRSPEEDS_M_S:
            rng = rng_for()
            name = f"runs/{engine.lower()}_v{v:04.1f}".replace(".", "p") + ext
            if v == PACK_CHANGE_AIRSPEED_M_S:
                charge = 0.0  # the paper's pack change before the last run
            charge_log.setdefault(engine, []).append(round(charge, 4))
            columns, charge = step_run(rng, v, truth[engine], charge, curves.get(engine, 1.0))
            add_nans(rng, columns, int(rng.integers(0, 6)))
            write_run(out / name, columns)
            runs.append({"file": name, "engine": engine, "kind": "throttle_steps"})
    for engine, ext in (("EDF1", ".mat"), ("EDF2", ".csv.gz"))[: 0 if steps_only else 2]:
        for v in SWEEP_AIRSPEEDS_M_S:
            rng = rng_for()
            name = f"runs/{engine.lower()}_sweep_v{v:02.0f}{ext}"
            write_run(out / name, sweep_run(rng, v, truth[engine]))
            runs.append({"file": name, "engine": engine, "kind": "sine_sweep"})
    if not steps_only:
        write_run(out / "runs/structure_drag.csv", drag_run(rng_for()))
        runs.append({"file": "runs/structure_drag.csv", "kind": "drag_sweep"})

    manifest = [
        "# Synthetic TU-Flex test campaign; written by scripts/generate_campaign.py (seeded).",
        "# Ground truth in truth.yaml; provenance in data/README.md (Test campaign).",
        "name: TU-Flex EDF wind-tunnel campaign (synthetic)",
        f"fan_area_m2: {FAN_AREA_M2:.6f}        # 93 mm fan (paper Table 1)",
        f"tunnel_area_m2: {TUNNEL_AREA_M2}            # 400 mm x 400 mm open jet (paper 2.1)",
        # the test day's density, so that the fitted file lapses with altitude like the
        # shipped one (without it the fit is used as measured at every density, SPEC 3)
        f"air_density_kg_m3: {AIR_DENSITY_KG_M3}     # the truth's (truth.yaml)",
        "runs:",
    ]
    for run in runs:
        fields = ", ".join(f"{key}: {value}" for key, value in run.items())
        manifest.append(f"  - {{{fields}}}")
    (out / "campaign.yaml").write_text("\n".join(manifest) + "\n", encoding="utf-8")

    truth_doc = {
        "note": "Ground truth of the synthetic campaign (scripts/generate_campaign.py); "
        "not an input of fit.",
        "seed": seed,
        "sample_rate_hz": SAMPLE_RATE_HZ,
        "delay_s": DELAY_S,
        "spool_lag_s": SPOOL_LAG_S,
        "reference_voltage_v": REFERENCE_VOLTAGE_V,
        "voltage_exponent": VOLTAGE_EXPONENT,
        "packs_in_parallel": PACKS_IN_PARALLEL,
        "pack_resistance_ohm": PACK_RESISTANCE_OHM,
        "jet_area_m2": JET_AREA_M2,
        "fan_efficiency": FAN_EFFICIENCY,
        "idle_current_a": IDLE_CURRENT_A,
        "start_charge_ah_per_pack": charge_log,
        "air_density_kg_m3": AIR_DENSITY_KG_M3,
        "structure_cda_m2": STRUCTURE_CDA_M2,
        "perturbation": PERTURBATION,
        "engines": [{"name": name, "coefficients": c} for name, c in truth.items()],
    }
    if curves:
        truth_doc["throttle_curve"] = curves
    (out / "truth.yaml").write_text(yaml.safe_dump(truth_doc, sort_keys=False), encoding="utf-8")
    total = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    print(f"wrote {len(runs)} runs to {out} ({total / 1e6:.2f} MB)")


if __name__ == "__main__":
    main()
