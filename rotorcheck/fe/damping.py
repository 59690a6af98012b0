"""Structural damping matrices built from M and K: modal (from the undamped modes) and Rayleigh.

Modal damping: ``C = M Phi diag(2 zeta_i w_i) Phi^T M`` with the mass-normalised undamped modes
``Phi`` of ``(K_s, M)`` (all of them), ``K_s = (K + K^T) / 2`` (the symmetric part, so cross-coupled
bearings are allowed), ``w_i`` in rad/s. Then ``Phi^T C Phi = diag(2 zeta_i w_i)`` exactly.

Ratios are given per *distinct* mode, the last value repeating. An axisymmetric rotor has each
bending mode twice (x and y planes, degenerate or, with unequal bearing stiffnesses, nearly so), so
the i-th ratio goes to the i-th mode *pair*. Pairs are detected as follows:

- if M and K do not couple the planes (``K[x, y] == 0``, the usual case, including kxx != kyy),
  each plane is solved on its own and the i-th mode of each plane gets ratio i (robust: no
  tolerance on frequencies, works for split pairs);
- otherwise (cross-coupled supports) the modes are sorted by frequency and modes 2i, 2i+1 form pair i.

Lumped models have no planes: ratio i goes to mode i.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from rotorcheck.lazy import lazy_module

if TYPE_CHECKING:
    import scipy.linalg as sla
else:  # loaded at the first modal damping matrix, not by every command importing the FE package
    sla = lazy_module("scipy.linalg")


def ratio_per_mode(ratios: Sequence[float], n: int) -> np.ndarray:
    """Ratios for n modes: the given list, the last value repeating."""
    r = np.asarray(ratios, dtype=float)
    if r.size == 0:
        return np.zeros(n)
    out = np.full(n, r[-1])
    out[: min(n, r.size)] = r[:n]
    return out


def undamped_modes(M: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Undamped modes of the symmetric part of K: ``(w (rad/s), Phi)`` with Phi^T M Phi = I.

    Negative eigenvalues (unsupported rigid-body modes, round-off) give w = 0.
    """
    Ks = 0.5 * (K + K.T)
    lam, phi = sla.eigh(Ks, M)
    return np.sqrt(np.clip(lam, 0.0, None)), phi


def _modal_block(M: np.ndarray, K: np.ndarray, zeta_of_rank: np.ndarray) -> np.ndarray:
    w, phi = undamped_modes(M, K)
    mp = M @ phi
    return (mp * (2.0 * zeta_of_rank[: w.size] * w)) @ mp.T


def modal_damping_matrix(
    M: np.ndarray,
    K: np.ndarray,
    ratios: Sequence[float],
    planes: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Modal damping matrix (N s/m) from ``ratios`` per distinct mode (see module docstring).

    ``planes``: DOF indices of the x plane and the y plane of a rotor (None for lumped models).
    """
    n = M.shape[0]
    if planes is None:
        return _modal_block(M, K, ratio_per_mode(ratios, n))
    ix, iy = planes
    scale = max(np.abs(K).max(), 1e-300)
    coupled = (
        np.abs(K[np.ix_(ix, iy)]).max(initial=0.0) > 1e-14 * scale
        or np.abs(K[np.ix_(iy, ix)]).max(initial=0.0) > 1e-14 * scale
        or np.abs(M[np.ix_(ix, iy)]).max(initial=0.0) > 0.0
    )
    if not coupled:
        C = np.zeros_like(M)
        for idx in (ix, iy):
            sub = np.ix_(idx, idx)
            C[sub] = _modal_block(M[sub], K[sub], ratio_per_mode(ratios, idx.size))
        return C
    pair_rank = np.arange(n) // 2
    return _modal_block(M, K, ratio_per_mode(ratios, n)[pair_rank])


def rayleigh_damping_matrix(
    M: np.ndarray, K: np.ndarray, alpha: float, beta: float, symmetric: bool = True
) -> np.ndarray:
    """C = alpha M + beta K_s (alpha 1/s, beta s; K_s the symmetric part of K, or K itself when not
    ``symmetric``)."""
    return alpha * M + beta * (0.5 * (K + K.T) if symmetric else K)
