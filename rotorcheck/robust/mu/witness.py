"""The explicit Delta that verifies the upper bound.

From a kernel vector of the certificate to a structured Delta (:func:`deltas_from_x`), a
Gauss-Newton polish until ``F_u(Me, Delta) W`` -- evaluated directly, not through the LMI --
reproduces the data within the noise bound (:func:`polish`), an SQP refinement where a gap to the
certificate is left (:func:`refine`), and the choice among the candidates (:func:`upper_from`).
A real block's Delta is real (real fit, polish and refinement in real unknowns); a real parameter
that is the only block gets its exact smallest Delta (:func:`exact_single_real`, the start of :func:`upper_from` via
:func:`start_witness`).
Stacked over points (leading axis); a Delta is a list over the blocks of arrays (f, p_i, q_i).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from rotorcheck.robust.mu.backends import SolveSession
from rotorcheck.robust.mu.certificates import herm
from rotorcheck.robust.mu.structure import Layout, Points

Deltas = list[np.ndarray]  # per block: (f, p_i, q_i)

_EPS = float(np.finfo(float).eps)
# an explicit Delta within this relative distance of the certificate closes the gap
CLOSE_RTOL = 1e-7
# candidates inside the noise set up to this relative slack are polished into it (exact real witness)
_SLACK = 1e-6
# blocks that are a scalar times the identity (one parameter each)
_SCALAR_KINDS = ("scalar", "repeated", "real")


def noise_ok(r: np.ndarray, V: np.ndarray, noise: str, scale: np.ndarray, rtol: float = 0.0,
             atol: float = 8 * _EPS) -> np.ndarray:
    """Residuals r (f, n_out) inside the noise set, up to floating-point rounding of their
    evaluation (``atol`` times the residual scale); (f,) bool."""
    if noise == "per_output":
        return np.all(np.abs(r) <= (V * (1 + rtol))[:, None] + atol * scale, axis=1)
    return np.linalg.norm(r, axis=1) <= V * (1 + rtol) + atol * np.max(scale, axis=1)


def project_noise(r: np.ndarray, V: np.ndarray, noise: str) -> np.ndarray:
    """Residuals moved just inside the noise set (f, n_out)."""
    shrink = 1 - 2 * _EPS
    Vs = (V * shrink)[:, None]
    if noise == "per_output":
        a = np.abs(r)
        return r * np.where(a > Vs, Vs / np.where(a > 0, a, 1), 1.0)
    nr = np.linalg.norm(r, axis=1, keepdims=True)
    return np.where(nr <= Vs, r, r * (Vs / np.where(nr > 0, nr, 1.0)))


def delta_matrix(lay: Layout, deltas: Deltas) -> np.ndarray:
    """The block-diagonal Delta (f, nu, nv)."""
    if len(deltas) == 1:
        return deltas[0]
    f = deltas[0].shape[0]
    D = np.zeros((f, lay.nu, lay.nv), complex)
    for d, us, vs in zip(deltas, lay.u_slices, lay.v_slices, strict=True):
        D[:, us, vs] = d
    return D


def _solve(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``solve(A, B)`` of a stack; (X, ok) with ok False (X NaN) where A is singular."""
    try:
        return np.linalg.solve(A, B), np.ones(A.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        X = np.full(B.shape, np.nan + 0j)
        ok = np.zeros(A.shape[0], dtype=bool)
        for i in range(A.shape[0]):
            try:
                X[i] = np.linalg.solve(A[i], B[i])
                ok[i] = True
            except np.linalg.LinAlgError:
                pass
        return X, ok


def evaluate(pts: Points, D: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(r, v, L, ok) for full Delta matrices D (f, nu, nv): ``r = Zt - F_u(Me, D) W`` evaluated as
    ``c - Me21 D v``, v the Delta input, ``L = Me21 (I - D Me11)^-1``; ok False where singular."""
    lay = pts.lay
    if lay.nu == 1 and lay.nv == 1:  # a scalar Delta channel: the solves are divisions
        d, a = D[:, 0, 0], pts.M11[:, 0, 0]
        den = 1 - a * d
        ok = den != 0
        with np.errstate(divide="ignore", invalid="ignore"):
            v1 = pts.M12W / np.where(ok, den, np.nan)[:, None]
            L1 = pts.M21 / np.where(ok, den, np.nan)[:, None, None]
        return pts.c - pts.M21[:, :, 0] * (d * v1[:, 0])[:, None], v1, L1, ok
    v, ok1 = _solve(np.eye(lay.nv) - pts.M11 @ D, pts.M12W[:, :, None])
    Lt, ok2 = _solve((np.eye(lay.nu) - D @ pts.M11).swapaxes(-1, -2), pts.M21.swapaxes(-1, -2))
    r = pts.c - (pts.M21 @ (D @ v))[:, :, 0]
    return r, v[:, :, 0], Lt.swapaxes(-1, -2), ok1 & ok2


def gamma_of(lay: Layout, deltas: Deltas) -> np.ndarray:
    """Size of each point's Delta in units of gamma: ``max_i ||Delta_i|| / w_i`` (f,)."""
    g = np.zeros(deltas[0].shape[0]) if deltas else np.zeros(0)
    for b, d in zip(lay.blocks, deltas, strict=True):
        nrm = np.abs(d[:, 0, 0]) if b.kind in _SCALAR_KINDS else np.linalg.norm(
            d, 2, axis=(1, 2))
        g = np.maximum(g, nrm / b.weight)
    return g


def deltas_from_x(pts: Points, x: np.ndarray) -> tuple[Deltas, np.ndarray]:
    """Structured Deltas from (unscaled) kernel vectors x = (u, e, t) (f, n); (deltas, valid)."""
    lay = pts.lay
    t = x[:, -1]
    valid = np.isfinite(t) & ~(np.abs(t) <= 1e-13 * np.linalg.norm(x, axis=1))
    u = x[:, : lay.nu] / np.where(valid, t, 1.0)[:, None]
    v = (pts.M11 @ u[:, :, None])[:, :, 0] + pts.M12W
    out = []
    for b, us, vs in zip(lay.blocks, lay.u_slices, lay.v_slices, strict=True):
        ui, vi = u[:, us], v[:, vs]
        nv2 = np.sum(vi.conj() * vi, axis=1).real
        zero = nv2 == 0.0
        valid &= ~(zero & (np.linalg.norm(ui, axis=1) > 0))
        den = np.where(zero, 1.0, nv2)
        if b.kind in _SCALAR_KINDS:
            delta = np.where(zero, 0.0, np.sum(vi.conj() * ui, axis=1) / den)
            if b.is_real:  # the real least-squares fit of u = delta v
                delta = delta.real + 0j
            d = delta[:, None, None] * np.eye(b.shape[0], dtype=complex)
        else:
            d = ui[:, :, None] * vi.conj()[:, None, :] / den[:, None, None]
            d[zero] = 0.0
        out.append(d)
    for d in out:  # a later block can invalidate a point
        d[~valid] = 0.0
    return out, valid


def _lstsq(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Minimum-norm least-squares solutions of a stack (g, M, N) x = (g, M), singular values below
    ``eps max(M, N)`` of the largest treated as zero (as ``numpy.linalg.lstsq(rcond=None)``)."""
    if A.shape[1] == 1:  # one row a: x = a^* b / |a|^2 (0 where a = 0)
        a = A[:, 0, :]
        n2 = np.sum((a.conj() * a).real, axis=1)
        pos = n2 > 0
        return np.where(pos, b[:, 0] / np.where(pos, n2, 1.0), 0.0)[:, None] * a.conj()
    U, s, Vh = np.linalg.svd(A, full_matrices=False)
    keep = s > _EPS * max(A.shape[1], A.shape[2]) * s[:, :1]
    sinv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    y = sinv * (herm(U) @ b[:, :, None])[:, :, 0]
    return (herm(Vh) @ y[:, :, None])[:, :, 0]


@np.errstate(over="ignore", divide="ignore", invalid="ignore")  # diverging candidates are rejected by evaluate
def polish(pts: Points, deltas: Deltas, live: np.ndarray, iters: int = 8
           ) -> tuple[Deltas, np.ndarray]:
    """Gauss-Newton on the Delta parameters of the ``live`` points until the residual lies in the
    noise set; (deltas, done) with done True where it does."""
    lay = pts.lay
    deltas = [d.copy() for d in deltas]
    live = live.copy()
    done = np.zeros(pts.f, dtype=bool)
    for _ in range(iters + 1):
        ix = np.flatnonzero(live)
        if ix.size == 0:
            break
        whole = ix.size == pts.f
        sub = pts if whole else pts.take(ix)
        V = sub.V
        r, v, L, ok = evaluate(sub, delta_matrix(lay, deltas if whole else [d[ix] for d in deltas]))
        fin = ok & np.all(np.isfinite(r), axis=1)
        good = fin & noise_ok(r, V, sub.noise, sub.scale)
        live[ix[~fin | good]] = False
        done[ix[good]] = True
        step_here = fin & ~good
        if not np.any(step_here):
            continue
        ix, r, v, L, V = ix[step_here], r[step_here], v[step_here], L[step_here], V[step_here]
        dz = r - project_noise(r, V, sub.noise)
        cols, where = [], []
        for bi, (b, us, vs) in enumerate(zip(lay.blocks, lay.u_slices, lay.v_slices,
                                             strict=True)):
            Lb, vb = L[:, :, us], v[:, vs]
            if b.kind in _SCALAR_KINDS:
                cols.append((Lb @ vb[:, :, None])[:, :, 0])
                where.append((bi, -1, -1))
            else:
                for a in range(b.shape[0]):
                    for c in range(b.shape[1]):
                        cols.append(Lb[:, :, a] * vb[:, c, None])
                        where.append((bi, a, c))
        J = np.stack(cols, axis=2)
        n_par = J.shape[2]
        step = np.zeros((ix.size, n_par), complex)
        zero = V == 0
        # the imaginary part of a real block's parameter is not free
        cplx = np.array([not lay.blocks[bi].is_real for bi, _, _ in where], dtype=bool)
        real_any = not bool(np.all(cplx))
        if np.any(zero) and not real_any:
            step[zero] = _lstsq(J[zero], dz[zero])  # r must vanish: complex equations
        elif np.any(zero):  # the same equations in real unknowns
            Jz, dzz = J[zero], dz[zero]
            Ar0 = np.concatenate([np.concatenate([Jz.real, -Jz.imag[:, :, cplx]], axis=2),
                                  np.concatenate([Jz.imag, Jz.real[:, :, cplx]], axis=2)], axis=1)
            xr0 = _lstsq(Ar0, np.concatenate([dzz.real, dzz.imag], axis=1))
            st0 = xr0[:, :n_par].astype(complex)
            st0[:, cplx] += 1j * xr0[:, n_par:]
            step[zero] = st0
        pos = ~zero
        if np.any(pos):
            # |r_k| <= V is one REAL constraint per output (per_output) or one in total
            # (euclidean): linearize d|r| = -Re(conj(r^) J dtheta) on the active ones and take
            # the minimum-norm real step (inactive rows are zero rows)
            rp, dzp, Jp, Vp = r[pos], dz[pos], J[pos], V[pos]
            if sub.noise == "per_output":
                ar = np.abs(rp)
                act = ar > (Vp * (1 - 1e-9))[:, None]
                w = np.where(act, rp.conj() / np.where(act, ar, 1.0), 0.0)
                a_rows = w[:, :, None] * Jp
                rhs = np.where(act, ar - np.abs(rp - dzp), 0.0)
            else:
                nr = np.linalg.norm(rp, axis=1)
                a_rows = (rp.conj() / nr[:, None])[:, None, :] @ Jp
                rhs = (nr - np.linalg.norm(rp - dzp, axis=1))[:, None]
            Ar = np.concatenate([a_rows.real, -a_rows.imag[:, :, cplx]], axis=2)
            xr = _lstsq(Ar, rhs)
            stp = xr[:, :n_par].astype(complex)
            stp[:, cplx] += 1j * xr[:, n_par:]
            step[pos] = stp
        for col, (bi, a, c) in enumerate(where):
            if a < 0:
                deltas[bi][ix] = deltas[bi][ix] + step[:, col, None, None] * np.eye(
                    deltas[bi].shape[1])
            else:
                deltas[bi][ix, a, c] += step[:, col]
    return deltas, done


def refine(pts: Points, deltas: Deltas) -> Deltas | None:
    """Local SQP on the block values of one point (scalar and repeated blocks only): minimize the
    largest ``|delta_i| / w_i`` keeping the residual in the noise set, from a verified start. Used
    to tighten gamma_upper where the kernel-vector construction left a gap (bisection, GEVP)."""
    lay = pts.lay
    if any(b.kind == "full" and b.shape != (1, 1) for b in lay.blocks):
        return None
    w = np.array([b.weight for b in lay.blocks])
    th0 = np.array([d[0, 0, 0] for d in deltas])
    g0 = float(gamma_of(lay, deltas)[0])
    if not np.isfinite(g0) or g0 == 0:
        return None
    nb = th0.size
    V = float(pts.V[0])
    sc = float(np.max(pts.scale[0])) if V == 0 else V
    # unknowns: the real parts, the imaginary parts of the complex blocks only, the bound t
    ci = np.array([i for i, b in enumerate(lay.blocks) if not b.is_real], dtype=int)
    ni = ci.size
    eyes = [np.eye(b.shape[0], dtype=complex)[None] for b in lay.blocks]

    def parts(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        im = np.zeros(nb)
        im[ci] = x[nb: nb + ni]
        return x[:nb], im

    def mats(x: np.ndarray) -> Deltas:
        re, im = parts(x)
        th = g0 * (re + 1j * im)
        return [t * e for t, e in zip(th, eyes, strict=True)]

    def size2(x: np.ndarray) -> np.ndarray:
        re, im = parts(x)
        return re**2 + im**2

    def resid(x: np.ndarray) -> np.ndarray:
        r, _, _, ok = evaluate(pts, delta_matrix(lay, mats(x)))
        return r[0] / sc if ok[0] else np.full(lay.n_out, 1e3 + 0j)

    cons: list[dict[str, object]] = [
        {"type": "ineq", "fun": lambda x: x[-1] * w**2 - size2(x)}]
    if V == 0:
        cons.append({"type": "eq",
                     "fun": lambda x: np.concatenate([resid(x).real, resid(x).imag])})
    elif pts.noise == "per_output":
        cons.append({"type": "ineq", "fun": lambda x: 1.0 - np.abs(resid(x)) ** 2})
    else:
        cons.append({"type": "ineq", "fun": lambda x: 1.0 - float(np.sum(np.abs(resid(x)) ** 2))})
    x0 = np.concatenate([th0.real / g0, th0.imag[ci] / g0, [1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = minimize(lambda x: x[-1], x0, method="SLSQP", constraints=cons,
                       options={"ftol": 1e-15, "maxiter": 200})
    if not np.all(np.isfinite(res.x)):
        return None
    d1, done = polish(pts, mats(res.x), np.ones(1, dtype=bool))
    if not done[0] or gamma_of(lay, d1)[0] >= g0:
        return None
    return d1


@dataclass
class Witness:
    """The best verified explicit Delta per point: its size ``upper`` (f,) (inf where none),
    the Deltas (valid where ``have``)."""

    upper: np.ndarray
    deltas: Deltas
    have: np.ndarray

    @classmethod
    def empty(cls, lay: Layout, f: int) -> Witness:
        return cls(np.full(f, np.inf), [np.zeros((f, *b.shape), complex) for b in lay.blocks],
                   np.zeros(f, dtype=bool))

    @classmethod
    def of_point(cls, lay: Layout, upper: float, best: Deltas | None) -> Witness:
        w = cls.empty(lay, 1)
        w.upper[0] = upper
        if best is not None:
            w.deltas = [d.copy() for d in best]
            w.have[0] = True
        return w

    def point(self, i: int) -> tuple[float, Deltas | None]:
        """(upper, Deltas as a stack of one or None) of point i."""
        best = [d[i: i + 1].copy() for d in self.deltas] if self.have[i] else None
        return float(self.upper[i]), best


def upper_from(pts: Points, cands: Sequence[tuple[np.ndarray, np.ndarray]], lower: np.ndarray,
               start: Witness) -> Witness:
    """Smallest verified explicit Delta among kernel-vector candidates ``(x (f, n), available
    (f,))``, in order of trust (the eigenvector of the certificate first, then the dual); a point
    stops once within :data:`CLOSE_RTOL` of its ``lower``."""
    upper = start.upper.copy()
    deltas = [d.copy() for d in start.deltas]
    have = start.have.copy()
    for x, avail in cands:
        ix = np.flatnonzero(avail & ~(upper <= lower * (1 + CLOSE_RTOL)))
        if ix.size == 0:
            continue
        sub = pts.take(ix)
        d0, valid = deltas_from_x(sub, x[ix])
        d1, ok = polish(sub, d0, valid)
        g = gamma_of(pts.lay, d1)
        better = ok & (g < upper[ix])
        jb = ix[better]
        upper[jb] = g[better]
        for d, dn in zip(deltas, d1, strict=True):
            d[jb] = dn[better]
        have[jb] = True
    return Witness(upper, deltas, have)


def refine_gap(pts: Points, lower: float, upper: float, best: Deltas | None,
               session: SolveSession) -> tuple[float, Deltas | None]:
    """The SQP refinement of one point's Delta when a gap above :data:`CLOSE_RTOL` is left."""
    if best is not None and upper > lower * (1 + CLOSE_RTOL):
        t_ref = time.perf_counter()
        d2 = refine(pts, best)
        session.add_time("refine", time.perf_counter() - t_ref)
        if d2 is not None:
            best, upper = d2, float(gamma_of(pts.lay, d2)[0])
    return upper, best


def explicit_delta(pts: Points, cands: Sequence[np.ndarray], lower: float, upper: float,
                   best: Deltas | None, session: SolveSession) -> tuple[float, Deltas | None]:
    """One point (``pts`` a stack of one): :func:`upper_from` over the candidates ``cands``
    (vectors (n,)), then :func:`refine_gap`."""
    w = upper_from(pts, [(x[None], np.ones(1, dtype=bool)) for x in cands], np.array([lower]),
                   Witness.of_point(pts.lay, upper, best))
    upper, best = w.point(0)
    return refine_gap(pts, lower, upper, best, session)


# --------------------------------------------------------------------------------------------------
# a real parameter alone: the exact explicit Delta


def _poly_coeffs(pts: Points, i: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Ascending complex coefficients of ``d(delta) = det(I - delta M11)`` (k + 1,) and of
    ``n_j(delta) = d(delta) r_j(delta)`` (n_out, k + 1) at point i (one block, k x k)."""
    M11, m12w, M21, c = pts.M11[i], pts.M12W[i], pts.M21[i], pts.c[i]
    if k == 1:
        a = M11[0, 0]
        d = np.array([1.0, -a])
        n = np.stack([c, -(c * a + M21[:, 0] * m12w[0])], axis=1)
        return d, n
    N = k + 1
    nrm = float(np.linalg.norm(M11, 2))
    rho = 1.0 / nrm if nrm > 0 else 1.0
    z = rho * np.exp(2j * np.pi * np.arange(N) / N)
    Ik = np.eye(k)
    A = Ik[None] - z[:, None, None] * M11[None]
    dv = np.linalg.det(A)
    v = np.linalg.solve(A, np.broadcast_to(m12w, (N, k))[:, :, None])[:, :, 0]
    r = c[None, :] - z[:, None] * (v @ M21.T)
    nv = dv[:, None] * r
    scale = rho ** -np.arange(N)
    d = np.fft.fft(dv) / N * scale
    n = (np.fft.fft(nv, axis=0) / N * scale[:, None]).T
    return d, n


def _real_roots(p: np.ndarray) -> np.ndarray:
    """Real roots of a real polynomial with ascending coefficients p (near-real ones included)."""
    p = np.real(p)
    big = np.max(np.abs(p)) if p.size else 0.0
    if big == 0:
        return np.zeros(0)
    nz = np.flatnonzero(np.abs(p) > 1e-14 * big)
    p = p[: nz[-1] + 1]
    if p.size < 2:
        return np.zeros(0)
    rts = np.roots(p[::-1])
    keep = np.abs(rts.imag) <= 1e-6 * np.maximum(np.abs(rts), 1e-300)
    return rts.real[keep]


def _residual(pts: Points, i: int, k: int, delta: np.ndarray) -> np.ndarray:
    """Residuals (g, n_out) of point i at real deltas (g,) (NaN at a pole)."""
    A = np.eye(k)[None] - delta[:, None, None] * pts.M11[i][None]
    with np.errstate(all="ignore"):
        try:
            v = np.linalg.solve(A, np.broadcast_to(pts.M12W[i], (delta.size, k))[:, :, None])
        except np.linalg.LinAlgError:
            v = np.full((delta.size, k, 1), np.nan + 0j)
        return pts.c[i][None, :] - delta[:, None] * (v[:, :, 0] @ pts.M21[i].T)


def _inside(r: np.ndarray, V: float, noise: str, slack: float) -> np.ndarray:
    if noise == "per_output":
        return np.all(np.abs(r) <= V * (1 + slack), axis=1)
    return np.linalg.norm(r, axis=1) <= V * (1 + slack)


def exact_single_real(pts: Points) -> Witness:
    """The smallest real delta that explains each point's data (one real block, the only one),
    verified by evaluating ``F_u(Me, delta) W`` directly; an empty witness (upper inf) where none
    is found (no real delta explains the data, or rounding beyond the polish)."""
    lay = pts.lay
    wit = Witness.empty(lay, pts.f)
    if len(lay.blocks) != 1 or not lay.blocks[0].is_real:
        return wit
    k = lay.blocks[0].shape[0]
    for i in range(pts.f):
        V = float(pts.V[i])
        d, n = _poly_coeffs(pts, i, k)
        dd = np.real(np.convolve(d, d.conj()))
        if pts.noise == "per_output":
            polys = [np.real(np.convolve(nj, nj.conj())) - V**2 * dd for nj in n]
        else:
            nn = np.sum([np.convolve(nj, nj.conj()) for nj in n], axis=0)
            polys = [np.real(nn) - V**2 * dd]
        cand = np.concatenate([np.zeros(1), *[_real_roots(p) for p in polys]])
        cand = cand[np.argsort(np.abs(cand))]
        ok = _inside(_residual(pts, i, k, cand), V, pts.noise, _SLACK)
        cand = cand[ok][:4]
        if cand.size == 0:
            continue
        sub = pts.take(np.full(cand.size, i))
        d0 = [cand[:, None, None] * np.eye(k, dtype=complex)[None]]
        d1, done = polish(sub, d0, np.ones(cand.size, dtype=bool))
        if not np.any(done):
            continue
        g = np.where(done, gamma_of(lay, d1), np.inf)
        j = int(np.argmin(g))
        wit.upper[i] = g[j]
        wit.deltas[0][i] = d1[0][j]
        wit.have[i] = True
    return wit


def start_witness(pts: Points) -> Witness:
    """The explicit Delta to start from: :func:`exact_single_real` when the only block is real,
    else none (an empty witness)."""
    if len(pts.lay.blocks) == 1 and pts.lay.blocks[0].is_real:
        return exact_single_real(pts)
    return Witness.empty(pts.lay, pts.f)
