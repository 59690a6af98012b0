"""The model the real-parameter certificates work on: a dynamic stiffness affine in real parameters
``theta`` (p,)::

    Z(w, theta) = K - w^2 M + j w D + sum_i theta_i s_i(w) A_i,   s_i = 1 | j w | -w^2  (kind K | D | M)
    G(w, theta) = c^T Z^-1 b                                       (m/N)

(:class:`AffineModel`), each ``A_i = U_i V_i^T`` factored to its rank, and ``Z`` held block by block where no
matrix couples a set of DOFs to the rest (:class:`StiffnessStack`: e.g. the two bending planes of a rotor
that does not spin).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

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
        # every matrix of Z stacked (rows K, M, D, then each parameter's terms), one complex matrix product per
        # stack, per block (:attr:`blocks`): each matrix's entries on that block's DOFs (held complex: the product
        # with the complex coefficients writes Z whole, faster than its real and imaginary parts apart)
        object.__setattr__(self, "_stacks", tuple(np.stack([np.asarray(A, dtype=float)[np.ix_(d, d)].reshape(-1)
                                                            for A in self.matrices]).astype(complex) for d in blocks))
        object.__setattr__(self, "_terms", tuple((i, k) for i, prm in enumerate(self.parameters) for k, _ in prm.terms))

    @property
    def matrices(self) -> list[np.ndarray]:
        """Every matrix of ``Z``: K, M, D, then each parameter's terms in order (n, n)."""
        return [self.K, self.M, self.D, *(A for prm in self.parameters for _, A in prm.terms)]

    @functools.cached_property
    def blocks(self) -> tuple[np.ndarray, ...]:
        """The DOF sets in which ``Z(w, theta)`` is block diagonal for every ``w`` and ``theta``
        (:func:`coupled_blocks` of every matrix): e.g. the two bending planes of a rotor with no gyroscopic or
        cross-coupled term. :meth:`stiffness_stack` holds ``Z`` block by block."""
        return coupled_blocks(self.matrices)

    def solve_both(self, Z: StiffnessStack, B: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Z^-1 B, Z^-T C)`` for a stack of this model's ``Z`` (:func:`solve_both`)."""
        return solve_both(Z, B, C, self.symmetric)

    @functools.cached_property
    def symmetric(self) -> bool:
        """``Z(w, theta) = Z^T`` for every ``w`` and ``theta`` (every matrix symmetric, 1e-12 of its largest entry:
        no gyroscopic term), so that ``Z^-T c = Z^-1 c``."""
        return all(np.allclose(A, A.T, rtol=0.0, atol=1e-12 * max(float(np.abs(A).max()), 1e-300))
                   for A in self.matrices)

    @staticmethod
    def _s(kind: str, w: float) -> complex:
        return {"K": 1.0 + 0j, "D": 1j * w, "M": -(w**2) + 0j}[kind]

    def matrices_at(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M, D, K)`` (n, n) at ``theta``: each parameter's terms added to the matrix of its kind (kg, N s/m,
        N/m)."""
        mats = {"M": self.M.copy(), "D": self.D.copy(), "K": self.K.copy()}
        for t, prm in zip(np.asarray(theta, dtype=float), self.parameters):
            for kind, A in prm.terms:
                mats[kind] = mats[kind] + t * A
        return mats["M"], mats["D"], mats["K"]

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
        one row per frequency, block by block (:class:`StiffnessStack`): per block one complex matrix product of the
        terms' coefficients and the stacked matrices."""
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
        rows = np.flatnonzero(np.any(re != 0.0, axis=0) | np.any(im != 0.0, axis=0))
        every = rows.size == re.shape[1]
        coef = re + 1j * im if every else re[:, rows] + 1j * im[:, rows]
        parts = []
        for d, stack in zip(self.blocks, stacks):
            parts.append((coef @ (stack if every else stack[rows])).reshape(w.size, d.size, d.size) if rows.size
                         else np.zeros((w.size, d.size, d.size), dtype=complex))
        return StiffnessStack(self.blocks, tuple(parts), int(self.K.shape[0]))

    def receptance(self, w: float, theta: np.ndarray) -> complex:
        """``G(w, theta)`` m/N, by a direct solve."""
        return complex(self.c @ np.linalg.solve(self.dynamic_stiffness(w, theta), self.b))
