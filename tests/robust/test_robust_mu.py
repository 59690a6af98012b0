"""The generalized-mu LMI against closed forms (500 SISO cases), brute force (two outputs, two
blocks), polynomial roots (repeated scalar), and its failure / pre-check behaviour."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from robust_helpers import gamma_methodmd_exact
from scipy.optimize import minimize

from rotorcheck.robust import lft, mu


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def siso_cases(seed: int = 2024) -> dict[str, np.ndarray]:
    """500 seeded SISO cases with SI magnitudes (receptances 1e-9..1e-6 m/N, forces 1..100 N)."""
    rng = np.random.default_rng(seed)
    mes, Ws, Zs, Vs, kinds = [], [], [], [], []

    def add(kind: str, n: int, general: bool) -> None:
        G = cplx(rng, n) * 10 ** rng.uniform(-9, -6, n)
        W = cplx(rng, n) * 10 ** rng.uniform(0, 2, n)
        Zt = G * W * (1 + 10 ** rng.uniform(-3, 0, n) * cplx(rng, n))
        me = lft.additive_me(G).copy()
        if general:
            me[:, 0, 0] = cplx(rng, n) * 10 ** rng.uniform(4, 9, n) * rng.uniform(0, 1, n)
            s12 = 10 ** rng.uniform(-3, 3, n)
            me[:, 0, 1] = cplx(rng, n) * s12
            me[:, 1, 0] = cplx(rng, n) / s12
        e = np.abs(Zt - G * W)
        if kind == "zero_noise":
            V = np.zeros(n)
        elif kind == "gamma_zero":
            V = e * rng.uniform(1.0, 3.0, n)
        elif kind == "near_zero":
            V = e * (1 - 10 ** rng.uniform(-6, -2, n))
        elif kind == "unexplainable":
            me[:, 0, 1] = 0.0
            V = e * rng.uniform(0, 0.9, n)
        else:
            V = e * rng.uniform(0, 1, n)
        mes.append(me)
        Ws.append(W)
        Zs.append(Zt)
        Vs.append(V)
        kinds.extend([kind + ("_general" if general else "")] * n)

    add("generic", 120, False)
    add("zero_noise", 40, False)
    add("gamma_zero", 40, False)
    add("near_zero", 60, False)
    add("generic", 120, True)
    add("zero_noise", 30, True)
    add("gamma_zero", 20, True)
    add("near_zero", 50, True)
    add("unexplainable", 20, True)
    return {"me": np.concatenate(mes), "W": np.concatenate(Ws), "Zt": np.concatenate(Zs),
            "V": np.concatenate(Vs), "kind": np.array(kinds)}


@pytest.fixture(scope="module")
def cases() -> dict[str, np.ndarray]:
    c = siso_cases()
    assert c["W"].size == 500
    ref = np.array([gamma_methodmd_exact(c["me"][i], c["W"][i], c["Zt"][i], c["V"][i])
                    for i in range(500)])
    # method.md's formula returns the pole 1/|a| when b = Me12 Me21 W = 0; no gamma explains then
    ref[c["kind"] == "unexplainable_general"] = np.inf
    c["ref"] = ref
    return c


@pytest.fixture(scope="module")
def point_by_point(cases: dict[str, np.ndarray]) -> Callable[[str], list[Any]]:
    """``point_by_point(backend)``: the 500 SISO cases in 500 calls of one point each, made once per backend for
    the tests that check them (against the closed form, against the stacked call)."""
    done: dict[str, list[Any]] = {}

    def calls(backend: str) -> list[Any]:
        if backend not in done:
            done[backend] = [mu.required_gamma(cases["me"][i:i + 1], cases["W"][i:i + 1], cases["Zt"][i:i + 1],
                                               cases["V"][i], backend=backend) for i in range(500)]
        return done[backend]

    return calls


@pytest.mark.parametrize("backend", ["cvxpy", "clarabel"])
def test_lmi_matches_closed_form_on_500_siso_cases(cases: dict[str, np.ndarray], backend: str,
                                                   point_by_point: Callable[[str], list[Any]]) -> None:
    per_point = point_by_point(backend)
    lo = np.array([r.gamma_lower[0] for r in per_point])
    up = np.array([r.gamma_upper[0] for r in per_point])
    st = np.array([r.status[0] for r in per_point])
    ref = cases["ref"]
    unexpl = ~np.isfinite(ref)
    assert np.all(st[unexpl] == "unexplainable")
    assert np.all(np.isinf(lo[unexpl])) and np.all(np.isinf(up[unexpl]))
    assert np.all(st[~unexpl] == "ok"), dict(zip(*np.unique(st, return_counts=True), strict=True))
    zero = ref == 0
    assert zero.sum() >= 60
    assert np.all(np.abs(lo[zero]) <= 1e-12) and np.all(np.abs(up[zero]) <= 1e-12)
    pos = np.isfinite(ref) & ~zero
    err_lo = np.abs(lo[pos] - ref[pos]) / ref[pos]
    err_up = np.abs(up[pos] - ref[pos]) / ref[pos]
    gap = (up[pos] - lo[pos]) / up[pos]
    print(f"\n[{backend}] 500 SISO: max rel err lower {err_lo.max():.2e}, upper {err_up.max():.2e},"
          f" max gap {gap.max():.2e}; near-zero max err "
          f"{np.max(err_lo[np.char.startswith(cases['kind'][pos], 'near')]):.2e}")
    assert err_lo.max() < 1e-6
    assert err_up.max() < 1e-6
    assert np.all(gap >= -1e-12) and gap.max() < 1e-6


def test_vectorized_call_equals_per_point_and_counts_solver_calls(cases: dict[str, np.ndarray]
                                                                  ) -> None:
    sel = np.flatnonzero(np.char.startswith(cases["kind"], "generic"))[:30]
    sel = np.concatenate([sel, np.flatnonzero(cases["kind"] == "gamma_zero")[:5]])
    V = cases["V"][sel]
    r = mu.required_gamma(cases["me"][sel], cases["W"][sel], cases["Zt"][sel], V)
    ref = cases["ref"][sel]
    np.testing.assert_allclose(r.gamma_lower, ref, rtol=1e-6, atol=0)
    assert np.all(r.method[-5:] == "precheck")
    assert 30 <= r.n_solver_calls <= 90  # one SDP per point, rarely a rescaled second pass


def test_large_unit_rescaling_gives_the_same_answer() -> None:
    """Same physical problem in m and in nm (1e9 x): gamma scales exactly, no silent SI error."""
    rng = np.random.default_rng(3)
    G = cplx(rng, 20) * 1e-8
    W = cplx(rng, 20) * 30
    Zt = G * W * (1 + 0.2 * cplx(rng, 20))
    V = 0.5 * np.abs(Zt - G * W)
    a = mu.required_gamma(lft.additive_me(G), W, Zt, V)
    b = mu.required_gamma(lft.additive_me(G * 1e9), W, Zt * 1e9, V * 1e9)
    np.testing.assert_allclose(b.gamma_lower, a.gamma_lower * 1e9, rtol=1e-8)


def _brute_two_output(me: np.ndarray, W: complex, Zt: np.ndarray, V: float, noise: str,
                      rng: np.random.Generator) -> float:
    """min |Delta| over a dense polar grid, refined by SLSQP from the 8 best feasible points."""
    a, m12 = me[0, 0], me[0, 1]
    m21, m22 = me[1:, 0], me[1:, 1]

    def resid(d: complex) -> np.ndarray:
        h = d / (1 - a * d) * m12 * W
        return Zt - m22 * W - m21 * h

    def ok(d: np.ndarray) -> np.ndarray:
        h = d / (1 - a * d) * m12 * W
        r = (Zt - m22 * W)[:, None] - m21[:, None] * h[None, :]
        return np.all(np.abs(r) <= V, 0) if noise == "per_output" else np.linalg.norm(r, axis=0) <= V

    rr = np.linspace(0, 4, 1601)
    th = np.linspace(0, 2 * np.pi, 1441)
    D = (rr[:, None] * np.exp(1j * th[None, :])).ravel()
    feas = ok(D)
    if not feas.any():
        return np.inf
    cand = D[feas][np.argsort(np.abs(D[feas]))[:8]]
    best = float(np.abs(cand[0]))
    for d0 in cand:
        if noise == "per_output":
            cons = [{"type": "ineq", "fun": lambda x, k=k: V**2 - abs(resid(x[0] + 1j * x[1])[k]) ** 2}
                    for k in range(2)]
        else:
            cons = [{"type": "ineq",
                     "fun": lambda x: V**2 - float(np.sum(np.abs(resid(x[0] + 1j * x[1])) ** 2))}]
        res = minimize(lambda x: x[0] ** 2 + x[1] ** 2, [d0.real, d0.imag], method="SLSQP",
                       constraints=cons, options={"ftol": 1e-15, "maxiter": 500})
        d = res.x[0] + 1j * res.x[1]
        r = np.abs(resid(d))
        feasible = (np.all(r <= V * (1 + 1e-9)) if noise == "per_output"
                    else np.linalg.norm(r) <= V * (1 + 1e-9))
        if feasible:
            best = min(best, abs(d))
    return best


@pytest.mark.parametrize("noise", ["per_output", "euclidean"])
def test_two_outputs_tall_kernel_against_brute_force(noise: str) -> None:
    """A tall M22 (two displacement outputs, one scalar uncertainty with Me11 != 0): the kernel
    constraint is real; the LMI bounds bracket a brute-force search over Delta."""
    rng = np.random.default_rng(7)
    f = 12
    me = np.zeros((f, 3, 2), complex)
    me[:, 0, 0] = 0.3 * cplx(rng, f)
    me[:, 0, 1] = cplx(rng, f)
    me[:, 1:, 0] = cplx(rng, f, 2)
    me[:, 1:, 1] = cplx(rng, f, 2)
    W = cplx(rng, f)
    Z = lft.lft_upper(me, 0.5 * cplx(rng, f)[:, None, None])[:, :, 0] * W[:, None]
    Zt = Z + 0.25 * cplx(rng, f, 2)
    V = 0.4
    st = mu.Structure(noise=noise)
    r = mu.required_gamma(me, W, Zt, V, st)
    n_checked = 0
    for i in range(f):
        ref = _brute_two_output(me[i], W[i], Zt[i], V, noise, rng)
        if not np.isfinite(ref) or ref > 3.9:
            assert r.status[i] == "unexplainable" or r.gamma_lower[i] > 3.9 * (1 - 1e-6)
            continue
        n_checked += 1
        if ref == 0:
            assert r.gamma_upper[i] == 0
            continue
        assert r.status[i] == "ok"
        assert r.gamma_lower[i] <= ref * (1 + 1e-7)
        assert r.gamma_upper[i] >= ref * (1 - 1e-7)
        assert abs(r.gamma_lower[i] - ref) / ref < 1e-5
        assert (r.gamma_upper[i] - r.gamma_lower[i]) / r.gamma_upper[i] < 1e-5
    assert n_checked >= 6
    # the second output matters: with the first output only the answer is smaller somewhere
    if noise == "per_output":
        r1 = mu.required_gamma(me[:, :2, :], W, Zt[:, :1], V)
        ok = (r.status == "ok") & (r1.status == "ok")
        assert np.any(r1.gamma_upper[ok] < r.gamma_lower[ok] * (1 - 1e-3))


def test_repeated_scalar_block_against_polynomial_roots() -> None:
    """A parameter entering with rank 2 (delta I_2, Hermitian D-scale, GEVP by bisection), V = 0:
    the data pins delta to the roots of a quadratic; the smallest |root| is the answer."""
    rng = np.random.default_rng(3)
    f, n = 5, 4
    Z0 = cplx(rng, f, n, n) + 3 * np.eye(n)
    L, R = cplx(rng, n, 2), cplx(rng, n, 2)
    b, c = cplx(rng, n, 1), cplx(rng, 1, n)
    me = lft.parametric_me(Z0, L, R, b, c)
    W = cplx(rng, f)
    dtrue = 0.3 * cplx(rng, f)
    Zt = lft.lft_upper(me, dtrue[:, None, None] * np.eye(2))[:, :, 0] * W[:, None]
    r = mu.required_gamma(me, W, Zt, 0.0, mu.Structure.repeated(2))
    assert np.all(r.status == "ok") and np.all(r.method == "bisection")
    for i in range(f):
        T = Zt[i, 0] / W[i]
        pts = np.exp(2j * np.pi * np.arange(8) / 8)
        vals = []
        for d in pts:
            Zd = Z0[i] + d * L @ R.T
            vals.append(np.linalg.det(Zd) * ((c @ np.linalg.solve(Zd, b))[0, 0] - T))
        coef = np.fft.fft(vals) / 8  # polynomial in d, degree <= 2
        assert np.all(np.abs(coef[3:]) < 1e-9 * np.abs(coef[:3]).max())
        ref = np.min(np.abs(np.roots(coef[:3][::-1])))
        assert abs(r.gamma_lower[i] - ref) / ref < 1e-7
        assert abs(r.gamma_upper[i] - ref) / ref < 1e-7


def test_two_scalar_blocks_sharing_gamma_against_brute_force() -> None:
    """Two complex scalar blocks with one gamma (generalized eigenvalue problem, bisection), V = 0:
    brute force over delta_1 (delta_2 then follows from the data, Moebius) with Nelder-Mead."""
    rng = np.random.default_rng(11)
    f = 3
    me = np.zeros((f, 3, 3), complex)
    me[:, :2, :2] = 0.3 * cplx(rng, f, 2, 2)
    me[:, :2, 2] = cplx(rng, f, 2)
    me[:, 2, :2] = cplx(rng, f, 2)
    me[:, 2, 2] = cplx(rng, f)
    W = cplx(rng, f)
    d = 0.4 * cplx(rng, f, 2)
    Zt = np.array([lft.lft_upper(me[i], np.diag(d[i]))[0, 0, 0] * W[i] for i in range(f)])
    st = mu.Structure((mu.Block("scalar"), mu.Block("scalar")))
    r = mu.required_gamma(me, W, Zt, 0.0, st)
    assert np.all(r.status == "ok")
    bs = np.array([0, 1, 1j])
    for i in range(f):
        deltas = np.zeros((3, 2, 2), complex)
        deltas[:, 1, 1] = bs

        def second(a: complex, i: int = i, deltas: np.ndarray = deltas) -> complex:
            deltas[:, 0, 0] = a  # the output at (a, b) for the three b in one call (a Moebius map of b)
            zs = lft.lft_upper(me[i], deltas)[:, 0, 0] * W[i]
            A = np.stack([bs, np.ones(3), -zs * bs, -zs], 1)
            p, q, rr, s = np.linalg.svd(A)[2][-1].conj()
            return -(q - Zt[i] * s) / (p - Zt[i] * rr)

        def obj(x: np.ndarray, second=second) -> float:  # type: ignore[no-untyped-def]
            a = x[0] + 1j * x[1]
            return max(abs(a), abs(second(a)))

        best = np.inf
        for x0 in np.linspace(-1.2, 1.2, 7):
            for y0 in np.linspace(-1.2, 1.2, 7):
                res = minimize(obj, [x0, y0], method="Nelder-Mead",
                               options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 4000})
                best = min(best, res.fun)
        assert abs(r.gamma_lower[i] - best) / best < 1e-6
        assert r.gamma_lower[i] <= best * (1 + 1e-9)
        assert r.gamma_upper[i] >= best * (1 - 1e-9)
        assert (r.gamma_upper[i] - r.gamma_lower[i]) / r.gamma_upper[i] < 1e-3


def test_prechecks_and_failure_injection() -> None:
    rng = np.random.default_rng(4)
    f = 8
    G = cplx(rng, f) * 1e-7
    W = cplx(rng, f) * 10
    Zt = G * W * (1 + 0.5 * cplx(rng, f))
    V = np.full(f, 0.3 * float(np.median(np.abs(Zt - G * W))))
    inside = np.abs(Zt - G * W) <= V
    me = lft.additive_me(G)
    base = mu.required_gamma(me, W, Zt, V)
    assert np.all(base.gamma_upper[inside] == 0) and np.all(base.method[inside] == "precheck")
    assert base.n_solver_calls >= np.count_nonzero(~inside)
    # injected failure at one point only
    k = int(np.flatnonzero(~inside)[0])
    inj = mu.required_gamma(me, W, Zt, V, fail_at=[k])
    assert inj.status[k] == "solver_failed"
    assert np.isnan(inj.gamma_lower[k]) and np.isnan(inj.gamma_upper[k])
    others = np.arange(f) != k
    assert np.all(inj.status[others] == base.status[others])
    np.testing.assert_array_equal(inj.gamma_upper[others], base.gamma_upper[others])
    with mu.inject_solver_failure([2]):
        ctx = mu.required_gamma(me, W, Zt, V)
    assert ctx.status[2] == "solver_failed" and np.isnan(ctx.gamma_upper[2])
    assert np.all(ctx.status[np.arange(f) != 2] != "solver_failed")
    assert np.all(mu.required_gamma(me, W, Zt, V).status != "solver_failed")  # hook cleared
    # the uncertainty cannot reach the output: flagged, never a number
    me0 = me.copy()
    me0[:, 1, 0] = 0.0
    r0 = mu.required_gamma(me0, W, Zt, V)
    assert np.all(r0.status[~inside] == "unexplainable")
    assert np.all(np.isinf(r0.gamma_upper[~inside]))
    assert np.all(r0.gamma_upper[inside] == 0)


def test_bisection_variant_and_backends_agree() -> None:
    rng = np.random.default_rng(5)
    f = 6
    G = cplx(rng, f) * 1e-6
    W = cplx(rng, f) * 5
    Zt = G * W * (1 + 0.3 * cplx(rng, f))
    V = 0.4 * np.abs(Zt - G * W)
    me = lft.additive_me(G)
    a = mu.required_gamma(me, W, Zt, V, backend="cvxpy")
    b = mu.required_gamma(me, W, Zt, V, backend="clarabel")
    c = mu.required_gamma_bisection(me, W, Zt, V)
    ref = np.maximum(0, (np.abs(Zt - G * W) - V) / np.abs(W))
    for r in (a, b, c):
        assert np.all(r.status == "ok")
        np.testing.assert_allclose(r.gamma_lower, ref, rtol=1e-6)
        np.testing.assert_allclose(r.gamma_upper, ref, rtol=1e-6)
    assert c.n_solver_calls > 10 * a.n_solver_calls


def test_implicit_lmi_bound_on_a_hand_built_lft() -> None:
    """x = (u, e, t): u = Delta (W t), residual (Zt - G W) t - u - V e = 0, |e| <= |t|."""
    G, W, Zt, V = 1.0 + 0.5j, 2.0 - 1.0j, 4.0 + 1.0j, 0.7
    N = np.array([[-1.0, -V, Zt - G * W]])
    A = [np.array([[0, 0, W]]), np.array([[0, 0, 1.0]])]
    B = [np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]])]
    for backend in ("cvxpy", "clarabel"):
        res = mu.implicit_lmi_bound(N, A, B, ["scalar", "scalar"], [True, False],
                                     backend=backend)
        ref = (abs(Zt - G * W) - V) / abs(W)
        assert res.status == "ok" and res.n_solver_calls == 1
        assert abs(res.gamma_lower - ref) / ref < 1e-7
        u, e, _ = res.x / res.x[2]
        # the raw worst-case direction (not polished): accurate to about sqrt(solver tolerance)
        assert abs(abs(u) / abs(W) - ref) / ref < 1e-4 and abs(abs(e) - 1) < 1e-4


@pytest.mark.parametrize("backend", ["cvxpy", "clarabel"])
def test_stacked_call_matches_closed_form_and_point_by_point_calls(
        cases: dict[str, np.ndarray], backend: str, point_by_point: Callable[[str], list[Any]]) -> None:
    """All 500 SISO cases in ONE call (the first SDP pass of all points evaluated as one stack,
    then the per-point driver) against 500 calls of one point each: same tolerances against the
    closed form, same statuses, methods and solver calls, bounds equal to rounding of the solver's
    iterates."""
    args = (cases["me"], cases["W"], cases["Zt"], cases["V"])
    r = mu.required_gamma(*args, backend=backend)
    per_point = point_by_point(backend)
    p_status = np.array([q.status[0] for q in per_point])
    p_method = np.array([q.method[0] for q in per_point])
    p_lower = np.array([q.gamma_lower[0] for q in per_point])
    p_upper = np.array([q.gamma_upper[0] for q in per_point])
    ref = cases["ref"]
    unexpl = ~np.isfinite(ref)
    assert np.all(r.status[unexpl] == "unexplainable") and np.all(np.isinf(r.gamma_lower[unexpl]))
    assert np.all(r.status[~unexpl] == "ok")
    np.testing.assert_array_equal(r.status, p_status)
    np.testing.assert_array_equal(r.method, p_method)
    assert r.n_solver_calls == sum(q.n_solver_calls for q in per_point)
    zero = ref == 0
    assert np.all(r.gamma_lower[zero] == 0) and np.all(r.gamma_upper[zero] == 0)
    pos = np.isfinite(ref) & ~zero
    for g in (r.gamma_lower, r.gamma_upper):
        assert np.max(np.abs(g[pos] - ref[pos]) / ref[pos]) < 1e-6
    gap = (r.gamma_upper[pos] - r.gamma_lower[pos]) / r.gamma_upper[pos]
    assert np.all(gap >= -1e-12) and gap.max() < 1e-6
    # certified lower bound never above the truth, verified Delta never below (away from the
    # near-cancellation cases, whose accuracy floor is set by the rounding of the data)
    far = pos & ~np.char.startswith(cases["kind"], "near")
    assert np.all(r.gamma_lower[far] <= ref[far] * (1 + 1e-9))
    assert np.all(r.gamma_upper[far] >= ref[far] * (1 - 1e-9))
    for a, b in ((r.gamma_lower, p_lower), (r.gamma_upper, p_upper)):
        assert np.max(np.abs(a[pos] - b[pos]) / ref[pos]) < 1e-7
    # the explicit Deltas reproduce the data within the noise bound
    for i in np.flatnonzero(pos):
        d = complex(r.delta[i][0][0, 0])
        me = cases["me"][i]
        z = me[1, 1] * cases["W"][i] + me[1, 0] * d / (1 - me[0, 0] * d) * me[0, 1] * cases["W"][i]
        assert abs(cases["Zt"][i] - z) <= cases["V"][i] * (1 + 1e-9) + 1e-12 * abs(cases["Zt"][i])
        assert abs(d) <= r.gamma_upper[i] * (1 + 1e-12)  # upper = max(|Delta|, lower)


def test_default_backend_is_clarabel_and_matches_cvxpy() -> None:
    rng = np.random.default_rng(8)
    f = 15
    G = cplx(rng, f) * 1e-6
    W = cplx(rng, f) * 5
    Zt = G * W * (1 + 0.3 * cplx(rng, f))
    V = 0.3 * np.abs(Zt - G * W)
    me = lft.additive_me(G)
    assert mu.DEFAULT_BACKEND == "clarabel"
    a = mu.required_gamma(me, W, Zt, V)
    b = mu.required_gamma(me, W, Zt, V, backend="cvxpy")
    np.testing.assert_array_equal(a.status, b.status)
    assert a.n_solver_calls == b.n_solver_calls
    np.testing.assert_allclose(a.gamma_lower, b.gamma_lower, rtol=1e-8)
    np.testing.assert_allclose(a.gamma_upper, b.gamma_upper, rtol=1e-8)
