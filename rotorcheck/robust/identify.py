"""Step 5: identified damage dynamics and its exact uncertainty set (dissertation eq. 3.11-3.12).

``D_u = [E12 (T - E22)^-1 E21 + E11]^-1`` per frequency, ``T`` the damaged FRF (m/N), ``E`` the
engineering system with ports (damage, io) in m/N; ``D_u`` is the extra force at the damage port per
unit port displacement (N/m): a stiffness loss dk gives ``D = +dk``.

With the engineering system uncertain through ONE complex scalar ``Delta`` (``|Delta| <= r``),
``E_hat(Delta) = F_u(Me_E, Delta)`` is a Moebius map of Delta entrywise and so is ``D_u(Delta)``.
The image of the disk is therefore a disk, the outside of a disk or a half-plane. It is computed
exactly: the Moebius coefficients are fitted to the images of Delta = 0 and three boundary points
(a 4 x 4 homogeneous system, rank 3; the fit residual checks that the map is Moebius), then the
image of the disk follows in closed form (pole inside the disk -> outside of a circle).

Additive io uncertainty with noise: ``E22 -> E22 + r Delta`` with ``r = gamma + V/|W|``: the data
noise ``v/W`` and the model uncertainty add in the same channel, so one complex scalar covers both
exactly.

Multiplicative io uncertainty is applied as validation and :mod:`rotorcheck.nominal` apply it, to
the whole output including the damage path: ``T = (1 + Delta) H(D) + v/W`` with
``H(D) = E22 + E21 D (1 - E11 D)^-1 E12``, ``|Delta| <= gamma``, ``|v| <= V``. Without noise
(or with gamma = 0) the set is again one Moebius image (exact). With both, the set of ``H`` is
``{(T - n)/(1 + Delta)}``, a product of two disks, which is not a disk: it is enclosed by the
smallest disk about the product of the centres (triangle inequality, touching the set), which
``H -> D`` maps exactly. The result is an outer set, exact to first order: its excess is of the
order ``gamma V/|T W|`` relative.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.lft import as_freq_matrix, io_me, lft_upper

__all__ = [
    "DamageSet",
    "damage_dynamics",
    "damage_set",
    "damage_set_io",
    "damage_set_multiplicative",
    "io_radius",
    "moebius_disk_image",
]


def damage_dynamics(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, E22: np.ndarray,
                    T: np.ndarray) -> np.ndarray:
    """Eq. 3.11 per frequency: ``D_0 = [E12 (T - E22)^-1 E21 + E11]^-1`` (N/m).

    SISO: all inputs ``(f,)`` -> ``(f,)``. Matrix: ``E11`` ``(f, nd, nd)``, ``E12`` ``(f, nd, n_in)``,
    ``E21`` ``(f, n_out, nd)``, ``E22`` and ``T`` ``(f, n_out, n_in)`` -> ``(f, nd, nd)``; a
    non-square ``T - E22`` uses the pseudo-inverse (least squares).
    """
    siso = all(np.ndim(x) <= 1 for x in (E11, E12, E21, E22, T))
    if siso:
        E11, E12, E21, E22, T = (np.asarray(x, dtype=complex) for x in (E11, E12, E21, E22, T))
        with np.errstate(divide="ignore", invalid="ignore"):
            return 1.0 / (E12 * E21 / (T - E22) + E11)
    f = max(np.shape(x)[0] if np.ndim(x) == 3 else 1 for x in (E11, E12, E21, E22, T))
    E11, E12, E21, E22, T = (as_freq_matrix(x, f) for x in (E11, E12, E21, E22, T))
    Q = T - E22
    if Q.shape[1] == Q.shape[2]:
        X = np.linalg.solve(Q, E21)
    else:
        X = np.linalg.pinv(Q) @ E21
    return np.linalg.inv(E12 @ X + E11)


@dataclass
class DamageSet:
    """Exact set of the identified damage dynamics over ``|Delta| <= r``, per frequency (f,)
    (an outer set for multiplicative uncertainty with noise: :func:`damage_set_multiplicative`).

    ``kind``: 'point' (r = 0), 'disk' (``|D - centre| <= radius``), 'outside'
    (``|D - centre| >= radius``, unbounded) or 'halfplane' (``Re(conj(normal) D) >= offset``,
    unbounded); 'plane' (r infinite: any D) or 'undecided' (r NaN: no healthy bound there, all
    numbers NaN); ``nominal`` the image of Delta = 0 (N/m). ``min_abs``/``max_abs`` exact (``inf``
    when unbounded); ``phase_min``/``phase_max`` in rad, ``phase_max - phase_min = 2 pi`` when the
    set surrounds the origin (holds it, or is unbounded in every direction).
    """

    nominal: np.ndarray
    kind: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    normal: np.ndarray
    offset: np.ndarray
    min_abs: np.ndarray
    max_abs: np.ndarray
    phase_min: np.ndarray
    phase_max: np.ndarray

    def contains(self, z: np.ndarray, rtol: float = 1e-9) -> np.ndarray:
        """Whether ``z`` (f,) lies in the set at each frequency (tolerance ``rtol`` relative to the
        set's scale)."""
        z = np.asarray(z, dtype=complex).reshape(-1)
        return np.array([bool(self.contains_at(i, z[i : i + 1], rtol)[0]) for i in range(z.size)])

    def contains_at(self, i: int, z: np.ndarray, rtol: float = 1e-9) -> np.ndarray:
        """Whether each of the points ``z`` (any shape) lies in the set of frequency ``i``."""
        z = np.asarray(z, dtype=complex)
        k = self.kind[i]
        scale = abs(self.nominal[i]) if np.isfinite(self.nominal[i]) else 0.0
        if np.isfinite(self.centre[i]):
            scale = max(scale, abs(self.centre[i]))
        if np.isfinite(self.radius[i]):
            scale = max(scale, float(self.radius[i]))
        tol = rtol * max(scale, 1e-300)
        if k == "point":
            return np.abs(z - self.nominal[i]) <= tol
        if k == "disk":
            return np.abs(z - self.centre[i]) <= self.radius[i] + tol
        if k == "outside":
            return np.abs(z - self.centre[i]) >= self.radius[i] - tol
        if k == "halfplane":
            return (np.conj(self.normal[i]) * z).real >= self.offset[i] - tol
        if k == "plane":
            return np.ones(z.shape, dtype=bool)
        return np.zeros(z.shape, dtype=bool)



def undecided_set(n: int) -> DamageSet:
    """A damage set with nothing identified at ``n`` points (kind 'undecided', all numbers NaN): a rig with
    no damage port."""
    nan = np.full(n, np.nan)
    return DamageSet(nan + 0j, np.full(n, "undecided", dtype="<U9"), nan + 0j, nan.copy(), nan + 0j, nan.copy(),
                     nan.copy(), nan.copy(), nan.copy(), nan.copy())

def _fit_moebius(d: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, float]:
    """Coefficients (a, b, c, d) of ``z = (a D + b) / (c D + d)`` through the sample pairs, by the
    null vector of ``[D, 1, -z D, -z]``; returns them (unit norm) and the relative fit residual."""
    A = np.stack([d, np.ones_like(d), -z * d, -z], axis=1)
    colscale = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    _, sv, Vh = np.linalg.svd(A / colscale)
    coef = Vh[-1].conj() / colscale
    coef = coef / np.linalg.norm(coef)
    resid = sv[-1] / max(sv[0], 1e-300)
    return coef, float(resid)


def moebius_disk_image(fun: Callable[[np.ndarray], np.ndarray], radius: np.ndarray | float,
                       n_freq: int | None = None, check_tol: float = 1e-6) -> DamageSet:
    """Exact image of ``|Delta| <= radius`` under a per-frequency Moebius map ``fun``.

    ``fun`` maps a complex array (f,) of Delta values to the images (f,); ``radius`` scalar or (f,).
    Uses the images of Delta = 0 and of three boundary points. Raises ``ValueError`` where the map
    is evidently not Moebius (fit residual above ``check_tol``).
    """
    z0 = np.asarray(fun(np.zeros(n_freq or np.size(radius), complex)), dtype=complex)
    f = z0.size
    r = np.broadcast_to(np.asarray(radius, dtype=float), (f,)).copy()
    if np.any(r < 0):
        raise ValueError("radius must be >= 0")
    unknown = np.isnan(r)  # no healthy bound at that point (solver failure): nothing to say
    whole = np.isposinf(r)  # healthy data not enclosable: every D is possible
    r = np.where(unknown | whole, 1.0, r)  # placeholder so the sampling below stays finite
    angles = np.array([0.1, 0.1 + 2 * np.pi / 3, 0.1 + 4 * np.pi / 3])
    samples = [np.zeros(f, complex)] + [r * np.exp(1j * a) for a in angles]
    images = [z0] + [np.asarray(fun(s), dtype=complex) for s in samples[1:]]
    # Delta = 0 at a pole: use an interior point instead
    bad0 = ~np.isfinite(z0)
    if np.any(bad0):
        s_alt = 0.5 * r * np.exp(0.7j)
        z_alt = np.asarray(fun(np.where(bad0, s_alt, 0)), dtype=complex)
        samples[0] = np.where(bad0, s_alt, 0)
        images[0] = np.where(bad0, z_alt, z0)
    out = DamageSet(
        nominal=z0, kind=np.empty(f, dtype="<U9"), centre=np.full(f, np.nan + 0j),
        radius=np.full(f, np.nan), normal=np.full(f, np.nan + 0j), offset=np.full(f, np.nan),
        min_abs=np.full(f, np.nan), max_abs=np.full(f, np.nan), phase_min=np.full(f, np.nan),
        phase_max=np.full(f, np.nan))
    for i in range(f):
        if unknown[i]:
            out.kind[i] = "undecided"
            continue
        if whole[i]:
            out.kind[i], out.min_abs[i], out.max_abs[i] = "plane", 0.0, np.inf
            out.phase_min[i], out.phase_max[i] = -np.pi, np.pi
            continue
        if r[i] == 0:
            _set_point(out, i, z0[i])
            continue
        dd = np.array([s[i] for s in samples])
        zz = np.array([z[i] for z in images])
        if not np.all(np.isfinite(zz)):
            # a boundary sample hit the pole exactly: rotate the samples
            dd = r[i] * np.exp(1j * (angles + 0.37))
            zz = np.array([complex(fun(np.where(np.arange(f) == i, d, 0))[i]) for d in dd])
            dd = np.concatenate([[samples[0][i]], dd])
            zz = np.concatenate([[images[0][i]], zz])
        coef, resid = _fit_moebius(dd, zz)
        if resid > check_tol:
            raise ValueError(f"point {i}: the map is not Moebius in Delta (fit residual {resid:.1e})")
        _set_image(out, i, coef, float(r[i]))
    return out


def _set_point(out: DamageSet, i: int, z: complex) -> None:
    out.kind[i] = "point"
    out.centre[i] = z
    out.radius[i] = 0.0
    out.min_abs[i] = out.max_abs[i] = abs(z)
    out.phase_min[i] = out.phase_max[i] = np.angle(z)


def _set_disk(out: DamageSet, i: int, C: complex, R: float) -> None:
    out.kind[i] = "disk"
    out.centre[i], out.radius[i] = C, R
    aC = abs(C)
    out.min_abs[i] = max(0.0, aC - R)
    out.max_abs[i] = aC + R
    if aC <= R:
        out.phase_min[i], out.phase_max[i] = -np.pi, np.pi
    else:
        half = np.arcsin(R / aC)
        out.phase_min[i], out.phase_max[i] = np.angle(C) - half, np.angle(C) + half


def _set_outside(out: DamageSet, i: int, C: complex, R: float) -> None:
    out.kind[i] = "outside"
    out.centre[i], out.radius[i] = C, R
    aC = abs(C)
    out.min_abs[i] = 0.0 if aC >= R else R - aC
    out.max_abs[i] = np.inf
    out.phase_min[i], out.phase_max[i] = -np.pi, np.pi


def _set_halfplane(out: DamageSet, i: int, n: complex, off: float) -> None:
    out.kind[i] = "halfplane"
    out.normal[i], out.offset[i] = n, off
    out.radius[i] = np.inf
    out.min_abs[i] = max(0.0, off)
    out.max_abs[i] = np.inf
    if off < 0:
        out.phase_min[i], out.phase_max[i] = -np.pi, np.pi
    else:
        out.phase_min[i], out.phase_max[i] = np.angle(n) - np.pi / 2, np.angle(n) + np.pi / 2


def _set_image(out: DamageSet, i: int, coef: np.ndarray, r: float, rel: float = 1e-12) -> None:
    """Image of ``|Delta| <= r`` under ``(a D + b) / (c D + d)`` in closed form."""
    a, b, c, d = coef
    if abs(c) * r <= rel * abs(d):  # affine (pole at infinity)
        _set_disk(out, i, b / d, r * abs(a / d))
        return
    k = (b * c - a * d) / c  # z = a/c + k / y,  y = c D + d in the disk |y - d| <= rho
    rho = r * abs(c)
    den = abs(d) ** 2 - rho**2
    if abs(den) <= rel * max(abs(d) ** 2, rho**2):
        # pole on the circle: half-plane Re((d/k)(z - a/c)) >= 1/2
        g = d / k
        n = np.conj(g) / abs(g)
        _set_halfplane(out, i, n, float((0.5 + (g * a / c).real) / abs(g)))
        return
    C = a / c + k * np.conj(d) / den
    R = abs(k) * rho / abs(den)
    if den > 0:
        _set_disk(out, i, C, R)
    else:
        _set_outside(out, i, C, R)


def _siso_du(E: np.ndarray, T: np.ndarray) -> np.ndarray:
    """D_u from a stack of 2x2 engineering systems (f, 2, 2) with ports (damage, io)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return 1.0 / (E[:, 0, 1] * E[:, 1, 0] / (T - E[:, 1, 1]) + E[:, 0, 0])


def damage_set(me_e: np.ndarray, T: np.ndarray, radius: np.ndarray | float) -> DamageSet:
    """Exact set of ``D_u`` for an engineering system uncertain through one complex scalar.

    ``me_e``: ``(f, 1 + 2, 1 + 2)`` upper-LFT Me of the engineering system with ports
    (damage, io) (e.g. :func:`rotorcheck.robust.lft.engineering_me` for a parameter of rank 1, or
    :func:`rotorcheck.robust.lft.io_me`); ``T``: damaged FRF (f,) in m/N (noise-free, or the noise
    already folded into ``radius`` for io structures); ``radius``: ``|Delta| <= radius`` (f,).
    """
    M = as_freq_matrix(me_e)
    if M.shape[1:] != (3, 3):
        raise ValueError("damage_set needs a SISO io channel, a scalar damage port and one scalar "
                         f"uncertainty: Me_E of shape (f, 3, 3), got {M.shape}")
    T = np.asarray(T, dtype=complex).reshape(-1)

    def fun(delta: np.ndarray) -> np.ndarray:
        E = lft_upper(M, np.asarray(delta, complex)[:, None, None])
        return _siso_du(E, T)

    return moebius_disk_image(fun, radius, n_freq=M.shape[0])


def io_radius(gamma: np.ndarray, noise_bound: float | np.ndarray, W: np.ndarray,
              E22: np.ndarray | None = None, kind: str = "additive") -> np.ndarray:
    """Radius of the io-channel disk ``E22 + r Delta`` (m/N) combining model and noise uncertainty:
    additive ``gamma + V/|W|``; multiplicative ``gamma |E22| + V/|W|``."""
    W = np.abs(np.asarray(W, dtype=complex).reshape(-1))
    g = np.asarray(gamma, dtype=float).reshape(-1)
    if kind == "additive":
        return g + noise_bound / W
    if kind == "multiplicative":
        if E22 is None:
            raise ValueError("multiplicative radius needs E22")
        return g * np.abs(np.asarray(E22).reshape(-1)) + noise_bound / W
    raise ValueError(f"kind must be 'additive' or 'multiplicative', got {kind!r}")


def damage_set_io(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, E22: np.ndarray,
                  T: np.ndarray, gamma: np.ndarray, noise_bound: float | np.ndarray,
                  W: np.ndarray, kind: str = "additive") -> DamageSet:
    """``D_u`` set for an io uncertainty with noise (SISO, (f,) arrays); ``T`` = measured
    ``Zt / W`` of the damaged sweep.

    ``kind='additive'``: exact, ``E22_hat = E22 + r Delta``, ``r`` from :func:`io_radius`.
    ``kind='multiplicative'``: :func:`damage_set_multiplicative` (the uncertainty scales the damage
    path too, as in validation; outer set, exact without noise)."""
    if kind == "multiplicative":
        return damage_set_multiplicative(E11, E12, E21, E22, T, gamma, noise_bound, W)
    r = io_radius(gamma, noise_bound, W, E22, kind)
    me_e = io_me(E11, E12, E21, E22, "additive")
    return damage_set(me_e, T, r)


def damage_set_multiplicative(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, E22: np.ndarray,
                              T: np.ndarray, gamma: np.ndarray | float,
                              noise_bound: float | np.ndarray, W: np.ndarray) -> DamageSet:
    """Set of ``D`` with ``T = (1 + Delta) H(D) + v/W``, ``|Delta| <= gamma``, ``|v| <= V`` (SISO).

    ``H(D) = E22 + E21 D E12 / (1 - E11 D)`` is the damaged receptance without model error; the
    output multiplicative uncertainty of :mod:`rotorcheck.nominal` (``z = (1 + Delta)(E21 f_d +
    E22 w)``) scales it whole. With ``r_n = V/|W|`` the possible ``H`` are ``(T - n)/(1 + Delta)``,
    ``|n| <= r_n``, enclosed by one disk (products of disks ``c_a + rho_a mu``, ``c_b + rho_b nu``
    lie in the disk about ``c_a c_b`` of radius ``|c_a| rho_b + rho_a |c_b| + rho_a rho_b``):

    * ``gamma < 1``: ``1/(1 + Delta)`` fills the disk about ``1/(1 - g^2)`` of radius
      ``g/(1 - g^2)``, so ``H`` lies in the disk about ``T/(1 - g^2)`` of radius
      ``(g |T| + r_n (1 + g))/(1 - g^2)``;
    * else, if ``q = r_n/|T| < 1``: ``T/H = (1 + Delta)/(1 - n/T)`` lies in the disk about
      ``1/(1 - q^2)`` of radius ``(g + q (1 + g))/(1 - q^2)``;
    * else every ``H`` is possible (``Delta = -1`` and ``n = T``): kind 'plane'.

    Both disks are exact when ``V = 0`` or ``gamma = 0`` and touch the true set; ``H -> D`` is a
    Moebius map, so the image is computed exactly by :func:`moebius_disk_image`. ``gamma`` NaN
    (no healthy bound): 'undecided'. ``nominal`` is eq. 3.11 with the nominal model
    (``Delta = 0``, ``n = 0``), a member of the set.
    """
    E11, E12, E21, E22, T, W = (np.asarray(x, dtype=complex).reshape(-1)
                                for x in (E11, E12, E21, E22, T, W))
    f = max(x.size for x in (E11, E12, E21, E22, T, W))
    E11, E12, E21, E22, T, W = (np.broadcast_to(x, (f,)) for x in (E11, E12, E21, E22, T, W))
    g = np.broadcast_to(np.asarray(gamma, dtype=float).reshape(-1), (f,))
    V = np.broadcast_to(np.asarray(noise_bound, dtype=float).reshape(-1), (f,))
    if np.any(V < 0) or np.any(g < 0):
        raise ValueError("gamma and the noise bound V must be >= 0")
    with np.errstate(divide="ignore", invalid="ignore"):
        rn = V / np.abs(W)
        rn = np.where(V == 0, 0.0, rn)
        aT = np.abs(T)
        q = np.where(rn == 0, 0.0, rn / aT)
        use_h = g < 1
        use_r = ~use_h & (q < 1)
        ch = T / (1 - g**2)
        rh = (g * aT + rn * (1 + g)) / (1 - g**2)
        cr = 1 / (1 - q**2)
        rr = (g + q * (1 + g)) / (1 - q**2)
    radius = np.where(use_h, rh, np.where(use_r, rr, np.inf))
    unit = np.where(np.isnan(g), np.nan,
                    np.where(~np.isfinite(radius), np.inf, np.where(radius == 0, 0.0, 1.0)))
    ch, rh = np.where(use_h, ch, 0), np.where(use_h & np.isfinite(rh), rh, 0)
    cr, rr = np.where(use_r, cr, 1), np.where(use_r & np.isfinite(rr), rr, 0)
    kk = E12 * E21

    def du(H: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return 1.0 / (kk / (H - E22) + E11)

    def fun(mu: np.ndarray) -> np.ndarray:
        mu = np.asarray(mu, dtype=complex)
        with np.errstate(divide="ignore", invalid="ignore"):
            H = np.where(use_h, ch + rh * mu, T / (cr + rr * mu))
        return du(H)

    out = moebius_disk_image(fun, unit, n_freq=f)
    out.nominal = du(np.array(T))
    return out
