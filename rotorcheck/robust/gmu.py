"""Generalized structured singular value bound as an LMI per frequency (cvxpy + Clarabel).

Validation problem at one frequency (dissertation eq. 3.1-3.6, method.md): the uncertain model
``z = F_u(Me, Delta_u) W + v`` explains the data ``Zt`` iff there are ``|Delta_u| <= gamma``,
``|v_k| <= V`` with zero residual. As an implicit LFT in ``x = (u, e, t)`` (``u`` the outputs of
the uncertainty blocks, ``e`` the normalized noise, ``t`` the homogeneous multiplier of the data)::

    block i:  input A_i x = (Me11 u + Me12 W t)_i,  output B_i x = u_i,   |Delta_i| <= w_i gamma
    noise k:  input t,                                output e_k,          |Delta_v,k| <= 1
    kernel:   N x = (Zt - Me22 W) t - Me21 u - V e = 0            (V in the residual row)

Certificate of invalidation (S-procedure on the kernel, P an orthonormal basis of Ker N)::

    P^* ( sum_i D_i-scaled( r_i^2 A_i^* A_i - B_i^* B_i ) ) P  < 0

with scalar ``d_i >= 0`` for complex scalar and full blocks and a Hermitian PSD ``D_i`` for
repeated complex scalar blocks (``delta I_k``). With one uncertainty block (scalar or full) its
scale is fixed to 1 and ``gamma^2 = s`` enters linearly: ONE SDP per frequency,
``maximize s  s.t.  P^*(s F_u + F_0 + sum d_k F_k) P <= 0``. Several uncertainty blocks sharing one
gamma, or a repeated-scalar uncertainty block, give a generalized eigenvalue problem; it is solved by
bisection on ``s`` with an LMI feasibility problem (minimize lambda) at each step (documented
exception to the one-SDP rule).

Bounds, per frequency (what each number certifies):

* ``gamma_lower``: every gamma below it is *proven* invalidated. It is recomputed from the solver's
  D-scales by an eigenvalue computation (``max s`` with ``s F_u + G(d) < 0``), so it does not rely on
  the solver's reported objective.
* ``gamma_upper``: the size of an explicit structured ``Delta`` (built from the kernel vector of the
  optimal LMI, then polished by Gauss-Newton) that reproduces the data within the noise bound,
  checked by evaluating ``F_u(Me, Delta) W`` directly.

So ``gamma_lower <= gamma_required <= gamma_upper``. (In mu language the LMI is the upper bound on
mu and the explicit Delta the lower bound; in gamma = 1/mu the roles swap.) For SISO (two complex
scalar blocks) the relaxation is exact and the gap is below 1e-7 relative (the explicit Delta is
accepted as soon as it is within 1e-7 of the certificate). With several blocks the explicit Delta is
additionally refined by a local SQP (gap ~1e-9 on the tests).

Numerics (method.md's pitfalls and what the tests showed):

* per-frequency scaling: residual rows by ``max(|c_k|, V)`` (``c = Zt - Me22 W``), u-columns by
  ``max|c| / ||Me21||``, gamma by an estimate (the noise-free answer, an exact generalized
  eigenvalue, shrunk by ``(|c| - V) / |c|``), noise D-scales by ``(V/|c|)((|c| - V)/|c|)`` (their
  value at the optimum for additive SISO; without it a tiny V stalls Clarabel);
* near gamma* = 0 (``|c|`` barely above V) the worst case is a near-cancellation; the SDP is then
  posed in a kernel basis adapted to it (first the heuristic "noise aligned with the residual", after
  a pass the LMI's own worst-case vector) and re-solved: a second pass, as method.md says;
* pre-checks ``|Zt - Me22 W| <= V`` (gamma = 0, no solve) and ``Me12 W = 0`` or ``Me21 = 0``
  (status 'unexplainable', gamma = inf, never a number);
* explicit projection onto Ker N (no free multiplier); no chordal decomposition; one thread;
* solver status point by point: the D-scales of every solver answer are projected onto their
  cones before the certificate is checked (a stalled iterate returns scales of about -1e-7 for
  noise blocks inactive at the optimum; with them the "certified" lower bound exceeded the exact
  answer by up to 4e-7 relative and points failed); Clarabel's 'InsufficientProgress' /
  'AlmostSolved' iterates are used if the independently verified bounds agree within 1e-6, else
  the point is re-solved by bisection on the same LMI (method 'sdp+bisect');
* per point, never the batch: non-finite Me, W or Zt -> 'bad_data'; a solver raising (also a
  ``BaseException`` such as Clarabel's pyo3 ``PanicException``) or a point exceeding
  ``time_limit`` seconds (passed to Clarabel as its ``time_limit``) -> 'solver_failed' with the
  reason in ``GammaResult.reason``; a negative or NaN noise bound is a ``ValueError``;
* accuracy floor: gamma* is a function of ``|c| - V``; the data determine it only to about
  ``eps |Zt| / (|c| - V)`` relative (1e-6 at ``(|c| - V)/|c| ~ 1e-7`` with ``|Zt| ~ 1e3 |c|``).

Backends: 'cvxpy' builds each LMI once per shape with cvxpy Parameters and re-solves it per
frequency; 'clarabel' (the default) fills the identical conic data (real embedding, Clarabel's
scaled upper-triangle PSD vectorization, a fixed sparsity pattern reused across solves) and calls
Clarabel directly, skipping cvxpy's per-solve canonicalization. Both give the same bounds (to about
1e-10 relative) and statuses.

SISO fast path (one output, one complex scalar uncertainty block, V > 0): the per-point numpy of
the first pass (pre-checks, gamma estimate, kernel bases, projected forms, certificate check,
explicit Delta and its Gauss-Newton polish) is batched over the frequencies; only the Clarabel calls
remain per point. Every point that needs more than the plain first pass (near-cancellation basis,
rescaled second pass, a stalled solve whose verified bounds do not close within 1e-7, the SQP
refinement) is recomputed by the per-point path, so the results are those of the per-point
algorithm up to rounding.

Units: gamma in the units of Delta_u (m/N for additive receptance uncertainty, kg for a mass
parameter, dimensionless for multiplicative); V in m (output displacement).
"""

from __future__ import annotations

import contextlib
import contextvars
import copy
import time
import warnings
from collections.abc import Callable, Collection, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from rotorcheck.robust.lft import as_freq_matrix

__all__ = [
    "Block",
    "GammaResult",
    "ImplicitBound",
    "Structure",
    "check_noise_bound",
    "implicit_lmi_bound",
    "inject_solver_failure",
    "required_gamma",
    "required_gamma_bisection",
]

STATUS_OK = "ok"
STATUS_FAILED = "solver_failed"
STATUS_UNEXPLAINABLE = "unexplainable"
STATUS_LOWER_ONLY = "lower_only"
STATUS_BAD_DATA = "bad_data"
# seconds of solver time per frequency point (every Clarabel call gets the point's remaining budget
# as its ``time_limit``); a point that exhausts it is 'solver_failed' with the reason
DEFAULT_TIME_LIMIT = 10.0

_INJECTED: set[int] = set()


@contextlib.contextmanager
def inject_solver_failure(indices: Collection[int]) -> Iterator[None]:
    """Testing hook: inside the ``with`` block every gamma computation treats the frequency indices
    ``indices`` as if the solver had failed there (status 'solver_failed', gamma NaN)."""
    old = set(_INJECTED)
    _INJECTED.update(int(i) for i in indices)
    try:
        yield
    finally:
        _INJECTED.clear()
        _INJECTED.update(old)


# --------------------------------------------------------------------------------------------------
# structure


@dataclass(frozen=True)
class Block:
    """One uncertainty block ``Delta_i`` mapping ``v_i`` (``shape[1]``) to ``u_i`` (``shape[0]``).

    ``kind``: 'scalar' (complex scalar, 1x1), 'repeated' (``delta I_k``, ``shape=(k, k)``) or
    'full' (complex matrix). Its bound is ``sigma_max(Delta_i) <= weight * gamma``.
    """

    kind: str = "full"
    shape: tuple[int, int] = (1, 1)
    weight: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in ("scalar", "repeated", "full"):
            raise ValueError(f"unknown block kind {self.kind!r}")
        if self.kind == "scalar" and tuple(self.shape) != (1, 1):
            raise ValueError("a scalar block has shape (1, 1)")
        if self.kind == "repeated" and self.shape[0] != self.shape[1]:
            raise ValueError("a repeated scalar block is square")
        if self.weight <= 0:
            raise ValueError("block weight must be positive")

    @property
    def lmi_kind(self) -> str:
        """'full' (scalar D-scale) or 'repeated' (Hermitian D-scale)."""
        return "repeated" if self.kind == "repeated" and self.shape[0] > 1 else "full"


@dataclass(frozen=True)
class Structure:
    """Uncertainty structure: the blocks of ``Delta_u`` (in the order of Me's Delta channel) and the
    noise model. ``blocks=None`` means one full block spanning the whole channel (for SISO a complex
    scalar). ``noise='per_output'``: ``|v_k| <= V`` for each output (independent scalars);
    ``'euclidean'``: ``||v||_2 <= V``.
    """

    blocks: tuple[Block, ...] | None = None
    noise: str = "per_output"

    def __post_init__(self) -> None:
        if self.noise not in ("per_output", "euclidean"):
            raise ValueError(f"noise must be 'per_output' or 'euclidean', got {self.noise!r}")

    @staticmethod
    def full() -> Structure:
        """One full complex block (a complex scalar for SISO additive / multiplicative)."""
        return Structure()

    @staticmethod
    def repeated(k: int) -> Structure:
        """One repeated complex scalar ``delta I_k`` (a parameter entering with rank k)."""
        return Structure((Block("repeated" if k > 1 else "scalar", (k, k)),))

    def resolve(self, nu: int, nv: int) -> tuple[Block, ...]:
        """Blocks checked against the Delta channel size (``nu`` outputs, ``nv`` inputs)."""
        if self.blocks is None:
            kind = "scalar" if (nu, nv) == (1, 1) else "full"
            return (Block(kind, (nu, nv)),)
        su = sum(b.shape[0] for b in self.blocks)
        sv = sum(b.shape[1] for b in self.blocks)
        if (su, sv) != (nu, nv):
            raise ValueError(f"blocks cover ({su}, {sv}) but Me's Delta channel is ({nu}, {nv})")
        return self.blocks


@dataclass
class GammaResult:
    """Per-frequency bounds on the required gamma (units of Delta_u), all arrays of shape (f,).

    ``status``: 'ok' | 'unexplainable' (no finite gamma explains the data; bounds = inf) |
    'solver_failed' (bounds NaN; ``reason`` says why when known: the solver raised, e.g. Clarabel's
    PanicException, or the point's time limit ran out) | 'bad_data' (Me, W or Zt not finite at that
    point: nothing to solve, bounds NaN) | 'lower_only' (certified lower bound, no explicit Delta
    found; upper NaN). ``method``: 'precheck' | 'eig' | 'sdp' | 'bisection' | 'sdp+bisect' (a
    stalled SDP re-solved by bisection on the same LMI) | '' per point. ``reason``: '' or a
    one-line explanation per point.
    """

    gamma_lower: np.ndarray
    gamma_upper: np.ndarray
    status: np.ndarray
    n_solver_calls: int
    method: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U12"))
    delta: list[list[np.ndarray] | None] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    reason: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))

    @property
    def gamma(self) -> np.ndarray:
        """The gamma that provably explains the data (``gamma_upper``)."""
        return self.gamma_upper

    @property
    def rel_gap(self) -> np.ndarray:
        """``(upper - lower) / upper`` (0 where both are 0)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            g = (self.gamma_upper - self.gamma_lower) / self.gamma_upper
        return np.where(self.gamma_upper == 0, 0.0, g)


# --------------------------------------------------------------------------------------------------
# small linear algebra helpers


def _emb(H: np.ndarray) -> np.ndarray:
    """Real symmetric embedding of a Hermitian matrix (same eigenvalues, each twice)."""
    m = H.shape[0]
    out = np.empty((2 * m, 2 * m))
    out[:m, :m] = out[m:, m:] = H.real
    out[m:, :m] = H.imag
    out[:m, m:] = -H.imag
    return out


def _herm_basis(k: int) -> list[np.ndarray]:
    """Real basis of the k x k Hermitian matrices (diagonal units first)."""
    out = []
    for i in range(k):
        E = np.zeros((k, k), complex)
        E[i, i] = 1
        out.append(E)
    for i in range(k):
        for j in range(i + 1, k):
            E = np.zeros((k, k), complex)
            E[i, j] = E[j, i] = 1
            out.append(E)
            F = np.zeros((k, k), complex)
            F[i, j], F[j, i] = 1j, -1j
            out.append(F)
    return out


def _kernel(N: np.ndarray, rtol: float = 1e-11) -> np.ndarray:
    """Orthonormal basis (n, m) of Ker N by SVD."""
    n = N.shape[1]
    if N.shape[0] == 0:
        return np.eye(n, dtype=complex)
    _, sv, Vh = np.linalg.svd(N)
    rank = int(np.sum(sv > rtol * max(sv[0], 1e-300)))
    return Vh[rank:].conj().T


def _max_s(G: np.ndarray, Fu: np.ndarray) -> float:
    """Largest s with ``s Fu + G < 0`` (Hermitian, ``Fu >= 0``): rigorous certificate check.

    Returns -1 if ``G`` itself is not negative definite (no certificate at s = 0)."""
    G = 0.5 * (G + G.conj().T)
    try:
        Lc = np.linalg.cholesky(-G)
    except np.linalg.LinAlgError:
        return -1.0
    Li = np.linalg.inv(Lc)  # tiny matrices: plain inverse of the triangular factor
    Y = Li @ Fu @ Li.conj().T
    lam = np.linalg.eigvalsh(0.5 * (Y + Y.conj().T))
    top = lam[-1]
    return np.inf if top <= 0 else 1.0 / top


def _top_eigvec(Q: np.ndarray) -> np.ndarray:
    _, U = np.linalg.eigh(0.5 * (Q + Q.conj().T))
    return U[:, -1]


# --------------------------------------------------------------------------------------------------
# LMI solvers: the cvxpy problems are built once per shape signature (cvxpy Parameters) and
# re-solved with new values per frequency; the 'clarabel' backend fills the same conic data directly
# (real embedding, Clarabel's scaled upper-triangle PSD vectorization) and calls Clarabel, skipping
# cvxpy's per-solve canonicalization. Both solve exactly the same LMI.

_SOLVER_OPTS: dict[str, object] = {"chordal_decomposition_enable": False, "max_threads": 1}
# Clarabel's 'InsufficientProgress' still returns its last iterate; every bound is verified
# independently, so such a point is accepted only if the verified gap stays below _INACCURATE_GAP
_CVXPY_ONLY_OPTS: dict[str, object] = {"accept_unknown": True}
_INACCURATE_GAP = 1e-6
# second-pass triggers: s~ = (gamma / gamma estimate)^2 outside _S_RANGE, or a worst-case vector whose
# u-part is below _ADAPT_RHO of its norm (near-cancellation); _NEAR_ZERO: excess/residual scale below
# which the first pass already uses the adapted kernel basis
_S_RANGE = (1e-2, 1e2)
_ADAPT_RHO = 1e-2
_NEAR_ZERO = 1e-1
BACKENDS = ("cvxpy", "clarabel")
DEFAULT_BACKEND = "clarabel"
# SISO points: the per-point numpy batched over the frequencies (False: every point through _point;
# a switch for tests that compare both)
_SISO_BATCH = True


@dataclass
class _LmiOut:
    status: str  # 'optimal' | 'inaccurate' | 'unbounded' | 'failed' | 'aborted'
    value: float = np.nan  # s (max problem) or lambda (feasibility problem)
    theta: list[np.ndarray] = field(default_factory=list)  # D-scale coordinates per variable block
    dual: np.ndarray | None = None  # complex m x m dual of the main LMI
    reason: str = ""  # why the point was aborted
    seconds: float = 0.0  # wall time of the point's call (batched first pass)


# --------------------------------------------------------------------------------------------------
# per-point guard: every solver call runs under the budget of the point it belongs to


class _SolverAbort(Exception):
    """A solver call raised something that is not an ordinary error (Clarabel's
    ``pyo3_runtime.PanicException`` derives from ``BaseException``), or the point's time budget ran
    out: the point is reported 'solver_failed' with this reason and not retried."""


@dataclass
class _Budget:
    deadline: float  # time.perf_counter() value
    seconds: float  # the point's whole budget (for the message)


_BUDGET: contextvars.ContextVar[_Budget | None] = contextvars.ContextVar("gmu_point_budget",
                                                                         default=None)


@contextlib.contextmanager
def _point_budget(seconds: float) -> Iterator[None]:
    """Solver calls inside the block share ``seconds`` of wall time (one frequency point)."""
    token = _BUDGET.set(_Budget(time.perf_counter() + seconds, seconds))
    try:
        yield
    finally:
        _BUDGET.reset(token)


def _guarded_call(call: Callable[[float], object]) -> object:
    """``call(time_limit)`` under the current point's budget.

    ``time_limit`` is the point's remaining time (Clarabel's ``time_limit`` setting). Ordinary
    exceptions pass through (the callers treat them as a failed solve). A ``BaseException`` that is
    not ``KeyboardInterrupt``/``SystemExit``/``GeneratorExit`` (a Rust panic surfacing through pyo3),
    an exhausted budget, or a call that returns after the deadline raises :class:`_SolverAbort`."""
    budget = _BUDGET.get()
    if budget is None:
        remaining = DEFAULT_TIME_LIMIT
    else:
        remaining = budget.deadline - time.perf_counter()
        if remaining <= 0:
            raise _SolverAbort(f"time limit of {budget.seconds:g} s per point exhausted")
    try:
        out = call(remaining)
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except Exception:
        raise
    except BaseException as exc:  # pyo3 panics derive from BaseException
        raise _SolverAbort(f"solver raised {type(exc).__name__}: {exc}") from exc
    if budget is not None and time.perf_counter() > budget.deadline:
        raise _SolverAbort(f"time limit of {budget.seconds:g} s per point exceeded")
    return out


def _guarded_point(solve: Callable[[], _LmiOut], seconds: float) -> _LmiOut:
    """One point's call of the batched first pass: its own budget; an abort becomes an
    'aborted' result with the reason instead of ending the batch."""
    t0 = time.perf_counter()
    try:
        with _point_budget(seconds):
            out = solve()
    except _SolverAbort as exc:
        out = _LmiOut("aborted", reason=str(exc))
    out.seconds = time.perf_counter() - t0
    return out


def _project_scales(theta: list[np.ndarray], blocks: Sequence[tuple[str, int]]
                    ) -> list[np.ndarray]:
    """D-scale coordinates projected onto their cones (``d >= 0``; Hermitian ``D >= 0`` for a
    repeated block, coordinates in the :func:`_herm_basis` order).

    An interior point iterate that stopped early ('InsufficientProgress', 'AlmostSolved') can sit
    slightly outside the cone (``d ~ -1e-7`` for a noise block that is inactive at the optimum).
    The S-procedure certifies nothing with a negative scale, so every certificate is verified with
    the projected scales; both backends return them through here."""
    out = []
    for th, (kind, k) in zip(theta, blocks, strict=True):
        th = np.asarray(th, dtype=float).reshape(-1)
        if kind == "full" or k == 1:
            out.append(np.maximum(th, 0.0))
            continue
        D = sum((t * H for t, H in zip(th, _herm_basis(k), strict=True)),
                np.zeros((k, k), complex))
        lam, U = np.linalg.eigh(0.5 * (D + D.conj().T))
        D = (U * np.maximum(lam, 0.0)) @ U.conj().T
        iu, ju = np.triu_indices(k, 1)
        out.append(np.concatenate([np.diag(D).real,
                                   np.stack([D[iu, ju].real, D[iu, ju].imag], 1).reshape(-1)]))
    return out


def _complexify(Xm: np.ndarray, m: int) -> np.ndarray:
    """Hermitian m x m matrix closest to a real 2m x 2m embedding."""
    return 0.5 * (Xm[:m, :m] + Xm[m:, m:]) + 0.5j * (Xm[m:, :m] - Xm[:m, m:])


class _CvxpyLmi:
    """``opt s.t. s Gs + G0 + sum_l theta_l G_l <= 0`` in the real embedding.

    kind 'maxs': maximize s (s a variable). kind 'feas': s is folded into the data, minimize
    lambda with ``G0 + sum theta G - lambda I <= 0``; ``fix_first`` is handled by the caller (the
    fixed block is part of G0), then ``lambda >= -1``, else ``sum trace(D) = 1``.
    """

    def __init__(self, kind: str, m: int, blocks: tuple[tuple[str, int], ...], normalize: bool):
        dim = 2 * m
        self.kind = kind
        self.G0 = cp.Parameter((dim, dim), symmetric=True)
        self.var = cp.Variable()
        if kind == "maxs":
            self.Gs = cp.Parameter((dim, dim), symmetric=True)
            expr = self.var * self.Gs + self.G0
        else:
            expr = self.G0 - self.var * np.eye(dim)
        cons: list[cp.Constraint] = []
        self.blocks = blocks
        self.thetas: list[cp.Variable] = []
        self.params: list[list[cp.Parameter]] = []
        traces = []
        for bkind, k in blocks:
            nb = 1 if bkind == "full" else k * k
            th = cp.Variable(nb)
            ps = [cp.Parameter((dim, dim), symmetric=True) for _ in range(nb)]
            for j in range(nb):
                expr = expr + th[j] * ps[j]
            if bkind == "full":
                cons.append(th >= 0)
                traces.append(th[0])
            else:
                embs = [_emb(H) for H in _herm_basis(k)]
                cons.append(sum(th[j] * embs[j] for j in range(nb)) >> 0)
                traces.append(cp.sum(th[:k]))
            self.thetas.append(th)
            self.params.append(ps)
        if kind == "feas":
            cons.append(sum(traces) == 1 if normalize else self.var >= -1)
        self.lmi = expr << 0
        obj = cp.Maximize(self.var) if kind == "maxs" else cp.Minimize(self.var)
        self.problem = cp.Problem(obj, [*cons, self.lmi])

    def solve(self, G0: np.ndarray, Gs: np.ndarray | None, terms: list[list[np.ndarray]],
              timing: dict[str, float]) -> _LmiOut:
        self.G0.value = _emb(G0)
        if self.kind == "maxs" and Gs is not None:
            self.Gs.value = _emb(Gs)
        for ps, ts in zip(self.params, terms, strict=True):
            for p, T in zip(ps, ts, strict=True):
                p.value = _emb(T)
        t0 = time.perf_counter()

        def run(limit: float) -> str:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                self.problem.solve(solver=cp.CLARABEL, warm_start=False, time_limit=limit,
                                   **_SOLVER_OPTS, **_CVXPY_ONLY_OPTS)
            return str(self.problem.status)

        try:
            status = str(_guarded_call(run))
        except (cp.SolverError, ValueError, ArithmeticError):
            status = "error"
        timing["solve_total"] = timing.get("solve_total", 0.0) + time.perf_counter() - t0
        st = self.problem.solver_stats
        if st is not None and st.solve_time is not None:
            timing["clarabel"] = timing.get("clarabel", 0.0) + float(st.solve_time)
        if status in ("unbounded", "unbounded_inaccurate"):
            return _LmiOut("unbounded")
        if status not in ("optimal", "optimal_inaccurate") or self.var.value is None:
            return _LmiOut("failed")
        if any(th.value is None for th in self.thetas):
            return _LmiOut("failed")
        theta = _project_scales([np.asarray(th.value, dtype=float).reshape(-1)
                                 for th in self.thetas], self.blocks)
        X = self.lmi.dual_value
        m = G0.shape[0]
        dual = _complexify(np.asarray(X), m) if X is not None else None
        flag = "optimal" if status == "optimal" else "inaccurate"
        return _LmiOut(flag, float(self.var.value), theta, dual)


class _ClarabelLmi:
    """The same LMI as :class:`_CvxpyLmi` (scalar D-scales only), conic data filled directly.

    Variables ``z = (var, theta_1..K)``; cones: K nonnegative (theta), [feas: 1 zero (normalization)
    or 1 nonnegative (lambda >= -1)], PSD triangle of size 2m for ``-(LMI expression)``.
    """

    def __init__(self, kind: str, m: int, n_theta: int, normalize: bool):
        import clarabel  # imported lazily: a dependency of cvxpy's Clarabel interface anyway

        self.clarabel = clarabel
        self.kind, self.m, self.K, self.normalize = kind, m, n_theta, normalize
        dim = 2 * m
        iu, ju = np.triu_indices(dim)
        order = np.lexsort((iu, ju))  # column-wise upper triangle
        self.iu, self.ju = iu[order], ju[order]
        self.wsv = np.where(self.iu == self.ju, 1.0, np.sqrt(2.0))
        self.nsv = self.iu.size
        nz = 1 + n_theta
        self.q = np.zeros(nz)
        self.q[0] = -1.0 if kind == "maxs" else 1.0
        self.P = sp.csc_matrix((nz, nz))
        cones = []
        self.n_lin = n_theta
        if n_theta:
            cones.append(clarabel.NonnegativeConeT(n_theta))
        self.extra = 0
        if kind == "feas":
            self.extra = 1
            cones.append(clarabel.ZeroConeT(1) if normalize else clarabel.NonnegativeConeT(1))
        cones.append(clarabel.PSDTriangleConeT(dim))
        self.cones = cones
        st = clarabel.DefaultSettings()
        st.verbose = False
        for key, val in _SOLVER_OPTS.items():
            setattr(st, key, val)
        self.settings = st
        self.eye_sv = self._svec(np.eye(dim))
        # svec(emb(H)) straight from the complex H: entry (i, j) of the embedding is
        # +-Re/Im H[i mod m, j mod m]; precompute the gather index and the signs
        bi, bj = self.iu // m, self.ju // m
        ii, jj = self.iu % m, self.ju % m
        use_imag = bi != bj
        self.gidx = np.where(use_imag, m * m, 0) + ii * m + jj
        self.gsgn = np.where(use_imag & (bi == 0), -1.0, 1.0) * self.wsv
        # fixed sparsity pattern of A: every entry that can be nonzero (the imaginary part of a
        # Hermitian diagonal is structurally zero). The CSC index arrays are built once; per solve
        # only the values are gathered from the dense fill into a reused matrix object. A value that
        # happens to be exactly zero falls back to the plain conversion (zeros dropped as before).
        self.r0 = n_theta + self.extra
        rows = self.r0 + self.nsv
        self.rows = rows
        var_psd = ~(use_imag & (ii == jj))
        pat = np.zeros((rows, nz), dtype=bool)
        if n_theta:
            pat[:n_theta, 1:] = np.eye(n_theta, dtype=bool)
        if kind == "feas":
            if normalize:
                pat[n_theta, 1:] = True
            else:
                pat[n_theta, 0] = True
            pat[self.r0:, 0] = self.eye_sv != 0
        else:
            pat[self.r0:, 0] = var_psd
        pat[self.r0:, 1:] = var_psd[:, None]
        self.pat_r, self.pat_c = np.nonzero(pat.T)[::-1]  # column-major order (CSC)
        self.A_csc = sp.csc_matrix(pat.astype(float))
        self.A_csc.sort_indices()
        self.A_dense = np.zeros((rows, nz))  # template; its fixed entries are set once
        if n_theta:
            self.A_dense[:n_theta, 1:] = -np.eye(n_theta)
        if kind == "feas":
            if normalize:
                self.A_dense[n_theta, 1:] = 1.0
            else:  # lambda >= -1: slack = 1 + lambda
                self.A_dense[n_theta, 0] = -1.0
            self.A_dense[self.r0:, 0] = -self.eye_sv
        self.b0 = np.zeros(rows)
        if kind == "feas":
            self.b0[n_theta] = 1.0

    def _svec_emb_many(self, H: np.ndarray) -> np.ndarray:
        """``_svec_emb`` of a stack (f, m, m) of Hermitian matrices, shape (f, nsv)."""
        f = H.shape[0]
        flat = np.concatenate([H.real.reshape(f, -1), H.imag.reshape(f, -1)], axis=1)
        return flat[:, self.gidx] * self.gsgn

    def _matrix(self, A: np.ndarray) -> sp.csc_matrix:
        data = A[self.pat_r, self.pat_c]
        if not np.all(data != 0):
            return sp.csc_matrix(A)
        self.A_csc.data = data
        return self.A_csc

    def _call(self, A: sp.csc_matrix, b: np.ndarray, timing: dict[str, float]
              ) -> tuple[str, np.ndarray | None, np.ndarray | None]:
        t0 = time.perf_counter()

        def run(limit: float) -> object:
            self.settings.time_limit = float(limit)
            solver = self.clarabel.DefaultSolver(self.P, self.q, A, b, self.cones, self.settings)
            return solver.solve()

        sol: Any
        try:
            sol = _guarded_call(run)
            status = str(sol.status)
        except (ValueError, RuntimeError, ArithmeticError):
            status = "error"
            sol = None
        dt = time.perf_counter() - t0
        timing["solve_total"] = timing.get("solve_total", 0.0) + dt
        if status == "MaxTime":
            raise _SolverAbort("Clarabel stopped at the time limit of the point")
        if sol is None:
            return status, None, None
        timing["clarabel"] = timing.get("clarabel", 0.0) + float(sol.solve_time)
        return status, np.asarray(sol.x), np.asarray(sol.z)

    def _svec_emb(self, H: np.ndarray) -> np.ndarray:
        flat = np.concatenate([H.real.ravel(), H.imag.ravel()])
        return flat[self.gidx] * self.gsgn

    def _svec(self, S: np.ndarray) -> np.ndarray:
        return S[self.iu, self.ju] * self.wsv

    def _smat(self, v: np.ndarray) -> np.ndarray:
        dim = 2 * self.m
        S = np.zeros((dim, dim))
        S[self.iu, self.ju] = v / self.wsv
        S[self.ju, self.iu] = v / self.wsv
        return S

    def solve(self, G0: np.ndarray, Gs: np.ndarray | None, terms: list[list[np.ndarray]],
              timing: dict[str, float]) -> _LmiOut:
        r0 = self.r0
        A = self.A_dense.copy()
        b = self.b0.copy()
        if self.kind != "feas":
            assert Gs is not None
            A[r0:, 0] = self._svec_emb(Gs)
        for j, ts in enumerate(terms):
            A[r0:, 1 + j] = self._svec_emb(ts[0])
        b[r0:] = -self._svec_emb(G0)
        status, x, z = self._call(self._matrix(A), b, timing)
        return self._result(status, x, z)

    def solve_many(self, G0: np.ndarray, Gs: np.ndarray, T: np.ndarray, timing: dict[str, float],
                   time_limit: float = DEFAULT_TIME_LIMIT) -> list[_LmiOut]:
        """``solve`` for a stack of 'maxs' problems with one D-scale each: G0, Gs, T of shape
        (f, m, m). The conic data of all points are filled at once; one Clarabel call per point,
        each under its own budget (:func:`_guarded_point`)."""
        assert self.kind == "maxs" and self.K == 1
        f, r0 = G0.shape[0], self.r0
        A = np.broadcast_to(self.A_dense, (f, *self.A_dense.shape)).copy()
        A[:, r0:, 0] = self._svec_emb_many(Gs)
        A[:, r0:, 1] = self._svec_emb_many(T)
        b = np.zeros((f, self.rows))
        b[:, r0:] = -self._svec_emb_many(G0)
        data = A[:, self.pat_r, self.pat_c]
        dense_ok = np.all(data != 0, axis=1)
        out = []
        for i in range(f):
            if dense_ok[i]:
                self.A_csc.data = data[i]
                Ai = self.A_csc
            else:
                Ai = sp.csc_matrix(A[i])
            out.append(_guarded_point(lambda Ai=Ai, bi=b[i]: self._result(*self._call(Ai, bi, timing)),
                                      time_limit))
        return out

    def _result(self, status: str, x: np.ndarray | None, z: np.ndarray | None) -> _LmiOut:
        K, r0 = self.K, self.r0
        if status in ("DualInfeasible", "AlmostDualInfeasible"):
            return _LmiOut("unbounded")
        ok = ("Solved",)
        usable = ("AlmostSolved", "InsufficientProgress", "MaxIterations")
        if x is None or z is None or status not in ok + usable:
            return _LmiOut("failed")
        if x.size != 1 + K or not np.all(np.isfinite(x)):
            return _LmiOut("failed")
        theta = _project_scales([np.array([x[1 + j]]) for j in range(K)], [("full", 1)] * K)
        dual = _complexify(self._smat(z[r0:]), self.m) if np.all(np.isfinite(z)) else None
        return _LmiOut("optimal" if status in ok else "inaccurate", float(x[0]), theta, dual)


_CACHE: dict[tuple, _CvxpyLmi | _ClarabelLmi] = {}


def _lmi(backend: str, kind: str, m: int, blocks: tuple[tuple[str, int], ...], normalize: bool
         ) -> _CvxpyLmi | _ClarabelLmi:
    use_direct = backend == "clarabel" and all(k == "full" for k, _ in blocks)
    key = ("clarabel" if use_direct else "cvxpy", kind, m, blocks, normalize)
    if key not in _CACHE:
        if use_direct:
            _CACHE[key] = _ClarabelLmi(kind, m, len(blocks), normalize)
        else:
            _CACHE[key] = _CvxpyLmi(kind, m, blocks, normalize)
    return _CACHE[key]


# --------------------------------------------------------------------------------------------------
# one frequency point, scaled implicit LFT


@dataclass
class _Forms:
    """Projected quadratic forms of one point on Ker N (kernel coordinates y, x = P y)."""

    P: np.ndarray
    gamma_blocks: list[tuple[str, int, np.ndarray, np.ndarray]]  # (lmi kind, k, Ap, Bp)
    fixed_blocks: list[tuple[str, int, np.ndarray, np.ndarray]]  # radius 1 folded in


def _block_terms(kind: str, k: int, Ap: np.ndarray, Bp: np.ndarray, s: float | None
                 ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Hermitian m x m terms of one block: returns (A-parts, B-parts) per D-scale basis element;
    the block's contribution is ``sum_l theta_l (r^2 A_l - B_l)``."""
    if kind == "full":
        return [Ap.conj().T @ Ap], [Bp.conj().T @ Bp]
    As, Bs = [], []
    for H in _herm_basis(k):
        As.append(Ap.conj().T @ H @ Ap)
        Bs.append(Bp.conj().T @ H @ Bp)
    return As, Bs


@dataclass
class _EngineOut:
    status: str  # 'ok' | 'unbounded' | 'failed'
    s_lower: float = 0.0  # verified, scaled units
    candidates: list[np.ndarray] = field(default_factory=list)  # kernel-space x (scaled coords)
    calls: int = 0
    method: str = ""
    y: np.ndarray | None = None  # kernel coordinates of the worst-case vector (basis fm.P)
    theta: list[float] = field(default_factory=list)  # scales of the fixed (noise) blocks
    inaccurate: bool = False  # the solver did not report success; bounds verified independently


def _engine_eig(fm: _Forms) -> _EngineOut:
    """One full uncertainty block, no free scales: max s with s Ah - Bh <= 0 is a generalized
    eigenvalue problem, solved exactly (no solver call)."""
    _, _, Ap, Bp = fm.gamma_blocks[0]
    Ah = Ap.conj().T @ Ap
    Bh = Bp.conj().T @ Bp
    m = Ah.shape[0]
    if m == 1:
        a, b = Ah[0, 0].real, Bh[0, 0].real
        if a <= 0:
            return _EngineOut("unbounded", method="eig")
        return _EngineOut("ok", b / a, [fm.P[:, 0]], method="eig")
    w, U = sla.eig(Bh, Ah)
    finite = np.isfinite(w) & (np.abs(w.imag) <= 1e-9 * np.maximum(1.0, np.abs(w.real)))
    if not np.any(finite):
        return _EngineOut("unbounded", method="eig")
    idx = np.flatnonzero(finite)[np.argmin(w.real[finite])]
    s = max(float(w.real[idx]), 0.0)
    return _EngineOut("ok", s, [fm.P @ U[:, idx]], method="eig")


def _engine_sdp(fm: _Forms, timing: dict[str, float], backend: str) -> _EngineOut:
    """One uncertainty block (scale fixed to 1) plus noise blocks: one SDP, maximize s."""
    _, _, Ap, Bp = fm.gamma_blocks[0]
    sig = tuple((kind, k) for kind, k, _, _ in fm.fixed_blocks)
    Fu = Ap.conj().T @ Ap
    F0 = -(Bp.conj().T @ Bp)
    fixed_terms: list[list[np.ndarray]] = []
    for kind, k, Ak, Bk in fm.fixed_blocks:
        As, Bs = _block_terms(kind, k, Ak, Bk, None)
        fixed_terms.append([a - b for a, b in zip(As, Bs, strict=True)])
    res = _lmi(backend, "maxs", fm.P.shape[1], sig, False).solve(F0, Fu, fixed_terms, timing)
    if res.status not in ("optimal", "inaccurate"):
        return _EngineOut("unbounded" if res.status == "unbounded" else "failed", calls=1,
                          method="sdp")
    G = F0.copy()
    theta: list[float] = []
    for th, terms in zip(res.theta, fixed_terms, strict=True):
        theta.append(float(th[0]) if len(terms) == 1 else np.nan)
        for j, T in enumerate(terms):
            G = G + float(th[j]) * T
    s_cert = _max_s(G, Fu)
    if s_cert < 0:
        s_cert = 0.0  # no strict certificate: only the trivial bound
    cands = []
    y = None
    if np.isfinite(s_cert):
        y = _top_eigvec(s_cert * Fu + G)
        cands.append(fm.P @ y)
    if res.dual is not None:
        cands.append(fm.P @ _top_eigvec(res.dual))
    return _EngineOut("ok", s_cert, cands, calls=1, method="sdp", y=y, theta=theta,
                      inaccurate=res.status == "inaccurate")


def _feas_terms(fm: _Forms, s: float, fix_first: bool
                ) -> tuple[np.ndarray, list[list[np.ndarray]], list[list[np.ndarray]]]:
    """(G_fix, per-variable-block terms at s, per-variable-block A-parts) for the feasibility LMI."""
    m = fm.P.shape[1]
    Gfix = np.zeros((m, m), complex)
    var_terms: list[list[np.ndarray]] = []
    var_a: list[list[np.ndarray]] = []
    for idx, (kind, k, Ap, Bp) in enumerate(fm.gamma_blocks):
        As, Bs = _block_terms(kind, k, Ap, Bp, s)
        terms = [s * a - b for a, b in zip(As, Bs, strict=True)]
        if fix_first and idx == 0:
            Gfix = terms[0]
            continue
        var_terms.append(terms)
        var_a.append(As)
    for kind, k, Ap, Bp in fm.fixed_blocks:
        As, Bs = _block_terms(kind, k, Ap, Bp, None)
        var_terms.append([a - b for a, b in zip(As, Bs, strict=True)])
        var_a.append([np.zeros((m, m), complex)] * len(As))
    return Gfix, var_terms, var_a


def _feasible(fm: _Forms, s: float, fix_first: bool, timing: dict[str, float], backend: str
              ) -> tuple[str, float, np.ndarray | None, np.ndarray | None]:
    """Certificate at s? Returns (status, verified lambda_max, Q(theta) at s, Fa(theta))."""
    m = fm.P.shape[1]
    blocks = [(kind, k) for kind, k, _, _ in fm.gamma_blocks]
    blocks = blocks[1:] if fix_first else blocks
    sig = tuple(blocks) + tuple((kind, k) for kind, k, _, _ in fm.fixed_blocks)
    Gfix, var_terms, var_a = _feas_terms(fm, s, fix_first)
    res = _lmi(backend, "feas", m, sig, not fix_first).solve(Gfix, None, var_terms, timing)
    if res.status not in ("optimal", "inaccurate"):
        return "failed", np.inf, None, None
    Q = Gfix.copy()
    Fa = np.zeros((m, m), complex)
    if fix_first:
        Fa = fm.gamma_blocks[0][2].conj().T @ fm.gamma_blocks[0][2]
    for th, terms, As in zip(res.theta, var_terms, var_a, strict=True):
        for j, (T, A) in enumerate(zip(terms, As, strict=True)):
            Q = Q + float(th[j]) * T
            Fa = Fa + float(th[j]) * A
    lam = float(np.linalg.eigvalsh(0.5 * (Q + Q.conj().T))[-1])
    return "ok", lam, Q, Fa


def _engine_bisection(fm: _Forms, timing: dict[str, float], rtol: float, fix_first: bool,
                      backend: str) -> _EngineOut:
    """Bisection on s with the feasibility LMI (GEVP for several blocks / repeated scalars)."""
    calls = 0
    # s = 0 must be certified (data outside the noise set); otherwise only the trivial bound
    st, lam, Q, Fa = _feasible(fm, 0.0, fix_first, timing, backend)
    calls += 1
    if st != "ok":
        return _EngineOut("failed", calls=calls, method="bisection")
    if lam >= 0:
        return _EngineOut("ok", 0.0, [fm.P @ _top_eigvec(Q)], calls, "bisection")
    lo, best = 0.0, (Q, Fa)
    hi = 1.0
    while True:
        st, lam, Q, Fa = _feasible(fm, hi, fix_first, timing, backend)
        calls += 1
        if st != "ok":
            return _EngineOut("failed", calls=calls, method="bisection")
        if lam >= 0:
            break
        lo, best = hi, (Q, Fa)
        hi *= 4.0
        if hi > 1e30:
            return _EngineOut("unbounded", calls=calls, method="bisection")
    # bisection on gamma = sqrt(s)
    while np.sqrt(hi) - np.sqrt(lo) > rtol * np.sqrt(hi):
        mid = (0.5 * (np.sqrt(lo) + np.sqrt(hi))) ** 2
        st, lam, Q, Fa = _feasible(fm, mid, fix_first, timing, backend)
        calls += 1
        if st != "ok":
            return _EngineOut("failed", calls=calls, method="bisection")
        if lam < 0:
            lo, best = mid, (Q, Fa)
        else:
            hi = mid
    Qb, Fab = best
    # the certificate at lo is affine in s for fixed scales: extend it exactly
    s_cert = lo
    if Qb is not None and Fab is not None:
        ext = _max_s(Qb - lo * Fab, Fab)
        if ext > lo:
            s_cert = float(ext)
    assert Qb is not None and Fab is not None
    Qs = (Qb - lo * Fab + s_cert * Fab) if np.isfinite(s_cert) else Qb
    return _EngineOut("ok", s_cert, [fm.P @ _top_eigvec(Qs)], calls, "bisection")


# --------------------------------------------------------------------------------------------------
# the Me-level pipeline


@dataclass
class _Layout:
    blocks: tuple[Block, ...]
    u_slices: list[slice]
    v_slices: list[slice]
    nu: int
    nv: int
    n_in: int
    n_out: int


def _layout(me: np.ndarray, n_in: int, n_out: int, structure: Structure) -> _Layout:
    nv = me.shape[1] - n_out
    nu = me.shape[2] - n_in
    if nv < 0 or nu < 0:
        raise ValueError(f"Me shape {me.shape[1:]} too small for {n_out} outputs, {n_in} inputs")
    blocks = structure.resolve(nu, nv)
    us, vs, ou, ov = [], [], 0, 0
    for b in blocks:
        us.append(slice(ou, ou + b.shape[0]))
        vs.append(slice(ov, ov + b.shape[1]))
        ou += b.shape[0]
        ov += b.shape[1]
    return _Layout(blocks, us, vs, nu, nv, n_in, n_out)


def _noise_ok(r: np.ndarray, V: float, noise: str, scale: np.ndarray, rtol: float = 0.0,
              atol: float = 8 * np.finfo(float).eps) -> bool:
    """Residual inside the noise set, up to floating-point rounding of its evaluation."""
    if noise == "per_output":
        return bool(np.all(np.abs(r) <= V * (1 + rtol) + atol * scale))
    return bool(np.linalg.norm(r) <= V * (1 + rtol) + atol * float(np.max(scale)))


def _project_noise(r: np.ndarray, V: float, noise: str) -> np.ndarray:
    shrink = 1 - 2 * np.finfo(float).eps
    if noise == "per_output":
        a = np.abs(r)
        f = np.where(a > V * shrink, V * shrink / np.where(a > 0, a, 1), 1.0)
        return r * f
    nr = np.linalg.norm(r)
    return r if nr <= V * shrink else r * (V * shrink / nr)


class _PointModel:
    """Me, W, Zt, V at one frequency and the Delta <-> output map."""

    def __init__(self, me: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: float, lay: _Layout,
                 noise: str):
        self.lay = lay
        self.noise = noise
        nv, nu = lay.nv, lay.nu
        self.M11, self.M12 = me[:nv, :nu], me[:nv, nu:]
        self.M21, self.M22 = me[nv:, :nu], me[nv:, nu:]
        self.W, self.Zt, self.V = W, Zt, V
        self.c = Zt - self.M22 @ W
        self.M12W = self.M12 @ W
        # residuals are evaluated as c - (z - Me22 W); c (the data) is rounded once, here
        self.scale = np.maximum(np.abs(self.c), V)

    def delta_matrix(self, deltas: list[np.ndarray]) -> np.ndarray:
        if len(deltas) == 1:
            return deltas[0]
        return sla.block_diag(*deltas) if deltas else np.zeros((0, 0), complex)

    def evaluate(self, D: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(r, v, L) for a full Delta matrix: r = Zt - F_u(Me, D) W evaluated as
        ``c - Me21 D v``, v the Delta input, L = Me21 (I - D Me11)^-1."""
        nv, nu = self.lay.nv, self.lay.nu
        v = np.linalg.solve(np.eye(nv) - self.M11 @ D, self.M12W)
        L = np.linalg.solve((np.eye(nu) - D @ self.M11).T, self.M21.T).T
        return self.c - self.M21 @ (D @ v), v, L

    def gamma_of(self, deltas: list[np.ndarray]) -> float:
        g = 0.0
        for b, d in zip(self.lay.blocks, deltas, strict=True):
            nrm = abs(d[0, 0]) if b.kind in ("scalar", "repeated") else np.linalg.norm(d, 2)
            g = max(g, float(nrm) / b.weight)
        return g

    def deltas_from_x(self, x: np.ndarray) -> list[np.ndarray] | None:
        """Structured Delta from an (unscaled) kernel vector x = (u, e, t)."""
        lay = self.lay
        t = x[-1]
        if not np.isfinite(t) or abs(t) <= 1e-13 * np.linalg.norm(x):
            return None
        u = x[: lay.nu] / t
        v = self.M11 @ u + self.M12W
        out = []
        for b, us, vs in zip(lay.blocks, lay.u_slices, lay.v_slices, strict=True):
            ui, vi = u[us], v[vs]
            nv2 = float(np.vdot(vi, vi).real)
            if nv2 == 0.0:
                if np.linalg.norm(ui) > 0:
                    return None
                out.append(np.zeros(b.shape, complex))
                continue
            if b.kind in ("scalar", "repeated"):
                delta = np.vdot(vi, ui) / nv2
                out.append(delta * np.eye(b.shape[0], dtype=complex))
            else:
                out.append(np.outer(ui, vi.conj()) / nv2)
        return out

    def refine(self, deltas: list[np.ndarray]) -> list[np.ndarray] | None:
        """Local SQP on the block values (scalar and repeated blocks only): minimize the largest
        ``|delta_i| / w_i`` keeping the residual in the noise set, from a verified start. Used to
        tighten gamma_upper where the kernel-vector construction left a gap (bisection, GEVP)."""
        from scipy.optimize import minimize

        lay = self.lay
        if any(b.kind == "full" and b.shape != (1, 1) for b in lay.blocks):
            return None
        w = np.array([b.weight for b in lay.blocks])
        th0 = np.array([d[0, 0] for d in deltas])
        g0 = self.gamma_of(deltas)
        if not np.isfinite(g0) or g0 == 0:
            return None
        nb = th0.size
        sc = float(np.max(self.scale)) if self.V == 0 else self.V

        def mats(x: np.ndarray) -> list[np.ndarray]:
            th = g0 * (x[:nb] + 1j * x[nb: 2 * nb])
            return [t * np.eye(b.shape[0], dtype=complex) for t, b in zip(th, lay.blocks,
                                                                            strict=True)]

        def resid(x: np.ndarray) -> np.ndarray:
            try:
                return self.evaluate(self.delta_matrix(mats(x)))[0] / sc
            except np.linalg.LinAlgError:
                return np.full(lay.n_out, 1e3 + 0j)

        cons: list[dict[str, object]] = [
            {"type": "ineq", "fun": lambda x: x[-1] * w**2 - (x[:nb] ** 2 + x[nb: 2 * nb] ** 2)}]
        if self.V == 0:
            cons.append({"type": "eq",
                         "fun": lambda x: np.concatenate([resid(x).real, resid(x).imag])})
        elif self.noise == "per_output":
            cons.append({"type": "ineq", "fun": lambda x: 1.0 - np.abs(resid(x)) ** 2})
        else:
            cons.append({"type": "ineq", "fun": lambda x: 1.0 - float(np.sum(np.abs(resid(x)) ** 2))})
        x0 = np.concatenate([th0.real / g0, th0.imag / g0, [1.0]])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = minimize(lambda x: x[-1], x0, method="SLSQP", constraints=cons,
                           options={"ftol": 1e-15, "maxiter": 200})
        if not np.all(np.isfinite(res.x)):
            return None
        d1 = self.polish(mats(res.x))
        if d1 is None or self.gamma_of(d1) >= g0:
            return None
        return d1

    def polish(self, deltas: list[np.ndarray], iters: int = 8) -> list[np.ndarray] | None:
        """Gauss-Newton on the Delta parameters until the residual lies in the noise set."""
        lay = self.lay
        deltas = [d.copy() for d in deltas]
        for _ in range(iters + 1):
            D = self.delta_matrix(deltas)
            try:
                r, v, L = self.evaluate(D)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(r)):
                return None
            if _noise_ok(r, self.V, self.noise, self.scale):
                return deltas
            dz = r - _project_noise(r, self.V, self.noise)
            cols, where = [], []
            for bi, (b, us, vs) in enumerate(zip(lay.blocks, lay.u_slices, lay.v_slices,
                                                 strict=True)):
                Lb, vb = L[:, us], v[vs]
                if b.kind in ("scalar", "repeated"):
                    cols.append(Lb @ vb)
                    where.append((bi, -1, -1))
                else:
                    for a in range(b.shape[0]):
                        for c in range(b.shape[1]):
                            cols.append(Lb[:, a] * vb[c])
                            where.append((bi, a, c))
            J = np.stack(cols, axis=1)
            if self.V == 0:
                step = np.linalg.lstsq(J, dz, rcond=None)[0]  # r must vanish: complex equations
            else:
                # |r_k| <= V is one REAL constraint per output (per_output) or one in total
                # (euclidean): linearize d|r| = -Re(conj(r^) J dtheta) on the active ones and take
                # the minimum-norm real step
                if self.noise == "per_output":
                    act = np.abs(r) > self.V * (1 - 1e-9)
                    a_rows = (np.conj(r[act]) / np.abs(r[act]))[:, None] * J[act]
                    rhs = np.abs(r[act]) - np.abs(r[act] - dz[act])
                else:
                    nr = float(np.linalg.norm(r))
                    a_rows = (r.conj() / nr)[None, :] @ J
                    rhs = np.array([nr - float(np.linalg.norm(r - dz))])
                Ar = np.concatenate([a_rows.real, -a_rows.imag], axis=1)
                xr = np.linalg.lstsq(Ar, rhs, rcond=None)[0]
                n_par = J.shape[1]
                step = xr[:n_par] + 1j * xr[n_par:]
            for val, (bi, a, c) in zip(step, where, strict=True):
                if a < 0:
                    deltas[bi] = deltas[bi] + val * np.eye(deltas[bi].shape[0])
                else:
                    deltas[bi][a, c] += val
        return None


def _adapted_basis(P0: np.ndarray, x: np.ndarray, nu: int) -> np.ndarray | None:
    """Kernel basis ``[x / |u(x)|, complement]`` (x a kernel vector in scaled coordinates)."""
    nu_out = float(np.linalg.norm(x[:nu]))
    if not np.isfinite(nu_out) or nu_out == 0.0:
        return None
    y = P0.conj().T @ x
    ny = float(np.linalg.norm(y))
    if ny == 0.0:
        return None
    Uc = np.linalg.svd((y / ny).conj()[None, :])[2][1:].conj().T
    return np.concatenate([x[:, None] / nu_out, P0 @ Uc], axis=1)


def _heuristic_x(pm: _PointModel, S: np.ndarray) -> np.ndarray | None:
    """Worst-case guess in scaled coordinates: noise aligned with the residual (as large as the bound
    allows), u the least-squares rest. Exact for additive SISO."""
    V, c = pm.V, pm.c
    a = np.abs(c)
    if pm.noise == "per_output":
        e = np.where(a > 0, c / np.where(a > 0, a, 1) * np.minimum(1.0, a / V), 0)
    else:
        nc = float(np.linalg.norm(c))
        e = c / nc * min(1.0, nc / V) if nc > 0 else np.zeros_like(c)
    u = np.linalg.lstsq(pm.M21, c - V * e, rcond=None)[0]
    x = np.concatenate([u, e, [1.0]])
    return x / S


def _scaled_forms(pm: _PointModel, ghat: float, basis: np.ndarray | None = None,
                  kappa: Sequence[float] | None = None) -> tuple[_Forms, np.ndarray]:
    """Scaled implicit LFT on its kernel; returns the forms and the column scaling S (x = S x~).

    ``basis``: kernel basis to use instead of the orthonormal one (second pass); ``kappa``: scale
    factors of the noise blocks' D-scales (so that the new scales are about 1)."""
    lay = pm.lay
    V, c = pm.V, pm.c
    n_out = lay.n_out
    sig = np.maximum(np.abs(c), V)
    sig_max = float(np.max(sig)) if sig.size else 1.0
    sig = np.where(sig > 0, sig, sig_max if sig_max > 0 else 1.0)
    su = np.ones(lay.nu)
    for us in lay.u_slices:
        nrm = np.linalg.norm(pm.M21[:, us], 2)
        su[us] = sig_max / nrm if nrm > 0 else 1.0
    n_e = n_out if V > 0 else 0
    n = lay.nu + n_e + 1
    S = np.concatenate([su, np.ones(n_e), [1.0]])
    # kernel rows, scaled by 1/sigma_k
    N = np.zeros((n_out, n), complex)
    N[:, : lay.nu] = -pm.M21 * su[None, :]
    if n_e:
        N[:, lay.nu: lay.nu + n_e] = -V * np.eye(n_out)
    N[:, -1] = c
    N = N / sig[:, None]
    P = _kernel(N) if basis is None else basis
    # v rows in scaled coordinates: v = M11 S_u u~ + M12 W t
    Arow = np.zeros((lay.nv, n), complex)
    Arow[:, : lay.nu] = pm.M11 * su[None, :]
    Arow[:, -1] = pm.M12W
    gamma_blocks = []
    for b, us, vs in zip(lay.blocks, lay.u_slices, lay.v_slices, strict=True):
        s_i = su[us][0]
        A = (ghat * b.weight / s_i) * Arow[vs]
        B = np.zeros((b.shape[0], n), complex)
        B[:, us] = np.eye(b.shape[0])
        k = b.shape[0]
        gamma_blocks.append((b.lmi_kind, k, A @ P, B @ P))
    fixed_blocks: list[tuple[str, int, np.ndarray, np.ndarray]] = []
    if n_e:
        et = np.zeros((1, n), complex)
        et[0, -1] = 1.0
        if pm.noise == "per_output":
            for kk in range(n_out):
                B = np.zeros((1, n), complex)
                B[0, lay.nu + kk] = 1.0
                fixed_blocks.append(("full", 1, et @ P, B @ P))
        else:
            B = np.zeros((n_out, n), complex)
            B[:, lay.nu: lay.nu + n_out] = np.eye(n_out)
            fixed_blocks.append(("full", 1, et @ P, B @ P))
    if kappa is not None:
        fixed_blocks = [(kd, k, np.sqrt(kp) * A, np.sqrt(kp) * B)
                        for (kd, k, A, B), kp in zip(fixed_blocks, kappa, strict=True)]
    return _Forms(P, gamma_blocks, fixed_blocks), S


def _upper_from(pm: _PointModel, cands: list[np.ndarray], lower: float, upper: float,
                best: list[np.ndarray] | None) -> tuple[float, list[np.ndarray] | None]:
    """Smallest verified explicit Delta among kernel-vector candidates (in order of trust: the
    eigenvector of the certificate first, then the dual); stops once within 1e-7 of ``lower``."""
    for x in cands:
        if upper <= lower * (1 + 1e-7):
            break
        d0 = pm.deltas_from_x(x)
        if d0 is None:
            continue
        d1 = pm.polish(d0)
        if d1 is None:
            continue
        g = pm.gamma_of(d1)
        if g < upper:
            upper, best = g, d1
    return upper, best


def _point(pm: _PointModel, mode: str, rtol: float, timing: dict[str, float], backend: str
           ) -> tuple[float, float, str, int, str, list[np.ndarray] | None]:
    """(lower, upper, status, solver calls, method, Delta blocks) at one frequency."""
    lay = pm.lay
    V, c = pm.V, pm.c
    # pre-check 1: the nominal model explains the data within the noise
    if _noise_ok(c, V, pm.noise, pm.scale, rtol=0.0, atol=0.0):
        return 0.0, 0.0, STATUS_OK, 0, "precheck", [np.zeros(b.shape, complex) for b in lay.blocks]
    # pre-check 2: the uncertainty cannot move the output
    b_est = 0.0
    for b, us, vs in zip(lay.blocks, lay.u_slices, lay.v_slices, strict=True):
        b_est = max(b_est, b.weight * np.linalg.norm(pm.M21[:, us], 2)
                    * np.linalg.norm(pm.M12W[vs]))
    if not np.isfinite(b_est) or b_est == 0.0:
        return np.inf, np.inf, STATUS_UNEXPLAINABLE, 0, "precheck", None
    if pm.noise == "per_output":
        excess = float(np.max(np.abs(c) - V))
    else:
        excess = float(np.linalg.norm(c) - V)
    sig_max = float(np.max(np.maximum(np.abs(c), V)))
    ghat = max(excess, 1e-14 * sig_max) / b_est
    single = len(lay.blocks) == 1 and lay.blocks[0].lmi_kind == "full"
    if single and V > 0:
        # better gamma scale: the noise-free answer (an exact generalized eigenvalue, no solver)
        # shrunk by the excess of the residual over the noise (exact for additive SISO)
        pm0 = copy.copy(pm)
        pm0.V = 0.0
        out0 = _engine_eig(_scaled_forms(pm0, ghat)[0])
        if out0.status == "ok" and np.isfinite(out0.s_lower) and out0.s_lower > 0:
            ghat = ghat * np.sqrt(out0.s_lower) * max(excess, 1e-14 * sig_max) / sig_max

    calls = 0
    lower = 0.0
    cands: list[np.ndarray] = []
    method = ""
    basis: np.ndarray | None = None
    kappa: list[float] | None = None
    upper: float = np.inf
    best: list[np.ndarray] | None = None
    use_sdp = mode != "bisection" and single and V > 0
    inaccurate = False
    if use_sdp:
        # noise D-scales are about (V / sigma)(excess / sigma) at the optimum (exact for additive
        # SISO): scale them to ~1 so a tiny noise block does not stall the interior point method
        kap = max(V / sig_max * max(excess, 0.0) / sig_max, 1e-12)
        kappa = [kap] * (lay.n_out if pm.noise == "per_output" else 1)
    fm0, S = _scaled_forms(pm, ghat, None, kappa)
    P0 = fm0.P  # orthonormal kernel basis (scaled coordinates); independent of ghat
    if use_sdp and excess < _NEAR_ZERO * sig_max:
        # gamma* far below the residual scale: start in a kernel basis adapted to the heuristic
        # worst case (noise aligned with the residual), D-scales of the noise scaled to ~1
        x0 = _heuristic_x(pm, S)
        if x0 is not None:
            basis = _adapted_basis(P0, P0 @ (P0.conj().T @ x0), lay.nu)
            if basis is not None:
                eps = max(excess / sig_max, 1e-12)
                kappa = [eps] * len(fm0.fixed_blocks)
    for _pass in range(3):
        fm = fm0 if (_pass == 0 and basis is None) else _scaled_forms(pm, ghat, basis, kappa)[0]
        if mode == "bisection" or not single:
            out = _engine_bisection(fm, timing, rtol, single, backend)
        elif not fm.fixed_blocks:
            out = _engine_eig(fm)
        else:
            out = _engine_sdp(fm, timing, backend)
        calls += out.calls
        method = out.method
        inaccurate = inaccurate or out.inaccurate
        if out.status == "unbounded" and basis is None:
            return np.inf, np.inf, STATUS_UNEXPLAINABLE, calls, method, None
        if out.status != "ok":
            if lower > 0 or cands:
                break  # keep the verified results of an earlier pass
            if basis is not None and _pass < 2:
                basis, kappa, fm0 = None, None, _scaled_forms(pm, ghat)[0]  # retry, plain basis
                continue
            if not use_sdp:
                return np.nan, np.nan, STATUS_FAILED, calls, method, None
            inaccurate = True  # no verified result at all: the bisection fallback below
            break
        lower = max(lower, ghat * np.sqrt(out.s_lower)) if np.isfinite(out.s_lower) else np.inf
        cands = [S * x for x in out.candidates] + cands  # latest pass first
        s = out.s_lower
        if out.method != "sdp" or not np.isfinite(s) or out.y is None or _pass == 2:
            break
        # next pass: rescale gamma by this answer and, when the worst-case vector is a
        # near-cancellation (gamma* << the residual scale), use a kernel basis adapted to it
        x1 = fm.P @ out.y
        nu_out = float(np.linalg.norm(x1[: lay.nu]))
        rho = nu_out / max(float(np.linalg.norm(x1)), 1e-300)
        if out.inaccurate:
            # the solver stalled but its iterate may still be good: the independent bounds decide
            upper, best = _upper_from(pm, cands, lower, upper, best)
            if upper <= lower * (1 + 1e-7):
                break
        adapt = (rho < _ADAPT_RHO or out.inaccurate) and basis is None
        if _S_RANGE[0] <= s <= _S_RANGE[1] and not adapt and not out.inaccurate:
            break
        if kappa is not None:
            kappa = [k * (th if (np.isfinite(th) and th > 1e-14) else 1.0)
                     for k, th in zip(kappa, out.theta, strict=True)]
        ghat = ghat * (np.sqrt(s) if s > 0 else 1e-3)
        if adapt:
            nb = _adapted_basis(P0, x1, lay.nu)
            if nb is not None:
                basis = nb
                kappa = [th * k if (np.isfinite(th) and th > 1e-14) else k
                         for th, k in zip(out.theta, kappa or [1.0] * len(out.theta), strict=True)]
    if not np.isfinite(lower):
        return np.inf, np.inf, STATUS_UNEXPLAINABLE, calls, method, None
    upper, best = _explicit_delta(pm, cands, lower, upper, best, timing)
    if inaccurate and (best is None or upper > lower * (1 + _INACCURATE_GAP) + 1e-300):
        # the SDP stalled (or failed) and its verified bounds do not close: a stalled iterate's
        # D-scales may be far from optimal, so solve the same LMI by bisection (feasibility
        # problems, scale of the uncertainty block fixed) and keep the best verified bounds. The
        # gap left then is the LMI's own (relaxation gap with several noise blocks), reported as is.
        fmb = _scaled_forms(pm, ghat, basis, kappa)[0]
        outb = _engine_bisection(fmb, timing, rtol, True, backend)
        calls += outb.calls
        method = "sdp+bisect"
        if outb.status != "ok" or not np.isfinite(outb.s_lower):
            return np.nan, np.nan, STATUS_FAILED, calls, method, None
        lower = max(lower, ghat * np.sqrt(outb.s_lower))
        upper, best = _explicit_delta(pm, [S * x for x in outb.candidates], lower, upper, best,
                                      timing)
    if best is None:
        return lower, np.nan, STATUS_LOWER_ONLY, calls, method, None
    # a verified Delta below a verified certificate means the numerics broke, beyond the floor set
    # by rounding of the data themselves (gamma* is a difference |c| - V of nearly equal numbers)
    floor = 1e-7 + 1e3 * np.finfo(float).eps * sig_max / max(excess, 1e-300)
    if upper < lower * (1 - floor):
        return np.nan, np.nan, STATUS_FAILED, calls, method, None
    return lower, max(upper, lower), STATUS_OK, calls, method, best


def _explicit_delta(pm: _PointModel, cands: list[np.ndarray], lower: float, upper: float,
                    best: list[np.ndarray] | None, timing: dict[str, float]
                    ) -> tuple[float, list[np.ndarray] | None]:
    """:func:`_upper_from`, then the local SQP refinement when a gap above 1e-7 is left."""
    upper, best = _upper_from(pm, cands, lower, upper, best)
    if best is not None and upper > lower * (1 + 1e-7):
        t_ref = time.perf_counter()
        d2 = pm.refine(best)
        timing["refine"] = timing.get("refine", 0.0) + time.perf_counter() - t_ref
        if d2 is not None:
            best, upper = d2, pm.gamma_of(d2)
    return upper, best


# --------------------------------------------------------------------------------------------------
# SISO fast path: the same one-SDP algorithm as _point, with the per-point numpy batched over the
# frequencies (one output, one complex scalar uncertainty block, V > 0). Every point that needs
# more than the plain first pass (near-cancellation basis, a rescaled second pass, a stalled solver,
# the SQP refinement of the explicit Delta, ...) is handed back and recomputed by _point.


def _batched_kernel(N: np.ndarray) -> np.ndarray:
    """Orthonormal kernel bases (f, n, n - 1) of a stack of nonzero rows N (f, 1, n) (as _kernel)."""
    Vh = np.linalg.svd(N)[2]
    return Vh[:, 1:, :].conj().transpose(0, 2, 1)


def _herm_top(Q: np.ndarray) -> np.ndarray:
    """Top eigenvectors (f, m) of a stack of Hermitian matrices (as _top_eigvec)."""
    _, U = np.linalg.eigh(0.5 * (Q + Q.conj().transpose(0, 2, 1)))
    return U[:, :, -1]


def _siso_max_s(G: np.ndarray, Fu: np.ndarray) -> np.ndarray:
    """_max_s for a stack (f, m, m); -1 where ``G`` is not negative definite."""
    G = 0.5 * (G + G.conj().transpose(0, 2, 1))
    try:
        Lc = np.linalg.cholesky(-G)
    except np.linalg.LinAlgError:
        return np.array([_max_s(g, fu) for g, fu in zip(G, Fu, strict=True)])
    Li = np.linalg.inv(Lc)
    Y = Li @ Fu @ Li.conj().transpose(0, 2, 1)
    top = np.linalg.eigvalsh(0.5 * (Y + Y.conj().transpose(0, 2, 1)))[:, -1]
    with np.errstate(divide="ignore"):
        return np.where(top <= 0, np.inf, 1.0 / np.where(top <= 0, 1.0, top))


class _SisoPoints:
    """Scalar data of SISO points (arrays over the points): Delta input ``v = a u + M12 W``,
    residual ``c - m21 u``, noise bound V, block weight w."""

    def __init__(self, M: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: np.ndarray, weight: float,
                 noise: str):
        self.a = M[:, 0, 0]
        self.m21 = M[:, 1, 0]
        self.m12w = (M[:, :1, 1:] @ W[:, :, None])[:, 0, 0]
        self.c = Zt[:, 0] - (M[:, 1:, 1:] @ W[:, :, None])[:, 0, 0]
        self.V = V
        self.w = weight
        self.noise = noise
        self.scale = np.maximum(np.abs(self.c), V)

    def deltas_from_x(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(delta, valid) from unscaled kernel vectors x (f, 3) (as _PointModel.deltas_from_x)."""
        t = x[:, -1]
        valid = np.isfinite(t) & (np.abs(t) > 1e-13 * np.linalg.norm(x, axis=1))
        ts = np.where(valid, t, 1.0)
        u = x[:, 0] / ts
        v = self.a * u + self.m12w
        nv2 = (v.conj() * v).real
        zero = nv2 == 0.0
        valid &= ~(zero & (np.abs(u) > 0))
        d = np.where(zero, 0.0, v.conj() * u / np.where(zero, 1.0, nv2))
        return d, valid

    def polish(self, d: np.ndarray, valid: np.ndarray, iters: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Gauss-Newton until the residual lies in the noise set (as _PointModel.polish)."""
        d = d.copy()
        done = np.zeros(d.shape, dtype=bool)
        live = valid.copy()
        V, shrink = self.V, 1 - 2 * np.finfo(float).eps
        for _ in range(iters + 1):
            if not np.any(live):
                break
            with np.errstate(all="ignore"):
                den_v = 1 - self.a * d
                v = self.m12w / den_v
                L = self.m21 / (1 - d * self.a)
                r = self.c - self.m21 * (d * v)
            bad = live & ((den_v == 0) | ~np.isfinite(r))
            live &= ~bad
            ok = live & (np.abs(r) <= V + 8 * np.finfo(float).eps * self.scale)
            done |= ok
            live &= ~ok
            if not np.any(live):
                break
            ar = np.abs(r)
            with np.errstate(all="ignore"):
                fct = np.where(ar > V * shrink, V * shrink / np.where(ar > 0, ar, 1), 1.0)
                dz = r - r * fct
                J = L * v
                arow = (r.conj() / ar) * J
                rhs = ar - np.abs(r - dz)
            if self.noise == "per_output":
                act = ar > V * (1 - 1e-9)
            else:
                act = np.ones(d.shape, dtype=bool)
            nrm2 = arow.real**2 + arow.imag**2
            use = live & act & (nrm2 > 0) & np.isfinite(nrm2)
            with np.errstate(all="ignore"):
                k = np.where(use, rhs / np.where(use, nrm2, 1.0), 0.0)
            d = d + np.where(use, k * arow.real - 1j * k * arow.imag, 0.0)
        return d, done


def _siso_batch(M: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: np.ndarray, lay: _Layout,
                noise: str, backend: str, timing: dict[str, float],
                time_limit: float = DEFAULT_TIME_LIMIT
                ) -> tuple[dict[str, np.ndarray], list[list[np.ndarray] | None], np.ndarray]:
    """One-SDP bounds for SISO points (arrays over the points). Returns the results (with the
    per-point 'reason' and the solver seconds 'spent'), the explicit Deltas, and a mask of the
    points left to :func:`_point` (their results are placeholders)."""
    f = M.shape[0]
    w = lay.blocks[0].weight
    pts = _SisoPoints(M, W, Zt, V, w, noise)
    a, m21, m12w, c = pts.a, pts.m21, pts.m12w, pts.c
    lower = np.full(f, np.nan)
    upper = np.full(f, np.nan)
    status = np.full(f, STATUS_FAILED, dtype="<U13")
    method = np.full(f, "", dtype="<U12")
    calls = np.zeros(f, dtype=int)
    reason = np.full(f, "", dtype=object)
    spent = np.zeros(f)
    deltas: list[list[np.ndarray] | None] = [None] * f
    todo = np.ones(f, dtype=bool)  # handed back to _point
    ac = np.abs(c)
    # pre-check 1: the nominal model explains the data within the noise
    pre = ac <= V
    lower[pre] = upper[pre] = 0.0
    status[pre], method[pre] = STATUS_OK, "precheck"
    for i in np.flatnonzero(pre):
        deltas[i] = [np.zeros((1, 1), complex)]
    todo &= ~pre
    # pre-check 2: the uncertainty cannot move the output
    b_est = w * np.abs(m21) * np.abs(m12w)
    unex = todo & (~np.isfinite(b_est) | (b_est == 0.0))
    lower[unex] = upper[unex] = np.inf
    status[unex], method[unex] = STATUS_UNEXPLAINABLE, "precheck"
    todo &= ~unex
    # the plain first pass only (near-cancellation points start in an adapted basis: _point)
    excess = ac - V
    sig_max = np.maximum(ac, V)
    run = todo & (V > 0) & (excess >= _NEAR_ZERO * sig_max) & np.isfinite(ac)
    idx = np.flatnonzero(run)
    if idx.size == 0:
        return {"lower": lower, "upper": upper, "status": status, "method": method,
                "calls": calls, "reason": reason, "spent": spent}, deltas, todo
    a, m21, m12w, c, Vi = a[idx], m21[idx], m12w[idx], c[idx], V[idx]
    exc, sgm = excess[idx], sig_max[idx]
    n = idx.size
    ghat = np.maximum(exc, 1e-14 * sgm) / b_est[idx]
    su = sgm / np.abs(m21)
    # noise-free answer (exact eigenvalue, m = 1) for the gamma scale
    N0 = np.stack([-m21 * su, c], axis=1)[:, None, :] / ac[idx][:, None, None]
    P0 = _batched_kernel(N0)[:, :, 0]
    ap0 = (ghat * w / su) * (a * su * P0[:, 0] + m12w * P0[:, 1])
    aa, bb = np.abs(ap0) ** 2, np.abs(P0[:, 0]) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        s0 = bb / aa
    good0 = (aa > 0) & np.isfinite(s0) & (s0 > 0)
    ghat = np.where(good0, ghat * np.sqrt(np.where(good0, s0, 1.0)) * np.maximum(exc, 1e-14 * sgm) / sgm,
                    ghat)
    kap = np.maximum(Vi / sgm * np.maximum(exc, 0.0) / sgm, 1e-12)
    # scaled implicit LFT on its kernel (as _scaled_forms): x~ = (u~, e, t), x = S x~
    N = np.stack([-m21 * su, -Vi + 0j, c], axis=1)[:, None, :] / ac[idx][:, None, None]
    P = _batched_kernel(N)  # (n, 3, 2)
    Ap = ((ghat * w / su)[:, None] * (a * su)[:, None]) * P[:, 0, :] + \
        ((ghat * w / su)[:, None] * m12w[:, None]) * P[:, 2, :]
    Ap = Ap[:, None, :]
    Bp = P[:, 0:1, :]
    rk = np.sqrt(kap)[:, None, None]
    Ak, Bk = rk * P[:, 2:3, :], rk * P[:, 1:2, :]

    def gram(X: np.ndarray) -> np.ndarray:
        return X.conj().transpose(0, 2, 1) @ X

    Fu = gram(Ap)
    F0 = -gram(Bp)
    T = gram(Ak) - gram(Bk)
    lmi = _lmi(backend, "maxs", 2, (("full", 1),), False)
    if isinstance(lmi, _ClarabelLmi):
        res = lmi.solve_many(F0, Fu, T, timing, time_limit)
    else:
        res = [_guarded_point(lambda i=i: lmi.solve(F0[i], Fu[i], [[T[i]]], timing), time_limit)
               for i in range(n)]
    calls[idx] = 1
    method[idx] = "sdp"
    spent[idx] = [r.seconds for r in res]
    # a solver that raised (a pyo3 panic) or ran out of time: that point fails, with the reason
    aborted = np.array([r.status == "aborted" for r in res])
    ai = idx[aborted]
    status[ai] = STATUS_FAILED
    reason[ai] = [r.reason for r in res if r.status == "aborted"]
    todo[ai] = False
    solved = np.array([r.status == "optimal" for r in res])
    # a stalled solve ('inaccurate') is kept only if the verified bounds close within 1e-7 below
    inacc = np.array([r.status == "inaccurate" for r in res])
    theta = np.array([float(r.theta[0][0]) if r.status in ("optimal", "inaccurate") else 0.0
                      for r in res])
    G = F0 + theta[:, None, None] * T
    s_cert = _siso_max_s(G, Fu)
    s_cert = np.where(s_cert < 0, 0.0, s_cert)
    fin = np.isfinite(s_cert)
    sc = np.where(fin, s_cert, 0.0)
    y = _herm_top(sc[:, None, None] * Fu + G)
    x1 = (P @ y[:, :, None])[:, :, 0]
    rho = np.abs(x1[:, 0]) / np.maximum(np.linalg.norm(x1, axis=1), 1e-300)
    # no second pass needed: rescaled answer inside _S_RANGE and no near-cancellation (a stalled
    # solve skips the second pass only when its verified bounds close, checked below, as in _point)
    keep = fin & ((solved & (sc >= _S_RANGE[0]) & (sc <= _S_RANGE[1]) & (rho >= _ADAPT_RHO)) | inacc)
    lo = ghat * np.sqrt(sc)
    S = np.stack([su, np.ones(n), np.ones(n)], axis=1)
    # explicit Delta: the certificate's eigenvector first, then the dual's (as _upper_from)
    sub = _SisoPoints.__new__(_SisoPoints)
    sub.a, sub.m21, sub.m12w, sub.c, sub.V, sub.w, sub.noise = a, m21, m12w, c, Vi, w, noise
    sub.scale = pts.scale[idx]
    up = np.full(n, np.inf)
    dbest = np.zeros(n, complex)
    have = np.zeros(n, dtype=bool)
    for cand in range(2):
        need = keep & ~(up <= lo * (1 + 1e-7))
        if cand == 1:
            has_dual = np.array([r.dual is not None for r in res])
            need &= has_dual
            if not np.any(need):
                break
            Z = np.stack([r.dual if (r.dual is not None) else np.eye(2, dtype=complex) for r in res])
            xc = (P @ _herm_top(Z)[:, :, None])[:, :, 0]
        else:
            xc = x1
        d0, valid = sub.deltas_from_x(S * xc)
        d1, ok = sub.polish(d0, valid & need)
        g = np.abs(d1) / w
        better = ok & need & (g < up)
        up = np.where(better, g, up)
        dbest = np.where(better, d1, dbest)
        have |= better
    # a gap left (SQP refinement) or no explicit Delta: _point
    keep &= have & (up <= lo * (1 + 1e-7))
    floor = 1e-7 + 1e3 * np.finfo(float).eps * sgm / np.maximum(exc, 1e-300)
    broke = keep & (up < lo * (1 - floor))
    fine = keep & ~broke
    gi = idx[fine]
    lower[gi] = lo[fine]
    upper[gi] = np.maximum(up[fine], lo[fine])
    status[gi] = STATUS_OK
    for i, dv in zip(gi, dbest[fine], strict=True):
        deltas[i] = [np.array([[dv]])]
    bi = idx[broke]
    lower[bi] = upper[bi] = np.nan
    status[bi] = STATUS_FAILED
    todo[idx[keep]] = False
    return {"lower": lower, "upper": upper, "status": status, "method": method, "calls": calls,
            "reason": reason, "spent": spent}, deltas, todo


def _prepare(me: np.ndarray, W: np.ndarray, Zt: np.ndarray, noise_bound: float | np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    Zt_a = np.asarray(Zt, dtype=complex)
    W_a = np.asarray(W, dtype=complex)
    Zt_a = Zt_a[:, None] if Zt_a.ndim == 1 else Zt_a
    W_a = W_a[:, None] if W_a.ndim == 1 else W_a
    f = Zt_a.shape[0]
    if W_a.shape[0] != f:
        raise ValueError(f"W has {W_a.shape[0]} frequencies, Zt has {f}")
    M = as_freq_matrix(me, f)
    return M, W_a, Zt_a, check_noise_bound(noise_bound, f)


def check_noise_bound(noise_bound: float | np.ndarray, n_freq: int | None = None) -> np.ndarray:
    """The noise bound V (m) as a float array ``(n_freq,)`` (or its own shape); ``ValueError``
    naming the noise bound if any entry is negative, NaN or infinite (a configuration error, not
    a property of one point's data)."""
    try:
        V = np.asarray(noise_bound, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"noise bound V must be a real number or array (m), got {noise_bound!r}"
                         ) from exc
    if n_freq is not None:
        V = np.broadcast_to(V, (n_freq,))
    with np.errstate(invalid="ignore"):
        bad = ~(V >= 0) | ~np.isfinite(V)
    if np.any(bad):
        where = np.flatnonzero(np.reshape(bad, -1))
        vals = np.reshape(V, -1)[where]
        raise ValueError(f"noise bound V must be finite and >= 0 (m); got {vals[:3].tolist()} at "
                         f"{where.size} of {V.size} point(s) (first index {int(where[0])})")
    return np.array(V, dtype=float)


def _run(me: np.ndarray, W: np.ndarray, Zt: np.ndarray, noise_bound: float | np.ndarray,
         structure: Structure | None, mode: str, rtol: float, fail_at: Collection[int],
         backend: str, time_limit: float = DEFAULT_TIME_LIMIT) -> GammaResult:
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if not time_limit > 0:
        raise ValueError(f"time_limit must be > 0 s, got {time_limit!r}")
    t0 = time.perf_counter()
    structure = structure or Structure()
    M, W_a, Zt_a, V = _prepare(me, W, Zt, noise_bound)
    f, n_in, n_out = Zt_a.shape[0], W_a.shape[1], Zt_a.shape[1]
    lay = _layout(M, n_in, n_out, structure)
    lower = np.full(f, np.nan)
    upper = np.full(f, np.nan)
    status = np.empty(f, dtype="<U13")
    method = np.empty(f, dtype="<U12")
    deltas: list[list[np.ndarray] | None]
    calls = 0
    timing: dict[str, float] = {}
    fails = set(int(i) for i in fail_at) | _INJECTED
    todo = np.ones(f, dtype=bool)
    deltas = [None] * f
    reason = np.full(f, "", dtype=object)
    spent = np.zeros(f)  # solver seconds of the batched first pass, charged to the point's budget
    # a point whose data are not finite (NaN/inf in Me, W or Zt) is marked, never solved
    finite = (np.all(np.isfinite(M), axis=(1, 2)) & np.all(np.isfinite(W_a), axis=1)
              & np.all(np.isfinite(Zt_a), axis=1))
    for i in np.flatnonzero(~finite):
        if i not in fails:
            status[i], method[i] = STATUS_BAD_DATA, ""
            reason[i] = "Me, W or Zt is not finite (NaN or inf) at this point"
    todo &= finite
    if (_SISO_BATCH and mode != "bisection" and n_out == 1 and lay.nu == 1 and lay.nv == 1
            and len(lay.blocks) == 1 and lay.blocks[0].lmi_kind == "full"):
        # SISO: the per-point numpy batched over the frequencies (same algorithm, see _siso_batch)
        sel = np.array([i not in fails for i in range(f)], dtype=bool) & finite
        if np.any(sel):
            out, dl, left = _siso_batch(M[sel], W_a[sel], Zt_a[sel], V[sel], lay, structure.noise,
                                        backend, timing, time_limit)
            isel = np.flatnonzero(sel)
            done = isel[~left]
            lower[done] = out["lower"][~left]
            upper[done] = out["upper"][~left]
            status[done] = out["status"][~left]
            method[done] = out["method"][~left]
            reason[done] = out["reason"][~left]
            spent[isel] = out["spent"]
            calls += int(out["calls"].sum())  # includes the first passes of points left to _point
            for k, i in enumerate(isel):
                if not left[k]:
                    deltas[i] = dl[k]
            todo[done] = False
    for i in range(f):
        if i in fails:
            status[i], method[i] = STATUS_FAILED, "injected"
            continue
        if not todo[i]:
            continue
        pm = _PointModel(M[i], W_a[i], Zt_a[i], float(V[i]), lay, structure.noise)
        try:
            with _point_budget(time_limit - spent[i]):
                lo, up, st, nc, meth, d = _point(pm, mode, rtol, timing, backend)
        except _SolverAbort as exc:
            lo, up, st, nc, meth, d = np.nan, np.nan, STATUS_FAILED, 0, "", None
            reason[i] = str(exc)
        except (np.linalg.LinAlgError, ArithmeticError) as exc:
            lo, up, st, nc, meth, d = np.nan, np.nan, STATUS_FAILED, 0, "", None
            reason[i] = f"{type(exc).__name__}: {exc}"
        lower[i], upper[i], status[i], method[i] = lo, up, st, meth
        calls += nc
        deltas[i] = d
    for i in fails:
        if 0 <= i < f:
            reason[i] = "injected failure (testing hook)"
    timing["wall"] = time.perf_counter() - t0
    return GammaResult(lower, upper, status, calls, method, deltas, timing, reason)


def required_gamma(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                   noise_bound: float | np.ndarray, structure: Structure | None = None, *,
                   fail_at: Collection[int] = (), rtol: float = 1e-8,
                   backend: str = DEFAULT_BACKEND,
                   time_limit: float = DEFAULT_TIME_LIMIT) -> GammaResult:
    """Smallest gamma(w) for which ``F_u(Me, gamma Delta) W + V Delta_v`` reproduces ``Zt``.

    ``me``: ``(f, n_v + n_out, n_u + n_in)`` complex; ``W``: ``(f, n_in)`` or ``(f,)`` input
    phasors (N); ``Zt``: ``(f, n_out)`` or ``(f,)`` output phasors (m); ``noise_bound``: V (m),
    scalar or ``(f,)``; ``structure``: blocks of Delta_u and noise model (default: one full block).
    One uncertainty block (scalar or full): one SDP per frequency (or an exact generalized
    eigenvalue when there is no noise block). Repeated-scalar or several blocks: bisection on the
    same LMI (GEVP), relative tolerance ``rtol`` on gamma. ``fail_at``: testing hook, indices
    treated as solver failures. ``backend``: 'clarabel' (default; same LMI, conic data filled
    directly, Clarabel called without cvxpy's per-solve canonicalization; falls back to cvxpy for
    Hermitian D-scales) or 'cvxpy' (the problem built once with cvxpy Parameters, re-solved per
    frequency). SISO data: the per-point numpy is batched over the frequencies (see the module
    docstring). ``time_limit``: seconds of solver time per frequency point (default 10).

    Per point, never for the whole batch: data that are not finite give status 'bad_data'; a
    solver that raises (also a ``BaseException`` such as Clarabel's pyo3 ``PanicException``; only
    ``KeyboardInterrupt``/``SystemExit`` propagate) or runs out of time gives 'solver_failed' with
    the reason in ``GammaResult.reason``. A negative, NaN or infinite noise bound is a
    ``ValueError``.
    """
    return _run(me, W, Zt, noise_bound, structure, "auto", rtol, fail_at, backend, time_limit)


def required_gamma_bisection(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                             noise_bound: float | np.ndarray, structure: Structure | None = None,
                             *, fail_at: Collection[int] = (), rtol: float = 1e-9,
                             backend: str = DEFAULT_BACKEND,
                             time_limit: float = DEFAULT_TIME_LIMIT) -> GammaResult:
    """Same bounds by bisection on gamma with an LMI feasibility problem per step (the classic
    approach of the dissertation, section 3.1); for benchmarking the one-SDP formulation."""
    return _run(me, W, Zt, noise_bound, structure, "bisection", rtol, fail_at, backend,
                time_limit)


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
    output rows of block i; ``kinds[i]``: 'scalar' | 'full' | 'repeated'; ``gamma_block[i]``: block
    bounded by ``radius[i] * gamma`` (else by ``radius[i]``, default 1). One gamma block of scalar
    or full kind: one SDP (or an exact eigenvalue without other blocks); otherwise bisection.
    ``time_limit``: seconds for all solver calls; a solver that raises or runs out of time gives
    status 'solver_failed'.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    N = np.atleast_2d(np.asarray(N, dtype=complex))
    rad = [1.0] * len(A) if radius is None else [float(r) for r in radius]
    P = _kernel(N)
    if P.shape[1] == 0:
        return ImplicitBound(np.inf, None, "unbounded", 0)
    gam, fix = [], []
    for Ai, Bi, kd, gb, ri in zip(A, B, kinds, gamma_block, rad, strict=True):
        Ai = np.atleast_2d(np.asarray(Ai, dtype=complex))
        Bi = np.atleast_2d(np.asarray(Bi, dtype=complex))
        lk = "repeated" if kd == "repeated" and Ai.shape[0] > 1 else "full"
        (gam if gb else fix).append((lk, Bi.shape[0], ri * Ai @ P, Bi @ P))
    if not gam:
        raise ValueError("at least one block must be scaled by gamma")
    fm = _Forms(P, gam, fix)
    timing: dict[str, float] = {}
    single = len(gam) == 1 and gam[0][0] == "full"
    try:
        with _point_budget(time_limit):
            if single and not fix:
                out = _engine_eig(fm)
            elif single:
                out = _engine_sdp(fm, timing, backend)
            else:
                out = _engine_bisection(fm, timing, rtol, False, backend)
    except _SolverAbort:  # the solver raised (pyo3 panic) or ran out of time
        return ImplicitBound(np.nan, None, STATUS_FAILED, 0)
    if out.status == "unbounded":
        return ImplicitBound(np.inf, None, "unbounded", out.calls)
    if out.status != "ok":
        return ImplicitBound(np.nan, None, STATUS_FAILED, out.calls)
    x = out.candidates[0] if out.candidates else None
    return ImplicitBound(float(np.sqrt(out.s_lower)), x, STATUS_OK, out.calls)


def blocks_for(me_shape: Sequence[int], n_in: int, n_out: int, structure: Structure
               ) -> tuple[Block, ...]:
    """The resolved block list for an Me of shape ``(f, rows, cols)`` (helper for callers)."""
    return structure.resolve(me_shape[-1] - n_in, me_shape[-2] - n_out)
