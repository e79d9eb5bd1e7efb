"""Every file the tool writes goes through here: one atomic writer, one output guard.

SPEC 5, "Nothing is lost": no command deletes, replaces or truncates a file it did not write
itself. An output that is, or would overwrite, one of the command's inputs is bad input; a
non-empty folder may be replaced only if it carries the marker that the same command wrote
there; output is staged beside the target and moved into place whole; files get the user's
umask; an interrupt (SIGINT, SIGTERM) leaves no staging behind and the earlier output intact.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import signal
import stat
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from tuflexperf.errors import InputError

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


MAX_YAML_BYTES = 16 << 20  # a case, aircraft, propulsion, battery or mission file
MAX_RUN_BYTES = 2 << 30  # one run file (the paper's rig: 1 kHz for minutes, a few MB)
MAX_TABLE_BYTES = 64 << 20  # a thrust table: one row per test point (~1 M rows)


def check_input_file(path: Path | str, what: str = "file", max_bytes: int = MAX_YAML_BYTES) -> Path:
    """``path`` if it is a regular, readable file of at most ``max_bytes``; else bad input.

    Refuses what would hang or exhaust memory before a byte is read: a FIFO (blocks
    forever), a device such as /dev/zero (endless), a symlink loop, a name too long.
    """
    import stat

    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except OSError as exc:
        why = {errno.ELOOP: "symbolic link loop", errno.ENAMETOOLONG: "file name too long"}
        raise InputError(f"{path}: cannot read: {why.get(exc.errno, exc.strerror)}") from None
    if stat.S_ISDIR(info.st_mode):
        raise InputError(f"{path}: is a directory, expected a {what}")
    if not stat.S_ISREG(info.st_mode):
        raise InputError(f"{path}: not a regular file (a pipe or device?), expected a {what}")
    if info.st_size > max_bytes:
        raise InputError(
            f"{path}: {info.st_size / 2**20:.0f} MiB is larger than a {what} can be "
            f"({max_bytes / 2**20:.0f} MiB)"
        )
    return path


def why_not_a_file(path: Path | str) -> str:
    """Why ``path`` is no input file: ``file not found``, or what it is instead (a directory,
    a pipe or device) — "file not found" of a folder sent the user looking for a missing file
    (outside audit)."""
    path = Path(path)
    if path.is_dir():
        return "a directory, not a file"
    if path.exists():
        return "not a regular file (a pipe or device?)"
    return "file not found"


def user_umask() -> int:
    """The process's umask (read without changing it for longer than a call)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _os_error(path: Path, exc: OSError) -> InputError:
    """A write failure as one line naming the file (disk full included)."""
    why = "disk full" if exc.errno in (errno.ENOSPC, errno.EDQUOT) else exc.strerror or str(exc)
    return InputError(f"{path}: cannot write: {why}")


def _staged_os_error(exc: OSError, staging: Path, out: Path) -> InputError:
    """An OS error inside a staged run: a write where it names the staging folder (or no
    file), else the read of the input it names (an unreadable campaign run was reported as
    "--out folder: cannot write: Permission denied"; outside audit)."""
    name = exc.filename
    if isinstance(name, (str, bytes, os.PathLike)):
        path = Path(os.fsdecode(name))
        if not (path == staging or staging in path.parents):
            return InputError(f"{path}: cannot read: {exc.strerror or exc}")
    return _os_error(out, exc)


def output_path(out: Path | str) -> Path:
    """Where an output named ``out`` lands: its folder resolved as the OS resolves it once the
    missing folders exist, its own name kept (a symbolic link there is still seen as one).

    ``missing/../folder`` is ``folder``: checked as written, nothing was there, the missing
    folder was made and the write replaced the user's folder (outside audit).
    """
    out = Path(out)
    if out.name in ("", ".", ".."):
        return Path(os.path.realpath(out))
    return Path(os.path.realpath(out.parent)) / out.name


def _short(name: str) -> str:
    """An output's name as its hidden helpers' names begin with: cut so that they stay within
    the 255 bytes a name may have (an output named with 240 characters was written once,
    then never replaced: its ``.old-`` name was too long; outside re-audit)."""
    # as the file system has it: a name of bytes that are no UTF-8 (surrogate escapes)
    # made every writer raise (outside audit); a character cut in two stays an escape
    return os.fsdecode(os.fsencode(name)[:200])


def _make_folders(folder: Path) -> list[Path]:
    """Make ``folder`` and its missing parents; return those made, outermost first (a
    failure part-way removes what it made and raises the ``OSError``)."""
    made: list[Path] = []
    try:
        for step in [folder, *folder.parents][::-1]:
            if not step.exists():
                step.mkdir()
                made.append(step)
    except OSError:
        _remove_folders(made)
        raise
    return made


def _remove_folders(made: list[Path]) -> None:
    """Remove folders :func:`_make_folders` made, innermost first (only while empty)."""
    for folder in reversed(made):
        with contextlib.suppress(OSError):
            folder.rmdir()


# Each single file the tool writes carries the sha256 of its bytes in an extended attribute:
# metadata of the file itself (no second file), which a copy (`cp`) or an editor's new file
# drops and an edit in place outdates. A later run replaces a CSV or PNG only as written (its
# header alone let a user's edited copy be replaced; outside audit). Where the file system
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
    import errno

    try:
        return os.getxattr(path, WRITTEN_XATTR).decode("ascii", "replace")
    except AttributeError:  # a platform without os.getxattr
        return _UNKNOWN
    except OSError as exc:
        return None if exc.errno == errno.ENODATA else _UNKNOWN


def write_files_atomically(files: dict[Path, bytes | str]) -> None:
    """Write several files all-or-nothing: every temporary file first, then the renames.

    Temporary files sit beside their targets (same filesystem, so ``os.replace`` is atomic)
    and get the user's umask (``mkstemp`` alone makes them 0600). On any failure, including
    an interrupt, no temporary file is left, no target is touched and no folder made for
    them stays. The renames run as one step with the interrupts held: an interrupt that
    comes meanwhile puts every earlier file back (a Ctrl-C between two renames left a new
    output beside the earlier table; outside audit) and is then raised.
    """
    import secrets  # lazy, with tempfile: `check` writes nothing
    import tempfile

    staged: list[tuple[str, Path]] = []
    created: list[Path] = []
    mode = 0o666 & ~user_umask()
    current: Path | None = None
    try:
        for path, data in files.items():
            current = output_path(path)
            created += _make_folders(current.parent)
            fd, tmp = tempfile.mkstemp(prefix=f".{_short(current.name)}.", suffix=".tmp",
                                       dir=current.parent)
            staged.append((tmp, current))
            raw = data.encode("utf-8") if isinstance(data, str) else data
            with os.fdopen(fd, "wb") as handle:
                handle.write(raw)
                handle.flush()
                os.fsync(handle.fileno())
            _mark_written(tmp, raw)
            try:  # an earlier file keeps the mode the user gave it (a 0600 file stays so)
                keep = stat.S_IMODE(current.stat().st_mode) if current.is_file() else mode
            except OSError:
                keep = mode
            os.chmod(tmp, keep)
        with interrupts_held():
            raise_if_interrupted()  # one a library dropped earlier: the run was interrupted
            kept: list[tuple[Path, Path | None]] = []  # target, its earlier file's second name
            try:
                for tmp, target in staged:
                    current = target
                    _refuse_changed_since_guarded(target)
                    old = None
                    if target.exists():
                        # a second name for the earlier file, which stays where it is until
                        # the new one replaces it in one rename (no moment without it)
                        old = target.parent / (f".{_short(target.name)}.old-"
                                               f"{secrets.token_hex(6)}")
                        try:
                            os.link(target, old)
                        except OSError:  # a file system without hard links
                            import shutil

                            shutil.copy2(target, old)
                    kept.append((target, old))
                    os.replace(tmp, target)
                    _written(target)
                raise_if_interrupted()
            except BaseException:
                for target, old in reversed(kept):  # every earlier file back in place
                    with contextlib.suppress(OSError):
                        if old is not None:
                            os.replace(old, target)
                        else:
                            target.unlink(missing_ok=True)
                raise
            _committed[0] = True
            for _, old in kept:
                if old is not None:
                    with contextlib.suppress(OSError):
                        old.unlink()
    except BaseException as exc:
        with _cleanup():
            for tmp, _ in staged:
                with contextlib.suppress(OSError):
                    Path(tmp).unlink(missing_ok=True)
            _remove_folders(created)
        if isinstance(exc, OSError):
            raise _os_error(current or Path("output"), exc) from None
        raise


def atomic_write_bytes(path: Path | str, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file and a rename: never half-written."""
    write_files_atomically({Path(path): data})


def atomic_write_text(path: Path | str, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` via a temporary file and a rename."""
    write_files_atomically({Path(path): text})


def same_file(a: Path, b: Path) -> bool:
    """True if ``a`` and ``b`` are one file on disk (a hard link or symlink included)."""
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


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
    """The varied dotted keys, then ``<requirement>_value, _limit, _passed`` per requirement."""
    keys = [c for c in columns if "." in c]
    tail = columns[len(keys):]
    if not keys or columns[: len(keys)] != keys or not tail or len(tail) % 3:
        return False
    for start in range(0, len(tail), 3):
        name = tail[start].removesuffix("_value")
        if name not in REQUIREMENT_NAMES or tail[start : start + 3] != [
                f"{name}_value", f"{name}_limit", f"{name}_passed"]:
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
    _passed`` per requirement).
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
    :data:`ARTEFACT_WRITERS`): fit's ``--table`` replaced a fitted propulsion model with a
    CSV, and sweep's ``--csv`` its own carpet plot, with exit 0 (outside audit)."""
    for flag, out in outputs.items():
        out, target = Path(out), output_path(out)
        if target.is_symlink():  # replacing it would replace the user's link, not write through
            raise InputError(f"{flag}: {out} is a symbolic link; give the file it points to, "
                             "or another path")
        if not os.path.lexists(target) or target.is_dir():
            continue
        if not target.is_file():  # a FIFO blocked the read below for ever (outside audit)
            raise InputError(f"{flag}: {out} is not a regular file; refusing to replace it, "
                             "choose another path")
        try:
            with open(target, "rb") as handle:
                # a mission history's header grows with its engines' names: 4 KiB cut one
                # of four 200-character names, refused as "not an earlier output" (audit)
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


_guarded: dict[Path, tuple[str, Path, tuple[int, int, int] | None]] = {}
"""What :func:`guard_outputs` saw at each output it allowed: flag, path as given, state."""


def _state_of(path: Path) -> tuple[int, int, int] | None:
    """An existing file's (inode, size, mtime ns), or None where there is none."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_ino, st.st_size, st.st_mtime_ns)


def _refuse_changed_since_guarded(target: Path) -> None:
    """Refuse to rename onto an output that changed after :func:`guard_outputs` allowed it
    (a file the user saved there while the command ran was overwritten; outside audit)."""
    seen = _guarded.get(target.resolve())
    if seen is not None and _state_of(target) != seen[2]:
        raise InputError(f"{seen[0]}: {seen[1]} changed while this command ran; refusing to "
                         "replace it, choose another path or run again")


def _written(target: Path) -> None:
    """A guarded output this process wrote: its new state is the one to compare with."""
    key = target.resolve()
    if key in _guarded:
        flag, shown, _ = _guarded[key]
        _guarded[key] = (flag, shown, _state_of(target))


def guard_outputs(outputs: dict[str, Path], inputs: Iterable[Path], command: str,
                  kinds: dict[str, str] | None = None) -> None:
    """Refuse an output that is, or would overwrite, one of the command's inputs, or an
    existing file that is not an earlier output of ``command`` of the artefact its flag
    writes (``kinds``: flag -> artefact, :data:`ARTEFACT_WRITERS`) (exit 2).

    ``outputs`` maps the flag (``--out``) to its path. Also refuses an output that is an
    existing directory where a file is expected. Two outputs may not be the same path.
    """
    inputs = [Path(p) for p in inputs]
    seen: dict[Path, str] = {}
    for flag, out in outputs.items():
        out, target = Path(out), output_path(out)
        resolved = target.resolve()
        _guarded[resolved] = (flag, out, _state_of(target))
        if resolved in seen:
            raise InputError(f"{flag}: {out} is also {seen[resolved]}; give different files")
        seen[resolved] = flag
        for source in inputs:
            if resolved == source.resolve() or same_file(target, source):
                raise InputError(
                    f"{flag}: {out} is an input of this command ({source}); refusing to "
                    "overwrite it, choose another path"
                )
        if target.is_dir():
            raise InputError(f"{flag}: {out} is a directory, expected a file")
    refuse_foreign_files(outputs, command, kinds)


def check_output_dir(out: Path, command: str, inputs: Iterable[Path] = ()) -> None:
    """``out`` may be new, empty, or an earlier output of ``command`` holding only what that
    command wrote (the marker lists it), and none of the command's ``inputs``.

    Anything else — a file, a symbolic link, a folder of the user's, an earlier output the
    user has added files to or that holds an input (a case saved there under a name the
    command writes was replaced by its output; outside audit) — is bad input: replacing it
    would delete what the command did not write.
    """
    shown, out = Path(out), output_path(out)
    inside = out.resolve()
    with contextlib.suppress(OSError):  # a working directory that is gone holds nothing
        here = Path.cwd().resolve()
        if inside == here or inside in here.parents:
            # replacing it left the shell in a deleted folder (outside audit)
            raise InputError(f"--out: {shown} is the working directory or holds it; "
                             "choose a folder inside or beside it")
    for source in inputs:
        found = Path(source).resolve()
        if found == inside or inside in found.parents:
            raise InputError(
                f"--out: {shown} holds {source}, an input of this command; refusing to replace "
                "the folder, choose another folder"
            )
    if out.is_symlink():  # the swap would replace the user's link, not write through it
        raise InputError(f"--out: {shown} is a symbolic link; give the folder it points to, or "
                         "another path")
    if out.exists() and not out.is_dir():
        raise InputError(f"--out: {shown} exists and is not a directory")
    # the nearest existing ancestor is where the staging folder will be made
    existing = next(p for p in (out.parent, *out.parent.parents) if p.exists())
    if not existing.is_dir():
        raise InputError(f"--out: {existing} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise InputError(f"--out: cannot write in {existing}")
    if out.is_dir():
        _refuse_unless_earlier_output(out, shown, command)


def _refuse_unless_earlier_output(out: Path, shown: Path, command: str) -> None:
    """``out`` (a folder) is empty, or holds exactly what an earlier ``command`` wrote there,
    each file as written (its marker's sha256); else bad input naming what it holds."""
    try:
        entries = _relative_files(out)
    except OSError as exc:
        raise InputError(f"--out: cannot read {shown}: {exc.strerror}") from None
    if not entries:
        return
    marker = _read_marker_data(out)
    if marker.get("command") != command:
        raise InputError(
            f"--out: {shown} is a non-empty folder that an earlier `tuflexperf {command}` did "
            "not write; refusing to replace it, choose a new or empty folder"
        )
    written, hashes = marker.get("files"), marker.get("sha256")
    if not (isinstance(written, list) and all(isinstance(n, str) for n in written)
            and isinstance(hashes, dict)
            and all(isinstance(k, str) and isinstance(v, str) for k, v in hashes.items())):
        # an earlier version's marker (names only) or one edited by hand: which files the
        # user changed cannot be told (a marker without its hashes let edits go; audit)
        raise InputError(
            f"--out: {shown} was written by `tuflexperf {command}` without the files' "
            "sha256 (an earlier version, or its marker edited): whether you changed them "
            "cannot be told; refusing to replace it, remove it or choose another folder"
        )
    # each file as the command wrote it: an edit since is the user's work (an edited
    # tfp_thrust.c, or a folder of notes where a written file was, went with the folder;
    # outside audit)
    _refuse_held(shown, [name for name in entries if name in hashes
                         and _sha256_or_none(out / name) != hashes[name]],
                 f"changed since `tuflexperf {command}` wrote it")
    listed = set(written)
    _refuse_held(shown, [name for name in entries if name != MARKER and name not in hashes
                         and name not in listed],
                 f"which the earlier `tuflexperf {command}` did not write")
    # its files are removed once the new output is in place: in a folder the user
    # write-protected they cannot be, and every run left a hidden copy behind (audit)
    folders = _folders_of(out, entries)
    locked = next((f for f in folders if not os.access(f, os.W_OK | os.X_OK)), None)
    if locked is not None:
        where = "" if locked == out else f" ({locked.relative_to(out)})"
        raise InputError(f"--out: {shown} is write-protected{where}: the earlier output "
                         "cannot be removed to replace it; make it writable or choose "
                         "another folder")


def _folders_of(out: Path, entries: list[str]) -> list[Path]:
    """``out`` and every folder under it that holds one of ``entries`` (relative paths)."""
    found = {out}
    for name in entries:
        found.update(p for p in (out / name).parents if p == out or out in p.parents)
    return sorted(found)


def _refuse_held(folder: Path, names: list[str], why: str) -> None:
    """Bad input: ``folder`` holds ``names`` (``why``), which replacing it would delete."""
    if names:
        raise InputError(
            f"--out: {folder} holds {names[0]}"
            + (f" (and {len(names) - 1} more)" if len(names) > 1 else "")
            + f", {why}; refusing to replace the folder, move that out or choose another folder"
        )


def _sha256_or_none(path: Path) -> str | None:
    """sha256 of a regular file, ``None`` for anything else (a folder, a link, unreadable)."""
    try:
        if path.is_symlink() or not path.is_file():
            return None
        return sha256_of(path)
    except OSError:
        return None


def _relative_files(folder: Path) -> list[str]:
    """Every file (and empty folder) under ``folder``, as sorted relative POSIX paths."""
    found = []
    for path in sorted(folder.rglob("*")):
        if path.is_symlink() or not path.is_dir() or not any(path.iterdir()):
            found.append(path.relative_to(folder).as_posix())
    return found


MAX_MARKER_BYTES = 16 << 20  # a marker lists files and their sha256: far below this


def _read_marker_data(folder: Path) -> dict[str, Any]:
    """The folder's marker, or ``{}`` when there is none that can be read as one: a FIFO
    there hung, /dev/zero ran out of memory, deep nesting raised (outside re-audit)."""
    path = Path(folder) / MARKER
    try:
        info = path.lstat()
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_MARKER_BYTES:
            return {}
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    return data if isinstance(data, dict) else {}


def read_marker(folder: Path) -> str | None:
    """The command that wrote ``folder`` (its marker), or ``None``."""
    command = _read_marker_data(folder).get("command")
    return command if isinstance(command, str) else None


class _Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP), delivered as an interrupt so every cleanup path runs (exit 130)."""


# Ctrl-C, kill, and the hang-up of a closed terminal or a dropped ssh session: a hang-up
# had left the staging folder and the --workers helpers behind (outside audit)
INTERRUPT_SIGNALS: tuple[int, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


_signals_received: list[int] = []


_holding = [False]  # inside interrupts_held(): an interrupt is noted, raised at its end
# the command's output has replaced the earlier one: an interrupt after that is noted, not
# raised, and the run ends as done (its earlier output is gone, so "aborted" would be false)
_committed = [False]


def _interrupt(signum: int) -> KeyboardInterrupt:
    return KeyboardInterrupt() if signum == signal.SIGINT else _Terminated()


def _raise_interrupt(signum: int, frame: object) -> None:
    if _committed[0]:
        return
    _signals_received.append(signum)
    if not _holding[0]:
        raise _interrupt(signum)


@contextlib.contextmanager
def _cleanup() -> Iterator[None]:
    """Hold interrupts while staging is removed on the way out: a second Ctrl-C landing in
    the removal left staging folders behind (outside audit); the run is unwinding already."""
    holding = _holding[0]
    _holding[0] = True
    try:
        yield
    finally:
        _holding[0] = holding


def hold_interrupts() -> None:
    """From here on an interrupt is noted, not raised: the process is on its way out."""
    _holding[0] = True


def output_committed() -> bool:
    """True once the command's output has replaced the earlier one (SPEC 5)."""
    return _committed[0]


def install_interrupt_handlers() -> None:
    """Make SIGTERM unwind like Ctrl-C (staging removed, earlier output intact), and note
    that either came, for :func:`interrupted`.

    An interrupt raised where Python cannot raise it (a finalizer, an import's callback) is
    dropped with an "Exception ignored" traceback on stderr; it is noted already, and raised
    again later (:func:`raise_if_interrupted`, the CLI's exit), so that traceback goes.
    """
    import sys

    # a new run (the CLI's main may run many times in one process, as in tests)
    _signals_received.clear()
    _committed[0] = False
    _holding[0] = False
    default_hook = sys.unraisablehook

    def quiet_interrupts(unraisable: Any) -> None:
        if not isinstance(unraisable.exc_value, KeyboardInterrupt):
            default_hook(unraisable)

    with contextlib.suppress(ValueError):  # not the main thread: leave the defaults
        for signum in INTERRUPT_SIGNALS:
            signal.signal(signum, _raise_interrupt)
        sys.unraisablehook = quiet_interrupts


@contextlib.contextmanager
def interrupts_held() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM back while the block runs (e.g. a fork): noted, not raised,
    then raised when the block ends.

    Python runs a signal's handler at any bytecode of the main thread, also inside the
    callbacks that ``os.fork`` runs, where the interrupt it raises is printed as "ignored"
    and dropped: the report went on to the end. (Blocking the signal would not do: the
    kernel hands it to another thread, e.g. a BLAS worker.) A helper forked inside the
    block calls :func:`release_interrupts`.
    """
    seen = len(_signals_received)
    _holding[0] = True
    try:
        yield
    finally:
        _holding[0] = False
    if len(_signals_received) > seen:
        raise_if_interrupted()


def release_interrupts() -> None:
    """In a forked helper: Ctrl-C and SIGTERM end it at once (the default action); the
    parent reports the interrupt and removes what was staged."""
    _signals_received.clear()  # the parent's to report, not this helper's
    _holding[0] = False
    for signum in INTERRUPT_SIGNALS:
        signal.signal(signum, signal.SIG_DFL)


def start_helper(target: Callable[..., None], args: tuple[Any, ...],
                 helpers: list[Any]) -> Any:
    """``target(*args)`` in a helper process (forked where the platform can), listed in
    ``helpers`` for :func:`stop_helpers`; returns the process.

    The interrupts are held across the fork until the helper is listed: one raised inside
    the fork's own callbacks would be dropped, and one raised before the listing would
    leave the helper running. In the helper, Ctrl-C or SIGTERM (sent to the whole process
    group) just ends it; the parent reports it and removes what was staged.
    """
    import multiprocessing

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else None
    with interrupts_held():
        helper = multiprocessing.get_context(method).Process(
            target=_helper_body, args=(target, args), daemon=True
        )
        helper.start()
        helpers.append(helper)
    return helper


def _helper_body(target: Callable[..., None], args: tuple[Any, ...]) -> None:
    release_interrupts()
    try:
        target(*args)
    except Exception:  # noqa: BLE001 - said once, by the parent
        # the parent does again what a helper left undone, and reports an error there in
        # one line (a full disk printed the helper's 35-line traceback as well; audit)
        os._exit(1)


def stop_helpers(helpers: list[Any]) -> None:
    """Stop every helper of :func:`start_helper` still running, and wait for them all.

    SIGKILL, not SIGTERM: a helper holds nothing to clean up (what it writes is staged),
    and a SIGTERM landing between its fork and its taking the default action would be
    lost (the helper then ran on, e.g. blocked on a full pipe, while the parent waited).
    """
    for helper in helpers:
        if helper.is_alive():
            helper.kill()
    for helper in helpers:
        helper.join()


def raise_if_interrupted() -> None:
    """Raise the interrupt again if one has come: Python prints an exception raised in a
    finalizer (or a fork's callback) as "ignored" and goes on, so a Ctrl-C that lands there
    is lost unless long work looks again between its steps."""
    if _signals_received:
        raise _interrupt(_signals_received[-1])


def interrupted() -> bool:
    """True once Ctrl-C or SIGTERM has come. A reader may turn the interrupt raised inside
    it into an error of its own (pandas: "Calling read(nbytes) on source failed"), which
    must not then be reported as a bad input file."""
    return bool(_signals_received)


@contextlib.contextmanager
def staged_directory(out: Path, command: str, inputs: Iterable[Path] = ()) -> Iterator[Path]:
    """Stage a folder beside ``out``, yield it, then move it into place whole.

    The staging folder gets the user's umask and, on success, the marker naming
    ``command`` and the files written. An earlier output at ``out`` (checked by
    :func:`check_output_dir` against the command's ``inputs``) is swapped out and removed
    only after the new one is in place. On any failure or interrupt (one that came at any
    time before the swap) the staging folder is removed and ``out`` is untouched; after
    the swap the run is done, and an interrupt is no longer noted.
    """
    import secrets  # lazy, with shutil: only the commands that write a folder need them
    import shutil

    check_output_dir(out, command, inputs)
    shown, out = Path(out), output_path(out)
    try:
        created = _make_folders(out.parent)
    except OSError as exc:
        raise InputError(f"--out: cannot create {exc.filename}: {exc.strerror}") from None
    staging = out.parent / f".{_short(out.name)}.tmp-{secrets.token_hex(6)}"
    try:
        staging.mkdir(mode=0o777 & ~user_umask())
    except OSError as exc:
        _remove_folders(created)
        raise InputError(f"--out: cannot write in {out.parent}: {exc.strerror}") from None
    try:
        yield staging
        # every file written (relative paths): a later run replaces the folder only while
        # it holds nothing else
        names = _relative_files(staging)
        hashes = {name: _sha256_or_none(staging / name) for name in names}
        marker = json.dumps({"command": command, "files": names,
                             "sha256": {name: h for name, h in hashes.items() if h is not None}},
                            indent=1)
        try:
            (staging / MARKER).write_text(marker + "\n", encoding="utf-8")
        except OSError as exc:
            raise _os_error(staging / MARKER, exc) from None
        # the swap and the earlier output's removal run to their end: an interrupt there
        # would leave `out` missing between the renames, or the earlier output behind as
        # a hidden folder; it is raised when they are done
        with interrupts_held():
            raise_if_interrupted()  # one a library dropped earlier: the run was interrupted
            if out.exists() or out.is_symlink():
                old = out.parent / f".{_short(out.name)}.old-{secrets.token_hex(6)}"
                os.replace(out, old)
                # checked again where nothing reaches it by its name: a note the user put
                # into the earlier output while this run worked was deleted with it (audit)
                try:
                    if old.is_symlink() or not old.is_dir():
                        raise InputError(f"--out: {shown} became a file or a link while "
                                         "this run worked; refusing to replace it")
                    _refuse_unless_earlier_output(old, shown, command)
                except BaseException:
                    os.replace(old, out)
                    raise
                with contextlib.suppress(OSError):  # the folder's mode stays the user's
                    os.chmod(staging, stat.S_IMODE(old.stat().st_mode))
                os.replace(staging, out)
                if _signals_received:
                    # interrupted before the swap was done: the earlier output stays (SPEC 5);
                    # the new one goes back to the staging, which the unwinding removes
                    os.replace(out, staging)
                    os.replace(old, out)
                else:
                    _committed[0] = True
                    shutil.rmtree(old, ignore_errors=True)
            else:
                os.replace(staging, out)
                if _signals_received:
                    os.replace(out, staging)
                else:
                    _committed[0] = True
    except BaseException as exc:
        with _cleanup():
            shutil.rmtree(staging, ignore_errors=True)
            _remove_folders(created)
        if isinstance(exc, OSError):
            raise _staged_os_error(exc, staging, out) from None
        raise
