"""Harmonic balance of the cracked rotor computed independently of rotorcheck.faults (test oracles).

``hill_matrix``: the full (2H+1) n Hill matrix ``blkdiag(Z_k) - [K_{k-j}]`` of a crack;
``harmonic_balance_plant``: a simulator plant solving the dense Hill system per frequency for a
given Fourier series of ``dK(t)`` (no reduction to the crack DOF, no receptance engine).
"""

from __future__ import annotations

import numpy as np

from rotorcheck.faults.crack import CrackStiffness
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.sim.simulator import Plant

TWO_PI = 2.0 * np.pi


def hill_matrix(
    system: MechanicalSystem, crack: CrackStiffness, speed_rpm: float, freq_hz: float, n_harmonics: int
) -> np.ndarray:
    """The full (2H+1) n Hill matrix ``blkdiag(Z_k) - [K_{k-j}]``, ``|p| <= 2H`` Fourier orders of K_c
    (constant K_c at rest)."""
    M, C, G, K = system.matrices(speed_rpm)
    n = system.n_dof
    omega = speed_rpm * RPM_TO_RAD_S
    D = C + omega * G
    H = int(n_harmonics)
    nk = 2 * H + 1
    if speed_rpm == 0.0:
        porders, kp = np.array([0]), crack.at_rotation(0.0).astype(complex)
    else:
        porders, kp = crack.harmonics()
        keep = np.abs(porders) <= 2 * H
        porders, kp = porders[keep], kp[keep]
    A = np.zeros((nk * n, nk * n), dtype=complex)
    for i, k in enumerate(range(-H, H + 1)):
        nu = TWO_PI * freq_hz + k * omega
        A[i * n : (i + 1) * n, i * n : (i + 1) * n] = K - nu**2 * M + 1j * nu * D
    for p, kpp in zip(porders, kp):
        for i in range(nk):
            j = i - int(p)
            if 0 <= j < nk:
                blk = A[i * n : (i + 1) * n, j * n : (j + 1) * n]
                blk[np.ix_(crack.dofs, crack.dofs)] -= kpp
    return A


def _z(m: np.ndarray, c: np.ndarray, k: np.ndarray, f_hz: float) -> np.ndarray:
    w = TWO_PI * f_hz
    return k - w**2 * m + 1j * w * c


def harmonic_balance_plant(
    m: np.ndarray,
    c: np.ndarray,
    k0: np.ndarray,
    dk_fourier: dict[int, np.ndarray],
    speed_hz: float,
    b_in: np.ndarray,
    c_out: np.ndarray,
    n_harmonics: int = 8,
) -> Plant:
    """Linear time-periodic plant by harmonic balance.

    ``dK(t) = sum_l dk_fourier[l] exp(j l Omega t)`` (``Omega = 2 pi speed_hz``; include both
    ``l`` and ``-l`` with ``dk_fourier[-l] = conj(dk_fourier[l])`` for a real ``dK``). For the
    drive ``Re{exp(j w t)}`` the response is ``Re sum_k Q_k exp(j (w + k Omega) t)``,
    ``|k| <= n_harmonics``, with ``Z(w + k Omega) Q_k + sum_l dK_l Q_{k-l} = b delta_k0``.
    """
    n = k0.shape[0]
    c_out = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    b = np.asarray(b_in, dtype=np.complex128).reshape(n)
    ks = np.arange(-n_harmonics, n_harmonics + 1)
    h = len(ks)

    def tones(f_hz: float) -> tuple[np.ndarray, np.ndarray]:
        big = np.zeros((h * n, h * n), dtype=np.complex128)
        for a, ka in enumerate(ks):
            big[a * n : (a + 1) * n, a * n : (a + 1) * n] += _z(m, c, k0, f_hz + ka * speed_hz)
            for bcol, kb in enumerate(ks):
                lk = int(ka - kb)
                if lk in dk_fourier:
                    big[a * n : (a + 1) * n, bcol * n : (bcol + 1) * n] += dk_fourier[lk]
        rhs = np.zeros(h * n, dtype=np.complex128)
        i0 = int(np.nonzero(ks == 0)[0][0])
        rhs[i0 * n : (i0 + 1) * n] = b
        q = np.linalg.solve(big, rhs).reshape(h, n)
        return f_hz + ks * speed_hz, q @ c_out.T

    return Plant(tones=tones, n_out=c_out.shape[0], name="harmonic_balance")


