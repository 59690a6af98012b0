"""General lateral Timoshenko shaft element: tapered hollow section, axial force and torque.

The element of :mod:`rotorcheck.fe.elements` generalised to a linearly tapered hollow circular
section (a conical frustum shell: outer and inner radius vary linearly from node 1 to node 2), with
switches for shear deformation, rotary inertia and gyroscopic effects, the geometric stiffness of an
axial force and the stiffness of an axial torque. DOF order and sign conventions are those of
:mod:`rotorcheck.fe.elements`: per node ``[u (x), v (y), theta (about x), psi (about y)]``, element
``[u1 v1 th1 psi1 u2 v2 th2 psi2]``; the x plane ``[u, psi]`` is the standard bending plane
``[w, beta]`` and the y plane ``[v, theta]`` the standard plane with the signs ``S = [1, -1, 1, -1]``.

Two formulations of the bending + shear stiffness, chosen by ``taper`` of :func:`shaft_matrices`;
the mass, gyroscopic, axial-force and torque matrices are the same in both.

Common part (Greenhill, Bickford & Nelson 1985, "A conical beam finite element for rotor dynamics
analysis", J. Vib. Acoust. 107, 421-430; the element of ROSS, ``ross.ShaftElement``):

* ``A(xi)`` and ``I(xi)`` (``xi = z / L``) are the exact polynomials of degree 2 and 4 of the
  frustum, not a staircase;
* the Timoshenko shape functions of :func:`~rotorcheck.fe.elements.beam_shape_functions` with one
  shear parameter per element, ``Phi = 12 E I_mid / (kappa G A_mid L^2)``, where ``A_mid`` and
  ``I_mid`` belong to the mid-length section (mean outer and mean inner diameter);
* the mass, gyroscopic, axial-force and torque matrices are the consistent ones of these shape
  functions: exact integrals of polynomial integrands, by 5-point Gauss-Legendre quadrature (exact
  to degree 9; the highest integrand degree is 8: ``A`` (2) times ``N_w N_w`` (6), and ``I`` (4)
  times ``N_b N_b`` (4)).

Stiffness:

* ``taper="exact"`` (default): the exact static stiffness of the tapered Timoshenko beam (not of
  the shape functions), by the flexibility method (see :func:`_exact_stiffness`): the tip flexibility
  of the element clamped at node 1, ``int (L - z)^k / EI(z) dz`` and ``int 1 / (kappa G A(z)) dz``
  by Gauss-Legendre on a graded subdivision (relative accuracy 1.4e-15 on the worst element of a
  4-element mesh of a 0.1 -> 0.01 m solid cone, 0.0325 -> 0.01 m, ``I`` varying 111x; 4e-15 for a
  0.1 -> 0.001 m element; one plain 24-point rule gives 5e-15 and 9e-2 there), inverted and
  completed by free-body equilibrium. A nodal load then gives the exact deflections of the actual
  tapered beam with any number of elements, and only the mass discretisation limits the
  convergence of the frequencies;
* ``taper="greenhill"``: ``int E I N_b'^T N_b' + kappa G A (N_w' - N_b)^T (N_w' - N_b) dz`` with the
  shape functions above, as ROSS. With a strong taper the one mid-section ``Phi`` does not fit the
  relation between shear strain and curvature that the varying ``EI(z) / kappa G A(z)`` imposes, and
  with shear on the element converges slowly.

For a uniform element both formulations equal the closed forms of
:func:`~rotorcheck.fe.elements.beam_matrices` to round-off (the interdependent element is exact in
statics; ``"exact"`` then keeps the polynomial integral, so that uniform elements give the same
numbers, bit for bit, in both). ``taper="greenhill"`` reproduces, with the same ``kappa``, ROSS 2.3.0's
``ShaftElement.M()``, ``G()`` and the lateral part of ``K()`` to round-off (1e-15 relative; the axial
force and torque parts on their own 1e-15 and 1e-14), including the tapered and hollow tapered
cases and every combination of the switches; ``"exact"`` differs from ROSS in ``K`` of tapered
elements only.

Convergence (steel solid cone 0.5 m, diameter 0.1 -> 0.01 m, pinned-pinned, E = 211 GPa,
G = 81.2 GPa, rho = 7810 kg/m^3, Cowper ``kappa``; error of the lowest two bending frequencies, %,
against the Richardson extrapolation of 256- and 512-step staircases of uniform elements, itself
within 2e-8 of a 512-element exact mesh)::

    elements      greenhill          exact              staircase (same n)
    shear on
       4        +4.9    +4.2      -0.030  -3.8        -14     -2.8
      16        +1.8    +1.1      +0.0030 +0.020      -2.3    -1.4
      64        +0.21   +0.12     +0.00022 +0.0014    -0.14   -0.086
    shear off
       4        +0.73   +0.81     -0.082  -4.5        -15     -3.5
      16        +0.092  +0.075    -0.00033 -0.0030    -2.4    -1.5
      64        +0.00083 +0.00066 -0.0000019 -0.000024 -0.15  -0.096

With shear on both converge as O(h^2) asymptotically (4x per halving from 32 elements on), the
rate of the uniform Timoshenko element itself (the mass of the shape functions, whose ``Phi`` grows
as ``1 / h^2``), ``exact`` with an error about 600x (mode 1) and 60-90x (mode 2) smaller: 16 exact
elements are closer than a 64-step staircase. From 16 to 64 elements the error falls 13x
(``exact``) and 9x (``greenhill``). With shear off both are O(h^4) and ``exact`` is 25-440x closer.
``exact`` is not a Rayleigh-Ritz method (its stiffness is not that of the mass's shape functions):
its frequencies are not upper bounds, and on a mild taper (0.1 -> 0.05 m over 1 m, Euler-Bernoulli)
its first-mode error is 2-4x that of ``greenhill`` (both O(h^4); 2e-9 and 1e-9 at 64 elements); at 4
elements on the strong cone its second mode is no better (-3.8 % against +4.2 %). A 512-step
staircase is itself 2.2e-5 (mode 1) low here, too coarse a reference below about 64 exact elements.
Modes 1-3 of ROSS's cone on rigid supports at 4, 8, 16 and 32 elements of either formulation
against a converged mesh: ``tests/fe/test_fe_taper_convergence.py`` (``exact`` 6-830x closer from 8
elements on; at 4 elements its modes 2 and 3 are -3.8 % and -17.5 % off, ``greenhill``'s +4.2 % and
+6.5 %).

In statics one ``greenhill`` element is too stiff wherever ``I`` varies much along it: under a tip
force its tip deflection is 9 % short (shear on; 7 % off) on ROSS's docstring element (outer
0.1 -> 0.15 m, inner 0.05 m, 0.5 m; ``I`` varies 5.3x) and 10 % short on 0.0325 -> 0.01 m, 0.125 m
(``I`` 111x), and under a tip moment its tip rotation is up to 44 % short; the ``exact`` element's
entries there are 10-21 % below ROSS's.

Findings on ROSS 2.3.0 (``ross/shaft_element.py``):

* its ``shear_method_calc="hutchinson"`` formula has ``(1 + nu)`` where Hutchinson (2001) has
  ``(1 + nu)^2``: it gives 0.712 for a solid section at nu = 0.3 instead of 0.925
  (:func:`rotorcheck.fe.elements.shear_coefficient` is the correct one). Its ``"cowper"`` option
  is Cowper's (1966) formula, :func:`cowper_shear_coefficient`;
* ROSS computes ``kappa`` of a tapered element from the ratio mean inner / mean outer diameter.
  Callers of :func:`shear_coefficient_by` should pass the mean diameters of the element,
  ``(outer_left + outer_right) / 2`` and ``(inner_left + inner_right) / 2``, to agree with it;
* the gyroscopic matrix is controlled by the ``gyroscopic`` switch alone (it stays on with
  ``rotary_inertia=False``); this module does the same;
* its torque matrix is the virtual work of an axial torque with the Euler-Bernoulli rotation shape
  functions even when shear is on, and it is not symmetric (see :func:`shaft_matrices`);
* the Timoshenko element (uniform too, here, in ROSS and in :mod:`rotorcheck.fe.elements`) converges
  only as O(h^2) in the natural frequencies once ``Phi`` of the elements exceeds about 1 (elements
  shorter than the diameter); with ``shear=False`` it converges as O(h^4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotorcheck.fe.elements import (
    _gyro_from_rotary,
    _plane_rotary_mass,
    _plane_stiffness,
    _plane_translational_mass,
    _planes_to_8,
    shear_coefficient,
)

Array = NDArray[np.float64]

# Gauss-Legendre points on xi in [0, 1]: 5 points integrate polynomials up to degree 9 exactly
_XG, _WG = np.polynomial.legendre.leggauss(5)
_XI = 0.5 * (_XG + 1.0)
_WXI = 0.5 * _WG

# Timoshenko shape functions (beam_shape_functions) as N = (P0 + Phi P1) / (1 + Phi), columns
# scaled by L (w) or 1/L (beta) below; rows are the coefficients of 1, xi, xi^2, xi^3
_NW0 = np.array([[1.0, 0.0, -3.0, 2.0], [0.0, 1.0, -2.0, 1.0], [0.0, 0.0, 3.0, -2.0], [0.0, 0.0, -1.0, 1.0]]).T
_NW1 = np.array([[1.0, -1.0, 0.0, 0.0], [0.0, 0.5, -0.5, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, -0.5, 0.5, 0.0]]).T
_NB0 = np.array([[0.0, -6.0, 6.0, 0.0], [1.0, -4.0, 3.0, 0.0], [0.0, 6.0, -6.0, 0.0], [0.0, -2.0, 3.0, 0.0]]).T
_NB1 = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]).T
_POW = np.arange(4)
_V = _XI[:, None] ** _POW  # (nq, 4) values of 1, xi, xi^2, xi^3
_DV = np.where(_POW > 0, _POW * _XI[:, None] ** np.maximum(_POW - 1, 0), 0.0)  # d/dxi

# exact (flexibility) stiffness: 16-point Gauss-Legendre on each piece of a graded subdivision
_XF16, _WF16 = np.polynomial.legendre.leggauss(16)
_XF = 0.5 * (_XF16 + 1.0)
_WF = 0.5 * _WF16
_MAX_LEVELS = 60  # pieces per side of a zero: enough for a zero 1e-18 lengths away
TAPER_FORMULATIONS = ("exact", "greenhill")


def cowper_shear_coefficient(
    poisson: ArrayLike, outer_diameter: ArrayLike, inner_diameter: ArrayLike = 0.0
) -> float | Array:
    """Shear coefficient of a (hollow) circular section, Cowper (1966).

    ``kappa = 6 (1 + nu) (1 + m^2)^2 / ((7 + 6 nu) (1 + m^2)^2 + (20 + 12 nu) m^2)`` with
    ``m = inner / outer`` (G. R. Cowper, J. Appl. Mech. 33 (1966) 335-340); 0.886 for a solid section
    at nu = 0.3. Diameters in m (only their ratio matters); vectorised.
    """
    nu = np.asarray(poisson, dtype=float)
    m2 = (np.asarray(inner_diameter, dtype=float) / np.asarray(outer_diameter, dtype=float)) ** 2
    s = (1.0 + m2) ** 2
    k = 6.0 * (1.0 + nu) * s / ((7.0 + 6.0 * nu) * s + (20.0 + 12.0 * nu) * m2)
    return float(k) if k.ndim == 0 else k


def shear_coefficient_by(
    method: str, poisson: ArrayLike, outer_diameter: ArrayLike, inner_diameter: ArrayLike
) -> float | Array:
    """Shear coefficient by ``method``: ``"hutchinson"`` (2001) or ``"cowper"`` (1966).

    For a tapered element pass the mean outer and mean inner diameter (m), as ROSS does.
    ``"hutchinson"`` is :func:`rotorcheck.fe.elements.shear_coefficient` (not ROSS's formula of the
    same name, which lacks a factor ``1 + nu``). Raises ``ValueError`` for another method.
    """
    if method == "cowper":
        return cowper_shear_coefficient(poisson, outer_diameter, inner_diameter)
    if method == "hutchinson":
        nu, do, di = np.broadcast_arrays(
            np.asarray(poisson, dtype=float),
            np.asarray(outer_diameter, dtype=float),
            np.asarray(inner_diameter, dtype=float),
        )
        if nu.ndim == 0:
            return float(shear_coefficient(float(nu), float(do), float(di)))
        flat = [shear_coefficient(float(a), float(b), float(c)) for a, b, c in zip(nu.ravel(), do.ravel(), di.ravel())]
        return np.asarray(flat, dtype=float).reshape(nu.shape)
    raise ValueError(f"unknown shear coefficient method {method!r}: use 'hutchinson' or 'cowper'")


@dataclass(frozen=True)
class ShaftMatrices:
    """Matrices of ne shaft elements, each (ne, 8, 8), DOF ``[u1 v1 th1 psi1 u2 v2 th2 psi2]``.

    ``mass`` (kg, kg m, kg m^2) symmetric; ``gyroscopic`` per unit spin speed (rad/s), skew-symmetric;
    ``stiffness`` bending plus shear (N/m, N/rad, N m/rad), symmetric, of the chosen ``taper``
    formulation; ``axial_force`` the geometric
    stiffness of the given axial force, symmetric; ``torque`` the stiffness of the given axial
    torque, NOT symmetric (skew theta-psi block ``-+T/2`` at each node; see :func:`shaft_matrices`).
    Stiffness units throughout. The total stiffness is ``stiffness + axial_force + torque``.
    """

    mass: Array
    gyroscopic: Array
    stiffness: Array
    axial_force: Array
    torque: Array


def _shape_functions(L: Array, phi: Array) -> tuple[Array, Array, Array, Array]:
    """N_w, N_b and their z-derivatives at the Gauss points, each (ne, nq, 4), standard plane."""
    c = (1.0 / (1.0 + phi))[:, None, None]
    p = phi[:, None, None]
    ll = L[:, None, None]
    one = np.ones_like(L)
    sw = np.stack([one, L, one, L], axis=1)[:, None, :]  # column scales of N_w
    sb = np.stack([1.0 / L, one, 1.0 / L, one], axis=1)[:, None, :]  # of N_b
    nw = c * sw * (_V @ _NW0 + p * (_V @ _NW1))
    nb = c * sb * (_V @ _NB0 + p * (_V @ _NB1))
    dnw = c * sw * (_DV @ _NW0 + p * (_DV @ _NW1)) / ll
    dnb = c * sb * (_DV @ _NB0 + p * (_DV @ _NB1)) / ll
    return nw, nb, dnw, dnb


def _flexibility_points(ro0: Array, ro1: Array, ri0: Array, ri1: Array) -> tuple[Array, Array]:
    """Quadrature points ``xi`` and weights on [0, 1], each (ne, n), for ``1 / I(xi)`` and ``1 / A(xi)``.

    ``ro0, ro1, ri0, ri1`` are the outer and inner radii at the two nodes. ``r_o^4 - r_i^4`` is the
    product of the linear factors ``r_o - r_i``, ``r_o + r_i`` and ``r_o -+ i r_i`` (``r_o^2 - r_i^2``
    of the first two), so the integrands are analytic except at the zeros ``p`` of those factors,
    off [0, 1]. For each zero at distance ``d0`` from its nearest point ``x0`` of [0, 1] the element
    is cut at ``x0 +- d0 2^k`` (a geometric grading towards the zero): every piece is then no longer
    than its distance to every zero, i.e. in the piece's own coordinate ``t`` in [-1, 1] the
    integrand is analytic inside the Bernstein ellipse ``rho >= 2 + sqrt(5)``, and 16-point
    Gauss-Legendre on each piece converges like ``rho^-32 ~ 1e-20`` (times the pole order's
    polynomial factor). A uniform element, or one whose zeros are at least one length away, is one
    piece (integrands of a uniform element are polynomials of degree <= 2: exact).
    """
    a = np.stack([ro0 - ri0, ro0 + ri0, ro0 + 1j * ri0], axis=1)  # factor values at xi = 0
    b = np.stack([ro1 - ri1 - (ro0 - ri0), ro1 + ri1 - (ro0 + ri0), ro1 - ro0 + 1j * (ri1 - ri0)], axis=1)
    tapered = b != 0
    with np.errstate(divide="ignore", invalid="ignore"):
        pole = np.where(tapered, -a / np.where(tapered, b, 1.0), np.inf)
    x0 = np.clip(np.where(tapered, pole.real, 0.0), 0.0, 1.0)
    d0 = np.where(tapered, np.abs(pole - x0), np.inf)
    need = d0 < 1.0
    levels = int(np.ceil(np.log2(1.0 / d0[need].min()))) + 1 if np.any(need) else 0
    levels = min(levels, _MAX_LEVELS)
    steps = np.where(need, d0, 0.0)[:, :, None] * 2.0 ** np.arange(levels)  # (ne, 3, levels)
    cuts = np.concatenate([x0[:, :, None] - steps, x0[:, :, None] + steps], axis=2).reshape(a.shape[0], -1)
    cuts = np.sort(np.concatenate([np.zeros((a.shape[0], 1)), np.clip(cuts, 0.0, 1.0), np.ones((a.shape[0], 1))], 1))
    h = np.diff(cuts, axis=1)  # piece lengths (zero for repeated cuts: no contribution)
    xi = (cuts[:, :-1, None] + h[:, :, None] * _XF).reshape(a.shape[0], -1)
    w = (h[:, :, None] * _WF).reshape(a.shape[0], -1)
    return xi, w


def _exact_stiffness(
    L: Array, E: Array, G: Array, kappa: Array, shear: Array, dol: Array, dil: Array, dor: Array, dir_: Array
) -> Array:
    """Exact static bending + shear stiffness of the tapered Timoshenko beam, (ne, 4, 4), standard plane.

    Flexibility method, standard plane ``[w1, beta1, w2, beta2]`` (``beta`` the section rotation,
    ``w' = beta + gamma``; forces ``[V1, M1, V2, M2]`` conjugate, i.e. ``M`` positive in the sense of
    ``beta``). Node 1 clamped, node 2 loaded by ``V`` and ``M``: equilibrium of the part beyond ``z``
    gives the shear force ``Q = kappa G A gamma = V`` and the bending moment
    ``EI beta' = M + V (L - z)``; Castigliano on the complementary energy
    ``1/2 int (M + V (L - z))^2 / EI + V^2 / (kappa G A) dz`` gives ``[w2, beta2] = F [V, M]`` with

        F = [[int (L - z)^2 / EI dz + int 1 / (kappa G A) dz,  int (L - z) / EI dz],
             [int (L - z) / EI dz,                              int 1 / EI dz      ]]

    (no shear term with shear off), and ``K22 = F^-1``. Free-body equilibrium (virtual work of a rigid
    motion ``w = w0 + b z``, ``beta = b``): ``[V1, M1] = R [V2, M2]``, ``R = [[-1, 0], [-L, -1]]``, and
    the deformation at node 2 relative to the rigid motion of node 1 is ``q2 + R^T q1``, so
    ``K = T^T K22 T``, ``T = [R^T, I]``, i.e. ``[[R K22 R^T, R K22], [K22 R^T, K22]]``.

    Evaluated through centred moments, without cancellation: with ``g = 1 / EI``, ``xi = z / L``,
    ``G0 = int g dxi``, the elastic centre ``a = int xi g dxi / G0``,
    ``Vr = int (xi - a)^2 g dxi``, ``H = int 1 / (kappa G A) dxi`` and ``c = 1 / (L^2 Vr + H)``
    (the shear force per unit relative rotation of the chord), ``det F = L^2 G0 / c`` and

        K = [[ c/L,      a c,                     -c/L,      (1-a) c                   ],
             [ a c,      L a^2 c + 1/(L G0),      -a c,      L a (1-a) c - 1/(L G0)    ],
             [-c/L,     -a c,                      c/L,     -(1-a) c                   ],
             [ (1-a) c,  L a (1-a) c - 1/(L G0),  -(1-a) c,  L (1-a)^2 c + 1/(L G0)    ]].

    A uniform element gives ``a = 1/2``, ``Vr = 1 / (12 EI)``, ``c = 12 EI / ((1 + Phi) L^2)``: the
    closed form :func:`rotorcheck.fe.elements._plane_stiffness`.
    """
    xi, w = _flexibility_points(0.5 * dol, 0.5 * dor, 0.5 * dil, 0.5 * dir_)
    ro = 0.5 * (dol[:, None] + (dor - dol)[:, None] * xi)
    rin = 0.5 * (dil[:, None] + (dir_ - dil)[:, None] * xi)
    g = w / (E[:, None] * 0.25 * np.pi * (ro**4 - rin**4))  # weights times 1 / EI
    g0 = g.sum(axis=1)
    a = (g * xi).sum(axis=1) / g0
    vr = (g * (xi - a[:, None]) ** 2).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = (w / (np.pi * (ro**2 - rin**2))).sum(axis=1) / (kappa * G)
    h = np.where(shear, h, 0.0)
    c = 1.0 / (L**2 * vr + h)
    r = 1.0 / (L * g0)
    b = 1.0 - a
    k = np.empty((L.size, 4, 4))
    k[:, 0] = np.stack([c / L, a * c, -c / L, b * c], axis=1)
    k[:, 1] = np.stack([a * c, L * a**2 * c + r, -a * c, L * a * b * c - r], axis=1)
    k[:, 2] = -k[:, 0]
    k[:, 3] = np.stack([b * c, L * a * b * c - r, -b * c, L * b**2 * c + r], axis=1)
    return k


def _integral(weight: Array, a: Array, b: Array) -> Array:
    """int weight(z) a^T b dz over each element: weight (ne, nq) already times dz; a, b (ne, nq, 4)."""
    return np.einsum("eq,eqi,eqj->eij", weight, a, b)


def _torque_matrix(L: Array, torque: Array) -> Array:
    """Torque matrix T int (psi d(theta)' - theta d(psi)') dz, Euler-Bernoulli N_b, (ne, 8, 8)."""
    _, nb, _, dnb = _shape_functions(L, np.zeros_like(L))
    a = _integral(torque[:, None] * L[:, None] * _WXI, nb, dnb)  # a_ij = T int N_i N_j' dz
    # psi = N_b q_x, theta = -N_b S q_y: rows d(theta) get -S (int N_b'^T N_b) q_x, rows d(psi) (int N_b'^T N_b) S q_y:
    # the placement of the gyroscopic matrix from its plane matrix
    return _gyro_from_rotary(np.swapaxes(a, 1, 2))


def shaft_matrices(
    length: ArrayLike,
    youngs_modulus: ArrayLike,
    shear_modulus: ArrayLike,
    density: ArrayLike,
    outer_left: ArrayLike,
    inner_left: ArrayLike,
    outer_right: ArrayLike,
    inner_right: ArrayLike,
    kappa: ArrayLike,
    *,
    shear: bool | ArrayLike = True,
    rotary_inertia: bool | ArrayLike = True,
    gyroscopic: bool | ArrayLike = True,
    axial_force: ArrayLike = 0.0,
    torque: ArrayLike = 0.0,
    taper: str = "exact",
) -> ShaftMatrices:
    """Matrices of ne tapered hollow Timoshenko shaft elements (vectorised).

    Parameters
    ----------
    length : element lengths L (m).
    youngs_modulus, shear_modulus : E and G (Pa).
    density : rho (kg/m^3).
    outer_left, inner_left, outer_right, inner_right : diameters at node 1 and node 2 (m); the radii
        vary linearly in between.
    kappa : shear coefficient, one per element (e.g. :func:`shear_coefficient_by` of the mean
        diameters); unused with ``shear`` off.
    shear : shear deformation; off: ``Phi = 0`` (Euler-Bernoulli shape functions and stiffness).
    rotary_inertia : rotary inertia ``int rho I N_b^T N_b dz`` in the mass matrix.
    gyroscopic : gyroscopic matrix, from ``int rho (2 I) N_b^T N_b dz`` as
        ``elements._gyro_from_rotary``; controlled by this switch alone, independent of
        ``rotary_inertia`` (as ROSS does); zero when off.
    axial_force : P (N), tension positive: geometric stiffness ``int P N_w'^T N_w' dz``
        (tension stiffens, compression softens; the Timoshenko ``N_w`` as ROSS).
    torque : T (N m), the twisting moment carried by the element (see Notes for the sign).
    taper : formulation of ``stiffness`` (bending + shear), one for all elements: ``"exact"``
        (default) the exact static stiffness of the tapered Timoshenko (shear off:
        Euler-Bernoulli) beam, by the flexibility method (:func:`_exact_stiffness`);
        ``"greenhill"`` the stiffness of the shape functions with the mid-section ``Phi``
        (Greenhill et al. 1985; ROSS's, to round-off). Both are the same for uniform elements
        (``"exact"`` uses the flexibility only where a diameter differs between the nodes). Mass,
        gyroscopic, axial-force and torque matrices are the consistent ones of the mid-section
        ``Phi`` shape functions in both. Raises ``ValueError`` for another value.

    Every argument but ``taper`` is an array of shape (ne,) or broadcastable to it (switches too).

    Returns
    -------
    ShaftMatrices
        Each (ne, 8, 8).

    Notes
    -----
    Torque model: the axial (fixed-direction) torque of ROSS 2.3.0 (``ShaftElement.K()``, term
    ``Ktq``). Its matrix is the virtual work ``T int (psi d(theta)' - theta d(psi)') dz`` of the
    twisting moment ``T n`` (``n = e_z + psi e_x - theta e_y``, the section normal) in the moment
    equilibrium ``M' + e_z x Q = 0``, with the Euler-Bernoulli (``Phi = 0``) rotation shape functions
    ``N_b = N_w'`` whatever ``shear`` is (ROSS's choice, kept so that results agree; with the
    Timoshenko ``N_b`` the matrix would differ by O(Phi)). It depends only on ``T / L`` and is NOT
    symmetric: the theta-psi block of each node is skew (``-+T/2``); on a chain of elements these cancel
    at interior nodes and remain at the two end nodes, where they make the natural boundary condition
    "no lateral component of the total end moment", i.e. an applied end torque of fixed direction
    (non-conservative). ``T`` is the twisting moment of the section: the moment about +z exerted on
    the part ``z' < z`` by the part ``z' > z``. Critical (static) torques of a uniform Euler-Bernoulli
    shaft with this model, all converging as O(h^4): pinned-pinned ``2 pi E I / L`` (Greenhill 1883),
    clamped-clamped ``2 x1 E I / L = 8.9868 E I / L`` (``tan x1 = x1``); a cantilever has none (no
    divergence under an axial torque; Ziegler, Principles of Structural Stability, 1968).
    """
    L, E, G, rho, dol, dil, dor, dir_, kap, sh, ri, gy, P, T = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(a, dtype=float)) for a in (length, youngs_modulus, shear_modulus, density)),
        *(np.atleast_1d(np.asarray(a, dtype=float)) for a in (outer_left, inner_left, outer_right, inner_right)),
        np.atleast_1d(np.asarray(kappa, dtype=float)),
        *(np.atleast_1d(np.asarray(a, dtype=bool)) for a in (shear, rotary_inertia, gyroscopic)),
        np.atleast_1d(np.asarray(axial_force, dtype=float)),
        np.atleast_1d(np.asarray(torque, dtype=float)),
    )
    if taper not in TAPER_FORMULATIONS:
        raise ValueError(f"unknown taper formulation {taper!r}: use 'exact' or 'greenhill'")
    if L.ndim != 1:
        raise ValueError(f"element arguments must broadcast to shape (ne,), got {L.shape}")
    if not (np.all(L > 0) and np.all(dil >= 0) and np.all(dir_ >= 0) and np.all(dol > dil) and np.all(dor > dir_)):
        raise ValueError("need length > 0 and outer > inner >= 0 diameters at both ends")
    if np.any(sh & ~(kap > 0)):
        raise ValueError("kappa must be positive for the elements with shear on")

    # section at the Gauss points and at mid-length (mean diameters)
    ro = 0.5 * (dol[:, None] + (dor - dol)[:, None] * _XI)
    rin = 0.5 * (dil[:, None] + (dir_ - dil)[:, None] * _XI)
    area = np.pi * (ro**2 - rin**2)
    inertia = 0.25 * np.pi * (ro**4 - rin**4)
    dm, dim = 0.5 * (dol + dor), 0.5 * (dil + dir_)
    area_mid = 0.25 * np.pi * (dm**2 - dim**2)
    inertia_mid = np.pi / 64.0 * (dm**4 - dim**4)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi_on = 12.0 * E * inertia_mid / (kap * G * area_mid * L**2)
    phi = np.where(sh, phi_on, 0.0)

    nw, nb, dnw, dnb = _shape_functions(L, phi)
    dz = L[:, None] * _WXI  # quadrature weights times dz, (ne, nq)

    mt = _integral(rho[:, None] * area * dz, nw, nw)
    rot = _integral(rho[:, None] * inertia * dz, nb, nb)
    mp = mt + np.where(ri, 1.0, 0.0)[:, None, None] * rot
    gamma = dnw - nb  # shear strain per DOF (constant along the element)
    kga = np.where(sh, kap * G, 0.0)[:, None] * area
    kp = _integral(E[:, None] * inertia * dz, dnb, dnb) + _integral(kga * dz, gamma, gamma)
    if taper == "exact":
        # tapered elements: the exact stiffness (uniform ones get the closed forms below)
        t = np.flatnonzero((dol != dor) | (dil != dir_))
        if t.size:
            kp[t] = _exact_stiffness(L[t], E[t], G[t], kap[t], sh[t], dol[t], dil[t], dor[t], dir_[t])
    u = np.flatnonzero((dol == dor) & (dil == dir_))
    if u.size:  # uniform elements: the closed forms (Friswell eq. 5.50 and the consistent masses),
        # evaluated as rotorcheck always has, so uniform rotors keep their numbers bit for bit
        area_u = np.pi / 4.0 * (dol[u] ** 2 - dil[u] ** 2)
        i_u = np.pi / 64.0 * (dol[u] ** 4 - dil[u] ** 4)
        ei_u = E[u] * i_u
        with np.errstate(divide="ignore", invalid="ignore"):
            phi_u = np.where(sh[u], 12.0 * ei_u / (kap[u] * G[u] * area_u * L[u] ** 2), 0.0)
        rot[u] = _plane_rotary_mass(L[u], rho[u] * i_u, phi_u)
        mt[u] = _plane_translational_mass(L[u], rho[u] * area_u, phi_u)
        mp[u] = mt[u] + np.where(ri[u], 1.0, 0.0)[:, None, None] * rot[u]
        kp[u] = _plane_stiffness(L[u], ei_u, phi_u)
    pp = _integral(P[:, None] * dz, dnw, dnw)
    # exactly symmetric (quadrature sums differ from their transposes in the last bit; eigen- and
    # modal solvers downstream take symmetry as exact)
    mt, rot, mp, kp, pp = (0.5 * (a + np.swapaxes(a, 1, 2)) for a in (mt, rot, mp, kp, pp))

    return ShaftMatrices(
        mass=_planes_to_8(mp, mp),
        gyroscopic=np.where(gy, 1.0, 0.0)[:, None, None] * _gyro_from_rotary(2.0 * rot),
        stiffness=_planes_to_8(kp, kp),
        axial_force=_planes_to_8(pp, pp),
        torque=_torque_matrix(L, T),
    )


__all__ = [
    "ShaftMatrices",
    "cowper_shear_coefficient",
    "shaft_matrices",
    "shear_coefficient_by",
]
