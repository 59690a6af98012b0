"""Regression tests for defects found by an independent check of the robust core.

Each test asserts numbers against an independent reference (closed forms, brute force over the
uncertainty, Monte Carlo members of the uncertainty set), never against the code itself:

1. enclose='system' with ``Me12 Me21 W = 0``: 'unexplainable', never ``1/|Me11|``;
2. enclose='system' honours ``Block.weight`` (gamma in units of the weighted block);
3. a negative / NaN noise bound V is a ValueError naming the noise bound;
4. multiplicative identification: the true D_0 lies in its own set (the uncertainty scales the
   damage path too, as in validation and ``rotorcheck.nominal``);
5. tall M22, full block, per-output noise: no 'solver_failed', bounds bracket a reference;
6. a NaN in Zt or Me at one point marks that point 'bad_data' and solves the others;
7. a solver raising a BaseException (Clarabel's pyo3 PanicException) fails that point only, with
   the reason; every Clarabel call is bounded by the point's time limit.
"""

from __future__ import annotations

import time
from typing import Any

import clarabel
import numpy as np
import pytest
from scipy.optimize import minimize, minimize_scalar

from rotorcheck.robust import closed_form as cf
from rotorcheck.robust import identify as idf
from rotorcheck.robust import lft, mu, validation
from rotorcheck.robust.mu.backends import project_scales


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def random_general_me(rng: np.random.Generator, f: int) -> np.ndarray:
    me = cplx(rng, f, 2, 2)
    me[:, 0, 0] *= 0.3
    return me


def brute_enclose(me: np.ndarray, W: complex, Zt: complex, V: float) -> float:
    """Smallest g with the data disk inside the image of |Delta| <= g, by brute force: the largest
    |Delta| any point of the data disk needs (inverse Moebius ``Delta = e / (b + a e)``), over a
    dense grid of its boundary refined by a bounded scalar search."""
    a, b = me[0, 0], me[0, 1] * me[1, 0] * W

    def need(t: np.ndarray | float) -> np.ndarray:
        e = Zt + V * np.exp(1j * np.asarray(t)) - me[1, 1] * W
        return np.abs(e / (b + a * e))

    th = np.linspace(0, 2 * np.pi, 20001)
    k = int(np.argmax(need(th)))
    res = minimize_scalar(lambda t: -float(need(t)), bounds=(th[max(k - 1, 0)], th[min(k + 1, th.size - 1)]),
                          method="bounded", options={"xatol": 1e-14})
    return max(float(need(th).max()), -float(res.fun))


# --------------------------------------------------------------------------------------------------
# (1) enclose='system' when the uncertainty cannot reach the output


def test_enclose_system_unexplainable_when_uncertainty_cannot_reach_output() -> None:
    rng = np.random.default_rng(21)
    f = 30
    me = random_general_me(rng, f)
    W = cplx(rng, f)
    Zt = me[:, 1, 1] * W * (1 + 0.5 * cplx(rng, f))
    V = 0.3 * np.abs(Zt - me[:, 1, 1] * W)
    me[:10, 0, 1] = 0.0  # Me12 = 0
    me[10:20, 1, 0] = 0.0  # Me21 = 0
    # brute force: with b = 0 every Delta gives the nominal output, so no gamma encloses a data
    # disk of radius V > 0 (the old code returned 1/|Me11| with status 'ok' there)
    deltas = 10 ** rng.uniform(-3, 3, 200) * np.exp(2j * np.pi * rng.uniform(size=200))
    for i in range(20):
        out = lft.lft_upper(np.broadcast_to(me[i], (200, 2, 2)), deltas[:, None, None])[:, 0, 0] * W[i]
        np.testing.assert_allclose(out, me[i, 1, 1] * W[i], rtol=1e-12)
    v = validation.validate(me, W, Zt, V, enclose="system")
    assert np.all(v.status[:20] == "unexplainable")
    assert np.all(np.isinf(v.gamma[:20])) and not v.enclosed
    assert np.all(np.isinf(cf.gamma_enclose_system_siso(me[:20], W[:20], Zt[:20], V[:20])))
    # the other points: finite, equal to the brute-force enclosure
    ref = np.array([brute_enclose(me[i], W[i], Zt[i], V[i]) for i in range(20, f)])
    ok = v.status[20:] == "ok"
    assert ok.sum() >= 8
    np.testing.assert_allclose(v.gamma[20:][ok], ref[ok], rtol=1e-8)
    # 'data' mode says the same at b = 0 (pre-check of the LMI)
    vd = validation.validate(me, W, Zt, V, enclose="data")
    assert np.all(vd.status[:20] == "unexplainable") and np.all(np.isinf(vd.gamma[:20]))
    # degenerate but exact: V = 0 and data equal to the nominal output: gamma 0 encloses it
    v0 = validation.validate(me[:3], W[:3], me[:3, 1, 1] * W[:3], 0.0, enclose="system")
    assert np.all(v0.status == "ok") and np.all(v0.gamma == 0)


# --------------------------------------------------------------------------------------------------
# (2) enclose='system' honours the block weight


@pytest.mark.parametrize("weight", [0.25, 3.0])
def test_enclose_system_honours_block_weight(weight: float) -> None:
    rng = np.random.default_rng(22)
    f = 25
    me = random_general_me(rng, f)
    W = cplx(rng, f) * 5
    Zt = me[:, 1, 1] * W * (1 + 0.4 * cplx(rng, f))
    V = 0.2 * np.abs(Zt - me[:, 1, 1] * W)
    st = mu.Structure((mu.Block("scalar", (1, 1), weight=weight),))
    v = validation.validate(me, W, Zt, V, enclose="system", structure=st)
    # by hand: |Delta| <= w gamma, Delta = w Delta' with |Delta'| <= gamma: Me's Delta row times w
    me_w = me.copy()
    me_w[:, 0, :] *= weight
    ref = np.array([brute_enclose(me_w[i], W[i], Zt[i], V[i]) for i in range(f)])
    fin = np.isfinite(cf.gamma_enclose_system_siso(me, W, Zt, V))
    assert fin.sum() >= 15
    assert np.all(v.status[fin] == "ok")
    np.testing.assert_allclose(v.gamma[fin], ref[fin], rtol=1e-8)
    unweighted = validation.validate(me, W, Zt, V, enclose="system")
    np.testing.assert_allclose(v.gamma[fin], unweighted.gamma[fin] / weight, rtol=1e-12)
    # additive closed form with the weight applied by hand: (|Zt - G W| + V) / (w |W|)
    G = me[:, 1, 1]
    va = validation.validate(lft.additive_me(G), W, Zt, V, enclose="system", structure=st)
    np.testing.assert_allclose(va.gamma, (np.abs(Zt - G * W) + V) / (weight * np.abs(W)), rtol=1e-12)
    # 'data' mode already honoured the weight: same convention in both modes
    vd = validation.validate(lft.additive_me(G), W, Zt, V, enclose="data", structure=st)
    np.testing.assert_allclose(vd.gamma, np.maximum(0, np.abs(Zt - G * W) - V) / (weight * np.abs(W)),
                               rtol=1e-6)


# --------------------------------------------------------------------------------------------------
# (3) the noise bound


@pytest.mark.parametrize("bad", [-1e-9, np.nan, np.inf, "array_negative", "array_nan"])
def test_negative_or_nan_noise_bound_is_rejected(bad: Any) -> None:
    rng = np.random.default_rng(23)
    f = 6
    G = cplx(rng, f) * 1e-7
    W = cplx(rng, f) * 10
    Zt = G * W * (1 + 0.3 * cplx(rng, f))
    me = lft.additive_me(G)
    if isinstance(bad, str):
        V = np.full(f, 1e-8)
        V[3] = -1e-12 if bad == "array_negative" else np.nan
    else:
        V = bad
    for enclose in ("data", "system"):
        with pytest.raises(ValueError, match="noise bound"):
            validation.validate(me, W, Zt, V, enclose=enclose)
    with pytest.raises(ValueError, match="noise bound"):
        validation.detect(me, W, Zt, V, np.full(f, 1e-9))
    with pytest.raises(ValueError, match="noise bound"):
        mu.required_gamma(me, W, Zt, V)


# --------------------------------------------------------------------------------------------------
# (4) multiplicative identification


def multiplicative_plant(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, E22: np.ndarray
                         ) -> np.ndarray:
    """Augmented plant [y_delta, d, z] <- [u_delta, f_d, w] of an output multiplicative
    uncertainty, written out from its definition z = (1 + Delta)(E21 f_d + E22 w) (as
    rotorcheck.nominal builds it)."""
    P = np.zeros((E11.size, 3, 3), complex)
    P[:, 1, 1], P[:, 1, 2], P[:, 2, 1], P[:, 2, 2] = E11, E12, E21, E22
    P[:, 0, 1], P[:, 0, 2] = E21, E22
    P[:, 2, 0] = 1.0
    return P


def multiplicative_cases(seed: int, n: int) -> dict[str, np.ndarray]:
    """Data from a member of the uncertainty set: |Delta_0| <= gamma, |v| <= V (half of each on
    the boundary, where a wrong set shows first), known D_0."""
    rng = np.random.default_rng(seed)
    E11, E12, E21, E22 = (cplx(rng, n) for _ in range(4))
    D0 = cplx(rng, n) * 10 ** rng.uniform(-1, 0.5, n)
    W = cplx(rng, n) * 10 ** rng.uniform(0, 2, n)
    g = 10 ** rng.uniform(-2, -0.1, n)
    rad = np.where(rng.uniform(size=n) < 0.5, 1.0, np.sqrt(rng.uniform(size=n)))
    Dl0 = g * rad * np.exp(2j * np.pi * rng.uniform(size=n))
    close = np.zeros((n, 2, 2), complex)
    close[:, 0, 0], close[:, 1, 1] = Dl0, D0
    clean = lft.lft_upper(multiplicative_plant(E11, E12, E21, E22), close)[:, 0, 0]
    V = np.abs(clean * W) * 10 ** rng.uniform(-3, -0.5, n)
    rn = np.where(rng.uniform(size=n) < 0.5, 1.0, np.sqrt(rng.uniform(size=n)))
    T = (clean * W + V * rn * np.exp(2j * np.pi * rng.uniform(size=n))) / W
    return {"E11": E11, "E12": E12, "E21": E21, "E22": E22, "T": T, "gamma": g, "V": V, "W": W,
            "D0": D0}


def test_multiplicative_identification_contains_true_damage_in_300_cases() -> None:
    c = multiplicative_cases(24, 300)
    E = (c["E11"], c["E12"], c["E21"], c["E22"])
    ds = idf.damage_set_io(*E, c["T"], c["gamma"], c["V"], c["W"], kind="multiplicative")
    inside = ds.contains(c["D0"])
    print(f"\n[multiplicative] D_0 outside its set in {np.count_nonzero(~inside)} of 300 cases")
    assert inside.all()
    assert np.all(np.isin(ds.kind, ["disk", "outside"]))
    # nominal estimate = eq. 3.11 with the nominal model, a member of the set
    np.testing.assert_allclose(ds.nominal, idf.damage_dynamics(*E, c["T"]), rtol=1e-12)
    assert ds.contains(ds.nominal).all()
    # Monte Carlo over the whole set: every member (Delta, v), both on their circles, maps into it
    th = np.exp(2j * np.pi * np.arange(96) / 96)
    for i in range(100):
        H = ((c["T"][i] - c["V"][i] / abs(c["W"][i]) * th[None, :]) / (1 + c["gamma"][i] * th[:, None])).ravel()
        D = 1 / (c["E12"][i] * c["E21"][i] / (H - c["E22"][i]) + c["E11"][i])
        assert ds.contains_at(i, D).all()
    # exact in the limits: without noise the images of |Delta| = gamma, with gamma = 0 the images
    # of |v| = V, lie on the set's circle
    for V, g in ((0.0, c["gamma"]), (c["V"], 0.0)):
        d0 = idf.damage_set_io(*E, c["T"], g, V, c["W"], kind="multiplicative")
        n_disk = 0
        for i in np.flatnonzero(d0.kind == "disk")[:40]:
            if np.ndim(V) == 0:
                H = c["T"][i] / (1 + c["gamma"][i] * th)
            else:
                H = c["T"][i] - c["V"][i] / abs(c["W"][i]) * th
            D = 1 / (c["E12"][i] * c["E21"][i] / (H - c["E22"][i]) + c["E11"][i])
            np.testing.assert_allclose(np.abs(D - d0.centre[i]), d0.radius[i], rtol=1e-9)
            n_disk += 1
        assert n_disk == 40


def test_io_me_multiplicative_scales_the_damage_path_like_the_nominal_plant() -> None:
    rng = np.random.default_rng(25)
    E11, E12, E21, E22 = (cplx(rng, 8) for _ in range(4))
    d = 0.3 * cplx(rng, 8)
    E_io = lft.lft_upper(lft.io_me(E11, E12, E21, E22, "multiplicative"), d[:, None, None])
    E_ref = lft.lft_upper(multiplicative_plant(E11, E12, E21, E22), d[:, None, None])
    np.testing.assert_allclose(E_io, E_ref, rtol=1e-13)
    np.testing.assert_allclose(E_io[:, 1, 0], (1 + d) * E21, rtol=1e-13)


# --------------------------------------------------------------------------------------------------
# (5) tall M22, full block, per-output noise


def tall_cases(seed: int, n: int = 360) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray, float]]:
    """Well-posed points (some output outside the noise): 2 or 3 outputs, one full (n_out x 1)
    block; additive Me, general Me with Me11 = 0, general Me."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        nout = 2 + i % 2
        kind = ("additive", "m11zero", "general")[(i // 2) % 3]
        if kind == "additive":
            me = lft.additive_me(cplx(rng, 1, nout, 1))[0]
        else:
            me = cplx(rng, 1 + nout, nout + 1)
            me[0, :nout] *= 0.0 if kind == "m11zero" else 0.3
        W = cplx(rng, 1)
        Z = lft.lft_upper(me, 0.5 * cplx(rng, nout, 1))[0] @ W
        Zt = Z + 0.3 * np.abs(Z).max() * rng.uniform(0, 1, nout) * np.exp(2j * np.pi * rng.uniform(size=nout))
        c = Zt - me[1:, nout:] @ W
        V = float(np.abs(c).max() * rng.uniform(0.05, 0.95))
        out.append((kind, me, W, Zt, V))
    return out


def tall_reference(kind: str, me: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: float,
                   rng: np.random.Generator) -> float:
    """Smallest ||Delta|| independently. With u = Delta v (v scalar), ||Delta|| = ||u|| / |v|,
    v = Me12 W + Me11 u and u = Me21^-1 (c - n) for a noise |n_k| <= V. Additive: closed form
    sqrt(sum max(0, |c_k| - V)^2) / |W|. Me11 = 0: a convex problem in n (one SLSQP run is
    global). General: SLSQP from the best of 3000 random noise vectors and from the projection."""
    nout = Zt.size
    c = Zt - me[1:, nout:] @ W
    if kind == "additive":
        return float(np.sqrt(np.sum(np.maximum(0.0, np.abs(c) - V) ** 2)) / abs(W[0]))
    m11, a = me[0, :nout], complex(me[0, nout:] @ W)
    Minv = np.linalg.inv(me[1:, :nout])

    def proj(n: np.ndarray) -> np.ndarray:
        return n * np.minimum(1.0, V / np.maximum(np.abs(n), 1e-300))

    def ratio(x: np.ndarray) -> float:
        u = Minv @ (c - (x[:nout] + 1j * x[nout:]))
        return float(np.linalg.norm(u) / abs(a + m11 @ u))

    def ratio_grad(x: np.ndarray) -> np.ndarray:
        """d ratio / d (Re n, Im n): ``u = Minv (c - n)``, ratio = |u| / |s|, ``s = a + m11 u``."""
        u = Minv @ (c - (x[:nout] + 1j * x[nout:]))
        s, nu = a + m11 @ u, float(np.linalg.norm(u))
        r = np.conj(u) / (nu * abs(s)) - nu / abs(s) ** 3 * np.conj(s) * m11  # d ratio = Re(r . du)
        q = r @ Minv  # du = -Minv[:, k] per unit Re n_k, -1j Minv[:, k] per unit Im n_k
        return np.concatenate([-q.real, q.imag])

    starts = [proj(c)]
    if kind == "general":
        ns = V * rng.uniform(size=(3000, nout)) ** 0.15 * np.exp(2j * np.pi * rng.uniform(size=(3000, nout)))
        U = (c[None, :] - ns) @ Minv.T
        starts += list(ns[np.argsort(np.linalg.norm(U, axis=1) / np.abs(a + U @ m11))[:3]])
    def ring_grad(x: np.ndarray, k: int) -> np.ndarray:
        g = np.zeros(2 * nout)
        g[k], g[nout + k] = -2.0 * x[k], -2.0 * x[nout + k]
        return g

    # exact gradients (the finite differences SLSQP takes otherwise were three quarters of this test's time)
    cons = [{"type": "ineq", "fun": lambda x, k=k: V**2 - x[k] ** 2 - x[nout + k] ** 2,
             "jac": lambda x, k=k: ring_grad(x, k)} for k in range(nout)]
    best = np.inf
    for n0 in starts:
        res = minimize(ratio, np.concatenate([n0.real, n0.imag]), jac=ratio_grad, method="SLSQP", constraints=cons,
                       options={"ftol": 1e-15, "maxiter": 500})
        n = proj(res.x[:nout] + 1j * res.x[nout:])  # feasible by construction
        best = min(best, ratio(np.concatenate([n.real, n.imag])))
    return best


def test_tall_full_block_per_output_noise_360_cases_no_failure_and_bracketing() -> None:
    cases = tall_cases(0)
    rng = np.random.default_rng(99)
    ref = np.array([tall_reference(*cs, rng) for cs in cases])
    kinds = np.array([cs[0] for cs in cases])
    lo, up = np.empty(len(cases)), np.empty(len(cases))
    status = np.empty(len(cases), dtype=object)
    for nout in (2, 3):  # one call per shape (the per-point driver over many points)
        idx = [i for i, cs in enumerate(cases) if cs[3].size == nout]
        r = mu.required_gamma(np.stack([cases[i][1] for i in idx]), np.stack([cases[i][2] for i in idx]),
                               np.stack([cases[i][3] for i in idx]), np.array([cases[i][4] for i in idx]))
        lo[idx], up[idx], status[idx] = r.gamma_lower, r.gamma_upper, r.status
    failed = int(np.count_nonzero(status != "ok"))
    over = lo / ref - 1
    print(f"\n[tall M22] 360 points: {failed} not ok; certified lower above the reference by at most "
          f"{over.max():.1e}; upper below it by at most {np.max(1 - up / ref):.1e}; max gap "
          f"{np.max((up - lo) / up):.1e}")
    assert failed == 0
    assert np.all(ref > 0) and np.all(np.isfinite(ref))
    # certified lower bound never above a feasible point (soundness), explicit Delta never below
    # the minimum (reference exact for 'additive', converged brute force otherwise)
    assert np.all(lo <= ref * (1 + 1e-9))
    assert np.all(up >= ref * (1 - 1e-7))
    assert np.all(up <= ref * (1 + 1e-6)) and np.all((up - lo) / up < 1e-6)
    assert set(kinds) == {"additive", "m11zero", "general"}


def test_stalled_iterate_scales_are_projected_onto_their_cone() -> None:
    """The D-scales a stalled interior point iterate returns can be slightly negative; the
    S-procedure certifies nothing with a negative scale (the old code then 'certified' a lower
    bound above an explicit Delta and failed the point). Scalar and Hermitian scales."""
    th = project_scales([np.array([-1e-7]), np.array([2.0])], [("full", 1), ("full", 1)])
    assert th[0][0] == 0.0 and th[1][0] == 2.0
    # repeated 2x2: D = [[1, 2], [2, 1]] (eigenvalues 3, -1) -> its PSD part [[1.5, 1.5], [1.5, 1.5]]
    (t,) = project_scales([np.array([1.0, 1.0, 2.0, 0.0])], [("repeated", 2)])
    np.testing.assert_allclose(t, [1.5, 1.5, 1.5, 0.0], atol=1e-14)


# --------------------------------------------------------------------------------------------------
# (6) non-finite data at one point


def test_nan_in_data_marks_that_point_and_solves_the_others() -> None:
    rng = np.random.default_rng(26)
    f = 12
    G = cplx(rng, f) * 1e-7
    W = cplx(rng, f) * 10
    Zt = G * W * (1 + 0.5 * cplx(rng, f))
    V = 0.2 * np.abs(Zt - G * W)
    me = lft.additive_me(G).copy()
    Zt_bad = Zt.copy()
    Zt_bad[3] = np.nan
    me[7, 1, 1] = np.nan + 0j
    good = np.ones(f, dtype=bool)
    good[[3, 7]] = False
    ref = np.maximum(0, np.abs(Zt - G * W) - V) / np.abs(W)  # additive closed form
    r = mu.required_gamma(me, W, Zt_bad, V)  # SISO: the batched path
    assert list(r.status[[3, 7]]) == ["bad_data", "bad_data"] and "not finite" in r.reason[3]
    assert np.all(r.status[good] == "ok") and np.all(np.isnan(r.gamma_upper[~good]))
    np.testing.assert_allclose(r.gamma_lower[good], ref[good], rtol=1e-6)
    # two outputs (the per-point path): NaN in one output of one point
    me2 = lft.additive_me(np.stack([G, 2 * G], 1)[:, :, None]).copy()
    Zt2 = np.stack([Zt, 2 * Zt], 1)
    Zt2[5, 1] = np.nan
    r2 = mu.required_gamma(me2, W, Zt2, V)
    assert r2.status[5] == "bad_data"
    ref2 = np.sqrt(np.maximum(0, np.abs(Zt - G * W) - V) ** 2
                   + np.maximum(0, 2 * np.abs(Zt - G * W) - V) ** 2) / np.abs(W)
    others = np.arange(f) != 5
    assert np.all(r2.status[others] == "ok")
    np.testing.assert_allclose(r2.gamma_lower[others], ref2[others], rtol=1e-6)
    # validation (both modes), detection and the verdict treat it as undecided
    for enclose in ("data", "system"):
        v = validation.validate(me, W, Zt_bad, V, enclose=enclose)
        assert list(v.status[[3, 7]]) == ["bad_data", "bad_data"] and np.all(v.status[good] == "ok")
        assert np.all(np.isnan(v.gamma[~good]))
    det = validation.detect(me, W, Zt_bad, V, ref * 1.01)
    assert list(det.status[[3, 7]]) == ["bad_data", "bad_data"] and not det.fault.any()
    ver = validation.verdict(det.fault, det.status)
    assert ver.verdict == "inconclusive" and ver.n_undecided == 2


# --------------------------------------------------------------------------------------------------
# (7) a solver that panics, and the time limit


class FakePanic(BaseException):
    """Stands in for pyo3_runtime.PanicException (a BaseException, not an Exception)."""


def _record_calls(monkeypatch: pytest.MonkeyPatch, run: Any) -> list[np.ndarray]:
    """The b vectors of every Clarabel call made by ``run()`` (a black-box fingerprint of one
    point's conic problems)."""
    real = clarabel.DefaultSolver
    seen: list[np.ndarray] = []

    def recorder(P: Any, q: Any, A: Any, b: Any, cones: Any, settings: Any) -> Any:
        seen.append(np.array(b, dtype=float))
        return real(P, q, A, b, cones, settings)

    monkeypatch.setattr(clarabel, "DefaultSolver", recorder)
    run()
    monkeypatch.setattr(clarabel, "DefaultSolver", real)
    return seen


def _faulty_solver(monkeypatch: pytest.MonkeyPatch, targets: list[np.ndarray], exc: BaseException | None,
                   sleep: float = 0.0, limits: list[float] | None = None) -> None:
    """Clarabel that raises ``exc`` (or sleeps) on the problems of the target point only."""
    real = clarabel.DefaultSolver

    class Faulty:
        def __init__(self, P: Any, q: Any, A: Any, b: Any, cones: Any, settings: Any) -> None:
            bb = np.array(b, dtype=float)
            self.hit = any(t.shape == bb.shape and np.allclose(t, bb, rtol=1e-9, atol=0) for t in targets)
            if limits is not None:
                limits.append(float(settings.time_limit))
            self.inner = real(P, q, A, b, cones, settings)

        def solve(self) -> Any:
            if self.hit and exc is not None:
                raise exc
            if self.hit:
                time.sleep(sleep)
            return self.inner.solve()

    monkeypatch.setattr(clarabel, "DefaultSolver", Faulty)


@pytest.mark.parametrize("n_out", [1, 2])
def test_solver_panic_fails_that_point_only_with_the_reason(monkeypatch: pytest.MonkeyPatch, n_out: int
                                                            ) -> None:
    rng = np.random.default_rng(27)
    f, k = 8, 5
    G = cplx(rng, f, n_out, 1) * 1e-7
    W = cplx(rng, f) * 10
    Zt = (G[:, :, 0] * W[:, None]) * (1 + 0.5 * cplx(rng, f, n_out))
    V = 0.2 * np.abs(Zt - G[:, :, 0] * W[:, None]).min(1)
    me = lft.additive_me(G)
    clean = mu.required_gamma(me, W, Zt, V)
    assert np.all(clean.status == "ok")
    ref = np.sqrt(np.sum(np.maximum(0, np.abs(Zt - G[:, :, 0] * W[:, None]) - V[:, None]) ** 2, 1)) / np.abs(W)
    np.testing.assert_allclose(clean.gamma_lower, ref, rtol=1e-6)
    target = _record_calls(monkeypatch, lambda: mu.required_gamma(me[k:k + 1], W[k:k + 1], Zt[k:k + 1], V[k]))
    assert target
    _faulty_solver(monkeypatch, target, FakePanic("called `Option::unwrap()` on a `None` value"))
    r = mu.required_gamma(me, W, Zt, V)
    assert r.status[k] == "solver_failed" and np.isnan(r.gamma_lower[k]) and np.isnan(r.gamma_upper[k])
    assert "FakePanic" in r.reason[k] and "unwrap" in r.reason[k]
    others = np.arange(f) != k
    assert np.all(r.status[others] == "ok") and np.all(r.reason[others] == "")
    np.testing.assert_allclose(r.gamma_lower[others], ref[others], rtol=1e-6)
    np.testing.assert_array_equal(r.gamma_upper[others], clean.gamma_upper[others])
    # through validation: the point is 'solver_failed' with the reason, the others validated
    v = validation.validate(me, W, Zt, V, enclose="data")
    assert v.status[k] == "solver_failed" and "FakePanic" in v.reason[k]
    assert np.all(v.status[others] == "ok")
    # KeyboardInterrupt / SystemExit still stop the whole computation
    for stop in (KeyboardInterrupt(), SystemExit(3)):
        _faulty_solver(monkeypatch, target, stop)
        with pytest.raises(type(stop)):
            mu.required_gamma(me, W, Zt, V)


def test_cvxpy_backend_panic_is_caught_per_point(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(28)
    f, k = 5, 2
    G = cplx(rng, f) * 1e-7
    W = cplx(rng, f) * 10
    Zt = G * W * (1 + 0.5 * cplx(rng, f))
    V = 0.2 * np.abs(Zt - G * W)
    me = lft.additive_me(G)
    target = _record_calls(monkeypatch, lambda: mu.required_gamma(me[k:k + 1], W[k:k + 1], Zt[k:k + 1], V[k],
                                                                   backend="cvxpy"))
    _faulty_solver(monkeypatch, target, FakePanic("index out of bounds"))
    r = mu.required_gamma(me, W, Zt, V, backend="cvxpy")
    assert r.status[k] == "solver_failed" and "FakePanic" in r.reason[k]
    others = np.arange(f) != k
    assert np.all(r.status[others] == "ok")
    np.testing.assert_allclose(r.gamma_lower[others], (np.abs(Zt - G * W) - V)[others] / np.abs(W[others]),
                               rtol=1e-6)


def test_time_limit_bounds_each_point(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(29)
    f, k = 6, 1
    G = cplx(rng, f, 2, 1) * 1e-7
    W = cplx(rng, f) * 10
    Zt = (G[:, :, 0] * W[:, None]) * (1 + 0.5 * cplx(rng, f, 2))
    V = 0.2 * np.abs(Zt - G[:, :, 0] * W[:, None]).min(1)
    me = lft.additive_me(G)
    # every Clarabel call gets the point's remaining budget as its time_limit
    limits: list[float] = []
    _faulty_solver(monkeypatch, [], None, limits=limits)
    assert np.all(mu.required_gamma(me, W, Zt, V, time_limit=3.0).status == "ok")
    assert limits and max(limits) <= 3.0 and min(limits) > 0
    limits.clear()
    mu.required_gamma(me, W, Zt, V)
    assert max(limits) <= mu.DEFAULT_TIME_LIMIT == 10.0
    monkeypatch.undo()
    # a point whose solve outlasts its budget fails with the reason; the others are solved
    target = _record_calls(monkeypatch, lambda: mu.required_gamma(me[k:k + 1], W[k:k + 1], Zt[k:k + 1], V[k]))
    _faulty_solver(monkeypatch, target, None, sleep=0.6)
    t0 = time.perf_counter()
    r = mu.required_gamma(me, W, Zt, V, time_limit=0.5)
    assert time.perf_counter() - t0 < 5.0
    assert r.status[k] == "solver_failed" and "time limit" in r.reason[k]
    assert np.all(r.status[np.arange(f) != k] == "ok")
    with pytest.raises(ValueError, match="time_limit"):
        mu.required_gamma(me, W, Zt, V, time_limit=0.0)
