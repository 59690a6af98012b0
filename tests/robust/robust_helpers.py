"""Independent references for the robust tests: high-precision closed form, three-mass matrices."""

from __future__ import annotations

from decimal import Decimal, getcontext

import numpy as np

# ECP 210a three-mass system, dissertation Table 1 (rigs.md section 2)
M1, M2, M3 = 2.8113, 2.6396, 2.6074
K1, K2, K3 = 842.3, 806.5, 386.0
C1, C2, C3 = 5.992, 1.9467, 10.7375
KD = 350.0


def three_mass_matrices(m1: float = M1, k3: float = K3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, K, C) by hand: k1,c1 between m1-m2; k2,c2 between m2-m3; k3,c3 between m3 and ground;
    m1 not grounded."""
    M = np.diag([m1, M2, M3])
    K = np.array([[K1, -K1, 0.0], [-K1, K1 + K2, -K2], [0.0, -K2, K2 + k3]])
    C = np.array([[C1, -C1, 0.0], [-C1, C1 + C2, -C2], [0.0, -C2, C2 + C3]])
    return M, K, C


def three_mass_Z(freq_hz: np.ndarray, m1: float = M1, k3: float = K3) -> np.ndarray:
    """Dynamic stiffness K - w^2 M + j w C, (f, 3, 3)."""
    M, K, C = three_mass_matrices(m1, k3)
    w = 2 * np.pi * np.asarray(freq_hz)[:, None, None]
    return K[None] - w**2 * M[None] + 1j * w * C[None]


class _C:
    """Minimal exact-decimal complex number."""

    def __init__(self, re: Decimal, im: Decimal):
        self.re, self.im = re, im

    @staticmethod
    def of(z: complex) -> _C:
        return _C(Decimal(float(np.real(z))), Decimal(float(np.imag(z))))

    def __add__(self, o: _C) -> _C:
        return _C(self.re + o.re, self.im + o.im)

    def __sub__(self, o: _C) -> _C:
        return _C(self.re - o.re, self.im - o.im)

    def __mul__(self, o: _C) -> _C:
        return _C(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)

    def scale(self, x: Decimal) -> _C:
        return _C(self.re * x, self.im * x)

    def conj(self) -> _C:
        return _C(self.re, -self.im)

    def abs2(self) -> Decimal:
        return self.re * self.re + self.im * self.im


def gamma_methodmd_exact(me: np.ndarray, W: complex, Zt: complex, V: float) -> float:
    """method.md's SISO closed form evaluated verbatim in 60-digit decimal arithmetic on the exact
    float inputs (``c0 / (|beta| + sqrt(|beta|^2 - alpha c0))``)."""
    getcontext().prec = 60
    a = _C.of(me[0, 0])
    b = _C.of(me[0, 1]) * _C.of(me[1, 0]) * _C.of(W)
    e = _C.of(Zt) - _C.of(me[1, 1]) * _C.of(W)
    Vd = Decimal(float(V))
    p = a * e + b
    alpha = p.abs2() - Vd * Vd * a.abs2()
    beta = e.conj() * p - a.scale(Vd * Vd)
    c0 = e.abs2() - Vd * Vd
    if c0 <= 0:
        return 0.0
    disc = beta.abs2() - alpha * c0
    if disc < 0:
        # at V = 0 the discriminant is an exact cancellation; below the 60-digit rounding it is 0
        if -disc <= Decimal(10) ** -45 * (beta.abs2() + abs(alpha * c0)):
            disc = Decimal(0)
        else:
            return float("inf")
    den = beta.abs2().sqrt() + disc.sqrt()
    if den == 0:
        return float("inf")
    return float(c0 / den)


#: the 4-mass spring chain of the severity tests: spring i joins mass i-1 (ground for i = 0) and mass i
CHAIN_K = np.array([4.0e5, 3.0e5, 2.5e5, 2.0e5])  # N/m
CHAIN_MASS = np.array([1.0, 0.8, 0.7, 0.5])  # kg


def chain_spring(i: int) -> np.ndarray:
    """The 4 x 4 stiffness matrix of chain spring i (0-based) alone, per unit stiffness."""
    A = np.zeros((4, 4))
    A[i, i] += 1.0
    if i > 0:
        A[i - 1, i - 1] += 1.0
        A[i, i - 1] -= 1.0
        A[i - 1, i] -= 1.0
    return A
