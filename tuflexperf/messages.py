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


CEILING_RULE = "ceilings to 10 m, below 1000 m to 1 m"


def ceiling_text(value_m: float) -> str:
    """A ceiling as shown [m]: to 10 m at 1000 m and above, to 1 m below (its root-find and
    the model's own accuracy make a tenth of a metre noise); the JSON keeps every digit."""
    step = 10.0 if abs(value_m) >= 1000.0 else 1.0
    return f"{step * round(value_m / step):.0f}"
