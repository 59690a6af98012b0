"""A certified interval of one real parameter (a severity) that every frequency point must share.

The per-point certificate of :mod:`rotorcheck.robust.real_box` asks, point by point, whether *some*
parameter values in the box explain the data there, each point free to choose its own. Here the values
are the same at every point (one shaft, one sweep), which is far sharper: per point, a benign parameter
at a range end explains almost any change near a resonance; jointly it must explain all of them.

The severity's range is cut into slices. For each slice, a branch and bound over the other parameters
(benign, real) proves the slice *excluded* when every sub-box is excluded by at least one point (the
small-gain bound of :func:`rotorcheck.robust.real_box._examine`, batched here in :func:`examine_points`),
or finds a *witness* (a parameter value that explains every point, evaluated exactly), or runs out of its
budget ("open": not excluded, kept). Each end of the interval is found from outside in: the outermost slice
not excluded is halved until ``tol`` wide, then searched for a witness. The interval is certified (no
parameter value outside it explains every point); with witnesses at both ends it is also attained
within ``tol``. When every slice is excluded, the hypothesis is excluded and the points that excluded
sub-boxes are named (the test of that: at those points no severity and benign value in the box explain
the data).
"""

from __future__ import annotations

import functools
import heapq
import itertools
from collections import Counter
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.real_box import AffineModel

#: how the severity interval is made (report.json)
SEVERITY_RULE = ("one severity and one set of benign parameter values (real, in their ranges) and gain for every point "
                 "jointly; a box of them is excluded when at one point of one channel pair |T_new - gain T_h G/G0| "
                 "exceeds z sqrt(var_new + |gain G/G0|^2 var_h) + tolerance + eps |T_h| |gain G/G0 - 1| for all its "
                 "members (small-gain bound; z Sidak over the points used, complex Gaussian noise with the variances "
                 "as known; tolerance and eps the model's error bounds); the certified interval holds every severity "
                 "not excluded (branch and bound per slice, outermost slices halved); a candidate element is "
                 "excluded when every one of its slices is excluded.")


#: points tried first on every box (the ones that excluded boxes most often)
EARLY = 6


@dataclass(frozen=True)
class SeverityInterval:
    """What :func:`severity_interval` certifies about one hypothesis."""

    status: str  # "excluded" | "consistent"
    lower: float  # certified: no value below explains every point jointly (nan when excluded)
    upper: float
    witness_interval: tuple[float, float]  # values at the ends that do explain every point (nan: none found)
    excluding: tuple[int, ...]  # points that excluded sub-boxes, most often first
    boxes: int  # sub-boxes examined
    witnessed: bool  # both ends hold a witness within tol (else the interval may be wider than the set)
    excluded_slices: tuple[tuple[float, float], ...] = ()  # the slices of the severity proved excluded


@dataclass(frozen=True)
class Points:
    """The points of :func:`severity_interval` as arrays (m,): frequency ``w`` rad/s, the model's
    receptance at the parameters' zero ``g0``, new and healthy FRFs and their variances, the quantile
    ``z``, the variance-like allowance ``a2``, the gain range, the deterministic ``tolerance`` (m/N) and
    ``relative_error`` of the prediction (see :class:`rotorcheck.robust.real_box._Point`); ``b``, ``c``
    (m, n) each point's force input and displacement output."""

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
class _Factors:
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
    def of(cls, model: AffineModel) -> _Factors:
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


#: points whose small-gain norm is computed together, most promising first (:func:`examine_points`)
BATCH = 4


def examine_points(model: AffineModel, fac: _Factors, pts: Points, centre: np.ndarray, half: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every point at once, for the box ``centre``, ``half`` (p,) (or (m, p) one box per point): ``(explained
    at the centre (m,), margin of the exclusion test (m,) (> 0: excluded; -inf where explained or
    unbounded), each parameter's share of the bound (m, p))`` -- the batched form of
    :func:`rotorcheck.robust.real_box._examine` (the same bounds). When no margin is positive, the margin is
    exact (Frobenius norm for the small-gain condition, the spectral norm where that is >= 0.5) at the
    largest (the point that decides) and at every point that could be the largest, and -inf (a lower
    bound) elsewhere; otherwise one positive margin (a lower bound) is enough: the box is excluded.

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
    u, v = (x[:, :, 0] for x in model.solve_both(Z, pts.b[:, :, None], pts.c[:, :, None]))
    g_c = np.sum(pts.c * u, axis=1)
    scale = _s_of(fac.kind, w) * half[:, fac.param]  # (m, r)
    x = (v @ fac.U) * scale  # c^T Z^-1 U diag(scale)
    y = u @ fac.V  # V^T Z^-1 b
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
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = g_c / pts.g0
        pred = pts.t_healthy * rho
        den = np.abs(pred) ** 2
        gm = np.where(den > 0, (pts.t_new * np.conj(pred)).real / np.where(den > 0, den, 1.0), 1.0)
        gm = np.clip(gm, pts.g_lo, pts.g_hi)
        resid = np.abs(pts.t_new - gm * pred)
        extra = pts.tolerance + pts.relative_error * np.abs(pts.t_healthy) * np.abs(gm * rho - 1.0)
        ok = resid <= pts.z * np.sqrt(pts.var_new + np.abs(gm * rho) ** 2 * pts.var_healthy + pts.a2) + extra
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
        for start in range(0, order.size, BATCH):
            at = order[start:start + BATCH]
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
            if big.size and top <= 0.0:
                low_n = np.zeros(at.size)
                for _, sel, N, _ in ns:
                    low_n[sel] = np.maximum(low_n[sel], np.maximum(np.linalg.norm(N, axis=1).max(axis=1),
                                                                   np.linalg.norm(N, axis=2).max(axis=1)))
                big = big[margin_of(low_n[big], at[big]) > max(best, top)]
            if big.size and top <= 0.0:
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
            if best > 0.0:
                break
    return ok, margin, share


def point_receptances(model: AffineModel, pts: Points, theta: np.ndarray) -> np.ndarray:
    """(m,) each point's receptance ``c^T Z(w, theta)^-1 b`` (m/N), one batched solve."""
    Z = model.stiffness_stack(pts.w, theta)
    return np.sum(pts.c * Z.solve(pts.b[:, :, None])[:, :, 0], axis=1)


def _ratios_of(pts: Points, g: np.ndarray) -> np.ndarray:
    """(m,) each point's residual over its allowance when the model's receptance there is ``g`` (m,) m/N
    (best gain per point clipped to its range)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = g / pts.g0
        pred = pts.t_healthy * rho
        den = np.abs(pred) ** 2
        gm = np.clip(np.where(den > 0, (pts.t_new * np.conj(pred)).real / np.where(den > 0, den, 1.0), 1.0),
                     pts.g_lo, pts.g_hi)
        allow = (pts.z * np.sqrt(pts.var_new + np.abs(gm * rho) ** 2 * pts.var_healthy + pts.a2) + pts.tolerance
                 + pts.relative_error * np.abs(pts.t_healthy) * np.abs(gm * rho - 1.0))
        return np.abs(pts.t_new - gm * pred) / allow


def point_ratios(model: AffineModel, pts: Points, theta: np.ndarray) -> np.ndarray:
    """(m,) each point's residual over its allowance at ``theta`` (exact; best gain per point clipped to
    its range): every ratio <= 1 makes ``theta`` a witness."""
    return _ratios_of(pts, point_receptances(model, pts, theta))


def ratio_jacobian(model: AffineModel, fac: _Factors, pts: Points, theta: np.ndarray
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


def _witness(model: AffineModel, fac: _Factors, pts: Points, lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    """Parameter values in ``[lo, hi]`` explaining every point (every ratio <= 1): the box's centre, else a
    bounded least squares of the ratios from it (Jacobian: :func:`ratio_jacobian`), then one that weighs
    the largest ratios; None if none."""
    from scipy.optimize import least_squares

    free = hi > lo
    x0 = 0.5 * (lo + hi)
    if np.all(point_ratios(model, pts, x0) <= 1.0):
        return x0
    if not np.any(free):
        return None

    def full(xf: np.ndarray) -> np.ndarray:
        x = x0.copy()
        x[free] = xf
        return x

    last: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def at(xf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = np.asarray(xf, dtype=float).tobytes()
        if key not in last:
            last.clear()
            r, J = ratio_jacobian(model, fac, pts, full(xf))
            last[key] = (r, J[:, free])
        return last[key]

    for power in (1.0, 4.0):
        def res(xf: np.ndarray, q: float = power) -> np.ndarray:
            r = at(xf)[0]
            return np.where(np.isfinite(r), r, 1e6) ** q

        def jac(xf: np.ndarray, q: float = power) -> np.ndarray:
            r, J = at(xf)
            ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
            return np.where(ok[:, None], q * np.where(ok, r, 1.0)[:, None] ** (q - 1.0) * J, 0.0)
        try:
            sol = least_squares(res, x0[free], jac=jac, bounds=(lo[free], hi[free]), x_scale=hi[free] - lo[free],
                                max_nfev=40)
        except (ValueError, np.linalg.LinAlgError):
            return None
        x0 = full(sol.x)
        if np.all(point_ratios(model, pts, x0) <= 1.0):
            return x0
    return None


def _box(model: AffineModel, fac: _Factors, pts: Points, lo: np.ndarray, hi: np.ndarray, max_boxes: int,
         used: Counter[int]) -> tuple[str, np.ndarray | None, int]:
    """Branch and bound over one box, every point jointly: ``("excluded" | "witness" | "open", witness,
    boxes)``. A sub-box is excluded when one point excludes it; its centre is a witness when it explains
    every point; the sub-box closest to exclusion is split first (along the parameter with the largest
    share of that point's bound); "open": the budget ran out first."""

    split: dict[tuple[int, ...], tuple[tuple[np.ndarray, Points], tuple[np.ndarray, Points]]] = {}

    def parts(first: tuple[int, ...]) -> tuple[tuple[np.ndarray, Points], tuple[np.ndarray, Points]]:
        """The points ``first`` and the rest, each as an index array and as points (made once per set)."""
        if first not in split:
            a = np.array(first, dtype=int)
            b = np.setdiff1d(np.arange(pts.size), a)
            split[first] = ((a, pts.take(a)), (b, pts.take(b)))
        return split[first]

    def examine(c: np.ndarray, h: np.ndarray) -> tuple[float, np.ndarray | None]:
        # the points that excluded boxes most often first (most boxes fall to one of them), then the rest
        found: list[tuple[float, bool, np.ndarray]] = []  # per part: largest margin, not all explained, its share
        for idx, sub in parts(tuple(k for k, _ in used.most_common(EARLY))):
            if not idx.size:
                continue
            ok, margins, shares = examine_points(model, fac, sub, c, h)
            k = int(np.argmax(margins))
            if margins[k] > 0:
                used[int(idx[k])] += 1
                return float(margins[k]), shares[k]
            found.append((float(margins[k]), not bool(np.all(ok)), shares[k]))
        if not any(open_ for _, open_, _ in found):
            return -np.inf, None
        top = max(found, key=lambda t: (t[0], t[1]))  # ties: the part not all explained, then the first
        return top[0], top[2]

    c0, h0 = (lo + hi) / 2.0, (hi - lo) / 2.0
    margin, share = examine(c0, h0)
    if margin > 0:
        return "excluded", None, 1
    if share is None:
        return "witness", c0, 1
    heap: list[tuple[float, int, np.ndarray, np.ndarray, np.ndarray]] = [(-margin, 0, c0, h0, share)]
    boxes, tick = 1, 1
    span = np.where(hi > lo, hi - lo, 1.0)
    while heap:
        if boxes >= max_boxes:
            return "open", None, boxes
        _, _, c, h, sh = heapq.heappop(heap)
        weight = np.where(h > 0, np.nan_to_num(sh), 0.0)
        i = int(np.argmax(weight)) if np.any(weight > 0) else int(np.argmax(np.where(hi > lo, h / span, -1.0)))
        if h[i] <= 0.0:
            return "open", None, boxes
        h1 = h.copy()
        h1[i] /= 2.0
        for sgn in (-1.0, 1.0):
            c1 = c.copy()
            c1[i] += sgn * h1[i]
            margin, share = examine(c1, h1)
            boxes += 1
            if margin > 0:
                continue
            if share is None:
                return "witness", c1, boxes
            heapq.heappush(heap, (-margin, tick, c1, h1, share))
            tick += 1
    return "excluded", None, boxes


def _end(model: AffineModel, fac: _Factors, pts: Points, lo: np.ndarray, hi: np.ndarray, index: int,
         upward: bool, tol: float, slices: int, max_boxes: int, used: Counter[int],
         cache: dict[tuple[float, float], str]) -> tuple[float, float, int, bool]:
    """One end of the interval: ``(certified end, witness value (nan: none found), boxes, witnessed)``;
    the end is nan when every slice is excluded. Slices are taken from that end inwards; one not excluded
    is halved until ``tol`` wide, then searched for a witness."""
    edges = np.linspace(lo[index], hi[index], slices + 1)
    stack = [(float(a), float(b)) for a, b in itertools.pairwise(edges)]
    if not upward:
        stack.reverse()  # pop() takes the lowest slice first
    boxes = 0
    while stack:
        a, b = stack.pop()
        l1, h1 = lo.copy(), hi.copy()
        l1[index], h1[index] = a, b
        kind = cache.get((a, b))
        wit = None
        if kind is None:
            kind, wit, n = _box(model, fac, pts, l1, h1, max_boxes, used)
            cache[(a, b)] = kind
            boxes += n
        if kind == "excluded":
            continue
        if b - a > tol:
            mid = 0.5 * (a + b)
            halves = [(a, mid), (mid, b)]
            stack.extend(halves if upward else halves[::-1])
            continue
        if wit is None:
            wit = _witness(model, fac, pts, l1, h1)
        return (b if upward else a), (float(wit[index]) if wit is not None else float("nan")), boxes, wit is not None
    return float("nan"), float("nan"), boxes, True


def severity_interval(model: AffineModel, pts: Points, lo: np.ndarray, hi: np.ndarray, index: int,
                      tol: float = 0.01, slices: int = 16, max_boxes: int = 16, witnessed_at_lo: bool = False,
                      earlier: SeverityInterval | None = None) -> SeverityInterval:
    """Certify the interval of parameter ``index`` over which the box ``[lo, hi]`` (p,) explains every
    point jointly (module docstring; each point's ``b``, ``c`` in ``pts``); ``tol`` the width to which
    the end slices are halved; ``slices`` the first division of the range; ``max_boxes`` the budget of
    sub-boxes per slice. ``witnessed_at_lo``: the caller holds a witness with the parameter at ``lo[index]``
    (e.g. the healthy hypothesis's): the lower end is ``lo[index]``, attained, without a search.
    ``earlier``: this hypothesis's result with a smaller budget on the same box, points and slices (its
    excluded slices stay excluded: they are not examined again; its excluding points are tried first)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    used: Counter[int] = Counter()
    cache: dict[tuple[float, float], str] = {}
    if earlier is not None:
        cache.update(dict.fromkeys(earlier.excluded_slices, "excluded"))
        used.update({k: len(earlier.excluding) - i for i, k in enumerate(earlier.excluding)})
    fac = _Factors.of(model)
    n_sl = slices if hi[index] > lo[index] else 1
    if witnessed_at_lo:
        lower, w_lo, n1, done1 = float(lo[index]), float(lo[index]), 0, True
    else:
        lower, w_lo, n1, done1 = _end(model, fac, pts, lo, hi, index, False, tol, n_sl, max_boxes, used, cache)
    excluded = tuple(sorted(k for k, v in cache.items() if v == "excluded"))
    if not np.isfinite(lower):
        return SeverityInterval("excluded", float("nan"), float("nan"), (float("nan"), float("nan")),
                                tuple(k for k, _ in used.most_common()), n1, False, excluded)
    upper, w_hi, n2, done2 = _end(model, fac, pts, lo, hi, index, True, tol, n_sl, max_boxes, used, cache)
    excluded = tuple(sorted(k for k, v in cache.items() if v == "excluded"))
    return SeverityInterval("consistent", float(lower), float(upper), (w_lo, w_hi),
                            tuple(k for k, _ in used.most_common()), n1 + n2, done1 and done2, excluded)
