"""The last change point of a series over time: where the straight line that describes the series' recent
part begins (a crack's onset, a repair, a change of growth rate).

Method. The null hypothesis is one straight line through the segment's ``m`` points with independent
Gaussian errors of one variance. The alternatives add one regressor to the line:

- a **kink** at a time ``tau`` (a change of slope, the line continuous: a crack's onset), the regressor
  ``max(0, t - tau)``, ``tau`` on a grid of :data:`KINK_GRID` times from each sweep to the next;
- a **step** between two sweeps (a change of level: a repair, a sensor moved), the regressor ``1(t > tau)``.

Each leaves at least :data:`MIN_TAIL` sweeps after it. With ``r`` the line's residuals and ``h`` a regressor
with the line's part removed, the statistic is the largest share of the residual sum of squares one
alternative explains, ``S = max (h.r)^2 / (|h|^2 |r|^2)`` (the sup-F statistic, ``F = (m - 3) S / (1 - S)``).
Under the null hypothesis ``S`` does not depend on the line or on the noise level, only on the sweep times
(it is pivotal): its distribution is simulated for those times (:data:`NULL_DRAWS` Gaussian series, a fixed
seed, cached per design), and the p-value is the share of simulated ``S`` at least as large (Monte Carlo
standard error about 0.0016 at p = 0.01). The maximum over every alternative is simulated as such: no
multiplicity correction is needed. A change is declared when ``p <= alpha`` (:data:`CHANGE_ALPHA`, 1 %: a
straight series gets a false change point 1 % of the time); the scan is then repeated on the sweeps after
it while at least :data:`MIN_RESCAN` are left, until none is found. The last change found is the last change
point, and the line since it is fitted to the sweeps after it (:mod:`rotorcheck.fleet.trend`).

A change known from elsewhere (``known_by``: the fleet's damage verdicts, a joint test per sweep with the
rig's benign ranges allowed, far more sensitive than this series alone, whose scatter is mostly benign
change) is not tested again, only located: the kink (a crack's onset: a change of slope, continuous) that
explains the most, among those before the first damage verdict of the current run (a crack's onset precedes
its detection); it is then the last change point (the damage run is taken as one growth, not scanned again).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

#: false change-point rate of one scan of a straight series
CHANGE_ALPHA = 0.01
#: the fewest sweeps after a change point (a line with a residual to estimate the scatter from)
MIN_TAIL = 3
#: kink times per interval between two sweeps
KINK_GRID = 8
#: the fewest sweeps after a change point for the scan to look for a later one (a shorter tail has too little
#: power for a second change to be worth its false ones: each costs the interval its coverage)
MIN_RESCAN = 8
#: simulated series of the null distribution
NULL_DRAWS = 4000


@dataclass(frozen=True)
class ChangePoint:
    """A change point found: the new segment begins at sweep ``index`` (its position in the series); the
    change happened at ``time`` (days) after sweep ``index - 1``, a ``kind`` of ``kink`` or ``step``."""

    index: int
    time: float  # days (same origin as the series)
    kind: str  # "kink" (change of slope) or "step" (change of level)
    statistic: float  # F of the best alternative, (m - 3) S / (1 - S)
    p_value: float  # of the maximum over every alternative, by simulation
    points: int  # sweeps in the segment scanned
    segment_start: int = 0  # the segment scanned begins at this sweep
    last_first: int | None = None  # the alternatives considered had their first sweep after at most this one


def kink_times(t: Any, start: int = 0, min_tail: int = MIN_TAIL, last_first: int | None = None) -> np.ndarray:
    """The kink times (days) a scan of ``[start, n)`` considers, limited like the change point's
    (``last_first``): the grid the trend's profile runs over."""
    tt = np.asarray(t, dtype=float)
    out = []
    for j in range(start + 1, tt.size - min_tail + 1):
        if last_first is None or j <= last_first:
            out += list(np.linspace(tt[j - 1], tt[j], KINK_GRID + 1)[:-1])
    return np.array(out)


def _alternatives(t: np.ndarray, min_tail: int) -> tuple[np.ndarray, list[tuple[int, float, str]]]:
    """The alternatives' regressors (rows) over ``t`` and, per row, (first sweep after it, tau, kind)."""
    m = t.size
    idx = np.arange(m)
    rows, info = [], []
    for j in range(1, m - min_tail + 1):
        after = idx >= j
        rows.append(after.astype(float))
        info.append((j, 0.5 * (t[j - 1] + t[j]), "step"))
        for tau in np.linspace(t[j - 1], t[j], KINK_GRID + 1)[:-1]:
            rows.append(np.where(after, t - tau, 0.0))
            info.append((j, float(tau), "kink"))
    return np.array(rows).reshape(len(rows), m), info


def _design(t: np.ndarray, min_tail: int) -> tuple[np.ndarray, np.ndarray, list[tuple[int, float, str]]]:
    """``(Q, H, info)``: an orthonormal basis of the line (m x 2) and the alternatives' regressors with the
    line removed and unit norm (rows; degenerate ones dropped); ``tau`` in ``info`` in the units of
    ``(t - mean(t)) / ptp(t)``."""
    return _design_scaled(tuple(np.round((t - t[0]) / np.ptp(t), 12)), min_tail)


@lru_cache(maxsize=64)
def _design_scaled(shape: tuple[float, ...], min_tail: int
                   ) -> tuple[np.ndarray, np.ndarray, list[tuple[int, float, str]]]:
    t = np.array(shape)
    tc = t - t.mean()
    Q, _ = np.linalg.qr(np.column_stack([np.ones(t.size), tc]))
    H, info = _alternatives(tc, min_tail)
    H = H - (H @ Q) @ Q.T
    norms = np.linalg.norm(H, axis=1)
    keep = norms > 1e-9 * max(float(norms.max(initial=0.0)), 1e-300)
    return Q, H[keep] / norms[keep, None], [x for x, k in zip(info, keep) if k]


@lru_cache(maxsize=64)
def _null(shape: tuple[float, ...], min_tail: int) -> np.ndarray:
    """Sorted simulated ``S`` of a straight series with sweeps at ``shape`` (times scaled to 0..1)."""
    Q, H, _ = _design_scaled(shape, min_tail)
    E = np.random.default_rng(20260315).standard_normal((NULL_DRAWS, len(shape)))
    R = E - (E @ Q) @ Q.T
    S = np.max((R @ H.T) ** 2, axis=1) / np.sum(R * R, axis=1)
    return np.sort(S)


def _best(t: np.ndarray, y: np.ndarray, start: int, min_tail: int, last_first: int | None,
          kinds: tuple[str, ...] = ("kink", "step")) -> ChangePoint | None:
    """The alternative of ``[start, n)`` that explains the most of the line's residuals, among those of
    ``kinds`` whose first sweep after is at most ``last_first`` (all when None), with its p-value (module
    docstring)."""
    t, y = t[start:], y[start:]
    m = t.size
    if m < min_tail + 1 or np.ptp(t) <= 0:
        return None
    Q, H, info = _design(t, min_tail)
    allowed = np.array([(last_first is None or start + j <= last_first) and kind in kinds
                        for j, _, kind in info], dtype=bool)
    if not np.any(allowed):
        return None
    r = y - Q @ (Q.T @ y)
    rr = float(r @ r)
    if rr <= 1e-24 * max(float(y @ y), 1e-300):
        return None
    share = np.where(allowed, (H @ r) ** 2 / rr, -1.0)
    best = int(np.argmax(share))
    s = float(min(share[best], 1.0))
    null = _null(tuple(np.round((t - t[0]) / np.ptp(t), 12)), min_tail)
    p = (1 + int(null.size - np.searchsorted(null, s, side="left"))) / (null.size + 1)
    j, tau_scaled, kind = info[best]
    f = (m - 3) * s / (1.0 - s) if s < 1.0 else float("inf")
    return ChangePoint(start + j, float(t.mean() + tau_scaled * np.ptp(t)), kind, f, p, m, start, last_first)


def scan(t: Any, y: Any, start: int = 0, alpha: float = CHANGE_ALPHA, min_tail: int = MIN_TAIL
         ) -> ChangePoint | None:
    """The best alternative of the segment ``[start, n)`` when its p-value is at most ``alpha`` (module
    docstring), else None (also when fewer than ``min_tail + 1`` sweeps or the series is exactly straight)."""
    cp = _best(np.asarray(t, dtype=float), np.asarray(y, dtype=float), start, min_tail, None)
    return cp if cp is not None and cp.p_value <= alpha else None


def last_change_point(t: Any, y: Any, alpha: float = CHANGE_ALPHA, min_tail: int = MIN_TAIL,
                      known_by: int | None = None) -> tuple[int, list[ChangePoint]]:
    """``(start, changes)``: the first sweep of the series' last straight segment (0 when no change was
    found) and every change point found, in time order (module docstring).

    ``known_by``: a change is known (from elsewhere: the detector's damage verdicts) to have begun at or
    before this sweep: the first change is then not tested, only located, as the kink (a crack's onset: a
    change of slope, continuous) that explains the most with its first sweep after at most ``known_by``,
    and it is the last change point (the current damage run is not scanned for another)."""
    tt, yy = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if known_by is not None:  # at 0: the change came before the first sweep, every sweep is after it
        cp = _best(tt, yy, 0, min_tail, known_by, ("kink",)) if known_by >= 1 else None
        return (0, []) if cp is None else (cp.index, [cp])
    changes: list[ChangePoint] = []
    start = 0
    while not changes or tt.size - start >= MIN_RESCAN:
        cp = scan(tt, yy, start, alpha, min_tail)
        if cp is None:
            break
        changes.append(cp)
        start = cp.index
    return start, changes
