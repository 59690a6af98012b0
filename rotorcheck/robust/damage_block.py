"""Certified bound on the 2 x 2 damage dynamics at one shaft station, from several channel pairs.

Model, per frequency (all complex; ``x, y`` the two damage DOFs at the damage station):

* ``E11`` (2, 2) m/N: model receptance between the damage DOFs; ``E12`` (2, n_in) m/N: from the
  inputs to the damage DOFs; ``E21`` (n_out, 2) m/N: from the damage DOFs to the outputs. These are
  taken as EXACT (no model uncertainty here).
* ``Q0`` (n_out, n_in) m/N: the measured FRF change ``T_new - T_healthy``; ``R`` (n_out, n_in) m/N,
  ``R > 0``: the noise allowance per channel pair at the caller's (family-wise) confidence. The noise
  set is the polydisc ``{N : |N_oi| <= R_oi}``; every statement below holds at that confidence.
* The damaged FRF change is ``Q = E21 W E12`` with ``W = D (I - E11 D)^-1``, i.e.
  ``D(W) = (I + W E11)^-1 W = W (I + E11 W)^-1`` (N/m): the convention of
  :func:`rotorcheck.robust.identify.damage_dynamics` (``D = [E12 (T - T_h)^+ E21 + E11]^-1``; both agree
  on noise-free data). ``D`` is the extra force at the damage DOFs per unit displacement there: a
  stiffness loss ``dk`` gives ``D = +dk``.

The consistent set ``C = {W : |Q0_oi - (E21 W E12)_oi| <= R_oi for all o, i}`` is convex (one
second-order cone per pair in the 8 real unknowns of ``W``); the set of damage dynamics is its image
under the Moebius map ``D(W)`` (not convex). Per frequency and per diagonal entry ``D_kk`` (``k = 0``:
xx, ``1``: yy) the result holds a CERTIFIED OUTER interval of ``Re D_kk`` and of ``Im D_kk`` (every
``D(W)``, ``W`` in ``C``, lies inside) and an INNER interval spanned by witnesses (points of ``C``,
checked against the constraints, whose ``D`` is evaluated exactly): ``outer ⊇ true range ⊇ inner``.

Construction, per frequency (SOCPs in the 8 real unknowns solved by Clarabel; the cone matrix is built
once per region and only the objective changes between solves):

1. ``W_hat``: weighted least squares, ``min sum |Q0_oi - (E21 W E12)_oi|^2 / R_oi^2``;
   ``estimate = D(W_hat)``, ``consistent``: ``W_hat`` in ``C``.
2. ``W0``: the minimiser of ``max_oi |res_oi| / R_oi`` (one SOCP). Its dual certifies a lower bound of
   that minimum: above 1 proves ``C`` empty ('empty'); a checked ``W0`` with ``max |res| / R <= 1 +
   1e-9`` shows ``C`` non-empty; neither -> 'undecided'.
3. Expansion about a centre ``W1`` (first ``W0``): with ``B1 = I + W1 E11``, ``C1 = I + E11 W1``,
   ``L = C1 E11`` and the linear change of variables ``Y = B1^-1 (W - W1) C1^-1``, exactly (2 x 2)
   ``D(W) - D(W1) = (I + Y L)^-1 Y = (Y + det(Y) adj(L)) / (1 + tr(L Y) + det(L) det(Y))``.
   The support functions ``max Re(e^{-i theta} f)`` over the region, for ``f`` each entry of ``Y`` and
   ``tr(L Y)`` and ``theta`` on ``angles`` equally spaced angles (4 axis angles on refinement caps),
   give the extremes of the linear part ``Y_kk`` (at ``theta = 0, pi/2, pi, 3 pi/2``) and bounds
   ``|f| <= max_theta h(theta) / cos(pi / angles)`` (the circumscribed polygon). With ``t = tr(L Y)``,
   ``q = det Y``: ``|D_kk - D1_kk - Y_kk| <= (|adj(L)_kk| |q| + |Y_kk| (|t| + |det L| |q|)) / (1 -
   max Re(-t) - |det L| |q|)``, and also ``<= |Y_k.| |Y_.k| |L| / (1 - |L| |Y|_F)`` (row and column
   ``k`` of ``Y``, spectral norm of ``L``); the smaller is used. Neither denominator positive ->
   ``I + W E11`` may be singular on ``C``: 'unbounded'. Outer bound of each side: ``D1_kk`` + linear
   extreme + remainder bound.
4. Refinement (``refine`` rounds per side, while the side's gap exceeds 1 % of the outer width and
   keeps shrinking): only points with a value above the best witness's matter, and they satisfy the
   linear cut ``Re(e^{-i a pi/2} Y_kk) >= best - D1 term - remainder`` (the cut is lowered by 1e-4 of
   the current gap and by the rounding pad to allow for the witnesses' 1e-9 tolerance). The cap ``C ∩
   cuts`` is convex and much smaller; re-expanding about the current maximiser over the cap gives a
   smaller remainder. Each bound found is valid, the outer side is the smallest.
5. Inner interval: min / max of the exact ``D_kk`` over the witnesses (``W0``, ``W_hat`` and every
   SOCP maximiser), each first pulled towards ``W0`` just enough to satisfy the constraints (``C`` is
   convex) and then checked within ``1e-9`` relative of ``R`` (else dropped).
   ``C`` minus the (real codimension 2) singular set of ``I + W E11`` is connected, so the range of
   ``Re``/``Im D_kk`` over ``C`` is an interval holding the witnesses' values.

Rigour: no outer bound relies on the solver's optimality or feasibility tolerances. Each SOCP maximum
is replaced by a Lagrangian bound evaluated here from the solver's dual ``(mu, nu)`` alone, valid for
ANY ``mu`` and ``nu >= 0``: ``max Re(c . vec(W - W1)) <= Re(mu^H h) + |mu|_1 - nu . lev + |c - G'
conj(mu) + sum nu_i d_i|_2 F`` over ``C`` and the cuts ``Re(d_i . vec(W - W1)) >= lev_i``, with ``G``
the R-weighted linear map, ``h`` the weighted residual at ``W1`` and ``F = (|h|_2 + sqrt(n_out n_in))
/ sigma_min(G) >= |W - W1|_F`` on ``C``. The only tolerances are floating-point pads: ``16 eps`` times
the magnitudes in each certificate and a relative pad ``max(1e-10, 64 eps cond(B1) cond(C1))`` of each
side's scale (``|D1_kk|`` + linear extreme + remainder). Singular values of ``G`` below ``1e-12`` of
the largest count as zero: the map ``W -> E21 W E12`` is then not injective (``n_in < 2`` or ``n_out <
2``, or rank-deficient receptances), ``C`` is unbounded and so is the bound.

``kind`` per frequency:

* 'bounded': ``C`` non-empty and the set of ``D`` certified bounded; outer and inner finite.
* 'unbounded': ``C`` non-empty but NOT certified bounded (the map is not injective, or ``C`` reaches
  so far that ``I + W E11`` may be singular on it); outer ``(-inf, inf)``, inner from the witnesses.
* 'empty': ``C`` proven empty: the data contradict the local-damage hypothesis (with exact receptances)
  at the stated confidence; outer and inner NaN.
* 'undecided': non-finite or invalid input at that point (``R <= 0``), a solver status other than
  Solved / AlmostSolved in steps 2-3, an emptiness test that neither proves nor refutes, or any
  exception (including Clarabel's Rust panics, which derive from ``BaseException``); outer and inner
  NaN. Never raised (``KeyboardInterrupt`` and ``SystemExit`` are). A solver status other than
  Solved / AlmostSolved during the refinement (step 4) only ends the refinement of that side: the
  bound found so far stands.

Tightness: the gap between outer and inner grows with the nonlinearity of ``D(W)`` over ``C``, about
``|L| |Y|`` (``|E11 W|`` times the relative spread of ``W`` over ``C``). For ``|E11 D|`` ~ 0.1 and
noise radii of 1-5 % of ``|Q0|`` the gap is about 1 % of the outer width (2 refinement rounds); for
``|E11 D|`` ~ 1 it can reach tens of % (the set of ``D`` is then far from an affine image of ``C``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp

from rotorcheck.progress import Progress, report

__all__ = ["KINDS", "DamageBlockBound", "damage_block_bound"]

KINDS = ("bounded", "unbounded", "empty", "undecided")
_USABLE = ("Solved", "AlmostSolved")
_RANK_RTOL = 1e-12  # singular values of the weighted map below this (relative) count as zero
_WITNESS_RTOL = 1e-9  # a witness may exceed R by this fraction
_PAD_RTOL = 1e-10  # relative pad of the outer intervals (floating-point rounding)
_REFINE_RTOL = 1e-2  # refine a side while its gap exceeds this fraction of the outer width ...
_MIN_GAIN = 0.1  # ... and the last round removed at least this fraction of it
_COND_MAX = 1e14  # I + W E11 with a larger condition number counts as singular
_EPS = float(np.finfo(float).eps)
_AXES = np.pi / 2 * np.arange(4)  # Re, Im, -Re, -Im: Re(e^{-i a pi/2} z), a = 0..3


@dataclass(frozen=True)
class DamageBlockBound:
    """Certified bound on the diagonal damage dynamics ``D_xx, D_yy`` (N/m) per frequency (f,).

    Attributes
    ----------
    estimate : (f, 2, 2) complex, N/m
        ``D`` at the weighted least-squares ``W_hat`` (NaN where ``I + W_hat E11`` is singular or the
        input is invalid).
    consistent : (f,) bool
        Whether ``W_hat`` itself lies in the consistent set ``C``.
    kind : (f,) str
        'bounded', 'unbounded', 'empty' or 'undecided' (see the module docstring).
    re_outer, im_outer : (f, 2, 2) float, N/m
        Certified outer interval of ``Re D_kk`` / ``Im D_kk``: ``[..., k, 0]`` low, ``[..., k, 1]``
        high, ``k = 0`` xx, ``1`` yy. ``(-inf, inf)`` where 'unbounded', NaN where 'empty' or
        'undecided'.
    re_inner, im_inner : (f, 2, 2) float, N/m
        Range attained by the witnesses (same layout), inside the true range; NaN where 'empty' or
        'undecided'.
    """

    estimate: np.ndarray
    consistent: np.ndarray
    kind: np.ndarray
    re_outer: np.ndarray
    im_outer: np.ndarray
    re_inner: np.ndarray
    im_inner: np.ndarray

    def contains(self, D: np.ndarray) -> np.ndarray:
        """Whether the diagonal of ``D`` ((f, 2, 2) or (2, 2), N/m) lies in the outer intervals.

        Returns (f,) bool: True for any finite ``D`` where 'unbounded', False where 'empty' or
        'undecided' (NaN bounds).
        """
        D = np.asarray(D, dtype=complex)
        d = np.broadcast_to(D, (self.kind.shape[0], 2, 2))[:, [0, 1], [0, 1]]
        with np.errstate(invalid="ignore"):
            ok = ((d.real >= self.re_outer[..., 0]) & (d.real <= self.re_outer[..., 1])
                  & (d.imag >= self.im_outer[..., 0]) & (d.imag <= self.im_outer[..., 1]))
        return np.asarray(ok.all(axis=-1))

    @property
    def re_gap(self) -> np.ndarray:
        """(f, 2) N/m: outer width minus inner width of ``Re D_kk`` (the bound's possible excess)."""
        return _width(self.re_outer) - _width(self.re_inner)

    @property
    def im_gap(self) -> np.ndarray:
        """(f, 2) N/m: outer width minus inner width of ``Im D_kk``."""
        return _width(self.im_outer) - _width(self.im_inner)


def _width(iv: np.ndarray) -> np.ndarray:
    return np.asarray(iv[..., 1] - iv[..., 0])


def _stack(X: np.ndarray | float, name: str, shape: tuple[int, int] | None) -> np.ndarray:
    A = np.asarray(X, dtype=complex)
    if A.ndim == 2:
        A = A[None]
    if A.ndim != 3 or (shape is not None and A.shape[1:] != shape):
        raise ValueError(f"{name}: expected (f, r, c) or (r, c) with (r, c) = {shape}, got shape {np.shape(X)}")
    return A


def damage_block_bound(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, Q0: np.ndarray,
                       R: np.ndarray | float, angles: int = 8, refine: int = 2,
                       progress: Progress | None = None) -> DamageBlockBound:
    """Certified outer and witnessed inner intervals of ``Re``/``Im`` of ``D_xx``, ``D_yy`` (N/m).

    Parameters
    ----------
    E11 : (f, 2, 2) or (2, 2) complex, m/N
        Model receptance between the damage DOFs (x, y at the damage station).
    E12 : (f, 2, n_in) or (2, n_in) complex, m/N
        Model receptance from the inputs to the damage DOFs.
    E21 : (f, n_out, 2) or (n_out, 2) complex, m/N
        Model receptance from the damage DOFs to the outputs.
    Q0 : (f, n_out, n_in) or (n_out, n_in) complex, m/N
        Measured FRF change ``T_new - T_healthy``.
    R : (f, n_out, n_in), (n_out, n_in) or scalar, m/N
        Noise radius per pair (``|noise_oi| <= R_oi`` at the caller's confidence), ``> 0``.
    angles : int
        Support-function angles (>= 3) per entry of the first expansion (the 4 axis angles are added
        if missing); the modulus bounds exceed the circumscribed polygon by at most ``1 / cos(pi /
        angles)``. Solves per frequency before refinement: ``1 + 5 angles`` for a multiple of 4.
    refine : int
        Refinement rounds per interval side (0: none); each costs 20 solves. A side is refined while
        its gap exceeds 1 % of the outer width and the previous round removed at least 10 % of it.
    progress : Progress, optional
        Hears each frequency done (:mod:`rotorcheck.progress`).

    Returns
    -------
    DamageBlockBound
        Per frequency; a point with invalid data or a solver failure is 'undecided', never raised.
        Shapes that do not fit raise ``ValueError``.
    """
    if int(angles) != angles or angles < 3:
        raise ValueError(f"angles must be an integer >= 3, got {angles}")
    if int(refine) != refine or refine < 0:
        raise ValueError(f"refine must be an integer >= 0, got {refine}")
    E12s, E21s = _stack(E12, "E12", None), _stack(E21, "E21", None)
    n_in, n_out = E12s.shape[2], E21s.shape[1]
    if E12s.shape[1] != 2 or E21s.shape[2] != 2 or n_in < 1 or n_out < 1:
        raise ValueError(f"E12 must be (f, 2, n_in) and E21 (f, n_out, 2), got {E12s.shape}, {E21s.shape}")
    E11s, Q0s = _stack(E11, "E11", (2, 2)), _stack(Q0, "Q0", (n_out, n_in))
    Rs = np.asarray(R, dtype=float)
    Rs = np.broadcast_to(Rs, (n_out, n_in))[None] if Rs.ndim < 2 else (Rs[None] if Rs.ndim == 2 else Rs)
    if Rs.ndim != 3 or Rs.shape[1:] != (n_out, n_in):
        raise ValueError(f"R: expected shape (f, {n_out}, {n_in}), ({n_out}, {n_in}) or scalar, got {np.shape(R)}")
    sizes = {a.shape[0] for a in (E11s, E12s, E21s, Q0s, Rs)} - {1}
    if len(sizes) > 1:
        raise ValueError(f"frequency axes do not match: {sorted(sizes)}")
    f = sizes.pop() if sizes else 1

    def per_freq(a: np.ndarray) -> np.ndarray:
        return np.broadcast_to(a, (f, *a.shape[1:]))

    E11s, E12s, E21s, Q0s, Rs = (per_freq(a) for a in (E11s, E12s, E21s, Q0s, Rs))
    estimate = np.full((f, 2, 2), np.nan + 0j)
    consistent = np.zeros(f, dtype=bool)
    kind = np.full(f, "undecided", dtype="<U9")
    bounds = np.full((4, f, 2, 2), np.nan)  # re_outer, im_outer, re_inner, im_inner
    report(progress, 0, f, "damage dynamics")
    for i in range(f):
        if i:  # the points before this one done
            report(progress, i, f, "damage dynamics")
        pt = _Point(E11s[i], E12s[i], E21s[i], Q0s[i], Rs[i])
        try:
            estimate[i], consistent[i] = pt.estimate()
            kind[i], out = pt.bound(int(angles), int(refine))
        except (KeyboardInterrupt, SystemExit):
            raise
        except BaseException:  # Clarabel's Rust panics derive from BaseException
            kind[i] = "undecided"
            continue
        if out is not None:
            bounds[:, i] = out
    report(progress, f, f, "damage dynamics")
    return DamageBlockBound(estimate, consistent, kind, *bounds)


# --------------------------------------------------------------------------------------------------
# one frequency


def _moebius(W: np.ndarray, E11: np.ndarray) -> np.ndarray:
    """``D = (I + W E11)^-1 W`` (NaN if numerically singular: condition number above ``_COND_MAX``)."""
    B = np.eye(2) + W @ E11
    det = B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0]
    fro2 = float(np.sum(np.abs(B) ** 2))  # cond_2(B) <= |B|_F^2 / |det B| for 2 x 2
    if not (np.isfinite(fro2) and abs(det) * _COND_MAX > fro2):
        return np.full((2, 2), np.nan + 0j)
    adj = np.array([[B[1, 1], -B[0, 1]], [-B[1, 0], B[0, 0]]])
    return np.asarray(adj @ W / det)


def _phi(z: complex, a: int) -> float:
    """Functional ``a`` of a complex number: ``Re(e^{-i a pi/2} z)`` = Re, Im, -Re, -Im for a = 0..3."""
    return float(np.real(z * (-1j) ** a))


class _Undecided(Exception):
    """A solver status that is neither usable nor a proof."""


@dataclass
class _Cut:
    """``Re(d . vec(W - Wref)) >= lev``: holds for every W of C whose value can beat the best witness."""

    d: np.ndarray
    Wref: np.ndarray
    lev: float


@dataclass
class _Expansion:
    """The expansion about ``W1`` over a convex region (``C`` and cuts).

    ``Y_kk = ycoef[k] . vec(W - W1)``; ``hax[k, a]``: certified max over the region of ``Re(e^{-i a
    pi/2} Y_kk)``, ``wax[k][a]`` its maximiser; ``rem[k]``: bound of ``|D_kk - D1_kk - Y_kk|`` over the
    region (None: not certified); ``prel``: the relative rounding pad; ``witnesses``: all maximisers.
    """

    W1: np.ndarray
    D1: np.ndarray
    ycoef: np.ndarray
    hax: np.ndarray
    wax: list[list[np.ndarray]]
    rem: np.ndarray | None
    prel: float
    witnesses: list[np.ndarray]

    def upper(self, k: int, a: int) -> float:
        """Certified max of functional ``a`` of ``D_kk`` over the region (inf if not certified)."""
        if self.rem is None:
            return math.inf
        d1, h, rem = _phi(self.D1[k, k], a), float(self.hax[k, a]), float(self.rem[k])
        return d1 + h + rem + self.prel * (abs(d1) + abs(h) + rem)


class _Point:
    """One frequency: the weighted map, the SOCPs and their certificates."""

    def __init__(self, E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, Q0: np.ndarray, R: np.ndarray):
        self.E11, self.E12, self.E21, self.Q0, self.R = E11, E12, E21, Q0, R
        self.m = Q0.size
        self.w_hat = np.full((2, 2), np.nan + 0j)
        self.G = np.zeros((self.m, 4), complex)
        self.g = np.zeros(self.m, complex)
        self.r = 0
        self.Ur = np.zeros((self.m, 0), complex)
        self.Tz = np.zeros((4, 0), complex)
        self.smin = 0.0
        self.settings = clarabel.DefaultSettings()
        self.settings.verbose = False
        self.settings.max_threads = 1

    # ---- data ------------------------------------------------------------------------------------
    def viol(self, W: np.ndarray) -> float:
        """``max_oi |Q0 - E21 W E12|_oi / R_oi`` (<= 1: ``W`` in ``C``)."""
        return float(np.max(np.abs(self.Q0 - self.E21 @ W @ self.E12) / self.R))

    def estimate(self) -> tuple[np.ndarray, bool]:
        """(D(W_hat), W_hat in C) with the weighted least-squares ``W_hat``."""
        data = (self.E11, self.E12, self.E21, self.Q0, self.R)
        if not all(np.all(np.isfinite(x)) for x in data) or not np.all(self.R > 0):
            raise ValueError("non-finite input or R <= 0")
        # G[(o, i), (j, l)] = E21[o, j] E12[l, i] / R[o, i]: (G vec W)_(o,i) = (E21 W E12)_oi / R_oi
        self.G = (np.einsum("oj,li->oijl", self.E21, self.E12) / self.R[:, :, None, None]).reshape(self.m, 4)
        self.g = (self.Q0 / self.R).reshape(self.m)
        w, *_ = np.linalg.lstsq(self.G, self.g, rcond=None)
        self.w_hat = w.reshape(2, 2)
        return _moebius(self.w_hat, self.E11), self.viol(self.w_hat) <= 1.0

    # ---- SOCP pieces -----------------------------------------------------------------------------
    def _soc_rows(self, n: int) -> np.ndarray:
        """Rows of the cones ``(t or 1, Re(h - U z), Im(h - U z)) in SOC(3)``, variables (Re z, Im z, ...)."""
        Ur, r = self.Ur, self.r
        A = np.zeros((3 * self.m, n))
        A[1::3, :r], A[1::3, r:2 * r] = Ur.real, -Ur.imag
        A[2::3, :r], A[2::3, r:2 * r] = Ur.imag, Ur.real
        return A

    @staticmethod
    def _b(h: np.ndarray, head: float) -> np.ndarray:
        b = np.empty(3 * h.size)
        b[0::3], b[1::3], b[2::3] = head, h.real, h.imag
        return b

    def _zeta_coef(self, c: np.ndarray) -> np.ndarray:
        """Real coefficients (of Re z, Im z) of ``Re(c . vec Delta)``, ``vec Delta = Tz z``."""
        bz = self.Tz.T @ c
        return np.concatenate([bz.real, -bz.imag])

    def _pads(self, F: float, W1: np.ndarray) -> np.ndarray:
        """Per pair, the magnitudes a certificate about ``W1`` rounds (the residual h and the product G Delta,
        ``|Delta|_F <= F``): its rounding allowance is ``16 eps mu_abs . pads`` (:meth:`_rounding`)."""
        mag = (np.abs(self.Q0) + np.abs(self.E21) @ np.abs(W1) @ np.abs(self.E12)) / self.R
        gnorm = np.linalg.norm(self.G, axis=1)
        return np.asarray(mag.reshape(-1) + gnorm * F)

    @staticmethod
    def _rounding(mu_abs: np.ndarray, pads: np.ndarray) -> float:
        """Rounding allowance of a certificate with dual moduli ``mu_abs`` (``pads``: :meth:`_pads`)."""
        return 16 * _EPS * float(mu_abs @ pads)

    # ---- step 2: emptiness and the centre W0 -----------------------------------------------------
    def centre(self) -> tuple[str, np.ndarray, float]:
        """('empty' | 'undecided' | 'ok', W0, max |res| / R at W0)."""
        G, m, r = self.G, self.m, self.r
        h = self.g - G @ self.w_hat.reshape(4)
        A = self._soc_rows(2 * r + 1)
        A[0::3, -1] = -1.0
        q = np.zeros(2 * r + 1)
        q[-1] = 1.0
        sol = clarabel.DefaultSolver(sp.csc_matrix((2 * r + 1, 2 * r + 1)), q, sp.csc_matrix(A), self._b(h, 0.0),
                                     [clarabel.SecondOrderConeT(3)] * m, self.settings).solve()
        if str(sol.status) not in _USABLE:
            return "undecided", self.w_hat, math.nan
        x, z = np.asarray(sol.x), np.asarray(sol.z)
        mu = -(z[1::3] + 1j * z[2::3])  # Clarabel's dual pairs with h - G Delta as -mu
        mu1 = float(np.sum(np.abs(mu)))
        # any mu; for W in C (|W - W_hat|_F <= F): 1 >= max |res_p| >= Re(mu^H res) / |mu|_1 >= lower / |mu|_1
        F = (float(np.linalg.norm(h)) + math.sqrt(m)) / self.smin
        a1 = float(np.real(np.vdot(mu, h)))
        e = float(np.linalg.norm(G.T @ mu.conj())) * F
        lower = a1 - e - self._rounding(np.abs(mu), self._pads(F, self.w_hat)) - 16 * _EPS * (abs(a1) + e)
        if mu1 > 0 and lower > mu1:
            return "empty", self.w_hat, math.nan
        W0 = self.w_hat + (self.Tz @ (x[:r] + 1j * x[r:2 * r])).reshape(2, 2)
        t0 = self.viol(W0)
        if not t0 <= 1 + _WITNESS_RTOL:
            return "undecided", W0, t0  # neither proven empty nor shown non-empty
        return "ok", W0, t0

    # ---- step 3: the expansion about W1 over C and the cuts --------------------------------------
    def expand(self, W1: np.ndarray, cuts: list[_Cut], angles: np.ndarray) -> _Expansion | None:
        """Support functions of the entries of ``Y`` and of ``tr(L Y)`` about ``W1`` over ``C`` and the
        cuts (None: ``I + W1 E11`` singular). Raises :class:`_Undecided` on a solver failure."""
        B1, C1 = np.eye(2) + W1 @ self.E11, np.eye(2) + self.E11 @ W1
        cB, cC = float(np.linalg.cond(B1)), float(np.linalg.cond(C1))
        if not (cB < _COND_MAX and cC < _COND_MAX):
            return None
        Binv, Cinv = np.linalg.inv(B1), np.linalg.inv(C1)
        ycoef = np.einsum("ja,bl->jlab", Binv, Cinv).reshape(2, 2, 4)  # Y_jl = ycoef[j, l] . vec(W - W1)
        L = C1 @ self.E11
        tcoef = np.einsum("lj,jlx->x", L, ycoef)  # tr(L Y) = tcoef . vec(W - W1)
        G, m, r = self.G, self.m, self.r
        h1 = self.g - G @ W1.reshape(4)
        F1 = (float(np.linalg.norm(h1)) + math.sqrt(m)) / self.smin  # |W - W1|_F <= F1 on C
        A = self._soc_rows(2 * r)
        b = self._b(h1, 1.0)
        cones = [clarabel.SecondOrderConeT(3)] * m
        levs = np.array([cut.lev - float(np.real(cut.d @ (W1 - cut.Wref).reshape(4))) for cut in cuts])
        if cuts:
            A = np.vstack([A, -np.array([self._zeta_coef(cut.d) for cut in cuts])])
            b = np.concatenate([b, -levs])
            cones.append(clarabel.NonnegativeConeT(len(cuts)))
        solver = clarabel.DefaultSolver(sp.csc_matrix((2 * r, 2 * r)), np.zeros(2 * r), sp.csc_matrix(A), b, cones,
                                        self.settings)
        witnesses: list[np.ndarray] = []
        # fixed over the region's support functions (computed once here, not per solve)
        pads = self._pads(F1, W1)
        GT = G.T
        cut_norms = [np.linalg.norm(cut.d) for cut in cuts]

        def support(c: np.ndarray) -> float:
            """Certified upper bound of ``max Re(c . vec(W - W1))`` over the region."""
            cz = self._zeta_coef(c)
            nc = float(np.linalg.norm(cz))
            if nc == 0:
                return 0.0 if r == 4 else math.inf
            solver.update(q=-cz / nc)
            s = solver.solve()
            if str(s.status) not in _USABLE:
                raise _Undecided(str(s.status))
            xs, zs = np.asarray(s.x), np.asarray(s.z)
            witnesses.append(W1 + (self.Tz @ (xs[:r] + 1j * xs[r:])).reshape(2, 2))
            if r < 4:
                return math.inf
            # any mu, nu >= 0: Re(c . Delta) <= Re(mu^H h1) + |mu|_1 - nu . lev + |c - G' conj mu + sum nu d| F1
            mu = nc * (zs[1:3 * m:3] + 1j * zs[2:3 * m:3])
            nu = nc * np.maximum(zs[3 * m:], 0.0)
            e = c - GT @ mu.conj()
            for cut, v in zip(cuts, nu):
                e = e + v * cut.d
            mabs = np.abs(mu)
            a1, s1, s3 = float(np.real(np.vdot(mu, h1))), float(np.sum(mabs)), float(np.linalg.norm(e)) * F1
            s2 = float(nu @ levs) if cuts else 0.0
            s4 = sum(float(v * dn) for dn, v in zip(cut_norms, nu)) * F1
            val = a1 + s1 - s2 + s3 + self._rounding(mabs, pads) + 16 * _EPS * (abs(a1) + s1 + abs(s2) + s3 + s4)
            if not math.isfinite(val):
                raise _Undecided("non-finite certificate")
            return val

        hs = np.empty((5, angles.size))  # rows: Y_00, Y_01, Y_10, Y_11, tr(L Y)
        wax: list[list[np.ndarray]] = [[W1] * 4, [W1] * 4]
        axes = [int(np.argmin(np.abs(angles - ax))) for ax in _AXES]
        for e, coef in enumerate([*ycoef.reshape(4, 4), tcoef]):
            for s, th in enumerate(angles):
                hs[e, s] = support(np.exp(-1j * th) * coef)
                if e in (0, 3) and s in axes:
                    wax[e // 3][axes.index(s)] = witnesses[-1]
        gaps = np.diff(np.append(angles, angles[0] + 2 * np.pi))
        mods = np.maximum(hs.max(axis=1), 0.0) / math.cos(float(gaps.max()) / 2)  # |Y_jl|, |tr(L Y)|
        mod = mods[:4].reshape(2, 2)
        tmax = min(float(mods[4]), float(np.abs(L.T).reshape(4) @ mod.reshape(4)))
        rem = self._remainder(L, mod, tmax, float(hs[4, axes[2]])) if r == 4 else None
        hax = np.array([[hs[3 * k, axes[a]] for a in range(4)] for k in range(2)])
        prel = max(_PAD_RTOL, 64 * _EPS * cB * cC)
        return _Expansion(W1, _moebius(W1, self.E11), np.array([ycoef[0, 0], ycoef[1, 1]]), hax, wax, rem, prel,
                          witnesses)

    @staticmethod
    def _remainder(L: np.ndarray, mod: np.ndarray, tmax: float, tneg: float) -> np.ndarray | None:
        """Bounds of ``|D_kk - D1_kk - Y_kk|`` (k = 0, 1) over a region where ``|Y_jl| <= mod[j, l]``,
        ``|tr(L Y)| <= tmax`` and ``Re(-tr(L Y)) <= tneg``; None if ``I + Y L`` may be singular there.

        2 x 2: ``D - D1 = (I + Y L)^-1 Y = (Y + det(Y) adj(L)) / (1 + tr(L Y) + det(L) det(Y))``, so
        ``D_kk - D1_kk - Y_kk = (adj(L)_kk q - Y_kk (t + det(L) q)) / (1 + t + det(L) q)`` with ``t =
        tr(L Y)``, ``q = det(Y)``, ``|q| <= mod_00 mod_11 + mod_01 mod_10``, ``|1 + t + det(L) q| >= 1 -
        tneg - |det L| |q|``; it also equals ``-(e_k' Y) (I + L Y)^-1 L (Y e_k)``, bounded by
        ``|Y_k.| |Y_.k| |L| / (1 - |L| |Y|_F)``. The smaller bound is returned.
        """
        qm = float(mod[0, 0] * mod[1, 1] + mod[0, 1] * mod[1, 0])
        detL = abs(complex(np.linalg.det(L)))
        den = 1 - min(tneg, tmax) - detL * qm
        Lnorm = float(np.linalg.norm(L, 2))
        y = float(np.linalg.norm(mod))
        if not (den > 0 or Lnorm * y < 1):
            return None
        rem = np.full(2, math.inf)
        for k in range(2):
            if den > 0:
                rem[k] = (abs(L[1 - k, 1 - k]) * qm + mod[k, k] * (tmax + detL * qm)) / den
            if Lnorm * y < 1:
                rem[k] = min(rem[k], math.hypot(*mod[k]) * math.hypot(*mod[:, k]) * Lnorm / (1 - Lnorm * y))
        return rem

    # ---- the bound -------------------------------------------------------------------------------
    def bound(self, angles: int, refine: int) -> tuple[str, np.ndarray | None]:
        """(kind, bounds (4, 2, 2): re_outer, im_outer, re_inner, im_inner; None when empty/undecided)."""
        U, S, Vh = np.linalg.svd(self.G, full_matrices=False)
        if not S[0] > 0:  # the data do not depend on W: C is empty or everything
            if np.max(np.abs(self.g)) > 1:
                return "empty", None
            wit = _Witnesses(self, self.w_hat, 1.0)
            wit.add([self.w_hat])
            return "unbounded", self._bounds(np.full((2, 4), np.inf), wit)
        r = self.r = int(np.sum(S > _RANK_RTOL * S[0]))
        if r < 4:  # treat the tiny singular values as zero (within rounding of the data)
            self.G = (U[:, :r] * S[:r]) @ Vh[:r]
        self.Ur = U[:, :r]
        self.Tz = Vh[:r].conj().T / S[:r]  # vec(W - W_ref) = Tz z
        self.smin = float(S[r - 1]) * (1 - 1e-12)

        status, W0, t0 = self.centre()
        if status != "ok":
            return status, None
        wit = _Witnesses(self, W0, t0)
        wit.add([W0, self.w_hat])
        th = 2 * np.pi * np.arange(angles) / angles
        th = np.sort(np.concatenate([th, [ax for ax in _AXES if np.min(np.abs(th - ax)) > 1e-9]]))
        base = self.expand(W0, [], th)
        if base is None:
            return "unbounded", self._bounds(np.full((2, 4), np.inf), wit)
        wit.add(base.witnesses)
        ub = np.array([[base.upper(k, a) for a in range(4)] for k in range(2)])
        if base.rem is None:
            return "unbounded", self._bounds(ub, wit)
        for k in range(2):
            for a in range(4):
                self._refine(k, a, base, ub, wit, refine)
        return "bounded", self._bounds(ub, wit)

    def _refine(self, k: int, a: int, base: _Expansion, ub: np.ndarray, wit: _Witnesses, rounds: int) -> None:
        """Lower ``ub[k, a]`` on caps of C (in place; the new witnesses join ``wit``).

        Only W with a value above the best witness's matter: by the current expansion they satisfy
        ``Re(e^{-i a pi/2} Y_kk) >= best - phi(D1_kk) - rem``, a linear cut. Re-expanding about the
        current maximiser over the cap (C and the cuts) gives a smaller remainder. A failure keeps the
        bound found so far (each is valid)."""
        cur = base
        cuts: list[_Cut] = []
        for _ in range(rounds):
            best = wit.best(k, a)
            gap = ub[k, a] - best
            if not (math.isfinite(best) and gap > _REFINE_RTOL * (ub[k, a] + ub[k, (a + 2) % 4])):
                return
            assert cur.rem is not None
            d1, rem = _phi(cur.D1[k, k], a), float(cur.rem[k])
            lev = best - d1 - rem - 1e-4 * gap - cur.prel * (abs(best) + abs(d1) + rem)
            cuts = [*cuts, _Cut((-1j) ** a * cur.ycoef[k], cur.W1, lev)]
            try:
                new = self.expand(cur.wax[k][a], cuts, _AXES)
            except _Undecided:
                return
            if new is None:
                return
            wit.add(new.witnesses)
            if new.rem is None:
                return
            old = ub[k, a]
            ub[k, a] = min(old, new.upper(k, a))
            cur = new
            if old - ub[k, a] < _MIN_GAIN * (old - best):
                return  # not converging: spend no more solves on this side

    def _bounds(self, ub: np.ndarray, wit: _Witnesses) -> np.ndarray:
        """(4, 2, 2) re_outer, im_outer, re_inner, im_inner from the upper bounds ``ub[k, a]`` of the four
        functionals and from the witnesses."""
        out = np.full((4, 2, 2), np.nan)
        out[0, :, 0], out[0, :, 1] = -ub[:, 2], ub[:, 0]
        out[1, :, 0], out[1, :, 1] = -ub[:, 3], ub[:, 1]
        d = wit.values()
        if d.size:
            out[2, :, 0], out[2, :, 1] = d.real.min(0), d.real.max(0)
            out[3, :, 0], out[3, :, 1] = d.imag.min(0), d.imag.max(0)
        return out


class _Witnesses:
    """Checked points of C and their exact ``D_xx, D_yy``.

    A point outside C is first pulled towards ``W0`` just enough (C convex: max |res|/R at ``W0 + lam
    (W - W0)`` is at most ``(1 - lam) t0 + lam tw``); it is dropped if still not within 1e-9 of R or if
    ``I + W E11`` is singular there."""

    def __init__(self, pt: _Point, W0: np.ndarray, t0: float):
        self.pt, self.W0, self.t0 = pt, W0, t0
        self.diag: list[np.ndarray] = []

    def add(self, Ws: list[np.ndarray]) -> None:
        for W in Ws:
            tw = self.pt.viol(W)
            if tw > 1 and self.t0 < 1:
                W = self.W0 + (1 - self.t0) / (tw - self.t0) * (W - self.W0)
                tw = self.pt.viol(W)
            if tw <= 1 + _WITNESS_RTOL:
                D = _moebius(W, self.pt.E11)
                if np.all(np.isfinite(D)):
                    self.diag.append(np.array([D[0, 0], D[1, 1]]))

    def values(self) -> np.ndarray:
        """(n, 2) complex: D_xx, D_yy of the checked witnesses."""
        return np.array(self.diag).reshape(-1, 2)

    def best(self, k: int, a: int) -> float:
        """Largest functional ``a`` of ``D_kk`` over the witnesses (-inf if none)."""
        d = self.values()[:, k]
        return float(np.max(np.real(d * (-1j) ** a))) if d.size else -math.inf
