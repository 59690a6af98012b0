"""Brute-force references for real (and real + complex) uncertainty blocks, SISO.

- :func:`gamma_complex_siso`: method.md's closed form for one complex scalar block, over a stack of Me;
- :func:`min_feasible_1d`: the smallest |delta| over real delta for which the data are explained;
- :func:`real_plus_complex`: one real and one complex scalar block sharing gamma: a grid over the real
  delta (closing the real loop gives a reduced Me with one complex block, solved in closed form), the
  best grid point refined by a bounded scalar search.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize_scalar


def gamma_complex_siso(me: np.ndarray, W: complex, Zt: complex, V: float) -> np.ndarray:
    """Smallest |delta| of one complex scalar explaining ``Zt`` within ``V`` (g,) for Me (g, 2, 2)."""
    a = me[:, 0, 0]
    b = me[:, 0, 1] * me[:, 1, 0] * W
    e = Zt - me[:, 1, 1] * W
    p = a * e + b
    alpha = np.abs(p) ** 2 - V**2 * np.abs(a) ** 2
    beta = np.conj(e) * p - V**2 * a
    c0 = np.abs(e) ** 2 - V**2
    disc = np.abs(beta) ** 2 - alpha * c0
    with np.errstate(all="ignore"):
        g = c0 / (np.abs(beta) + np.sqrt(np.maximum(disc, 0.0)))
    g = np.where(disc < 0, np.inf, g)
    g = np.where(np.abs(b) == 0, np.inf, g)
    return np.where(c0 <= 0, 0.0, g)


def min_feasible_1d(feasible: Callable[[np.ndarray], np.ndarray], hi: float = 1e3, n: int = 4001) -> float:
    """Smallest |delta| (delta real) with ``feasible(delta)`` True: a log grid on both signs from 1e-6
    to ``hi``, the first feasible grid point per sign refined by bisection; inf if none."""
    if feasible(np.zeros(1))[0]:
        return 0.0
    mag = np.geomspace(1e-6, hi, n)
    best = np.inf
    for sgn in (1.0, -1.0):
        ok = feasible(sgn * mag)
        if not ok.any():
            continue
        j = int(np.argmax(ok))
        lo_, hi_ = (0.0 if j == 0 else mag[j - 1]), mag[j]
        for _ in range(60):
            mid = 0.5 * (lo_ + hi_)
            if feasible(np.array([sgn * mid]))[0]:
                hi_ = mid
            else:
                lo_ = mid
        best = min(best, hi_)
    return best


def real_plus_complex(me: np.ndarray, W: np.ndarray, Zt: np.ndarray, V: np.ndarray, grid_n: int = 1601
                      ) -> np.ndarray:
    """Required gamma (n,) for Me (n, 3, 3) with a real block (channel 0) and a complex block (channel 1)."""
    grid = np.linspace(-4.0, 4.0, grid_n)
    ref = np.empty(me.shape[0])
    for i in range(me.shape[0]):
        M = me[i]

        def g(x: np.ndarray, M: np.ndarray = M, i: int = i) -> np.ndarray:
            x = np.atleast_1d(x)
            with np.errstate(all="ignore"):
                red = M[None, 1:, 1:] + (x / (1 - M[0, 0] * x))[:, None, None] * np.outer(M[1:, 0], M[0, 1:])[None]
            return np.maximum(np.abs(x), gamma_complex_siso(red, W[i], Zt[i], V[i]))

        vals = g(grid)
        j = int(np.argmin(vals))
        res = minimize_scalar(lambda x, g=g: float(g(np.array([x]))[0]),
                              bounds=(grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]),
                              method="bounded", options={"xatol": 1e-13})
        ref[i] = min(float(vals[j]), float(res.fun))
    return ref


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    """Complex standard normal draws (real and imaginary parts each N(0, 1))."""
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def real_plus_complex_cases(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``n`` random points for one real and one complex scalar block sharing gamma: ``(Me (n, 3, 3), W, Zt,
    V)``, the data made by a known Delta (real 0.4 N(0,1), complex 0.4 CN(0,1)) plus a 30 % perturbation,
    V a random 20-90 % of that perturbation's size (so most points need a nonzero gamma)."""
    from rotorcheck.robust import lft

    me = np.zeros((n, 3, 3), complex)
    me[:, :2, :2] = 0.3 * cplx(rng, n, 2, 2)
    me[:, :2, 2], me[:, 2, :2], me[:, 2, 2] = cplx(rng, n, 2), cplx(rng, n, 2), cplx(rng, n)
    W = cplx(rng, n)
    d = np.stack([0.4 * rng.normal(size=n), 0.4 * cplx(rng, n)], axis=1)
    Z0 = np.array([lft.lft_upper(me[i], np.diag(d[i]))[0, 0, 0] for i in range(n)]) * W
    Zt = Z0 + 0.3 * np.abs(Z0) * cplx(rng, n)
    V = rng.uniform(0.2, 0.9, n) * np.abs(Zt - Z0)
    return me, W, Zt, V
