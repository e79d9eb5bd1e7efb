"""Thrust-stand exports in their vendor's own format, converted to the project's run columns.

A campaign manifest names the format of a run with ``format:`` (SPEC 4); supported:
``rcbenchmark`` (docs/formats.md, "Thrust-stand CSV": its columns and units). Units come from
the header, never assumed. Throttle is the ESC pulse mapped linearly by the manifest's
``esc_pulse_us: [idle, full]``; the force is ``thrust_sign`` times the logged thrust (stands
are mounted both ways round); a run without an airspeed column takes the manifest's
``airspeed_m_s``. The result holds the columns :func:`tuflexperf.io.runs.read_run` validates.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.models.atmosphere import G0_M_S2 as G0

VENDOR_FORMATS: tuple[str, ...] = ("rcbenchmark",)

#: 1 lbf = 0.45359237 kg x g0 exactly (international pound); 1 kgf = g0 N (CGPM 1901).
LBF_N = 0.45359237 * G0

THRUST_UNITS_N: dict[str, float] = {
    "n": 1.0,
    "kgf": G0,
    "kg": G0,  # some exports label kilogram-force as kg
    "gf": G0 / 1000.0,
    "g": G0 / 1000.0,
    "lbf": LBF_N,
    "lb": LBF_N,
    "ozf": LBF_N / 16.0,
    "oz": LBF_N / 16.0,
}
SPEED_UNITS_M_S: dict[str, float] = {
    "m/s": 1.0,
    "km/h": 1.0 / 3.6,
    "kph": 1.0 / 3.6,
    "kt": 1852.0 / 3600.0,
    "kn": 1852.0 / 3600.0,
    "kts": 1852.0 / 3600.0,
    "knots": 1852.0 / 3600.0,
    "mph": 1609.344 / 3600.0,
    "ft/s": 0.3048,
    "fps": 0.3048,
}
TIME_UNITS_S: dict[str, float] = {"s": 1.0, "ms": 1e-3}
MICROSECONDS = ("µs", "μs", "us", "âµs", "microseconds", "usec")
AIRSPEED_NAMES = ("airspeed", "air speed", "wind speed", "tunnel speed", "freestream speed")
RPM_NAMES = ("motor electrical speed", "motor optical speed", "motor speed", "rpm")
#: ESC pulses may overshoot the manifest's range by this share of it (calibration rounding).
PULSE_TOLERANCE = 0.05


@dataclass(frozen=True)
class VendorSettings:
    """How to read one vendor run: its format and the manifest keys it needs.

    ``esc_pulse_us`` is the (idle, full) ESC pulse width in microseconds, ``thrust_sign`` +1 or
    -1, ``airspeed_m_s`` the tunnel speed for runs without an airspeed column; ``where`` names
    the manifest entry in messages.
    """

    format: str
    esc_pulse_us: tuple[float, float] = (1000.0, 2000.0)
    thrust_sign: float = 1.0
    airspeed_m_s: float | None = None
    where: str = ""


_HEADER = re.compile(r"^(?P<name>.*?)\s*[\(\[](?P<unit>[^\)\]]*)[\)\]]\s*$")


AIRSPEED_AGREEMENT_M_S = 0.5
"""A manifest's ``airspeed_m_s`` and a run's airspeed column agree within this [m/s] (or 5 %)."""


def _split_header(cell: str) -> tuple[str, str]:
    """``"Thrust (kgf)"`` -> ``("thrust", "kgf")``; no unit -> ``(name, "")``."""
    text = " ".join(str(cell).replace("\ufeff", "").split())
    match = _HEADER.match(text)
    if match is None:
        return text.lower(), ""
    return match.group("name").strip().lower(), match.group("unit").strip().lower()


def repeated_columns(names: Sequence[object]) -> set[str]:
    """Header names, stripped, that a CSV repeats, from the names pandas read: one it renamed
    ``X.1`` beside ``X``, or two that are equal once stripped.

    pandas renames a repeated ``throttle`` to ``throttle.1`` and the first one was read as
    the measurement, silently: which of the two is meant only the user can tell. The names
    pandas itself read, not a second reading of the header line, which a blank first line,
    a BOM or a quoted newline leads astray.
    """
    stripped = [str(name).strip() for name in names]
    present = set(stripped)
    repeated = {name for name in stripped if stripped.count(name) > 1}
    for name in stripped:
        base, dot, count = name.rpartition(".")
        if dot and count.isdigit() and base in present:
            repeated.add(base)
    return repeated


def numeric_cells(cells: Any) -> tuple[np.ndarray | None, tuple[int, str] | None]:
    """A CSV column (pandas) as floats, or None with its first non-numeric cell's (line,
    text) (an empty cell is a NaN; the line counts the header)."""
    import pandas as pd

    values = pd.to_numeric(cells, errors="coerce")
    bad = values.isna() & cells.notna() & (cells.astype(str).str.strip() != "")
    if bad.any():
        row = int(np.flatnonzero(bad.to_numpy())[0])
        return None, (row + 2, str(cells.iloc[row]))  # +2: header line, 1-based
    return values.to_numpy(dtype=float), None


def repeated_header_error(path: Path, name: str) -> InputError:
    """Bad input: a column the run needs appears twice in the header."""
    return InputError(f"{path}: column {name!r} appears more than once in the header: which "
                      "one is the measurement? (rename or drop the other)")


def _read_table(path: Path) -> object:
    """The CSV as a pandas DataFrame; the vendor software writes UTF-8 (older versions Latin-1)."""
    import pandas as pd

    last: Exception | None = None
    for encoding in ("utf-8-sig", "latin-1"):
        try:
            return pd.read_csv(path, encoding=encoding, skipinitialspace=True, dtype=str)
        except UnicodeDecodeError as exc:
            last = exc
        except pd.errors.EmptyDataError:
            raise InputError(f"{path}: empty file (expected the thrust stand's header)") from None
        except (pd.errors.ParserError, OSError, ValueError) as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise InputError(f"{path}: cannot read as CSV: {first}") from None
    raise InputError(f"{path}: cannot decode as text: {last}")


def read_rcbenchmark(
    path: Path, settings: VendorSettings
) -> tuple[dict[str, np.ndarray], dict[str, tuple[int, str]]]:
    """Columns of an RCbenchmark CSV in the project's names and SI units.

    Parameters
    ----------
    path : Path
        The vendor CSV.
    settings : VendorSettings
        ``esc_pulse_us``, ``thrust_sign``, ``airspeed_m_s`` from the manifest.

    Returns
    -------
    tuple
        ``(columns, bad_cells)``: float arrays ``time_s`` [s], ``force_n`` [N],
        ``airspeed_m_s`` [m/s], ``throttle`` [fraction], and when logged ``voltage_v`` [V],
        ``current_a`` [A], ``rpm`` [1/min]; ``bad_cells`` maps a column with a non-numeric cell
        to its (line, text), as :func:`tuflexperf.io.runs.read_run` expects.

    References
    ----------
    Tyto Robotics, *RCbenchmark / Flight Stand software manual*, data logging (CSV columns);
    BIPM SI Brochure, 9th ed., table 8 (kgf = 9.80665 N); NIST SP 811 (lbf, kt, mph).
    """
    import pandas as pd

    frame = _read_table(path)
    headers = {str(c): _split_header(str(c)) for c in frame.columns}
    where = f" ({settings.where})" if settings.where else ""

    repeated = repeated_columns(frame.columns)

    def find(test: Callable[[str, str], bool], units: dict[str, float] | None = None) -> str | None:
        found = [raw for raw, (name, unit) in headers.items() if test(name, unit)]
        raw = found[0] if found else None
        if raw is not None and raw.strip() in repeated:
            raise repeated_header_error(path, raw.strip())
        for other in found[1:]:  # 'Thrust (kgf)' beside 'Thrust (N)': read the first only if
            _same_quantity(raw, other, units)  # both say the same (one was read, unchecked)
        return raw

    def _same_quantity(raw: str, other: str, units: dict[str, float] | None) -> None:
        both = f"columns {raw!r} and {other!r} both give the {headers[raw][0]}"
        if units is None or headers[raw][1] not in units or headers[other][1] not in units:
            raise InputError(f"{path}: {both}; keep one{where}")
        a, b = (pd.to_numeric(frame[c], errors="coerce").to_numpy(dtype=float)
                * units[headers[c][1]] for c in (raw, other))
        scale = max(float(np.nanmax(np.abs(a), initial=0.0)), 1e-12)
        gap = np.abs(a - b)
        # a vendor logging one quantity in two units rounds each: a part in 1000 of the range
        # (nanmax's initial is a floor: an initial of inf said "by up to inf" every time)
        largest = float(np.nanmax(gap, initial=0.0))
        if (np.isnan(a) != np.isnan(b)).any():
            raise InputError(f"{path}: {both} and one is empty where the other is not; keep "
                             f"the one to read{where}")
        if largest > 1e-3 * scale:
            raise InputError(f"{path}: {both} and they disagree (by up to {largest:.3g} in SI "
                             f"units); keep the one to read{where}")

    columns: dict[str, np.ndarray] = {}
    bad_cells: dict[str, tuple[int, str]] = {}

    def numeric(raw: str, target: str) -> np.ndarray | None:
        values, bad = numeric_cells(frame[raw])
        if bad is not None:
            bad_cells[target] = (bad[0], f"{bad[1]} in {raw!r}")
        return values

    def need(raw: str | None, what: str) -> str:
        if raw is None:
            found = ", ".join(repr(c) for c in headers) or "none"
            raise InputError(f"{path}: missing column {what}{where} (found: {found})")
        return raw

    def convert(target: str, raw: str, factor: float) -> None:
        values = numeric(raw, target)
        if values is not None:
            columns[target] = values * factor

    time_raw = need(find(lambda n, u: n == "time" and u in TIME_UNITS_S, TIME_UNITS_S),
                    "'Time (s)'")
    convert("time_s", time_raw, TIME_UNITS_S[headers[time_raw][1]])

    thrust_raw = need(
        find(lambda n, u: n == "thrust" and u in THRUST_UNITS_N, THRUST_UNITS_N),
        "'Thrust (kgf)' (or N, lbf, gf, ozf)",
    )
    convert("force_n", thrust_raw, settings.thrust_sign * THRUST_UNITS_N[headers[thrust_raw][1]])

    esc_raw = need(
        find(lambda n, u: n.startswith("esc") and u in MICROSECONDS), "'ESC signal (µs)'"
    )
    pulse = numeric(esc_raw, "throttle")
    if pulse is not None:
        idle, full = settings.esc_pulse_us
        span = full - idle
        finite = pulse[np.isfinite(pulse)]
        low, high = idle - PULSE_TOLERANCE * span, full + PULSE_TOLERANCE * span
        if finite.size and (finite.min() < low or finite.max() > high):
            raise InputError(
                f"{path}: column {esc_raw!r}: pulses from {finite.min():g} to {finite.max():g} us "
                f"are outside esc_pulse_us [{idle:g}, {full:g}]{where}"
            )
        columns["throttle"] = (pulse - idle) / span

    speed_raw = find(lambda n, u: any(n.startswith(a) for a in AIRSPEED_NAMES), SPEED_UNITS_M_S)
    if speed_raw is not None:
        unit = headers[speed_raw][1]
        if unit not in SPEED_UNITS_M_S:
            raise InputError(
                f"{path}: column {speed_raw!r}: unknown airspeed unit {unit!r} "
                f"(use one of {', '.join(SPEED_UNITS_M_S)})"
            )
        convert("airspeed_m_s", speed_raw, SPEED_UNITS_M_S[unit])
        logged = columns.get("airspeed_m_s")
        if settings.airspeed_m_s is not None and logged is not None and np.isfinite(logged).any():
            # the column is read; a manifest speed it contradicts is not dropped unsaid
            median = float(np.nanmedian(logged))
            if abs(median - settings.airspeed_m_s) > max(AIRSPEED_AGREEMENT_M_S,
                                                          0.05 * abs(median)):
                raise InputError(
                    f"{path}: column {speed_raw!r} gives {median:.3g} m/s (median), the "
                    f"manifest's airspeed_m_s {settings.airspeed_m_s:g} m/s{where}: which is "
                    "it? drop one")
    elif settings.airspeed_m_s is not None:
        columns["airspeed_m_s"] = np.full(len(frame), float(settings.airspeed_m_s))
    else:
        raise InputError(
            f"{path}: no airspeed column (e.g. 'Airspeed (m/s)') and no airspeed_m_s in the "
            f"manifest{where}"
        )

    optional = {
        "voltage_v": find(lambda n, u: n == "voltage" and u == "v"),
        "current_a": find(lambda n, u: n == "current" and u == "a"),
        "rpm": next(
            (r for name in RPM_NAMES for r in [find(lambda n, u, m=name: n == m and u == "rpm")]
             if r is not None),
            None,
        ),
    }
    for target, raw in optional.items():
        if raw is not None:
            values = numeric(raw, target)
            if values is not None:
                columns[target] = values
            else:
                bad_cells.pop(target)  # an unreadable optional column is left out, not fatal
    _check_sign(path, columns, settings, where)
    return columns, bad_cells


def _check_sign(
    path: Path, columns: dict[str, np.ndarray], settings: VendorSettings, where: str
) -> None:
    """A stand mounted the other way round logs pull as negative: refuse rather than fit it.

    At the run's upper throttles (at least 30 %, within the top half of what it reached) a fan
    pulls; a force whose median there is negative means ``thrust_sign`` is the wrong way round.
    """
    force, throttle = columns.get("force_n"), columns.get("throttle")
    if force is None or throttle is None:
        return
    finite = np.isfinite(force) & np.isfinite(throttle)
    if not finite.any() or float(throttle[finite].max()) < 0.3:
        return
    high = finite & (throttle >= 0.5 * float(throttle[finite].max()))
    median = float(np.median(force[high]))
    if median < 0:
        raise InputError(
            f"{path}: thrust is negative ({median:.3g} N median) at throttle >= "
            f"{0.5 * float(throttle[finite].max()):.2f}: the stand logs pull the other way; "
            f"set thrust_sign: {-int(settings.thrust_sign)} in the manifest{where}"
        )


READERS = {"rcbenchmark": read_rcbenchmark}


def read_vendor_columns(
    path: Path, settings: VendorSettings
) -> tuple[dict[str, np.ndarray], dict[str, tuple[int, str]]]:
    """Dispatch on ``settings.format`` (one of :data:`VENDOR_FORMATS`).

    Returns
    -------
    tuple
        As :func:`read_rcbenchmark`: columns in SI units and the first non-numeric cells.

    References
    ----------
    SPEC 4 (run formats, ``format:``).
    """
    reader = READERS.get(settings.format)
    if reader is None:
        raise InputError(
            f"{path}: unknown run format {settings.format!r} "
            f"(choose from run, {', '.join(VENDOR_FORMATS)})"
        )
    return reader(path, settings)
