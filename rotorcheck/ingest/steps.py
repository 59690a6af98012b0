"""Stepped-sine steps: from a step table, or found in the force channel's zero crossings.

Finding steps: the force's rising zero crossings (level = the block median, hysteresis a quarter of
its amplitude) give one period per cycle; consecutive periods within ``rtol`` of the running median
of the current step belong to it, a change starts a new step (the partial cycle at a step boundary
forms a 1-2 cycle fragment, dropped). A step's frequency is the least-squares slope of its crossing
times against the cycle count (Hz), its phase reference the first crossing (s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorcheck.ingest.crossings import rising_crossings
from rotorcheck.ingest.record import TimeRecord

__all__ = ["FoundStep", "find_steps", "force_crossings"]

#: cycles of a fragment that is not a step (the partial cycles at a boundary)
FRAGMENT_CYCLES = 3


@dataclass(frozen=True)
class FoundStep:
    """A step found in the force: frequency (Hz), first and last rising zero crossing (s)."""

    frequency_hz: float
    start_s: float
    end_s: float
    n_cycles: int


def force_crossings(rec: TimeRecord, channel: str, block: int = 1 << 20) -> np.ndarray:
    """Rising zero-crossing times (s, absolute) of a force channel, read block by block (while the
    channel is not driven its noise stays inside the hysteresis: no crossings)."""
    out = []
    armed = True
    for s in range(0, rec.n_samples, block):
        lo = max(0, s - 1)  # one sample overlap: the pair across the block boundary is this block's
        x = rec.read([channel], lo, s + block)[0]
        if x.size < 2:
            break
        sub = x[:: max(1, x.size // 65536)]  # level statistics from <= 64 k samples
        level = float(np.median(sub))
        lo_, hi_ = np.percentile(sub, [1, 99])
        amp = 0.5 * float(hi_ - lo_)
        t, armed = rising_crossings(x, rec.fs_hz, level, 0.25 * amp, armed)
        t = rec.t0_s + lo / rec.fs_hz + t
        out.append(t)
    return np.concatenate(out) if out else np.empty(0)


def find_steps(crossings: np.ndarray, rtol: float = 2e-3) -> list[FoundStep]:
    """Group the crossings into constant-frequency steps (see the module docstring)."""
    c = np.asarray(crossings, dtype=np.float64)
    if c.size < FRAGMENT_CYCLES + 1:
        return []
    d = np.diff(c)
    groups: list[tuple[int, int]] = []  # [first period, last period] inclusive
    start = 0
    ref = d[0]
    for i in range(1, d.size):
        if abs(d[i] - ref) > rtol * ref:
            groups.append((start, i - 1))
            start, ref = i, d[i]
        elif i - start < 16:
            ref = float(np.median(d[start : i + 1]))
    groups.append((start, d.size - 1))
    steps = []
    for a, b in groups:
        n = b - a + 1
        if n < FRAGMENT_CYCLES:
            continue
        tc = c[a : b + 2]
        k = np.arange(tc.size, dtype=np.float64)
        slope = np.polyfit(k, tc, 1)[0]
        steps.append(FoundStep(1.0 / float(slope), float(tc[0]), float(tc[-1]), n))
    return steps
