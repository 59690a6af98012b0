"""Wall-clock timing shared by the benches: one warm-up call, then ``repeat`` timed calls."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np


def call_times(fn: Callable[[], Any], repeat: int) -> list[float]:
    """Seconds of each of ``repeat`` calls of ``fn`` after one warm-up call (imports, caches, BLAS threads)."""
    fn()
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def median_time(fn: Callable[[], Any], repeat: int) -> float:
    """Median of :func:`call_times`, s."""
    return float(np.median(call_times(fn, repeat)))
