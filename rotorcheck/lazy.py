"""Package exports loaded on first use (PEP 562), so that importing one submodule does not load the
others (the LMI solvers, scipy.optimize and cvxpy stay unloaded on the measured-detection path)."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
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
