"""The two bounded least-squares solvers (rotorcheck.robust.bounded) against scipy's BVLS and each other."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

from rotorcheck.robust.bounded import bounded_lsq, box_lsq


def test_box_lsq_matches_scipy_bounded_least_squares() -> None:
    """The face enumeration against scipy.optimize.lsq_linear on 4 x 50 random problems (one direction nearly
    flat, as a bearing at rest): never a larger misfit (relative 1e-9) and inside the box."""
    rng = np.random.default_rng(0)
    for p in (1, 2, 3, 4):
        A = rng.standard_normal((50, 6, p))
        A[:, :, -1] *= 0.01
        b = rng.standard_normal((50, 6))
        lo, hi = -rng.uniform(0.1, 1.0, p), rng.uniform(0.1, 1.0, p)
        X = box_lsq(A, b, lo, hi)
        assert np.all(X >= lo) and np.all(X <= hi)
        for i in range(50):
            ref = optimize.lsq_linear(A[i], b[i], bounds=(lo, hi + 1e-15)).x
            mine, theirs = np.sum((A[i] @ X[i] - b[i]) ** 2), np.sum((A[i] @ ref - b[i]) ** 2)
            assert mine <= theirs * (1 + 1e-9) + 1e-15, (p, i, mine, theirs)
        # the unconstrained solution where it lies inside the box
        wide = box_lsq(A, b, np.full(p, -1e6), np.full(p, 1e6))
        np.testing.assert_allclose(wide[0], np.linalg.lstsq(A[0], b[0], rcond=None)[0], rtol=1e-8, atol=1e-10)


def test_bounded_lsq_on_the_triangular_factor_matches_the_full_problem() -> None:
    """The reduction to A's R factor against scipy's BVLS on the full tall problem and against the face
    enumeration of box_lsq: 4 x 40 random problems (2000 rows, one column nearly flat, one
    problem rank deficient, an infinite upper bound as the crack's): the same minimum misfit (relative 1e-9),
    x inside the bounds, and the misfit returned is the full problem's."""
    rng = np.random.default_rng(7)
    for p in (1, 2, 3, 4):
        for i in range(40):
            A = rng.standard_normal((2000, p))
            A[:, -1] *= 0.01
            if i == 0 and p > 1:
                A[:, 0] = A[:, 1]  # rank deficient
            b = A @ rng.uniform(-2.0, 2.0, p) + rng.standard_normal(2000)
            lo, hi = -rng.uniform(0.1, 1.0, p), rng.uniform(0.1, 1.0, p)
            if i % 2:
                hi[-1] = np.inf
            x, chi2_x = bounded_lsq(A, b, lo, hi)
            assert np.all(x >= lo) and np.all(x <= hi)
            assert chi2_x == pytest.approx(float(np.sum((A @ x - b) ** 2)), rel=1e-12)
            full = optimize.lsq_linear(A, b, bounds=(lo, hi), method="bvls")
            ref = float(full.fun @ full.fun)
            assert chi2_x <= ref * (1 + 1e-9), (p, i, chi2_x, ref)
            if np.all(np.isfinite(hi)):
                enum = box_lsq(A[None], b[None], lo, hi)[0]
                assert chi2_x <= float(np.sum((A @ enum - b) ** 2)) * (1 + 1e-9)
                assert float(np.sum((A @ enum - b) ** 2)) <= chi2_x * (1 + 1e-9)
