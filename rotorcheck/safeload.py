"""Bounded parsing of YAML and TOML text (issue 32): an input file cannot make a parser run for minutes or
recurse past the stack.

YAML aliases let a few hundred bytes describe billions of nodes ("billion laughs"): PyYAML builds them as
shared objects, and the first walk over the result (a check for non-finite numbers, a schema validation, a
copy) expands them. :func:`load_yaml` composes the document with a loader that counts aliases and nesting
while composing, then counts the document's nodes *as expanded* (each node once, memoised) before any
object is constructed; over a bound it raises :class:`YamlBoundError`, a ``yaml.YAMLError`` (so code that
handles malformed YAML handles it too) with the line of the offending node.

TOML has no aliases; ``tomllib`` parses nested arrays recursively, so a deeply nested array ends in
``RecursionError``: :func:`load_toml` refuses nesting deeper than :data:`MAX_DEPTH` before parsing.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

from rotorcheck.errors import InputError
from rotorcheck.fileio import read_bounded_text

__all__ = ["MAX_ALIASES", "MAX_DEPTH", "MAX_NODES", "YamlBoundError", "load_toml", "load_yaml", "load_yaml_file",
           "toml_depth"]

#: nesting depth of mappings/sequences (YAML) or arrays/inline tables (TOML) refused beyond
MAX_DEPTH = 64
#: alias uses refused beyond (a hand-written rig file uses a handful)
MAX_ALIASES = 1000
#: nodes of a YAML document counted with every alias expanded, refused beyond
MAX_NODES = 1_000_000

ErrorFactory = Callable[[str | Path, str, str], Exception]


class YamlBoundError(yaml.YAMLError):
    """A YAML document over a bound (aliases, nesting, expanded nodes); ``problem``/``problem_mark`` as a
    ``yaml.MarkedYAMLError`` has them."""

    def __init__(self, problem: str, mark: Any = None):
        super().__init__(problem)
        self.problem = problem
        self.problem_mark = mark

    def __str__(self) -> str:
        where = f"line {self.problem_mark.line + 1}, column {self.problem_mark.column + 1}: " \
            if self.problem_mark is not None else ""
        return where + self.problem


class _Bounds:
    """Mixed into a SafeLoader subclass: counts aliases and nesting while composing."""

    _aliases = 0
    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        loader: Any = self
        if loader.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise YamlBoundError(f"more than {MAX_ALIASES} aliases (*name): refused (an alias bomb?)",
                                     loader.peek_event().start_mark)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise YamlBoundError(f"nested deeper than {MAX_DEPTH} levels: refused",
                                     loader.peek_event().start_mark)
            return super().compose_node(parent, index)  # type: ignore[misc]
        finally:
            self._depth -= 1


_BOUNDED: dict[type, type] = {}


def _bounded(loader: type) -> type:
    if loader not in _BOUNDED:
        _BOUNDED[loader] = type(f"Bounded{loader.__name__}", (_Bounds, loader), {})
    return _BOUNDED[loader]


def _expanded_nodes(root: yaml.Node) -> int:
    """Nodes of the document with every alias expanded, without expanding (memoised per node; iterative)."""
    size: dict[int, int] = {}
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        if id(node) in size:
            continue
        kids: list[yaml.Node] = []
        if isinstance(node, yaml.SequenceNode):
            kids = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            kids = [n for pair in node.value for n in pair]
        if done or not kids:
            size[id(node)] = 1 + sum(size[id(k)] for k in kids)
            if size[id(node)] > MAX_NODES:
                raise YamlBoundError(f"more than {MAX_NODES} nodes with its aliases expanded: refused (an alias "
                                     "bomb?)", node.start_mark)
            continue
        stack.append((node, True))
        stack.extend((k, False) for k in kids if id(k) not in size)
    return size[id(root)]


def load_yaml(text: str, loader: type = yaml.SafeLoader) -> Any:
    """``yaml.load(text, Loader=loader)`` (a SafeLoader subclass) within :data:`MAX_DEPTH`,
    :data:`MAX_ALIASES` and :data:`MAX_NODES`; over a bound :class:`YamlBoundError` (a ``yaml.YAMLError``)."""
    if not (isinstance(loader, type) and issubclass(loader, yaml.SafeLoader)):
        raise TypeError("load_yaml needs a yaml.SafeLoader subclass")
    ld = _bounded(loader)(text)
    try:
        node = ld.get_single_node()
        if node is None:
            return None
        _expanded_nodes(node)
        return ld.construct_document(node)
    except RecursionError:  # pragma: no cover - MAX_DEPTH stops nesting long before
        raise YamlBoundError("nested too deeply to parse") from None
    finally:
        ld.dispose()


def yaml_error_message(exc: yaml.YAMLError) -> tuple[str, str]:
    """``(where, problem)`` of a YAML error: ``"line L, column C"`` (or "") and the problem."""
    mark = getattr(exc, "problem_mark", None)
    where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    return where, str(getattr(exc, "problem", None) or exc)


def load_yaml_file(path: str | Path, max_bytes: int, what: str, error: ErrorFactory = InputError,
                   loader: type = yaml.SafeLoader) -> Any:
    """The parsed YAML of the file ``path`` (a ``what``), bounded in size (:func:`read_bounded_text`, a
    UTF-8 byte-order mark dropped) and in structure (:func:`load_yaml`); any failure is ``error(file,
    "line L, column C", message)``."""
    text = read_bounded_text(path, max_bytes, what, error).removeprefix("\ufeff")
    try:
        return load_yaml(text, loader)
    except yaml.YAMLError as exc:
        where, problem = yaml_error_message(exc)
        raise error(path, where, f"malformed YAML: {problem}") from None


def toml_depth(text: str) -> int:
    """The deepest nesting of arrays and inline tables in TOML ``text`` (brackets in strings and comments not
    counted; ``[table]`` headers are depth 1)."""
    depth = best = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if c in "\"'":
            triple = text.startswith(c * 3, i)
            close = c * 3 if triple else c
            j = i + len(close)
            while j < n:
                if c == '"' and text[j] == "\\":
                    j += 2
                    continue
                if text.startswith(close, j) or (not triple and text[j] == "\n"):
                    break
                j += 1
            i = j + len(close)
            continue
        if c in "[{":
            depth += 1
            best = max(best, depth)
        elif c in "]}":
            depth = max(0, depth - 1)
        i += 1
    return best


def load_toml(text: str, file: str | Path, error: ErrorFactory = InputError) -> dict[str, Any]:
    """The TOML document ``text`` of ``file``; nesting deeper than :data:`MAX_DEPTH` refused before parsing,
    malformed TOML refused; both as ``error(file, "", message)``."""
    depth = toml_depth(text)
    if depth > MAX_DEPTH:
        raise error(file, "", f"arrays or tables nested {depth} deep: refused (at most {MAX_DEPTH})")
    toml = importlib.import_module("tomllib" if sys.version_info >= (3, 11) else "tomli")
    try:
        data = toml.loads(text)
    except toml.TOMLDecodeError as exc:
        raise error(file, "", f"not TOML: {exc}") from None
    except RecursionError:  # pragma: no cover - the depth check comes first
        raise error(file, "", "nested too deeply to parse") from None
    if not isinstance(data, dict):  # pragma: no cover - a TOML document is a table
        raise error(file, "", "not TOML")
    return data
