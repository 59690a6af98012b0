"""Per-point certificate over a box of real parameters: can the data at one frequency be explained by
some parameter values inside their ranges? (The real-mu branch and bound.)

The model is a dynamic stiffness affine in real parameters ``theta`` (p,)::

    Z(w, theta) = K - w^2 M + j w D + sum_i theta_i s_i(w) A_i,   s_i = 1 | j w | -w^2  (kind K | D | M)
    G(w, theta) = c^T Z^-1 b                                       (m/N)

and the prediction of the data is anchored at the measured healthy FRF ``T_h``:
``T(theta, gamma) = gamma T_h G(w, theta) / G(w, 0)`` with ``gamma`` a real gain factor in its own
range (sensor and actuator calibration enter exactly as a factor). At each point the question is
whether some ``theta`` in the box and ``gamma`` in its range give::

    |T_new - T(theta, gamma)| <= z sqrt(var_new + |gamma G(theta) / G(0)|^2 var_h + a^2)

(``z`` the per-point quantile, ``var_*`` the variances of both sweeps' mean FRFs, ``a`` the model's own
error at that point, m/N, carried like a variance as in :mod:`rotorcheck.robust.joint`).

Certificate. On a sub-box (centre ``theta_c``, half-widths ``h``) the parameters enter as
``Z_c + U Delta V^T`` with ``Delta = diag(delta_i I_{r_i})``, ``delta_i`` real in ``[-1, 1]``
(``A_i = U_i V_i^T`` of rank ``r_i``, scaled by ``h_i s_i``), so ``G`` is an upper LFT of the real
block structure and, by the small-gain theorem, ``|G(theta) - G(theta_c)| <= |x| |y| / (1 - ||N||)``
for every theta in the sub-box when ``||N|| < 1`` (``x = c^T Z_c^-1 U``, ``y = V^T Z_c^-1 b``,
``N = V^T Z_c^-1 U``, after a diagonal scaling that commutes with Delta). A sub-box is excluded when
even that bound leaves the data outside the allowance; a point is *unexplained* (certified) when every
sub-box is excluded, *explained* when a sub-box centre is a witness (evaluated exactly), and
*undecided* when the box budget runs out first. Boxes are split along the parameter with the largest
share of the bound, the most promising first (best-first on the margin). At the root box (no split)
the bound treats the parameters as one complex disc each: :attr:`BoxCertificate.complex_unexplained`
is what that relaxation certifies, for comparison.
"""

from __future__ import annotations

import functools
import heapq
from dataclasses import dataclass, field

import numpy as np

#: how the certified per-point verdict is made (report.json)
BOX_RULE = ("per point: unexplained iff for every benign parameter value in its range (real, branch and bound "
            "with small-gain bounds on each sub-box) and every gain in its range, |T_new - gain T_h G(theta)/G(0)| "
            "exceeds z sqrt(var_new + |gain G(theta)/G(0)|^2 var_h + a^2), a the model-error allowance; z: Sidak "
            "over the points at the stated rate, complex Gaussian noise with the variances treated as known")

KINDS = ("K", "D", "M")


@dataclass(frozen=True)
class AffineParameter:
    """One real parameter: ``theta`` in ``[lo, hi]`` adds ``theta sum_terms s(w) A`` to the dynamic
    stiffness; ``terms`` pairs a kind (K: s = 1, D: s = j w, M: s = -w^2) with ``A`` (n, n) per unit
    theta (e.g. a stiffness that also moves a stiffness-proportional damping: K and D terms)."""

    name: str
    terms: tuple[tuple[str, np.ndarray], ...]
    lo: float
    hi: float


@dataclass(frozen=True)
class StiffnessStack:
    """A stack of dynamic stiffnesses ``Z_k`` (m, n, n) complex N/m held block by block: ``parts[i]`` (m, n_i, n_i)
    is ``Z_k`` on the DOFs ``blocks[i]``, and ``Z_k`` is zero between blocks (:attr:`AffineModel.blocks`: e.g. the
    two bending planes of a rotor that does not spin). Solving block by block does a quarter of a full LU's work
    with two equal blocks, and skips a block where the right-hand side is zero."""

    blocks: tuple[np.ndarray, ...]
    parts: tuple[np.ndarray, ...]
    n: int

    @property
    def size(self) -> int:
        return int(self.parts[0].shape[0])

    def take(self, at: np.ndarray) -> StiffnessStack:
        """The members ``at`` (an index array) of the stack."""
        return StiffnessStack(self.blocks, tuple(z[at] for z in self.parts), self.n)

    def transpose(self) -> StiffnessStack:
        """``Z_k^T``."""
        return StiffnessStack(self.blocks, tuple(np.swapaxes(z, 1, 2) for z in self.parts), self.n)

    def full(self) -> np.ndarray:
        """``Z_k`` (m, n, n) as full matrices."""
        if len(self.parts) == 1:
            return self.parts[0]
        Z = np.zeros((self.size, self.n, self.n), dtype=complex)
        for d, z in zip(self.blocks, self.parts):
            Z[:, d[:, None], d[None, :]] = z
        return Z

    def solve(self, B: np.ndarray) -> np.ndarray:
        """``Z_k^-1 B_k`` (m, n, k) complex for ``B`` (m, n, k) or broadcastable (e.g. (n, k)): one batched solve per
        block, for the members whose right-hand sides are nonzero in it and only those right-hand sides."""
        m, n = self.size, self.n
        B = np.asarray(B)
        if len(self.parts) == 1:
            return np.linalg.solve(self.parts[0], np.broadcast_to(B, (m, n, B.shape[-1])).astype(complex))
        X = np.zeros((m, n, B.shape[-1]), dtype=complex)
        per_member = B.ndim == 3 and B.shape[0] == m and m > 1
        for d, z in zip(self.blocks, self.parts):
            Bd = B[..., d, :]
            nz = Bd != 0
            cols = np.flatnonzero(np.any(nz, axis=tuple(range(nz.ndim - 1))))
            if not cols.size:
                continue
            if per_member:
                rows = np.flatnonzero(np.any(nz, axis=(1, 2)))
                if rows.size < m:
                    X[np.ix_(rows, d, cols)] = np.linalg.solve(z[rows], Bd[np.ix_(rows, np.arange(d.size), cols)]
                                                               .astype(complex))
                    continue
            rhs = np.broadcast_to(Bd[..., cols], (m, d.size, cols.size)).astype(complex)
            X[:, d[:, None], cols[None, :]] = np.linalg.solve(z, rhs)
        return X


def solve_both(Z: StiffnessStack, B: np.ndarray, C: np.ndarray, symmetric: bool) -> tuple[np.ndarray, np.ndarray]:
    """``(Z^-1 B, Z^-T C)`` for a stack ``Z`` and right-hand sides ``B`` (m, n, nb), ``C`` (m, n, nc) (or
    broadcastable): one batched solve of ``[B, C]`` when ``Z`` is symmetric, two otherwise."""
    m, n = Z.size, Z.n
    B = np.broadcast_to(B, (m, n, B.shape[-1]))
    C = np.broadcast_to(C, (m, n, C.shape[-1]))
    if symmetric:
        X = Z.solve(np.concatenate([B, C], axis=2))
        return X[:, :, :B.shape[2]], X[:, :, B.shape[2]:]
    return Z.solve(B), Z.transpose().solve(C)


def coupled_blocks(mats: list[np.ndarray]) -> tuple[np.ndarray, ...]:
    """The DOF sets (index arrays, ascending) that no matrix of ``mats`` (n, n) couples: the connected components
    of their joint nonzero pattern. A matrix sum of them is block diagonal in these sets."""
    pattern = np.zeros_like(np.asarray(mats[0]), dtype=bool)
    for A in mats:
        pattern |= np.asarray(A) != 0
    pattern |= pattern.T
    n = pattern.shape[0]
    seen = np.zeros(n, dtype=bool)
    out = []
    for start in range(n):
        if seen[start]:
            continue
        comp = np.zeros(n, dtype=bool)
        comp[start] = True
        while True:
            grown = comp | pattern[comp].any(axis=0)
            if np.array_equal(grown, comp):
                break
            comp = grown
        seen |= comp
        out.append(np.flatnonzero(comp))
    return tuple(out)


def _norm2_bound(N: np.ndarray) -> float:
    """An upper bound on the spectral norm: the cheaper of Frobenius and sqrt(||N||_1 ||N||_inf), the
    exact value (singular values only) when those are not already small."""
    if N.size == 0:
        return 0.0
    a = np.abs(N)
    cheap = min(float(np.sqrt(np.sum(a * a))), float(np.sqrt(a.sum(axis=0).max() * a.sum(axis=1).max())))
    if cheap < 0.25:
        return cheap
    return float(np.linalg.svd(N, compute_uv=False)[0])


def _factor(A: np.ndarray, blocks: tuple[np.ndarray, ...] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``A = U V^T`` with ``U`` (n, r), ``V`` (n, r), r the numerical rank (SVD, 1e-12 of A's largest singular
    value). With ``blocks`` (A block diagonal in them) each block is factored on its own, so that every column
    lies in one block: an SVD of ``A`` all the same (within a repeated singular value the choice of vectors is
    free, and the small-gain bounds do not depend on it)."""
    A = np.asarray(A, dtype=float)
    s_max = float(np.linalg.norm(A, 2)) if A.size else 0.0
    us, vs = [], []
    for d in (blocks if blocks is not None and len(blocks) > 1 else (np.arange(A.shape[0]),)):
        sub = A[np.ix_(d, d)]
        if not np.any(sub):
            continue
        u, s, vt = np.linalg.svd(sub)
        r = int(np.sum(s > 1e-12 * max(s_max, 1e-300)))
        U = np.zeros((A.shape[0], r))
        V = np.zeros((A.shape[0], r))
        U[d] = u[:, :r] * s[:r]
        V[d] = vt[:r].T
        us.append(U)
        vs.append(V)
    if not us:
        return np.zeros((A.shape[0], 0)), np.zeros((A.shape[0], 0))
    return np.hstack(us), np.hstack(vs)


@dataclass(frozen=True)
class AffineModel:
    """``Z(w, theta) = K - w^2 M + j w D + sum theta_i s_i(w) A_i``; io receptance ``c^T Z^-1 b``."""

    M: np.ndarray
    D: np.ndarray
    K: np.ndarray
    b: np.ndarray  # (n,) force input
    c: np.ndarray  # (n,) displacement output
    parameters: tuple[AffineParameter, ...]
    factors: tuple[tuple[tuple[str, np.ndarray, np.ndarray], ...], ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        out = []
        blocks = self.blocks
        for prm in self.parameters:
            terms = []
            for kind, A in prm.terms:
                if kind not in KINDS:
                    raise ValueError(f"{prm.name}: kind must be one of {KINDS}, got {kind!r}")
                terms.append((kind, *_factor(A, blocks)))
            out.append(tuple(terms))
        object.__setattr__(self, "factors", tuple(out))
        # every matrix of Z stacked (rows K, M, D, then each parameter's terms), one matrix product per stack
        mats = [self.K, self.M, self.D, *(A for prm in self.parameters for _, A in prm.terms)]
        # and per block (:attr:`blocks`): each matrix's entries on that block's DOFs
        object.__setattr__(self, "_stacks", tuple(np.stack([np.asarray(A, dtype=float)[np.ix_(d, d)].reshape(-1)
                                                            for A in mats]) for d in blocks))
        object.__setattr__(self, "_terms", tuple((i, k) for i, prm in enumerate(self.parameters) for k, _ in prm.terms))

    @functools.cached_property
    def blocks(self) -> tuple[np.ndarray, ...]:
        """The DOF sets in which ``Z(w, theta)`` is block diagonal for every ``w`` and ``theta``
        (:func:`coupled_blocks` of every matrix): e.g. the two bending planes of a rotor with no gyroscopic or
        cross-coupled term. :meth:`stiffness_stack` holds ``Z`` block by block."""
        return coupled_blocks([self.K, self.M, self.D, *(A for prm in self.parameters for _, A in prm.terms)])

    def solve_both(self, Z: StiffnessStack, B: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Z^-1 B, Z^-T C)`` for a stack of this model's ``Z`` (:func:`solve_both`)."""
        return solve_both(Z, B, C, self.symmetric)

    @functools.cached_property
    def symmetric(self) -> bool:
        """``Z(w, theta) = Z^T`` for every ``w`` and ``theta`` (every matrix symmetric, 1e-12 of its largest entry:
        no gyroscopic term), so that ``Z^-T c = Z^-1 c``."""
        mats = [self.K, self.M, self.D, *(A for prm in self.parameters for _, A in prm.terms)]
        return all(np.allclose(A, A.T, rtol=0.0, atol=1e-12 * max(float(np.abs(A).max()), 1e-300)) for A in mats)

    @staticmethod
    def _s(kind: str, w: float) -> complex:
        return {"K": 1.0 + 0j, "D": 1j * w, "M": -(w**2) + 0j}[kind]

    def dynamic_stiffness(self, w: float, theta: np.ndarray) -> np.ndarray:
        """``Z(w, theta)`` (n, n) complex, N/m; ``w`` in rad/s."""
        Z = self.K - w**2 * self.M + 1j * w * self.D
        for t, prm in zip(np.asarray(theta, dtype=float), self.parameters):
            if t != 0.0:
                for kind, A in prm.terms:
                    Z = Z + t * self._s(kind, w) * A
        return Z

    def stiffness_stack(self, w: np.ndarray, theta: np.ndarray) -> StiffnessStack:
        """``Z(w_k, theta_k)`` N/m for frequencies ``w`` (m,) rad/s and parameters ``theta`` (p,) for all or (m, p)
        one row per frequency, block by block (:class:`StiffnessStack`): per block two real matrix products over
        the stacked matrices, the real and the imaginary part."""
        w = np.asarray(w, dtype=float).reshape(-1)
        th = np.broadcast_to(np.asarray(theta, dtype=float), (w.size, len(self.parameters)))
        terms: tuple[tuple[int, str], ...] = self._terms  # type: ignore[attr-defined]
        stacks: tuple[np.ndarray, ...] = self._stacks  # type: ignore[attr-defined]
        re = np.zeros((w.size, 3 + len(terms)))
        im = np.zeros_like(re)
        re[:, 0], re[:, 1], im[:, 2] = 1.0, -(w**2), w
        for col, (i, kind) in enumerate(terms, start=3):
            t = th[:, i]
            if kind == "K":
                re[:, col] = t
            elif kind == "D":
                im[:, col] = t * w
            else:
                re[:, col] = -t * w**2
        used = [(coef[:, rows], rows) for coef in (re, im) for rows in [np.flatnonzero(np.any(coef != 0.0, axis=0))]]
        parts = []
        for d, stack in zip(self.blocks, stacks):
            Z = np.empty((w.size, d.size, d.size), dtype=complex)
            for part, (coef, rows) in zip((Z.real, Z.imag), used):
                part[...] = (coef @ stack[rows]).reshape(w.size, d.size, d.size) if rows.size else 0.0
            parts.append(Z)
        return StiffnessStack(self.blocks, tuple(parts), int(self.K.shape[0]))

    def receptance(self, w: float, theta: np.ndarray) -> complex:
        """``G(w, theta)`` m/N, by a direct solve."""
        return complex(self.c @ np.linalg.solve(self.dynamic_stiffness(w, theta), self.b))

    def box_bound(self, w: float, centre: np.ndarray, half: np.ndarray) -> tuple[complex, float, np.ndarray]:
        """``(G_c, radius, share)``: the receptance at the centre, a bound on ``|G - G_c|`` over the box
        (inf when the small-gain condition fails) and each parameter's share of the bound (p,)."""
        Z = self.dynamic_stiffness(w, centre)
        cols_u, cols_v, sizes = [], [], []
        for terms, h in zip(self.factors, half):
            for kind, u, v in terms:
                cols_u.append(u * (h * self._s(kind, w)))
                cols_v.append(v)
            sizes.append(sum(u.shape[1] for _, u, _ in terms))
        U = np.hstack([*cols_u, self.b[:, None]])
        V = np.hstack(cols_v) if cols_v else np.zeros((self.K.shape[0], 0))
        X = np.linalg.solve(Z, U)  # Z_c^-1 [U, b]
        g_c = complex(self.c @ X[:, -1])
        x = self.c @ X[:, :-1]
        y = V.T @ X[:, -1]
        N = V.T @ X[:, :-1]
        # one positive scale per block (commutes with delta_i I): balance |x_i| against |y_i|
        edges = np.cumsum([0, *sizes])
        blocks = [slice(edges[i], edges[i + 1]) for i in range(len(sizes))]
        sc = np.ones(int(edges[-1]))
        share = np.zeros(len(sizes))
        for i, sl in enumerate(blocks):
            nx, ny = float(np.linalg.norm(x[sl])), float(np.linalg.norm(y[sl]))
            share[i] = nx * ny
            if nx > 0 and ny > 0:
                sc[sl] = np.sqrt(nx / ny)
        xs, ys = x / sc, y * sc
        Ns = (sc[:, None] * N) / sc[None, :]
        n_norm = _norm2_bound(Ns)
        if n_norm >= 1.0:
            return g_c, float("inf"), share
        return g_c, float(np.linalg.norm(xs) * np.linalg.norm(ys) / (1.0 - n_norm)), share


@dataclass
class BoxCertificate:
    """Per-point result of :func:`certify_points` (n points)."""

    status: np.ndarray  # (n,) str: "explained" | "unexplained" | "undecided"
    witness: np.ndarray  # (n, p) parameter values explaining the point (NaN where none found)
    witness_gain: np.ndarray  # (n,) gain factor of the witness (NaN where none)
    boxes: np.ndarray  # (n,) sub-boxes examined per point
    complex_unexplained: np.ndarray  # (n,) bool: certified at the root box alone (complex-disc relaxation)
    rule: str = BOX_RULE

    @property
    def unexplained(self) -> np.ndarray:
        return self.status == "unexplained"

    @property
    def undecided(self) -> np.ndarray:
        return self.status == "undecided"


def _best_gain(t_new: complex, pred: complex, g_lo: float, g_hi: float) -> float:
    """The gain in ``[g_lo, g_hi]`` closest to explaining ``t_new`` by ``gain * pred``."""
    den = abs(pred) ** 2
    g = (t_new * np.conj(pred)).real / den if den > 0 else 1.0
    return float(min(max(g, g_lo), g_hi))


@dataclass(frozen=True)
class _Point:
    """The data of one point for :func:`_examine` (m/N, m^2/N^2; ``w`` rad/s)."""

    w: float
    g0: complex
    t_new: complex
    t_healthy: complex
    var_new: float
    var_healthy: float
    z: float
    allowance2: float
    g_lo: float
    g_hi: float
    # a deterministic bound on the model's error, added to the noise allowance: ``tolerance`` (m/N) plus
    # ``relative_error`` times the predicted change ``|T_h| |gain rho - 1|``
    tolerance: float = 0.0
    relative_error: float = 0.0


def _examine(model: AffineModel, pt: _Point, centre: np.ndarray, half: np.ndarray
             ) -> tuple[bool, float, np.ndarray, float]:
    """(the centre explains the point?, margin of the exclusion test (> 0: the box is excluded), each
    parameter's share of the bound, the centre's best gain)."""
    share = np.zeros(len(half))
    rho = model.receptance(pt.w, centre) / pt.g0
    gm = _best_gain(pt.t_new, pt.t_healthy * rho, pt.g_lo, pt.g_hi)
    resid = abs(pt.t_new - gm * pt.t_healthy * rho)
    extra = pt.tolerance + pt.relative_error * abs(pt.t_healthy) * abs(gm * rho - 1.0)
    if resid <= pt.z * np.sqrt(pt.var_new + abs(gm * rho) ** 2 * pt.var_healthy + pt.allowance2) + extra:
        return True, -np.inf, share, gm
    _, rad, share = model.box_bound(pt.w, centre, half)
    if not np.isfinite(rad):
        return False, -np.inf, share, gm
    eps = rad / abs(pt.g0)
    low = resid - pt.g_hi * abs(pt.t_healthy) * eps
    # |gain rho' - 1| over the box and the gain range: largest at a gain end (convex in the gain), plus eps
    change = max(abs(pt.g_lo * rho - 1.0), abs(pt.g_hi * rho - 1.0)) + pt.g_hi * eps
    extra = pt.tolerance + pt.relative_error * abs(pt.t_healthy) * change
    up = pt.z * np.sqrt(pt.var_new + (pt.g_hi * (abs(rho) + eps)) ** 2 * pt.var_healthy + pt.allowance2) + extra
    return False, low - up, share, gm


def _certify_one(model: AffineModel, pt: _Point, lo: np.ndarray, hi: np.ndarray, max_boxes: int
                 ) -> tuple[str, np.ndarray | None, float, int, bool]:
    """(status, witness, witness gain, boxes examined, certified at the root box) of one point."""
    centre, half = (lo + hi) / 2.0, (hi - lo) / 2.0
    ok, margin, share, gm = _examine(model, pt, centre, half)
    if ok:
        return "explained", centre, gm, 1, False
    if margin > 0:
        return "unexplained", None, float("nan"), 1, True
    heap: list[tuple[float, int, np.ndarray, np.ndarray, np.ndarray]] = [(margin, 0, centre, half, share)]
    boxes, tick = 1, 1
    while heap:
        if boxes >= max_boxes:
            return "undecided", None, float("nan"), boxes, False
        _, _, c0, h0, sh = heapq.heappop(heap)
        weight = np.where(h0 > 0, sh, 0.0)
        i = int(np.argmax(weight)) if np.any(weight > 0) else int(np.argmax(h0))
        h1 = h0.copy()
        h1[i] /= 2.0
        for sign in (-1.0, 1.0):
            c1 = c0.copy()
            c1[i] += sign * h1[i]
            ok, margin, share, gm = _examine(model, pt, c1, h1)
            boxes += 1
            if ok:
                return "explained", c1, gm, boxes, False
            if margin <= 0:
                heapq.heappush(heap, (margin, tick, c1, h1, share))
                tick += 1
    return "unexplained", None, float("nan"), boxes, False


def certify_points(model: AffineModel, omega: np.ndarray, t_new: np.ndarray, t_healthy: np.ndarray,
                   var_new: np.ndarray, var_healthy: np.ndarray, z: float, allowance: np.ndarray,
                   gain: tuple[float, float] = (1.0, 1.0), max_boxes: int = 200) -> BoxCertificate:
    """Certify each point (``omega`` rad/s, (n,)) as explained / unexplained / undecided by benign
    parameters in ``model``'s box and a gain factor in ``gain`` (see the module docstring); the
    allowance ``a`` (n,) m/N is the model's own error; ``max_boxes`` the sub-box budget per point."""
    p = len(model.parameters)
    lo = np.array([q.lo for q in model.parameters], dtype=float)
    hi = np.array([q.hi for q in model.parameters], dtype=float)
    n = len(omega)
    status = np.full(n, "undecided", dtype="<U11")
    witness = np.full((n, p), np.nan)
    wgain = np.full(n, np.nan)
    boxes = np.zeros(n, dtype=int)
    root = np.zeros(n, dtype=bool)
    for k in range(n):
        w = float(omega[k])
        pt = _Point(w, model.receptance(w, np.zeros(p)), complex(t_new[k]), complex(t_healthy[k]),
                    float(var_new[k]), float(var_healthy[k]), float(z), float(allowance[k]) ** 2,
                    float(gain[0]), float(gain[1]))
        st, wit, g, nb, at_root = _certify_one(model, pt, lo, hi, max_boxes)
        status[k], boxes[k], root[k], wgain[k] = st, nb, at_root, g
        if wit is not None:
            witness[k] = wit
    return BoxCertificate(status, witness, wgain, boxes, root)


def merge_certificates(certs: list[BoxCertificate]) -> BoxCertificate:
    """One per-point certificate from several channels' on the same points: a point is unexplained when
    any channel's is, else undecided when any is, else explained (the first channel's witness)."""
    if len(certs) == 1:
        return certs[0]
    st = np.array([c.status for c in certs])
    status = np.where(np.any(st == "unexplained", axis=0), "unexplained",
                      np.where(np.any(st == "undecided", axis=0), "undecided", "explained")).astype("<U11")
    return BoxCertificate(status, certs[0].witness, certs[0].witness_gain, np.sum([c.boxes for c in certs], axis=0),
                          np.any([c.complex_unexplained for c in certs], axis=0))
