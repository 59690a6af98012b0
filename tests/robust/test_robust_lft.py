"""LFTs and Me builders against direct formulas and direct solves."""

from __future__ import annotations

import numpy as np
import pytest
from robust_helpers import three_mass_Z

from rotorcheck.robust import lft


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def test_lft_upper_and_lower_match_their_formulas() -> None:
    rng = np.random.default_rng(0)
    f = 7
    M = cplx(rng, f, 2 + 3, 3 + 2)  # n_v = 2, n_u = 3, n_z = 3, n_w = 2
    D = 0.2 * cplx(rng, f, 3, 2)
    got = lft.lft_upper(M, D)
    for i in range(f):
        M11, M12, M21, M22 = M[i, :2, :3], M[i, :2, 3:], M[i, 2:, :3], M[i, 2:, 3:]
        ref = M22 + M21 @ D[i] @ np.linalg.inv(np.eye(2) - M11 @ D[i]) @ M12
        np.testing.assert_allclose(got[i], ref, rtol=1e-12, atol=1e-14)
    Dl = 0.2 * cplx(rng, f, 2, 3)  # closes n_y = 3 rows, n_u = 2 cols
    got_l = lft.lft_lower(M, Dl)
    for i in range(f):
        M11, M12, M21, M22 = M[i, :2, :3], M[i, :2, 3:], M[i, 2:, :3], M[i, 2:, 3:]
        ref = M11 + M12 @ Dl[i] @ np.linalg.inv(np.eye(3) - M22 @ Dl[i]) @ M21
        np.testing.assert_allclose(got_l[i], ref, rtol=1e-12, atol=1e-14)
    with pytest.raises(ValueError):
        lft.lft_upper(M, D, n=3)


def test_additive_and_multiplicative_me() -> None:
    rng = np.random.default_rng(1)
    G = cplx(rng, 5, 2, 3) * 1e-7
    D = cplx(rng, 5, 2, 3) * 1e-8
    np.testing.assert_allclose(lft.lft_upper(lft.additive_me(G), D), G + D, rtol=1e-13)
    Dm = 0.1 * cplx(rng, 5, 2, 2)
    np.testing.assert_allclose(lft.lft_upper(lft.multiplicative_me(G), Dm),
                               (np.eye(2) + Dm) @ G, rtol=1e-12)
    Di = 0.1 * cplx(rng, 5, 3, 3)
    np.testing.assert_allclose(lft.lft_upper(lft.multiplicative_me(G, "input"), Di),
                               G @ (np.eye(3) + Di), rtol=1e-12)


@pytest.mark.parametrize("rank", [1, 2])
def test_parametric_me_equals_direct_solve(rank: int) -> None:
    rng = np.random.default_rng(2 + rank)
    f, n = 6, 5
    Z0 = cplx(rng, f, n, n) + 4 * np.eye(n)
    L = cplx(rng, f, n, rank)  # frequency dependent
    R = cplx(rng, n, rank)
    b = cplx(rng, n, 2)
    c = cplx(rng, 3, n)
    me = lft.parametric_me(Z0, L, R, b, c)
    assert me.shape == (f, rank + 3, rank + 2)
    for _ in range(5):
        delta = 0.3 * cplx(rng, f)
        got = lft.lft_upper(me, delta[:, None, None] * np.eye(rank))
        ref = c @ np.linalg.solve(Z0 + L @ (delta[:, None, None] * R.T[None]), b[None])
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-13)


def test_mass_factor_three_mass_and_engineering_me() -> None:
    fr = np.linspace(0.5, 8, 40)
    w = 2 * np.pi * fr
    Ze = three_mass_Z(fr, m1=2.6)
    L, R = lft.mass_factor(w, 0, 3)
    for dm in (0.2113, -0.1, 0.05 + 0.02j):
        Zd = Ze + L @ (dm * R.T[None])
        np.testing.assert_allclose(Zd, three_mass_Z(fr, m1=2.6 + dm), rtol=1e-13, atol=1e-9)
        meE = lft.engineering_me(Ze, L, R, 2, 0, 0)
        E = lft.lft_upper(meE, np.full((40, 1, 1), dm))
        E11, E12, E21, E22 = lft.engineering_system(Zd, 2, 0, 0)
        np.testing.assert_allclose(E[:, 0, 0], E11[:, 0, 0], rtol=1e-10)
        np.testing.assert_allclose(E[:, 0, 1], E12[:, 0, 0], rtol=1e-10)
        np.testing.assert_allclose(E[:, 1, 0], E21[:, 0, 0], rtol=1e-10)
        np.testing.assert_allclose(E[:, 1, 1], E22[:, 0, 0], rtol=1e-10)


def test_engineering_system_partitions_and_damage_sign() -> None:
    """E from solves equals the explicit inverse; T = E22 + E21 D (1 - E11 D)^-1 E12 with
    D = +dk reproduces a stiffness loss dk at the damage port (method.md convention)."""
    fr = np.geomspace(0.5, 8, 30)
    Z = three_mass_Z(fr)
    E11, E12, E21, E22 = lft.engineering_system(Z, 2, 0, 0)
    H = np.linalg.inv(Z)
    np.testing.assert_allclose(E11[:, 0, 0], H[:, 2, 2], rtol=1e-12)
    np.testing.assert_allclose(E12[:, 0, 0], H[:, 2, 0], rtol=1e-12)
    np.testing.assert_allclose(E21[:, 0, 0], H[:, 0, 2], rtol=1e-12)
    np.testing.assert_allclose(E22[:, 0, 0], H[:, 0, 0], rtol=1e-12)
    dk = 36.0
    E = np.concatenate([np.concatenate([E11, E12], 2), np.concatenate([E21, E22], 2)], 1)
    T = lft.lft_upper(E, np.full((30, 1, 1), dk))[:, 0, 0]
    T_ref = np.linalg.inv(three_mass_Z(fr, k3=386.0 - dk))[:, 0, 0]
    np.testing.assert_allclose(T, T_ref, rtol=1e-10)


def test_io_me_and_low_rank_factor() -> None:
    rng = np.random.default_rng(5)
    E11, E12, E21, E22 = (cplx(rng, 4) for _ in range(4))
    d = 0.3 * cplx(rng, 4)
    Ea = lft.lft_upper(lft.io_me(E11, E12, E21, E22, "additive"), d[:, None, None])
    np.testing.assert_allclose(Ea[:, 1, 1], E22 + d, rtol=1e-13)
    np.testing.assert_allclose(Ea[:, 0, 0], E11, rtol=1e-13)
    Em = lft.lft_upper(lft.io_me(E11, E12, E21, E22, "multiplicative"), d[:, None, None])
    np.testing.assert_allclose(Em[:, 1, 1], (1 + d) * E22, rtol=1e-13)
    A = rng.normal(size=(6, 3))
    S = A @ np.diag([2.0, -1.0, 0.5]) @ A.T
    Lf, Rf = lft.low_rank_factor(S)
    assert Lf.shape == (6, 3)
    np.testing.assert_allclose(Lf @ Rf.T, S, atol=1e-12)
