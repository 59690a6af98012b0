"""No ``typing.Any`` in the public signatures of the pipeline objects (issue 28).

The pipeline objects: the rig (:class:`rotorcheck.rig.Rig`), the measured FRF, the baseline and its parts, a
detector's settings, answer and protocol, the diagnosis and the outcome of a detection, and the public
functions of :mod:`rotorcheck.workflow.checking`. Every public field, every public method's parameters and
return (properties too) is resolved with :func:`typing.get_type_hints` and walked through
:func:`typing.get_args`: ``Any`` anywhere in a hint fails, naming the object and the name.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import sys
import types
import typing
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import pytest

#: module -> its pipeline classes
PIPELINE_CLASSES: dict[str, tuple[str, ...]] = {
    "rotorcheck.rig": ("Rig",),
    "rotorcheck.workflow.frf": ("MeasuredFRF",),
    "rotorcheck.baseline": ("Baseline", "Provenance", "NoiseFit", "ModelBound", "HealthyData", "DriftModel"),
    "rotorcheck.workflow.detectors.base": ("Detection", "DetectorSettings", "Detector"),
    "rotorcheck.workflow.detection": ("Diagnosis", "DetectionOutcome"),
}
#: modules whose public functions are pipeline steps
PIPELINE_FUNCTION_MODULES = ("rotorcheck.workflow.checking",)


class _Missing:
    """Stands for a module an annotation names under ``TYPE_CHECKING`` that is not installed (an optional
    dependency): its attributes are fresh classes, never ``Any``."""

    def __getattr__(self, name: str) -> type:
        return type(name, (), {})


def _type_checking_names(module: types.ModuleType) -> dict[str, object]:
    """The names a module imports under ``if TYPE_CHECKING:`` (for annotations only), imported here."""
    names: dict[str, object] = {}
    try:
        tree = ast.parse(inspect.getsource(module))
    except (OSError, TypeError):
        return names
    for node in tree.body:
        if not isinstance(node, ast.If):
            continue
        if (getattr(node.test, "id", None) or getattr(node.test, "attr", None)) != "TYPE_CHECKING":
            continue
        for stmt in node.body:
            code = compile(ast.Module(body=[stmt], type_ignores=[]), module.__name__, "exec")
            try:
                exec(code, {"__name__": module.__name__, "__package__": module.__package__}, names)
            except ImportError:  # an optional dependency that is not installed
                if isinstance(stmt, (ast.Import, ast.ImportFrom)):
                    names.update({(a.asname or a.name).split(".")[0]: _Missing() for a in stmt.names})
    return names


def _namespace(module_name: str) -> dict[str, object]:
    module = sys.modules[module_name]
    return {**vars(module), **_type_checking_names(module)}


def hints(obj: object, module_name: str) -> dict[str, object]:
    """:func:`typing.get_type_hints` of ``obj`` with its module's names, the ``TYPE_CHECKING`` ones too."""
    return typing.get_type_hints(obj, globalns=_namespace(module_name))


def has_any(hint: object, seen: frozenset[int] = frozenset()) -> bool:
    """``typing.Any`` anywhere in ``hint`` (its arguments walked recursively)."""
    if hint is Any:
        return True
    if id(hint) in seen:
        return False
    return any(has_any(a, seen | {id(hint)}) for a in typing.get_args(hint))


def _function_of(member: object) -> Callable[..., object] | None:
    if isinstance(member, property):
        return member.fget
    if isinstance(member, cached_property):
        return member.func
    if isinstance(member, (staticmethod, classmethod)):
        return member.__func__
    return member if inspect.isfunction(member) else None


def public_hints(cls: type) -> Iterator[tuple[str, object]]:
    """``(name, hint)`` of every public field and of every public method's parameters and return (``__init__``
    where it is written by hand; a dataclass's is its fields)."""
    for name, hint in hints(cls, cls.__module__).items():
        if not name.startswith("_"):
            yield name, hint
    done: set[str] = set()
    for klass in cls.__mro__:
        if klass is object or klass.__module__ in ("typing", "builtins", "abc"):
            continue
        for name, member in vars(klass).items():
            if name in done or (name.startswith("_") and name != "__init__"):
                continue
            done.add(name)
            fn = _function_of(member)
            if fn is None or (name == "__init__" and dataclasses.is_dataclass(cls)):
                continue
            for arg, hint in hints(fn, fn.__module__).items():
                if not arg.startswith("_"):
                    yield f"{name}({arg})" if arg != "return" else f"{name} -> return", hint


def any_in_class(cls: type) -> list[str]:
    return [f"{cls.__module__}.{cls.__qualname__}.{name}: {hint}" for name, hint in public_hints(cls)
            if has_any(hint)]


def public_functions(module_name: str) -> list[Callable[..., object]]:
    module = importlib.import_module(module_name)
    return [fn for name, fn in vars(module).items()
            if not name.startswith("_") and inspect.isfunction(fn) and fn.__module__ == module_name]


def any_in_function(fn: Callable[..., object]) -> list[str]:
    return [f"{fn.__module__}.{fn.__qualname__}({arg}): {hint}"
            for arg, hint in hints(fn, fn.__module__).items() if has_any(hint)]


@pytest.mark.parametrize("module_name", sorted(PIPELINE_CLASSES))
def test_no_any_in_the_pipeline_classes(module_name: str) -> None:
    module = importlib.import_module(module_name)
    bad = []
    for name in PIPELINE_CLASSES[module_name]:
        cls = getattr(module, name)
        assert list(public_hints(cls)), f"{module_name}.{name}: no public hints found"
        bad += any_in_class(cls)
    assert not bad, "typing.Any in a public signature:\n" + "\n".join(bad)


@pytest.mark.parametrize("module_name", PIPELINE_FUNCTION_MODULES)
def test_no_any_in_the_pipeline_functions(module_name: str) -> None:
    functions = public_functions(module_name)
    assert functions, f"{module_name}: no public functions found"
    bad = [b for fn in functions for b in any_in_function(fn)]
    assert not bad, "typing.Any in a public signature:\n" + "\n".join(bad)


# --------------------------------------------------------------------------------------------
# the check itself


@dataclass
class _Loose:
    name: str
    extra: dict[str, list[Any]]  # Any two levels down
    _private: Any = None  # not public: not checked

    @property
    def size(self) -> int:
        return 0

    def merge(self, other: Any, *, strict: bool = False) -> _Loose:
        return self

    def _helper(self, x: Any) -> Any:
        return x


@dataclass
class _Tight:
    name: str
    values: dict[str, list[float | None]]

    def merge(self, other: _Tight) -> _Tight:
        return self


def _loose_function(x: int, rest: tuple[Any, ...]) -> int:
    return x


def test_the_check_reports_any_in_a_public_signature() -> None:
    assert any_in_class(_Loose) == [
        f"{__name__}._Loose.extra: dict[str, list[typing.Any]]",
        f"{__name__}._Loose.merge(other): typing.Any",
    ]
    assert any_in_class(_Tight) == []
    assert any_in_function(_loose_function) == [f"{__name__}._loose_function(rest): tuple[typing.Any, ...]"]
    assert not has_any(int | None) and has_any(int | Any) and has_any(Callable[[int], Any])
