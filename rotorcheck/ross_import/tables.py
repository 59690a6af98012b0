"""Reading a ROSS rotor file: the bounded TOML load, its tables with typed getters whose errors name
``table.key``, and the small text helpers the import's notes and names use."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.errors import InputError
from rotorcheck.fileio import read_bounded_text
from rotorcheck.safeload import load_toml

#: a ROSS file larger than this is refused before it is parsed (bytes)
MAX_ROSS_BYTES = 50_000_000
#: keys of every ROSS element table that only change how ROSS draws it
COSMETIC = frozenset({"tag", "color", "scale_factor"})
#: rad/s -> rpm
RAD_S_TO_RPM = 30.0 / math.pi
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def load_ross_toml(path: Path) -> dict[str, Any]:
    """The parsed TOML of a ROSS rotor file (size and nesting bounded before parsing)."""
    source = str(path)
    text = read_bounded_text(path, MAX_ROSS_BYTES, "ROSS rotor file")
    return load_toml(text, source)  # nesting bounded before parsing


def toml_key(name: str) -> str:
    """A TOML key as written in a dotted path: bare when it can be, else quoted."""
    if _BARE_KEY.fullmatch(name):
        return name
    return '"' + name.replace("\\", "\\\\").replace('"', '\\"') + '"'


class Table:
    """One TOML table of the ROSS file, with typed getters whose errors name ``table.key``."""

    def __init__(self, source: str, path: str, data: dict[str, Any]):
        self.source = source
        self.path = path  # dotted path of the table, e.g. '"ShaftElement_Shaft Element 3".material'
        self.data = data

    def field(self, key: str) -> str:
        return f"{self.path}.{toml_key(key)}"

    def error(self, key: str, message: str) -> InputError:
        return InputError(self.source, self.field(key) if key else self.path, message)

    def has(self, key: str) -> bool:
        return key in self.data

    def _number(self, value: Any, field: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(self.source, field, f"must be a number, not {kind_of(value)}")
        x = float(value)
        if not math.isfinite(x):
            raise InputError(self.source, field, "must be a finite number")
        return x

    def number(self, key: str, default: float | None = None) -> float:
        """A finite number; ``default`` when absent (``None``: required)."""
        if key not in self.data:
            if default is None:
                raise self.error(key, "required field is missing")
            return default
        return self._number(self.data[key], self.field(key))

    def integer(self, key: str) -> int | None:
        """An integer (an integral float is accepted), None when absent."""
        if key not in self.data:
            return None
        value = self.data[key]
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be an integer, not {kind_of(value)}")
        if value < 0:
            raise self.error(key, "must be >= 0 (a ROSS node number)")
        return value

    def flag(self, key: str, default: bool) -> bool:
        if key not in self.data:
            return default
        value = self.data[key]
        if not isinstance(value, bool):
            raise self.error(key, f"must be true or false, not {kind_of(value)}")
        return value

    def text(self, key: str, default: str) -> str:
        if key not in self.data:
            return default
        value = self.data[key]
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, not {kind_of(value)}")
        return value

    def numbers(self, key: str) -> np.ndarray | None:
        """A list of finite numbers (a single number is a list of one), None when absent."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not isinstance(value, list):
            return np.array([self._number(value, self.field(key))])
        if not value:
            raise self.error(key, "must not be empty")
        return np.array([self._number(v, f"{self.field(key)}[{i}]") for i, v in enumerate(value)])

    def table(self, key: str) -> Table:
        if key not in self.data:
            raise self.error(key, "required table is missing")
        value = self.data[key]
        if not isinstance(value, dict):
            raise self.error(key, f"must be a table, not {kind_of(value)}")
        return Table(self.source, self.field(key), value)

    def unknown(self, known: frozenset[str]) -> list[str]:
        return sorted(k for k in self.data if k not in known)


def kind_of(value: Any) -> str:
    """What a TOML value is, for an error message (``"a list"``, ``"the string 'x'"``, ...)."""
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return f"the string {value!r}" if len(value) <= 40 else "a string"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def listing(names: Sequence[str], limit: int = 4) -> str:
    """``a, b and c``; long lists cut after ``limit`` names with the count."""
    items = list(names)
    if len(items) <= limit:
        return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]
    return ", ".join(items[:limit]) + f", ... ({len(items)} in all)"


def slug(text: str, fallback: str) -> str:
    """``text`` as a lower-case name of letters, digits and ``_`` (``fallback`` when nothing is left)."""
    s = re.sub(r"[^0-9a-z]+", "_", text.strip().lower()).strip("_")
    return s or fallback


def unique_name(name: str, taken: set[str]) -> str:
    """``name``, or ``name_2``, ``name_3``, ... if taken; the result is added to ``taken``."""
    out, k = name, 2
    while out in taken:
        out, k = f"{name}_{k}", k + 1
    taken.add(out)
    return out
