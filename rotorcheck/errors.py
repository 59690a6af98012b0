"""Errors that the command line turns into exit code 2 with a message naming the file and field."""

from __future__ import annotations

import math
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


def finite_positive(value: float | None, option: str, *, allow_zero: bool = False,
                    maximum: float | None = None) -> float | None:
    """``value`` when it is None or a finite number > 0 (>= 0 with ``allow_zero``, <= ``maximum`` when given),
    else an InputError naming ``option``."""
    if value is None:
        return None
    ok = math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok or (maximum is not None and value > maximum):
        want = ">= 0" if allow_zero else "> 0"
        if maximum is not None:
            want += f" and <= {maximum:g}"
        raise InputError(None, option, f"must be a finite number {want}, got {value!r}")
    return value


def in_open_unit(value: float, option: str) -> float:
    """``value`` when it is in (0, 1), else an InputError naming ``option`` (NaN refused)."""
    if not 0.0 < value < 1.0:  # NaN compares false
        raise InputError(None, option, f"must be in (0, 1), got {value!r}")
    return value


#: a rig_id is a name: letters, digits, "_", "-", "."; not starting with "." (so never "." or "..")
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.")


def check_rig_id(value: object, file: str | Path | None, field: str) -> str:
    """``value`` when it is a rig NAME (letters, digits, ``_-.``, 1-128 characters, no path: no ``/``, ``\\``,
    not starting with ``.``), else an InputError naming ``file`` and ``field``; used by every reader and writer
    of a rig_id, so a rig_id never names a file elsewhere on disk."""
    if not isinstance(value, str) or not 0 < len(value) <= 128 or value.startswith(".") \
            or not set(value) <= _NAME_CHARS or ".." in value:
        raise InputError(file, field, f"{value!r} is no rig name (letters, digits, '_', '-', '.'; no path)")
    return value
