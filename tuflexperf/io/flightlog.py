"""Flight logs in: PX4 ULog (``.ulg``), a ``ulog2csv`` folder, ArduPilot DataFlash (``.bin``).

One reader per format; each returns the same :class:`FlightLog`: the few streams the flown
side needs (battery, airspeed, baro, throttle, land detector, climb rate), each on its own
timestamps [s], with the topic it came from. Nothing is resampled here.

pyulog and pymavlink are an optional extra (``pip install tuflexperf[flightlog]``) and are
imported only by the reader that needs them: ``check`` never loads them.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tuflexperf.errors import InputError

US = 1e-6  # ULog and DataFlash timestamps are microseconds
# PX4's battery_status.current_a is -1 when the pack has no current sensor (ArduPilot: NaN)
NO_CURRENT_SENSOR = -1.0
# the PX4 topics read (and only those: memory stays bounded on a long log)
ULOG_TOPICS = (
    "battery_status", "airspeed_validated", "airspeed", "vehicle_air_data", "sensor_baro",
    "vehicle_land_detected", "vehicle_status", "actuator_controls_0", "actuator_motors",
    "vehicle_thrust_setpoint", "vehicle_local_position",
)
DATAFLASH_TYPES = ("BAT", "CURR", "ARSP", "BARO", "CTUN", "STAT", "GPS")


@dataclass(frozen=True)
class Stream:
    """One quantity set on its own clock.

    Attributes
    ----------
    source : str
        Topic (and instance) it was read from, e.g. ``battery_status[1]``.
    time_s : numpy.ndarray
        Sample times [s] since the log's clock zero, as logged (sorted by the flown side).
    values : dict of str to numpy.ndarray
        Columns by name, each as long as ``time_s``; units in the name (``voltage_v``).
    """

    source: str
    time_s: np.ndarray
    values: dict[str, np.ndarray] = field(default_factory=dict)

    def column(self, name: str) -> np.ndarray:
        """The column ``name`` as float64 (NaN where it is absent)."""
        value = self.values.get(name)
        if value is None:
            return np.full(self.time_s.shape, np.nan)
        return np.asarray(value, dtype=float)


@dataclass(frozen=True)
class FlightLog:
    """The streams of one flight log that the flown side reads.

    Attributes
    ----------
    path : pathlib.Path
        The log (file or ulog2csv folder).
    kind : str
        ``ulog``, ``ulog-csv`` or ``dataflash``.
    batteries : tuple of Stream
        One per battery instance: ``voltage_v`` [V], ``current_a`` [A] (NaN: no sensor),
        ``discharged_mah`` [mAh] (the log's own counter, any start value).
    airspeed : Stream or None
        ``airspeed_m_s`` [m/s], calibrated where the log has it (see ``airspeed_kind``).
    airspeed_kind : str
        ``calibrated``, ``indicated`` or ``ground speed`` (the stated fallback).
    baro : Stream or None
        ``altitude_m`` [m], ``pressure_pa`` [Pa], ``temperature_c`` [degC] (NaN if absent).
    climb : Stream or None
        ``climb_rate_m_s`` [m/s], positive up, where the log has an estimate of it.
    throttle : Stream or None
        ``throttle`` [-], the commanded throttle as a fraction 0-1.
    landed : Stream or None
        ``landed`` [-], 1 on the ground and 0 airborne, as the land detector says.
    armed : Stream or None
        ``armed`` [-], 1 when armed.
    notes : tuple of str
        What the reader had to decide (a truncated file, a fallback topic).
    """

    path: Path
    kind: str
    batteries: tuple[Stream, ...]
    airspeed: Stream | None
    airspeed_kind: str
    baro: Stream | None
    climb: Stream | None
    throttle: Stream | None
    landed: Stream | None
    armed: Stream | None
    notes: tuple[str, ...] = ()


def read_flight_log(path: Path | str) -> FlightLog:
    """Read a ``.ulg``, a ulog2csv folder or a DataFlash ``.bin`` by what ``path`` is.

    Raises
    ------
    InputError
        One line naming the file and what is wrong (not a log, no battery topic, ...).
    """
    path = Path(path)
    if path.is_dir():
        return read_ulog_csv(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file or folder")
    with open(path, "rb") as handle:
        head = handle.read(8)
    if head.startswith(b"ULog\x01\x12\x35"):
        return read_ulog(path)
    if head[:2] == b"\xa3\x95":  # DataFlash message header
        return read_dataflash(path)
    suffix = path.suffix.lower()
    what = {".ulg": "a ULog", ".bin": "a DataFlash log"}.get(suffix, "a flight log")
    raise InputError(f"{path}: not {what} (no ULog or DataFlash header); give a PX4 .ulg, "
                     "the folder ulog2csv writes, or an ArduPilot .bin")


def _require(module: str, extra: str = "flightlog") -> Any:
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise InputError(f"flightlog needs the package {module.split('.')[0]}: "
                         f"pip install 'tuflexperf[{extra}]'") from None


# ---- PX4: ULog and ulog2csv ----------------------------------------------------------------

Topics = dict[tuple[str, int], dict[str, np.ndarray]]


class _CountingFile:
    """A binary file that remembers whether its last read came back short (a cut file)."""

    def __init__(self, handle: Any) -> None:
        self._handle = handle
        self.short = False

    def read(self, size: int = -1) -> bytes:
        data = self._handle.read(size)
        self.short = 0 < len(data) < size if size > 0 else False
        return data

    def __getattr__(self, name: str) -> Any:
        return getattr(self._handle, name)


def read_ulog(path: Path) -> FlightLog:
    """A PX4 ULog, only the topics :data:`ULOG_TOPICS` read."""
    pyulog = _require("pyulog")
    notes: list[str] = []
    with open(path, "rb") as raw:
        handle = _CountingFile(raw)
        try:
            with _quiet():
                ulog = pyulog.ULog(handle, list(ULOG_TOPICS))
        except Exception as exc:  # pyulog's ULogException, or struct errors on garbage
            raise InputError(f"{path}: not a readable ULog ({_short(exc)})") from None
    if handle.short:
        notes.append(f"{path.name}: the file ends inside a message (truncated, e.g. power "
                     "lost in flight); read up to its last whole message")
    if ulog.file_corruption:
        notes.append(f"{path.name}: pyulog found corrupt data and skipped it")
    topics: Topics = {(d.name, d.multi_id): d.data for d in ulog.data_list}
    return _from_px4_topics(path, "ulog", topics, notes)


_CSV_NAME = re.compile(r"^(?P<log>.+?)_(?P<topic>[a-z0-9_]+?)_(?P<instance>\d+)\.csv$")


def read_ulog_csv(folder: Path) -> FlightLog:
    """The folder of ``<name>_<topic>_<instance>.csv`` that pyulog's ``ulog2csv`` writes."""
    found: Topics = {}
    notes: list[str] = []
    files = sorted(folder.glob("*.csv"))
    if not files:
        raise InputError(f"{folder}: no ulog2csv CSV files (<name>_<topic>_<instance>.csv) in "
                         "this folder")
    for csv in files:
        match = _CSV_NAME.match(csv.name)
        if match is None:
            continue
        # the log name may itself hold underscores: take the longest known topic suffix
        stem = csv.name[: -len(f"_{match['instance']}.csv")]
        topic = next((t for t in sorted(ULOG_TOPICS, key=len, reverse=True)
                      if stem.endswith(f"_{t}")), None)
        if topic is None:
            continue
        found[(topic, int(match["instance"]))] = _read_topic_csv(csv)
    if not found:
        raise InputError(f"{folder}: none of the CSVs is a topic flightlog reads "
                         f"({', '.join(ULOG_TOPICS[:4])}, ...)")
    return _from_px4_topics(folder, "ulog-csv", found, notes)


def _read_topic_csv(csv: Path) -> dict[str, np.ndarray]:
    """One ulog2csv file as columns, every column float (NaN where blank)."""
    import warnings

    import pandas as pd  # the C parser: a 30-minute log's CSVs in well under a second

    try:
        with warnings.catch_warnings():  # a row longer than the header: refused, not cut
            warnings.simplefilter("error", pd.errors.ParserWarning)
            frame = pd.read_csv(csv, dtype=float, encoding="utf-8", index_col=False,
                                low_memory=False)
    except UnicodeDecodeError:
        raise InputError(f"{csv}: not text (not a ulog2csv file)") from None
    except (ValueError, pd.errors.ParserError, pd.errors.ParserWarning) as exc:
        raise InputError(f"{csv}: not a ulog2csv table ({_short(exc)})") from None
    if "timestamp" not in frame.columns:
        raise InputError(f"{csv}: no 'timestamp' column (not a ulog2csv file)")
    return {str(name): frame[name].to_numpy() for name in frame.columns}


def _from_px4_topics(path: Path, kind: str, topics: Topics, notes: list[str]) -> FlightLog:
    """The streams out of PX4 topics (ULog or its CSVs: the same field names)."""

    def instances(name: str) -> list[tuple[int, dict[str, np.ndarray]]]:
        return sorted((i, d) for (n, i), d in topics.items() if n == name)

    def stream(name: str, instance: int, data: dict[str, np.ndarray],
               columns: dict[str, str | None]) -> Stream:
        time = np.asarray(data["timestamp"], dtype=float) * US
        values = {out: (np.asarray(data[src], dtype=float) if src in data
                        else np.full(time.shape, np.nan))
                  for out, src in columns.items() if src is not None}
        return Stream(f"{name}[{instance}]", time, values)

    batteries = tuple(
        stream("battery_status", i, d, {"voltage_v": "voltage_v", "current_a": "current_a",
                                         "discharged_mah": "discharged_mah"})
        for i, d in instances("battery_status")
    )
    if not batteries:
        raise InputError(f"{path}: no battery topic (battery_status): the flown power is "
                         "read from it")
    airspeed, airspeed_kind = _px4_airspeed(instances, stream, notes)
    baro = None
    for i, d in instances("vehicle_air_data")[:1]:
        baro = stream("vehicle_air_data", i, d, {
            "altitude_m": "baro_alt_meter", "pressure_pa": "baro_pressure_pa",
            "temperature_c": "baro_temp_celcius"})
    climb = None
    for i, d in instances("vehicle_local_position")[:1]:
        if "vz" in d:  # NED: down positive
            climb = Stream(f"vehicle_local_position[{i}]", np.asarray(d["timestamp"]) * US,
                           {"climb_rate_m_s": -np.asarray(d["vz"], dtype=float)})
    throttle = None
    for name, col in (("actuator_controls_0", "control[3]"), ("actuator_motors", "control[0]"),
                      ("vehicle_thrust_setpoint", "xyz[0]")):
        found = [(i, d) for i, d in instances(name) if col in d]
        if found:
            i, d = found[0]
            throttle = stream(name, i, d, {"throttle": col})
            break
    landed = None
    for i, d in instances("vehicle_land_detected")[:1]:
        landed = stream("vehicle_land_detected", i, d, {"landed": "landed"})
    armed = None
    for i, d in instances("vehicle_status")[:1]:
        if "arming_state" in d:  # ARMING_STATE_ARMED = 2
            armed = Stream(f"vehicle_status[{i}]", np.asarray(d["timestamp"]) * US,
                           {"armed": (np.asarray(d["arming_state"]) == 2).astype(float)})
    return FlightLog(path, kind, batteries, airspeed, airspeed_kind, baro, climb, throttle,
                     landed, armed, tuple(notes))


def _px4_airspeed(instances: Any, stream: Any, notes: list[str]) -> tuple[Stream | None, str]:
    """Calibrated airspeed (airspeed_validated), else indicated (airspeed), else ground speed."""
    for i, d in instances("airspeed_validated")[:1]:
        # older PX4 (< 1.12) names it indicated_airspeed_m_s: the calibrated one of the time
        col = ("calibrated_airspeed_m_s" if "calibrated_airspeed_m_s" in d
               else "indicated_airspeed_m_s")
        if col in d:
            return stream("airspeed_validated", i, d, {"airspeed_m_s": col}), "calibrated"
    for i, d in instances("airspeed")[:1]:
        if "indicated_airspeed_m_s" in d:
            notes.append("airspeed: airspeed_validated not logged; the raw sensor's indicated "
                         "airspeed (airspeed topic) is used as calibrated")
            return stream("airspeed", i, d, {"airspeed_m_s": "indicated_airspeed_m_s"}), \
                "indicated"
    for i, d in instances("vehicle_local_position")[:1]:
        if "vx" in d and "vy" in d:
            notes.append("airspeed: no airspeed topic; ground speed (vehicle_local_position) "
                         "stands in for it, so wind biases every bin")
            speed = np.hypot(np.asarray(d["vx"], float), np.asarray(d["vy"], float))
            return Stream(f"vehicle_local_position[{i}]", np.asarray(d["timestamp"]) * US,
                          {"airspeed_m_s": speed}), "ground speed"
    return None, "none"


# ---- ArduPilot DataFlash -------------------------------------------------------------------


def read_dataflash(path: Path) -> FlightLog:
    """An ArduPilot DataFlash ``.bin`` with pymavlink (only the messages needed are unpacked)."""
    mavutil = _require("pymavlink.mavutil")
    notes: list[str] = []
    try:
        with _quiet():
            log = mavutil.mavlink_connection(str(path), dialect="ardupilotmega")
            rows: dict[str, list[dict[str, Any]]] = {t: [] for t in DATAFLASH_TYPES}
            while True:
                msg = log.recv_match(type=list(DATAFLASH_TYPES))
                if msg is None:
                    break
                rows[msg.get_type()].append(msg.to_dict())
    except Exception as exc:  # pymavlink raises bare exceptions on garbage
        raise InputError(f"{path}: not a readable DataFlash log ({_short(exc)})") from None

    def table(kind: str) -> dict[str, np.ndarray]:
        got = rows[kind]
        if not got:
            return {}
        keys = [k for k, v in got[0].items() if isinstance(v, (int, float))]
        return {k: np.array([r.get(k, np.nan) for r in got], dtype=float) for k in keys}

    bat = table("BAT") or table("CURR")
    kind_name = "BAT" if rows["BAT"] else "CURR"
    if not bat or "TimeUS" not in bat:
        raise InputError(f"{path}: no battery messages (BAT or CURR): the flown power is read "
                         "from them")
    instance = bat.get("Instance", bat.get("Inst", np.zeros_like(bat["TimeUS"])))
    batteries = []
    for inst in np.unique(instance):
        pick = instance == inst
        current = bat.get("Curr", np.full(pick.shape, np.nan))[pick]
        batteries.append(Stream(f"{kind_name}[{int(inst)}]", bat["TimeUS"][pick] * US, {
            "voltage_v": bat.get("Volt", np.full(pick.shape, np.nan))[pick],
            "current_a": current,
            "discharged_mah": bat.get("CurrTot", np.full(pick.shape, np.nan))[pick]}))
    arsp = table("ARSP")
    airspeed, airspeed_kind = None, "none"
    if arsp:
        # several sensors log as instances I = 0, 1, ...: the first one is read
        pick = arsp["I"] == 0 if "I" in arsp else np.ones(arsp["TimeUS"].shape, bool)
        airspeed = Stream("ARSP", arsp["TimeUS"][pick] * US,
                          {"airspeed_m_s": arsp["Airspeed"][pick]})
        airspeed_kind = "calibrated"
    else:
        gps = table("GPS")
        if gps and "Spd" in gps:
            notes.append("airspeed: no ARSP messages; GPS ground speed stands in for it, so "
                         "wind biases every bin")
            airspeed = Stream("GPS", gps["TimeUS"] * US, {"airspeed_m_s": gps["Spd"]})
            airspeed_kind = "ground speed"
    baro_t = table("BARO")
    baro = climb = None
    if baro_t:
        pick = baro_t["I"] == 0 if "I" in baro_t else np.ones(baro_t["TimeUS"].shape, bool)
        t = baro_t["TimeUS"][pick] * US
        blank = np.full(pick.shape, np.nan)
        baro = Stream("BARO", t, {"altitude_m": baro_t["Alt"][pick],
                                  "pressure_pa": baro_t.get("Press", blank)[pick],
                                  "temperature_c": baro_t.get("Temp", blank)[pick]})
        if "CRt" in baro_t:
            climb = Stream("BARO.CRt", t, {"climb_rate_m_s": baro_t["CRt"][pick]})
    ctun = table("CTUN")
    throttle = None
    for col in ("ThrOut", "ThO"):  # percent (ArduPlane)
        if col in ctun:
            throttle = Stream(f"CTUN.{col}", ctun["TimeUS"] * US, {"throttle": ctun[col] / 100})
            break
    stat = table("STAT")
    landed = armed = None
    if stat and "isFlying" in stat:
        landed = Stream("STAT.isFlying", stat["TimeUS"] * US, {"landed": 1.0 - stat["isFlying"]})
    if stat and "Armed" in stat:
        armed = Stream("STAT.Armed", stat["TimeUS"] * US, {"armed": stat["Armed"]})
    return FlightLog(path, "dataflash", tuple(batteries), airspeed, airspeed_kind, baro, climb,
                     throttle, landed, armed, tuple(notes))


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """The readers' own prints ("unknown msg type", "File corruption detected") kept off
    stdout (it carries --json) and stderr (one line per problem): the notes say it."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        with _quiet_c_stderr():
            yield


@contextlib.contextmanager
def _quiet_c_stderr() -> Iterator[None]:
    """File descriptor 2 to the null device: pymavlink's compiled indexer writes "unknown
    msg type" with C's stdio, past Python's ``sys.stderr``."""
    try:
        sys.stderr.flush()
        saved, null = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    except (OSError, ValueError, AttributeError):  # no fd 2 (an embedded interpreter)
        yield
        return
    os.dup2(null, 2)
    try:
        yield
    finally:
        with contextlib.suppress(OSError, AttributeError, TypeError):
            import ctypes

            ctypes.CDLL(None).fflush(None)  # C's buffer out to the null device, not later
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)


def _short(exc: BaseException) -> str:
    text = str(exc).replace("\n", " ").strip() or type(exc).__name__
    return text if len(text) <= 120 else text[:117] + "..."

