"""Linear least squares with each unknown in a box, ``min ||A x - b||`` with ``lo <= x <= hi``: two solvers for the
two shapes the pipeline meets, checked against each other (``tests/robust/test_bounded.py``).

- :func:`bounded_lsq`: one tall problem (thousands of whitened residual rows, a few unknowns, bounds possibly
  infinite: the joint test's benign fits and each candidate's loss), by scipy's BVLS on ``A``'s triangular factor.
- :func:`box_lsq`: many tiny problems at once (the pole-shift profile: one per loss of a grid, a few modes and
  unknowns, finite bounds), exact by enumerating the box's faces, batched.
"""

from __future__ import annotations

import numpy as np

from rotorcheck.lazy import lazy_module

optimize = lazy_module("scipy.optimize")  # loaded when a tall bounded problem is solved


def bounded_lsq(A: np.ndarray, b: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> tuple[np.ndarray, float]:
    """``(x, ||A x - b||^2)`` for the ``x`` minimizing ``||A x - b||`` with ``lb <= x <= ub`` (bounds may be
    infinite): scipy's BVLS on the problem reduced to ``A``'s triangular factor (``A = Q R``:
    ``||A x - b||^2 = ||R x - Q^T b||^2 + ||b - Q Q^T b||^2``, the same minimizer for a tall ``A``, thousands of
    rows down to ``p``); the misfit of the returned ``x`` evaluated on the full problem."""
    A, b = np.asarray(A, dtype=float), np.asarray(b, dtype=float)
    Ar, br = A, b
    if A.shape[0] > A.shape[1] > 0:
        Q, Ar = np.linalg.qr(A)
        br = Q.T @ b
    x = np.clip(optimize.lsq_linear(Ar, br, bounds=(lb, ub), method="bvls").x, lb, ub)
    r = A @ x - b
    return x, float(r @ r)


def box_lsq(A: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n, p): for each of n problems the ``x`` minimizing ``||A_i x - b_i||`` with ``lo <= x <= hi``: ``A`` (n, k, p),
    ``b`` (n, k), ``p`` small. Exact by enumeration: the minimum of a convex quadratic over a box is the free
    minimum (least norm) of one face's problem (each parameter free, at its lower or at its upper end) that lies in
    the box; every face is solved for all n at once (3^p batched pseudo-inverses) and the best feasible kept."""
    n, _, p = A.shape
    best = np.full((n, p), np.nan)
    cost = np.full(n, np.inf)
    tol = 1e-12 * np.maximum(1.0, np.abs(hi - lo))
    for face in np.ndindex(*(3,) * p):
        state = np.array(face)  # 0 free, 1 at lo, 2 at hi
        x = np.where(state == 1, lo, hi)[None, :].repeat(n, axis=0)
        free = state == 0
        if np.any(free):
            r = b - np.einsum("nkp,np->nk", A[:, :, ~free], x[:, ~free])
            Af = A[:, :, free]
            x[:, free] = np.einsum("npk,nk->np", np.linalg.pinv(Af), r)
        ok = np.all((x >= lo - tol) & (x <= hi + tol), axis=1)
        res = np.einsum("nkp,np->nk", A, x) - b
        c = np.where(ok, np.sum(res**2, axis=1), np.inf)
        with np.errstate(invalid="ignore"):  # inf - inf where neither is feasible yet
            better = c < cost - 1e-12 * np.where(np.isfinite(cost), np.maximum(cost, 1.0), 0.0)
        best[better], cost[better] = np.clip(x[better], lo, hi), c[better]
    return best
