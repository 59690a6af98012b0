r"""Stiffness of a cracked shaft element: open crack and breathing crack (Madden 2016, eq. 5.2-5.26).

Model (eq. 5.5, 5.9, 5.20): the fixed-frame stiffness of the cracked rotor is ``K0 - K_c(t)`` with

    K_c(t) = T(phi(t)) K~_c(theta(t)) T(phi(t))^T,

``theta(t) = theta_0 + Omega t`` the crack opening angle (0 = crack facing up, closed; pi = facing
down, fully open; see :mod:`rotorcheck.faults.breathing` for the resolved sign of eq. 5.21),
``phi(t) = up_angle + theta(t)`` the direction of the rotating ``xi`` axis measured from ``+x``
towards ``+y`` (``up_angle = pi/2``: vertical = ``+y``, gravity along ``-y``, by default), ``T`` the
8x8 block-diagonal rotation of eq. 5.26 acting on the (u, v) and (theta, psi) pairs of both nodes.

Rotating reduction. With the bending-plane vectors ``a_xi = [u1, psi1, u2, psi2]`` and
``a_eta = [v1, -theta1, v2, -theta2]`` (both see the same 4x4 beam matrix ``B``; this reproduces the
sign pattern of eq. 5.22), the rotating-frame reduction is ``K~_c = sum_ab R_ab(theta) P_a^T B P_b``,
``R`` the dimensionless 2x2 law of :mod:`~rotorcheck.faults.breathing`. ``(psi, -theta)`` rotates
exactly like ``(u, v)`` under eq. 5.26, so the fixed-frame matrix is the same construction with
``S(t) = T2(phi) R(theta) T2(phi)^T`` (2x2) in place of ``R``.

``F_xi, F_eta`` of eq. 5.25 are the crack's ``compliance_xi/compliance_eta`` or, when it gives
a depth (``depth``, or the older ``depth_ratio``), the strip-method values of :mod:`rotorcheck.faults.compliance`.

``form`` of the reduction matrix:

- ``"euler_bernoulli"`` (default, the dissertation's eq. 5.24): ``B = E/l^3 [...]`` of eq. 5.22 with
  ``I -> I0``, and ``R = f(theta) diag(dI_xi, dI_eta)/I0`` (eq. 5.25).
- ``"timoshenko"``: per plane, the exact change of the Timoshenko element when ``I0 -> I0 - dI``,
  ``B_T(I0) - B_T(I0 - dI)`` (shear parameter re-evaluated; the element of
  :func:`rotorcheck.fe.assembly.element_matrices`, so the same element as the assembly),
  so that a fully open crack equals the healthy Timoshenko element with the second moment reduced
  by ``dI`` in each direction.

The Jun et al. law is a fraction of the healthy element stiffness (``B_EB(I0)`` or ``B_T(I0)``).
A refined config element (several mesh elements) is cracked over all of its mesh elements.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from rotorcheck.config import Crack, RigConfig
from rotorcheck.faults.breathing import (
    gasch_fourier,
    gasch_steering,
    jun_fourier,
    jun_reduction,
    mayes_davies_fourier,
    mayes_davies_steering,
)
from rotorcheck.faults.compliance import crack_compliances
from rotorcheck.faults.kinds.open_crack import OpenCrackModel
from rotorcheck.fe.assembly import build_system, element_matrices
from rotorcheck.fe.elements import X_PLANE
from rotorcheck.fe.system import BeamElementInfo, MechanicalSystem

__all__ = [
    "UP_ANGLE",
    "CrackStiffness",
    "crack_stiffness",
    "delta_i_ratio",
    "eb_plane_stiffness",
    "open_crack_system",
    "plane_selectors",
    "rotating_reduction",
    "timoshenko_plane_stiffness",
]

UP_ANGLE = 0.5 * np.pi  # direction of "up" from +x towards +y (rad): vertical = +y by default
Form = Literal["euler_bernoulli", "timoshenko"]

# bending-plane vectors in the element DOF order [u1, v1, th1, psi1, u2, v2, th2, psi2] (eq. 5.23)
_PLANE_IDX = (np.array([0, 3, 4, 7]), np.array([1, 2, 5, 6]))
_PLANE_SGN = (np.array([1.0, 1.0, 1.0, 1.0]), np.array([1.0, -1.0, 1.0, -1.0]))


# --------------------------------------------------------------------------------------------
# eq. 5.25 and beam matrices


def delta_i_ratio(compliance: float, radius: float, section_length: float, poisson: float) -> float:
    """Eq. 5.25: ``dI/I0 = x/(1 + x)``, ``x = (R/l)(1 - nu^2) F``; R, l in m, F dimensionless."""
    x = radius / section_length * (1.0 - poisson**2) * compliance
    return x / (1.0 + x)


def eb_plane_stiffness(ei: float, length: float) -> np.ndarray:
    """Euler-Bernoulli bending stiffness (N/m units) on ``[w1, w1', w2, w2']``; EI in N m^2, l in m."""
    l = length
    return (ei / l**3) * np.array(
        [
            [12.0, 6 * l, -12.0, 6 * l],
            [6 * l, 4 * l**2, -6 * l, 2 * l**2],
            [-12.0, -6 * l, 12.0, -6 * l],
            [6 * l, 2 * l**2, -6 * l, 4 * l**2],
        ]
    )


def timoshenko_plane_stiffness(ei: float, length: float, kappa_ga: float) -> np.ndarray:
    """Timoshenko bending stiffness on ``[w1, w1', w2, w2']``: shear parameter
    ``Phi = 12 EI / (kappa G A l^2)``; EI in N m^2, l in m, kappa G A in N.
    """
    l = length
    phi = 12.0 * ei / (kappa_ga * l**2)
    return (ei / ((1.0 + phi) * l**3)) * np.array(
        [
            [12.0, 6 * l, -12.0, 6 * l],
            [6 * l, (4 + phi) * l**2, -6 * l, (2 - phi) * l**2],
            [-12.0, -6 * l, 12.0, -6 * l],
            [6 * l, (2 - phi) * l**2, -6 * l, (4 + phi) * l**2],
        ]
    )


def plane_selectors() -> tuple[np.ndarray, np.ndarray]:
    """Signed 4x8 selectors ``P_xi, P_eta``: ``a_xi = P_xi q_e``, ``a_eta = P_eta q_e``."""
    out = []
    for idx, sgn in zip(_PLANE_IDX, _PLANE_SGN):
        p = np.zeros((4, 8))
        p[np.arange(4), idx] = sgn
        out.append(p)
    return out[0], out[1]


# --------------------------------------------------------------------------------------------
# rotation algebra: T2(phi) X T2(phi)^T = sum_{r in -2,0,2} e^{j r phi} Q_r(X)

_J = np.array([[0.0, -1.0], [1.0, 0.0]])
_PP = 0.5 * (np.eye(2) - 1j * _J)  # T2(phi) = e^{j phi} _PP + e^{-j phi} _PM
_PM = 0.5 * (np.eye(2) + 1j * _J)


def _q_r(x: np.ndarray) -> dict[int, np.ndarray]:
    return {
        2: _PP @ x @ _PP.T,
        0: _PP @ x @ _PM.T + _PM @ x @ _PP.T,
        -2: _PM @ x @ _PM.T,
    }


def _t2(phi: np.ndarray) -> np.ndarray:
    """Rotations ``[[c, -s], [s, c]]`` (..., 2, 2) by ``phi`` (rad), filled in place (no nested stacks:
    the time-domain references call this once per right-hand side)."""
    c, s = np.cos(phi), np.sin(phi)
    out = np.empty((*np.shape(phi), 2, 2))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    return out


# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Term:
    rotating: Callable[[np.ndarray], np.ndarray]  # theta (N,) -> R (N, 2, 2)
    fourier: dict[int, np.ndarray]  # theta-harmonics m -> R_m (2, 2) complex
    basis: np.ndarray  # (2, 2, m, m): E_ab = sum_el scatter(P_a^T B P_b)


@dataclass(frozen=True)
class CrackStiffness:
    """Fixed-frame stiffness reduction ``K_c`` of a cracked element, on its DOF set ``dofs``.

    Angles in rad: ``rotation`` is ``Omega t``; ``theta0`` the opening angle at ``t = 0``.
    """

    dofs: np.ndarray  # (m,) global DOF indices of the cracked element(s), sorted
    terms: tuple[_Term, ...]
    theta0: float
    up_angle: float
    model: str
    form: str
    delta_xi: float  # dI_xi / I0 (Mayes-Davies, Gasch), nan otherwise
    delta_eta: float
    n_terms: int | None  # Gasch truncation used by harmonics(); None elsewhere

    @property
    def size(self) -> int:
        return int(self.dofs.size)

    def rotating_matrix(self, theta: np.ndarray | float) -> np.ndarray:
        """Rotating-frame reduction ``K~_c(theta)`` on ``dofs``, shape (N, m, m) (N/m, N, N m)."""
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        out = np.zeros((th.size, self.size, self.size))
        for term in self.terms:
            out += np.einsum("tab,abij->tij", term.rotating(th), term.basis)
        return out

    def at_rotation(self, rotation: np.ndarray | float) -> np.ndarray:
        """Fixed-frame ``K_c`` at shaft rotation ``Omega t`` (rad), shape (N, m, m)."""
        rot = np.atleast_1d(np.asarray(rotation, dtype=float))
        theta = self.theta0 + rot
        t2 = _t2(self.up_angle + theta)
        out = np.zeros((rot.size, self.size, self.size))
        for term in self.terms:
            s = t2 @ term.rotating(theta) @ np.swapaxes(t2, -1, -2)
            out += np.einsum("tab,abij->tij", s, term.basis)
        return out

    def harmonics(self) -> tuple[np.ndarray, np.ndarray]:
        """Fourier coefficients in time: ``K_c(t) = sum_p K_p exp(j p Omega t)``.

        Returns ``(orders (P,), K_p (P, m, m) complex)``, ``K_{-p} = conj(K_p)``. Exact for
        Mayes-Davies (|p| <= 3) and Jun; the Gasch series is truncated at ``n_terms`` (|p| <= n+2).
        """
        acc: dict[int, np.ndarray] = {}
        for term in self.terms:
            for m, rm in term.fourier.items():
                if not np.any(rm):
                    continue
                for r, qr in _q_r(rm).items():
                    p = m + r
                    phase = np.exp(1j * p * self.theta0 + 1j * r * self.up_angle)
                    kp = phase * np.einsum("ab,abij->ij", qr, term.basis)
                    acc[p] = acc.get(p, 0.0) + kp
        orders = np.array(sorted(acc), dtype=int)
        kp = np.array([acc[int(p)] for p in orders]) if orders.size else np.zeros((0, 0, 0))
        tol = 1e-14 * max(float(np.max(np.abs(kp))), 1.0) if kp.size else 0.0
        keep = np.array([np.max(np.abs(k)) > tol for k in kp], dtype=bool)
        return orders[keep], kp[keep]

    def mean(self) -> np.ndarray:
        """Time average of ``K_c(t)`` over a revolution (the p = 0 coefficient), (m, m) real."""
        orders, kp = self.harmonics()
        i = np.flatnonzero(orders == 0)
        return kp[i[0]].real.copy() if i.size else np.zeros((self.size, self.size))

    def scatter(self, local: np.ndarray, n_dof: int) -> np.ndarray:
        """Embed (..., m, m) local matrices into (..., n, n) global ones."""
        out = np.zeros((*local.shape[:-2], n_dof, n_dof), dtype=local.dtype)
        out[..., self.dofs[:, None], self.dofs[None, :]] = local
        return out


def _fft_coefficients(fun: Callable[[np.ndarray], np.ndarray], n_terms: int) -> dict[int, complex]:
    """Fourier coefficients ``c_m``, |m| <= n_terms, of a 2 pi periodic function (FFT)."""
    n = max(64, 4 * (n_terms + 1))
    th = 2.0 * np.pi * np.arange(n) / n
    c = np.fft.fft(_steer(fun, th)) / n
    return {m: complex(c[m % n]) for m in range(-n_terms, n_terms + 1)}


def _steer(fun: Callable[[np.ndarray], np.ndarray], th: np.ndarray) -> np.ndarray:
    """``fun(th)`` as floats of ``th``'s shape (broadcast only when a law returns a constant)."""
    val = np.asarray(fun(th), dtype=float)
    return val if val.shape == th.shape else np.broadcast_to(val, th.shape)


def _steered(fun: Callable[[np.ndarray], np.ndarray], mat: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``theta (N,) -> fun(theta)[:, None, None] * mat`` (N, 2, 2), ``mat`` bound now."""

    def rotating(th: np.ndarray) -> np.ndarray:
        return _steer(fun, th)[:, None, None] * mat

    return rotating


def _elements_of(system: MechanicalSystem, element: int) -> list[BeamElementInfo]:
    els = [e for e in system.elements if e.segment == element]
    if not els:
        raise ValueError(f"no mesh element belongs to config element {element}")
    return els


def crack_stiffness(
    system: MechanicalSystem,
    crack: Crack,
    form: Form = "euler_bernoulli",
    n_terms: int = 25,
    up_angle: float = UP_ANGLE,
    steering: Callable[[np.ndarray], np.ndarray] | None = None,
) -> CrackStiffness:
    """Build the crack's stiffness reduction for ``system`` (see the module docstring).

    ``crack.angle`` is the opening angle theta at t = 0 (rad; 0 = crack up and closed).
    ``n_terms``: Gasch Fourier truncation (harmonics of the steering function) used by
    :meth:`CrackStiffness.harmonics`; ``at_rotation`` always uses the exact square wave.
    ``steering``: a custom steering law ``f(theta)`` (0 closed .. 1 open) replacing the model's
    for the ``mayes_davies``/``gasch`` reductions (eq. 5.25); its Fourier coefficients up to
    ``n_terms`` come from an FFT (exact for trigonometric polynomials of degree <= n_terms).
    """
    if form not in ("euler_bernoulli", "timoshenko"):
        raise ValueError(f"unknown form {form!r}")
    els = _elements_of(system, crack.element)
    nodes = sorted({e.node_i for e in els} | {e.node_j for e in els})
    dofs = np.array([4 * nd + k for nd in nodes for k in range(4)])
    pos = {int(d): i for i, d in enumerate(dofs)}
    m = dofs.size
    psel = plane_selectors()

    def basis_for(bmats: list[np.ndarray]) -> np.ndarray:
        out = np.zeros((2, 2, m, m))
        for e, b in zip(els, bmats):
            loc = np.array([pos[int(d)] for d in e.dofs])
            for a in range(2):
                for c in range(2):
                    out[a, c][np.ix_(loc, loc)] += psel[a].T @ b @ psel[c]
        return out

    def eb(scale: float = 1.0) -> list[np.ndarray]:
        return [eb_plane_stiffness(scale * e.youngs_modulus * e.second_moment, e.length) for e in els]

    def timo(scale: float = 1.0) -> list[np.ndarray]:
        # the assembly's own element (same shear coefficient); x-plane block = standard plane
        k = element_matrices(tuple(replace(e, youngs_modulus=scale * e.youngs_modulus) for e in els)).stiffness
        return [k[i][np.ix_(X_PLANE, X_PLANE)] for i in range(len(els))]

    ident = {0: np.eye(2, dtype=complex)}
    terms: list[_Term] = []
    d_xi = d_eta = float("nan")
    if crack.model == "open":
        assert crack.modulus_factor is not None
        loss = 1.0 - crack.modulus_factor
        if form == "euler_bernoulli":
            bm = [loss * b for b in eb()]
        else:
            bm = [b0 - b1 for b0, b1 in zip(timo(), timo(crack.modulus_factor))]
        const = lambda th: np.broadcast_to(np.eye(2), (np.size(th), 2, 2))  # noqa: E731
        terms.append(_Term(const, ident, basis_for(bm)))
        d_xi = d_eta = loss
    elif crack.model in ("mayes_davies", "gasch"):
        e0 = els[0]
        nu = crack.poisson if crack.poisson is not None else e0.poisson
        radius = 0.5 * e0.outer_diameter
        if crack.compliance_xi is None and e0.inner_diameter > 0:
            raise ValueError(f"element {crack.element} is hollow: a depth needs a solid shaft (strip method)")
        f_xi, f_eta = crack_compliances(crack)
        assert crack.section_length is not None
        d_xi = delta_i_ratio(f_xi, radius, crack.section_length, nu)
        d_eta = delta_i_ratio(f_eta, radius, crack.section_length, nu)
        if steering is not None:
            steer: Callable[[np.ndarray], np.ndarray] = steering
            coef = _fft_coefficients(steering, n_terms)
        elif crack.model == "mayes_davies":
            steer = mayes_davies_steering
            coef = mayes_davies_fourier()
        else:
            steer = gasch_steering
            coef = gasch_fourier(n_terms)
        if form == "euler_bernoulli":
            dmat = np.diag([d_xi, d_eta])
            terms.append(
                _Term(
                    _steered(steer, dmat),
                    {k: c * dmat for k, c in coef.items()},
                    basis_for(eb()),
                )
            )
        else:
            for i, d in enumerate((d_xi, d_eta)):
                proj = np.zeros((2, 2))
                proj[i, i] = 1.0
                bm = [b0 - b1 for b0, b1 in zip(timo(), timo(1.0 - d))]
                terms.append(
                    _Term(
                        _steered(steer, proj),
                        {k: c * proj for k, c in coef.items()},
                        basis_for(bm),
                    )
                )
    elif crack.model == "jun":
        bx, be, aa = list(crack.jun_b_xi), list(crack.jun_b_eta), list(crack.jun_a)
        terms.append(
            _Term(
                lambda th: jun_reduction(th, bx, be, aa),
                jun_fourier(bx, be, aa),
                basis_for(eb() if form == "euler_bernoulli" else timo()),
            )
        )
    else:  # pragma: no cover - config validation forbids it
        raise ValueError(f"unknown crack model {crack.model!r}")
    return CrackStiffness(
        dofs=dofs,
        terms=tuple(terms),
        theta0=float(crack.angle),
        up_angle=float(up_angle),
        model=crack.model,
        form=form,
        delta_xi=float(d_xi),
        delta_eta=float(d_eta),
        n_terms=n_terms if crack.model == "gasch" else None,
    )


def rotating_reduction(crack: Crack, theta: np.ndarray, poisson: float, radius: float) -> np.ndarray:
    """Dimensionless rotating reduction ``R(theta)`` (N, 2, 2) of a config crack (Fig. 56).

    ``k_xi/k0 = 1 - R[:, 0, 0]``, ``k_eta/k0 = 1 - R[:, 1, 1]``; ``poisson`` and ``radius`` (m)
    are used when the crack does not set them (eq. 5.25).
    """
    th = np.atleast_1d(np.asarray(theta, dtype=float))
    if crack.model == "jun":
        return jun_reduction(th, crack.jun_b_xi, crack.jun_b_eta, crack.jun_a)
    if crack.model == "open":
        assert crack.modulus_factor is not None
        return np.broadcast_to((1.0 - crack.modulus_factor) * np.eye(2), (th.size, 2, 2)).copy()
    nu = crack.poisson if crack.poisson is not None else poisson
    f_xi, f_eta = crack_compliances(crack)
    assert crack.section_length is not None
    d = np.diag(
        [
            delta_i_ratio(f_xi, radius, crack.section_length, nu),
            delta_i_ratio(f_eta, radius, crack.section_length, nu),
        ]
    )
    f = mayes_davies_steering(th) if crack.model == "mayes_davies" else gasch_steering(th)
    return f[:, None, None] * d


def open_crack_system(config: RigConfig, crack: Crack | None = None) -> MechanicalSystem:
    """The rig with the cracked element's Young's modulus scaled by ``crack.modulus_factor``.

    Chapter IV open crack (element 4 at 46 % of E), through
    ``build_system(config, modulus_factors={element: factor})`` (on top of the config element's
    own factor). ``crack`` defaults to the config's first crack fault with a ``modulus_factor``.
    """
    if crack is None:
        cracks = [f for f in config.faults.values() if isinstance(f, Crack) and f.modulus_factor is not None]
        if not cracks:
            raise ValueError("the config has no crack fault with a modulus_factor")
        crack = cracks[0]
    if crack.modulus_factor is None:
        raise ValueError("the crack has no modulus_factor (open-crack model)")
    return build_system(config, modulus_factors=OpenCrackModel().built_in(crack).modulus_factors)
