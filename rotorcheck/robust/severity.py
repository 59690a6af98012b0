"""A certified interval of one real parameter (a severity) that every frequency point must share.

The per-point certificate of :mod:`rotorcheck.robust.real_box` asks, point by point, whether *some*
parameter values in the box explain the data there, each point free to choose its own. Here the values
are the same at every point (one shaft, one sweep), which is far sharper: per point, a benign parameter
at a range end explains almost any change near a resonance; jointly it must explain all of them.

The severity's range is cut into slices. For each slice, a branch and bound over the other parameters
(benign, real) proves the slice *excluded* when every sub-box is excluded by at least one point (the
small-gain bound of :func:`rotorcheck.robust.box_test.examine_points`, every point against one box),
or finds a *witness* (a parameter value that explains every point, evaluated exactly), or runs out of its
budget ("open": not excluded, kept). Each end of the interval is found from outside in: the outermost slice
not excluded is halved until ``tol`` wide, then searched for a witness. The interval is certified (no
parameter value outside it explains every point); with witnesses at both ends it is also attained
within ``tol``. When every slice is excluded, the hypothesis is excluded and the points that excluded
sub-boxes are named (the test of that: at those points no severity and benign value in the box explain
the data).
"""

from __future__ import annotations

import heapq
import itertools
from collections import Counter
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.affine import AffineModel
from rotorcheck.robust.box_test import BoxFactors, Points, examine_points, halve, point_ratios, ratio_jacobian

#: how the severity interval is made (report.json)
SEVERITY_RULE = ("one severity and one set of benign parameter values (real, in their ranges) and gain for every point "
                 "jointly; a box of them is excluded when at one point of one channel pair |T_new - gain T_h G/G0| "
                 "exceeds z sqrt(var_new + |gain G/G0|^2 var_h) + tolerance + eps |T_h| |gain G/G0 - 1| for all its "
                 "members (small-gain bound; z Sidak over the points used, complex Gaussian noise with the variances "
                 "as known; tolerance and eps the model's error bounds); the certified interval holds every severity "
                 "not excluded (branch and bound per slice, outermost slices halved); a candidate element is "
                 "excluded when every one of its slices is excluded.")


@dataclass(frozen=True)
class SeverityInterval:
    """What :func:`severity_interval` certifies about one hypothesis."""

    status: str  # "excluded" | "consistent"
    lower: float  # certified: no value below explains every point jointly (nan when excluded)
    upper: float
    witness_interval: tuple[float, float]  # values at the ends that do explain every point (nan: none found)
    excluding: tuple[int, ...]  # points that excluded sub-boxes, most often first
    boxes: int  # sub-boxes examined
    witnessed: bool  # both ends hold a witness within tol (else the interval may be wider than the set)
    excluded_slices: tuple[tuple[float, float], ...] = ()  # the slices of the severity proved excluded


def _witness(model: AffineModel, fac: BoxFactors, pts: Points, lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    """Parameter values in ``[lo, hi]`` explaining every point (every ratio <= 1): the box's centre, else a
    bounded least squares of the ratios from it (Jacobian: :func:`ratio_jacobian`), then one that weighs
    the largest ratios; None if none."""
    from scipy.optimize import least_squares  # lazy: scipy.optimize only when a witness is searched

    free = hi > lo
    x0 = 0.5 * (lo + hi)
    if np.all(point_ratios(model, pts, x0) <= 1.0):
        return x0
    if not np.any(free):
        return None

    def full(xf: np.ndarray) -> np.ndarray:
        x = x0.copy()
        x[free] = xf
        return x

    last: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def at(xf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = np.asarray(xf, dtype=float).tobytes()
        if key not in last:
            last.clear()
            r, J = ratio_jacobian(model, fac, pts, full(xf))
            last[key] = (r, J[:, free])
        return last[key]

    for power in (1.0, 4.0):
        def res(xf: np.ndarray, q: float = power) -> np.ndarray:
            r = at(xf)[0]
            return np.where(np.isfinite(r), r, 1e6) ** q

        def jac(xf: np.ndarray, q: float = power) -> np.ndarray:
            r, J = at(xf)
            ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
            return np.where(ok[:, None], q * np.where(ok, r, 1.0)[:, None] ** (q - 1.0) * J, 0.0)
        try:
            sol = least_squares(res, x0[free], jac=jac, bounds=(lo[free], hi[free]), x_scale=hi[free] - lo[free],
                                max_nfev=40)
        except (ValueError, np.linalg.LinAlgError):
            return None
        x0 = full(sol.x)
        if np.all(point_ratios(model, pts, x0) <= 1.0):
            return x0
    return None


def _box(model: AffineModel, fac: BoxFactors, pts: Points, lo: np.ndarray, hi: np.ndarray, max_boxes: int,
         used: Counter[int]) -> tuple[str, np.ndarray | None, int]:
    """Branch and bound over one box, every point jointly: ``("excluded" | "witness" | "open", witness,
    boxes)``. A sub-box is excluded when one point excludes it; its centre is a witness when it explains
    every point; the sub-box closest to exclusion is split first (along the parameter with the largest
    share of that point's bound); "open": the budget ran out first."""

    def examine(c: np.ndarray, h: np.ndarray) -> tuple[float, np.ndarray | None]:
        """The box's largest margin and that point's shares; ``(-inf, None)`` when its centre explains every point."""
        ok, margins, shares, _ = examine_points(model, fac, pts, c, h)
        k = int(np.argmax(margins))
        if margins[k] > 0:
            used[k] += 1
            return float(margins[k]), shares[k]
        if np.all(ok):
            return -np.inf, None
        return float(margins[k]), shares[k]

    c0, h0 = (lo + hi) / 2.0, (hi - lo) / 2.0
    margin, share = examine(c0, h0)
    if margin > 0:
        return "excluded", None, 1
    if share is None:
        return "witness", c0, 1
    heap: list[tuple[float, int, np.ndarray, np.ndarray, np.ndarray]] = [(-margin, 0, c0, h0, share)]
    boxes, tick = 1, 1
    span = np.where(hi > lo, hi - lo, 1.0)
    while heap:
        if boxes >= max_boxes:
            return "open", None, boxes
        _, _, c, h, sh = heapq.heappop(heap)
        i, h1, children = halve(c, h, sh, np.where(hi > lo, h / span, -1.0))
        if h[i] <= 0.0:
            return "open", None, boxes
        for c1 in children:
            margin, share = examine(c1, h1)
            boxes += 1
            if margin > 0:
                continue
            if share is None:
                return "witness", c1, boxes
            heapq.heappush(heap, (-margin, tick, c1, h1, share))
            tick += 1
    return "excluded", None, boxes


def _end(model: AffineModel, fac: BoxFactors, pts: Points, lo: np.ndarray, hi: np.ndarray, index: int,
         upward: bool, tol: float, slices: int, max_boxes: int, used: Counter[int],
         cache: dict[tuple[float, float], str]) -> tuple[float, float, int, bool]:
    """One end of the interval: ``(certified end, witness value (nan: none found), boxes, witnessed)``;
    the end is nan when every slice is excluded. Slices are taken from that end inwards; one not excluded
    is halved until ``tol`` wide, then searched for a witness."""
    edges = np.linspace(lo[index], hi[index], slices + 1)
    stack = [(float(a), float(b)) for a, b in itertools.pairwise(edges)]
    if not upward:
        stack.reverse()  # pop() takes the lowest slice first
    boxes = 0
    while stack:
        a, b = stack.pop()
        l1, h1 = lo.copy(), hi.copy()
        l1[index], h1[index] = a, b
        kind = cache.get((a, b))
        wit = None
        if kind is None:
            kind, wit, n = _box(model, fac, pts, l1, h1, max_boxes, used)
            cache[(a, b)] = kind
            boxes += n
        if kind == "excluded":
            continue
        if b - a > tol:
            mid = 0.5 * (a + b)
            halves = [(a, mid), (mid, b)]
            stack.extend(halves if upward else halves[::-1])
            continue
        if wit is None:
            wit = _witness(model, fac, pts, l1, h1)
        return (b if upward else a), (float(wit[index]) if wit is not None else float("nan")), boxes, wit is not None
    return float("nan"), float("nan"), boxes, True


def severity_interval(model: AffineModel, pts: Points, lo: np.ndarray, hi: np.ndarray, index: int,
                      tol: float = 0.01, slices: int = 16, max_boxes: int = 16, witnessed_at_lo: bool = False,
                      earlier: SeverityInterval | None = None) -> SeverityInterval:
    """Certify the interval of parameter ``index`` over which the box ``[lo, hi]`` (p,) explains every
    point jointly (module docstring; each point's ``b``, ``c`` in ``pts``); ``tol`` the width to which
    the end slices are halved; ``slices`` the first division of the range; ``max_boxes`` the budget of
    sub-boxes per slice. ``witnessed_at_lo``: the caller holds a witness with the parameter at ``lo[index]``
    (e.g. the healthy hypothesis's): the lower end is ``lo[index]``, attained, without a search.
    ``earlier``: this hypothesis's result with a smaller budget on the same box, points and slices (its
    excluded slices stay excluded: they are not examined again; its excluding points stay named)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    used: Counter[int] = Counter()
    cache: dict[tuple[float, float], str] = {}
    if earlier is not None:
        cache.update(dict.fromkeys(earlier.excluded_slices, "excluded"))
        used.update({k: len(earlier.excluding) - i for i, k in enumerate(earlier.excluding)})
    fac = BoxFactors.of(model)
    n_sl = slices if hi[index] > lo[index] else 1
    if witnessed_at_lo:
        lower, w_lo, n1, done1 = float(lo[index]), float(lo[index]), 0, True
    else:
        lower, w_lo, n1, done1 = _end(model, fac, pts, lo, hi, index, False, tol, n_sl, max_boxes, used, cache)
    excluded = tuple(sorted(k for k, v in cache.items() if v == "excluded"))
    if not np.isfinite(lower):
        return SeverityInterval("excluded", float("nan"), float("nan"), (float("nan"), float("nan")),
                                tuple(k for k, _ in used.most_common()), n1, False, excluded)
    upper, w_hi, n2, done2 = _end(model, fac, pts, lo, hi, index, True, tol, n_sl, max_boxes, used, cache)
    excluded = tuple(sorted(k for k, v in cache.items() if v == "excluded"))
    return SeverityInterval("consistent", float(lower), float(upper), (w_lo, w_hi),
                            tuple(k for k, _ in used.most_common()), n1 + n2, done1 and done2, excluded)
