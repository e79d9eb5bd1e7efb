"""One line per problem: how an error message is cut and escaped for stderr (SPEC 5).

Standard library only: the console entry point and every command may use it before
anything heavy is imported.
"""

from __future__ import annotations

_MAX_MESSAGE = 1000  # characters of one error message (a file's garbage quoted is cut)


def one_line(text: str, limit: int | None = _MAX_MESSAGE) -> str:
    """``text`` as one line of at most ``limit`` characters (SPEC 5: one line):
    a newline in a path is shown escaped (it made two lines), and a message quoting a
    binary file's garbage is cut (one was 5,091 characters; outside audit)."""
    text = text.replace("\r", "\\r").replace("\n", "\\n")
    if limit is None or len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text) - limit} more characters)"
