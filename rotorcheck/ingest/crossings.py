"""Rising level crossings of a sampled signal (the force's zero crossings, the keyphasor's edges).

A crossing counts only after the signal has been below ``level - hysteresis`` since the previous
one (noise near the level gives no double counts); its time is interpolated linearly between the
two samples around it (s, relative to the first sample).
"""

from __future__ import annotations

import numpy as np

__all__ = ["rising_crossings"]


def rising_crossings(x: np.ndarray, fs_hz: float, level: float, hysteresis: float,
                     armed: bool = True) -> tuple[np.ndarray, bool]:
    """Times (s from ``x[0]``) of the rising crossings of ``level`` and whether the detector is armed
    at the end (the signal went below ``level - hysteresis`` after the last crossing): pass it to
    the next block's call so that blocks chain without losing or doubling a crossing."""
    x = np.asarray(x, dtype=np.float64)
    if x.size < 2:
        return np.empty(0), armed
    above = x >= level
    idx = np.flatnonzero(~above[:-1] & above[1:])  # crossing between idx and idx+1
    low = x < level - hysteresis
    if idx.size:
        # armed before crossing i: some low sample between the previous crossing and this one
        lows = np.flatnonzero(low)
        # last low sample index before each crossing (inclusive of idx)
        pos = np.searchsorted(lows, idx, side="right") - 1
        last_low = np.where(pos >= 0, lows[np.maximum(pos, 0)], -1)
        # armed iff a low sample lies after the previous raw crossing (a rejected crossing had no low
        # sample since the kept one before it, so comparing with the raw previous one is exact)
        prev = np.concatenate([[-1], idx[:-1]])
        keep = last_low > prev
        keep[0] = bool(armed) or bool(last_low[0] >= 0)
        idx = idx[keep]
    last = int(idx[-1]) if idx.size else -1
    if idx.size:
        armed_end = bool(np.any(low[last + 1 :]))
    else:
        armed_end = armed or bool(np.any(low))
    x0, x1 = x[idx], x[idx + 1]
    frac = (level - x0) / (x1 - x0)
    return (idx + frac) / fs_hz, armed_end
