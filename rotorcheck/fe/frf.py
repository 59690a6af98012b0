"""Frequency response (receptance, m/N) of a mechanical system, vectorised over frequency.

``H(w) = Z(w)^-1``, ``Z(w) = K - w^2 M + j w (C + Omega G)`` (method.md), frequencies in Hz at the
interface. Two engines, which agree to round-off (tests/fe):

- ``"solve"``: batched LU solves of Z for the requested input columns, ``np.linalg.solve`` on
  (f, n, n) stacks: O(f n^3), exact for any damping;
- ``"modal"``: one state-space eigendecomposition at the speed, then modal superposition
  ``H(w) = Y diag(1 / (j w - lambda)) W`` with ``Y`` the displacement rows of the right
  eigenvectors and ``W = V^-1 B``: O(n^3 + f n n_out n_in). Optionally truncated to the lowest modes.

``"auto"`` picks ``"modal"`` for more than 64 frequencies (measured faster, bench/bench_fe.py) and
``"solve"`` otherwise. The modal engine relies on a diagonalisable state matrix (always the case for
distinct eigenvalues; degenerate pairs of an axisymmetric rotor are fine); a condition-number check
falls back to ``"solve"`` when the eigenvector basis is ill-conditioned.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg as sla

from rotorcheck.fe.modal import state_matrix
from rotorcheck.fe.system import MechanicalSystem

TWO_PI = 2.0 * np.pi
Method = Literal["auto", "solve", "modal"]
_AUTO_MODAL_MIN_F = 64
_MAX_COND = 1e10


def _dofs(d: int | Sequence[int] | np.ndarray | None, n: int) -> np.ndarray:
    if d is None:
        return np.arange(n)
    return np.atleast_1d(np.asarray(d, dtype=int))


def receptance_solve(
    system: MechanicalSystem,
    freq_hz: np.ndarray,
    speed_rpm: float,
    out_dofs: np.ndarray,
    in_dofs: np.ndarray,
) -> np.ndarray:
    """Receptance by batched solves of Z(w): (f, n_out, n_in) complex, m/N."""
    Z = system.dynamic_stiffness(freq_hz, speed_rpm)
    B = np.zeros((system.n_dof, in_dofs.size))
    B[in_dofs, np.arange(in_dofs.size)] = 1.0
    X = np.linalg.solve(Z, np.broadcast_to(B, (Z.shape[0], *B.shape)))
    return X[:, out_dofs, :]


def modal_receptance(
    system: MechanicalSystem,
    freq_hz: np.ndarray,
    speed_rpm: float = 0.0,
    out_dofs: int | Sequence[int] | np.ndarray | None = None,
    in_dofs: int | Sequence[int] | np.ndarray | None = None,
    n_modes: int | None = None,
) -> np.ndarray:
    """Receptance by state-space modal superposition: (f, n_out, n_in) complex, m/N.

    ``n_modes``: keep only the lowest ``n_modes`` oscillatory modes (with their conjugates, plus any
    non-oscillatory real roots); None keeps all, which equals the direct solve.
    """
    n = system.n_dof
    out_d, in_d = _dofs(out_dofs, n), _dofs(in_dofs, n)
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    lam, Y, W = _modal_factors(system, speed_rpm, out_d, in_d)
    if n_modes is not None:
        keep = _lowest(lam, n_modes)
        lam, Y, W = lam[keep], Y[:, keep], W[keep]
    s = 1j * TWO_PI * f
    R = 1.0 / (s[:, None] - lam[None, :])  # (f, 2n)
    return np.einsum("ok,fk,ki->foi", Y, R, W, optimize=True)


def _modal_factors(
    system: MechanicalSystem,
    speed_rpm: float,
    out_d: np.ndarray,
    in_d: np.ndarray,
    check: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lambda (2n,), Y (n_out, 2n), W (2n, n_in)) of the state-space realisation at the speed.

    ``check``: raise LinAlgError when the eigenvector basis is ill-conditioned (defective A).
    """
    M = system.matrices(speed_rpm)[0]
    n = system.n_dof
    A = state_matrix(system, speed_rpm)
    lam, V = sla.eig(A, check_finite=False)
    if check and np.linalg.cond(V) > _MAX_COND:
        raise np.linalg.LinAlgError("ill-conditioned eigenvector basis")
    Minv_in = np.linalg.solve(M, np.eye(n)[:, in_d])  # (n, n_in)
    B = np.vstack([np.zeros_like(Minv_in), Minv_in]).astype(complex)
    return lam, V[out_d], np.linalg.solve(V, B)


def _lowest(lam: np.ndarray, n_modes: int) -> np.ndarray:
    """Indices of the lowest n_modes oscillatory modes and their conjugates (+ real roots)."""
    osc = np.nonzero(np.abs(lam.imag) > 1e-9 * max(np.abs(lam).max(), 1.0))[0]
    order = osc[np.argsort(np.abs(lam[osc].imag), kind="stable")]
    keep = order[: 2 * n_modes]
    real = np.setdiff1d(np.arange(lam.size), osc)
    return np.sort(np.r_[keep, real])


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
    out_d, in_d = _dofs(out_dofs, n), _dofs(in_dofs, n)
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    if method == "auto":
        method = "modal" if f.size > _AUTO_MODAL_MIN_F else "solve"
    if method == "solve":
        return receptance_solve(system, f, speed_rpm, out_d, in_d)
    if method != "modal":
        raise ValueError(f"unknown method {method!r} (auto, solve, modal)")
    try:
        lam, Y, W = _modal_factors(system, speed_rpm, out_d, in_d, check=True)
    except np.linalg.LinAlgError:
        return receptance_solve(system, f, speed_rpm, out_d, in_d)
    R = 1.0 / (1j * TWO_PI * f[:, None] - lam[None, :])
    return np.einsum("ok,fk,ki->foi", Y, R, W, optimize=True)


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
