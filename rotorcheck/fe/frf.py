r"""The receptance / state-space engine: every receptance and state matrix of rotorcheck comes from here.

``H(nu) = C Z(nu)^-1 B``, ``Z(nu) = K - nu^2 M + j nu D``, ``D = C + Omega G`` (method.md), for chosen
outputs (DOF indices or output rows ``C``) and inputs (DOF indices or force vectors ``B``) at many
angular frequencies ``nu`` (rad/s, any shape, any sign). :class:`Receptance` is built once per
(matrices, outputs, inputs) and evaluated on any grid; :func:`receptance` is the one-call form on a
:class:`~rotorcheck.fe.system.MechanicalSystem` with frequencies in Hz. Users: the nominal model
(:mod:`rotorcheck.nominal`), the harmonic balance (:mod:`rotorcheck.faults.harmonic_balance`), the
simulator's plants (:mod:`rotorcheck.sim`), modal analysis (:mod:`rotorcheck.fe.modal`).

Nothing here grows with (points x n^2): the cost is one factorisation per speed plus
O(points x (outputs x inputs) x modes) for the evaluation, done in chunks of bounded memory.

Methods (``method=``):

- ``"modal"``: one eigendecomposition of the state matrix (all 2n modes, not truncated), written
  in energy-scaled undamped modal coordinates (an exact change of variables that keeps its norm at
  ``w_max`` instead of ``w_max^2``, see :func:`_scaled_modal_factors`),
  ``Z^-1 F = Phi W^-1 [I 0] V diag(1/(j nu - lambda)) V^-1 [0; Phi^T F]``: O((2n)^3) once, exact
  for a diagonalisable state matrix. Chosen by ``"auto"`` from :data:`N_DIRECT` to :data:`N_FULL`
  DOF when it agrees with a direct solve to 1e-9 at one frequency (an ill-conditioned eigenvector
  basis does not). Two exact shortcuts (issue 13: the 9-element rig's 262 points in ~1/5 of the
  per-frequency dense solves' time, bench/bench_engine.py): an isotropic rotor (``planes=``, which
  :func:`system_receptance` passes for rotors; checked to a few ulps) is one complex model of half
  the size, whose n-state eigensolution costs about half that of the real 2n-state one
  (:func:`_isotropic_half`); and when D and K are diagonal in the undamped modes (modal damping at
  rest) the eigenpairs are 2x2 blocks in closed form (:func:`_decoupled_pairs`): no eigensolution
  of the state matrix at all. The evaluation is one product ``(points, modes) x (modes, outputs x
  inputs)`` of the residues; the undamped modes of the half model come from
  :func:`rotorcheck.fe.dense.eigh_pencil`. The full real path (anisotropic rotors, lumped models,
  the harmonic balance, the simulator's truth rigs) is unchanged to the bit: the bundled samples
  are checked bit for bit against a regeneration. scipy.sparse is loaded by the reduced path only.
- ``"direct"``: per-frequency LU solves of ``Z(nu)`` for the input columns only, in chunks of at
  most :data:`CHUNK_ELEMENTS` matrix entries (sparse LU per frequency when M, D, K are sparse and
  n > :data:`N_FULL`). O(points n^3) dense: the reference, the choice of ``"auto"`` for tiny
  models (up to :data:`N_DIRECT` DOF, e.g. the three-mass rig) and the fallback of small ones.
- ``"reduced"``: for large meshes (chosen by ``"auto"`` above :data:`N_FULL` DOF). A Ritz basis
  ``V`` spans the undamped modes of ``(K_s, M)`` up to ``CUTOFF_FACTOR`` x the highest frequency
  asked for (shift-invert Lanczos on the sparse M, K), the static responses ``K^-1 [B, C^T, D Phi]``
  of the inputs, outputs and the damping/gyroscopic coupling of those modes, and one more Krylov
  level ``K^-1 [M W, D W]`` (modal truncation augmentation). The Galerkin model ``V^T (M, D, K) V``
  (m ~ 100, independent of the mesh) is then evaluated by ``"modal"`` (or ``"direct"`` when its own
  check fails). Measured against per-frequency dense solves of the 72-, 144- and 288-element rig
  (tests/fe, bench/bench_engine.py): the same to the conditioning of Z itself (~1e-9 relative at 72
  elements, where merely rescaling Z changes a dense solve by 3e-9).

Frequencies beyond the band a reduced basis was built for rebuild it. The state matrix
``A = [[0, I], [-M^-1 K, -M^-1 D]]`` of ``x = [q, q']`` is :func:`state_matrix` (modal analysis uses
the same one).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from rotorcheck.fe.blas import one_blas_thread
from rotorcheck.fe.dense import eigh_pencil
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.lazy import lazy_module

if TYPE_CHECKING:
    import scipy.linalg as sla
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
else:  # the reduced path of large meshes only: not loaded for the small models of every command
    sla = lazy_module("scipy.linalg")
    sp = lazy_module("scipy.sparse")
    spla = lazy_module("scipy.sparse.linalg")

__all__ = [
    "CUTOFF_FACTOR",
    "N_DIRECT",
    "N_FULL",
    "PartitionedFRF",
    "Receptance",
    "RitzBasis",
    "lowest_undamped_modes",
    "partitioned_system",
    "receptance",
    "ritz_basis",
    "state_matrix",
    "system_receptance",
]

TWO_PI = 2.0 * np.pi
Method = Literal["auto", "modal", "direct", "reduced", "solve"]  # "solve": former name of "direct"

#: largest model (DOF) that ``"auto"`` solves directly at every frequency (exact and cheaper than
#: any factorisation there)
N_DIRECT = 8
#: largest model (DOF) that ``"auto"`` treats with the full state-space eigendecomposition
N_FULL = 128
#: undamped modes up to this factor times the highest requested frequency span a reduced basis
CUTOFF_FACTOR = 10.0
#: largest number of complex entries of one evaluation chunk (bounds the engine's working memory)
CHUNK_ELEMENTS = 2_000_000
_CHECK_RTOL = 1e-9
_ORTH_TOL = 1e-8
_SHIFT = -1.0  # (rad/s)^2: shift-invert point of the undamped problem (K - shift M is definite)


def state_matrix(M: np.ndarray, D: np.ndarray, K: np.ndarray) -> np.ndarray:
    """First-order system matrix ``A = [[0, I], [-M^-1 K, -M^-1 D]]`` (2n, 2n) of ``x = [q, q']``."""
    n = M.shape[0]
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -np.linalg.solve(M, K)
    A[n:, n:] = -np.linalg.solve(M, D)
    return A


# --------------------------------------------------------------------------------------------
# reduced (Ritz) bases for large meshes


def _sparse(A: np.ndarray | sp.spmatrix) -> sp.csc_matrix:
    if isinstance(A, np.ndarray) or not sp.issparse(A):  # isinstance narrows the union for type checkers
        return sp.csc_matrix(np.asarray(A))
    return A.tocsc()


def _dense(A: np.ndarray | sp.spmatrix) -> np.ndarray:
    if isinstance(A, np.ndarray) or not sp.issparse(A):
        return np.asarray(A)
    return A.toarray()


def lowest_undamped_modes(
    M: np.ndarray | sp.spmatrix, K: np.ndarray | sp.spmatrix, f_max_hz: float = np.inf, min_count: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Undamped modes of ``(K_s, M)`` (K_s the symmetric part) up to ``f_max_hz`` and at least
    ``min_count`` of them: ``(w (rad/s) ascending, Phi (n, k))`` with ``Phi^T M Phi = I``.

    Shift-invert Lanczos on the sparse matrices (the number of modes grows until the band is
    covered); dense ``eigh`` for small models.
    """
    n = M.shape[0]
    w_max2 = (TWO_PI * f_max_hz) ** 2
    if n <= N_FULL:
        Md, Kd = _dense(M), _dense(K)
        lam, phi = sla.eigh(0.5 * (Kd + Kd.T), Md)
    else:
        Ms, Ks = _sparse(M), _sparse(K)
        Ksym = (0.5 * (Ks + Ks.T)).tocsc()
        k = min(max(16, int(min_count) + 4), n - 2)
        v0 = np.random.default_rng(0).standard_normal(n)  # deterministic Lanczos start
        while True:
            lam, phi = spla.eigsh(Ksym, k=k, M=Ms, sigma=_SHIFT, which="LM", v0=v0)
            order = np.argsort(lam)
            lam, phi = lam[order], phi[:, order]
            if (lam[-1] > w_max2 and k > min_count) or k >= n - 2:
                break
            k = min(2 * k, n - 2)
    keep = (lam <= w_max2) | (np.arange(lam.size) < min_count)
    return np.sqrt(np.clip(lam[keep], 0.0, None)), phi[:, keep]


def _orthonormal(blocks: Sequence[np.ndarray]) -> np.ndarray:
    """Orthonormal basis of the span of the columns (each normalised; rank-revealing QR)."""
    cols = [b / np.maximum(np.linalg.norm(b, axis=0), 1e-300) for b in blocks if b.size]
    V = np.hstack(cols)
    Q, R, _ = sla.qr(V, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    return Q[:, : int(np.count_nonzero(d > _ORTH_TOL * d[0]))]


def _real_columns(F: np.ndarray) -> np.ndarray:
    """Real and (nonzero) imaginary parts of complex columns, side by side."""
    F = np.asarray(F)
    if not np.iscomplexobj(F):
        return F
    im = F.imag[:, np.any(F.imag != 0, axis=0)]
    return np.hstack([F.real, im])


@dataclass(frozen=True)
class RitzBasis:
    """Orthonormal Ritz basis ``V`` (n, m) of a large model and the band it was built for (Hz)."""

    V: np.ndarray
    band_hz: float
    cutoff_hz: float
    n_modes: int  # undamped modes in the basis


def ritz_basis(
    M: np.ndarray,
    K: np.ndarray,
    couplings: Sequence[np.ndarray],
    vectors: Sequence[np.ndarray],
    band_hz: float,
    levels: int = 2,
) -> RitzBasis:
    """Ritz basis for the band ``[0, band_hz]`` (see the module docstring, ``"reduced"``).

    ``couplings``: the velocity matrices (n, n) that couple the undamped modes (damping, the
    gyroscopic matrix), ``vectors``: input and output vectors (n, k) whose static responses are
    included. ``levels``: Krylov levels of ``K^-1 [M, couplings]`` beyond the undamped modes.
    """
    cutoff = CUTOFF_FACTOR * max(float(band_hz), 1.0)
    Ms, Ks = _sparse(M), _sparse(K)
    _, phi = lowest_undamped_modes(Ms, Ks, cutoff, min_count=4)
    lu = spla.splu((Ks - _SHIFT * Ms).tocsc())
    F = np.hstack([_real_columns(v) for v in vectors] + [np.asarray(c) @ phi for c in couplings])
    blocks = [phi]
    W = lu.solve(F)
    blocks.append(W)
    for _ in range(levels - 1):
        W = _orthonormal([W])
        W = lu.solve(np.hstack([Ms @ W] + [np.asarray(c) @ W for c in couplings]))
        blocks.append(W)
    return RitzBasis(_orthonormal(blocks), float(band_hz), cutoff, phi.shape[1])


# --------------------------------------------------------------------------------------------
# the receptance


def _as_outputs(outputs: int | Sequence[int] | np.ndarray, n: int) -> tuple[np.ndarray | None, np.ndarray]:
    """(DOF indices or None, output matrix (n_out, n)) from DOF indices or output rows."""
    arr = np.asarray(outputs)
    if arr.ndim <= 1 and arr.dtype.kind in "iu":
        idx = np.atleast_1d(arr).astype(int)
        C = np.zeros((idx.size, n))
        C[np.arange(idx.size), idx] = 1.0
        return idx, C
    C = np.atleast_2d(arr)
    if C.shape[1] != n:
        raise ValueError(f"output rows need {n} columns, got {C.shape}")
    return None, C


def _as_inputs(inputs: int | Sequence[int] | np.ndarray, n: int) -> np.ndarray:
    """Force vectors (n, n_in) from DOF indices or vectors (n,)/(n, n_in)."""
    arr = np.asarray(inputs)
    if arr.ndim <= 1 and arr.dtype.kind in "iu":
        idx = np.atleast_1d(arr).astype(int)
        B = np.zeros((n, idx.size))
        B[idx, np.arange(idx.size)] = 1.0
        return B
    B = arr[:, None] if arr.ndim == 1 else arr
    if B.shape[0] != n:
        raise ValueError(f"input vectors need {n} rows, got {B.shape}")
    return B


def _modal_state(
    M: np.ndarray, D: np.ndarray, K: np.ndarray, eigh: Callable[..., tuple[np.ndarray, np.ndarray]] = eigh_pencil,
    closed_form_pairs: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The state matrix in energy-scaled undamped modal coordinates and its eigendecomposition.

    ``q = Phi W^-1 r1``, ``q' = Phi r2`` (``Phi`` the mass-normalised undamped modes of the Hermitian
    part of K, ``W = diag(w_i)``) is an exact change of variables of ``x = [q, q']`` that turns the
    state matrix into ``[[0, W], [-Phi^H K Phi W^-1, -Phi^H D Phi]]``, of norm ~ ``w_max`` instead of
    ``w_max^2``: its low eigenvalues and their vectors come out far more accurately (5e-10 -> 1e-12
    relative at a resonance of the 9-element rig). M, D, K real or complex (M Hermitian positive
    definite). ``eigh``: the generalized symmetric eigensolver of the undamped modes;
    ``closed_form_pairs``: take the closed form when D and K are diagonal in those modes.
    Returns ``(lambda (2n,), V (2n, 2n), Phi (n, n), w (n,))``.
    """
    n = M.shape[0]
    w2, phi = eigh(0.5 * (K + K.conj().T), M)
    w_max = np.sqrt(max(float(w2.max()), 1e-300))
    wn = np.sqrt(np.maximum(w2, (1e-6 * w_max) ** 2))
    ph = phi.conj().T
    Kt, Dt = ph @ K @ phi, ph @ D @ phi
    if closed_form_pairs and _is_diagonal(Dt) and _is_diagonal(Kt):
        # undamped modes that D does not couple (modal damping at rest): 2x2 blocks in closed form
        pair = _decoupled_pairs(np.diag(Kt) / wn, np.diag(Dt), wn)
        if pair is not None:
            return (*pair, phi, wn)
    A = np.zeros((2 * n, 2 * n), dtype=np.result_type(Kt, Dt))
    A[:n, n:] = np.diag(wn)
    A[n:, :n] = -Kt / wn[None, :]
    A[n:, n:] = -Dt
    lam, V = np.linalg.eig(A)
    return lam, V, phi, wn


#: off-diagonal entries of a modal matrix below this fraction of the geometric mean of their
#: diagonal entries count as round-off (they are 2e-12 for the modal damping of the crack rig)
_DIAG_RTOL = 1e-10


def _is_diagonal(X: np.ndarray) -> bool:
    off = np.abs(X)
    d = np.sqrt(np.diag(off))
    np.fill_diagonal(off, 0.0)
    return bool(np.all(off <= _DIAG_RTOL * np.outer(d, d)))


def _decoupled_pairs(
    k: np.ndarray, c: np.ndarray, wn: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """Eigenpairs of the state matrix ``[[0, diag(wn)], [-diag(k), -diag(c)]]`` in closed form:
    ``lambda^2 + c lambda + k wn = 0`` per mode, vectors ``[wn, lambda]``. None when a mode is
    (nearly) critically damped (its two vectors nearly parallel)."""
    n = wn.size
    disc = np.sqrt((c * c - 4.0 * k * wn).astype(complex))
    l1, l2 = 0.5 * (-c + disc), 0.5 * (-c - disc)
    if np.any(np.abs(l1 - l2) <= 1e-6 * np.maximum(np.abs(l1), np.abs(l2))):
        return None
    i = np.arange(n)
    V = np.zeros((2 * n, 2 * n), dtype=complex)
    V[i, i] = V[i, n + i] = wn
    V[n + i, i], V[n + i, n + i] = l1, l2
    return np.r_[l1, l2], V


def _scaled_modal_factors(
    M: np.ndarray, D: np.ndarray, K: np.ndarray, cols: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Eigendecomposition of the real state matrix in energy-scaled undamped modal coordinates:
    :func:`_modal_state` with scipy's ``eigh`` and no closed form (the simulator's truth rigs and the
    harmonic balance take this path, and the bundled samples are checked bit for bit against a
    regeneration). Returns
    ``(lambda (2n,), V (2n, 2n), V^-1 B (2n, c), Phi W^-1 (n, n))``:
    ``Z(nu)^-1 B = Phi W^-1 V[:n] diag(1/(j nu - lambda)) V^-1 [0; Phi^T B]``.
    """
    n = M.shape[0]
    lam, V, phi, wn = _modal_state(M, D, K, sla.eigh, closed_form_pairs=False)
    rhs = np.zeros((2 * n, cols.shape[1]), dtype=complex)
    rhs[n:] = phi.T @ cols
    return lam, V, np.linalg.solve(V, rhs), phi / wn[None, :]


#: a rotor's x/y plane map: ``(ix, iy, sign)`` with DOF ``iy[k]`` (times ``sign[k]``) the image of
#: DOF ``ix[k]`` under a quarter turn about the shaft axis (see :func:`_isotropic_half`)
Planes = tuple[np.ndarray, np.ndarray, np.ndarray]
#: largest deviation from isotropy (relative to the largest entry of each matrix) that
#: :func:`_isotropic_half` accepts: a few ulps (the assembled rig is isotropic bit for bit)
_ISO_TOL = 1e-14


def _isotropic_half(
    matrices: Sequence[np.ndarray], planes: Planes
) -> list[np.ndarray] | None:
    """The half-size complex matrices of an isotropic rotor, or None when it is not isotropic.

    With ``x = q[ix]`` and ``y = sign q[iy]`` every matrix ``X`` of an isotropic rotor (axisymmetric
    shaft and discs, equal supports in x and y; gyroscopic and cross-coupled terms allowed) has the
    form ``[[A, B], [-B, A]]``: it commutes with the quarter turn ``J = [[0, -I], [I, 0]]``. In the
    eigenvector basis ``[I; -jI] / sqrt 2``, ``[I; jI] / sqrt 2`` of J the dynamic stiffness is
    ``diag(Z1, Z2)`` with ``Z1 = A - jB`` (n/2 DOF, complex) and ``Z2(nu) = conj(Z1(-nu))``: one
    eigensolution of the n-state matrix of Z1 instead of the 2n-state real one (the same poles, as
    ``lambda`` and ``conj(lambda)``). Returns ``[A - jB for each X]`` (real when every B is 0).
    """
    ix, iy, sign = planes
    n = matrices[0].shape[0]
    m = ix.size
    if 2 * m != n or iy.size != m or np.unique(np.r_[ix, iy]).size != n:
        return None
    perm = np.r_[ix, iy]
    flip = np.r_[np.ones(m), sign]
    k = len(matrices)
    P = np.take(np.take(np.stack(matrices), perm, axis=1), perm, axis=2)  # (k, n, n) C-contiguous
    P *= flip[:, None] * flip[None, :]  # [[xx, xy], [yx, yy]] in the aligned coordinates
    xx, xy, yx, yy = P[:, :m, :m], P[:, :m, m:], P[:, m:, :m], P[:, m:, m:]
    tol = _ISO_TOL * np.abs(P).reshape(k, -1).max(axis=1)
    if np.any(np.abs(xx - yy).reshape(k, -1).max(axis=1) > tol) or np.any(
        np.abs(xy + yx).reshape(k, -1).max(axis=1) > tol
    ):
        return None
    a = 0.5 * (xx + yy)
    b = 0.5 * (xy - yx)
    return [a[i] - 1j * b[i] if np.any(b[i]) else a[i] for i in range(k)]


class Receptance:
    """``C Z(nu)^-1 B`` for many angular frequencies ``nu`` (rad/s): ``rec(nu) -> (..., n_out, n_in)``.

    ``M, D, K`` (n, n) with ``D = C + Omega G`` at the speed; ``outputs``: DOF indices or output rows
    (n_out, n); ``inputs``: DOF indices or force vectors (n, n_in) (complex allowed). ``band_hz``:
    the highest |frequency| that will be asked for (reduced bases are built for it; a wider call
    rebuilds). ``method``: see the module docstring; :attr:`method` is the one in use.
    """

    def __init__(
        self,
        M: np.ndarray,
        D: np.ndarray,
        K: np.ndarray,
        outputs: int | Sequence[int] | np.ndarray,
        inputs: int | Sequence[int] | np.ndarray,
        method: Method = "auto",
        band_hz: float | None = None,
        planes: Planes | None = None,
    ):
        if method == "solve":
            method = "direct"
        if method not in ("auto", "modal", "direct", "reduced"):
            raise ValueError(f"unknown method {method!r} (auto, modal, direct, reduced)")
        self.M, self.D, self.K = np.asarray(M), np.asarray(D), np.asarray(K)
        n = self.n = self.M.shape[0]
        self.rows, self.C = _as_outputs(outputs, n)
        self.cols = _as_inputs(inputs, n)
        self.band_hz = float(band_hz) if band_hz is not None else None
        self.planes = planes
        self._residues = False  # evaluate the modal sum by residues (see _modal)
        self._res: np.ndarray | None = None
        self.method: str = "direct"
        self._sparse_direct = n > N_FULL and all(
            np.count_nonzero(A) <= 0.05 * n * n for A in (self.M, self.D, self.K)
        )
        if method == "direct" or (method == "auto" and n <= N_DIRECT):
            return
        if method == "modal" or (method == "auto" and n <= N_FULL):
            with one_blas_thread():  # small dense problems: BLAS threads only synchronise
                done = self._setup_modal(check=method == "auto") or method == "modal"
            if done:
                return
            if n <= 64:
                return  # small: direct per-frequency solves are cheap and exact
        self.method = "reduced"
        if self.band_hz is not None:  # else built at the first call, for its frequencies
            self._setup_reduced(self.band_hz)

    # -- modal ---------------------------------------------------------------------------------
    def _setup_modal(self, check: bool) -> bool:
        try:
            half = (_isotropic_half((self.M, self.D, self.K), self.planes)
                    if self.planes is not None else None)
            if half is None:
                self._lam, self._left, self._right = self._modal_full()
            else:
                self._lam, self._left, self._right = self._modal_isotropic(*half)
            self._residues = half is not None
            self._res = None
        except np.linalg.LinAlgError:
            if not check:
                raise
            return False
        self.method = "modal"
        if check:
            mid = np.sort(np.abs(self._lam.imag))
            nu = np.array([[float(mid[mid.size // 2])]])
            ref = self._direct(nu)
            err = np.abs(self._modal(nu) - ref).max()
            if not np.isfinite(err) or err > _CHECK_RTOL * np.abs(ref).max():
                self.method = "direct"
                return False
        return True

    def _modal_full(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(poles (2n,), left (r, 2n), right (2n, c)) of the 2n-state system."""
        lam, V, right, out = _scaled_modal_factors(self.M, self.D, self.K, self.cols)
        left = (out[self.rows] if self.rows is not None else self.C @ out) @ V[: self.n]
        return lam, left, right

    def _modal_isotropic(
        self, Mh: np.ndarray, Dh: np.ndarray, Kh: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The same for an isotropic rotor from the half-size complex ``Z1`` (:func:`_isotropic_half`):

        ``C Z^-1 B = 1/2 [(Cx - jCy) Z1(nu)^-1 (Bx + jBy) + (Cx + jCy) conj(Z1(-nu)^-1) (Bx - jBy)]``
        (``Cx = C[:, ix]``, ``Cy = C[:, iy] sign``, ``Bx = B[ix]``, ``By = sign B[iy]``), the second
        term the conjugate of a modal sum of Z1 at ``-nu``: poles ``[lambda, conj(lambda)]``.
        """
        assert self.planes is not None
        ix, iy, sign = self.planes
        m = ix.size
        lam, V, phi, wn = _modal_state(Mh, Dh, Kh)
        Cx, Cy = self.C[:, ix], self.C[:, iy] * sign[None, :]
        Bx, By = self.cols[ix], sign[:, None] * self.cols[iy]
        c = Bx.shape[1]
        rhs = np.zeros((2 * m, 2 * c), dtype=complex)
        rhs[m:] = phi.conj().T @ np.hstack([Bx + 1j * By, Bx.conj() + 1j * By.conj()])
        R = np.linalg.solve(V, rhs)
        top = (phi / wn[None, :]) @ V[:m]  # (m, 2m)
        L1 = (Cx - 1j * Cy) @ top
        L2 = (Cx.conj() - 1j * Cy.conj()) @ top
        return (np.r_[lam, lam.conj()], 0.5 * np.hstack([L1, L2.conj()]),
                np.vstack([R[:, :c], R[:, c:].conj()]))

    def _modal(self, nu: np.ndarray) -> np.ndarray:
        shape = nu.shape
        flat = nu.reshape(-1)
        r, k = self._left.shape
        c = self._right.shape[1]
        out = np.empty((flat.size, r, c), dtype=complex)
        if self._residues and r * c * k <= CHUNK_ELEMENTS // 8:
            # few outputs x inputs: the residues (k, r c) once, then one product per chunk (the
            # isotropic path only: the full one keeps its summation order, bit for bit)
            res = self._res
            if res is None:
                res = self._res = (self._left.T[:, :, None] * self._right[:, None, :]).reshape(k, r * c)
            step = max(1, CHUNK_ELEMENTS // max(k + r * c, 1))
            for s in range(0, flat.size, step):
                d = 1.0 / (1j * flat[s : s + step, None] - self._lam)  # (chunk, k)
                out[s : s + step] = (d @ res).reshape(-1, r, c)
        else:
            step = max(1, CHUNK_ELEMENTS // max(r * k, 1))
            for s in range(0, flat.size, step):
                d = 1.0 / (1j * flat[s : s + step, None] - self._lam)  # (chunk, k)
                out[s : s + step] = np.matmul(self._left * d[:, None, :], self._right)
        return out.reshape(*shape, r, c)

    # -- direct --------------------------------------------------------------------------------
    def _select(self, x: np.ndarray) -> np.ndarray:
        return x[..., self.rows, :] if self.rows is not None else np.matmul(self.C, x)

    def _direct(self, nu: np.ndarray) -> np.ndarray:
        shape = nu.shape
        flat = nu.reshape(-1)
        n, c = self.n, self.cols.shape[1]
        out = np.empty((flat.size, self.C.shape[0], c), dtype=complex)
        if self._sparse_direct:
            Ms, Ds, Ks = (_sparse(A) for A in (self.M, self.D, self.K))
            for i, w in enumerate(flat):
                lu = spla.splu((Ks - w**2 * Ms + 1j * w * Ds).astype(complex).tocsc())
                out[i] = self._select(lu.solve(self.cols.astype(complex)))
            return out.reshape(*shape, *out.shape[1:])
        step = max(1, CHUNK_ELEMENTS // (n * n))
        for s in range(0, flat.size, step):
            w = flat[s : s + step]
            Z = self.K - (w**2)[:, None, None] * self.M + 1j * w[:, None, None] * self.D
            x = np.linalg.solve(Z, np.broadcast_to(self.cols, (w.size, *self.cols.shape)))
            out[s : s + step] = self._select(x)
        return out.reshape(*shape, *out.shape[1:])

    # -- reduced -------------------------------------------------------------------------------
    def _setup_reduced(self, band_hz: float | None) -> None:
        band = band_hz if band_hz is not None else 1000.0
        with one_blas_thread():  # Lanczos, sparse LU, tall-skinny products: threads do not pay
            basis = ritz_basis(self.M, self.K, [self.D], [self.cols, self.C.T], band)
            V = basis.V
            Mr, Dr, Kr = V.T @ self.M @ V, V.T @ self.D @ V, V.T @ self.K @ V
            Cr, Br = self.C @ V, V.T @ self.cols
        self._basis = basis
        direct = Receptance(Mr, Dr, Kr, Cr, Br, method="direct")
        self._reduced = direct
        try:
            modal: Receptance | None = Receptance(Mr, Dr, Kr, Cr, Br, method="modal")
        except np.linalg.LinAlgError:
            modal = None
        if modal is not None:
            nu = np.array([TWO_PI * band, 0.5 * TWO_PI * band])
            with one_blas_thread():
                ref = direct(nu)
                err = np.abs(modal(nu) - ref).max()
            if np.isfinite(err) and err <= _CHECK_RTOL * np.abs(ref).max():
                self._reduced = modal
        self.method = "reduced"
        self.band_hz = band

    # -- evaluation ----------------------------------------------------------------------------
    def ensure_band(self, band_hz: float) -> None:
        """Prepare for frequencies up to ``band_hz`` (Hz): a reduced basis is (re)built once here
        rather than at a later, wider call."""
        if self.method != "reduced":
            return
        if not hasattr(self, "_reduced"):
            self._setup_reduced(max(float(band_hz), self.band_hz or 0.0))
        elif self.band_hz is None or band_hz > self.band_hz * (1.0 + 1e-12):
            # a wider call: grow geometrically, so that a rising sweep rebuilds O(log) times
            self._setup_reduced(max(float(band_hz), 2.0 * (self.band_hz or 0.0)))

    def __call__(self, nu: np.ndarray | float) -> np.ndarray:
        """(..., n_out, n_in) complex (m/N for unit forces) at angular frequencies ``nu`` (rad/s)."""
        nu = np.asarray(nu, dtype=float)
        if self.method == "reduced":
            self.ensure_band(float(np.max(np.abs(nu))) / TWO_PI if nu.size else 0.0)
            return self._reduced(nu)
        if self.method == "direct" and self.n > N_FULL:
            return self._direct(nu)  # large dense solves: leave BLAS its threads
        with one_blas_thread():
            return self._modal(nu) if self.method == "modal" else self._direct(nu)

    def at_hz(self, freq_hz: np.ndarray | float) -> np.ndarray:
        """The receptance at frequencies in Hz (``rec(2 pi f)``)."""
        return self(TWO_PI * np.asarray(freq_hz, dtype=float))


def system_receptance(
    system: MechanicalSystem,
    speed_rpm: float,
    outputs: int | Sequence[int] | np.ndarray,
    inputs: int | Sequence[int] | np.ndarray,
    method: Method = "auto",
    band_hz: float | None = None,
) -> Receptance:
    """The :class:`Receptance` of ``system`` at ``speed_rpm`` (``D = C + Omega G``)."""
    M, C, G, K = system.matrices(speed_rpm)
    planes = system.plane_pairs() if system.kind == "rotor" else None
    return Receptance(M, C + speed_rpm * RPM_TO_RAD_S * G, K, outputs, inputs, method, band_hz, planes)


def _dofs(d: int | Sequence[int] | np.ndarray | None, n: int) -> np.ndarray:
    if d is None:
        return np.arange(n)
    return np.atleast_1d(np.asarray(d, dtype=int))


def receptance(
    system: MechanicalSystem,
    freq_hz: np.ndarray | Sequence[float] | float,
    speed_rpm: float = 0.0,
    out_dofs: int | Sequence[int] | np.ndarray | None = None,
    in_dofs: int | Sequence[int] | np.ndarray | None = None,
    method: Method = "auto",
) -> np.ndarray:
    """Receptance H (f, n_out, n_in), complex, m/N, from input forces to output displacements.

    ``out_dofs``/``in_dofs``: global DOF indices (see ``MechanicalSystem.dof``/``port_dof``); None
    means all DOF.
    """
    n = system.n_dof
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    band = float(np.max(np.abs(f))) if f.size else None
    rec = system_receptance(system, speed_rpm, _dofs(out_dofs, n), _dofs(in_dofs, n), method, band)
    return rec.at_hz(f)


@dataclass(frozen=True)
class PartitionedFRF:
    """Engineering system at each frequency (method.md): all (f, ., .) complex, m/N.

    ``E11 = H_dd`` (damage port to itself), ``E12 = H_d,in``, ``E21 = H_out,d``, ``E22 = H_out,in``.
    """

    frequency_hz: np.ndarray
    E11: np.ndarray
    E12: np.ndarray
    E21: np.ndarray
    E22: np.ndarray

    def block(self) -> np.ndarray:
        """The full (f, n_d + n_out, n_d + n_in) matrix [[E11, E12], [E21, E22]]."""
        top = np.concatenate([self.E11, self.E12], axis=2)
        bottom = np.concatenate([self.E21, self.E22], axis=2)
        return np.concatenate([top, bottom], axis=1)


def partitioned_system(
    system: MechanicalSystem,
    freq_hz: np.ndarray | Sequence[float],
    speed_rpm: float,
    damage_dofs: int | Sequence[int],
    in_dofs: int | Sequence[int],
    out_dofs: int | Sequence[int],
    method: Method = "auto",
) -> PartitionedFRF:
    """E11..E22 from one receptance evaluation (outputs [damage, out], inputs [damage, in])."""
    d = np.atleast_1d(np.asarray(damage_dofs, dtype=int))
    i = np.atleast_1d(np.asarray(in_dofs, dtype=int))
    o = np.atleast_1d(np.asarray(out_dofs, dtype=int))
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    H = receptance(system, f, speed_rpm, np.r_[d, o], np.r_[d, i], method=method)
    nd = d.size
    return PartitionedFRF(
        frequency_hz=f,
        E11=H[:, :nd, :nd],
        E12=H[:, :nd, nd:],
        E21=H[:, nd:, :nd],
        E22=H[:, nd:, nd:],
    )
