"""The tool's own outputs: where one lands, and how a file is told to be one.

An existing file is replaced only when it is an earlier output of the same command, of
the artefact its flag writes, as the tool wrote it (SPEC 5): fit's YAML by its seal, a
CSV or PNG by the sha256 mark in its extended attributes, each kind by how it begins.
The writers (:mod:`tuflexperf.io.files`) use these checks; they live apart so that the
writers stay within a file's size and import nothing back.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
from pathlib import Path

from tuflexperf.errors import InputError
from tuflexperf.io.inputs import MAX_YAML_BYTES

MARKER = ".tuflexperf-output.json"  # written into every folder a command writes whole


def sha256_of(path: Path | str) -> str:
    """Hex sha256 of a file's bytes, read in 1 MiB chunks."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


# fit's YAML ends with this comment and the sha256 of every byte before it, so a later fit
# replaces it only as written: a hand edit (a tweaked coefficient, a note) is the user's work
SEAL = "# sha256 of the lines above: "


def sealed(text: str) -> str:
    """``text`` (YAML) with a last comment line holding the sha256 of the text before it."""
    body = text if text.endswith("\n") else text + "\n"
    return f"{body}{SEAL}{hashlib.sha256(body.encode('utf-8')).hexdigest()}\n"


def seal_intact(data: bytes) -> bool:
    """Whether ``data`` ends with a seal (see :func:`sealed`) matching what precedes it."""
    if not data.endswith(b"\n"):
        return False
    cut = data.rfind(b"\n", 0, len(data) - 1) + 1
    digest = hashlib.sha256(data[:cut]).hexdigest()
    return data[cut:-1] == f"{SEAL}{digest}".encode()


def output_path(out: Path | str) -> Path:
    """Where an output named ``out`` lands: its folder resolved as the OS resolves it once the
    missing folders exist, its own name kept (a symbolic link there is still seen as one).

    ``missing/../folder`` is ``folder``: checked as written, nothing would be there, and the
    write would replace the user's folder.
    """
    out = Path(out)
    if out.name in ("", ".", ".."):
        return Path(os.path.realpath(out))
    return Path(os.path.realpath(out.parent)) / out.name


# Each single file the tool writes carries the sha256 of its bytes in an extended attribute:
# metadata of the file itself (no second file), which a copy (`cp`) or an editor's new file
# drops and an edit in place outdates. A later run replaces a CSV or PNG only as written (its
# header alone would let a user's edited copy be replaced). Where the file system
# keeps no extended attributes, how the file begins is all there is to go by.
WRITTEN_XATTR = "user.tuflexperf.sha256"
_UNKNOWN = "unknown"  # no extended attributes here: whether we wrote it cannot be told


def _mark_written(path: str | Path, data: bytes) -> None:
    """Give ``path`` the sha256 of ``data`` (its bytes) in :data:`WRITTEN_XATTR`, where the
    platform and file system keep extended attributes."""
    with contextlib.suppress(OSError, AttributeError):  # AttributeError: no os.setxattr
        os.setxattr(path, WRITTEN_XATTR, hashlib.sha256(data).hexdigest().encode("ascii"))


def written_mark(path: Path) -> str | None:
    """The sha256 ``path`` was written with (:data:`WRITTEN_XATTR`), None where it has no
    mark, or :data:`_UNKNOWN` where the file system keeps no extended attributes."""
    try:
        return os.getxattr(path, WRITTEN_XATTR).decode("ascii", "replace")
    except AttributeError:  # a platform without os.getxattr
        return _UNKNOWN
    except OSError as exc:
        return None if exc.errno == errno.ENODATA else _UNKNOWN


# How each single-file output of the tool begins (the folders carry MARKER instead): an
# existing file is replaced only when it begins exactly like one of these, i.e. an earlier
# output. A user's file that merely looks alike (an extra column) is never replaced.
def _thrust_table_headers() -> tuple[str, ...]:
    from tuflexperf.io.runs import REFIT_TABLE_EXTRA_COLUMNS, TABLE_COLUMNS, TABLE_EXTRA_COLUMNS

    # fit's thrust table from a campaign (SPEC 4's four columns, then the reduction's), and
    # refitted from a table (then the model and its misfit); never the four alone, which is
    # the input format a user's own table has
    return (",".join((*TABLE_COLUMNS, *TABLE_EXTRA_COLUMNS)),
            ",".join((*TABLE_COLUMNS, *REFIT_TABLE_EXTRA_COLUMNS)))


MISSION_CSV_COLUMNS = ("time_s", "segment", "altitude_m", "distance_m", "airspeed_m_s",
                       "airspeed_eas_m_s", "throttle", "climb_rate_m_s")
MISSION_CSV_ENGINE_COLUMNS = ("current_a", "voltage_v", "charge_ah", "charge_fraction",
                              "power_w", "energy_wh")  # each + "_<engine>", per engine
REQUIREMENT_NAMES = frozenset({  # check's result names (analysis/requirements.py)
    "takeoff_ground_roll", "takeoff_distance_to_obstacle", "trim_throttle_max",
    "oei_min_throttle", "flight_endurance", "mission_landing_charge", "mission_solved_time",
})
PNG_SOFTWARE = "tuflexperf"  # the PNG text chunk 'Software' of a report page: + " VERSION"
SWEEP_PNG_SOFTWARE = "tuflexperf sweep"  # ... and of sweep's carpet plot
FLIGHT_PNG_SOFTWARE = "tuflexperf flightlog"  # ... and of flightlog's power plot
# flightlog's --csv header (the aligned series; tuflexperf.analysis.flown)
FLIGHT_CSV_COLUMNS = ("time_s", "airspeed_m_s", "power_w", "throttle", "altitude_m",
                      "climb_rate_m_s", "airborne")


def _is_mission_history(columns: list[str]) -> bool:
    fixed, rest = columns[: len(MISSION_CSV_COLUMNS)], columns[len(MISSION_CSV_COLUMNS):]
    width = len(MISSION_CSV_ENGINE_COLUMNS)
    if tuple(fixed) != MISSION_CSV_COLUMNS or not rest or len(rest) % width:
        return False
    for start in range(0, len(rest), width):
        group = rest[start : start + width]
        engine = group[0].removeprefix(MISSION_CSV_ENGINE_COLUMNS[0] + "_")
        if group != [f"{name}_{engine}" for name in MISSION_CSV_ENGINE_COLUMNS]:
            return False
    return True


def _is_sweep_grid(columns: list[str]) -> bool:
    """The varied dotted keys, then ``<requirement>_value, _limit, _passed, _verdict`` per
    requirement (an earlier version's grid without ``_verdict`` too)."""
    keys = [c for c in columns if "." in c]
    tail = columns[len(keys):]
    if not keys or columns[: len(keys)] != keys or not tail:
        return False
    return any(_sweep_groups(tail, suffixes)
               for suffixes in (("_value", "_limit", "_passed", "_verdict"),
                                ("_value", "_limit", "_passed")))


def _sweep_groups(tail: list[str], suffixes: tuple[str, ...]) -> bool:
    """Whether ``tail`` is whole groups of ``<requirement><suffix>`` columns."""
    size = len(suffixes)
    if len(tail) % size:
        return False
    for start in range(0, len(tail), size):
        name = tail[start].removesuffix("_value")
        if name not in REQUIREMENT_NAMES or tail[start : start + size] != [
                f"{name}{suffix}" for suffix in suffixes]:
            return False
    return True


def _png_software(head: bytes) -> str | None:
    """The text of a PNG's ``Software`` chunk among ``head``'s chunks (None without one)."""
    at = 8  # past the signature
    while at + 8 <= len(head):
        length = int.from_bytes(head[at:at + 4], "big")
        kind, body = head[at + 4:at + 8], head[at + 8:at + 8 + length]
        if kind == b"IDAT" or len(body) < length:  # metadata comes before the image
            return None
        if kind == b"tEXt" and body.startswith(b"Software\x00"):
            return body.removeprefix(b"Software\x00").decode("latin-1")
        at += 12 + length
    return None


ARTEFACT_WRITERS = {
    "propulsion file": "fit", "battery file": "fit", "thrust table": "fit",
    "mission history": "mission", "sweep grid": "sweep", "sweep plot": "sweep",
    "report page": "report", "flight series": "flightlog", "flight plot": "flightlog",
}
"""Each single-file artefact of the tool and the command that writes it."""


def artefact_of(head: bytes) -> str | None:
    """Which of the tool's artefacts (:data:`ARTEFACT_WRITERS`) a file that begins with
    ``head`` is (None: not this tool's).

    YAML written by ``fit`` says ``written by `tuflexperf ...``` on its first comment line
    (the propulsion model's line names poly22); a PNG carries ``Software: tuflexperf sweep``
    (the carpet plot) or ``tuflexperf VERSION`` (a report page); each CSV has its own
    header, matched whole: fit's thrust table, a mission's history (its columns, then six
    per engine), a sweep's grid (the varied keys, then ``<requirement>_value, _limit,
    _passed, _verdict`` per requirement).
    """
    first_line = head.split(b"\n", 1)[0]
    # fit's YAML (thrust model, battery) says so on its first comment line
    if first_line.startswith(b"#") and b"written by `tuflexperf fit" in first_line.lower():
        return fit_yaml_kind(head) + " file"
    if head.startswith(b"\x89PNG"):
        software = _png_software(head) or ""
        if software == FLIGHT_PNG_SOFTWARE:
            return "flight plot"
        if software in (SWEEP_PNG_SOFTWARE, PNG_SOFTWARE):  # the bare name: earlier sweeps'
            return "sweep plot"
        return "report page" if software.startswith(PNG_SOFTWARE + " ") else None
    if b"\n" not in head:  # a header is a whole first line
        return None
    try:
        header = first_line.decode("utf-8").strip()
    except UnicodeDecodeError:
        return None
    columns = header.split(",")
    if header == ",".join(FLIGHT_CSV_COLUMNS):
        return "flight series"
    if header in _thrust_table_headers():
        return "thrust table"
    if _is_mission_history(columns):
        return "mission history"
    return "sweep grid" if _is_sweep_grid(columns) else None


FIT_PROPULSION_HEADER = "# Written by `tuflexperf fit` (poly22"  # the propulsion file's


def fit_yaml_kind(head: bytes) -> str:
    """Which YAML ``fit`` wrote, by its first line: ``"propulsion"`` or ``"battery"``."""
    first = head.split(b"\n", 1)[0]
    return "propulsion" if first.startswith(FIT_PROPULSION_HEADER.encode()) else "battery"


def refuse_foreign_files(outputs: dict[str, Path], command: str,
                         kinds: dict[str, str] | None = None) -> None:
    """Refuse (exit 2) to replace an existing file that ``command`` did not write (SPEC 5:
    a fitted model is not a mission's to overwrite, nor a report page a sweep's), or that
    is another artefact than the one its flag writes (``kinds``: flag -> artefact of
    :data:`ARTEFACT_WRITERS`): fit's ``--table`` may not replace a fitted propulsion model,
    nor sweep's ``--csv`` its own carpet plot."""
    for flag, out in outputs.items():
        out, target = Path(out), output_path(out)
        if target.is_symlink():  # replacing it would replace the user's link, not write through
            raise InputError(f"{flag}: {out} is a symbolic link; give the file it points to, "
                             "or another path")
        if not os.path.lexists(target) or target.is_dir():
            continue
        if not target.is_file():  # a FIFO would block the read below for ever
            raise InputError(f"{flag}: {out} is not a regular file; refusing to replace it, "
                             "choose another path")
        try:
            with open(target, "rb") as handle:
                # a mission history's header grows with its engines' names (four of 200
                # characters pass 4 KiB)
                head = handle.read(1 << 16)
        except OSError:
            head = None
        found = artefact_of(head) if head is not None else None
        if found is None:
            raise InputError(
                f"{flag}: {out} exists and is not an earlier output of tuflexperf; refusing "
                "to replace it, choose another path"
            )
        writer = ARTEFACT_WRITERS[found]
        if writer != command:
            raise InputError(
                f"{flag}: {out} was written by `tuflexperf {writer}`, not by `tuflexperf "
                f"{command}`; refusing to replace it, choose another path"
            )
        wanted = (kinds or {}).get(flag)
        if wanted is not None and found != wanted:
            raise InputError(
                f"{flag}: {out} is a {found} written by `tuflexperf {writer}`, not a "
                f"{wanted}; refusing to replace it, choose another path")
        if found.endswith(" file"):  # fit's YAML: replaced only as fit wrote it
            _refuse_unsealed(flag, out, target)
        else:
            _refuse_unmarked(flag, out, target, found, writer)


def _refuse_unmarked(flag: str, shown: Path, target: Path, found: str, writer: str) -> None:
    """Refuse to replace a CSV or PNG at ``target`` unless it is as the tool wrote it there
    (:func:`written_mark`; where the file system cannot say, its beginning was enough)."""
    mark = written_mark(target)
    if mark == _UNKNOWN:
        return
    if mark is None:
        raise InputError(
            f"{flag}: {shown} looks like a {found} of `tuflexperf {writer}` but was not written "
            "there by it (a copy, a file saved anew, or an earlier version's output): whether "
            "it is yours cannot be told; refusing to replace it, move it away or choose "
            "another path")
    try:
        same = sha256_of(target) == mark
    except OSError:
        same = False
    if not same:
        raise InputError(
            f"{flag}: {shown} was written by `tuflexperf {writer}` and changed since; refusing "
            "to replace it, move it away or choose another path")


def _refuse_unsealed(flag: str, shown: Path, target: Path) -> None:
    """Refuse to replace fit's YAML at ``target`` unless it is byte for byte as fit wrote it."""
    try:
        with open(target, "rb") as handle:
            data = handle.read(MAX_YAML_BYTES + 1)
    except OSError:
        data = b""
    if len(data) <= MAX_YAML_BYTES and seal_intact(data):
        return
    raise InputError(
        f"{flag}: {shown} was written by `tuflexperf fit` and changed since (or by a version "
        "that did not seal it): whether you edited it cannot be told; refusing to replace it, "
        "move it away or choose another path"
    )
