"""Reading wind-tunnel run files (CSV or MATLAB .mat) and thrust tables (SPEC 4).

Their columns: docs/formats.md, "Run files" and "Thrust table". Every problem is an
:class:`~tuflexperf.errors.InputError` naming the file and the column. A few NaN samples (at
most :data:`MAX_NAN_FRACTION` of a column) are tolerated: in ``time_s`` their rows are
dropped, elsewhere they are linearly interpolated in time; both are reported.
"""

from __future__ import annotations

import csv
import io
import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.errors import InputError
from tuflexperf.io.vendor import (
    VendorSettings,
    numeric_cells,
    read_vendor_columns,
    repeated_columns,
    repeated_header_error,
)
from tuflexperf.models.aircraft import MAX_AIRSPEED_M_S

RUN_COLUMNS: tuple[str, ...] = ("time_s", "force_n", "airspeed_m_s", "throttle")
KNOWN_OPTIONAL: tuple[str, ...] = ("voltage_v", "current_a", "rpm")
"""Columns any run may carry (SPEC 4), read and repaired like the required ones."""
TABLE_COLUMNS: tuple[str, ...] = ("engine", "throttle", "airspeed_m_s", "thrust_n")
# what fit's thrust table from a campaign adds after them (the reduction's diagnostics)
TABLE_EXTRA_COLUMNS: tuple[str, ...] = (
    "airspeed_measured_m_s", "force_n", "drag_n", "force_std_n", "n_samples", "glauert_ratio",
    "run", "thrust_at_voltage_n", "voltage_v", "current_a", "electrical_power_w",
    "ideal_power_w", "figure_of_merit", "overall_efficiency",
)
# what fit's thrust table refitted from a table adds: the model at each row and the misfit
# (also what tells that table from a user's own four-column one: the output guard)
REFIT_TABLE_EXTRA_COLUMNS: tuple[str, ...] = ("fitted_thrust_n", "residual_n")
MAX_MAGNITUDE = 1e9  # no force, airspeed, voltage or current of a thrust stand comes near it
# A logged pack voltage outside this range is no pack's [V]: one cell is 3-4.2 V, the
# largest electric-aircraft packs ~800 V
MIN_PACK_VOLTAGE_V = 1.0
MAX_PACK_VOLTAGE_V = 1000.0
MAX_PACK_CURRENT_A = 2000.0  # a median current beyond this is no ducted fan's [A]
STATIC_AIRSPEED_NOISE_M_S = 0.5  # a thrust table's airspeed may dip this far below 0 at rest
# a run's median airspeed this far below 0 is a flipped sign, not a pitot's zero offset at rest
# (a signed root of a slightly negative dynamic pressure reads -0.6 m/s on a real rig)
BACKWARDS_RUN_AIRSPEED_M_S = 2.0
MAX_NAN_FRACTION = 0.01
"""Largest share of NaN samples per column that is repaired rather than refused."""
MIN_SAMPLE_INTERVAL_S = 1e-10
"""The shortest median sample interval [s] of a run: no balance logs at 10 GHz (a run logged
in microseconds, 1e-9 s apart, reads and is named as giving no test point)."""
MAX_SAMPLE_INTERVAL_S = 3600.0
"""The longest [s]: a run logged once an hour measures no step, sweep or discharge."""
MIN_SAMPLES = 10
THROTTLE_TOLERANCE = 0.05
"""A logged throttle may overshoot [0, 1] by this much (PWM rounding); beyond it is an error."""


@dataclass(frozen=True)
class Run:
    """One run file's columns as float arrays (SI units) and what was repaired."""

    path: Path
    time_s: NDArray[np.float64]
    columns: dict[str, NDArray[np.float64]]
    sample_rate_hz: float
    nan_samples: dict[str, int] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        return self.columns[name]

    @property
    def n_samples(self) -> int:
        return int(self.time_s.size)

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0])


def _suffix(path: Path) -> str:
    name = path.name.lower()
    for suffix in (".csv.gz", ".csv", ".mat"):
        if name.endswith(suffix):
            return suffix
    return path.suffix.lower()


class _TooLarge(Exception):
    """A compressed run that unpacks to more than the run size cap."""


class _BoundedReader:
    """A gzip stream that stops at ``limit`` unpacked bytes (a 9 MB bomb unpacks to 6 GB):
    the cap of a plain run file holds for what the compressed one holds."""

    def __init__(self, path: Path, limit: int) -> None:
        import gzip

        self._stream = gzip.open(path, "rb")
        self._left = limit

    def read(self, size: int = -1) -> bytes:
        data = self._stream.read(size if size is not None and size >= 0 else self._left + 1)
        self._left -= len(data)
        if self._left < 0:
            raise _TooLarge
        return data

    def __iter__(self) -> Any:  # pandas asks whether it may iterate
        raise io.UnsupportedOperation

    def close(self) -> None:
        self._stream.close()


def _first_line(path: Path) -> str:
    """The first line of a (possibly gzipped) text file, at most 64 KiB of it ('' if none)."""
    import gzip

    try:
        opener: Any = gzip.open if path.name.lower().endswith(".gz") else open
        with opener(path, "rb") as handle:
            return handle.readline(1 << 16).decode("utf-8", errors="replace")
    except (OSError, EOFError, zlib.error):
        return ""


def _refuse_header(path: Path, header: str, semicolons: bool) -> None:
    # binary bytes (NUL, not UTF-8) are no header (a Latin-1 degree sign is one bad byte in
    # a header, not a tenth of it)
    if "\x00" in header or header.count("\ufffd") > 0.1 * len(header):
        raise InputError(f"{path}: holds binary bytes, not text: a run file is comma-separated "
                         "text (CSV) with a header row, or a .csv.gz / .mat of one")
    # a continental-European export (and its decimal commas), named as such
    if semicolons:
        raise InputError(f"{path}: the header's columns are separated by ';'; a run file is "
                         "comma-separated (CSV), with decimal points")


def _read_csv_columns(path: Path) -> tuple[dict[str, np.ndarray], dict[str, tuple[int, str]]]:
    """Numeric columns, and for each column with a non-numeric cell its (line, text)."""
    import pandas as pd

    from tuflexperf.io.inputs import MAX_RUN_BYTES

    source: Any = path
    if path.name.lower().endswith(".gz"):
        source = _BoundedReader(path, MAX_RUN_BYTES)
    try:
        frame = pd.read_csv(source, compression=None if source is not path else "infer",
                            skipinitialspace=True)
    except _TooLarge:
        raise InputError(f"{path}: unpacks to more than {MAX_RUN_BYTES >> 30} GiB, the "
                         "largest run file read") from None
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: empty file (expected a header row and data)") from None
    except zlib.error as exc:  # a damaged compressed body: it raised past every handler
        raise InputError(f"{path}: corrupt gzip data ({exc})") from None
    except (pd.errors.ParserError, UnicodeDecodeError, OSError, EOFError, ValueError) as exc:
        header = _first_line(path)
        _refuse_header(path, header, ";" in header)
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{path}: cannot read as CSV: {first}") from None
    finally:
        if source is not path:
            source.close()
    _refuse_header(path, " ".join(map(str, frame.columns)),
                   frame.shape[1] == 1 and ";" in str(frame.columns[0]))
    repeated = repeated_columns(frame.columns)
    for name in (*RUN_COLUMNS, *KNOWN_OPTIONAL):
        if name in repeated:
            raise repeated_header_error(path, name)
    names = [str(c).strip() for c in frame.columns]
    columns: dict[str, np.ndarray] = {}
    bad_cells: dict[str, tuple[int, str]] = {}
    # by position: 'note' and 'note ' are two columns of one name once stripped
    for index, name in enumerate(names):
        raw = frame.iloc[:, index]
        if raw.dtype.kind in "biuf":
            columns[name] = raw.to_numpy(dtype=float)
            continue
        values, bad = numeric_cells(raw)
        if bad is not None:
            bad_cells[name] = bad  # only an error if the column is needed
        else:
            columns[name] = values
    return columns, bad_cells


def _read_mat_columns(path: Path) -> tuple[dict[str, np.ndarray], dict[str, tuple[int, str]]]:
    import scipy.io

    from tuflexperf.io.inputs import MAX_RUN_BYTES

    try:  # scipy's word for a file it may not open is "Reader needs file name"
        open(path, "rb").close()
    except OSError as exc:
        raise InputError(f"{path}: {exc.strerror or exc}") from None
    try:
        # a compressed variable unpacks whole: its declared size is checked first
        declared = sum(8 * math.prod(shape) for _, shape, _ in scipy.io.whosmat(path))
        if declared > MAX_RUN_BYTES:
            raise InputError(f"{path}: its variables hold {declared / (1 << 30):.1f} GiB, more "
                             f"than the {MAX_RUN_BYTES >> 30} GiB of the largest run file read")
        content = scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)
    except NotImplementedError:
        raise InputError(
            f"{path}: MATLAB v7.3 (HDF5) files are not supported; save with save(..., '-v7')"
        ) from None
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - scipy raises many types for a corrupt file
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{path}: cannot read as a MATLAB .mat file: {first}") from None
    variables = {k: v for k, v in content.items() if not k.startswith("__")}
    if not variables:
        raise InputError(f"{path}: empty .mat file (no variables)")
    if not any(name in variables for name in RUN_COLUMNS):
        # One struct holding the columns as fields (a common MATLAB export).
        structs = [v for v in variables.values() if hasattr(v, "_fieldnames")]
        if len(structs) == 1:
            variables = {name: getattr(structs[0], name) for name in structs[0]._fieldnames}
    columns: dict[str, np.ndarray] = {}
    not_numbers: dict[str, tuple[int, str]] = {}
    for name, value in variables.items():
        array = np.asarray(value)
        if array.dtype.kind not in "biuf":
            # strings, cells and structs are metadata, not columns, unless named as one
            what = "text" if array.dtype.kind in "US" else "cells or a struct"
            not_numbers[name] = (0, f"not numbers ({what})")
            continue
        columns[name] = np.atleast_1d(array)
    return columns, not_numbers


def _numeric_column(
    path: Path,
    columns: dict[str, np.ndarray],
    bad_cells: dict[str, tuple[int, str]],
    name: str,
) -> np.ndarray:
    if name in bad_cells:
        line, text = bad_cells[name]
        if line == 0:  # a whole variable of a .mat file: no line to name
            raise InputError(f"{path}: column {name}: {text}")
        raise InputError(f"{path}: column {name}: non-numeric value {text!r} (line {line})")
    if name not in columns:
        present = sorted(columns)
        raise InputError(f"{path}: missing column {name!r} (found: {', '.join(present) or 'none'})")
    array = columns[name]
    if array.ndim != 1:
        raise InputError(f"{path}: column {name}: expected a 1-D array, got shape {array.shape}")
    return array.astype(float, copy=False)


def _repair_nans(path: Path, name: str, time_s: np.ndarray, values: np.ndarray) -> int:
    """Interpolate a few NaN samples in place; refuse when there are too many."""
    bad = ~np.isfinite(values)
    count = int(np.count_nonzero(bad))
    if count == 0:
        return 0
    if count > MAX_NAN_FRACTION * values.size or count == values.size:
        raise InputError(
            f"{path}: column {name}: {count} of {values.size} samples are NaN or infinite "
            f"(at most {MAX_NAN_FRACTION:.0%} can be repaired)"
        )
    good = ~bad
    values[bad] = np.interp(time_s[bad], time_s[good], values[good])
    return count


def read_run(
    path: Path | str,
    required: Sequence[str] = RUN_COLUMNS,
    optional: Sequence[str] = KNOWN_OPTIONAL,
    vendor: VendorSettings | None = None,
) -> Run:
    """Read one run file (``.csv``, ``.csv.gz`` or ``.mat``) and validate its columns.

    Parameters
    ----------
    path : Path
        The run file.
    required : sequence of str
        Column names that must be present (SPEC 4); ``time_s`` is always needed.
    optional : sequence of str
        Columns read and repaired like the required ones when the file has them (SPEC 4:
        any run may carry ``voltage_v`` and ``current_a``).
    vendor : VendorSettings, optional
        A thrust-stand export in its vendor's format (manifest ``format:``), converted to these
        columns by :mod:`tuflexperf.io.vendor` and then validated like any run.

    Returns
    -------
    Run
        Columns as float64 arrays; the sample rate in Hz is ``1 / median(diff(time_s))``
        (never assumed: the paper's rig logged 1 kHz, others do not).
    """
    from tuflexperf.io.inputs import MAX_RUN_BYTES, check_input_file

    path = check_input_file(path, "run file", MAX_RUN_BYTES)
    suffix = _suffix(path)
    if vendor is not None:
        raw, bad_cells = read_vendor_columns(path, vendor)
    elif suffix in (".csv", ".csv.gz"):
        raw, bad_cells = _read_csv_columns(path)
    elif suffix == ".mat":
        raw, bad_cells = _read_mat_columns(path)
    else:
        raise InputError(f"{path}: unsupported run file type {suffix!r} (use .csv, .csv.gz, .mat)")

    names = ["time_s", *[c for c in required if c != "time_s"]]
    names += [c for c in optional if c in raw and c not in names]
    arrays = {
        name: np.array(_numeric_column(path, raw, bad_cells, name), dtype=float) for name in names
    }
    lengths = {name: a.size for name, a in arrays.items()}
    if len(set(lengths.values())) != 1:
        raise InputError(f"{path}: columns have different lengths: {lengths}")
    n = lengths["time_s"]
    if n == 0:
        raise InputError(f"{path}: no data rows")

    warnings: list[str] = []
    nan_samples: dict[str, int] = {}
    time_s = arrays["time_s"]
    bad_time = ~np.isfinite(time_s)
    if bad_time.any():
        count = int(np.count_nonzero(bad_time))
        if count > MAX_NAN_FRACTION * n:
            raise InputError(f"{path}: column time_s: {count} of {n} samples are NaN or infinite")
        keep = ~bad_time
        arrays = {name: a[keep] for name, a in arrays.items()}
        time_s = arrays["time_s"]
        nan_samples["time_s"] = count
        warnings.append(f"{count} rows with a NaN time_s dropped")
    if time_s.size < MIN_SAMPLES:
        raise InputError(f"{path}: only {time_s.size} samples (need at least {MIN_SAMPLES})")
    steps = np.diff(time_s)
    if not np.all(steps > 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise InputError(
            f"{path}: column time_s: not strictly increasing at sample {row} "
            f"({float(time_s[row - 1])!r} -> {float(time_s[row])!r})"
        )
    if "voltage_v" in arrays:
        # a logger's dropout reads 0 V: a missing sample, repaired as a NaN is (not the whole
        # run refused); a channel mostly at 0 is refused there
        dropped = arrays["voltage_v"] <= 0.0
        if dropped.any() and not dropped.all():
            arrays["voltage_v"] = np.where(dropped, np.nan, arrays["voltage_v"])
            warnings.append(f"{int(np.count_nonzero(dropped))} samples of voltage_v at or "
                            "below 0 V taken as missing")
    for name in names[1:]:
        count = _repair_nans(path, name, time_s, arrays[name])
        if count:
            nan_samples[name] = count
            warnings.append(f"{count} NaN samples in {name} interpolated")
        worst = float(np.max(np.abs(arrays[name])))
        if worst > MAX_MAGNITUDE:  # squares of it overflow the filters' sums
            raise InputError(f"{path}: column {name}: a value of {worst:.3g} is no measurement "
                             f"(beyond {MAX_MAGNITUDE:g})")
    if "throttle" in arrays:
        throttle = arrays["throttle"]
        high, low = float(throttle.max()), float(throttle.min())
        if high > 1 + THROTTLE_TOLERANCE or low < -THROTTLE_TOLERANCE:
            hint = " (percent? throttle is a fraction)" if high > 1.5 else ""
            raise InputError(
                f"{path}: column throttle: values from {low:g} to {high:g}, "
                f"expected a fraction in [0, 1]{hint}"
            )
    if "voltage_v" in arrays:
        # a pack voltage logged in mV is no 24 kV pack, one near zero breaks the exponent's
        # fit (samples at or below 0 V were repaired above, unless all are)
        typical = float(np.median(arrays["voltage_v"]))
        if not MIN_PACK_VOLTAGE_V <= typical <= MAX_PACK_VOLTAGE_V:
            hint = " (millivolts?)" if typical > MAX_PACK_VOLTAGE_V else ""
            raise InputError(
                f"{path}: column voltage_v: median {typical:.4g} V is no pack voltage "
                f"(expected {MIN_PACK_VOLTAGE_V:g}-{MAX_PACK_VOLTAGE_V:g} V){hint}"
            )
    if "current_a" in arrays:
        typical = float(np.median(np.abs(arrays["current_a"])))
        if typical > MAX_PACK_CURRENT_A:
            raise InputError(
                f"{path}: column current_a: median {typical:.4g} A is no fan's current "
                f"(beyond {MAX_PACK_CURRENT_A:g} A; milliamperes?)"
            )
    if "airspeed_m_s" in arrays:
        # a tunnel blows one way (as a thrust table's rows): noise dips below zero at rest,
        # a run that sits below it had its sign flipped
        typical = float(np.median(arrays["airspeed_m_s"]))
        if typical < -BACKWARDS_RUN_AIRSPEED_M_S:
            raise InputError(f"{path}: column airspeed_m_s: median {typical:.4g} m/s is "
                             "negative (a tunnel blows one way: is its sign flipped?)")
    step = float(np.median(steps))
    if not MIN_SAMPLE_INTERVAL_S <= step <= MAX_SAMPLE_INTERVAL_S:
        # a time base scaled by 1e-300 overflows the filters
        raise InputError(f"{path}: column time_s: a sample interval of {step:.3g} s is no "
                         f"measurement (expected {MIN_SAMPLE_INTERVAL_S:g}-"
                         f"{MAX_SAMPLE_INTERVAL_S:g} s; a time base in other units?)")
    if steps.max() > 10 * step:
        gap = int(np.argmax(steps))
        warnings.append(f"gap of {steps[gap]:.3g} s in time_s after t = {time_s[gap]:.6g} s")
    arrays.pop("time_s")
    return Run(
        path=path,
        time_s=time_s,
        columns=arrays,
        sample_rate_hz=1.0 / step,
        nan_samples=nan_samples,
        warnings=tuple(warnings),
    )


# --- thrust table ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ThrustTable:
    """Scattered thrust points per engine, in the order engines first appear."""

    path: Path | None
    engine: tuple[str, ...]
    throttle: NDArray[np.float64]
    airspeed_m_s: NDArray[np.float64]
    thrust_n: NDArray[np.float64]

    def engines(self) -> list[str]:
        return list(dict.fromkeys(self.engine))

    def select(self, engine: str) -> tuple[NDArray[np.float64], ...]:
        mask = np.array([e == engine for e in self.engine], dtype=bool)
        return self.throttle[mask], self.airspeed_m_s[mask], self.thrust_n[mask]


def read_thrust_table(path: Path | str) -> ThrustTable:
    """Read a long-format thrust table ``engine,throttle,airspeed_m_s,thrust_n`` (SPEC 4).

    Values are parsed with Python's ``float`` (correctly rounded), so a fit on the
    table sees exactly the numbers in the file. Extra columns (the reduction writes
    a few diagnostics) are ignored; the four SPEC columns are required.
    """
    from tuflexperf.io.inputs import MAX_TABLE_BYTES, check_input_file
    from tuflexperf.io.yamlio import engine_name_problem

    # a FIFO, a device or a huge file is refused before it is read
    path = check_input_file(path, "thrust table (.csv)", MAX_TABLE_BYTES)
    try:
        data = path.read_bytes()
        if data[:2] == b"\x1f\x8b":  # not "cannot decode byte 0x8b"
            raise InputError(f"{path}: gzip-compressed; a thrust table is plain CSV text "
                             "(unpack it with gunzip)")
        text = data.decode("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None
    try:
        rows = [r for r in csv.reader(io.StringIO(text)) if any(cell.strip() for cell in r)]
    except csv.Error as exc:  # e.g. a field beyond the csv module's 128 kB
        raise InputError(f"{path}: cannot read as CSV: {exc}") from None
    if not rows:
        raise InputError(f"{path}: empty file (expected the header {','.join(TABLE_COLUMNS)})")
    header = [cell.strip() for cell in rows[0]]
    missing = [c for c in TABLE_COLUMNS if c not in header]
    if missing:
        raise InputError(
            f"{path}: missing column {missing[0]!r} (header must include {','.join(TABLE_COLUMNS)})"
        )
    for name in TABLE_COLUMNS:
        if header.count(name) > 1:
            raise repeated_header_error(path, name)
    index = {name: header.index(name) for name in TABLE_COLUMNS}
    engines: list[str] = []
    values: dict[str, list[float]] = {c: [] for c in TABLE_COLUMNS[1:]}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise InputError(f"{path}: line {line}: {len(row)} fields, header has {len(header)}")
        name = row[index["engine"]].strip()
        if not name:
            raise InputError(f"{path}: line {line}: engine: empty name")
        problem = engine_name_problem(name)
        if problem is not None:  # the fit writes it into a propulsion file that must load
            raise InputError(f"{path}: line {line}: engine: {problem}")
        engines.append(name)
        for column in TABLE_COLUMNS[1:]:
            cell = row[index[column]].strip()
            try:
                number = float(cell)
            except ValueError:
                raise InputError(f"{path}: line {line}: {column}: not a number: {cell!r}") from None
            if not math.isfinite(number):
                raise InputError(f"{path}: line {line}: {column}: {cell!r} is not finite")
            if abs(number) > MAX_MAGNITUDE:
                raise InputError(f"{path}: line {line}: {column}: {cell} is no measurement "
                                 f"(beyond {MAX_MAGNITUDE:g})")
            values[column].append(number)
    if not engines:
        raise InputError(f"{path}: no data rows")
    throttle = np.array(values["throttle"])
    bad = np.flatnonzero((throttle < -THROTTLE_TOLERANCE) | (throttle > 1 + THROTTLE_TOLERANCE))
    if bad.size:
        hint = " (percent? throttle is a fraction)" if throttle.max() > 1.5 else ""
        raise InputError(
            f"{path}: line {bad[0] + 2}: throttle: {throttle[bad[0]]:g} is outside [0, 1]{hint}"
        )
    airspeed = np.array(values["airspeed_m_s"])
    # a tunnel blows one way: beyond a static point's sensor noise (fit's own tables carry
    # mean airspeeds of -0.002 m/s at rest) a negative airspeed is a sign slip
    backwards = np.flatnonzero(airspeed < -STATIC_AIRSPEED_NOISE_M_S)
    if backwards.size:
        raise InputError(f"{path}: line {backwards[0] + 2}: airspeed_m_s: "
                         f"{airspeed[backwards[0]]:g} is negative (a tunnel blows one way)")
    # no ducted fan is tested beyond the speed of sound
    supersonic = np.flatnonzero(airspeed > MAX_AIRSPEED_M_S)
    if supersonic.size:
        raise InputError(f"{path}: line {supersonic[0] + 2}: airspeed_m_s: "
                         f"{airspeed[supersonic[0]]:g} m/s is beyond the speed of sound "
                         f"({MAX_AIRSPEED_M_S:g} m/s): units?")
    return ThrustTable(
        path=path,
        engine=tuple(engines),
        throttle=throttle,
        airspeed_m_s=airspeed,
        thrust_n=np.array(values["thrust_n"]),
    )


def format_number(value: float) -> str:
    """Ten significant digits: what the thrust table stores and the fit then reads back."""
    return f"{value:.10g}"


def render_thrust_table(rows: Sequence[dict[str, object]], extra: Sequence[str] = ()) -> str:
    """CSV text of a thrust table: the SPEC columns first, then ``extra`` diagnostic columns."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    columns = [*TABLE_COLUMNS, *extra]
    writer.writerow(columns)
    for row in rows:
        cells = []
        for column in columns:
            value = row.get(column)
            if value is None:
                cells.append("")
            elif isinstance(value, float):
                cells.append(format_number(value) if math.isfinite(value) else "")
            else:
                cells.append(str(value))
        writer.writerow(cells)
    return buffer.getvalue()
