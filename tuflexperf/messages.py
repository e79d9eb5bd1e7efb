"""One line per problem: how an error message is cut and escaped for stderr (SPEC 5).

Light: the console entry point and every command may use it before anything heavy is
imported (its helpers, in :mod:`tuflexperf.io.inputs`, only when a message is written).
"""

from __future__ import annotations

_MAX_MESSAGE = 1000  # characters of one error message (a file's garbage quoted is cut)


def one_line(text: str, limit: int | None = _MAX_MESSAGE) -> str:
    """``text`` as one line of at most about ``limit`` characters (SPEC 5: one line), a
    newline in a path shown escaped (it made two lines), and a file name's bytes that are
    no UTF-8 as ``\\xfc``. What is cut is the middle of the longest words (a long path, a
    binary file's garbage quoted: one was 5,091 characters), never the key, the value or
    the reason around them: a cut at the end removed those from a long path's message."""
    from tuflexperf.io.inputs import cut_middle, path_text

    text = path_text(text.replace("\r", "\\r").replace("\n", "\\n"))
    return text if limit is None else cut_middle(text, limit)
