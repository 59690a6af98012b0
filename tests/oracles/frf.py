"""Receptances computed independently of :mod:`rotorcheck.fe.frf` (test oracles).

``dense_receptance``: per-frequency dense solves of ``Z(w) = K - w^2 M + j w (C + Omega G)``;
``modal_receptance``: state-space modal superposition of the full first-order system, optionally
truncated to the lowest modes (plus real roots). Both build their own matrices from
``system.matrices``. Small grids and models only (they form dense (n, n) systems per frequency).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg as sla

from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem

TWO_PI = 2.0 * np.pi
Dofs = int | Sequence[int] | np.ndarray | None


def _dofs(d: Dofs, n: int) -> np.ndarray:
    return np.arange(n) if d is None else np.atleast_1d(np.asarray(d, dtype=int))


def dense_receptance(
    system: MechanicalSystem, freq_hz: np.ndarray | Sequence[float] | float, speed_rpm: float = 0.0,
    out_dofs: Dofs = None, in_dofs: Dofs = None,
) -> np.ndarray:
    """(f, n_out, n_in) complex, m/N, by ``np.linalg.solve(Z(w), B)`` at every frequency."""
    M, C, G, K = system.matrices(speed_rpm)
    D = C + speed_rpm * RPM_TO_RAD_S * G
    n = system.n_dof
    o, i = _dofs(out_dofs, n), _dofs(in_dofs, n)
    B = np.zeros((n, i.size))
    B[i, np.arange(i.size)] = 1.0
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    out = np.empty((f.size, o.size, i.size), dtype=complex)
    for k, fk in enumerate(f):
        w = TWO_PI * fk
        out[k] = np.linalg.solve(K - w**2 * M + 1j * w * D, B)[o]
    return out


def _lowest(lam: np.ndarray, n_modes: int) -> np.ndarray:
    """Indices of the lowest n_modes oscillatory modes and their conjugates (+ real roots)."""
    osc = np.nonzero(np.abs(lam.imag) > 1e-9 * max(np.abs(lam).max(), 1.0))[0]
    order = osc[np.argsort(np.abs(lam[osc].imag), kind="stable")]
    keep = order[: 2 * n_modes]
    real = np.setdiff1d(np.arange(lam.size), osc)
    return np.sort(np.r_[keep, real])


def modal_receptance(
    system: MechanicalSystem, freq_hz: np.ndarray | Sequence[float] | float, speed_rpm: float = 0.0,
    out_dofs: Dofs = None, in_dofs: Dofs = None, n_modes: int | None = None,
) -> np.ndarray:
    """(f, n_out, n_in) by state-space modal superposition ``Y diag(1/(jw - lambda)) W``.

    ``n_modes``: keep only the lowest ``n_modes`` oscillatory modes (with their conjugates, plus any
    non-oscillatory real roots); None keeps all, which equals the direct solve.
    """
    M, C, G, K = system.matrices(speed_rpm)
    D = C + speed_rpm * RPM_TO_RAD_S * G
    n = system.n_dof
    o, i = _dofs(out_dofs, n), _dofs(in_dofs, n)
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])
    lam, V = sla.eig(A)
    B = np.vstack([np.zeros((n, i.size)), Minv[:, i]]).astype(complex)
    Y, W = V[o], np.linalg.solve(V, B)
    if n_modes is not None:
        keep = _lowest(lam, n_modes)
        lam, Y, W = lam[keep], Y[:, keep], W[keep]
    s = 1j * TWO_PI * np.atleast_1d(np.asarray(freq_hz, dtype=float))
    return np.einsum("ok,fk,ki->foi", Y, 1.0 / (s[:, None] - lam[None, :]), W, optimize=True)
