"""Certified bound on the 2 x 2 damage dynamics (rotorcheck.robust.damage_block).

Independent references: the eq. 3.11 estimator (identify.damage_dynamics) on exact data, brute-force
sampling of the consistent set (hit-and-run chords computed here from the constraints, interior and
boundary points) and a local nonlinear optimiser (SLSQP) pushing each Re/Im of D_kk to its extreme
over the set, a least-squares residual argument for emptiness, and a W that makes I + W E11 singular.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from scipy.optimize import minimize

import rotorcheck.robust.damage_block as dbm
from rotorcheck.robust.damage_block import DamageBlockBound, damage_block_bound
from rotorcheck.robust.identify import damage_dynamics


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def w_of_d(D: np.ndarray, E11: np.ndarray) -> np.ndarray:
    """W = D (I - E11 D)^-1 (the damaged FRF change is E21 W E12)."""
    return D @ np.linalg.inv(np.eye(2) - E11 @ D)


def d_of_w(W: np.ndarray, E11: np.ndarray) -> np.ndarray:
    """D = (I + W E11)^-1 W, stacked over a leading axis."""
    return np.linalg.solve(np.eye(2) + W @ E11, W)


def make_case(seed: int, n_out: int = 4, n_in: int = 2, f: int = 1, noise: float = 0.02, dscale: float = 3e4,
              fill: float = 1.0) -> dict[str, np.ndarray]:
    """Receptances ~1e-6 m/N, damage ~dscale N/m, noise radius ``noise`` x mean |Q| per pair (varying
    0.5-1.5x), the actual noise a random point of the polydisc scaled by ``fill``."""
    rng = np.random.default_rng(seed)
    E11 = 1e-6 * cplx(rng, f, 2, 2)
    E12 = 1e-6 * cplx(rng, f, 2, n_in)
    E21 = 1e-6 * cplx(rng, f, n_out, 2)
    D = dscale * cplx(rng, f, 2, 2)
    W = w_of_d(D, E11)
    Q = E21 @ W @ E12
    R = noise * np.abs(Q).mean(axis=(1, 2), keepdims=True) * rng.uniform(0.5, 1.5, Q.shape)
    N = fill * R * np.sqrt(rng.uniform(size=Q.shape)) * np.exp(2j * np.pi * rng.uniform(size=Q.shape))
    return {"E11": E11, "E12": E12, "E21": E21, "Q0": Q + N, "R": R, "D": D, "W": W, "Q": Q}


def weighted_map(E12: np.ndarray, E21: np.ndarray, Q0: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(G, g): (G vec W)_p = (E21 W E12)_p / R_p, g = Q0 / R (one frequency)."""
    G = np.einsum("oj,li->oijl", E21, E12).reshape(Q0.size, 4) / R.reshape(-1, 1)
    return G, (Q0 / R).reshape(-1)


def set_jacobian(x: np.ndarray, G: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Jacobian of ``1 - |g - G w|^2`` (per pair) in ``x = (Re w, Im w)``."""
    J = np.conj(g - G @ (x[:4] + 1j * x[4:]))[:, None] * G
    return np.concatenate([2 * J.real, -2 * J.imag], axis=1)


def hit_and_run(G: np.ndarray, g: np.ndarray, W_start: np.ndarray, n: int,
                rng: np.random.Generator) -> np.ndarray:
    """Points of {W : |g - G vec W| <= 1 entrywise}: chord end points and uniform chord points."""
    w = W_start.reshape(4).astype(complex)
    out = []
    for _ in range(n):
        d = cplx(rng, 4)
        r0, v = g - G @ w, G @ d  # |r0 - t v|^2 <= 1
        a, b, c = np.abs(v) ** 2, -2 * np.real(np.conj(r0) * v), np.abs(r0) ** 2 - 1
        disc = b * b - 4 * a * c
        if np.any(disc < 0):
            continue
        lo, hi = np.max((-b - np.sqrt(disc)) / (2 * a)), np.min((-b + np.sqrt(disc)) / (2 * a))
        if lo > hi:
            continue
        out += [w + lo * d, w + hi * d]
        w = w + rng.uniform(lo, hi) * d
        out.append(w.copy())
    return np.array(out).reshape(-1, 2, 2)


def outer_violations(b: DamageBlockBound, i: int, Ds: np.ndarray) -> int:
    d = np.stack([Ds[:, 0, 0], Ds[:, 1, 1]], axis=1)
    bad = ((d.real < b.re_outer[i, :, 0]) | (d.real > b.re_outer[i, :, 1])
           | (d.imag < b.im_outer[i, :, 0]) | (d.imag > b.im_outer[i, :, 1]))
    return int(bad.sum())


def assert_inner_in_outer(b: DamageBlockBound) -> None:
    ok = b.kind == "bounded"
    for inner, outer in ((b.re_inner, b.re_outer), (b.im_inner, b.im_outer)):
        assert np.all(inner[ok, :, 0] >= outer[ok, :, 0])
        assert np.all(inner[ok, :, 1] <= outer[ok, :, 1])
        assert np.all(inner[ok, :, 0] <= inner[ok, :, 1])


def relative_gap(b: DamageBlockBound) -> np.ndarray:
    """(f, 4): (outer width - inner width) / outer width for Re/Im of D_xx, D_yy."""
    width = np.concatenate([np.diff(b.re_outer, axis=-1)[..., 0], np.diff(b.im_outer, axis=-1)[..., 0]], axis=-1)
    return np.asarray(np.concatenate([b.re_gap, b.im_gap], axis=-1) / width)


# --------------------------------------------------------------------------------------------------


def test_noise_free_limit_matches_damage_dynamics_and_true_d() -> None:
    c = make_case(1, f=6, noise=1e-9)
    rng = np.random.default_rng(11)
    Th = 1e-5 * cplx(rng, 6, 4, 2)
    exact = c["Q"]
    # sign convention: the eq. 3.11 estimator on exact data returns the true D
    D_ref = damage_dynamics(c["E11"], c["E12"], c["E21"], Th, Th + exact)
    np.testing.assert_allclose(D_ref, c["D"], rtol=1e-10)
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], exact, c["R"])
    assert (b.kind == "bounded").all() and b.consistent.all()
    np.testing.assert_allclose(b.estimate, D_ref, rtol=1e-10)
    assert b.contains(c["D"]).all()
    scale = np.abs(c["D"][:, [0, 1], [0, 1]])
    for outer in (b.re_outer, b.im_outer):
        assert (np.diff(outer, axis=-1)[..., 0] / scale).max() < 1e-6
    # with the noise of the radius the same holds for the noisy data, and the width follows R
    b2 = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"])
    assert b2.contains(c["D"]).all()
    np.testing.assert_allclose(b2.estimate, c["D"], rtol=1e-6)
    b3 = damage_block_bound(c["E11"], c["E12"], c["E21"], exact, 1e3 * c["R"])
    w1, w3 = np.diff(b.re_outer, axis=-1), np.diff(b3.re_outer, axis=-1)
    assert np.all((w3 / w1 > 300) & (w3 / w1 < 3000))


@pytest.mark.parametrize(("shape", "seed", "angles"), [((4, 2), 0, 8), ((4, 2), 1, 8), ((2, 2), 2, 8),
                                                       ((3, 2), 3, 5), ((2, 3), 4, 8), ((4, 2), 5, 12)])
def test_outer_contains_every_sampled_and_optimised_point(shape: tuple[int, int], seed: int, angles: int) -> None:
    n_out, n_in = shape
    dscale, noise = [(3e4, 0.05), (1e5, 0.03), (3e5, 0.01)][seed % 3]  # up to |E11 D| ~ 1: strongly nonlinear
    c = make_case(100 + seed, n_out, n_in, f=3, noise=noise, dscale=dscale)
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"], angles=angles)
    assert_inner_in_outer(b)
    rng = np.random.default_rng(seed)
    n_checked = 0
    for i in range(3):
        G, g = weighted_map(c["E12"][i], c["E21"][i], c["Q0"][i], c["R"][i])
        assert np.linalg.matrix_rank(G) == 4  # injective map: the set is bounded in W
        assert b.kind[i] == "bounded"
        assert b.contains(c["D"])[i]
        E11 = c["E11"][i]
        Ws = hit_and_run(G, g, c["W"][i], 1500, rng)
        assert np.max(np.abs(g[None] - Ws.reshape(-1, 4) @ G.T)) <= 1 + 1e-9
        # convex combinations of sampled points are in the set too
        pick = rng.integers(0, len(Ws), size=(500, 3))
        lam = rng.dirichlet(np.ones(3), size=500)
        Ws = np.concatenate([Ws, np.einsum("nk,nkab->nab", lam, Ws[pick])])
        assert outer_violations(b, i, d_of_w(Ws, E11)) == 0
        n_checked += len(Ws)
        # a local optimiser pushing Re/Im D_kk to its extremes over the set stays inside the outer interval
        # (exact gradients: with SLSQP's finite differences 12 of the 144 optima ended outside the set, and the
        # extremes reached were up to 5e-4 less far; they also took four times as long)
        cons = {"type": "ineq", "fun": lambda x, G=G, g=g: 1 - np.abs(g - G @ (x[:4] + 1j * x[4:])) ** 2,
                "jac": lambda x, G=G, g=g: set_jacobian(x, G, g)}
        x0 = np.concatenate([c["W"][i].reshape(4).real, c["W"][i].reshape(4).imag])
        for k in range(2):
            for a in range(4):
                def neg(x: np.ndarray, k: int = k, a: int = a, E11: np.ndarray = E11) -> float:
                    W = (x[:4] + 1j * x[4:]).reshape(2, 2)
                    return -float(np.real(d_of_w(W, E11)[k, k] * (-1j) ** a))

                def neg_grad(x: np.ndarray, k: int = k, a: int = a, E11: np.ndarray = E11) -> np.ndarray:
                    W = (x[:4] + 1j * x[4:]).reshape(2, 2)  # dD = (I + W E11)^-1 dW (I + E11 W)^-1
                    Binv, Cinv = np.linalg.inv(np.eye(2) + W @ E11), np.linalg.inv(np.eye(2) + E11 @ W)
                    coef = np.outer(Binv[k], Cinv[:, k]).reshape(4) * (-1j) ** a  # of vec dW in the functional
                    return np.concatenate([-coef.real, coef.imag])

                res = minimize(neg, x0, jac=neg_grad, constraints=[cons], method="SLSQP",
                               options={"maxiter": 300, "ftol": 1e-12})
                Wx = (res.x[:4] + 1j * res.x[4:]).reshape(2, 2)
                if np.max(np.abs(g - G @ Wx.reshape(4))) > 1 + 1e-9:
                    continue
                assert outer_violations(b, i, d_of_w(Wx[None], E11)) == 0
    print(f"shape {shape}: {n_checked} sampled D, 0 outside the outer intervals")


def test_not_injective_is_unbounded() -> None:
    """3 outputs x 1 input: E21 W E12 sees only W E12, two of the four complex unknowns."""
    c = make_case(7, 3, 1, f=2, noise=0.02)
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"])
    assert (b.kind == "unbounded").all()
    assert np.isinf(b.re_outer).all() and np.isinf(b.im_outer).all()
    assert b.contains(c["D"]).all()
    assert np.isfinite(b.re_inner).all()


@pytest.mark.parametrize("noise", [0.01, 0.02, 0.05])
def test_tightness_for_moderate_noise(noise: float) -> None:
    c = make_case(3, f=10, noise=noise, dscale=3e4)
    t = time.perf_counter()
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"])
    dt = time.perf_counter() - t
    assert (b.kind == "bounded").all()
    assert b.contains(c["D"]).all()
    assert_inner_in_outer(b)
    rel = relative_gap(b)
    b0 = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"], refine=0)
    rel0 = relative_gap(b0)
    print(f"noise {noise:.0%}: gap / outer width median {np.median(rel):.4f} max {rel.max():.4f} "
          f"(no refinement: median {np.median(rel0):.4f} max {rel0.max():.4f}); {1e3 * dt / 10:.1f} ms per frequency")
    assert np.median(rel) < 0.02
    assert rel.max() < 0.06
    assert np.all(rel <= rel0 + 1e-12)  # refinement only tightens
    # the refined outer interval lies inside the unrefined one
    assert np.all(b.re_outer[..., 0] >= b0.re_outer[..., 0]) and np.all(b.re_outer[..., 1] <= b0.re_outer[..., 1])


def test_inconsistent_data_is_empty() -> None:
    c = make_case(5, f=3, noise=0.02)
    rng = np.random.default_rng(5)
    Q0 = c["Q0"].copy()
    for i in range(3):
        G, _ = weighted_map(c["E12"][i], c["E21"][i], Q0[i], c["R"][i])
        v = cplx(rng, G.shape[0])
        U = np.linalg.qr(G)[0]
        v -= U @ (U.conj().T @ v)  # outside the range of the weighted map
        # independent reference: |res|_2 >= |v|_2 for every W, so max |res| / R >= |v|_2 / sqrt(m)
        scale = [3.0, 1.5, 0.5][i] * np.sqrt(G.shape[0]) / np.linalg.norm(v)
        Q0[i] = c["Q"][i] + (scale * v).reshape(Q0[i].shape) * c["R"][i]
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], Q0, c["R"])
    assert list(b.kind[:2]) == ["empty", "empty"]
    assert not b.consistent[:2].any()
    assert np.isnan(b.re_outer[:2]).all() and not b.contains(c["D"])[:2].any()
    # the third: the true W has max |res| / R <= 0.5 * sqrt(m) ... not necessarily <= 1; check by the residual
    G, g = weighted_map(c["E12"][2], c["E21"][2], Q0[2], c["R"][2])
    if np.max(np.abs(g - G @ c["W"][2].reshape(4))) <= 1:
        assert b.kind[2] == "bounded" and b.contains(c["D"])[2]


def test_barely_consistent_data_is_not_empty() -> None:
    """Noise filling 99 % of the radius: the true W is in the set, which must not be called empty."""
    c = make_case(6, f=8, noise=0.02, fill=0.99)
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"])
    assert (b.kind == "bounded").all()
    assert b.contains(c["D"]).all()


def test_singular_point_in_the_set_is_unbounded() -> None:
    c = make_case(8, f=2, noise=0.01)
    E11 = c["E11"]
    Ws = -np.linalg.inv(E11)  # I + Ws E11 = 0: D infinite there
    Q0 = c["E21"] @ Ws @ c["E12"]
    R = 0.01 * np.abs(Q0).mean(axis=(1, 2), keepdims=True) * np.ones(Q0.shape)
    b = damage_block_bound(E11, c["E12"], c["E21"], Q0, R)
    assert (b.kind == "unbounded").all()
    assert np.isinf(b.re_outer).all()
    assert b.contains(np.full((2, 2, 2), 1e12 + 0j)).all()
    # half-way: W whose I + W E11 has a singular value of about 1/2 -- bounded, and sound
    c2 = make_case(8, f=1, noise=0.01, dscale=1e5)
    b2 = damage_block_bound(c2["E11"], c2["E12"], c2["E21"], c2["Q0"], c2["R"])
    assert b2.kind[0] in ("bounded", "unbounded") and b2.contains(c2["D"])[0]


class FakePanic(BaseException):
    """Like pyo3's PanicException (a BaseException)."""


def test_failures_are_isolated_per_frequency(monkeypatch: pytest.MonkeyPatch) -> None:
    c = make_case(9, f=6, noise=0.02)
    Q0, R = c["Q0"].copy(), c["R"].copy()
    Q0[2, 1, 0] = np.nan
    R[4, 0, 1] = 0.0
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], Q0, R)
    assert list(b.kind) == ["bounded", "bounded", "undecided", "bounded", "undecided", "bounded"]
    assert np.isnan(b.re_outer[[2, 4]]).all() and not b.contains(c["D"])[[2, 4]].any()
    ref = damage_block_bound(c["E11"][[0, 1, 3, 5]], c["E12"][[0, 1, 3, 5]], c["E21"][[0, 1, 3, 5]],
                             Q0[[0, 1, 3, 5]], R[[0, 1, 3, 5]])
    for name in ("re_outer", "im_outer", "re_inner", "im_inner", "estimate"):
        np.testing.assert_array_equal(getattr(b, name)[[0, 1, 3, 5]], getattr(ref, name))

    # a Rust panic inside Clarabel at one frequency: that point undecided, the others unaffected
    real_solver = dbm.clarabel.DefaultSolver
    calls = {"n": 0}

    def panicking(*args: object) -> object:
        calls["n"] += 1
        if calls["n"] == 1:
            raise FakePanic("index out of bounds")
        return real_solver(*args)

    monkeypatch.setattr(dbm.clarabel, "DefaultSolver", panicking)
    b = damage_block_bound(c["E11"][:3], c["E12"][:3], c["E21"][:3], c["Q0"][:3], c["R"][:3])
    assert list(b.kind) == ["undecided", "bounded", "bounded"]
    assert np.isfinite(b.estimate[0]).all()  # computed before the solver

    def interrupted(*args: object) -> object:
        raise KeyboardInterrupt

    monkeypatch.setattr(dbm.clarabel, "DefaultSolver", interrupted)
    with pytest.raises(KeyboardInterrupt):
        damage_block_bound(c["E11"][:1], c["E12"][:1], c["E21"][:1], c["Q0"][:1], c["R"][:1])


def test_input_shapes() -> None:
    c = make_case(10, f=1)
    E11, E12, E21, Q0, R = (c[k][0] for k in ("E11", "E12", "E21", "Q0", "R"))
    b = damage_block_bound(E11, E12, E21, Q0, float(R.mean()))  # unstacked matrices, scalar radius
    assert b.kind.shape == (1,) and b.re_outer.shape == (1, 2, 2) and b.estimate.shape == (1, 2, 2)
    with pytest.raises(ValueError, match="Q0"):
        damage_block_bound(E11, E12, E21, Q0[:3], R[:3])
    with pytest.raises(ValueError, match="frequency axes"):
        damage_block_bound(np.stack([E11] * 2), np.stack([E12] * 3), E21, Q0, R)
    with pytest.raises(ValueError, match="angles"):
        damage_block_bound(E11, E12, E21, Q0, R, angles=2)


def test_vectorised_call_over_many_frequencies() -> None:
    """One call over 40 frequencies: the truth is inside wherever bounded (timing: bench, not here)."""
    f = 40
    c = make_case(12, f=f, noise=0.02)
    b = damage_block_bound(c["E11"], c["E12"], c["E21"], c["Q0"], c["R"])
    assert set(b.kind) <= set(dbm.KINDS)
    assert b.contains(c["D"])[b.kind == "bounded"].all()
    assert b.re_outer.shape == (f, 2, 2) and b.im_inner.shape == (f, 2, 2)
