"""Block-diagonal dynamic stiffness (robust.affine.StiffnessStack): a rotor that does not spin has two
uncoupled bending planes, and the certificates solve them block by block.

References: the full matrix (the same model glued by one negligible coupling entry, 1e-200 of the largest
stiffness: one block, the full LU) for the solves and receptances; the model cut to one plane for each
point's box margin (a point's input-output map never sees the other plane, so neither does its bound); brute
force over a dense parameter grid for the soundness of the certified interval. The blocks themselves are
checked against the interleaved layout they were built from, and the block-wise factors against ``A``.
"""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.robust.affine import AffineModel, AffineParameter, StiffnessStack, _factor, coupled_blocks
from rotorcheck.robust.box_test import BoxFactors, Points, examine_points, point_ratios
from rotorcheck.robust.severity import severity_interval
from tests.robust.robust_helpers import CHAIN_K, CHAIN_MASS, chain_spring

K, MASS, _spring = CHAIN_K, CHAIN_MASS, chain_spring


def _planes(A: np.ndarray, Ay: np.ndarray | None = None) -> np.ndarray:
    """The 4 x 4 matrix ``A`` on the x plane (DOFs 0, 2, 4, 6) and ``Ay`` (default ``A``) on y (1, 3, 5, 7)."""
    out = np.zeros((8, 8))
    out[0::2, 0::2] = A
    out[1::2, 1::2] = A if Ay is None else Ay
    return out


def _model(glue: float = 0.0, aniso: float = 1.0) -> AffineModel:
    """Two chains, one per plane (y ``aniso`` times stiffer); a benign factor on every spring, a bearing-like
    spring at mass 1 in both planes and a loss of spring 3 in both planes; ``glue`` couples x0 and y3."""
    Kx = sum(K[i] * _spring(i) for i in range(4))
    K0 = _planes(Kx, aniso * Kx)
    K0[0, 7] = K0[7, 0] = glue * K0.max()
    M = _planes(np.diag(MASS))
    D = 2e-4 * K0
    bearing = _planes(np.diag([1.0, 0.0, 0.0, 0.0])) * 1e5
    loss = -_planes(K[2] * _spring(2), aniso * K[2] * _spring(2))
    return AffineModel(M, D, K0, np.eye(8)[6], np.eye(8)[2], (
        AffineParameter("E", (("K", _planes(Kx, aniso * Kx)),), -0.02, 0.02),
        AffineParameter("bearing", (("K", bearing),), -0.3, 0.3),
        AffineParameter("loss", (("K", loss),), 0.0, 0.8)))


def _points(model: AffineModel, planes: str, seed: int = 0) -> Points:
    """Noisy data of the model with spring 3 30 % weaker and E + 1 %, at 30 frequencies, x (and y) plane pairs."""
    w = 2 * np.pi * np.linspace(20.0, 180.0, 30)
    ins = [np.eye(8)[6]] + ([np.eye(8)[7]] if planes == "xy" else [])
    outs = [np.eye(8)[2]] + ([np.eye(8)[3]] if planes == "xy" else [])
    b = np.array([ins[k % len(ins)] for k in range(w.size)])
    c = np.array([outs[k % len(outs)] for k in range(w.size)])
    Z0 = model.stiffness_stack(w, np.zeros(3)).full()
    Z1 = model.stiffness_stack(w, np.array([0.01, 0.0, 0.3])).full()
    g0 = np.einsum("kn,kn->k", c, np.linalg.solve(Z0, b[:, :, None])[:, :, 0])
    g1 = np.einsum("kn,kn->k", c, np.linalg.solve(Z1, b[:, :, None])[:, :, 0])
    rng = np.random.default_rng(seed)
    var_n, var_h = (0.01 * np.abs(g1)) ** 2, (0.01 * np.abs(g0)) ** 2
    tn = g1 + np.sqrt(var_n / 2) * (rng.standard_normal(w.size) + 1j * rng.standard_normal(w.size))
    th = g0 + np.sqrt(var_h / 2) * (rng.standard_normal(w.size) + 1j * rng.standard_normal(w.size))
    z = float(np.sqrt(-np.log1p(-(0.99) ** (1 / w.size))))
    return Points(w, g0, tn, th, var_n, var_h, z, np.zeros(w.size), 0.98, 1.02, np.zeros(w.size),
                  np.full(w.size, 0.05), b, c)


def test_blocks_are_the_two_interleaved_planes_and_glue_joins_them() -> None:
    blocks = _model().blocks
    assert [list(d) for d in blocks] == [[0, 2, 4, 6], [1, 3, 5, 7]]
    assert len(_model(glue=1e-200).blocks) == 1
    # a chain of couplings: 0-1, 1-2 joined, 3 alone
    A = np.zeros((4, 4))
    A[0, 1] = A[2, 1] = 1.0
    A[3, 3] = 1.0
    assert [list(d) for d in coupled_blocks([A])] == [[0, 1, 2], [3]]


@pytest.mark.parametrize("aniso", [1.0, 1.3])
def test_blockwise_factors_reproduce_the_matrix_one_block_per_column(aniso: float) -> None:
    A = _model(aniso=aniso).parameters[0].terms[0][1]
    blocks = _model(aniso=aniso).blocks
    U, V = _factor(A, blocks)
    np.testing.assert_allclose(U @ V.T, A, atol=1e-9 * np.abs(A).max())
    for j in range(U.shape[1]):
        on = [bool(np.any(U[d, j] != 0) or np.any(V[d, j] != 0)) for d in blocks]
        assert sum(on) == 1
    # the same nonzero singular values as the SVD of the whole matrix
    s = np.linalg.svd(A, compute_uv=False)
    np.testing.assert_allclose(np.sort(np.linalg.norm(U, axis=0) * np.linalg.norm(V, axis=0))[::-1],
                               s[s > 1e-12 * s[0]], rtol=1e-10)


def test_stack_solve_equals_the_full_solve() -> None:
    model = _model(aniso=1.3)
    w = 2 * np.pi * np.array([15.0, 60.0, 120.0])
    Z = model.stiffness_stack(w, np.array([0.01, -0.2, 0.4]))
    assert isinstance(Z, StiffnessStack) and len(Z.parts) == 2
    full = np.stack([model.dynamic_stiffness(x, np.array([0.01, -0.2, 0.4])) for x in w])
    np.testing.assert_array_equal(Z.full() == 0, full == 0)
    np.testing.assert_allclose(Z.full(), full, rtol=1e-14, atol=0)
    rng = np.random.default_rng(1)
    B = rng.standard_normal((3, 8, 2)) + 1j * rng.standard_normal((3, 8, 2))
    B[1, 1::2, :] = 0.0  # member 1 in the x plane only
    B[:, 0::2, 1] = 0.0  # right-hand side 1 in the y plane only
    for rhs in (B, B[0, :, :1].real, np.eye(8)[:, :3]):
        np.testing.assert_allclose(Z.solve(rhs), np.linalg.solve(full, np.broadcast_to(rhs, (3, 8, rhs.shape[-1]))),
                                   rtol=1e-10, atol=1e-22)
    np.testing.assert_allclose(Z.transpose().solve(B), np.linalg.solve(np.swapaxes(full, 1, 2), B), rtol=1e-10,
                               atol=1e-22)
    np.testing.assert_allclose(Z.take(np.array([2, 0])).full(), full[[2, 0]], rtol=1e-14)


def _plane_model(model: AffineModel, d: np.ndarray) -> AffineModel:
    """The model restricted to the DOFs ``d`` (one plane): every matrix cut to them."""
    cut = np.ix_(d, d)
    return AffineModel(model.M[cut], model.D[cut], model.K[cut], model.b[d], model.c[d],
                       tuple(AffineParameter(q.name, tuple((k, A[cut]) for k, A in q.terms), q.lo, q.hi)
                             for q in model.parameters))


def _plane_points(pts: Points, d: np.ndarray, idx: np.ndarray) -> Points:
    sub = pts.take(idx)
    return Points(sub.w, sub.g0, sub.t_new, sub.t_healthy, sub.var_new, sub.var_healthy, sub.z, sub.a2, sub.g_lo,
                  sub.g_hi, sub.tolerance, sub.relative_error, sub.b[:, d], sub.c[:, d])


@pytest.mark.parametrize("planes", ["x", "xy"])
@pytest.mark.parametrize("aniso", [1.0, 1.3])
def test_each_points_margin_is_its_own_planes_model(planes: str, aniso: float) -> None:
    """Blockwise, a point's box margin is the one of the model cut to its plane (the other plane's block of N
    does not enter the input-output map); the receptances equal the full matrix's (the glued model)."""
    split, glued = _model(aniso=aniso), _model(glue=1e-200, aniso=aniso)
    assert len(split.blocks) == 2 and len(glued.blocks) == 1
    pts = _points(split, planes)
    fs = BoxFactors.of(split)
    assert len(fs.groups) == 2 and len(BoxFactors.of(glued).groups) == 1
    own = {}
    for d in split.blocks:
        idx = np.flatnonzero(np.any(pts.b[:, d] != 0, axis=1))
        if idx.size:
            red = _plane_model(split, d)
            own[int(d[0])] = (idx, red, BoxFactors.of(red), _plane_points(pts, d, idx))
    assert len(own) == (2 if planes == "xy" else 1)
    decided = 0
    for centre, scale in ((c, s) for c in (np.array([0.0, 0.0, 0.1]), np.array([0.0, 0.1, 0.5]))
                          for s in (0.01, 0.1, 0.3, 1.0)):
        half = scale * np.array([0.02, 0.3, 0.4])
        for idx, red, fr, rp in own.values():
            for j, k in enumerate(idx):
                ok_s, m_s, sh_s, _ = examine_points(split, fs, pts.take(np.array([k])), centre, half)
                ok_r, m_r, sh_r, _ = examine_points(red, fr, rp.take(np.array([j])), centre, half)
                assert ok_s[0] == ok_r[0] and np.isfinite(m_s[0]) == np.isfinite(m_r[0])
                if np.isfinite(m_s[0]):
                    assert m_s[0] == pytest.approx(m_r[0], rel=1e-8, abs=1e-20)
                    decided += 1
                np.testing.assert_allclose(sh_s, sh_r, rtol=1e-8, atol=1e-30)
    assert decided >= 40
    theta = np.array([0.005, -0.1, 0.25])
    np.testing.assert_allclose(point_ratios(split, pts, theta), point_ratios(glued, pts, theta), rtol=1e-10)


@pytest.mark.parametrize("planes", ["x", "xy"])
def test_blockwise_interval_is_sound_by_brute_force(planes: str) -> None:
    """The certified loss interval (blockwise) holds the truth, and outside it no member of a dense grid of
    (E, bearing, loss) explains every point (exact receptances); with one plane it is the plane model's."""
    split = _model(aniso=1.3)
    pts = _points(split, planes)
    lo, hi = np.array([-0.02, -0.3, 0.0]), np.array([0.02, 0.3, 0.8])
    res = severity_interval(split, pts, lo, hi, 2, tol=0.02, slices=8, max_boxes=8)
    assert res.status == "consistent" and res.lower <= 0.3 <= res.upper
    grid = [(e, k) for e in np.linspace(-0.02, 0.02, 9) for k in np.linspace(-0.3, 0.3, 9)]
    outside = [a for a in np.linspace(0.0, 0.8, 81) if a < res.lower - 1e-9 or a > res.upper + 1e-9]
    assert len(outside) >= 40
    for a in outside:
        assert all(np.any(point_ratios(split, pts, np.array([e, k, a])) > 1.0) for e, k in grid), a
    if planes == "x":
        d = split.blocks[0]
        red = severity_interval(_plane_model(split, d), _plane_points(pts, d, np.arange(pts.size)), lo, hi, 2,
                                tol=0.02, slices=8, max_boxes=8)
        assert (red.status, red.boxes, red.excluded_slices) == (res.status, res.boxes, res.excluded_slices)
        assert red.lower == pytest.approx(res.lower) and red.upper == pytest.approx(res.upper)
