"""The small-gain test of a box of real parameters at many frequency points at once (the bound the per-point
certificate, :mod:`rotorcheck.robust.real_box`, and the joint severity interval, :mod:`rotorcheck.robust.severity`,
both branch and bound with).

The prediction of the data is anchored at the measured healthy FRF ``T_h``:
``T(theta, gamma) = gamma T_h G(w, theta) / G(w, 0)`` with ``gamma`` a real gain factor in its own
range (sensor and actuator calibration enter exactly as a factor). A point is explained by ``theta`` when
some ``gamma`` in its range gives::

    |T_new - T(theta, gamma)| <= z sqrt(var_new + |gamma G(theta) / G(0)|^2 var_h + a^2)
                                 + tolerance + relative_error |T_h| |gamma G(theta) / G(0) - 1|

(``z`` the per-point quantile, ``var_*`` the variances of both sweeps' mean FRFs, ``a`` the model's own
error at that point, m/N, carried like a variance as in :mod:`rotorcheck.robust.joint`; ``tolerance`` and
``relative_error`` a deterministic bound on the model's error of the prediction).

Bound. On a sub-box (centre ``theta_c``, half-widths ``h``) the parameters enter as
``Z_c + U Delta V^T`` with ``Delta = diag(delta_i I_{r_i})``, ``delta_i`` real in ``[-1, 1]``
(``A_i = U_i V_i^T`` of rank ``r_i``, scaled by ``h_i s_i``), so ``G`` is an upper LFT of the real
block structure and, by the small-gain theorem, ``|G(theta) - G(theta_c)| <= |x| |y| / (1 - ||N||)``
for every theta in the sub-box when ``||N|| < 1`` (``x = c^T Z_c^-1 U``, ``y = V^T Z_c^-1 b``,
``N = V^T Z_c^-1 U``, after a diagonal scaling that commutes with Delta). A sub-box is excluded at a point
when even that bound leaves the data outside the allowance there (:func:`examine_points`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.affine import AffineModel, StiffnessStack


@dataclass(frozen=True)
class Points:
    """The frequency points a box is tested at, as arrays (m,): frequency ``w`` rad/s, the model's receptance
    at the parameters' zero ``g0`` (m/N), new and healthy FRFs (m/N) and their variances (m^2/N^2), the
    quantile ``z``, the variance-like allowance ``a2`` (m^2/N^2), the gain range, the deterministic
    ``tolerance`` (m/N) and ``relative_error`` of the prediction (module docstring); ``b``, ``c`` (m, n)
    each point's force input and displacement output."""

    w: np.ndarray
    g0: np.ndarray
    t_new: np.ndarray
    t_healthy: np.ndarray
    var_new: np.ndarray
    var_healthy: np.ndarray
    z: float
    a2: np.ndarray
    g_lo: float
    g_hi: float
    tolerance: np.ndarray
    relative_error: np.ndarray
    b: np.ndarray
    c: np.ndarray

    @property
    def size(self) -> int:
        return int(self.w.size)

    def touched(self, blocks: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        """Per DOF set of ``blocks``, (m,) bool: the point's input or output has an entry there (kept once made)."""
        key = tuple(int(d[0]) for d in blocks)
        cache: dict[tuple[int, ...], tuple[np.ndarray, ...]] = self.__dict__.setdefault("_touched", {})
        if key not in cache:
            on = (self.b != 0) | (self.c != 0)
            cache[key] = tuple(np.any(on[:, d], axis=1) for d in blocks)
        return cache[key]

    def on_blocks(self, blocks: tuple[np.ndarray, ...]) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...]:
        """Per DOF set of ``blocks``: ``(rows, b, c)``, the points whose input or output has an entry there (an index
        array) and their inputs and outputs on those DOFs, (k, n_d) complex each (kept once made)."""
        key = tuple(int(d[0]) for d in blocks)
        cache: dict[tuple[int, ...], tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...]] = (
            self.__dict__.setdefault("_on_blocks", {}))
        if key not in cache:
            out = []
            for d, hit in zip(blocks, self.touched(blocks)):
                rows = np.flatnonzero(hit)
                out.append((rows, self.b[np.ix_(rows, d)].astype(complex), self.c[np.ix_(rows, d)].astype(complex)))
            cache[key] = tuple(out)
        return cache[key]

    def take(self, idx: np.ndarray) -> Points:
        """The points ``idx`` (an index array) only."""
        def t(x: np.ndarray) -> np.ndarray:
            return np.asarray(x)[idx]

        return Points(t(self.w), t(self.g0), t(self.t_new), t(self.t_healthy), t(self.var_new), t(self.var_healthy),
                      self.z, t(self.a2), self.g_lo, self.g_hi, t(self.tolerance), t(self.relative_error), t(self.b),
                      t(self.c))


@dataclass(frozen=True)
class _Group:
    """The factor columns ``cols`` (r_g,) that lie on block ``block`` of the model (its DOFs ``dofs``): ``U`` there
    (n_g, r_g) complex and ``Vt`` = ``V^T`` there (r_g, n_g)."""

    block: int
    dofs: np.ndarray
    cols: np.ndarray
    U: np.ndarray
    Vt: np.ndarray


@dataclass(frozen=True)
class BoxFactors:
    """A model's parameter factors stacked: ``U`` (n, r), ``V`` (n, r), each column's parameter and kind, and the
    columns grouped by the block of the model they lie on (:attr:`AffineModel.blocks`: ``V^T Z^-1 U`` is block
    diagonal in the groups)."""

    U: np.ndarray
    V: np.ndarray
    param: np.ndarray  # (r,) int
    kind: np.ndarray  # (r,) str
    groups: tuple[_Group, ...] = ()

    @functools.cached_property
    def starts(self) -> np.ndarray:
        """The first column of each parameter's block (its columns are adjacent)."""
        return np.flatnonzero(np.r_[True, self.param[1:] != self.param[:-1]]) if self.param.size else self.param

    @classmethod
    def of(cls, model: AffineModel) -> BoxFactors:
        us, vs, prm, kind = [], [], [], []
        for i, terms in enumerate(model.factors):
            for k, u, v in terms:
                us.append(u)
                vs.append(v)
                prm += [i] * u.shape[1]
                kind += [k] * u.shape[1]
        n = model.K.shape[0]
        U = np.hstack(us) if us else np.zeros((n, 0))
        V = np.hstack(vs) if vs else np.zeros((n, 0))
        # each column lies on one block (AffineModel factors block by block): the block of its support
        where = np.full(n, -1)
        for i, d in enumerate(model.blocks):
            where[d] = i
        first = np.argmax(U != 0, axis=0)
        groups = []
        for i, d in enumerate(model.blocks):
            cols = np.flatnonzero(where[first] == i)
            if cols.size:
                groups.append(_Group(i, d, cols, U[np.ix_(d, cols)].astype(complex), V[np.ix_(d, cols)].T.copy()))
        return cls(U, V, np.array(prm, dtype=int), np.array(kind), tuple(groups))


def _s_of(kind: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(m, r) the factor s(w) of each column: 1 (K), j w (D), -w^2 (M)."""
    out = np.ones((w.size, kind.size), dtype=complex)
    out[:, kind == "D"] = 1j * w[:, None]
    out[:, kind == "M"] = -(w**2)[:, None]
    return out


def halve(centre: np.ndarray, half: np.ndarray, share: np.ndarray, fallback: np.ndarray
          ) -> tuple[int, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """A box (``centre``, ``half`` (p,)) halved along the parameter with the largest share of the bound (``share``
    (p,), :func:`examine_points`; ``fallback`` (p,) ranks the parameters when no share is positive):
    ``(that parameter, the halves' half-widths, (the lower half's centre, the upper half's))``."""
    weight = np.where(half > 0, np.nan_to_num(share), 0.0)
    i = int(np.argmax(weight)) if np.any(weight > 0) else int(np.argmax(fallback))
    h1 = half.copy()
    h1[i] /= 2.0
    lower, upper = centre.copy(), centre.copy()
    lower[i] -= h1[i]
    upper[i] += h1[i]
    return i, h1, (lower, upper)


#: points whose small-gain norm is computed together, most promising first (:func:`examine_points`)
BATCH = 4


def examine_points(model: AffineModel, fac: BoxFactors, pts: Points, centre: np.ndarray, half: np.ndarray,
                   each: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every point at once, for the box ``centre``, ``half`` (p,) (or (m, p) one box per point): ``(explained
    at the centre (m,), margin of the exclusion test (m,) (> 0: excluded; -inf where explained or
    unbounded), each parameter's share of the bound (m, p), the centre's best gain (m,))`` (module docstring).

    One box for every point (``each`` False, the joint severity interval): when no margin is positive, the
    margin is exact (Frobenius norm for the small-gain condition, the spectral norm where that is >= 0.5) at
    the largest (the point that decides) and at every point that could be the largest, and -inf (a lower
    bound) elsewhere; otherwise one positive margin (a lower bound) is enough: the box is excluded. Each
    point on its own (``each`` True, the per-point certificate): every point's margin, the spectral norm
    where the Frobenius norm is >= 0.5 and the spectral norm could make the margin positive.

    The cost: the centre's receptance and the bound's numerator (``x = c^T Z^-1 U``, ``y = V^T Z^-1 b``)
    take two right-hand sides per point (one solve of ``[b, c]`` when Z is symmetric); the small-gain
    norm needs ``Z^-1 U`` (r right-hand sides) and is computed only at the points whose margin with a
    zero norm (an upper bound: the margin falls as the norm grows) could still beat the best found. Where Z is
    block diagonal (:attr:`AffineModel.blocks`, e.g. the two bending planes of a rotor that does not spin), the
    small-gain matrix is too, and only the blocks a point's input or output touches enter its bound (the others
    do not reach its receptance): a smaller norm, and half the solves for a single-plane pair."""
    w = pts.w
    m = w.size
    p = len(model.parameters)
    half = np.broadcast_to(np.asarray(half, dtype=float), (m, p))
    Z = model.stiffness_stack(w, centre)
    r = fac.U.shape[1]
    g_c, vU, uV = _centre_terms(model, fac, pts, Z)
    scale = _s_of(fac.kind, w) * half[:, fac.param]  # (m, r)
    x = vU * scale  # c^T Z^-1 U diag(scale)
    y = uV  # V^T Z^-1 b
    # one positive scale per parameter block (commutes with delta_i I): the blocks' norms summed over their
    # columns (a parameter's columns are adjacent, fac.starts)
    share = np.zeros((m, p))
    sc = np.ones((m, r))
    if r:
        nx = np.sqrt(np.add.reduceat(x.real**2 + x.imag**2, fac.starts, axis=1))  # (m, blocks)
        ny = np.sqrt(np.add.reduceat(y.real**2 + y.imag**2, fac.starts, axis=1))
        share[:, fac.param[fac.starts]] = nx * ny
        good = (nx > 0) & (ny > 0)
        sc = np.repeat(np.where(good, np.sqrt(np.where(good, nx, 1.0) / np.where(good, ny, 1.0)), 1.0),
                       np.diff(np.r_[fac.starts, r]), axis=1)
    xs, ys = x / sc, y * sc
    rho, gm, resid, allow = _best_gain(pts, g_c)
    ok = resid <= allow
    with np.errstate(divide="ignore", invalid="ignore"):
        gain_change = np.maximum(np.abs(pts.g_lo * rho - 1.0), np.abs(pts.g_hi * rho - 1.0))
        xy = np.linalg.norm(xs, axis=1) * np.linalg.norm(ys, axis=1)

        def margin_of(nrm: np.ndarray, at: np.ndarray | slice = slice(None)) -> np.ndarray:
            """The exclusion margin at the points ``at`` for the norm bounds ``nrm`` (falls as nrm grows)."""
            rad = np.where(nrm < 1.0, xy[at] / (1.0 - nrm), np.inf)
            eps = rad / np.abs(pts.g0[at])
            low = resid[at] - pts.g_hi * np.abs(pts.t_healthy[at]) * eps
            change = gain_change[at] + pts.g_hi * eps
            extra = pts.tolerance[at] + pts.relative_error[at] * np.abs(pts.t_healthy[at]) * change
            up = pts.z * np.sqrt(pts.var_new[at] + (pts.g_hi * (np.abs(rho[at]) + eps)) ** 2 * pts.var_healthy[at]
                                 + pts.a2[at]) + extra
            return np.where(ok[at] | ~np.isfinite(rad), -np.inf, low - up)

        # a zero norm bounds every point's margin from above (the margin falls as the norm grows): the norm only
        # where that bound beats the best margin found, the most promising points first; a positive margin
        # (the box excluded) ends the search
        upper = margin_of(np.zeros(m))
        touched = pts.touched(model.blocks)
        upper = np.where(np.isnan(upper), np.inf, upper)
        order = np.argsort(-upper, kind="stable")
        order = order[upper[order] > -np.inf]
        margin = np.full(m, -np.inf)
        best = -np.inf
        batches = ([order] if order.size else []) if each else [order[k:k + BATCH] for k in range(0, order.size, BATCH)]
        for at in batches:
            if not each:
                at = at[upper[at] > best]
                if not at.size:
                    break
            # N_s = diag(sc) V^T Z^-1 U diag(scale / sc) at these points, block diagonal in the column groups (each
            # on one block of Z, whose inverse is block diagonal too); x and y vanish on a group whose block neither
            # the point's input nor its output touches, so that the group's block of N_s does not enter the bound:
            # per point, the groups it touches (per group: V^T on Re and Im side by side)
            frob2 = np.zeros(at.size)
            ns = []
            for g in fac.groups:
                sel = np.flatnonzero(touched[g.block][at])  # positions in at
                if not sel.size:
                    continue
                ag = at[sel]
                Q = np.linalg.solve(Z.parts[g.block][ag], np.broadcast_to(g.U, (sel.size, *g.U.shape)))
                Q *= (scale[ag][:, g.cols] / sc[ag][:, g.cols])[:, None, :]  # (k, n_g, r_g)
                N = (g.Vt @ Q.view(float)).view(complex) * sc[ag][:, g.cols, None]
                frob2[sel] += np.einsum("kij,kij->k", N.view(float), N.view(float))
                ns.append((g, sel, N, Q))
            frob = np.sqrt(frob2)
            here = margin_of(frob, at)
            top = float(np.nanmax(here)) if np.any(~np.isnan(here)) else -np.inf
            # where the Frobenius norm costs much (>= 0.5) and a lower bound of the spectral norm (the largest
            # column or row) leaves room above the best, the exact spectral norm: the largest of the groups'
            big = np.flatnonzero(frob >= 0.5)
            if each:
                big = big[~(here[big] > 0.0)]  # a point already excluded needs no sharper norm
            if big.size and (each or top <= 0.0):
                low_n = np.zeros(at.size)
                for _, sel, N, _ in ns:
                    low_n[sel] = np.maximum(low_n[sel], np.maximum(np.linalg.norm(N, axis=1).max(axis=1),
                                                                   np.linalg.norm(N, axis=2).max(axis=1)))
                big = big[margin_of(low_n[big], at[big]) > (0.0 if each else max(best, top))]
            if big.size and (each or top <= 0.0):
                lam = np.zeros(at.size)
                in_big = np.zeros(at.size, dtype=bool)
                in_big[big] = True
                for g, sel, N, Q in ns:
                    keep = in_big[sel]
                    if not np.any(keep):
                        continue
                    if g.cols.size > g.dofs.size:
                        # N_s = P Q, P = diag(sc) V^T (r_g, n_g): with P = Q_p R, ||N_s|| = ||R Q||, an n_g x n_g
                        # Hermitian eigenvalue problem instead of r_g x r_g (r > n with E and speed)
                        R = np.linalg.qr(sc[at[sel[keep]]][:, g.cols, None] * g.Vt[None], mode="r")
                        C = R @ Q[keep]
                    else:
                        C = N[keep]
                    pos = sel[keep]
                    lam[pos] = np.maximum(lam[pos], np.linalg.eigvalsh(C @ np.conj(np.swapaxes(C, 1, 2)))[:, -1])
                nrm = np.minimum(frob[big], np.sqrt(np.maximum(lam[big], 0.0)) * (1.0 + 1e-12))
                here[big] = margin_of(nrm, at[big])
            margin[at] = here
            if np.any(~np.isnan(here)):
                best = max(best, float(np.nanmax(here)))
            if best > 0.0 and not each:
                break
    return ok, margin, share, gm


def _centre_terms(model: AffineModel, fac: BoxFactors, pts: Points, Z: StiffnessStack
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(c^T Z^-1 b (m,), c^T Z^-1 U (m, r), V^T Z^-1 b (m, r))`` at each point, block by block of ``Z``: per block,
    the points whose input or output touches it (:meth:`Points.on_blocks`), one solve of ``[b, c]`` there (two,
    ``Z`` and ``Z^T``, when ``Z`` is not symmetric); the three sums gathered per block (Z^-1 is block diagonal)."""
    m, r = pts.size, fac.U.shape[1]
    g = np.zeros(m, dtype=complex)
    vU = np.zeros((m, r), dtype=complex)
    uV = np.zeros((m, r), dtype=complex)
    for d, z_all, (rows, b, c) in zip(Z.blocks, Z.parts, pts.on_blocks(Z.blocks)):
        if not rows.size:
            continue
        z = z_all if rows.size == m else z_all[rows]
        if model.symmetric:
            X = np.linalg.solve(z, np.stack([b, c], axis=2))
            u, v = X[:, :, 0], X[:, :, 1]
        else:
            u = np.linalg.solve(z, b[:, :, None])[:, :, 0]
            v = np.linalg.solve(np.swapaxes(z, 1, 2), c[:, :, None])[:, :, 0]
        g[rows] += np.sum(c * u, axis=1)
        vU[rows] += v @ fac.U[d]
        uV[rows] += u @ fac.V[d]
    return g, vU, uV


def point_receptances(model: AffineModel, pts: Points, theta: np.ndarray) -> np.ndarray:
    """(m,) each point's receptance ``c^T Z(w, theta)^-1 b`` (m/N), one batched solve."""
    Z = model.stiffness_stack(pts.w, theta)
    return np.sum(pts.c * Z.solve(pts.b[:, :, None])[:, :, 0], axis=1)


def _best_gain(pts: Points, g: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(rho, gain, residual, allowance)`` (m,) each when the model's receptance at the points is ``g`` (m,) m/N:
    ``rho = g / g0``, the gain in its range closest to explaining ``T_new`` by ``gain T_h rho``, the residual
    ``|T_new - gain T_h rho|`` and the allowance it is held to (m/N; module docstring)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = g / pts.g0
        pred = pts.t_healthy * rho
        den = np.abs(pred) ** 2
        gm = np.clip(np.where(den > 0, (pts.t_new * np.conj(pred)).real / np.where(den > 0, den, 1.0), 1.0),
                     pts.g_lo, pts.g_hi)
        extra = pts.tolerance + pts.relative_error * np.abs(pts.t_healthy) * np.abs(gm * rho - 1.0)
        allow = pts.z * np.sqrt(pts.var_new + np.abs(gm * rho) ** 2 * pts.var_healthy + pts.a2) + extra
        return rho, gm, np.abs(pts.t_new - gm * pred), allow


def _ratios_of(pts: Points, g: np.ndarray) -> np.ndarray:
    """(m,) each point's residual over its allowance when the model's receptance there is ``g`` (m,) m/N
    (best gain per point clipped to its range)."""
    _, _, resid, allow = _best_gain(pts, g)
    with np.errstate(divide="ignore", invalid="ignore"):
        return resid / allow


def point_ratios(model: AffineModel, pts: Points, theta: np.ndarray) -> np.ndarray:
    """(m,) each point's residual over its allowance at ``theta`` (exact; best gain per point clipped to
    its range): every ratio <= 1 makes ``theta`` a witness."""
    return _ratios_of(pts, point_receptances(model, pts, theta))


def ratio_jacobian(model: AffineModel, fac: BoxFactors, pts: Points, theta: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``(ratios (m,), their derivatives by theta (m, p))`` at ``theta``: the receptance's derivative exact,
    ``dG/dtheta_i = -sum s(w) (Z^-T c)^T U_i V_i^T Z^-1 b`` from one solve, the ratio's by G (an elementwise
    function) by forward differences in G's real and imaginary parts (relative step 1e-7)."""
    Z = model.stiffness_stack(pts.w, theta)
    u, v = (x[:, :, 0] for x in model.solve_both(Z, pts.b[:, :, None], pts.c[:, :, None]))
    g = np.sum(pts.c * u, axis=1)
    cols = -(v @ fac.U) * (u @ fac.V) * _s_of(fac.kind, pts.w)  # (m, r)
    dg = np.zeros((pts.size, len(model.parameters)), dtype=complex)
    np.add.at(dg.T, fac.param, cols.T)
    r0 = _ratios_of(pts, g)
    step = 1e-7 * np.maximum(np.abs(g), 1e-300)
    d_re = (_ratios_of(pts, g + step) - r0) / step
    d_im = (_ratios_of(pts, g + 1j * step) - r0) / step
    return r0, d_re[:, None] * dg.real + d_im[:, None] * dg.imag
