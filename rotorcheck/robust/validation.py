"""Steps 3-4: validation of the uncertain model on healthy data, detection on new data, verdict.

Validation (FDMVOP): per frequency the healthy uncertainty bound ``gamma_h(w)``:

* ``enclose='data'`` (the dissertation): the smallest gamma for which the uncertain model
  ``F_u(Me, gamma Delta) W + V Delta_v`` reproduces the healthy data. We store the *upper* bound of
  the LMI pair (the size of an explicit, verified Delta), so the healthy data is provably enclosed.
  This puts the healthy data on the edge of the set: a repeat healthy sweep with fresh noise leaves
  it wherever the model error exceeds the noise (false alarms).
* ``enclose='system'``: the smallest gamma whose model set contains every system consistent with
  the data and V, i.e. the whole data disk ``|Z - Zt| <= V`` (SISO, one complex scalar Delta;
  exact closed form via the Moebius pre-image; additive: ``(|Zt - G W| + V)/|W|``), in units of the
  weighted block: ``|Delta| <= weight * gamma`` (the Structure's ``Block.weight``, as in 'data').
  Where ``Me12 Me21 W = 0`` the uncertainty cannot reach the output: 'unexplainable', never a
  number (unless ``V = 0`` and the data equal the nominal output exactly: gamma = 0).

Several healthy sweeps: gamma_h is the maximum over the sweeps, point by point.

Detection (FDIMVDP): a point of new data is a fault iff ``gamma_required_new > gamma_h``. We compare
the *certified lower* bound of the new data's required gamma (every gamma below it is proven to be
invalidated) with ``gamma_h (1 + rtol)``; ``rtol = 1e-6`` absorbs rounding and the LMI gap (about
1e-9 relative for SISO) and is far below any physical resolution.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

import numpy as np

from rotorcheck.robust.closed_form import gamma_enclose_system_additive, gamma_enclose_system_siso
from rotorcheck.robust.lft import as_freq_matrix
from rotorcheck.robust.mu.structure import (
    DEFAULT_BACKEND,
    DEFAULT_TIME_LIMIT,
    STATUS_BAD_DATA,
    STATUS_FAILED,
    STATUS_LOWER_ONLY,
    STATUS_OK,
    STATUS_UNEXPLAINABLE,
    GammaResult,
    Structure,
    check_noise_bound,
)
from rotorcheck.robust.noise import NoiseBound

__all__ = [
    "STATUS_EXCLUDED",
    "DetectionResult",
    "ValidationResult",
    "Verdict",
    "detect",
    "longest_run",
    "validate",
    "verdict",
]

STATUS_FAULT = "fault"
STATUS_NO_BASELINE = "no_baseline"
#: a point the caller kept out of every claim (e.g. on a shaft harmonic): neither fault nor undecided, and not
#: an enclosure failure of the healthy data
STATUS_EXCLUDED = "excluded"
_SEVERITY = {STATUS_OK: 0, STATUS_LOWER_ONLY: 1, STATUS_UNEXPLAINABLE: 2, STATUS_FAILED: 3,
             STATUS_BAD_DATA: 4}
_UNDECIDED = (STATUS_FAILED, STATUS_NO_BASELINE, STATUS_BAD_DATA)


def _v(noise_bound: float | np.ndarray | NoiseBound) -> float | np.ndarray:
    """V (m) from a number, an array or a :class:`NoiseBound`; ``ValueError`` naming the noise
    bound if it is negative, NaN or infinite anywhere."""
    V = noise_bound.value_m if isinstance(noise_bound, NoiseBound) else noise_bound
    check_noise_bound(V)
    return V


@dataclass
class ValidationResult:
    """Healthy uncertainty bound per frequency (f,), units of Delta_u.

    ``gamma``: the baseline gamma_h (enclose='data': verified upper bound; 'system': closed form);
    ``gamma_lower``/``gamma_upper``: the LMI pair (equal to ``gamma`` for 'system');
    ``status``: 'ok' | 'unexplainable' (no finite gamma encloses the data) | 'solver_failed' |
    'lower_only' | 'bad_data' (Me, W or Zt not finite there); worst over the sweeps;
    ``reason``: '' or why a point failed (first sweep that gives one).
    """

    gamma: np.ndarray
    gamma_lower: np.ndarray
    gamma_upper: np.ndarray
    status: np.ndarray
    enclose: str
    noise_bound_m: float | np.ndarray
    n_solver_calls: int = 0
    per_sweep: list[GammaResult] = field(default_factory=list)
    reason: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))

    @property
    def enclosed(self) -> bool:
        """True when every point not excluded has a finite, verified gamma_h."""
        return bool(np.all(np.isin(self.status, [STATUS_OK, STATUS_EXCLUDED])))

    def exclude(self, points: np.ndarray) -> None:
        """Mark ``points`` (f,) bool 'excluded': their gamma_h stays computed (figures) but is no part of the
        bound (status not 'ok': detection and the verdict do not use it)."""
        self.status = np.where(np.asarray(points, dtype=bool), STATUS_EXCLUDED, self.status).astype("<U13")


def _as_list(x: np.ndarray | Sequence[np.ndarray]) -> list[np.ndarray]:
    if isinstance(x, (list, tuple)):
        return [np.asarray(a) for a in x]
    return [np.asarray(x)]


def validate(me: np.ndarray, W: np.ndarray | Sequence[np.ndarray],
             Zt: np.ndarray | Sequence[np.ndarray], noise_bound: float | np.ndarray | NoiseBound,
             enclose: str = "data", structure: Structure | None = None, *,
             fail_at: Collection[int] = (), backend: str = DEFAULT_BACKEND,
             time_limit: float = DEFAULT_TIME_LIMIT) -> ValidationResult:
    """gamma_h per frequency from healthy data.

    ``me``: ``(f, n_v + n_out, n_u + n_in)``; ``W``/``Zt``: input (N) and output (m) phasors,
    ``(f, n_in)``/``(f, n_out)`` or ``(f,)``, or lists of them for several healthy sweeps (max over
    sweeps); ``noise_bound``: V (m) or a :class:`NoiseBound`; ``enclose``: 'data' | 'system';
    ``backend``/``time_limit``: LMI backend and per-point solver time limit (s) of
    :func:`rotorcheck.robust.mu.required_gamma`; ``fail_at``: testing hook (indices treated as
    solver failures). ``ValueError`` if V is negative, NaN or infinite anywhere.
    """
    V = _v(noise_bound)
    Ws, Zs = _as_list(W), _as_list(Zt)
    if len(Ws) != len(Zs):
        raise ValueError("W and Zt must have the same number of sweeps")
    if enclose not in ("data", "system"):
        raise ValueError(f"enclose must be 'data' or 'system', got {enclose!r}")
    f = Zs[0].shape[0]
    lo = np.full(f, -np.inf)
    up = np.full(f, -np.inf)
    sev = np.zeros(f, dtype=int)
    reason = np.full(f, "", dtype=object)
    calls = 0
    per: list[GammaResult] = []
    for Wk, Zk in zip(Ws, Zs, strict=True):
        if enclose == "data":
            from rotorcheck.robust.mu.driver import required_gamma  # lazy: the LMI solvers (cvxpy) load only when used

            res = required_gamma(me, Wk, Zk, V, structure, fail_at=fail_at, backend=backend,
                                 time_limit=time_limit)
            per.append(res)
            calls += res.n_solver_calls
            g_lo, g_up, st = res.gamma_lower, res.gamma_upper, res.status
            rk = res.reason
        else:
            g, st, rk = _enclose_system(me, Wk, Zk, V, structure, f, fail_at)
            g_lo = g_up = g
        lo = np.fmax(lo, g_lo)
        up = np.fmax(up, g_up)
        sev = np.maximum(sev, np.array([_SEVERITY.get(s, 3) for s in st]))
        reason = np.where(reason == "", rk, reason)
    inv = {v: k for k, v in _SEVERITY.items()}
    status = np.array([inv[s] for s in sev], dtype="<U13")
    gam = np.where(status == STATUS_OK, up, np.where(status == STATUS_UNEXPLAINABLE, np.inf, np.nan))
    undecided = np.isin(status, _UNDECIDED)
    lo = np.where(undecided, np.nan, lo)
    up = np.where(undecided, np.nan, up)
    return ValidationResult(gam, lo, up, status, enclose, V, calls, per, reason)


def _additive_shape(M: np.ndarray, W: np.ndarray, Zt: np.ndarray, f: int) -> bool:
    """Whether ``M`` is the additive uncertainty's ``[[0, I_in], [I_out, G]]`` for the data's sizes."""
    n_in = np.asarray(W).reshape(f, -1).shape[1]
    n_out = np.asarray(Zt).reshape(f, -1).shape[1]
    if M.shape[1:] != (n_in + n_out, n_out + n_in):
        return False
    return (np.allclose(M[:, :n_in, :n_out], 0) and np.allclose(M[:, :n_in, n_out:], np.eye(n_in))
            and np.allclose(M[:, n_in:, :n_out], np.eye(n_out)))


def _enclose_system(me: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: float | np.ndarray,
                    structure: Structure | None, f: int, fail_at: Collection[int]
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """enclose='system' for one sweep: (gamma, status, reason), each (f,).

    The closed form gives the smallest ``|Delta|``; the block bound is ``|Delta| <= weight gamma``,
    so gamma is that divided by the block weight."""
    M = as_freq_matrix(me, f)
    blocks = (structure or Structure()).blocks
    if M.shape[1:] != (2, 2) and blocks is None and _additive_shape(M, W, Zt, f):
        # several outputs/inputs, additive full block (Me = [[0, I], [I, G]]): closed form
        n_in = np.asarray(W).reshape(f, -1).shape[1]
        n_out = np.asarray(Zt).reshape(f, -1).shape[1]
        g = gamma_enclose_system_additive(M[:, n_in:, n_out:], W, Zt, V)
        st = np.asarray(np.where(np.isfinite(g), STATUS_OK, STATUS_UNEXPLAINABLE), dtype="<U13")
        reason = np.full(f, "", dtype=object)
        for i in set(int(j) for j in fail_at):
            st[i], g[i], reason[i] = STATUS_FAILED, np.nan, "injected failure (testing hook)"
        return g, st, reason
    if M.shape[1:] != (2, 2) or (blocks is not None and len(blocks) != 1):
        raise NotImplementedError(
            "enclose='system' is implemented for SISO data with one complex scalar "
            "uncertainty (Me of shape (f, 2, 2))")
    block = (structure or Structure()).resolve(1, 1)[0]
    if block.is_real:
        raise NotImplementedError("enclose='system' has a closed form for a complex scalar only; "
                                  "a real parameter block needs enclose='data'")
    Wv = np.asarray(W, dtype=complex).reshape(f, -1)
    Zv = np.asarray(Zt, dtype=complex).reshape(f, -1)
    if Wv.shape[1] != 1 or Zv.shape[1] != 1:
        raise NotImplementedError("enclose='system' needs one input and one output")
    finite = np.all(np.isfinite(M), axis=(1, 2)) & np.isfinite(Wv[:, 0]) & np.isfinite(Zv[:, 0])
    with np.errstate(invalid="ignore"):
        g = gamma_enclose_system_siso(M, Wv[:, 0], Zv[:, 0], V) / block.weight
    st = np.asarray(np.where(np.isfinite(g), STATUS_OK, STATUS_UNEXPLAINABLE), dtype="<U13")
    reason = np.full(f, "", dtype=object)
    reason[st == STATUS_UNEXPLAINABLE] = ("no finite gamma encloses the data: the uncertainty "
                                          "does not reach the output, or alpha <= 0")
    st[~finite], g[~finite] = STATUS_BAD_DATA, np.nan
    reason[~finite] = "Me, W or Zt is not finite (NaN or inf) at this point"
    for i in set(int(j) for j in fail_at):
        st[i], g[i], reason[i] = STATUS_FAILED, np.nan, "injected failure (testing hook)"
    return g, st, reason


@dataclass
class DetectionResult:
    """Per-point detection (f,).

    ``gamma_required``: certified lower bound of the gamma the new data needs (inf when no gamma
    explains it, NaN on failure); ``gamma_required_upper``: verified upper bound;
    ``gamma_healthy``: gamma_h; ``fault``: bool; ``status``: 'ok' | 'fault' | 'unexplainable'
    (no finite gamma explains the new data: counted as a fault) | 'solver_failed' (no decision) |
    'bad_data' (Me, W or the new data not finite at this point: no decision) | 'no_baseline'
    (gamma_h not finite at this point: no decision); ``reason``: '' or why a point failed.
    """

    gamma_required: np.ndarray
    gamma_required_upper: np.ndarray
    gamma_healthy: np.ndarray
    fault: np.ndarray
    status: np.ndarray
    rtol: float
    n_solver_calls: int = 0
    reason: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))

    @property
    def n_fault(self) -> int:
        """Number of fault points."""
        return int(np.count_nonzero(self.fault))


def detect(me: np.ndarray, W: np.ndarray, Zt_new: np.ndarray,
           noise_bound: float | np.ndarray | NoiseBound, gamma_h: np.ndarray,
           structure: Structure | None = None, *, rtol: float = 1e-6,
           fail_at: Collection[int] = (), backend: str = DEFAULT_BACKEND,
           time_limit: float = DEFAULT_TIME_LIMIT) -> DetectionResult:
    """Fault points of new data against the healthy bound ``gamma_h`` (f,).

    fault iff ``gamma_required_lower > gamma_h (1 + rtol)`` (certified invalidation). ``ValueError``
    if V is negative, NaN or infinite anywhere.
    """
    V = _v(noise_bound)
    gh = np.asarray(gamma_h, dtype=float).reshape(-1)
    from rotorcheck.robust.mu.driver import required_gamma  # lazy: the LMI solvers (cvxpy) load only when used

    res = required_gamma(me, W, Zt_new, V, structure, fail_at=fail_at, backend=backend,
                         time_limit=time_limit)
    f = gh.size
    if res.gamma_lower.size != f:
        raise ValueError(f"gamma_h has {f} points, the data {res.gamma_lower.size}")
    fault = np.zeros(f, dtype=bool)
    status = np.empty(f, dtype="<U13")
    for i in range(f):
        st = res.status[i]
        if not np.isfinite(gh[i]):
            status[i] = STATUS_NO_BASELINE
        elif st in (STATUS_FAILED, STATUS_BAD_DATA):
            status[i] = st
        elif st == STATUS_UNEXPLAINABLE:
            status[i], fault[i] = STATUS_UNEXPLAINABLE, True
        elif res.gamma_lower[i] > gh[i] * (1 + rtol):
            status[i], fault[i] = STATUS_FAULT, True
        else:
            status[i] = STATUS_OK
    return DetectionResult(res.gamma_lower, res.gamma_upper, gh, fault, status, rtol,
                           res.n_solver_calls, res.reason)


@dataclass
class Verdict:
    """Sweep-level decision: 'damage' | 'healthy' | 'inconclusive' and why."""

    verdict: str
    reason: str
    n_points: int
    n_fault: int
    n_undecided: int
    longest_run: int
    threshold: int


def longest_run(mask: np.ndarray) -> int:
    """Length of the longest run of adjacent True values."""
    best = cur = 0
    for m in mask:
        cur = cur + 1 if m else 0
        best = max(best, cur)
    return best


def verdict(fault: np.ndarray, status: np.ndarray, healthy_status: np.ndarray | None = None, *,
            min_points: int = 3, min_fraction: float = 0.02, min_run: int = 2) -> Verdict:
    """Sweep verdict from per-point detection.

    Rule: 'damage' if ``n_fault >= max(min_points, ceil(min_fraction * n))`` or the longest run of
    adjacent fault points is ``>= min_run`` (fault points are certified invalidations, so they count
    even when other points could not be decided); otherwise 'inconclusive' if any point is
    undecided (solver failure, bad data, no baseline) or the healthy data could not be enclosed somewhere
    (``healthy_status`` not all 'ok'); otherwise 'healthy'. Points of status 'excluded' (in either) are
    neither undecided nor an enclosure failure; they are no fault points either (the caller clears them).
    """
    fault = np.asarray(fault, dtype=bool)
    status = np.asarray(status)
    n = fault.size
    thr = max(min_points, int(np.ceil(min_fraction * n)))
    n_fault = int(np.count_nonzero(fault))
    run = longest_run(fault)
    undecided = int(np.count_nonzero(np.isin(status, _UNDECIDED)))
    if n_fault >= thr or run >= min_run:
        why = (f"{n_fault} fault points (threshold {thr})" if n_fault >= thr
               else f"{run} adjacent fault points (threshold {min_run})")
        return Verdict("damage", why, n, n_fault, undecided, run, thr)
    bad_healthy = 0
    if healthy_status is not None:
        bad_healthy = int(np.count_nonzero(~np.isin(np.asarray(healthy_status), [STATUS_OK, STATUS_EXCLUDED])))
    if undecided or bad_healthy:
        reasons: list[str] = []
        if undecided:
            reasons.append(f"{undecided} points undecided (solver failure, bad data or no baseline)")
        if bad_healthy:
            reasons.append(f"healthy data not enclosed at {bad_healthy} points")
        return Verdict("inconclusive", "; ".join(reasons), n, n_fault, undecided, run, thr)
    return Verdict("healthy", f"{n_fault} fault points, below threshold {thr} and no run of "
                   f"{min_run}", n, n_fault, undecided, run, thr)
