"""Solver backends: one LMI family, two ways to solve it, and the guard around every solver call.

The LMI ``opt s.t. s Gs + G0 + sum_l theta_l G_l <= 0`` (kind 'maxs': maximize s; kind 'feas':
minimize lambda) in its real embedding, solved by 'cvxpy' (built once per shape with cvxpy
Parameters, re-solved per point) or 'clarabel' (the default: the identical conic data -- Clarabel's
scaled upper-triangle PSD vectorization, a fixed sparsity pattern -- filled directly and Clarabel
called without cvxpy's per-solve canonicalization; Hermitian D-scales and the G-scales of real
blocks: :class:`ClarabelGeneralLmi`, the same LMI with its own PSD cones, also without cvxpy). Both
return D-scales projected onto their cones (:func:`project_scales`).

No module state: the built problems live in an :class:`LmiCache` object and the per-call state
(backend, cache, timings, the current point's time budget) in a :class:`SolveSession`.
"""

from __future__ import annotations

import contextlib
import time
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, cast

import clarabel
import numpy as np
import scipy.sparse as sp

from rotorcheck.robust.mu.structure import DEFAULT_BACKEND, DEFAULT_TIME_LIMIT

if TYPE_CHECKING:  # cvxpy costs ~0.8 s to import: only the 'cvxpy' backend loads it
    import cvxpy as cp

BACKENDS = ("cvxpy", "clarabel")
SOLVER_OPTS: Mapping[str, object] = MappingProxyType(
    {"chordal_decomposition_enable": False, "max_threads": 1})
# Clarabel's 'InsufficientProgress' still returns its last iterate; every bound is verified
# independently (the driver accepts such a point only if the verified gap closes)
_CVXPY_ONLY_OPTS: Mapping[str, object] = MappingProxyType({"accept_unknown": True})
_CLARABEL_USABLE = ("Solved", "AlmostSolved", "InsufficientProgress", "MaxIterations")

BlockSig = tuple[tuple[str, int], ...]


# --------------------------------------------------------------------------------------------------
# real embedding of Hermitian matrices


def emb(H: np.ndarray) -> np.ndarray:
    """Real symmetric embedding of a Hermitian matrix (same eigenvalues, each twice)."""
    m = H.shape[0]
    out = np.empty((2 * m, 2 * m))
    out[:m, :m] = out[m:, m:] = H.real
    out[m:, :m] = H.imag
    out[:m, m:] = -H.imag
    return out


def herm_basis(k: int) -> list[np.ndarray]:
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


def complexify(Xm: np.ndarray, m: int) -> np.ndarray:
    """Hermitian m x m matrix closest to a real 2m x 2m embedding."""
    return 0.5 * (Xm[:m, :m] + Xm[m:, m:]) + 0.5j * (Xm[m:, :m] - Xm[:m, m:])


def project_scales(theta: Sequence[np.ndarray], blocks: Sequence[tuple[str, int]]
                   ) -> list[np.ndarray]:
    """D-scale coordinates projected onto their cones (``d >= 0``; Hermitian ``D >= 0`` for a
    repeated block, coordinates in the :func:`herm_basis` order; a 'free' block -- the G-scale of a
    real block, any Hermitian matrix -- is returned as is).

    An interior point iterate that stopped early ('InsufficientProgress', 'AlmostSolved') can sit
    slightly outside the cone (``d ~ -1e-7`` for a noise block that is inactive at the optimum).
    The S-procedure certifies nothing with a negative scale, so every certificate is verified with
    the projected scales; both backends return them through here."""
    out = []
    for th, (kind, k) in zip(theta, blocks, strict=True):
        th = np.asarray(th, dtype=float).reshape(-1)
        if kind == "free":  # a G-scale (real block): Hermitian, no cone
            out.append(th.copy())
            continue
        if kind == "full" or k == 1:
            out.append(np.maximum(th, 0.0))
            continue
        D = sum((t * H for t, H in zip(th, herm_basis(k), strict=True)),
                np.zeros((k, k), complex))
        lam, U = np.linalg.eigh(0.5 * (D + D.conj().T))
        D = (U * np.maximum(lam, 0.0)) @ U.conj().T
        iu, ju = np.triu_indices(k, 1)
        out.append(np.concatenate([np.diag(D).real,
                                   np.stack([D[iu, ju].real, D[iu, ju].imag], 1).reshape(-1)]))
    return out


@dataclass
class LmiOut:
    """One solver answer: status 'optimal' | 'inaccurate' | 'unbounded' | 'failed' | 'aborted'."""

    status: str
    value: float = np.nan  # s (max problem) or lambda (feasibility problem)
    theta: list[np.ndarray] = field(default_factory=list)  # D-scale coordinates per variable block
    dual: np.ndarray | None = None  # complex m x m dual of the main LMI
    reason: str = ""  # why the point was aborted
    seconds: float = 0.0  # wall time of the point's call (stacked first pass)


# --------------------------------------------------------------------------------------------------
# per-point guard: every solver call runs under the budget of the point it belongs to


class SolverAbort(Exception):
    """A solver call raised something that is not an ordinary error (Clarabel's
    ``pyo3_runtime.PanicException`` derives from ``BaseException``), or the point's time budget ran
    out: the point is reported 'solver_failed' with this reason and not retried."""


@dataclass(frozen=True)
class Budget:
    """Wall-time budget of one frequency point."""

    deadline: float  # time.perf_counter() value
    seconds: float  # the point's whole budget (for the message)

    @classmethod
    def start(cls, seconds: float) -> Budget:
        return cls(time.perf_counter() + seconds, seconds)


def guarded_call(call: Callable[[float], object], budget: Budget | None) -> object:
    """``call(time_limit)`` under ``budget`` (None: :data:`DEFAULT_TIME_LIMIT`, no deadline).

    ``time_limit`` is the point's remaining time (Clarabel's ``time_limit`` setting). Ordinary
    exceptions pass through (the callers treat them as a failed solve). A ``BaseException`` that is
    not ``KeyboardInterrupt``/``SystemExit``/``GeneratorExit`` (a Rust panic surfacing through pyo3),
    an exhausted budget, or a call that returns after the deadline raises :class:`SolverAbort`."""
    if budget is None:
        remaining = DEFAULT_TIME_LIMIT
    else:
        remaining = budget.deadline - time.perf_counter()
        if remaining <= 0:
            raise SolverAbort(f"time limit of {budget.seconds:g} s per point exhausted")
    try:
        out = call(remaining)
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except Exception:
        raise
    except BaseException as exc:  # pyo3 panics derive from BaseException
        raise SolverAbort(f"solver raised {type(exc).__name__}: {exc}") from exc
    if budget is not None and time.perf_counter() > budget.deadline:
        raise SolverAbort(f"time limit of {budget.seconds:g} s per point exceeded")
    return out


class SolveSession:
    """Per-call solver state: the backend, the problem cache, timings (seconds: 'solve_total',
    'clarabel', 'refine', ...) and the time budget of the point being solved. One per call and
    thread (the cached problems hold parameter values and a reused sparse buffer)."""

    def __init__(self, backend: str = DEFAULT_BACKEND, cache: LmiCache | None = None):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        self.backend = backend
        self.cache = LmiCache() if cache is None else cache
        self.timing: dict[str, float] = {}
        self.budget: Budget | None = None

    def add_time(self, key: str, seconds: float) -> None:
        self.timing[key] = self.timing.get(key, 0.0) + seconds

    @contextlib.contextmanager
    def point_budget(self, seconds: float) -> Iterator[None]:
        """Solver calls inside the block share ``seconds`` of wall time (one frequency point)."""
        old = self.budget
        self.budget = Budget.start(seconds)
        try:
            yield
        finally:
            self.budget = old

    def guarded(self, call: Callable[[float], object]) -> object:
        """:func:`guarded_call` under the current point's budget."""
        return guarded_call(call, self.budget)

    def guarded_point(self, solve: Callable[[], LmiOut], seconds: float) -> LmiOut:
        """One point's solve under its own budget of ``seconds``; an abort becomes an 'aborted'
        result with the reason instead of ending the stack."""
        t0 = time.perf_counter()
        try:
            with self.point_budget(seconds):
                out = solve()
        except SolverAbort as exc:
            out = LmiOut("aborted", reason=str(exc))
        out.seconds = time.perf_counter() - t0
        return out

    def lmi(self, kind: str, m: int, blocks: BlockSig, normalize: bool
            ) -> CvxpyLmi | ClarabelLmi | ClarabelGeneralLmi:
        """The (cached) LMI of this shape for the session's backend."""
        return self.cache.get(self.backend, kind, m, blocks, normalize)


# --------------------------------------------------------------------------------------------------
# the two backends


def solve_each(solve_one: Callable[..., LmiOut], G0: np.ndarray, Gs: np.ndarray,
               terms: Sequence[Sequence[np.ndarray]], session: SolveSession, point_seconds: float | None
               ) -> list[LmiOut]:
    """The 'maxs' problems of a stack of points one by one (each guarded when ``point_seconds`` is set)."""
    out = []
    for i in range(G0.shape[0]):
        def solve(i: int = i) -> LmiOut:
            return solve_one(G0[i], Gs[i], [[T[i] for T in ts] for ts in terms], session)

        out.append(solve() if point_seconds is None else session.guarded_point(solve, point_seconds))
    return out


class CvxpyLmi:
    """``opt s.t. s Gs + G0 + sum_l theta_l G_l <= 0`` in the real embedding.

    kind 'maxs': maximize s (s a variable). kind 'feas': s is folded into the data, minimize
    lambda with ``G0 + sum theta G - lambda I <= 0``; ``fix_first`` is handled by the caller (the
    fixed block is part of G0), then ``lambda >= -1``, else ``sum trace(D) = 1``.
    """

    def __init__(self, kind: str, m: int, blocks: BlockSig, normalize: bool):
        import cvxpy as cp  # lazy: cvxpy only for the LMI

        dim = 2 * m
        self.kind = kind
        self.G0 = cp.Parameter((dim, dim), symmetric=True)
        self.Gs = cp.Parameter((dim, dim), symmetric=True)
        self.var = cp.Variable()
        if kind == "maxs":
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
            if bkind == "free":  # G-scale of a real block: free, not in the normalization
                pass
            elif bkind == "full":
                cons.append(th >= 0)
                traces.append(th[0])
            else:
                embs = [emb(H) for H in herm_basis(k)]
                cons.append(sum(th[j] * embs[j] for j in range(nb)) >> 0)
                traces.append(cp.sum(th[:k]))
            self.thetas.append(th)
            self.params.append(ps)
        if kind == "feas":
            cons.append(cast(cp.Constraint, sum(traces) == 1 if normalize else self.var >= -1))
            if normalize and any(bk == "free" for bk, _ in blocks):
                # free G-scales can drive lambda to -inf (a certificate for every s): keep it
                # bounded; only its sign is used
                cons.append(self.var >= -1)
        self.lmi = expr << 0
        obj: cp.Maximize | cp.Minimize = cp.Maximize(self.var) if kind == "maxs" else cp.Minimize(self.var)
        self.problem = cp.Problem(obj, [*cons, self.lmi])

    def solve(self, G0: np.ndarray, Gs: np.ndarray | None, terms: Sequence[Sequence[np.ndarray]],
              session: SolveSession) -> LmiOut:
        """One point: ``G0``, ``Gs`` (m, m), ``terms[block][basis element]`` (m, m)."""
        import cvxpy as cp  # lazy: cvxpy only for the LMI

        self.G0.value = emb(G0)
        if self.kind == "maxs" and Gs is not None:
            self.Gs.value = emb(Gs)
        for ps, ts in zip(self.params, terms, strict=True):
            for p, T in zip(ps, ts, strict=True):
                p.value = emb(T)
        t0 = time.perf_counter()

        def run(limit: float) -> str:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                self.problem.solve(solver=cp.CLARABEL, warm_start=False, time_limit=limit,
                                   **SOLVER_OPTS, **_CVXPY_ONLY_OPTS)
            return str(self.problem.status)

        try:
            status = str(session.guarded(run))
        except (cp.SolverError, ValueError, ArithmeticError):
            status = "error"
        session.add_time("solve_total", time.perf_counter() - t0)
        st = self.problem.solver_stats
        if st is not None and st.solve_time is not None:
            session.add_time("clarabel", float(st.solve_time))
        if status in ("unbounded", "unbounded_inaccurate"):
            return LmiOut("unbounded")
        if status not in ("optimal", "optimal_inaccurate") or self.var.value is None:
            return LmiOut("failed")
        if any(th.value is None for th in self.thetas):
            return LmiOut("failed")
        theta = project_scales([np.asarray(th.value, dtype=float).reshape(-1)
                                for th in self.thetas], self.blocks)
        X = self.lmi.dual_value
        m = G0.shape[0]
        dual = complexify(np.asarray(X), m) if X is not None else None
        flag = "optimal" if status == "optimal" else "inaccurate"
        return LmiOut(flag, float(self.var.value), theta, dual)

    def solve_many(self, G0: np.ndarray, Gs: np.ndarray, terms: Sequence[Sequence[np.ndarray]],
                   session: SolveSession, point_seconds: float | None) -> list[LmiOut]:
        """'maxs' problems of a stack of points (see :meth:`ClarabelLmi.solve_many`)."""
        return solve_each(self.solve, G0, Gs, terms, session, point_seconds)


class ClarabelLmi:
    """The same LMI as :class:`CvxpyLmi` (scalar D-scales only), conic data filled directly.

    Variables ``z = (var, theta_1..K)``; cones: K nonnegative (theta), [feas: 1 zero (normalization)
    or 1 nonnegative (lambda >= -1)], PSD triangle of size 2m for ``-(LMI expression)``.
    """

    def __init__(self, kind: str, m: int, n_theta: int, normalize: bool):
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
        cones: list[Any] = []
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
        for key, val in SOLVER_OPTS.items():
            setattr(st, key, val)
        self.settings = st
        eye_sv = np.eye(dim)[self.iu, self.ju] * self.wsv
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
            pat[self.r0:, 0] = eye_sv != 0
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
            self.A_dense[self.r0:, 0] = -eye_sv
        self.b0 = np.zeros(rows)
        if kind == "feas":
            self.b0[n_theta] = 1.0

    def _svec_emb(self, H: np.ndarray) -> np.ndarray:
        """``svec(emb(H))`` of a stack (..., m, m) of Hermitian matrices, shape (..., nsv)."""
        lead = H.shape[:-2]
        flat = np.concatenate([H.real.reshape(*lead, -1), H.imag.reshape(*lead, -1)], axis=-1)
        return flat[..., self.gidx] * self.gsgn

    def _fill(self, G0: np.ndarray, Gs: np.ndarray | None, T: Sequence[np.ndarray]
              ) -> tuple[np.ndarray, np.ndarray]:
        """Dense A (f, rows, 1 + K) and b (f, rows) of a stack of points."""
        f, r0 = G0.shape[0], self.r0
        A = np.broadcast_to(self.A_dense, (f, *self.A_dense.shape)).copy()
        if self.kind != "feas":
            assert Gs is not None
            A[:, r0:, 0] = self._svec_emb(Gs)
        for j, Tj in enumerate(T):
            A[:, r0:, 1 + j] = self._svec_emb(Tj)
        b = np.broadcast_to(self.b0, (f, self.rows)).copy()
        b[:, r0:] = -self._svec_emb(G0)
        return A, b

    def _call(self, A: sp.csc_matrix, b: np.ndarray, session: SolveSession
              ) -> tuple[str, np.ndarray | None, np.ndarray | None]:
        t0 = time.perf_counter()

        def run(limit: float) -> object:
            self.settings.time_limit = float(limit)
            solver = clarabel.DefaultSolver(self.P, self.q, A, b, self.cones, self.settings)
            return solver.solve()

        sol: Any
        try:
            sol = session.guarded(run)
            status = str(sol.status)
        except (ValueError, RuntimeError, ArithmeticError):
            status = "error"
            sol = None
        session.add_time("solve_total", time.perf_counter() - t0)
        if status == "MaxTime":
            raise SolverAbort("Clarabel stopped at the time limit of the point")
        if sol is None:
            return status, None, None
        session.add_time("clarabel", float(sol.solve_time))
        return status, np.asarray(sol.x), np.asarray(sol.z)

    def _matrix(self, A: np.ndarray, data: np.ndarray, dense_ok: bool) -> sp.csc_matrix:
        """A of one point: its values ``data`` on the fixed pattern put into the reused CSC
        object when none of them is zero (``dense_ok``), else the plain conversion."""
        if dense_ok:
            self.A_csc.data = data
            return self.A_csc
        return sp.csc_matrix(A)

    def solve(self, G0: np.ndarray, Gs: np.ndarray | None, terms: Sequence[Sequence[np.ndarray]],
              session: SolveSession) -> LmiOut:
        """One point: ``G0``, ``Gs`` (m, m), ``terms[block][0]`` (m, m)."""
        A, b = self._fill(G0[None], None if Gs is None else Gs[None], [ts[0][None] for ts in terms])
        data = A[0, self.pat_r, self.pat_c]
        return self._results([self._call(self._matrix(A[0], data, bool(np.all(data != 0))), b[0],
                                         session)])[0]

    def solve_many(self, G0: np.ndarray, Gs: np.ndarray, terms: Sequence[Sequence[np.ndarray]],
                   session: SolveSession, point_seconds: float | None) -> list[LmiOut]:
        """'maxs' problems of a stack of points: G0, Gs and ``terms[j][0]`` (the one term of scalar
        D-scale j) of shape (f, m, m). The conic data of all points are filled at once; one Clarabel
        call per point. ``point_seconds``: each point under its own budget, an abort becomes an
        'aborted' result; None: the session's current budget, an abort raises
        :class:`SolverAbort`."""
        assert self.kind == "maxs" and len(terms) == self.K
        A, b = self._fill(G0, Gs, [ts[0] for ts in terms])
        data = A[:, self.pat_r, self.pat_c]
        dense_ok = np.all(data != 0, axis=1).tolist()
        raw: list[tuple[str, np.ndarray | None, np.ndarray | None]] = []
        seconds: list[float] = []
        aborted: dict[int, str] = {}
        for i in range(G0.shape[0]):
            Ai = self._matrix(A[i], data[i], dense_ok[i])
            t0 = time.perf_counter()
            try:
                if point_seconds is None:
                    raw.append(self._call(Ai, b[i], session))
                else:
                    with session.point_budget(point_seconds):
                        raw.append(self._call(Ai, b[i], session))
            except SolverAbort as exc:
                if point_seconds is None:
                    raise
                raw.append(("aborted", None, None))
                aborted[i] = str(exc)
            seconds.append(time.perf_counter() - t0)
        out = self._results(raw)
        for i, reason in aborted.items():
            out[i] = LmiOut("aborted", reason=reason)
        for o, sec in zip(out, seconds, strict=True):
            o.seconds = sec
        return out

    def _results(self, raw: Sequence[tuple[str, np.ndarray | None, np.ndarray | None]]
                 ) -> list[LmiOut]:
        """The answers (status, x, z) of a stack of solves: D-scales projected onto their cones
        (``d >= 0``, as :func:`project_scales`) and the complex duals, for all points at once."""
        K, m = self.K, self.m
        out: list[LmiOut] = []
        good: list[int] = []
        for k, (status, x, z) in enumerate(raw):
            if status in ("DualInfeasible", "AlmostDualInfeasible"):
                out.append(LmiOut("unbounded"))
            elif (x is None or z is None or status not in _CLARABEL_USABLE or x.size != 1 + K
                  or not np.all(np.isfinite(x))):
                out.append(LmiOut("failed"))
            else:
                out.append(LmiOut("optimal" if status == "Solved" else "inaccurate"))
                good.append(k)
        if good:
            X = np.stack([raw[k][1] for k in good])  # type: ignore[misc]
            Z = np.stack([raw[k][2] for k in good])  # type: ignore[misc]
            theta = np.maximum(X[:, 1:], 0.0)
            zfin = np.all(np.isfinite(Z), axis=1)
            dim = 2 * m
            Sm = np.zeros((len(good), dim, dim))
            v = Z[:, self.r0:] / self.wsv
            Sm[:, self.iu, self.ju] = v
            Sm[:, self.ju, self.iu] = v
            D = 0.5 * (Sm[:, :m, :m] + Sm[:, m:, m:]) + 0.5j * (Sm[:, m:, :m] - Sm[:, :m, m:])
            for j, k in enumerate(good):
                o = out[k]
                o.value = float(X[j, 0])
                o.theta = [theta[j, q: q + 1] for q in range(K)]
                o.dual = D[j] if zfin[j] else None
        return out


def _svec_index(dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row / column indices and weights of Clarabel's svec (column-wise upper triangle,
    off-diagonal entries times sqrt 2) of a dim x dim symmetric matrix."""
    iu, ju = np.triu_indices(dim)
    order = np.lexsort((iu, ju))
    iu, ju = iu[order], ju[order]
    return iu, ju, np.where(iu == ju, 1.0, np.sqrt(2.0))


class ClarabelGeneralLmi:
    """The LMI of :class:`CvxpyLmi` with any variable blocks, conic data built directly (no
    cvxpy): 'full' (``d >= 0``), 'repeated' (Hermitian ``D >= 0``, its own PSD cone of size 2k)
    and 'free' (the Hermitian G-scale of a real block, k^2 free coordinates, no cone).

    Variables ``z = (var, coordinates of block 1, ..., block B)``; cones: nonnegative (scalar
    D-scales), [feas: zero (normalization ``sum trace D = 1``) and/or nonnegative
    (``lambda >= -1``)], one PSD cone per Hermitian D-scale, the PSD cone of ``-(LMI)``."""

    def __init__(self, kind: str, m: int, blocks: BlockSig, normalize: bool):
        self.kind, self.m, self.blocks, self.normalize = kind, m, blocks, normalize
        has_free = any(bk == "free" for bk, _ in blocks)
        cols: list[list[int]] = []
        nz = 1
        for bk, k in blocks:
            nb = 1 if bk == "full" else k * k
            cols.append(list(range(nz, nz + nb)))
            nz += nb
        self.cols, self.nz = cols, nz
        dim = 2 * m
        self.iu, self.ju, self.wsv = _svec_index(dim)
        rows_A: list[np.ndarray] = []
        rows_b: list[np.ndarray] = []
        cones: list[Any] = []
        scal = [c[0] for (bk, _), c in zip(blocks, cols, strict=True) if bk == "full"]
        if scal:
            A = np.zeros((len(scal), nz))
            A[np.arange(len(scal)), scal] = -1.0
            rows_A.append(A)
            rows_b.append(np.zeros(len(scal)))
            cones.append(clarabel.NonnegativeConeT(len(scal)))
        if kind == "feas":
            if normalize:
                A = np.zeros((1, nz))
                for (bk, k), c in zip(blocks, cols, strict=True):
                    if bk != "free":
                        A[0, c[:1] if bk == "full" else c[:k]] = 1.0
                rows_A.append(A)
                rows_b.append(np.ones(1))
                cones.append(clarabel.ZeroConeT(1))
            if not normalize or has_free:  # lambda >= -1
                A = np.zeros((1, nz))
                A[0, 0] = -1.0
                rows_A.append(A)
                rows_b.append(np.ones(1))
                cones.append(clarabel.NonnegativeConeT(1))
        for (bk, k), c in zip(blocks, cols, strict=True):
            if bk != "repeated":
                continue
            iu, ju, w = _svec_index(2 * k)
            A = np.zeros((iu.size, nz))
            for j, H in zip(c, herm_basis(k), strict=True):
                A[:, j] = -emb(H)[iu, ju] * w
            rows_A.append(A)
            rows_b.append(np.zeros(iu.size))
            cones.append(clarabel.PSDTriangleConeT(2 * k))
        self.A_top = np.concatenate(rows_A) if rows_A else np.zeros((0, nz))
        self.b_top = np.concatenate(rows_b) if rows_b else np.zeros(0)
        cones.append(clarabel.PSDTriangleConeT(dim))
        self.cones = cones
        self.r0 = self.A_top.shape[0]
        self.q = np.zeros(nz)
        self.q[0] = -1.0 if kind == "maxs" else 1.0
        self.P = sp.csc_matrix((nz, nz))
        st = clarabel.DefaultSettings()
        st.verbose = False
        for key, val in SOLVER_OPTS.items():
            setattr(st, key, val)
        self.settings = st

    def _svec_emb(self, H: np.ndarray) -> np.ndarray:
        return emb(0.5 * (H + H.conj().T))[self.iu, self.ju] * self.wsv

    def solve(self, G0: np.ndarray, Gs: np.ndarray | None, terms: Sequence[Sequence[np.ndarray]],
              session: SolveSession) -> LmiOut:
        """One point: ``G0``, ``Gs`` (m, m), ``terms[block][basis element]`` (m, m)."""
        dim = 2 * self.m
        nsv = self.iu.size
        A = np.zeros((self.r0 + nsv, self.nz))
        A[: self.r0] = self.A_top
        if self.kind == "maxs":
            assert Gs is not None
            A[self.r0:, 0] = self._svec_emb(Gs)
        else:
            A[self.r0:, 0] = -(np.eye(dim)[self.iu, self.ju] * self.wsv)
        for c, ts in zip(self.cols, terms, strict=True):
            for j, T in zip(c, ts, strict=True):
                A[self.r0:, j] = self._svec_emb(T)
        b = np.concatenate([self.b_top, -self._svec_emb(G0)])
        Acsc = sp.csc_matrix(A)
        t0 = time.perf_counter()

        def run(limit: float) -> object:
            self.settings.time_limit = float(limit)
            return clarabel.DefaultSolver(self.P, self.q, Acsc, b, self.cones,
                                          self.settings).solve()

        sol: Any
        try:
            sol = session.guarded(run)
            status = str(sol.status)
        except (ValueError, RuntimeError, ArithmeticError):
            status, sol = "error", None
        session.add_time("solve_total", time.perf_counter() - t0)
        if status == "MaxTime":
            raise SolverAbort("Clarabel stopped at the time limit of the point")
        if sol is None:
            return LmiOut("failed")
        session.add_time("clarabel", float(sol.solve_time))
        if status in ("DualInfeasible", "AlmostDualInfeasible"):
            return LmiOut("unbounded")
        x, z = np.asarray(sol.x), np.asarray(sol.z)
        if status not in _CLARABEL_USABLE or x.size != self.nz or not np.all(np.isfinite(x)):
            return LmiOut("failed")
        theta = project_scales([x[c] for c in self.cols], self.blocks)
        dual = None
        zm = z[self.r0:]
        if np.all(np.isfinite(zm)):
            Sm = np.zeros((dim, dim))
            v = zm / self.wsv
            Sm[self.iu, self.ju] = v
            Sm[self.ju, self.iu] = v
            dual = complexify(Sm, self.m)
        return LmiOut("optimal" if status == "Solved" else "inaccurate", float(x[0]), theta, dual)

    def solve_many(self, G0: np.ndarray, Gs: np.ndarray, terms: Sequence[Sequence[np.ndarray]],
                   session: SolveSession, point_seconds: float | None) -> list[LmiOut]:
        """'maxs' problems of a stack of points (see :meth:`ClarabelLmi.solve_many`)."""
        return solve_each(self.solve, G0, Gs, terms, session, point_seconds)


class LmiCache:
    """The problem-structure cache: one built LMI per (backend, kind, size, blocks, normalization),
    re-filled per point. Not thread-safe (its problems hold parameter values and a reused sparse
    buffer): one per call or thread; :func:`required_gamma` makes its own."""

    def __init__(self) -> None:
        self._lmis: dict[tuple[str, str, int, BlockSig, bool],
                         CvxpyLmi | ClarabelLmi | ClarabelGeneralLmi] = {}

    def __len__(self) -> int:
        return len(self._lmis)

    def get(self, backend: str, kind: str, m: int, blocks: BlockSig, normalize: bool
            ) -> CvxpyLmi | ClarabelLmi | ClarabelGeneralLmi:
        use_direct = backend == "clarabel" and all(k == "full" for k, _ in blocks)
        # G-scales (real blocks) or Hermitian D-scales (repeated blocks) with the clarabel
        # backend: the general direct class
        general = backend == "clarabel" and any(k in ("free", "repeated") for k, _ in blocks)
        name = "clarabel" if use_direct else ("clarabel-general" if general else "cvxpy")
        key = (name, kind, m, blocks, normalize)
        lmi = self._lmis.get(key)
        if lmi is None:
            if use_direct:
                lmi = ClarabelLmi(kind, m, len(blocks), normalize)
            elif general:
                lmi = ClarabelGeneralLmi(kind, m, blocks, normalize)
            else:
                lmi = CvxpyLmi(kind, m, blocks, normalize)
            self._lmis[key] = lmi
        return lmi
