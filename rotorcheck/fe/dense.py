"""Small dense generalized eigensolutions on numpy alone.

:func:`eigh_pencil` computes the undamped modes of the half-size complex model of an isotropic
rotor (:func:`rotorcheck.fe.frf._isotropic_half`) with the algorithm of LAPACK's
``xSYGV``/``xHEGV`` (Cholesky factor of the mass matrix, reduction to a standard problem,
``xSYEVD``) after a diagonal scaling of the pencil: per-mode residuals of the crack rig's meshes
like those of ``scipy.linalg.eigh(A, B)`` (tests/fe/test_fe_frf_fast.py), at the same cost for
20-40 DOF, and usable where scipy.linalg is not loaded (its import costs 0.1-0.2 s of start-up:
scipy 1.17 clones numpy's namespace through ``array_api_compat``, which imports numpy.testing,
numpy.f2py, ...).
"""

from __future__ import annotations

import numpy as np

__all__ = ["eigh_pencil"]


def eigh_pencil(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and eigenvectors of the Hermitian pencil ``A x = lambda B x``.

    ``A`` Hermitian, ``B`` Hermitian positive definite (real or complex); ``X^H B X = I``. The pencil
    is first scaled symmetrically to a unit diagonal of ``B`` (a rotor's mass matrix mixes kg and
    kg m^2: the scaling keeps the Cholesky reduction from mixing those magnitudes). Raises
    :class:`numpy.linalg.LinAlgError` when ``B`` is not positive definite.
    """
    d = np.diag(B).real
    if np.any(d <= 0.0):
        raise np.linalg.LinAlgError("B is not positive definite")
    s = 1.0 / np.sqrt(d)
    L = np.linalg.cholesky(s[:, None] * B * s[None, :])  # D B D = L L^H
    Li = np.linalg.inv(L)  # lower triangular (the inverse of a triangular factor, backward stable)
    S = Li @ (s[:, None] * A * s[None, :]) @ Li.conj().T
    S = 0.5 * (S + S.conj().T)
    lam, Y = np.linalg.eigh(S)
    return lam, s[:, None] * (Li.conj().T @ Y)
