"""Errors that the command line turns into exit code 2 with a message naming the file and field."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path


class UserInputError(ValueError):
    """Any error caused by what the user gave (a file, a field, an option): exit code 2 with its message."""


class InputError(UserInputError):
    """Unusable input: ``str()`` is ``"<file>: <field>: <message>"`` (parts omitted when empty)."""

    def __init__(self, file: str | Path | None, field: str, message: str):
        self.file = "" if file is None else str(file)
        self.field = field
        self.message = message
        parts = [p for p in (self.file, field) if p]
        super().__init__(": ".join([*parts, message]))


class OutputExistsError(InputError):
    """An output file exists and ``--force`` was not given."""


def check_choice(value: str, choices: Iterable[str], option: str) -> str:
    """``value`` when it is one of ``choices``, else an InputError naming ``option`` and the choices."""
    names = list(choices)
    if value not in names:
        raise InputError(None, option, f"must be one of {', '.join(names)}, got {value!r}")
    return value
