"""SISO closed forms: test oracles for the LMI and the 'system' enclosure mode.

One complex scalar uncertainty ``|Delta| <= gamma`` and one complex scalar noise ``|v| <= V`` (m).
For a 2x2 ``Me`` (scalars ``Me11 .. Me22``, f-vectorized) and data ``W`` (N), ``Zt`` (m) define::

    a = Me11,  b = Me12 Me21 W,  e = Zt - Me22 W,  p = a e + b
    alpha = |p|^2 - V^2 |a|^2,  beta = conj(e) p - V^2 a,  c0 = |e|^2 - V^2

The model output is ``Me22 W + b Delta / (1 - a Delta)``, a Moebius map of Delta, with inverse
``Delta(e') = e' / (b + a e')`` for an output deviation ``e'``. The pre-image of the noise disk
``|e' - e| <= V`` is (when ``alpha > 0``) the disk with centre ``conj(beta)/alpha`` and radius
``|b| V / alpha`` (derived here; it reproduces method.md's forms). Hence

* required gamma (enclose='data', FDMVOP): ``c0 / (|beta| + |b| V)`` for ``c0 > 0`` (else 0),
  identical to method.md's ``c0 / (|beta| + sqrt(|beta|^2 - alpha c0))`` because
  ``|beta|^2 - alpha c0 = |b|^2 V^2`` identically (so the root is never imaginary; the only
  unexplainable case is ``b = 0``), and to ``(|beta| - |b| V) / alpha`` when ``alpha != 0``;
* enclosing gamma (enclose='system'): the smallest g with the whole data disk inside the image of
  ``|Delta| <= g``: ``(|beta| + |b| V) / alpha``, infinite if ``alpha <= 0`` (the image of
  ``Delta = oo`` lies in the data disk) or ``b = 0`` (the image is the single point ``Me22 W``
  whatever g: only ``V = 0`` with ``Zt = Me22 W`` is enclosed, by g = 0). Additive:
  ``(|Zt - G W| + V) / |W|``. (At ``b = 0`` the formula would give ``1/|a|``, the limit
  ``b -> 0`` of the outside-of-a-disk images; at ``b = 0`` that image has collapsed to a point.)
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "damage_disk_additive",
    "gamma_enclose_additive",
    "gamma_enclose_system_siso",
    "gamma_required_additive",
    "gamma_required_siso",
    "gamma_required_siso_methodmd",
    "siso_coefficients",
]


def _siso_parts(me: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    M = np.asarray(me, dtype=complex)
    if M.ndim == 2:
        M = M[None]
    if M.shape[1:] != (2, 2):
        raise ValueError(f"SISO closed forms need Me of shape (f, 2, 2), got {M.shape}")
    return M[:, 0, 0], M[:, 0, 1], M[:, 1, 0], M[:, 1, 1]


def siso_coefficients(me: np.ndarray, W: np.ndarray, Zt: np.ndarray, noise_bound: float | np.ndarray
                      ) -> dict[str, np.ndarray]:
    """The scalars a, b, e, p, alpha, beta, c0 above, each shape (f,)."""
    m11, m12, m21, m22 = _siso_parts(me)
    W = np.asarray(W, dtype=complex).reshape(-1)
    Zt = np.asarray(Zt, dtype=complex).reshape(-1)
    V = np.broadcast_to(np.asarray(noise_bound, dtype=float), Zt.shape)
    a = m11
    b = m12 * m21 * W
    e = Zt - m22 * W
    p = a * e + b
    alpha = np.abs(p) ** 2 - V**2 * np.abs(a) ** 2
    beta = np.conj(e) * p - V**2 * a
    c0 = np.abs(e) ** 2 - V**2
    return {"a": a, "b": b, "e": e, "p": p, "alpha": alpha, "beta": beta, "c0": c0, "V": V}


def gamma_required_siso(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                        noise_bound: float | np.ndarray) -> np.ndarray:
    """Required gamma (FDMVOP) for a 2x2 Me, shape (f,); ``inf`` when no gamma explains the data.

    method.md's ``c0 / (|beta| + sqrt(|beta|^2 - alpha c0))`` with the identity
    ``|beta|^2 - alpha c0 = |b|^2 V^2`` (so the root is never imaginary): evaluated as
    ``c0 / (|beta| + |b| V)``, which keeps full precision at V = 0 where the square root of a
    cancellation loses half the digits. ``b = 0``: the uncertainty cannot move the output (inf).
    """
    k = siso_coefficients(me, W, Zt, noise_bound)
    e, V, b, beta = k["e"], k["V"], k["b"], k["beta"]
    ae = np.abs(e)
    c0 = (ae - V) * (ae + V)
    den = np.abs(beta) + np.abs(b) * V
    out = np.full(c0.shape, np.inf)
    zero = c0 <= 0
    out[zero] = 0.0
    ok = ~zero & (np.abs(b) > 0) & (den > 0)
    out[ok] = c0[ok] / den[ok]
    return out


def gamma_required_siso_methodmd(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                                 noise_bound: float | np.ndarray) -> np.ndarray:
    """method.md's formula verbatim (with its square root); kept for comparison only."""
    k = siso_coefficients(me, W, Zt, noise_bound)
    alpha, beta, c0 = k["alpha"], k["beta"], k["c0"]
    disc = np.abs(beta) ** 2 - alpha * c0
    out = np.full(c0.shape, np.inf)
    zero = c0 <= 0
    out[zero] = 0.0
    ok = ~zero & (disc >= 0)
    den = np.abs(beta[ok]) + np.sqrt(disc[ok])
    with np.errstate(divide="ignore", invalid="ignore"):
        out[ok] = np.where(den > 0, c0[ok] / den, np.inf)
    return out


def gamma_required_additive(G: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                            noise_bound: float | np.ndarray) -> np.ndarray:
    """Additive io: ``max(0, (|Zt - G W| - V) / |W|)`` (m/N), shape (f,)."""
    G, W, Zt = (np.asarray(x, dtype=complex).reshape(-1) for x in (G, W, Zt))
    with np.errstate(divide="ignore"):
        return np.maximum(0.0, (np.abs(Zt - G * W) - noise_bound) / np.abs(W))


def gamma_enclose_additive(G: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                           noise_bound: float | np.ndarray) -> np.ndarray:
    """Additive io, enclose every system consistent with data and V: ``(|Zt - G W| + V)/|W|``."""
    G, W, Zt = (np.asarray(x, dtype=complex).reshape(-1) for x in (G, W, Zt))
    with np.errstate(divide="ignore"):
        return (np.abs(Zt - G * W) + noise_bound) / np.abs(W)


def gamma_enclose_system_siso(me: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                              noise_bound: float | np.ndarray) -> np.ndarray:
    """Smallest g such that ``{Z : |Z - Zt| <= V}`` lies inside ``{W F_u(Me, Delta) : |Delta| <= g}``.

    Exact via the Moebius pre-image of the data disk: ``(|beta| + |b| V) / alpha`` when
    ``alpha > 0`` and ``b != 0``, else ``inf`` (not enclosable by any finite g; ``b = Me12 Me21 W
    = 0``: the uncertainty does not reach the output). Shape (f,).
    """
    k = siso_coefficients(me, W, Zt, noise_bound)
    alpha, beta, b, V = k["alpha"], k["beta"], k["b"], k["V"]
    out = np.full(alpha.shape, np.inf)
    ok = (alpha > 0) & (np.abs(b) > 0)
    out[ok] = (np.abs(beta[ok]) + np.abs(b[ok]) * V[ok]) / alpha[ok]
    # V = 0 and the data equal to the nominal output: nothing to enclose but a point at Delta = 0.
    out[(V == 0) & (np.abs(k["e"]) == 0)] = 0.0
    return out


def gamma_enclose_system_additive(G: np.ndarray, W: np.ndarray, Zt: np.ndarray,
                                  noise_bound: float | np.ndarray) -> np.ndarray:
    """Smallest g such that every output in the data polydisc ``{Z : |Z_o - Zt_o| <= V}`` is
    ``(G + Delta) W`` for some full block ``sigma_max(Delta) <= g`` (additive uncertainty, several outputs
    and inputs): ``{Delta W}`` is the ball of radius ``g |W|``, so ``g = sqrt(sum_o (|Zt_o - (G W)_o| +
    V)^2) / |W|``. ``G`` (f, n_out, n_in), ``W`` (f, n_in), ``Zt`` (f, n_out), V scalar or (f,); (f,)."""
    G = np.asarray(G, dtype=complex)
    W = np.asarray(W, dtype=complex).reshape(G.shape[0], G.shape[2])
    Zt = np.asarray(Zt, dtype=complex).reshape(G.shape[0], G.shape[1])
    V = np.broadcast_to(np.asarray(noise_bound, dtype=float), (G.shape[0],))
    r = np.abs(Zt - np.einsum("fij,fj->fi", G, W))
    nw = np.linalg.norm(W, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(nw > 0, np.sqrt(np.sum((r + V[:, None]) ** 2, axis=1)) / nw, np.inf)


def damage_disk_additive(T: np.ndarray, E11: np.ndarray, E12: np.ndarray, E21: np.ndarray,
                         E22: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """method.md's additive closed form for the identified-damage disk (test oracle).

    ``q = T - E22, c = E12 E21, delta = E11 q + c``; for ``|delta| > r |E11|``: centre
    ``(q conj(delta) - r^2 conj(E11)) / (|delta|^2 - r^2 |E11|^2)``, radius
    ``r |c| / (|delta|^2 - r^2 |E11|^2)``. Returns (centre, radius, valid) with valid the mask
    where the image is a bounded disk.
    """
    T, E11, E12, E21, E22 = (np.asarray(x, dtype=complex).reshape(-1) for x in (T, E11, E12, E21, E22))
    r = np.broadcast_to(np.asarray(r, dtype=float), T.shape)
    q = T - E22
    c = E12 * E21
    delta = E11 * q + c
    den = np.abs(delta) ** 2 - r**2 * np.abs(E11) ** 2
    valid = den > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        centre = (q * np.conj(delta) - r**2 * np.conj(E11)) / den
        radius = r * np.abs(c) / den
    return centre, radius, valid
