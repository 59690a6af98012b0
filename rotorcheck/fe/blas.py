"""Scoped BLAS thread limits for loops of many small dense operations (threadpoolctl).

The harmonic balance, the time integrator and the Ritz eigensolutions do thousands of 40-300 sized
matrix operations; a multithreaded BLAS spends more time synchronising its threads than computing
on them, and far more on a loaded machine (measured in bench/bench_engine.py). :func:`one_blas_thread`
limits every loaded BLAS to one thread for the body of a ``with`` block and restores the previous
counts on exit: nothing outside the block changes (no environment variables, no global setting).
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import Any

from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread"]

_controller: list[ThreadpoolController] = []  # created on first use (inspecting the loaded libraries)


def one_blas_thread() -> AbstractContextManager[Any]:
    """``with one_blas_thread(): ...`` runs the body with one BLAS thread (scoped, restored on exit)."""
    if not _controller:
        _controller.append(ThreadpoolController())
    return _controller[0].limit(limits=1, user_api="blas")
