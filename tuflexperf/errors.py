"""Exceptions the CLI turns into exit codes (SPEC 5)."""


class InputError(Exception):
    """Bad input: exit 2 with this one-line message (it names the file, key or flag)."""


class NotAttainable(Exception):
    """The analysis ran and its answer is "not attainable"; the message says why (exit 1).

    ``known`` holds the results found before the answer was no (e.g. the lift-off speed of
    a take-off that never reaches it), by their JSON keys.
    """

    def __init__(self, message: str, known: dict[str, float] | None = None) -> None:
        super().__init__(message)
        self.known = dict(known or {})
