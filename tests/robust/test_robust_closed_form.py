"""SISO closed forms against an exact-decimal evaluation of method.md and a brentq oracle."""

from __future__ import annotations

import numpy as np
from robust_helpers import gamma_methodmd_exact
from scipy.optimize import minimize_scalar

from rotorcheck.robust import closed_form as cf
from rotorcheck.robust import lft
from tests.oracles.enclose_bisect import gamma_enclose_system_siso_bisect


def random_siso(rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    me = np.zeros((n, 2, 2), complex)
    c = lambda *s: rng.normal(size=s) + 1j * rng.normal(size=s)  # noqa: E731
    me[:, 0, 0] = c(n) * 10 ** rng.uniform(-2, 8, n)
    s12 = 10 ** rng.uniform(-3, 3, n)
    me[:, 0, 1] = c(n) * s12
    me[:, 1, 0] = c(n) / s12 * 10 ** rng.uniform(-9, -6, n)
    me[:, 1, 1] = c(n) * 10 ** rng.uniform(-9, -6, n)
    W = c(n) * 10 ** rng.uniform(0, 2, n)
    Zt = me[:, 1, 1] * W * (1 + c(n))
    V = np.abs(Zt - me[:, 1, 1] * W) * rng.uniform(0, 1.2, n)
    V[: n // 5] = 0.0
    return me, W, Zt, V


def test_required_siso_matches_exact_decimal_method_md() -> None:
    rng = np.random.default_rng(10)
    me, W, Zt, V = random_siso(rng, 300)
    got = cf.gamma_required_siso(me, W, Zt, V)
    ref = np.array([gamma_methodmd_exact(me[i], W[i], Zt[i], V[i]) for i in range(300)])
    assert np.all(np.isfinite(ref))
    zero = ref == 0
    assert np.all(got[zero] == 0)
    rel = np.abs(got[~zero] - ref[~zero]) / ref[~zero]
    assert rel.max() < 1e-12


def test_method_md_sqrt_form_loses_digits_at_zero_noise() -> None:
    """The verbatim sqrt form takes the root of a cancellation at V = 0 (|beta|^2 - alpha c0 =
    |b|^2 V^2 = 0): ~1e-8 relative error or a spurious 'imaginary root' (inf). The implemented form
    c0 / (|beta| + |b| V) does not."""
    rng = np.random.default_rng(11)
    me, W, Zt, V = random_siso(rng, 200)
    V[:] = 0.0
    ref = np.array([gamma_methodmd_exact(me[i], W[i], Zt[i], 0.0) for i in range(200)])
    stable = cf.gamma_required_siso(me, W, Zt, V)
    verbatim = cf.gamma_required_siso_methodmd(me, W, Zt, V)
    assert np.max(np.abs(stable - ref) / ref) < 1e-12
    bad = ~np.isfinite(verbatim) | (np.abs(verbatim - ref) / ref > 1e-10)
    assert np.count_nonzero(bad) > 10


def test_additive_forms() -> None:
    rng = np.random.default_rng(12)
    n = 50
    G = (rng.normal(size=n) + 1j * rng.normal(size=n)) * 1e-7
    W = (rng.normal(size=n) + 1j * rng.normal(size=n)) * 10
    Zt = G * W + (rng.normal(size=n) + 1j * rng.normal(size=n)) * 1e-7
    V = 5e-8
    e = np.abs(Zt - G * W)
    np.testing.assert_allclose(cf.gamma_required_additive(G, W, Zt, V),
                               np.maximum(0, (e - V) / np.abs(W)), rtol=1e-14)
    me = lft.additive_me(G)
    req = cf.gamma_required_siso(me, W, Zt, V)
    np.testing.assert_allclose(req, np.maximum(0, (e - V) / np.abs(W)), rtol=1e-12, atol=0)
    np.testing.assert_allclose(cf.gamma_enclose_system_siso(me, W, Zt, V),
                               (e + V) / np.abs(W), rtol=1e-12)


def test_enclose_system_matches_forward_brentq_and_geometry() -> None:
    rng = np.random.default_rng(13)
    me, W, Zt, V = random_siso(rng, 120)
    V = np.where(V == 0, 0.3 * np.abs(Zt - me[:, 1, 1] * W), V)
    g = cf.gamma_enclose_system_siso(me, W, Zt, V)
    g_bisect = gamma_enclose_system_siso_bisect(me, W, Zt, V)
    finite = np.isfinite(g)
    assert np.array_equal(finite, np.isfinite(g_bisect))
    assert finite.sum() > 60
    np.testing.assert_allclose(g[finite], g_bisect[finite], rtol=1e-9)
    # geometry: every point of the data disk needs |Delta| <= g, the worst one needs g
    th = np.linspace(0, 2 * np.pi, 4001)
    for i in np.flatnonzero(finite)[:40]:
        Z = Zt[i] + V[i] * np.exp(1j * th)
        ep = Z - me[i, 1, 1] * W[i]
        b = me[i, 0, 1] * me[i, 1, 0] * W[i]
        need = np.abs(ep / (b + me[i, 0, 0] * ep))
        assert need.max() <= g[i] * (1 + 1e-12)
        k = int(np.argmax(need))

        def neg_need(t: float, i: int = i, b: complex = b) -> float:
            e1 = Zt[i] + V[i] * np.exp(1j * t) - me[i, 1, 1] * W[i]
            return -abs(e1 / (b + me[i, 0, 0] * e1))

        best = minimize_scalar(neg_need, bounds=(th[max(k - 1, 0)], th[min(k + 1, th.size - 1)]),
                               method="bounded", options={"xatol": 1e-14})
        assert -best.fun <= g[i] * (1 + 1e-12)
        assert -best.fun >= g[i] * (1 - 1e-8)
    # and the required (data) gamma is the minimum over the data disk
    req = cf.gamma_required_siso(me, W, Zt, V)
    assert np.all(req[finite] <= g[finite])
