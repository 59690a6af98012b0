"""Oracle for the closed-form 'enclose system' gamma: brentq on the forward Moebius image
(moved out of the package: it exists only to check :func:`gamma_enclose_system_siso`)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from rotorcheck.robust.closed_form import siso_coefficients


def _forward_disk(a: complex, b: complex, g: float) -> tuple[str, complex, float]:
    """Image of ``|Delta| <= g`` under ``Delta -> b Delta / (1 - a Delta)``: (kind, centre, radius)."""
    q = 1.0 - g**2 * abs(a) ** 2
    if q == 0.0:
        return "halfplane", complex("nan"), np.inf
    centre = b * g**2 * np.conj(a) / q
    radius = abs(b) * g / abs(q)
    return ("disk" if q > 0 else "outside"), centre, radius


def gamma_enclose_system_siso_bisect(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                                     noise_bound: float | np.ndarray, g_max: float = 1e12
                                     ) -> np.ndarray:
    """Independent oracle for :func:`gamma_enclose_system_siso`: brentq on the forward Moebius image
    (the images grow monotonically with g, so data-disk inclusion is a monotone condition)."""
    k = siso_coefficients(me, W, Zt, noise_bound)
    out = np.empty(k["a"].shape)
    for i in range(out.size):
        a, b, e, V = complex(k["a"][i]), complex(k["b"][i]), complex(k["e"][i]), float(k["V"][i])

        def margin(g: float, a: complex = a, b: complex = b, e: complex = e, V: float = V) -> float:
            kind, c, r = _forward_disk(a, b, g)
            if kind == "disk":
                return r - (abs(e - c) + V)  # >= 0: data disk inside the image disk
            if kind == "outside":
                return (abs(e - c) - V) - r  # >= 0: data disk in the exterior region
            return 0.0

        scale = max(abs(e) + V, 1e-300) / max(abs(b), 1e-300)
        if margin(g_max * scale) < 0:
            out[i] = np.inf
            continue
        lo, hi = 0.0, scale
        while margin(hi) < 0:
            lo, hi = hi, 2 * hi
        if margin(lo) >= 0:
            out[i] = lo
            continue
        # the margin jumps at the half-plane g = 1/|a|; keep brentq away from the singularity
        if a != 0 and lo < 1 / abs(a) < hi:
            ga = 1 / abs(a)
            if margin(ga * (1 - 1e-12)) >= 0:
                hi = ga * (1 - 1e-12)
            else:
                lo = ga * (1 + 1e-12)
        out[i] = brentq(margin, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500)
    return out
