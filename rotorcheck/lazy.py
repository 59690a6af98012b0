"""Package exports and modules loaded on first use (PEP 562, :class:`importlib.util.LazyLoader`), so
that importing one submodule does not load the others (the LMI solvers, scipy.optimize and cvxpy
stay unloaded on the measured-detection path; scipy.sparse and scipy.linalg stay unloaded unless a
large mesh needs them)."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any


def lazy_exports(package: str, home: Mapping[str, str]
                 ) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """``(__all__, __getattr__, __dir__)`` for ``package`` whose public name ``n`` lives in the
    submodule ``home[n]``."""
    def getattr_(name: str) -> Any:
        if name in home:
            return getattr(importlib.import_module(f"{package}.{home[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def dir_() -> list[str]:
        return sorted({*vars(importlib.import_module(package)), *home})

    return sorted(home), getattr_, dir_


class _Deferred(ModuleType):
    """Stands for the module of its name until the first attribute access imports it."""

    def __getattr__(self, attr: str) -> Any:
        module = importlib.import_module(self.__name__)
        self.__dict__.update(vars(module))  # later accesses are plain lookups
        return getattr(module, attr)


def lazy_module(name: str) -> ModuleType:
    """The module ``name``, imported at the first attribute access rather than now.

    ``sp = lazy_module("scipy.sparse")`` at module level in place of ``import scipy.sparse as sp``
    (with the real import under ``typing.TYPE_CHECKING`` for the type checkers). Nothing is
    imported or registered until then (not even the parent packages); an already imported module
    is returned as it is.
    """
    return sys.modules.get(name) or _Deferred(name)
