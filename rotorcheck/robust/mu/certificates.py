"""Certificate engines: lower bounds on gamma that hold whatever the solver reported.

The scaled implicit LFT of a stack of points projected onto its kernel (:class:`Forms`), and three
ways to certify on it that every gamma below a bound is invalidated (S-procedure,
``P^*(sum_i d_i (r_i^2 A_i^* A_i - B_i^* B_i)) P < 0``): an exact generalized eigenvalue (one
uncertainty block, no noise block), one SDP (one uncertainty block with its scale fixed to 1, noise
blocks: maximize ``s = gamma^2``) and bisection on a feasibility LMI (several blocks sharing gamma,
repeated scalars: a GEVP). Every bound is recomputed from the solver's projected D-scales by an
eigenvalue computation (:func:`max_s`). Also :func:`implicit_lmi_bound`, the LMI on a user-built
implicit LFT at one frequency.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from rotorcheck.robust.mu.backends import (
    BACKENDS,
    DEFAULT_BACKEND,
    SolverAbort,
    SolveSession,
    herm_basis,
)
from rotorcheck.robust.mu.structure import DEFAULT_TIME_LIMIT, STATUS_FAILED, STATUS_OK, Points

# one block of the LMI: (lmi kind 'full' | 'repeated', size k, A P (f, q, m), B P (f, p, m))
FormBlock = tuple[str, int, np.ndarray, np.ndarray]


def herm(X: np.ndarray) -> np.ndarray:
    """Conjugate transpose of a stack (..., p, q)."""
    return X.conj().swapaxes(-1, -2)


def gram(X: np.ndarray) -> np.ndarray:
    """``X^* X`` of a stack."""
    return herm(X) @ X


def kernel_bases(N: np.ndarray, rtol: float = 1e-11) -> list[tuple[np.ndarray, np.ndarray]]:
    """Orthonormal bases of Ker N for a stack of rows N (f, r, n), by SVD, grouped by kernel
    dimension: a list of (point indices, bases (g, n, m))."""
    f, r, n = N.shape
    if r == 0:
        return [(np.arange(f), np.broadcast_to(np.eye(n, dtype=complex), (f, n, n)).copy())]
    _, sv, Vh = np.linalg.svd(N)
    rank = np.sum(sv > rtol * np.maximum(sv[:, :1], 1e-300), axis=1)
    if f == 1:
        return [(np.zeros(1, dtype=int), herm(Vh[:, int(rank[0]):, :]))]
    out = []
    for rk in np.unique(rank):
        idx = np.flatnonzero(rank == rk)
        out.append((idx, herm(Vh[idx, rk:, :])))
    return out


def max_s(G: np.ndarray, Fu: np.ndarray) -> np.ndarray:
    """Largest s with ``s Fu + G < 0`` (Hermitian stacks, ``Fu >= 0``): the rigorous certificate
    check. -1 where ``G`` itself is not negative definite (no certificate at s = 0)."""
    G = 0.5 * (G + herm(G))
    try:
        Lc = np.linalg.cholesky(-G)
    except np.linalg.LinAlgError:
        if G.shape[0] == 1:
            return np.array([-1.0])
        return np.concatenate([max_s(g[None], fu[None]) for g, fu in zip(G, Fu, strict=True)])
    Li = np.linalg.inv(Lc)  # tiny matrices: plain inverse of the triangular factor
    Y = Li @ Fu @ herm(Li)
    top = np.linalg.eigvalsh(0.5 * (Y + herm(Y)))[:, -1]
    with np.errstate(divide="ignore"):
        return np.where(top <= 0, np.inf, 1.0 / np.where(top <= 0, 1.0, top))


def top_eigvec(Q: np.ndarray) -> np.ndarray:
    """Eigenvectors (f, m) of the largest eigenvalue of a stack of Hermitian matrices."""
    _, U = np.linalg.eigh(0.5 * (Q + herm(Q)))
    return U[:, :, -1]


@dataclass
class Forms:
    """Projected quadratic forms of a stack of points on Ker N (kernel coordinates y, x = P y)."""

    P: np.ndarray  # (f, n, m)
    gamma_blocks: list[FormBlock]  # bounded by gamma (times the block weight)
    fixed_blocks: list[FormBlock]  # radius 1 folded in (the noise blocks)

    @property
    def f(self) -> int:
        return int(self.P.shape[0])

    @property
    def m(self) -> int:
        return int(self.P.shape[2])

    def take(self, idx: np.ndarray | Sequence[int]) -> Forms:
        ix = np.asarray(idx, dtype=int)
        return Forms(self.P[ix], [(kd, k, A[ix], B[ix]) for kd, k, A, B in self.gamma_blocks],
                     [(kd, k, A[ix], B[ix]) for kd, k, A, B in self.fixed_blocks])


@dataclass
class EngineOut:
    """What an engine certified at one point (scaled units)."""

    status: str  # 'ok' | 'unbounded' | 'failed' | 'aborted'
    s_lower: float = 0.0  # verified
    candidates: list[np.ndarray] = field(default_factory=list)  # kernel-space x (scaled coords)
    calls: int = 0
    method: str = ""
    y: np.ndarray | None = None  # kernel coordinates of the worst-case vector (basis P)
    theta: list[float] = field(default_factory=list)  # scales of the fixed (noise) blocks
    inaccurate: bool = False  # the solver did not report success; bounds verified independently
    reason: str = ""  # why the solve was aborted
    seconds: float = 0.0  # wall time of the solve of a stacked pass


# --------------------------------------------------------------------------------------------------
# the scaled implicit LFT of a stack of points


def _u_scales(pts: Points) -> tuple[np.ndarray, np.ndarray]:
    """(sigma (f, n_out), s_u (f, nu)): residual-row and u-column scales."""
    V, c = pts.V, pts.c
    sig = np.maximum(np.abs(c), V[:, None])
    sig_max = np.max(sig, axis=1) if sig.size else np.ones(pts.f)
    fill = np.where(sig_max > 0, sig_max, 1.0)
    sig = np.where(sig > 0, sig, fill[:, None])
    su = np.ones((pts.f, pts.lay.nu))
    for us in pts.lay.u_slices:
        nrm = norm2(pts.M21[:, :, us])
        su[:, us] = np.where(nrm > 0, sig_max / np.where(nrm > 0, nrm, 1.0), 1.0)[:, None]
    return sig, su


def norm2(X: np.ndarray) -> np.ndarray:
    """Spectral norms of a stack (f, p, q) (the vector norm for a single column or row)."""
    if X.shape[2] == 1 or X.shape[1] == 1:
        return np.sqrt(np.sum((X.conj() * X).real, axis=(1, 2)))
    return np.linalg.norm(X, 2, axis=(1, 2))


def _n_noise(pts: Points) -> int:
    """Noise coordinates in x (all points of a stack have V > 0, or all V = 0)."""
    pos = pts.V > 0
    if pts.f and not (np.all(pos) or not np.any(pos)):
        raise ValueError("a stack mixes V > 0 and V = 0")
    return pts.lay.n_out if pts.f and pos[0] else 0


def kernel_rows(pts: Points) -> tuple[np.ndarray, np.ndarray]:
    """The scaled kernel rows N (f, n_out, n) of the implicit LFT in ``x = (u, e, t)`` (residual
    rows scaled by ``max(|c_k|, V)``, u-columns by ``max|c| / ||Me21||``) and the column scaling
    S (f, n) (``x = S x~``)."""
    return _kernel_rows(pts, *_u_scales(pts))


def _column_scaling(su: np.ndarray, n_e: int) -> np.ndarray:
    return np.concatenate([su, np.ones((su.shape[0], n_e + 1))], axis=1)


def _kernel_rows(pts: Points, sig: np.ndarray, su: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lay = pts.lay
    n_out, n_e = lay.n_out, _n_noise(pts)
    n = lay.nu + n_e + 1
    S = _column_scaling(su, n_e)
    N = np.zeros((pts.f, n_out, n), complex)
    N[:, :, : lay.nu] = -pts.M21 * su[:, None, :]
    if n_e:
        N[:, :, lay.nu: lay.nu + n_e] = -pts.V[:, None, None] * np.eye(n_out)
    N[:, :, -1] = pts.c
    return N / sig[:, :, None], S


def scaled_forms(pts: Points, ghat: np.ndarray, basis: np.ndarray | None = None,
                 kappa: np.ndarray | None = None) -> tuple[Forms, np.ndarray]:
    """Scaled implicit LFT on its kernel; returns the forms and the column scaling S (x = S x~).

    ``ghat`` (f,): gamma scale; ``basis`` (f, n, m): kernel bases to use instead of the orthonormal
    ones (a second pass, or from :func:`kernel_bases` for a stack); without it every point must have
    the same kernel dimension (one point always has). ``kappa`` (f, K): scale factors of the noise
    blocks' D-scales (so that the new scales are about 1)."""
    lay = pts.lay
    n_out, n_e = lay.n_out, _n_noise(pts)
    sig, su = _u_scales(pts)
    n = lay.nu + n_e + 1
    if basis is None:
        N, S = _kernel_rows(pts, sig, su)
        groups = kernel_bases(N)
        if len(groups) != 1:
            raise ValueError("points with different kernel dimensions: pass bases per group")
        P = groups[0][1]
    else:
        S = _column_scaling(su, n_e)
        P = basis
    f = pts.f
    # v rows in scaled coordinates: v = M11 S_u u~ + M12 W t
    Arow = np.zeros((f, lay.nv, n), complex)
    Arow[:, :, : lay.nu] = pts.M11 * su[:, None, :]
    Arow[:, :, -1] = pts.M12W
    gamma_blocks: list[FormBlock] = []
    for b, us, vs in zip(lay.blocks, lay.u_slices, lay.v_slices, strict=True):
        s_i = su[:, us][:, 0]
        A = (ghat * b.weight / s_i)[:, None, None] * Arow[:, vs]
        B = np.zeros((b.shape[0], n), complex)
        B[:, us] = np.eye(b.shape[0])
        gamma_blocks.append((b.lmi_kind, b.shape[0], A @ P, B @ P))
    fixed_blocks: list[FormBlock] = []
    if n_e:
        et = np.zeros((1, n), complex)
        et[0, -1] = 1.0
        if pts.noise == "per_output":
            for kk in range(n_out):
                B = np.zeros((1, n), complex)
                B[0, lay.nu + kk] = 1.0
                fixed_blocks.append(("full", 1, et @ P, B @ P))
        else:
            B = np.zeros((n_out, n), complex)
            B[:, lay.nu: lay.nu + n_out] = np.eye(n_out)
            fixed_blocks.append(("full", 1, et @ P, B @ P))
    if kappa is not None:
        rk = np.sqrt(np.asarray(kappa, dtype=float).reshape(f, -1))
        fixed_blocks = [(kd, k, rk[:, j, None, None] * A, rk[:, j, None, None] * B)
                        for j, (kd, k, A, B) in enumerate(fixed_blocks)]
    return Forms(P, gamma_blocks, fixed_blocks), S


def adapted_basis(P0: np.ndarray, x: np.ndarray, nu: int) -> np.ndarray | None:
    """Kernel basis ``[x / |u(x)|, complement]`` of one point (``P0`` (n, m) orthonormal, ``x`` a
    kernel vector in scaled coordinates), for a worst case that is a near-cancellation."""
    nu_out = float(np.linalg.norm(x[:nu]))
    if not np.isfinite(nu_out) or nu_out == 0.0:
        return None
    y = P0.conj().T @ x
    ny = float(np.linalg.norm(y))
    if ny == 0.0:
        return None
    Uc = np.linalg.svd((y / ny).conj()[None, :])[2][1:].conj().T
    return np.concatenate([x[:, None] / nu_out, P0 @ Uc], axis=1)


REAL_KINDS = ("real", "realrep")


def d_kind(kind: str) -> str:
    """The D-scale kind of an LMI block kind: 'full' (scalar d >= 0) or 'repeated' (D >= 0)."""
    return {"real": "full", "realrep": "repeated"}.get(kind, kind)


def block_terms(kind: str, k: int, Ap: np.ndarray, Bp: np.ndarray
                ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Hermitian (f, m, m) terms of one block: returns (A-parts, B-parts) per D-scale basis
    element; the block's contribution is ``sum_l theta_l (r^2 A_l - B_l)``."""
    kind = d_kind(kind)
    if kind == "full":
        return [gram(Ap)], [gram(Bp)]
    As, Bs = [], []
    for H in herm_basis(k):
        As.append(herm(Ap) @ H @ Ap)
        Bs.append(herm(Bp) @ H @ Bp)
    return As, Bs


def g_terms(kind: str, k: int, Ap: np.ndarray, Bp: np.ndarray) -> list[np.ndarray]:
    """G-scale terms (f, m, m) of a real block, one per coordinate of the Hermitian G
    (:func:`herm_basis` order; k = 1: one real g): ``j (B^* H A - A^* H B)``. For ``u = delta v``
    with delta real, ``x^* j(B^* G A - A^* G B) x = j delta (v^* G v - v^* G v) = 0``: the term
    vanishes on the uncertainty set and enters the certificate with a free sign (the D-G scaling
    bound of mixed mu). Empty for complex blocks."""
    if kind not in REAL_KINDS:
        return []
    out = []
    for H in herm_basis(k):
        X = herm(Bp) @ H @ Ap
        out.append(1j * (X - herm(X)))
    return out


# --------------------------------------------------------------------------------------------------
# engines


def engine_eig(fm: Forms) -> list[EngineOut]:
    """One full uncertainty block, no free scales: max s with s Ah - Bh <= 0 is a generalized
    eigenvalue problem, solved exactly (no solver call). One result per point."""
    _, _, Ap, Bp = fm.gamma_blocks[0]
    Ah, Bh = gram(Ap), gram(Bp)
    if fm.m == 1:
        a, b = Ah[:, 0, 0].real.tolist(), Bh[:, 0, 0].real.tolist()
        x = fm.P[:, :, 0]
        return [EngineOut("unbounded", method="eig") if a[i] <= 0
                else EngineOut("ok", b[i] / a[i], [x[i]], method="eig") for i in range(fm.f)]
    out = []
    for i in range(fm.f):
        w, U = sla.eig(Bh[i], Ah[i])
        finite = np.isfinite(w) & (np.abs(w.imag) <= 1e-9 * np.maximum(1.0, np.abs(w.real)))
        if not np.any(finite):
            out.append(EngineOut("unbounded", method="eig"))
            continue
        k = np.flatnonzero(finite)[np.argmin(w.real[finite])]
        out.append(EngineOut("ok", max(float(w.real[k]), 0.0), [fm.P[i] @ U[:, k]], method="eig"))
    return out


def engine_sdp(fm: Forms, session: SolveSession, point_seconds: float | None = None
               ) -> list[EngineOut]:
    """One uncertainty block (scale fixed to 1) plus noise blocks: one SDP per point, maximize s.

    ``point_seconds``: every point's solve under its own budget (an abort gives status 'aborted'
    with the reason); None: the session's current budget (an abort raises)."""
    kind0, k0, Ap, Bp = fm.gamma_blocks[0]
    sig = tuple((kind, k) for kind, k, _, _ in fm.fixed_blocks)
    Fu = gram(Ap)
    F0 = -gram(Bp)
    fixed_terms: list[list[np.ndarray]] = []
    for kind, k, Ak, Bk in fm.fixed_blocks:
        As, Bs = block_terms(kind, k, Ak, Bk)
        fixed_terms.append([a - b for a, b in zip(As, Bs, strict=True)])
    n_noise = len(fixed_terms)
    gt = g_terms(kind0, k0, Ap, Bp)
    if gt:  # a real uncertainty block: its free G-scale (its D-scale stays fixed to 1)
        sig = (*sig, ("free", k0))
        fixed_terms.append(gt)
    lmi = session.lmi("maxs", fm.m, sig, False)
    res = lmi.solve_many(F0, Fu, fixed_terms, session, point_seconds)
    out = [EngineOut("aborted", calls=1, method="sdp", reason=r.reason) if r.status == "aborted"
           else EngineOut("unbounded" if r.status == "unbounded" else "failed", calls=1,
                          method="sdp")
           for r in res]
    idx = np.array([i for i, r in enumerate(res) if r.status in ("optimal", "inaccurate")],
                   dtype=int)
    if idx.size:
        G = F0[idx].copy()
        for b, terms in enumerate(fixed_terms):
            for j, T in enumerate(terms):
                th = np.array([float(res[i].theta[b][j]) for i in idx])
                G = G + th[:, None, None] * T[idx]
        s_cert = max_s(G, Fu[idx])
        s_cert = np.where(s_cert < 0, 0.0, s_cert)  # no strict certificate: the trivial bound
        fin = np.isfinite(s_cert)
        y = top_eigvec(np.where(fin, s_cert, 0.0)[:, None, None] * Fu[idx] + G)
        xy = (fm.P[idx] @ y[:, :, None])[:, :, 0]
        duals = [res[i].dual for i in idx]
        has_dual = [d is not None for d in duals]
        xd = np.zeros_like(xy)
        if any(has_dual):
            jd = np.flatnonzero(has_dual)
            Z = np.stack([d for d in duals if d is not None])
            xd[jd] = (fm.P[idx[jd]] @ top_eigvec(Z)[:, :, None])[:, :, 0]
        one = [len(terms) == 1 for terms in fixed_terms[:n_noise]]
        for j, (i, s_j, fin_j) in enumerate(zip(idx.tolist(), s_cert.tolist(), fin.tolist(),
                                                strict=True)):
            r = res[i]
            cands = ([xy[j]] if fin_j else []) + ([xd[j]] if has_dual[j] else [])
            theta = [float(th[0]) if o else np.nan
                     for th, o in zip(r.theta[:n_noise], one, strict=True)]
            out[i] = EngineOut("ok", s_j, cands, calls=1, method="sdp", y=y[j] if fin_j else None,
                               theta=theta, inaccurate=r.status == "inaccurate")
    for o, r in zip(out, res, strict=True):
        o.seconds = r.seconds
    return out


def _feas_terms(fm: Forms, s: float, fix_first: bool
                ) -> tuple[np.ndarray, list[tuple[str, int]], list[list[np.ndarray]],
                           list[list[np.ndarray]]]:
    """(G_fix, variable-block signature, per-variable-block terms at s, per-variable-block
    A-parts) for the feasibility LMI of one point (``fm`` a stack of one). A real block adds its
    G-scale as a 'free' variable block (zero A-part), also when its D-scale is fixed."""
    m = fm.m
    Gfix = np.zeros((m, m), complex)
    sig: list[tuple[str, int]] = []
    var_terms: list[list[np.ndarray]] = []
    var_a: list[list[np.ndarray]] = []
    zero = np.zeros((m, m), complex)
    g_blocks: list[tuple[int, list[np.ndarray]]] = []
    for idx, (kind, k, Ap, Bp) in enumerate(fm.gamma_blocks):
        gt = g_terms(kind, k, Ap, Bp)
        if gt:
            g_blocks.append((k, [g[0] for g in gt]))
        As, Bs = block_terms(kind, k, Ap, Bp)
        terms = [s * a[0] - b[0] for a, b in zip(As, Bs, strict=True)]
        if fix_first and idx == 0:
            Gfix = terms[0]
            continue
        sig.append((d_kind(kind), k))
        var_terms.append(terms)
        var_a.append([a[0] for a in As])
    for kind, k, Ap, Bp in fm.fixed_blocks:
        As, Bs = block_terms(kind, k, Ap, Bp)
        sig.append((d_kind(kind), k))
        var_terms.append([a[0] - b[0] for a, b in zip(As, Bs, strict=True)])
        var_a.append([zero] * len(As))
    for k, gt0 in g_blocks:
        sig.append(("free", k))
        var_terms.append(gt0)
        var_a.append([zero] * len(gt0))
    return Gfix, sig, var_terms, var_a


def _feasible(fm: Forms, s: float, fix_first: bool, session: SolveSession
              ) -> tuple[str, float, np.ndarray | None, np.ndarray | None]:
    """Certificate at s? Returns (status, verified lambda_max, Q(theta) at s, Fa(theta))."""
    m = fm.m
    Gfix, sig, var_terms, var_a = _feas_terms(fm, s, fix_first)
    res = session.lmi("feas", m, tuple(sig), not fix_first).solve(Gfix, None, var_terms, session)
    if res.status not in ("optimal", "inaccurate"):
        return "failed", np.inf, None, None
    Q = Gfix.copy()
    Fa = np.zeros((m, m), complex)
    if fix_first:
        Fa = gram(fm.gamma_blocks[0][2])[0]
    for th, terms, As in zip(res.theta, var_terms, var_a, strict=True):
        for j, (T, A) in enumerate(zip(terms, As, strict=True)):
            Q = Q + float(th[j]) * T
            Fa = Fa + float(th[j]) * A
    lam = float(np.linalg.eigvalsh(0.5 * (Q + Q.conj().T))[-1])
    return "ok", lam, Q, Fa


def engine_bisection(fm: Forms, session: SolveSession, rtol: float, fix_first: bool
                     ) -> EngineOut:
    """Bisection on s with the feasibility LMI (GEVP for several blocks / repeated scalars), one
    point (``fm`` a stack of one)."""
    P = fm.P[0]
    calls = 0
    # s = 0 must be certified (data outside the noise set); otherwise only the trivial bound
    st, lam, Q, Fa = _feasible(fm, 0.0, fix_first, session)
    calls += 1
    if st != "ok":
        return EngineOut("failed", calls=calls, method="bisection")
    if lam >= 0:
        assert Q is not None
        return EngineOut("ok", 0.0, [P @ top_eigvec(Q[None])[0]], calls, "bisection")
    lo, best = 0.0, (Q, Fa)
    hi = 1.0
    while True:
        st, lam, Q, Fa = _feasible(fm, hi, fix_first, session)
        calls += 1
        if st != "ok":
            return EngineOut("failed", calls=calls, method="bisection")
        if lam >= 0:
            break
        lo, best = hi, (Q, Fa)
        hi *= 4.0
        if hi > 1e30:
            return EngineOut("unbounded", calls=calls, method="bisection")
    # bisection on gamma = sqrt(s)
    while np.sqrt(hi) - np.sqrt(lo) > rtol * np.sqrt(hi):
        mid = (0.5 * (np.sqrt(lo) + np.sqrt(hi))) ** 2
        st, lam, Q, Fa = _feasible(fm, mid, fix_first, session)
        calls += 1
        if st != "ok":
            return EngineOut("failed", calls=calls, method="bisection")
        if lam < 0:
            lo, best = mid, (Q, Fa)
        else:
            hi = mid
    Qb, Fab = best
    assert Qb is not None and Fab is not None
    # the certificate at lo is affine in s for fixed scales: extend it exactly
    s_cert = lo
    ext = float(max_s((Qb - lo * Fab)[None], Fab[None])[0])
    if ext > lo:
        s_cert = ext
    Qs = (Qb - lo * Fab + s_cert * Fab) if np.isfinite(s_cert) else Qb
    return EngineOut("ok", s_cert, [P @ top_eigvec(Qs[None])[0]], calls, "bisection")


# --------------------------------------------------------------------------------------------------
# the LMI on a user-built implicit LFT


@dataclass
class ImplicitBound:
    """Result of :func:`implicit_lmi_bound`: ``gamma_lower`` (every gamma below it is certified
    to admit no nonzero kernel vector), the worst-case kernel vector ``x`` (None if not available)
    and ``status`` ('ok' | 'unbounded' | 'solver_failed')."""

    gamma_lower: float
    x: np.ndarray | None
    status: str
    n_solver_calls: int


def implicit_lmi_bound(N: np.ndarray, A: Sequence[np.ndarray], B: Sequence[np.ndarray],
                       kinds: Sequence[str], gamma_block: Sequence[bool],
                       radius: Sequence[float] | None = None, *, backend: str = DEFAULT_BACKEND,
                       rtol: float = 1e-8, time_limit: float = DEFAULT_TIME_LIMIT) -> ImplicitBound:
    """The LMI on a user-built implicit LFT at ONE frequency (no automatic scaling: pass a
    well-scaled problem).

    ``N`` (rows, n): kernel constraint ``N x = 0``; ``A[i]`` (q_i, n) / ``B[i]`` (p_i, n): input and
    output rows of block i; ``kinds[i]``: 'scalar' | 'full' | 'repeated' | 'real' (a real
    (repeated) scalar: D-G scalings); ``gamma_block[i]``: block
    bounded by ``radius[i] * gamma`` (else by ``radius[i]``, default 1). One gamma block of scalar
    or full kind: one SDP (or an exact eigenvalue without other blocks); otherwise bisection.
    ``time_limit``: seconds for all solver calls; a solver that raises or runs out of time gives
    status 'solver_failed'.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    session = SolveSession(backend)
    N = np.atleast_2d(np.asarray(N, dtype=complex))
    rad = [1.0] * len(A) if radius is None else [float(r) for r in radius]
    ((_, P),) = kernel_bases(N[None])
    if P.shape[2] == 0:
        return ImplicitBound(np.inf, None, "unbounded", 0)
    gam: list[FormBlock] = []
    fix: list[FormBlock] = []
    for Ai, Bi, kd, gb, ri in zip(A, B, kinds, gamma_block, rad, strict=True):
        Ai = np.atleast_2d(np.asarray(Ai, dtype=complex))
        Bi = np.atleast_2d(np.asarray(Bi, dtype=complex))
        if kd == "real":
            lk = "realrep" if Ai.shape[0] > 1 else "real"
        else:
            lk = "repeated" if kd == "repeated" and Ai.shape[0] > 1 else "full"
        (gam if gb else fix).append((lk, Bi.shape[0], ri * Ai @ P, Bi @ P))
    if not gam:
        raise ValueError("at least one block must be scaled by gamma")
    fm = Forms(P, gam, fix)
    single = len(gam) == 1 and gam[0][0] in ("full", "real")
    try:
        with session.point_budget(time_limit):
            if single and not fix and gam[0][0] == "full":
                out = engine_eig(fm)[0]
            elif single:
                out = engine_sdp(fm, session)[0]
            else:
                out = engine_bisection(fm, session, rtol, False)
    except SolverAbort:  # the solver raised (pyo3 panic) or ran out of time
        return ImplicitBound(np.nan, None, STATUS_FAILED, 0)
    if out.status == "unbounded":
        return ImplicitBound(np.inf, None, "unbounded", out.calls)
    if out.status != "ok":
        return ImplicitBound(np.nan, None, STATUS_FAILED, out.calls)
    x = out.candidates[0] if out.candidates else None
    return ImplicitBound(float(np.sqrt(out.s_lower)), x, STATUS_OK, out.calls)
