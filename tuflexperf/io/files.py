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
import json
import os
import signal
import stat
import sys
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from tuflexperf.errors import InputError
from tuflexperf.io import swap
from tuflexperf.io.artefacts import (  # noqa: F401 - re-exported: the writers' checks
    FIT_PROPULSION_HEADER,
    FLIGHT_PNG_SOFTWARE,
    MARKER,
    SEAL,
    SWEEP_PNG_SOFTWARE,
    _mark_written,
    output_path,
    refuse_foreign_files,
    seal_intact,
    sealed,
    sha256_of,
)
from tuflexperf.io.inputs import why_not_a_file  # noqa: F401 - re-exported: every reader's


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
    file), else the read of the input it names (an unreadable run is no write failure)."""
    name = exc.filename
    if isinstance(name, (str, bytes, os.PathLike)):
        path = Path(os.fsdecode(name))
        if not (path == staging or staging in path.parents):
            return InputError(f"{path}: cannot read: {exc.strerror or exc}")
    return _os_error(out, exc)


def _short(name: str) -> str:
    """An output's name as its hidden helpers' names begin with: cut so that they stay within
    the 255 bytes a name may have (a long output's ``.old-`` name must fit too)."""
    # in the file system's bytes (a name that is no UTF-8 has surrogate escapes); a character
    # cut in two stays an escape
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


_CLOEXEC = getattr(os, "O_CLOEXEC", 0)


def write_files_atomically(files: dict[Path, bytes | str]) -> None:
    """Write several files all-or-nothing: every temporary file first, then the renames.

    Temporary files sit beside their targets (same filesystem, so ``os.replace`` is atomic)
    and get the user's umask (``mkstemp`` alone makes them 0600). On any failure, including
    an interrupt, no temporary file is left, no target is touched and no folder made for
    them stays. The renames run as one step with the interrupts held: an interrupt that
    comes meanwhile puts every earlier file back (never a new output beside an earlier one)
    and is then raised.
    """
    staged: list[tuple[str, Path]] = []
    created: list[Path] = []
    mode = 0o666 & ~user_umask()
    current: Path | None = None
    try:
        for path, data in files.items():
            current = output_path(path)
            created += _make_folders(current.parent)
            swap.clean_stale(current, _short(current.name))  # a killed run's, beside it
            tmp = str(current.parent / swap.hidden_name(_short(current.name), "tmp"))
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _CLOEXEC, 0o600)
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
                        old = target.parent / swap.hidden_name(_short(target.name), "old")
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


def atomic_write_text(path: Path | str, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` via a temporary file and a rename."""
    write_files_atomically({Path(path): text})


def same_file(a: Path, b: Path) -> bool:
    """True if ``a`` and ``b`` are one file on disk (a hard link or symlink included)."""
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def listed_file(listing: Path, key: str, name: str, earlier: Iterable[Path] = (),
                twice: str = "", shown: bool = False) -> Path:
    """The file ``name`` that the file ``listing`` names under ``key``, resolved beside it.

    Bad input naming ``listing`` and ``key`` when it is no regular file (``shown``: where it
    was looked for too), or is one of ``earlier`` (a hard link of one too: it would count
    twice; ``twice`` ends that message).
    """
    target = (Path(listing).parent / name).resolve()
    if not target.is_file():
        where = f" (resolved to {target})" if shown else ""
        raise InputError(f"{listing}: {key}: {why_not_a_file(target)}: {name}{where}")
    if any(target == e or same_file(target, e) for e in earlier):
        raise InputError(f"{listing}: {key}: {name} is listed twice{twice}")
    return target


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
    (a file the user saved there while the command ran is theirs)."""
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
    user has added files to or that holds an input — is bad input: replacing it would delete
    what the command did not write.
    """
    shown, out = Path(out), output_path(out)
    inside = out.resolve()
    with contextlib.suppress(OSError):  # a working directory that is gone holds nothing
        here = Path.cwd().resolve()
        if inside == here or inside in here.parents:
            # replacing it would leave the shell in a deleted folder
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
        # user changed cannot be told
        raise InputError(
            f"--out: {shown} was written by `tuflexperf {command}` without the files' "
            "sha256 (an earlier version, or its marker edited): whether you changed them "
            "cannot be told; refusing to replace it, remove it or choose another folder"
        )
    # each file as the command wrote it: an edit since (a changed tfp_thrust.c, a folder of
    # notes where a written file was) is the user's work
    _refuse_held(shown, [name for name in entries if name in hashes
                         and _sha256_or_none(out / name) != hashes[name]],
                 f"changed since `tuflexperf {command}` wrote it")
    listed = set(written)
    _refuse_held(shown, [name for name in entries if name != MARKER and name not in hashes
                         and name not in listed],
                 f"which the earlier `tuflexperf {command}` did not write")
    # its files are removed once the new output is in place: in a folder the user
    # write-protected they cannot be, and every run would leave a hidden copy behind
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
    """The folder's marker, or ``{}`` when there is none that can be read as one (a FIFO,
    a device, a huge or deeply nested file is none)."""
    path = Path(folder) / MARKER
    try:
        info = path.lstat()
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_MARKER_BYTES:
            return {}
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    return data if isinstance(data, dict) else {}


class _Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP), delivered as an interrupt so every cleanup path runs (exit 130)."""


# Ctrl-C, kill, and the hang-up of a closed terminal or a dropped ssh session: each unwinds
# the staging folder and the --workers helpers
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
    the removal would leave staging behind, and the run is unwinding already."""
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
            target=_helper_body, args=(target, args, os.getpid()), daemon=True
        )
        helper.start()
        helpers.append(helper)
    return helper


def _helper_body(target: Callable[..., None], args: tuple[Any, ...], parent: int) -> None:
    release_interrupts()
    _die_with(parent)
    try:
        target(*args)
    except Exception:  # noqa: BLE001 - said once, by the parent
        # the parent does again what a helper left undone, and reports an error there in
        # one line (no helper's traceback beside it)
        os._exit(1)


def _die_with(parent: int) -> None:
    """End this helper when its parent dies, however (Linux): a SIGKILLed report's page
    writers ran on into a staging folder the next run was removing as debris."""
    if sys.platform.startswith("linux"):
        import ctypes

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # it died before that took hold
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


def _commit_or_back(held: Path, out: Path, shown: Path, command: str,
                    earlier: list[Path | None], staging: Path | None = None) -> None:
    """The earlier output, now at ``held``, is checked again where nothing reaches it by
    its name (a note the user put into it while this run worked is theirs), then removed;
    on a failure or an interrupt it goes back to ``out``.

    ``staging`` None: ``out`` holds the new output already (exchanged); else ``out`` is
    free and the new output moves in from ``staging``. ``earlier[0]`` follows where the
    earlier output is, None once it is back at ``out`` or committed to go.
    """
    import shutil

    def back() -> None:
        if staging is None:
            if not swap.exchange(held, out):
                raise OSError(errno.EINVAL, "the exchange was refused", os.fsdecode(out))
        else:
            if os.path.lexists(out):
                os.replace(out, staging)
            os.replace(held, out)
        earlier[0] = None

    try:
        if held.is_symlink() or not held.is_dir():
            raise InputError(f"--out: {shown} became a file or a link while this run "
                             "worked; refusing to replace it")
        _refuse_unless_earlier_output(held, shown, command)
        if staging is not None:
            os.replace(staging, out)
    except BaseException:
        back()
        raise
    if _signals_received:
        # interrupted before the swap was done: the earlier output stays (SPEC 5); the new
        # one goes back to the staging, which the unwinding removes
        back()
        return
    _committed[0] = True
    earlier[0] = None
    shutil.rmtree(held, ignore_errors=True)


@contextlib.contextmanager
def staged_directory(out: Path, command: str, inputs: Iterable[Path] = ()) -> Iterator[Path]:
    """Stage a folder beside ``out``, yield it, then move it into place whole.

    The staging folder gets the user's umask and, on success, the marker naming
    ``command`` and the files written. An earlier output at ``out`` (checked by
    :func:`check_output_dir` against the command's ``inputs``) is exchanged with the new
    one in one step (:func:`tuflexperf.io.swap.exchange`; two renames only where the file
    system refuses that) and removed only after the new one is in place; what a killed
    run left beside ``out`` is cleaned first (:func:`tuflexperf.io.swap.clean_stale`).
    On any failure or interrupt (one that came at any time before the swap) the staging
    folder is removed and ``out`` is untouched; after the swap the run is done, and an
    interrupt is no longer noted.
    """
    import shutil  # lazy: only the commands that write a folder need it

    target = output_path(out)
    swap.clean_stale(target, _short(target.name))  # what a killed run left beside `out`
    check_output_dir(out, command, inputs)
    shown, out = Path(out), target
    try:
        created = _make_folders(out.parent)
    except OSError as exc:
        raise InputError(f"--out: cannot create {exc.filename}: {exc.strerror}") from None
    staging = out.parent / swap.hidden_name(_short(out.name), "tmp")
    earlier: list[Path | None] = [None]  # where the earlier output is while not at `out`
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
        # would leave the earlier output behind as a hidden folder; it is raised when
        # they are done
        with interrupts_held():
            raise_if_interrupted()  # one a library dropped earlier: the run was interrupted
            if out.exists() or out.is_symlink():
                with contextlib.suppress(OSError):  # the folder's mode stays the user's
                    os.chmod(staging, stat.S_IMODE(out.lstat().st_mode))
                if swap.exchange(staging, out):  # `out` is the new output, at once
                    earlier[0] = staging
                    _commit_or_back(staging, out, shown, command, earlier)
                else:  # no exchange here (swap's docstring): two renames, a moment apart
                    old = out.parent / swap.hidden_name(_short(out.name), "old")
                    os.replace(out, old)
                    earlier[0] = old
                    _commit_or_back(old, out, shown, command, earlier, staging)
            else:
                os.replace(staging, out)
                if _signals_received:
                    os.replace(out, staging)
                else:
                    _committed[0] = True
    except BaseException as exc:
        kept = earlier[0]
        with _cleanup():
            if kept is None:
                shutil.rmtree(staging, ignore_errors=True)
            _remove_folders(created)
        if kept is not None:  # putting the earlier output back failed: it stays, named
            raise InputError(f"--out: {shown}: the earlier output could not be put back "
                             f"({exc}); it is {kept}") from None
        if isinstance(exc, OSError):
            raise _staged_os_error(exc, staging, out) from None
        raise
