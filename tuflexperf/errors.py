"""Exceptions the CLI turns into exit codes (SPEC 5)."""


class InputError(Exception):
    """Bad input: exit 2 with this one-line message (it names the file, key or flag)."""


class NotAttainable(Exception):
    """The analysis ran and its answer is "not attainable"; the message says why (exit 1)."""
