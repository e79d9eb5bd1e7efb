"""What every reader shares: the size caps of input files, the check that a path is a
regular file within its cap, and how a path is shown in text.

Kept apart from :mod:`tuflexperf.io.files` (the writers) so that the readers
(:mod:`~tuflexperf.io.runs`, :mod:`~tuflexperf.io.yamlio`, ...) import no writer: the
writers import the readers' column names, and the readers importing the writers back
made an import circle.
"""

from __future__ import annotations

import errno
import os
import re
import stat
from pathlib import Path

from tuflexperf.errors import InputError

MAX_YAML_BYTES = 16 << 20  # a case, aircraft, propulsion, battery or mission file
MAX_RUN_BYTES = 2 << 30  # one run file (the paper's rig: 1 kHz for minutes, a few MB)
MAX_TABLE_BYTES = 64 << 20  # a thrust table: one row per test point (~1 M rows)


def path_text(path: Path | str | bytes) -> str:
    """``path`` (or a text naming one) as text that any UTF-8 writer takes: bytes of a name
    that are no UTF-8 (a Latin-1 ``ü`` from an old archive) as ``\\xfc``, the rest as it is.

    Python holds such bytes as lone surrogates (``os.fsdecode``, surrogateescape), which
    the UTF-8 encoder of a YAML file, a JSON file or a PNG's text refuses: ``fit`` and
    ``report`` under such a folder must not end in a ``UnicodeEncodeError``.
    """
    text = os.fsdecode(path) if isinstance(path, (bytes, os.PathLike)) else path
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        pass
    try:  # the name's own bytes, those that are no UTF-8 escaped
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate no file name has: its code point
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


NAME_ERRORS = "tuflexperf.names"
"""The codec error handler that writes a lone surrogate as :func:`path_text` does."""


def _escape_names(error: UnicodeError) -> tuple[str, int]:
    if not isinstance(error, UnicodeEncodeError):
        raise error
    bad = error.object[error.start:error.end]
    return "".join(f"\\x{ord(c) - 0xDC00:02x}" if "\udc80" <= c <= "\udcff"
                   else c.encode("ascii", "backslashreplace").decode("ascii")
                   for c in bad), error.end


def register_name_errors() -> str:
    """Register :data:`NAME_ERRORS` (idempotent) and return its name: a stream that would
    raise on a file name's bytes (stdout in a UTF-8 locale) writes them escaped instead."""
    import codecs

    codecs.register_error(NAME_ERRORS, _escape_names)
    return NAME_ERRORS


def cut_middle(text: str, limit: int, keep: int = 60) -> str:
    """``text`` within about ``limit`` characters, cut in the middle of its longest words
    (runs without a space: a path, a quoted garbage), each keeping ``keep`` characters
    (its two ends), longest first; the words around them stay whole. Only if that is not
    enough, the middle of the text goes, keeping its first third and last two thirds."""
    if len(text) <= limit:
        return text
    words = re.split(r"(\s+)", text)
    excess = len(text) - limit
    for index in sorted(range(len(words)), key=lambda k: -len(words[k])):
        word = words[index]
        if excess <= 0 or len(word) <= keep or word.isspace():
            break
        cut = min(len(word) - keep, excess + 24)  # + the mark's own length
        head = (len(word) - cut) // 2
        mark = f"...({cut} characters)..."
        words[index] = word[:head] + mark + word[head + cut:]
        excess -= cut - len(mark)
    text = "".join(words)
    if len(text) <= limit + 24:
        return text
    head, tail = limit // 3, limit - limit // 3
    return f"{text[:head]}...({len(text) - head - tail} characters)...{text[-tail:]}"


def check_input_file(path: Path | str, what: str = "file", max_bytes: int = MAX_YAML_BYTES) -> Path:
    """``path`` if it is a regular, readable file of at most ``max_bytes``; else bad input.

    Refuses what would hang or exhaust memory before a byte is read: a FIFO (blocks
    forever), a device such as /dev/zero (endless), a symlink loop, a name too long.
    """
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
    a pipe or device), never "file not found" of a file that is there."""
    path = Path(path)
    if path.is_dir():
        return "a directory, not a file"
    if path.exists():
        return "not a regular file (a pipe or device?)"
    return "file not found"
