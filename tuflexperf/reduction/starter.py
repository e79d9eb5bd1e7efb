"""``tuflexperf init``: a commented starter case that ``check`` runs at once, or a copy of
the shipped example. Nothing already in the folder is overwritten (SPEC 5, nothing lost).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tuflexperf.errors import InputError
from tuflexperf.io.datasheet import (
    CUTOFF_V_PER_CELL,
    RUN_THROTTLES,
    DatasheetSchema,
    StarterModel,
    starter_model,
)

EXAMPLES = ("tuflex",)


@dataclass(frozen=True)
class InitResult:
    """What ``init`` wrote: the folder, its files (in writing order), the case to check."""

    folder: Path
    files: tuple[Path, ...]
    case: Path
    model: StarterModel | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"folder": str(self.folder), "case": str(self.case),
                               "files": [str(f) for f in self.files]}
        if self.model is not None:
            m = self.model
            out["datasheet"] = {
                **m.sheet.model_dump(), "fan_area_m2": m.fan_area_m2,
                "jet_velocity_m_s": m.jet_velocity_m_s, "figure_of_merit": m.figure_of_merit,
                "thrust_coefficients": m.thrust, "power_coefficients": m.power,
                "thrust_sd_n": m.thrust_sd_n, "power_rmse_w": m.power_rmse_w,
                "resistance_per_cell_ohm": m.resistance_per_cell_ohm,
                "resistance_source": m.resistance_source,
                "packs_in_parallel_per_engine": m.packs_in_parallel,
            }
        return out


def refuse_existing(folder: Path, names: list[str]) -> None:
    """Bad input naming the first of ``names`` (relative to ``folder``) that exists already."""
    if folder.exists() and not folder.is_dir():
        raise InputError(f"DIR: {folder} exists and is not a folder")
    for name in names:
        if (folder / name).exists() or (folder / name).is_symlink():
            raise InputError(f"{folder / name}: exists already; init writes only new files "
                             "(give an empty or new folder)")


def copy_example(folder: Path, example: str) -> InitResult:
    """The shipped example ``example`` (its case and data) copied into ``folder``."""
    from tuflexperf.io.case import shipped_case_path
    from tuflexperf.io.files import write_files_atomically

    if example not in EXAMPLES:
        raise InputError(f"--example: unknown example {example!r} (known: {', '.join(EXAMPLES)})")
    root = shipped_case_path().parent.parent  # holds requirements/ and data/
    sources = sorted(p for top in ("requirements", "data") for p in (root / top).rglob("*")
                     if p.is_file() and "__pycache__" not in p.parts)
    names = [p.relative_to(root).as_posix() for p in sources]
    refuse_existing(folder, names)
    write_files_atomically({folder / name: src.read_bytes()
                            for name, src in zip(names, sources, strict=True)})
    return InitResult(folder, tuple(folder / n for n in names),
                      folder / "requirements" / "tuflex.yaml")


def write_starter(folder: Path, sheet: DatasheetSchema, from_datasheet: bool) -> InitResult:
    """The starter case, aircraft, propulsion (from ``sheet``), battery with its stand-in
    discharge runs and fitted circuit, written into ``folder`` (all or nothing)."""
    from tuflexperf.io.datasheet import discharge_run_csv
    from tuflexperf.io.files import write_files_atomically
    from tuflexperf.reduction.battery import fitted_battery_text

    model = starter_model(sheet)
    runs = {f"endurance/run_{round(100 * x):d}.csv": discharge_run_csv(model, x)
            for x in RUN_THROTTLES}
    texts = {"case.yaml": case_text(model), "aircraft.yaml": AIRCRAFT_TEXT,
             "propulsion.yaml": propulsion_text(model, from_datasheet)}
    names = [*texts, "battery.yaml", *runs]
    refuse_existing(folder, names)
    with tempfile.TemporaryDirectory(prefix="tuflexperf-init-") as scratch:
        work = Path(scratch)
        for name, text in runs.items():
            (work / name).parent.mkdir(parents=True, exist_ok=True)
            (work / name).write_text(text, encoding="utf-8")
        (work / "battery.yaml").write_text(battery_text(model, list(runs)), encoding="utf-8")
        fitted, _ = fitted_battery_text(work / "battery.yaml", work / "battery.yaml")
    # the starter is the user's file to edit, not fit's output: fit's first line goes
    texts["battery.yaml"] = fitted.split("\n", 1)[1]
    write_files_atomically({folder / n: t for n, t in {**texts, **runs}.items()})
    return InitResult(folder, tuple(folder / n for n in names), folder / "case.yaml", model)


def _g(value: float) -> str:
    return f"{value:.6g}"


def _q(text: str) -> str:
    """``text`` as a double-quoted YAML scalar (a name may hold a colon or a bracket)."""
    import json

    return json.dumps(text)


def case_text(m: StarterModel) -> str:
    """The starter case: its files and requirements, endurance included (OEI with two or
    more engines)."""
    oei = ("  oei: {dead_engine: windmilling, max_throttle: 1.0}   # one engine out, level "
           "flight\n" if m.sheet.engines >= 2 else "")
    return f"""\
# Starter case written by `tuflexperf init`: edit every value for your aircraft.
# Run it with `tuflexperf check case.yaml`; docs/formats.md lists every key.
name: {_q(f"My aircraft, {m.sheet.engines} x {m.sheet.name}")}
aircraft: aircraft.yaml          # paths relative to this file
propulsion: propulsion.yaml
battery: battery.yaml
atmosphere: {{altitude_m: 0, temperature_offset_k: 0}}   # ISA day at the airfield
requirements:
  takeoff: {{max_ground_roll_m: 40}}                      # runway length you have [m]
  envelope: {{min_airspeed_m_s: 14, max_airspeed_m_s: 30, max_trim_throttle: 1.0}}  # EAS
{oei}  endurance: {{throttle: 0.5, min_flight_time_min: 10}}  # flight time at this throttle
"""


#: The starter aircraft: typical values of a 5 kg two-fan jet model, each to be replaced.
AIRCRAFT_TEXT = """\
# Starter aircraft written by `tuflexperf init`: typical values of a 5 kg ducted-fan
# model, NOT your aircraft's. Replace each one; units in the key names.
name: My aircraft
mass_kg: 5.0             # take-off mass with the packs
wing_area_m2: 0.55       # reference wing area
cd0: 0.030               # zero-lift drag coefficient (clean jet model 0.025-0.035)
k: 0.050                 # induced-drag factor 1/(pi e AR): AR 8, e 0.8
cl_max: 1.3              # maximum lift coefficient (no flaps 1.2-1.4)
takeoff:
  cl_ground: 0.4         # lift coefficient in the ground-roll attitude
  rolling_friction: 0.04 # paved 0.02-0.04, short grass 0.05-0.07
"""


def propulsion_text(m: StarterModel, from_datasheet: bool) -> str:
    """The fans' thrust and power poly22 surfaces from momentum theory (io.datasheet)."""
    s = m.sheet
    where = "your datasheet" if from_datasheet else "typical values of a 70 mm fan (edit)"
    t, p = m.thrust, m.power
    engines = "".join(f"""\
  - name: EDF{i + 1}
    coefficients: {{p00: {_g(t['p00'])}, p10: {_g(t['p10'])}, p01: {_g(t['p01'])}, \
p20: {_g(t['p20'])}, p11: {_g(t['p11'])}, p02: {_g(t['p02'])}}}
    residual_sd_n: {_g(m.thrust_sd_n)}      # stated uncertainty (1 sd), see above
    extrapolation_sd_n: {_g(m.thrust_sd_n)}
    extrapolation_distance_m_s: 2.5  # the stated sd per 2.5 m/s beyond (a tunnel step)
    power:
      model: poly22
      coefficients: {{p00: {_g(p['p00'])}, p10: {_g(p['p10'])}, p01: {_g(p['p01'])}, \
p20: {_g(p['p20'])}, p11: {_g(p['p11'])}, p02: {_g(p['p02'])}}}
      rmse_w: {_g(m.power_rmse_w)}
""" for i in range(s.engines))
    return f"""\
# Starter propulsion written by `tuflexperf init` from {where}:
#   static thrust {_g(s.static_thrust_n)} N and electrical power {_g(s.max_power_w)} W per fan
#   at full throttle, fan diameter {_g(s.fan_diameter_m)} m (area {m.fan_area_m2:.5g} m^2).
# NOT MEASURED. Thrust by momentum theory, the jet at x V_j at throttle x:
#   T = T0 x^2 - (T0/V_j) x V, V_j = sqrt(T0/(rho A)) = {m.jet_velocity_m_s:.4g} m/s
#   (figure of merit of the datasheet: ideal power {m.figure_of_merit:.2f} x its electrical power).
# Stated uncertainty: 1 sd = {_g(100 * m.thrust_sd_n / s.static_thrust_n)} % of the static thrust
#   (a datasheet's own range is ~ +-18 %).
# Power: fan affinity laws, P = Pmax x^3 (1 - (V/V_j)^2), as a poly22 fitted up to
#   {m.power_fit_top_m_s:.3g} m/s (rmse_w); P(1, 0) = Pmax exactly.
# Replace this file with `tuflexperf fit` of your tunnel or thrust-stand runs.
name: {_q(s.name)}
model: poly22            # T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2 (x fraction, v m/s)
tested_airspeed_m_s: [0, 1]   # a datasheet is a static test: above 1 m/s it is momentum theory
reference_density_kg_m3: {m.density_kg_m3:g}   # ISA sea level, the datasheet's assumed air
format: 2                # fan_area_m2 is the disk area (docs/formats.md)
fan_area_m2: {m.fan_area_m2:.6g}
engines:
{engines}"""


def battery_text(m: StarterModel, runs: list[str]) -> str:
    """The pack from its datasheet, with stand-in discharge runs of its circuit."""
    s = m.sheet
    resistance = (f"{1000 * m.resistance_per_cell_ohm:.3g} mOhm per cell from "
                  + ("the datasheet" if s.internal_resistance_ohm_per_cell is not None
                     else m.resistance_source))
    listed = "".join(f"  - {{file: {r}, engine: EDF1}}\n" for r in runs)
    return f"""\
# Starter battery written by `tuflexperf init` from the pack's datasheet: {s.cells} cells,
# {_g(s.capacity_ah)} Ah, {_g(s.c_rating)}C; internal resistance {resistance}.
# NOT MEASURED: the runs below are stand-ins, discharges of the datasheet's equivalent
# circuit (tuflexperf/io/datasheet.py) at constant power on a static stand, until your
# tunnel runs replace them (then `tuflexperf fit battery.yaml --out battery_fit.yaml`).
name: {_q(f"{s.cells}S {_g(s.capacity_ah)} Ah {_g(s.c_rating)}C pack")}
cells_in_series: {s.cells}
capacity_ah: {_g(s.capacity_ah)}
max_discharge_c: {_g(s.c_rating)}
packs_in_parallel_per_engine: {m.packs_in_parallel}   # enough for full power within the C rating
cutoff_voltage_per_cell_v: {CUTOFF_V_PER_CELL:g}     # the usual ESC cut-off under load
runs:
{listed}fan_power:               # the datasheet's numbers, +-10 % as a published range
  published_power_range_w: [{_g(0.9 * s.max_power_w)}, {_g(1.1 * s.max_power_w)}]
  published_static_thrust_range_n: [{_g(0.9 * s.static_thrust_n)}, {_g(1.1 * s.static_thrust_n)}]
  jet_velocity_m_s: {m.jet_velocity_m_s:.4g}       # momentum theory, sqrt(T0/(rho A))
mission:
  pattern_altitude_m: 100           # circuit height
  landing_reserve_fraction: 0.2     # the usual LiPo "80 % rule"
"""

