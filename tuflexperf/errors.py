"""Exceptions the CLI turns into exit codes (SPEC 5)."""

from __future__ import annotations


class InputError(Exception):
    """Bad input: exit 2 with this one-line message (it names the file, key or flag).

    One run may find several problems (three misspelt keys, two bad files): ``problems``
    holds each as its own line, and the message is those lines.
    """

    @property
    def problems(self) -> tuple[str, ...]:
        """Every problem found, one line each (one: the message)."""
        return tuple(getattr(self, "_problems", None) or (str(self),))

    @classmethod
    def of(cls, problems: list[str] | tuple[str, ...]) -> InputError:
        """One error holding every one of ``problems`` (at least one), in order."""
        error = cls("\n".join(problems))
        error._problems = tuple(problems)
        return error


class NotAttainable(Exception):
    """The analysis ran and its answer is "not attainable"; the message says why (exit 1).

    ``known`` holds the results found before the answer was no (e.g. the lift-off speed of
    a take-off that never reaches it), by their JSON keys.
    """

    def __init__(self, message: str, known: dict[str, float] | None = None) -> None:
        super().__init__(message)
        self.known = dict(known or {})
