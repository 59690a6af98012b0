"""Limit OpenBLAS threads around loops of small dense operations.

The time integrator and the harmonic balance do many 40-170 sized matrix operations; multithreaded
OpenBLAS on a loaded machine spends far more time synchronising threads than computing (measured:
scipy ``expm`` of an 82x82 matrix 0.6 ms single-threaded vs 20-300 ms with 2 threads under load).
:func:`single_thread_blas` sets every loaded OpenBLAS to one thread and restores the old counts.
Best effort: does nothing when no OpenBLAS (or no setter) is found.
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterator
from contextlib import contextmanager

_SETTERS = (
    "scipy_openblas_set_num_threads64_",
    "scipy_openblas_set_num_threads",
    "openblas_set_num_threads64_",
    "openblas_set_num_threads",
)
_GETTERS = (
    "scipy_openblas_get_num_threads64_",
    "scipy_openblas_get_num_threads",
    "openblas_get_num_threads64_",
    "openblas_get_num_threads",
)

_cache: list[tuple[object, object]] | None = None


def _libs() -> list[tuple[object, object]]:
    global _cache
    if _cache is not None:
        return _cache
    found: list[tuple[object, object]] = []
    paths: set[str] = set()
    try:
        with open("/proc/self/maps", encoding="utf-8") as fh:
            for line in fh:
                part = line.split()
                if part and "openblas" in part[-1].lower() and part[-1].endswith(".so"):
                    paths.add(part[-1])
    except OSError:
        paths = set()
    for p in sorted(paths):
        try:
            lib = ctypes.CDLL(p)
        except OSError:
            continue
        setter = next((getattr(lib, s) for s in _SETTERS if hasattr(lib, s)), None)
        getter = next((getattr(lib, g) for g in _GETTERS if hasattr(lib, g)), None)
        if setter is not None and getter is not None:
            found.append((setter, getter))
    _cache = found
    return found


@contextmanager
def single_thread_blas() -> Iterator[None]:
    """Run the body with all loaded OpenBLAS libraries set to one thread."""
    import numpy  # noqa: F401  (make sure numpy's BLAS is loaded)
    import scipy.linalg  # noqa: F401

    libs = _libs()
    old = []
    for setter, getter in libs:
        try:
            old.append(int(getter()))  # type: ignore[operator]
            setter(1)  # type: ignore[operator]
        except Exception:  # pragma: no cover - foreign ABI
            old.append(None)
    try:
        yield
    finally:
        for (setter, _), n in zip(libs, old):
            if n is not None:
                setter(n)  # type: ignore[operator]
