"""Structure and result types: what the validation problem is, not how it is solved.

The uncertainty blocks (:class:`Block`, :class:`Structure`) and their place in Me's Delta channel
(:class:`Layout`), the data of a stack of frequency points (:class:`Points`, leading axis = the
points), the noise-bound check, the per-point statuses and the result (:class:`GammaResult`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

STATUS_OK = "ok"
STATUS_FAILED = "solver_failed"
STATUS_UNEXPLAINABLE = "unexplainable"
STATUS_LOWER_ONLY = "lower_only"
STATUS_BAD_DATA = "bad_data"
# seconds of solver time per frequency point (every Clarabel call gets the point's remaining budget
# as its ``time_limit``); a point that exhausts it is 'solver_failed' with the reason
DEFAULT_TIME_LIMIT = 10.0
DEFAULT_BACKEND = "clarabel"  # the Clarabel-direct backend (no cvxpy); "cvxpy" builds the LMI with cvxpy


@dataclass(frozen=True)
class Block:
    """One uncertainty block ``Delta_i`` mapping ``v_i`` (``shape[1]``) to ``u_i`` (``shape[0]``).

    ``kind``: 'scalar' (complex scalar, 1x1), 'repeated' (``delta I_k``, ``shape=(k, k)``),
    'full' (complex matrix) or 'real' (a REAL scalar ``delta I_k``, ``shape=(k, k)``; k = 1 a real
    parameter, k > 1 a real parameter entering with rank k). Its bound is
    ``sigma_max(Delta_i) <= weight * gamma``. A real block gets a D-scale and a G-scale in the
    certificate (mixed mu, D-G scalings; see the package docstring).
    """

    kind: str = "full"
    shape: tuple[int, int] = (1, 1)
    weight: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in ("scalar", "repeated", "full", "real"):
            raise ValueError(f"unknown block kind {self.kind!r}")
        if self.kind == "scalar" and tuple(self.shape) != (1, 1):
            raise ValueError("a scalar block has shape (1, 1)")
        if self.kind in ("repeated", "real") and self.shape[0] != self.shape[1]:
            raise ValueError(f"a {self.kind} scalar block is square")
        if self.weight <= 0:
            raise ValueError("block weight must be positive")

    @property
    def is_real(self) -> bool:
        """A real (repeated) scalar block."""
        return self.kind == "real"

    @property
    def lmi_kind(self) -> str:
        """'full' (scalar D-scale), 'repeated' (Hermitian D-scale), 'real' (real scalar: scalar D
        and G scales) or 'realrep' (real repeated scalar: Hermitian D and G scales)."""
        if self.kind == "real":
            return "realrep" if self.shape[0] > 1 else "real"
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

    @staticmethod
    def real(k: int = 1, weight: float = 1.0) -> Structure:
        """One REAL (repeated) scalar ``delta I_k``, ``|delta| <= weight gamma``: a physical
        parameter (a mass, a stiffness) that can only change by a real amount."""
        return Structure((Block("real", (k, k), weight),))

    @property
    def has_real(self) -> bool:
        """Some block is a real scalar."""
        return self.blocks is not None and any(b.is_real for b in self.blocks)

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


def blocks_for(me_shape: Sequence[int], n_in: int, n_out: int, structure: Structure
               ) -> tuple[Block, ...]:
    """The resolved block list for an Me of shape ``(f, rows, cols)`` (helper for callers)."""
    return structure.resolve(me_shape[-1] - n_in, me_shape[-2] - n_out)


@dataclass(frozen=True)
class Layout:
    """The resolved blocks and their slices of the Delta channel (``u`` rows, ``v`` columns)."""

    blocks: tuple[Block, ...]
    u_slices: tuple[slice, ...]
    v_slices: tuple[slice, ...]
    nu: int
    nv: int
    n_in: int
    n_out: int

    @property
    def single(self) -> bool:
        """One uncertainty block with a scalar D-scale (one SDP per point, no bisection); a real
        scalar (k = 1) also has a free G-scale."""
        return len(self.blocks) == 1 and self.blocks[0].lmi_kind in ("full", "real")

    @property
    def has_real(self) -> bool:
        """Some block is a real scalar (D-G scalings; no exact eigenvalue shortcut)."""
        return any(b.is_real for b in self.blocks)


def layout(me_shape: Sequence[int], n_in: int, n_out: int, structure: Structure) -> Layout:
    """The layout of an Me of shape ``(..., n_v + n_out, n_u + n_in)`` for ``structure``."""
    nv = me_shape[-2] - n_out
    nu = me_shape[-1] - n_in
    if nv < 0 or nu < 0:
        raise ValueError(f"Me shape {tuple(me_shape[-2:])} too small for {n_out} outputs, "
                         f"{n_in} inputs")
    blocks = structure.resolve(nu, nv)
    us, vs, ou, ov = [], [], 0, 0
    for b in blocks:
        us.append(slice(ou, ou + b.shape[0]))
        vs.append(slice(ov, ov + b.shape[1]))
        ou += b.shape[0]
        ov += b.shape[1]
    return Layout(tuple(blocks), tuple(us), tuple(vs), nu, nv, n_in, n_out)


@dataclass(frozen=True)
class Points:
    """The data of a stack of frequency points sharing one layout (leading axis: the points).

    ``M11`` (f, nv, nu), ``M21`` (f, n_out, nu), ``M12W = Me12 W`` (f, nv), the residual of the
    nominal model ``c = Zt - Me22 W`` (f, n_out; the data, rounded once, here: every residual is
    evaluated as ``c - (z - Me22 W)``), the noise bound ``V`` (f,) and the residual scale
    ``max(|c|, V)`` (f, n_out).
    """

    lay: Layout
    noise: str
    M11: np.ndarray
    M12W: np.ndarray
    M21: np.ndarray
    c: np.ndarray
    V: np.ndarray
    scale: np.ndarray

    @classmethod
    def from_data(cls, M: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: np.ndarray, lay: Layout,
                  noise: str) -> Points:
        """Points from Me (f, nv + n_out, nu + n_in), W (f, n_in), Zt (f, n_out), V (f,)."""
        nv, nu = lay.nv, lay.nu
        c = Zt - (M[:, nv:, nu:] @ W[:, :, None])[:, :, 0]
        m12w = (M[:, :nv, nu:] @ W[:, :, None])[:, :, 0]
        V = np.asarray(V, dtype=float)
        return cls(lay, noise, M[:, :nv, :nu], m12w, M[:, nv:, :nu], c, V,
                   np.maximum(np.abs(c), V[:, None]))

    @property
    def f(self) -> int:
        """Number of points."""
        return int(self.V.shape[0])

    def take(self, idx: np.ndarray | Sequence[int]) -> Points:
        """The points ``idx`` (an index array) as a new stack."""
        ix = np.asarray(idx, dtype=int)
        return Points(self.lay, self.noise, self.M11[ix], self.M12W[ix], self.M21[ix], self.c[ix],
                      self.V[ix], self.scale[ix])

    def point(self, i: int) -> Points:
        """Point i as a stack of one (views)."""
        sl = slice(i, i + 1)
        return Points(self.lay, self.noise, self.M11[sl], self.M12W[sl], self.M21[sl], self.c[sl],
                      self.V[sl], self.scale[sl])

    def noise_free(self) -> Points:
        """The same points with ``V = 0`` (the residual scale is kept)."""
        return replace(self, V=np.zeros_like(self.V))


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


# relative noise floor (of max |Zt|) used for V = 0 points of a structure with a real block: the
# data pin delta there, and a delta that is real in exact arithmetic is real only to rounding
REAL_V0_FLOOR = 1e-6


def v0_floor(V: np.ndarray, Zt: np.ndarray) -> np.ndarray:
    """Noise bound (m) of points with a real block: V, or :data:`REAL_V0_FLOOR` times
    ``max_k |Zt_k|`` where V = 0 (f,)."""
    zmax = np.max(np.abs(Zt), axis=1) if Zt.size else np.zeros(V.shape)
    return np.where(V > 0, V, REAL_V0_FLOOR * zmax)


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
