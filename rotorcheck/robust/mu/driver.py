"""The per-point driver and the public entry points :func:`required_gamma` and
:func:`required_gamma_bisection`.

One driver (:func:`_point`) decides everything about a point: pre-checks, gamma scale, the passes
of the certificate (a rescaled second pass, a kernel basis adapted to a near-cancellation, the
bisection fallback for a stalled SDP), the explicit Delta and the status. The plain first SDP pass
of all the points that start with one is evaluated for the whole stack at once (stacked numerics,
one solver call per point, each under its own time budget) and handed to :func:`_point`, which
continues from it exactly as from its own first pass.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Collection, Iterator
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.lft import as_freq_matrix
from rotorcheck.robust.mu.backends import DEFAULT_BACKEND, LmiCache, SolverAbort, SolveSession
from rotorcheck.robust.mu.certificates import (
    EngineOut,
    Forms,
    adapted_basis,
    engine_bisection,
    engine_eig,
    engine_sdp,
    kernel_bases,
    kernel_rows,
    norm2,
    scaled_forms,
)
from rotorcheck.robust.mu.structure import (
    DEFAULT_TIME_LIMIT,
    STATUS_BAD_DATA,
    STATUS_FAILED,
    STATUS_LOWER_ONLY,
    STATUS_OK,
    STATUS_UNEXPLAINABLE,
    GammaResult,
    Points,
    Structure,
    check_noise_bound,
    layout,
    v0_floor,
)
from rotorcheck.robust.mu.witness import (
    CLOSE_RTOL,
    Deltas,
    Witness,
    explicit_delta,
    noise_ok,
    refine_gap,
    start_witness,
    upper_from,
)

# a stalled solve ('inaccurate') is accepted only if its verified gap stays below this
_INACCURATE_GAP = 1e-6
# second-pass triggers: s~ = (gamma / gamma estimate)^2 outside _S_RANGE, or a worst-case vector whose
# u-part is below _ADAPT_RHO of its norm (near-cancellation); _NEAR_ZERO: excess/residual scale below
# which the first pass already uses the adapted kernel basis
_S_RANGE = (1e-2, 1e2)
_ADAPT_RHO = 1e-2
_NEAR_ZERO = 1e-1

# testing hook (see inject_solver_failure): context-local, so concurrent calls do not see it
_INJECTED: ContextVar[frozenset[int]] = ContextVar("rotorcheck_mu_injected_failures",
                                                   default=frozenset())


@contextlib.contextmanager
def inject_solver_failure(indices: Collection[int]) -> Iterator[None]:
    """Testing hook: inside the ``with`` block every gamma computation (of this thread / context)
    treats the frequency indices ``indices`` as if the solver had failed there (status
    'solver_failed', gamma NaN)."""
    token = _INJECTED.set(_INJECTED.get() | frozenset(int(i) for i in indices))
    try:
        yield
    finally:
        _INJECTED.reset(token)


# --------------------------------------------------------------------------------------------------
# pre-checks and gamma scale of a stack of points


@dataclass
class _Plan:
    """Pre-checks and gamma scale, arrays (f,) over the points of a stack."""

    inside: np.ndarray  # the nominal model explains the data within the noise: gamma = 0
    unexplainable: np.ndarray  # the uncertainty cannot move the output
    excess: np.ndarray  # residual beyond the noise bound
    sig_max: np.ndarray  # residual scale max(|c|, V)
    ghat: np.ndarray  # gamma estimate (the scale of the LMI)
    error: list[str]  # '' or why the numerics failed at that point


def _noise_free_scale(pts: Points, ghat: np.ndarray) -> np.ndarray:
    """``s`` of the noise-free problem (an exact generalized eigenvalue, no solver) per point;
    NaN where it is not usable."""
    s = np.full(pts.f, np.nan)
    p0 = pts.noise_free()
    N, _ = kernel_rows(p0)
    for idx, P in kernel_bases(N):
        fm, _ = scaled_forms(p0.take(idx), ghat[idx], P)
        for i, out in zip(idx, engine_eig(fm), strict=True):
            if out.status == "ok" and np.isfinite(out.s_lower) and out.s_lower > 0:
                s[i] = out.s_lower
    return s


def _plan(pts: Points) -> _Plan:
    lay = pts.lay
    V, c = pts.V, pts.c
    # pre-check 1: the nominal model explains the data within the noise
    inside = noise_ok(c, V, pts.noise, pts.scale, rtol=0.0, atol=0.0)
    # pre-check 2: the uncertainty cannot move the output
    b_est = np.zeros(pts.f)
    for b, us, vs in zip(lay.blocks, lay.u_slices, lay.v_slices, strict=True):
        b_est = np.maximum(b_est, b.weight * norm2(pts.M21[:, :, us])
                           * np.linalg.norm(pts.M12W[:, vs], axis=1))
    unexpl = ~inside & (~np.isfinite(b_est) | (b_est == 0.0))
    if pts.noise == "per_output":
        excess = np.max(np.abs(c) - V[:, None], axis=1)
    else:
        excess = np.linalg.norm(c, axis=1) - V
    sig_max = np.max(np.maximum(np.abs(c), V[:, None]), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ghat = np.maximum(excess, 1e-14 * sig_max) / b_est
    error = [""] * pts.f
    todo = np.flatnonzero(~inside & ~unexpl & (V > 0))
    if lay.single and todo.size:
        # better gamma scale: the noise-free answer shrunk by the excess of the residual over the
        # noise (exact for additive SISO)
        try:
            s0 = _noise_free_scale(pts.take(todo), ghat[todo])
        except (np.linalg.LinAlgError, ArithmeticError):  # point by point, to name the point
            s0 = np.full(todo.size, np.nan)
            for k, i in enumerate(todo.tolist()):
                try:
                    s0[k] = _noise_free_scale(pts.take([i]), ghat[[i]])[0]
                except (np.linalg.LinAlgError, ArithmeticError) as exc:
                    error[i] = f"{type(exc).__name__}: {exc}"
        ok = np.isfinite(s0)
        t = todo[ok]
        ghat[t] = ghat[t] * np.sqrt(s0[ok]) * np.maximum(excess[t], 1e-14 * sig_max[t]) / sig_max[t]
    return _Plan(inside, unexpl, excess, sig_max, ghat, error)


def _kappa(V: float, excess: float, sig_max: float, n: int) -> list[float]:
    """Initial scale factors of the ``n`` noise D-scales of a point: they are about
    (V / sigma)(excess / sigma) at the optimum (exact for additive SISO); scaled to ~1 a tiny noise
    block does not stall the interior point method."""
    return [max(V / sig_max * max(excess, 0.0) / sig_max, 1e-12)] * n


# --------------------------------------------------------------------------------------------------
# the plain first pass of a stack of points


@dataclass
class _FirstPass:
    """The plain first SDP pass of one point, evaluated with its stack."""

    out: EngineOut
    P: np.ndarray  # orthonormal kernel basis (n, m) of the pass (scaled coordinates)
    S: np.ndarray  # column scaling (n,)
    stack_witness: Witness  # explicit Deltas of the stack from the pass's candidates alone
    j: int  # the point's index in stack_witness

    @property
    def witness(self) -> tuple[float, Deltas | None]:
        return self.stack_witness.point(self.j)


def _first_pass(pts: Points, plan: _Plan, idx: np.ndarray, session: SolveSession,
                time_limit: float) -> dict[int, _FirstPass]:
    """The first pass of :func:`_point` (orthonormal kernel basis, one SDP) for the points
    ``idx``, its explicit Delta included; each solve under its own budget of ``time_limit``."""
    out: dict[int, _FirstPass] = {}
    if idx.size == 0:
        return out
    sub = pts.take(idx)
    N, _ = kernel_rows(sub)
    for gi, P in kernel_bases(N):
        g = idx[gi]
        pg = sub.take(gi)
        n_fixed = pts.lay.n_out if pts.noise == "per_output" else 1
        kappa = np.array([_kappa(float(pts.V[i]), float(plan.excess[i]), float(plan.sig_max[i]),
                                 n_fixed) for i in g])
        fm, S = scaled_forms(pg, plan.ghat[g], P, kappa)
        res = engine_sdp(fm, session, point_seconds=time_limit)
        lower = np.array([max(0.0, float(plan.ghat[i]) * math.sqrt(r.s_lower))
                          if r.status == "ok" and math.isfinite(r.s_lower) else np.inf
                          for i, r in zip(g, res, strict=True)])
        cands = []
        for k in range(2):
            avail = np.array([r.status == "ok" and len(r.candidates) > k for r in res], dtype=bool)
            x = np.zeros(S.shape, complex)
            for q in np.flatnonzero(avail).tolist():
                x[q] = S[q] * res[q].candidates[k]
            cands.append((x, avail))
        wit = upper_from(pg, cands, lower, start_witness(pg))
        for j, i in enumerate(g.tolist()):
            out[i] = _FirstPass(res[j], P[j], S[j], wit, j)
    return out


# --------------------------------------------------------------------------------------------------
# the per-point driver


@dataclass
class _PointResult:
    lower: float
    upper: float
    status: str
    calls: int
    method: str
    deltas: list[np.ndarray] | None = None  # per block (p, q)
    reason: str = ""


def _vnorm(x: np.ndarray) -> float:
    """Euclidean norm of a vector."""
    return math.sqrt(float(np.vdot(x, x).real))


def _heuristic_x(pt: Points, S: np.ndarray) -> np.ndarray | None:
    """Worst-case guess in scaled coordinates: noise aligned with the residual (as large as the bound
    allows), u the least-squares rest. Exact for additive SISO."""
    V, c = float(pt.V[0]), pt.c[0]
    a = np.abs(c)
    if pt.noise == "per_output":
        e = np.where(a > 0, c / np.where(a > 0, a, 1) * np.minimum(1.0, a / V), 0)
    else:
        nc = float(np.linalg.norm(c))
        e = c / nc * min(1.0, nc / V) if nc > 0 else np.zeros_like(c)
    u = np.linalg.lstsq(pt.M21[0], c - V * e, rcond=None)[0]
    x = np.concatenate([u, e, [1.0]])
    return x / S


def _forms(pt: Points, ghat: float, basis: np.ndarray | None, kappa: list[float] | None) -> Forms:
    return scaled_forms(pt, np.array([ghat]), None if basis is None else basis[None],
                        None if kappa is None else np.array([kappa]))[0]


def _point(pt: Points, plan: _Plan, i: int, first: _FirstPass | None, mode: str, rtol: float,
           session: SolveSession) -> _PointResult:
    """Bounds at one frequency (``pt`` a stack of one: point ``i`` of ``plan``), continuing from
    its stacked first pass when given."""
    lay = pt.lay
    V = float(pt.V[0])
    excess, sig_max, ghat = float(plan.excess[i]), float(plan.sig_max[i]), float(plan.ghat[i])
    single = lay.single
    calls = 0
    lower = 0.0
    cands: list[np.ndarray] = []
    method = ""
    basis: np.ndarray | None = None
    kappa: list[float] | None = None
    upper: float = np.inf
    best: Deltas | None = None
    if lay.has_real and first is None:  # a real parameter alone: its exact explicit Delta
        upper, best = start_witness(pt).point(0)
    use_sdp = mode != "bisection" and single and V > 0
    inaccurate = False
    n_fixed = lay.n_out if pt.noise == "per_output" else 1  # noise blocks (V > 0)
    if use_sdp:
        kappa = _kappa(V, excess, sig_max, n_fixed)
    # P0: the orthonormal kernel basis (scaled coordinates; independent of ghat) of the first pass
    fm0: Forms | None = None
    if first is not None:
        P0, S = first.P, first.S
    else:
        fm0, Ss = scaled_forms(pt, np.array([ghat]), None,
                               None if kappa is None else np.array([kappa]))
        P0, S = fm0.P[0], Ss[0]
    if use_sdp and excess < _NEAR_ZERO * sig_max:  # (never a point with a stacked first pass)
        # gamma* far below the residual scale: start in a kernel basis adapted to the heuristic
        # worst case (noise aligned with the residual), D-scales of the noise scaled to ~1
        x0 = _heuristic_x(pt, S)
        if x0 is not None:
            basis = adapted_basis(P0, P0 @ (P0.conj().T @ x0), lay.nu)
            if basis is not None:
                kappa = [max(excess / sig_max, 1e-12)] * n_fixed
    last_pass = -1
    for _pass in range(3):
        last_pass = _pass
        if _pass == 0 and first is not None:
            P, out = P0, first.out
        else:
            fm = fm0 if (_pass == 0 and basis is None and fm0 is not None) else _forms(
                pt, ghat, basis, kappa)
            P = fm.P[0]
            if mode == "bisection" or not single:
                out = engine_bisection(fm, session, rtol, single)
            elif not fm.fixed_blocks and not lay.has_real:
                out = engine_eig(fm)[0]
            else:
                out = engine_sdp(fm, session)[0]
        calls += out.calls
        method = out.method
        inaccurate = inaccurate or out.inaccurate
        if out.status == "unbounded" and basis is None:
            return _PointResult(np.inf, np.inf, STATUS_UNEXPLAINABLE, calls, method)
        if out.status != "ok":
            if lower > 0 or cands:
                break  # keep the verified results of an earlier pass
            if basis is not None and _pass < 2:
                basis, kappa = None, None  # retry in the plain basis
                continue
            if not use_sdp:
                return _PointResult(np.nan, np.nan, STATUS_FAILED, calls, method)
            inaccurate = True  # no verified result at all: the bisection fallback below
            break
        lower = max(lower, ghat * math.sqrt(out.s_lower)) if math.isfinite(out.s_lower) else np.inf
        cands = [S * x for x in out.candidates] + cands  # latest pass first
        s = out.s_lower
        if out.method != "sdp" or not math.isfinite(s) or out.y is None or _pass == 2:
            break
        # next pass: rescale gamma by this answer and, when the worst-case vector is a
        # near-cancellation (gamma* << the residual scale), use a kernel basis adapted to it
        x1 = P @ out.y
        rho = _vnorm(x1[: lay.nu]) / max(_vnorm(x1), 1e-300)
        if out.inaccurate:
            # the solver stalled but its iterate may still be good: the independent bounds decide
            if _pass == 0 and first is not None:
                upper, best = first.witness
            else:
                upper, best = _upper_from(pt, cands, lower, upper, best)
            if upper <= lower * (1 + CLOSE_RTOL):
                break
        adapt = (rho < _ADAPT_RHO or out.inaccurate) and basis is None
        if _S_RANGE[0] <= s <= _S_RANGE[1] and not adapt and not out.inaccurate:
            break
        if kappa is not None:
            kappa = [k * (th if (math.isfinite(th) and th > 1e-14) else 1.0)
                     for k, th in zip(kappa, out.theta, strict=True)]
        ghat = ghat * (math.sqrt(s) if s > 0 else 1e-3)
        if adapt:
            nb = adapted_basis(P0, x1, lay.nu)
            if nb is not None:
                basis = nb
                kappa = [th * k if (math.isfinite(th) and th > 1e-14) else k
                         for th, k in zip(out.theta, kappa or [1.0] * len(out.theta), strict=True)]
    if not math.isfinite(lower):
        return _PointResult(np.inf, np.inf, STATUS_UNEXPLAINABLE, calls, method)
    if first is not None and last_pass == 0 and first.out.status == "ok":
        upper, best = first.witness  # the explicit Delta of the stacked first pass
        upper, best = refine_gap(pt, lower, upper, best, session)
    else:
        upper, best = explicit_delta(pt, cands, lower, upper, best, session)
    if inaccurate and (best is None or upper > lower * (1 + _INACCURATE_GAP) + 1e-300):
        # the SDP stalled (or failed) and its verified bounds do not close: a stalled iterate's
        # D-scales may be far from optimal, so solve the same LMI by bisection (feasibility
        # problems, scale of the uncertainty block fixed) and keep the best verified bounds. The
        # gap left then is the LMI's own (relaxation gap with several noise blocks), reported as is.
        outb = engine_bisection(_forms(pt, ghat, basis, kappa), session, rtol, True)
        calls += outb.calls
        method = "sdp+bisect"
        if outb.status != "ok" or not math.isfinite(outb.s_lower):
            return _PointResult(np.nan, np.nan, STATUS_FAILED, calls, method)
        lower = max(lower, ghat * math.sqrt(outb.s_lower))
        upper, best = explicit_delta(pt, [S * x for x in outb.candidates], lower, upper, best,
                                     session)
    if best is None:
        return _PointResult(lower, np.nan, STATUS_LOWER_ONLY, calls, method)
    # a verified Delta below a verified certificate means the numerics broke, beyond the floor set
    # by rounding of the data themselves (gamma* is a difference |c| - V of nearly equal numbers)
    floor = 1e-7 + 1e3 * np.finfo(float).eps * sig_max / max(excess, 1e-300)
    if upper < lower * (1 - floor):
        return _PointResult(np.nan, np.nan, STATUS_FAILED, calls, method)
    return _PointResult(lower, max(upper, lower), STATUS_OK, calls, method, [d[0] for d in best])


def _upper_from(pt: Points, cands: list[np.ndarray], lower: float, upper: float,
                best: Deltas | None) -> tuple[float, Deltas | None]:
    w = upper_from(pt, [(x[None], np.ones(1, dtype=bool)) for x in cands], np.array([lower]),
                   Witness.of_point(pt.lay, upper, best))
    return w.point(0)


def _solve_points(pts: Points, mode: str, rtol: float, session: SolveSession, time_limit: float
                  ) -> list[_PointResult]:
    """Every point of a stack: pre-checks, the stacked first pass, then :func:`_point` per point
    under its remaining time budget."""
    lay = pts.lay
    plan = _plan(pts)
    live = ~plan.inside & ~plan.unexplainable & np.array([not e for e in plan.error], dtype=bool)
    plain = (live & (mode != "bisection") & lay.single & (pts.V > 0)
             & ~(plan.excess < _NEAR_ZERO * plan.sig_max))
    try:
        first = _first_pass(pts, plan, np.flatnonzero(plain), session, time_limit)
    except (np.linalg.LinAlgError, ArithmeticError):
        first = {}  # every point then runs (and reports) its own first pass
    out = []
    for i in range(pts.f):
        if plan.error[i]:
            out.append(_PointResult(np.nan, np.nan, STATUS_FAILED, 0, "", reason=plan.error[i]))
            continue
        if plan.inside[i]:
            out.append(_PointResult(0.0, 0.0, STATUS_OK, 0, "precheck",
                                    [np.zeros(b.shape, complex) for b in lay.blocks]))
            continue
        if plan.unexplainable[i]:
            out.append(_PointResult(np.inf, np.inf, STATUS_UNEXPLAINABLE, 0, "precheck"))
            continue
        fp = first.get(i)
        n0 = fp.out.calls if fp is not None else 0
        if fp is not None and fp.out.status == "aborted":
            # the solver raised (a pyo3 panic) or ran out of time: that point fails, with the reason
            out.append(_PointResult(np.nan, np.nan, STATUS_FAILED, n0, "sdp", reason=fp.out.reason))
            continue
        spent = fp.out.seconds if fp is not None else 0.0
        try:
            with session.point_budget(time_limit - spent):
                out.append(_point(pts.point(i), plan, i, fp, mode, rtol, session))
        except SolverAbort as exc:
            out.append(_PointResult(np.nan, np.nan, STATUS_FAILED, n0, "", reason=str(exc)))
        except (np.linalg.LinAlgError, ArithmeticError) as exc:
            out.append(_PointResult(np.nan, np.nan, STATUS_FAILED, n0, "",
                                    reason=f"{type(exc).__name__}: {exc}"))
    return out


# --------------------------------------------------------------------------------------------------
# entry points


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


def _run(me: np.ndarray, W: np.ndarray, Zt: np.ndarray, noise_bound: float | np.ndarray,
         structure: Structure | None, mode: str, rtol: float, fail_at: Collection[int],
         backend: str, time_limit: float, cache: LmiCache | None) -> GammaResult:
    session = SolveSession(backend, cache)  # checks the backend
    if not time_limit > 0:
        raise ValueError(f"time_limit must be > 0 s, got {time_limit!r}")
    t0 = time.perf_counter()
    structure = structure or Structure()
    M, W_a, Zt_a, V = _prepare(me, W, Zt, noise_bound)
    f, n_in, n_out = Zt_a.shape[0], W_a.shape[1], Zt_a.shape[1]
    lay = layout(M.shape, n_in, n_out, structure)
    lower = np.full(f, np.nan)
    upper = np.full(f, np.nan)
    status = np.empty(f, dtype="<U13")
    method = np.empty(f, dtype="<U12")
    deltas: list[list[np.ndarray] | None] = [None] * f
    reason = np.full(f, "", dtype=object)
    calls = 0
    fails = set(int(i) for i in fail_at) | _INJECTED.get()
    injected = np.array([i in fails for i in range(f)], dtype=bool)
    # a point whose data are not finite (NaN/inf in Me, W or Zt) is marked, never solved
    finite = (np.all(np.isfinite(M), axis=(1, 2)) & np.all(np.isfinite(W_a), axis=1)
              & np.all(np.isfinite(Zt_a), axis=1))
    bad = ~finite & ~injected
    status[bad], method[bad] = STATUS_BAD_DATA, ""
    reason[bad] = "Me, W or Zt is not finite (NaN or inf) at this point"
    status[injected], method[injected] = STATUS_FAILED, "injected"
    reason[injected] = "injected failure (testing hook)"
    idx = np.flatnonzero(finite & ~injected)
    if idx.size:
        Vi = v0_floor(V[idx], Zt_a[idx]) if lay.has_real else V[idx]
        pts = Points.from_data(M[idx], W_a[idx], Zt_a[idx], Vi, lay, structure.noise)
        for i, r in zip(idx, _solve_points(pts, mode, rtol, session, time_limit), strict=True):
            lower[i], upper[i], status[i], method[i] = r.lower, r.upper, r.status, r.method
            deltas[i], reason[i] = r.deltas, r.reason
            calls += r.calls
    session.timing["wall"] = time.perf_counter() - t0
    return GammaResult(lower, upper, status, calls, method, deltas, session.timing, reason)


def required_gamma(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                   noise_bound: float | np.ndarray, structure: Structure | None = None, *,
                   fail_at: Collection[int] = (), rtol: float = 1e-8,
                   backend: str = DEFAULT_BACKEND, time_limit: float = DEFAULT_TIME_LIMIT,
                   cache: LmiCache | None = None) -> GammaResult:
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
    frequency). The first SDP pass of all points is evaluated as one stack (see the package
    docstring). Real scalar blocks (``Block('real', ...)``, :meth:`Structure.real`): D-G scalings
    (mixed mu, see the package docstring), a real explicit Delta; V = 0 points are
    solved with a relative noise floor there. ``time_limit``: seconds of solver time per frequency point (default 10).
    ``cache``: the built problems to reuse across calls (an :class:`LmiCache`, one per thread;
    default: a new one per call).

    Per point, never for the whole batch: data that are not finite give status 'bad_data'; a
    solver that raises (also a ``BaseException`` such as Clarabel's pyo3 ``PanicException``; only
    ``KeyboardInterrupt``/``SystemExit`` propagate) or runs out of time gives 'solver_failed' with
    the reason in ``GammaResult.reason``. A negative, NaN or infinite noise bound is a
    ``ValueError``.
    """
    return _run(me, W, Zt, noise_bound, structure, "auto", rtol, fail_at, backend, time_limit,
                cache)


def required_gamma_bisection(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                             noise_bound: float | np.ndarray, structure: Structure | None = None,
                             *, fail_at: Collection[int] = (), rtol: float = 1e-9,
                             backend: str = DEFAULT_BACKEND,
                             time_limit: float = DEFAULT_TIME_LIMIT,
                             cache: LmiCache | None = None) -> GammaResult:
    """Same bounds by bisection on gamma with an LMI feasibility problem per step (the classic
    approach of the dissertation, section 3.1); for benchmarking the one-SDP formulation."""
    return _run(me, W, Zt, noise_bound, structure, "bisection", rtol, fail_at, backend,
                time_limit, cache)
