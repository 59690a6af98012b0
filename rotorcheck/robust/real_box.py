"""Per-point certificate over a box of real parameters: can the data at one frequency be explained by
some parameter values inside their ranges, each point free to choose its own? (The real-mu branch and bound.)

The model (:class:`rotorcheck.robust.affine.AffineModel`) and the small-gain test of a sub-box at a point
(:func:`rotorcheck.robust.box_test.examine_points`) are shared with the joint severity interval. A point is
*unexplained* (certified) when every sub-box of the box is excluded there, *explained* when a sub-box centre
is a witness (evaluated exactly), and *undecided* when its box budget runs out first. Boxes are split along the
parameter with the largest share of the bound, the one furthest from exclusion first (best-first on the
margin: a witness is looked for where the data are nearest to being explained). Every point runs its own
branch and bound; the points still open are examined together, one batched test per round. At the root box
(no split) the bound treats the parameters as one complex disc each: :attr:`BoxCertificate.complex_unexplained`
is what that relaxation certifies, for comparison.
"""

from __future__ import annotations

import dataclasses
import heapq
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.affine import AffineModel
from rotorcheck.robust.box_test import BoxFactors, Points, examine_points, halve, point_receptances

#: how the certified per-point verdict is made (report.json)
BOX_RULE = ("per point: unexplained iff for every benign parameter value in its range (real, branch and bound "
            "with small-gain bounds on each sub-box) and every gain in its range, |T_new - gain T_h G(theta)/G(0)| "
            "exceeds z sqrt(var_new + |gain G(theta)/G(0)|^2 var_h + a^2), a the model-error allowance; z: Sidak "
            "over the points at the stated rate, complex Gaussian noise with the variances treated as known")


@dataclass
class BoxCertificate:
    """Per-point result of :func:`certify_points` (n points)."""

    status: np.ndarray  # (n,) str: "explained" | "unexplained" | "undecided"
    witness: np.ndarray  # (n, p) parameter values explaining the point (NaN where none found)
    witness_gain: np.ndarray  # (n,) gain factor of the witness (NaN where none)
    boxes: np.ndarray  # (n,) sub-boxes examined per point
    complex_unexplained: np.ndarray  # (n,) bool: certified at the root box alone (complex-disc relaxation)
    rule: str = BOX_RULE

    @property
    def unexplained(self) -> np.ndarray:
        return self.status == "unexplained"

    @property
    def undecided(self) -> np.ndarray:
        return self.status == "undecided"


def certify_points(model: AffineModel, omega: np.ndarray, t_new: np.ndarray, t_healthy: np.ndarray,
                   var_new: np.ndarray, var_healthy: np.ndarray, z: float, allowance: np.ndarray,
                   gain: tuple[float, float] = (1.0, 1.0), max_boxes: int = 200) -> BoxCertificate:
    """Certify each point (``omega`` rad/s, (n,)) as explained / unexplained / undecided by benign
    parameters in ``model``'s box and a gain factor in ``gain`` (see the module docstring); the
    allowance ``a`` (n,) m/N is the model's own error; ``max_boxes`` the sub-box budget per point."""
    p = len(model.parameters)
    lo = np.array([q.lo for q in model.parameters], dtype=float)
    hi = np.array([q.hi for q in model.parameters], dtype=float)
    w = np.asarray(omega, dtype=float).reshape(-1)
    n = w.size
    status = np.full(n, "undecided", dtype="<U11")
    witness = np.full((n, p), np.nan)
    wgain = np.full(n, np.nan)
    boxes = np.zeros(n, dtype=int)
    root = np.zeros(n, dtype=bool)
    if n == 0:
        return BoxCertificate(status, witness, wgain, boxes, root)
    b, c = np.broadcast_to(model.b, (n, model.b.size)), np.broadcast_to(model.c, (n, model.c.size))
    zeros = np.zeros(n)
    pts = Points(w, zeros.astype(complex), np.asarray(t_new, dtype=complex), np.asarray(t_healthy, dtype=complex),
                 np.asarray(var_new, dtype=float), np.asarray(var_healthy, dtype=float), float(z),
                 np.asarray(allowance, dtype=float) ** 2, float(gain[0]), float(gain[1]), zeros, zeros, b, c)
    pts = dataclasses.replace(pts, g0=point_receptances(model, pts, np.zeros(p)))
    fac = BoxFactors.of(model)
    centre, half = (lo + hi) / 2.0, (hi - lo) / 2.0
    ok, margin, share, gm = examine_points(model, fac, pts, centre, half, each=True)
    boxes[:] = 1
    status[ok] = "explained"
    witness[ok] = centre
    wgain[ok] = gm[ok]
    root[:] = ~ok & (margin > 0)
    status[root] = "unexplained"
    # per open point a heap of its sub-boxes, the one furthest from exclusion first (a NaN margin: not excluded)
    heaps: dict[int, list[tuple[float, int, np.ndarray, np.ndarray, np.ndarray]]] = {
        k: [(float(np.nan_to_num(margin[k], nan=-np.inf)), 0, centre, half, share[k])]
        for k in map(int, np.flatnonzero(~ok & ~root))}
    tick = 1
    while heaps:
        kids: list[tuple[int, np.ndarray, np.ndarray]] = []
        for k in list(heaps):
            heap = heaps[k]
            if not heap:
                status[k] = "unexplained"  # every sub-box excluded
                del heaps[k]
                continue
            if boxes[k] >= max_boxes:
                del heaps[k]  # undecided
                continue
            _, _, c0, h0, sh = heapq.heappop(heap)
            _, h1, children = halve(c0, h0, sh, h0)
            kids.extend((k, c1, h1) for c1 in children)
        if not kids:
            break
        at = np.array([k for k, _, _ in kids])
        ok, margin, share, gm = examine_points(model, fac, pts.take(at), np.array([x for _, x, _ in kids]),
                                               np.array([x for _, _, x in kids]), each=True)
        for j, (k, c1, h1) in enumerate(kids):
            if k not in heaps:
                continue  # explained by its first child this round
            boxes[k] += 1
            if ok[j]:
                status[k], witness[k], wgain[k] = "explained", c1, gm[j]
                del heaps[k]
            elif not margin[j] > 0:
                heapq.heappush(heaps[k], (float(np.nan_to_num(margin[j], nan=-np.inf)), tick, c1, h1, share[j]))
                tick += 1
    return BoxCertificate(status, witness, wgain, boxes, root)


def merge_certificates(certs: list[BoxCertificate]) -> BoxCertificate:
    """One per-point certificate from several channels' on the same points: a point is unexplained when
    any channel's is, else undecided when any is, else explained (the first channel's witness)."""
    if len(certs) == 1:
        return certs[0]
    st = np.array([c.status for c in certs])
    status = np.where(np.any(st == "unexplained", axis=0), "unexplained",
                      np.where(np.any(st == "undecided", axis=0), "undecided", "explained")).astype("<U11")
    return BoxCertificate(status, certs[0].witness, certs[0].witness_gain, np.sum([c.boxes for c in certs], axis=0),
                          np.any([c.complex_unexplained for c in certs], axis=0))
