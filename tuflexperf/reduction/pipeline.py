"""``tuflexperf fit``: campaign manifest or thrust table -> propulsion file (paper section 4).

Campaign path, in the paper's order:

1. read every run (CSV, gzip CSV or .mat; a few NaN samples repaired and reported);
2. sine sweeps -> dead time and spool lag per run (:mod:`.delay`), one mean delay;
3. bare-structure velocity sweeps -> structure drag ``D(V)`` (:mod:`.drag`);
4. throttle-step runs -> outliers filled (2 s moving mean, 1.5 local standard
   deviations), moving median, change points in the force cross-checked against
   the logged throttle steps, transients left out, steady segment means
   (:mod:`.filters`, :mod:`.changepoints`, :mod:`.segments`);
5. thrust = force + D(V); Glauert blockage ratio per point (:mod:`.glauert`),
   applied to the airspeed only when asked;
6. poly22 per engine by ordinary least squares (:mod:`.poly22fit`), and each run's
   validation error: the model (minus structure drag) against the measured force
   over the run's steady segments, as mean negative / mean positive error;
7. where the step runs log ``voltage_v`` and ``current_a`` (:mod:`.power`): the voltage
   exponent (thrust brought to the reference voltage before step 6 when the runs determine
   it) and the electrical power surface per engine; with or without them, the windmilling
   drag coefficient from the throttle-0 holds on the disk area ``fan_area_m2``, said per
   engine in the output (or why none).

Outputs are rendered in memory, the propulsion file is validated against the
schema ``check`` uses, and only then are files written, atomically.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.files import sealed, sha256_of, write_files_atomically
from tuflexperf.io.inputs import path_text
from tuflexperf.io.runs import (
    REFIT_TABLE_EXTRA_COLUMNS,
    ThrustTable,
    read_thrust_table,
    render_thrust_table,
)
from tuflexperf.reduction.campaign_fit import fit_campaign
from tuflexperf.reduction.delay import MAX_DELAY_S
from tuflexperf.reduction.fit_checks import (
    MIN_SET_POINTS,
    poor_fit_notes,
    refuse_unphysical_fit,
    set_point,
    speeds_by_engine,
)
from tuflexperf.reduction.fit_output import FitResult, fit_summary, render_propulsion
from tuflexperf.reduction.lack_of_fit import engine_lack_of_fit, lack_of_fit_note
from tuflexperf.reduction.poly22fit import fit_poly22
from tuflexperf.reduction.step_runs import Progress


def fit_table(path: Path | str, delay_s: float | None = None) -> FitResult:
    """Fit the poly22 per engine to a thrust table alone (no reduction).

    ``path`` is a thrust table (SPEC 4) or a propeller-table manifest (UIUC / APC PER3 files,
    :mod:`tuflexperf.io.proptables`), converted to the same points.
    """
    from tuflexperf.io.proptables import is_propeller_manifest, read_propeller_tables

    manifest = is_propeller_manifest(Path(path))
    table: ThrustTable = read_propeller_tables(path) if manifest else read_thrust_table(path)
    for engine in table.engines():
        # a surface in airspeed needs airspeeds: as a campaign's step runs must cover three
        # set points, a table's rows must (counted at the set-point resolution)
        points = {set_point(float(v)) for v in table.select(engine)[1]}
        if len(points) < MIN_SET_POINTS:
            raise InputError(
                f"{table.path}: {engine}: the rows cover only {len(points)} airspeed set "
                f"point(s); a poly22 surface needs at least {MIN_SET_POINTS}"
            )
    fits = {
        engine: fit_poly22(*table.select(engine), label=f"{table.path}: engine {engine}")
        for engine in table.engines()
    }
    refuse_unphysical_fit(str(table.path), fits)
    # a table holds no samples: only repeated rows (same throttle and set point) test the fit
    lack = {engine: engine_lack_of_fit(x, v, t, [set_point(float(s)) for s in v])
            for engine in table.engines() for x, v, t in [table.select(engine)]}
    speeds = speeds_by_engine(zip(table.engine, table.airspeed_m_s, strict=True))
    source = {
        "tool": "tuflexperf fit",
        "input": path_text(Path(path).resolve()),
        "input_sha256": sha256_of(Path(path)),
    }
    summary = fit_summary(kind="table", input_path=Path(path), fits=fits, delay=delay_s,
                          speeds=speeds, lack_of_fit=lack)
    summary["warnings"].extend(poor_fit_notes(fits))
    summary["warnings"].extend(note for engine, result in lack.items() if result is not None
                               for note in [lack_of_fit_note(engine, result)] if note)
    propulsion = render_propulsion(
        name=f"poly22 fit of {path_text(Path(path).name)}",
        fits=fits,
        speeds=speeds,
        delay=delay_s,
        density=None,
        source=source,
        lack_of_fit=lack,
    )
    rows = []
    for e, x, v, t in zip(table.engine, table.throttle, table.airspeed_m_s, table.thrust_n,
                          strict=True):
        fitted = float(np.ravel(fits[e].predict(x, v))[0])
        rows.append({"engine": e, "throttle": x, "airspeed_m_s": v, "thrust_n": t,
                     "fitted_thrust_n": fitted, "residual_n": float(t) - fitted})
    return FitResult(
        summary=summary,
        propulsion_text=propulsion,
        table_text=render_thrust_table(rows, REFIT_TABLE_EXTRA_COLUMNS),
        engines=fits,
    )


def _fit_inputs(input_path: Path) -> list[Path]:
    """Every file ``fit`` reads: the input and, for a campaign, each run file it names."""
    inputs = [input_path]
    if is_thrust_table(input_path):
        return inputs
    from tuflexperf.io.yamlio import read_yaml

    data = read_yaml(input_path)
    if isinstance(data, dict) and {"aircraft", "propulsion"} <= set(data):
        raise InputError(
            f"{input_path}: this is a case (requirement) file, not a campaign manifest or "
            "thrust table; give fit a campaign.yaml or a thrust-table .csv"
        )
    if isinstance(data, dict) and isinstance(data.get("runs"), list):
        for entry in data["runs"]:
            name = entry.get("file") if isinstance(entry, dict) else None
            # a name the OS cannot take is refused by the manifest's schema, naming it
            if isinstance(name, str) and "\x00" not in name:
                inputs.append(input_path.parent / name)
    return inputs


def is_battery_file(path: Path) -> bool:
    """A battery file (SPEC 4): a YAML mapping whose keys are more a battery file's than a
    campaign manifest's (so that a misspelt ``cells_in_series`` is still told apart, and
    named with the closest key, rather than read as a manifest with a dozen unknown keys)."""
    if is_thrust_table(path):
        return False
    from tuflexperf.io.battery import BatterySchema
    from tuflexperf.io.campaign import CampaignSchema
    from tuflexperf.io.yamlio import read_yaml

    data = read_yaml(path)
    if not isinstance(data, dict):
        return False
    keys = set(map(str, data))
    battery, campaign = set(BatterySchema.model_fields), set(CampaignSchema.model_fields)
    return len(keys & battery) > len(keys & campaign)


def _fit_battery(path: Path, out: Path, table: Path | None, glauert: bool,
                 delay_s: float | None, propulsion: Path | None = None) -> dict[str, Any]:
    """``fit BATTERY.yaml``: the pack model fitted to the file's discharge runs, written back."""
    from tuflexperf.reduction.battery import fitted_battery_text

    # a flag the pack fit has no use for is refused, not ignored
    given = [flag for flag, used in (("--table", table is not None), ("--glauert", glauert),
                                     ("--delay-s", delay_s is not None)) if used]
    if given:
        raise InputError(f"{given[0]}: not for a battery file (it fits the pack model alone)")
    if propulsion is not None and not Path(propulsion).is_file():
        from tuflexperf.io.files import why_not_a_file

        raise InputError(f"--propulsion: {why_not_a_file(Path(propulsion))}: {propulsion}")
    text, block = fitted_battery_text(path, out, propulsion)
    write_files_atomically({out: sealed(text)})
    return {"kind": "battery", "input": str(path), "out": str(out), "table": None,
            "battery_fit": block}


def _check_output(path: Path, flag: str) -> None:
    if str(path) == "-":  # the shell's "stdout": fit writes files, and JSON with --json
        raise InputError(f"{flag}: '-' (stdout) is no file name; give a file, and --json for "
                         "the summary on stdout")
    if path.is_dir():
        raise InputError(f"{flag}: {path} is a directory, expected a file name")


def is_thrust_table(path: Path) -> bool:
    """A ``.csv`` input is a thrust table (a ``.csv.gz`` one is told to unpack it); anything
    else is a campaign manifest."""
    return path.name.lower().endswith((".csv", ".csv.gz"))


def default_table_path(out: Path) -> Path:
    """Where the campaign's thrust table goes without ``--table``: beside ``--out``."""
    return out.with_name(f"{out.stem}_thrust_table.csv")


def run_fit(
    input_path: Path,
    out: Path,
    table: Path | None = None,
    glauert: bool = False,
    delay_s: float | None = None,
    progress: Progress | None = None,
    propulsion: Path | None = None,
) -> dict[str, Any]:
    """The ``fit`` command: compute, validate, then write ``out`` (and the table).

    ``propulsion`` (battery files only): the propulsion file whose power model the measured
    power correction is fitted against (default: ``propulsion.yaml`` beside the battery).
    Returns the JSON summary, with ``out`` and ``table`` set to the files written.
    """
    input_path = Path(input_path)
    if not input_path.exists():
        raise InputError(f"{input_path}: file not found")
    if input_path.is_dir():
        raise InputError(f"{input_path}: is a directory, expected campaign.yaml or a table .csv")
    if delay_s is not None and not (math.isfinite(delay_s) and delay_s >= 0):
        raise InputError(f"--delay-s: must be a finite number >= 0, got {delay_s}")
    if delay_s is not None and delay_s > MAX_DELAY_S:
        # a dead time past every throttle plateau would leave no steady data to fit
        raise InputError(f"--delay-s: {delay_s:.10g} s is beyond {MAX_DELAY_S:g} s, the longest "
                         "delay the reduction knows (an EDF answers within tens of ms)")
    out = Path(out)
    _check_output(out, "--out")
    from tuflexperf.io.files import guard_outputs
    from tuflexperf.io.proptables import is_propeller_manifest

    inputs = _fit_inputs(input_path)
    battery = is_battery_file(input_path)
    if battery:  # the power model the correction is fitted against is read too
        beside = input_path.parent / "propulsion.yaml"
        inputs += [p for p in (propulsion, beside) if p is not None and Path(p).is_file()]
    guard_outputs({"--out": out}, inputs, "fit",
                  {"--out": "battery file" if battery else "propulsion file"})
    if battery:
        return _fit_battery(input_path, out, table, glauert, delay_s, propulsion)
    if propulsion is not None:
        raise InputError("--propulsion: only for a battery file (the power model its measured "
                         "power correction is fitted against)")

    if is_thrust_table(input_path) or is_propeller_manifest(input_path):
        if glauert:
            raise InputError("--glauert: needs a campaign (fan and tunnel areas), not a table")
        result = fit_table(input_path, delay_s)
    else:
        result = fit_campaign(input_path, glauert=glauert, delay_s=delay_s, progress=progress)
        if table is None:
            table = default_table_path(out)
    files = {out: sealed(result.propulsion_text)}
    if table is not None:
        table = Path(table)
        _check_output(table, "--table")
        if table.resolve() == out.resolve():
            raise InputError("--table: must differ from --out")
        guard_outputs({"--out": out, "--table": table}, inputs, "fit",
                      {"--out": "propulsion file", "--table": "thrust table"})
        if result.table_text is not None:
            files[table] = result.table_text
    write_files_atomically(files)
    summary = result.summary
    summary["out"] = str(out)
    summary["table"] = str(table) if table is not None else None
    return summary
