r"""Breathing laws of a transverse crack in the rotating frame (Madden 2016, section 5.1, eq. 5.10-5.21).

Angle convention (used everywhere in :mod:`rotorcheck.faults`): ``theta`` is the crack *opening
angle*, the angle of the crack (the direction from the shaft axis to the crack mouth, i.e. the
rotating ``xi`` axis of Fig. 54) measured from the **upward** vertical in the sense of rotation.
With weight dominance the crack is **closed at theta = 0** (crack on top, faces in compression) and
**fully open at theta = pi** (crack at the bottom, faces in tension).

Sign of eq. 5.21. Eq. 5.13 (Mayes-Davies) gives the rotating stiffness
``k_R = (k0 + kc)/2 + (k0 - kc)/2 cos(theta)``, i.e. ``k0`` (healthy) at theta = 0 and ``kc``
(open) at theta = pi. The *reduction* ``k0 - k_R = (k0 - kc) (1 - cos theta)/2``, so the steering
of the reduction is

    f(theta) = (1 - cos theta) / 2      (0 closed at theta = 0, 1 fully open at theta = pi).

Eq. 5.21 prints ``(1 + cos theta)/2``; that form is the same law with the angle measured from the
*open* position (theta' = theta - pi). We keep the text's statement (and rigs.md): closed at
theta = 0, so ``f = (1 - cos theta)/2`` here.

Every law is returned as a dimensionless 2x2 *rotating-frame reduction* ``R(theta)`` on the
(xi, eta) bending planes: the fraction of the element's healthy bending stiffness removed, with
``R = f(theta) diag(dxi, deta)`` for Mayes-Davies and Gasch and ``R = I - k_R(theta)/k0`` for the
Jun et al. series (eq. 5.14-5.16), together with its Fourier series in theta,
``R(theta) = sum_m R_m exp(j m theta)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "gasch_fourier",
    "gasch_steering",
    "jun_fourier",
    "jun_reduction",
    "mayes_davies_fourier",
    "mayes_davies_steering",
]


def mayes_davies_steering(theta: np.ndarray | float) -> np.ndarray:
    """Mayes-Davies steering of the reduction, ``(1 - cos theta)/2`` (theta in rad, 0 = closed)."""
    return 0.5 * (1.0 - np.cos(np.asarray(theta, dtype=float)))


def mayes_davies_fourier() -> dict[int, complex]:
    """Exact Fourier coefficients ``c_m`` of ``(1 - cos theta)/2 = sum c_m e^{j m theta}``."""
    return {-1: -0.25 + 0j, 0: 0.5 + 0j, 1: -0.25 + 0j}


def gasch_steering(theta: np.ndarray | float, n_terms: int | None = None) -> np.ndarray:
    """Gasch hinge (eq. 5.11-5.12): 1 (open) for ``theta mod 2 pi`` in [pi/2, 3 pi/2), else 0.

    With ``n_terms`` the Fourier series truncated at ``|m| <= n_terms`` is returned instead.
    """
    th = np.asarray(theta, dtype=float)
    if n_terms is None:
        r = np.mod(th, 2.0 * np.pi)
        return ((r >= 0.5 * np.pi) & (r < 1.5 * np.pi)).astype(float)
    c = gasch_fourier(n_terms)
    out = np.zeros(th.shape, dtype=complex)
    for m, cm in c.items():
        out = out + cm * np.exp(1j * m * th)
    return out.real


def gasch_fourier(n_terms: int) -> dict[int, complex]:
    """Fourier coefficients of the Gasch square wave for ``|m| <= n_terms``.

    ``c_0 = 1/2``, ``c_m = (e^{-j m pi/2} - e^{-j 3 m pi/2}) / (2 pi j m)`` (zero for even m),
    i.e. ``f = 1/2 - (2/pi)(cos theta - cos 3 theta / 3 + cos 5 theta / 5 - ...)``.
    """
    if n_terms < 0:
        raise ValueError("n_terms must be >= 0")
    out: dict[int, complex] = {0: 0.5 + 0j}
    for m in range(1, n_terms + 1):
        for mm in (m, -m):
            c = (np.exp(-1j * mm * np.pi / 2) - np.exp(-1j * mm * 1.5 * np.pi)) / (2j * np.pi * mm)
            out[mm] = complex(c) if abs(c) > 1e-15 else 0j
    return out


def jun_reduction(
    theta: np.ndarray | float,
    b_xi: Sequence[float],
    b_eta: Sequence[float],
    a: Sequence[float] = (),
) -> np.ndarray:
    """Jun et al. rotating reduction ``I - k_R(theta)/k0``, shape (..., 2, 2).

    ``k_xixi/k0 = sum_n b_xi[n] cos(n theta)`` (n from 0), likewise ``k_etaeta``; the cross term
    ``k_xieta/k0 = k_etaxi/k0 = sum_n a[n] sin((n + 1) theta)`` (``a[0]`` multiplies sin theta).
    """
    th = np.asarray(theta, dtype=float)
    if not b_xi or not b_eta:
        raise ValueError("the jun model needs jun_b_xi and jun_b_eta (cosine series / k0)")
    kxx = sum(b * np.cos(n * th) for n, b in enumerate(b_xi))
    kyy = sum(b * np.cos(n * th) for n, b in enumerate(b_eta))
    kxy = sum(c * np.sin((n + 1) * th) for n, c in enumerate(a)) if a else np.zeros_like(th)
    out = np.empty((*th.shape, 2, 2))
    out[..., 0, 0] = 1.0 - kxx
    out[..., 1, 1] = 1.0 - kyy
    out[..., 0, 1] = -kxy
    out[..., 1, 0] = -kxy
    return out


def jun_fourier(b_xi: Sequence[float], b_eta: Sequence[float], a: Sequence[float] = ()) -> dict[int, np.ndarray]:
    """Exact Fourier coefficients (2x2 complex) of :func:`jun_reduction` in theta."""
    if not b_xi or not b_eta:
        raise ValueError("the jun model needs jun_b_xi and jun_b_eta (cosine series / k0)")
    n_max = max(len(b_xi), len(b_eta), len(a) + 1) - 1
    out = {m: np.zeros((2, 2), dtype=complex) for m in range(-n_max, n_max + 1)}
    out[0] += np.eye(2)
    for idx, series in ((0, b_xi), (1, b_eta)):
        for n, b in enumerate(series):
            if n == 0:
                out[0][idx, idx] -= b
            else:
                out[n][idx, idx] -= b / 2.0
                out[-n][idx, idx] -= b / 2.0
    for n0, c in enumerate(a):
        n = n0 + 1  # -c sin(n th) = -c (e^{jn th} - e^{-jn th}) / (2j)
        for i, j in ((0, 1), (1, 0)):
            out[n][i, j] -= c / 2j
            out[-n][i, j] += c / 2j
    return out
