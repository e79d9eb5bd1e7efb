"""Replacing an output folder with no moment without it, and the hidden names the writers use.

:func:`exchange` swaps two folders in one step: Linux's ``renameat2`` with
``RENAME_EXCHANGE`` (since Linux 3.15; ext4, XFS, Btrfs, tmpfs and others). Where the kernel
or the file system refuses it (``EINVAL``, ``ENOSYS``, ``EOPNOTSUPP``: an older kernel, some
network and FUSE file systems, or another OS), it returns False and the writer falls back to
two renames, the earlier output moved aside and the new one moved in: for the moment between
them the output's name holds nothing. A SIGKILL exactly there (the OOM killer, a CI time-out)
leaves the earlier output under its hidden ``.old-`` name; the next run of the same output
puts it back (:func:`clean_stale`).

Every hidden name a writer makes beside its output says who made it
(:func:`hidden_name`): ``.<output>.<tmp|old>-<machine>-<pid>-<start>-<random>``, the
machine a hash of the host name and PID namespace, ``start`` the process's start time in
clock ticks since boot. A name of that form whose process is gone (no such PID, or one
started at another time) on this machine, owned by this user, is debris of a run that
was killed: :func:`clean_stale` removes it at the next run of the same output, with a
one-line note on stderr. Anything else (another machine's, a live process's, an earlier
version's names, the user's own files) is left alone.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tuflexperf.io.inputs import path_text

RENAME_EXCHANGE = 2  # linux/fs.h
_AT_FDCWD = -100
# renameat2's system call number where the C library has no wrapper (glibc < 2.28)
_SYS_RENAMEAT2 = {"x86_64": 316, "aarch64": 276, "riscv64": 276, "i686": 353, "i386": 353,
                  "armv7l": 382, "ppc64le": 357, "ppc64": 357, "s390x": 347}
# what a kernel or file system without the exchange answers: fall back to two renames
REFUSED = frozenset({errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP,
                     getattr(errno, "ENOTSUP", errno.EOPNOTSUPP)})
Exchange = Callable[[bytes, bytes, int], int]  # (old, new, flags) -> 0, or -1 with errno
_call: list[Exchange | None] = []  # the C function found once (None: none on this platform)


def _from_libc(libc: Any, machine: str) -> Exchange | None:
    """renameat2 of the C library ``libc`` (ctypes), or its system call (number by
    ``machine``) where the library has no wrapper; None where neither is known."""
    import ctypes

    wrapper = getattr(libc, "renameat2", None)
    if wrapper is not None:
        wrapper.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                            ctypes.c_uint]
        return lambda a, b, flags: int(wrapper(_AT_FDCWD, a, _AT_FDCWD, b, flags))
    if machine not in _SYS_RENAMEAT2:
        return None
    number, syscall = _SYS_RENAMEAT2[machine], libc.syscall
    return lambda a, b, flags: int(syscall(
        ctypes.c_long(number), ctypes.c_int(_AT_FDCWD), ctypes.c_char_p(a),
        ctypes.c_int(_AT_FDCWD), ctypes.c_char_p(b), ctypes.c_uint(flags)))


def _renameat2() -> Exchange | None:
    """:func:`_from_libc` of this process's C library, found once; None off Linux."""
    if not _call:
        found = None
        if sys.platform.startswith("linux"):
            import ctypes

            with contextlib.suppress(OSError):
                found = _from_libc(ctypes.CDLL(None, use_errno=True), os.uname().machine)
        _call.append(found)
    return _call[0]


def exchange(a: Path, b: Path) -> bool:
    """Swap the folders (or files) at ``a`` and ``b`` in one atomic step; both must exist.

    Returns False, having changed nothing, where the kernel or the file system has no such
    step (:data:`REFUSED`, or no ``renameat2`` on this platform): the caller then uses two
    renames (module docstring). Any other failure raises the ``OSError``.
    """
    import ctypes

    call = _renameat2()
    if call is None:
        return False
    if call(os.fsencode(a), os.fsencode(b), RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in REFUSED:
        return False
    raise OSError(code, os.strerror(code), os.fsdecode(a), None, os.fsdecode(b))


# ---- the hidden names' owner -----------------------------------------------------------------


def _start_ticks(pid: int) -> int | None:
    """When process ``pid`` started, in clock ticks since boot (Linux /proc), else None."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as handle:
            text = handle.read()
    except OSError:
        return None
    # the command name in parentheses may hold spaces: the fields follow the last ')'
    fields = text[text.rfind(b")") + 2:].split()
    try:
        return int(fields[19])  # field 22 of proc(5), the 20th after the name
    except (IndexError, ValueError):
        return None


def _machine() -> str:
    """8 hex digits naming this host and PID namespace: a PID means a process only there."""
    import hashlib

    try:
        namespace = os.stat("/proc/self/ns/pid").st_ino
    except OSError:
        namespace = 0
    return hashlib.sha256(f"{os.uname().nodename}\0{namespace}".encode()).hexdigest()[:8]


_owner: dict[int, str] = {}  # per PID: a forked helper names its files as itself


def _owner_tag() -> str:
    pid = os.getpid()
    if pid not in _owner:
        _owner[pid] = f"{_machine()}-{pid}-{_start_ticks(pid) or 0}"
    return _owner[pid]


def hidden_name(short: str, kind: str) -> str:
    """A hidden name beside an output whose name begins with ``short``: ``kind`` is
    ``tmp`` (the new output being staged) or ``old`` (the earlier one on its way out)."""
    return f".{short}.{kind}-{_owner_tag()}-{os.urandom(6).hex()}"


_HIDDEN = re.compile(r"(tmp|old)-([0-9a-f]{8})-([0-9]+)-([0-9]+)-[0-9a-f]{12}")


def _gone(pid: int, start: int) -> bool:
    """True where process ``pid`` (started at ``start`` ticks) is no longer running."""
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # another user's live process
        return False
    now = _start_ticks(pid)
    return start != 0 and now is not None and now != start  # the PID was given again


def _only_the_tools(tree: Path) -> bool:
    """True where a folder a killed run left holds nothing but what the tool wrote: no
    marker yet (a staging folder, killed while being written), or each file as its marker
    lists it. An earlier output exchanged out of the way holds a note the user added to it
    during the run until the check that refuses the swap: such a folder stays."""
    import hashlib
    import json

    from tuflexperf.io.artefacts import MARKER

    marker = tree / MARKER
    if not marker.is_file():
        return not marker.is_symlink()
    try:
        data = json.loads(marker.read_text(encoding="utf-8"))
        hashes, listed = data["sha256"], set(data["files"])
        for path in tree.rglob("*"):
            name = path.relative_to(tree).as_posix()
            if name == MARKER or (path.is_dir() and not path.is_symlink()):
                continue
            if path.is_symlink() or not path.is_file():
                if name not in listed:
                    return False
            elif hashes.get(name) != hashlib.sha256(path.read_bytes()).hexdigest():
                return False
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return True


def clean_stale(out: Path, short: str) -> None:
    """Remove what killed runs of the tool left beside ``out`` under its hidden names
    (module docstring), and put an earlier output found only under its ``.old-`` name
    back at ``out``. One line on stderr says what was done; nothing else is touched."""
    import shutil

    folder, prefix = out.parent, f".{short}."
    try:
        names = [e.name for e in os.scandir(folder) if e.name.startswith(prefix)]
    except OSError:
        return
    done: list[str] = []
    restored = None
    for name in sorted(names, key=lambda n: ".old-" not in n):  # a restore before a removal
        found = _HIDDEN.fullmatch(name[len(prefix):])
        if found is None or found.group(2) != _machine():
            continue
        if not _gone(int(found.group(3)), int(found.group(4))):
            continue
        path = folder / name
        try:
            info = path.lstat()
            if info.st_uid != os.getuid() or not (stat.S_ISDIR(info.st_mode)
                                                  or stat.S_ISREG(info.st_mode)):
                continue
            if found.group(1) == "old" and not os.path.lexists(out):
                os.rename(path, out)  # killed between the fallback's two renames
                restored = name
                continue
            if stat.S_ISDIR(info.st_mode):
                if not _only_the_tools(path):
                    continue
                shutil.rmtree(path)
            else:
                path.unlink()
        except OSError:
            continue
        done.append(name)
    if restored or done:
        said = [f"put the earlier output back from {restored}"] if restored else []
        if done:
            said.append(f"removed {done[0]}" + (f" and {len(done) - 1} more" if len(done) > 1
                                                 else ""))
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.write(f"tuflexperf: note: {path_text('; '.join(said))} beside "
                             f"{path_text(out.name)}, left by a run that was killed\n")


# ---- scratch folders in the temporary directory ---------------------------------------------
_SCRATCH = re.compile(r"tuflexperf-[a-z]+-([0-9a-f]{8})-([0-9]+)-([0-9]+)-[a-z0-9_]+")


def scratch(kind: str) -> Any:
    """``tempfile.TemporaryDirectory`` for ``kind`` (``report``, ``export``), its name saying
    who made it like :func:`hidden_name`; the scratch folders of killed runs (SIGKILL leaves
    them) are removed first, silently: nothing in them was ever the user's."""
    import shutil
    import tempfile

    folder = Path(tempfile.gettempdir())
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            found = _SCRATCH.fullmatch(entry.name)
            if (found is None or found.group(1) != _machine()
                    or not _gone(int(found.group(2)), int(found.group(3)))):
                continue
            with contextlib.suppress(OSError):
                if entry.stat(follow_symlinks=False).st_uid == os.getuid() and entry.is_dir(
                        follow_symlinks=False):
                    shutil.rmtree(entry.path)
    return tempfile.TemporaryDirectory(prefix=f"tuflexperf-{kind}-{_owner_tag()}-")
