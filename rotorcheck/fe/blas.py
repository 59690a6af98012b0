"""Scoped BLAS thread limits for loops of many small dense operations (threadpoolctl).

The harmonic balance, the time integrator and the Ritz eigensolutions do thousands of 40-300 sized
matrix operations; a multithreaded BLAS spends more time synchronising its threads than computing
on them, and far more on a loaded machine (measured in bench/bench_engine.py). :func:`one_blas_thread`
limits every loaded BLAS to one thread for the body of a ``with`` block and restores the previous
counts on exit: nothing outside the block changes (no environment variables, no global setting).
"""

from __future__ import annotations

import sys
from contextlib import AbstractContextManager
from typing import Any

from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread"]

#: (number of imported modules when created, controller): created on first use by inspecting the
#: loaded libraries, again when modules were imported since (scipy.linalg, loaded lazily, brings
#: its own OpenBLAS next to numpy's; a controller made before would not limit it)
_controller: list[tuple[int, ThreadpoolController]] = []


def one_blas_thread() -> AbstractContextManager[Any]:
    """``with one_blas_thread(): ...`` runs the body with one BLAS thread (scoped, restored on exit)."""
    loaded = len(sys.modules)
    if not _controller or _controller[0][0] != loaded:
        _controller[:] = [(loaded, ThreadpoolController())]
    return _controller[0][1].limit(limits=1, user_api="blas")
