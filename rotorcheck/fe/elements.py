"""Finite elements of a rotor: Timoshenko shaft element, rigid disc, bearing, station spring.

All matrices use the lateral DOF order of Friswell et al., *Dynamics of Rotating Machines* (2010),
eq. 5.23 of the dissertation: per node ``[u (x), v (y), theta (rotation about x), psi (rotation about
y)]``, i.e. ``[u1 v1 theta1 psi1 u2 v2 theta2 psi2]`` for a shaft element. The spin axis is +z from
node 1 to node 2, spin positive from +x towards +y. Small rotations give the slopes
``du/dz = psi`` and ``dv/dz = -theta``; this is the origin of the sign pattern of eq. 5.22 (``u`` couples
to ``psi`` with ``+6l``, ``v`` to ``theta`` with ``-6l``).

Equation of motion: ``M q'' + (C + Omega G) q' + K q = f`` with ``G`` per unit spin (rad/s) and the
disc gyroscopic block ``G[theta, psi] = +Ip``, ``G[psi, theta] = -Ip`` (angular momentum of a disc
spinning about +z, tilted by theta and psi).

SI units throughout (m, kg, Pa, N/m, N s/m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorcheck.fe.system import BeamElementInfo, section_area, section_second_moment

# local DOF indices of the two bending planes inside an 8x8 element matrix
X_PLANE = np.array([0, 3, 4, 7])  # u1, psi1, u2, psi2   (psi = du/dz)
Y_PLANE = np.array([1, 2, 5, 6])  # v1, theta1, v2, theta2 (theta = -dv/dz)
_S = np.array([1.0, -1.0, 1.0, -1.0])  # y-plane DOF = S * standard [w, beta] DOF


def shear_coefficient(poisson: float, outer_diameter: float, inner_diameter: float = 0.0) -> float:
    """Shear coefficient kappa of a circular (solid or hollow) section, Hutchinson (2001).

    Solid: ``kappa = 6 (1 + nu)^2 / (7 + 12 nu + 4 nu^2)`` (0.9252 for nu = 0.3). Hollow, radii
    ``a`` (outer) and ``b`` (inner):
    ``6 (a^2 + b^2)^2 (1 + nu)^2 / [(a^2 + b^2)^2 (7 + 12 nu + 4 nu^2) + 4 a^2 b^2 (5 + 6 nu + 2 nu^2)]``
    (J. W. Hutchinson, J. Appl. Mech. 68 (2001) 87-92), which reduces to the solid form for b = 0 and
    to (1 + nu) / (2 + nu) for a thin wall; it stays within 7 % above Cowper's (1966) hollow formula.
    """
    nu = float(poisson)
    a2 = (0.5 * outer_diameter) ** 2
    b2 = (0.5 * inner_diameter) ** 2
    s2 = (a2 + b2) ** 2
    num = 6.0 * s2 * (1.0 + nu) ** 2
    den = s2 * (7.0 + 12.0 * nu + 4.0 * nu**2) + 4.0 * a2 * b2 * (5.0 + 6.0 * nu + 2.0 * nu**2)
    return num / den


# --------------------------------------------------------------------------------------------
# plane matrices (standard bending plane [w1, beta1, w2, beta2], beta = dw/dz for Euler-Bernoulli)


def _plane_stiffness(L: np.ndarray, EI: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Timoshenko bending stiffness, (ne, 4, 4): EI / ((1 + Phi) L^3) [...] (Friswell eq. 5.50)."""
    c = (EI / ((1.0 + phi) * L**3))[:, None, None]
    k = np.empty((L.size, 4, 4))
    L2 = L**2
    k[:, 0] = np.stack([12.0 + 0 * L, 6 * L, -12.0 + 0 * L, 6 * L], axis=1)
    k[:, 1] = np.stack([6 * L, (4 + phi) * L2, -6 * L, (2 - phi) * L2], axis=1)
    k[:, 2] = np.stack([-12.0 + 0 * L, -6 * L, 12.0 + 0 * L, -6 * L], axis=1)
    k[:, 3] = np.stack([6 * L, (2 - phi) * L2, -6 * L, (4 + phi) * L2], axis=1)
    return c * k


def _plane_translational_mass(L: np.ndarray, rhoA: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Consistent translational mass of the Timoshenko element, (ne, 4, 4)."""
    p, p2 = phi, phi**2
    m1 = 13 / 35 + 7 * p / 10 + p2 / 3
    m2 = 11 / 210 + 11 * p / 120 + p2 / 24
    m3 = 9 / 70 + 3 * p / 10 + p2 / 6
    m4 = 13 / 420 + 3 * p / 40 + p2 / 24
    m5 = 1 / 105 + p / 60 + p2 / 120
    m6 = 1 / 140 + p / 60 + p2 / 120
    L2 = L**2
    m = np.empty((L.size, 4, 4))
    m[:, 0] = np.stack([m1, m2 * L, m3, -m4 * L], axis=1)
    m[:, 1] = np.stack([m2 * L, m5 * L2, m4 * L, -m6 * L2], axis=1)
    m[:, 2] = np.stack([m3, m4 * L, m1, -m2 * L], axis=1)
    m[:, 3] = np.stack([-m4 * L, -m6 * L2, -m2 * L, m5 * L2], axis=1)
    return (rhoA * L / (1.0 + phi) ** 2)[:, None, None] * m


def _plane_rotary_mass(L: np.ndarray, rhoI: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Consistent rotary inertia matrix rho I int(N_beta^T N_beta) dz, (ne, 4, 4)."""
    p, p2 = phi, phi**2
    r1 = 6 / 5 + 0 * L
    r2 = (1 / 10 - p / 2) * L
    r3 = (2 / 15 + p / 6 + p2 / 3) * L**2
    r4 = (-1 / 30 - p / 6 + p2 / 6) * L**2
    m = np.empty((L.size, 4, 4))
    m[:, 0] = np.stack([r1, r2, -r1, r2], axis=1)
    m[:, 1] = np.stack([r2, r3, -r2, r4], axis=1)
    m[:, 2] = np.stack([-r1, -r2, r1, -r2], axis=1)
    m[:, 3] = np.stack([r2, r4, -r2, r3], axis=1)
    return (rhoI / ((1.0 + phi) ** 2 * L))[:, None, None] * m


def _planes_to_8(px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Place x-plane and (standard-form) y-plane matrices into (ne, 8, 8) with the theta sign flip."""
    out = np.zeros((px.shape[0], 8, 8))
    out[:, X_PLANE[:, None], X_PLANE[None, :]] = px
    out[:, Y_PLANE[:, None], Y_PLANE[None, :]] = _S[:, None] * py * _S[None, :]
    return out


def _gyro_from_rotary(rp: np.ndarray) -> np.ndarray:
    """Gyroscopic (ne, 8, 8) from the polar rotary matrix rp = rho Ip int(N_beta^T N_beta) dz.

    From the kinetic energy term ``Omega int rho Ip theta' psi dz`` with psi = N_beta q_x and
    theta = -N_beta S q_y: ``G[y, x] = -S rp``, ``G[x, y] = rp S`` (skew-symmetric).
    """
    g = np.zeros((rp.shape[0], 8, 8))
    g[:, Y_PLANE[:, None], X_PLANE[None, :]] = -_S[:, None] * rp
    g[:, X_PLANE[:, None], Y_PLANE[None, :]] = rp * _S[None, :]
    return g


# --------------------------------------------------------------------------------------------
# shaft element


@dataclass(frozen=True)
class TimoshenkoBeam:
    """Timoshenko shaft element (shear deformation and rotary inertia), Friswell et al. ch. 5.

    ``Phi = 12 E I / (kappa G A L^2)``; ``kappa`` from :func:`shear_coefficient` (Hutchinson) unless
    given. ``shear=False`` gives Phi = 0 (Euler-Bernoulli stiffness); ``rotary=False`` drops the
    rotary inertia (and the gyroscopic matrix, which is its polar counterpart, Ip = 2 I).
    Lengths m, moduli Pa, density kg/m^3.
    """

    length: float
    youngs_modulus: float
    shear_modulus: float
    density: float
    outer_diameter: float
    inner_diameter: float = 0.0
    poisson: float = 0.3
    kappa: float | None = None
    shear: bool = True
    rotary: bool = True

    @classmethod
    def from_info(cls, info: BeamElementInfo, **kw: object) -> TimoshenkoBeam:
        """The uniform element of a :class:`BeamElementInfo` (modulus factor already applied): a
        tapered element's mid-length section, its shear coefficient and switches (its shape functions'
        Phi; the tapered matrices themselves come from :mod:`rotorcheck.fe.shaft`)."""
        args: dict[str, object] = {
            "kappa": info.kappa, "shear": info.shear, "rotary": info.rotary_inertia, **kw
        }
        return cls(
            length=info.length,
            youngs_modulus=info.youngs_modulus,
            shear_modulus=info.shear_modulus,
            density=info.density,
            outer_diameter=info.mean_outer_diameter,
            inner_diameter=info.mean_inner_diameter,
            poisson=info.poisson,
            **args,  # type: ignore[arg-type]
        )

    @property
    def area(self) -> float:
        """Cross-section area A (m^2)."""
        return section_area(self.outer_diameter, self.inner_diameter)

    @property
    def second_moment(self) -> float:
        """Second moment of area I (m^4); the polar moment is 2 I."""
        return section_second_moment(self.outer_diameter, self.inner_diameter)

    @property
    def shear_coefficient(self) -> float:
        """kappa used in Phi."""
        if self.kappa is not None:
            return self.kappa
        return shear_coefficient(self.poisson, self.outer_diameter, self.inner_diameter)

    @property
    def phi(self) -> float:
        """Shear parameter Phi = 12 E I / (kappa G A L^2) (0 when ``shear`` is off)."""
        if not self.shear:
            return 0.0
        ei = self.youngs_modulus * self.second_moment
        return 12.0 * ei / (self.shear_coefficient * self.shear_modulus * self.area * self.length**2)

    def _arrays(self) -> tuple[np.ndarray, ...]:
        L = np.array([self.length])
        return L, np.array([self.phi])

    def stiffness(self) -> np.ndarray:
        """Stiffness matrix (8, 8), N/m, N/rad, N m/rad."""
        L, phi = self._arrays()
        p = _plane_stiffness(L, np.array([self.youngs_modulus * self.second_moment]), phi)
        return _planes_to_8(p, p)[0]

    def mass(self) -> np.ndarray:
        """Mass matrix (8, 8): translational plus rotary inertia, kg and kg m^2."""
        L, phi = self._arrays()
        p = _plane_translational_mass(L, np.array([self.density * self.area]), phi)
        if self.rotary:
            p = p + _plane_rotary_mass(L, np.array([self.density * self.second_moment]), phi)
        return _planes_to_8(p, p)[0]

    def gyroscopic(self) -> np.ndarray:
        """Gyroscopic matrix per unit spin speed (8, 8), skew-symmetric, kg m^2."""
        L, phi = self._arrays()
        if not self.rotary:
            return np.zeros((8, 8))
        rp = _plane_rotary_mass(L, np.array([2.0 * self.density * self.second_moment]), phi)
        return _gyro_from_rotary(rp)[0]


def beam_matrices(
    length: np.ndarray,
    youngs_modulus: np.ndarray,
    shear_modulus: np.ndarray,
    density: np.ndarray,
    outer_diameter: np.ndarray,
    inner_diameter: np.ndarray,
    kappa: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised Timoshenko matrices for ne elements: (M, G, K), each (ne, 8, 8). SI units."""
    L = np.asarray(length, dtype=float)
    area = np.pi / 4.0 * (outer_diameter**2 - inner_diameter**2)
    I = np.pi / 64.0 * (outer_diameter**4 - inner_diameter**4)
    EI = youngs_modulus * I
    phi = 12.0 * EI / (kappa * shear_modulus * area * L**2)
    kp = _plane_stiffness(L, EI, phi)
    rot = _plane_rotary_mass(L, density * I, phi)
    mp = _plane_translational_mass(L, density * area, phi) + rot
    return _planes_to_8(mp, mp), _gyro_from_rotary(2.0 * rot), _planes_to_8(kp, kp)


def beam_shape_functions(xi: np.ndarray, length: float, phi: float) -> tuple[np.ndarray, np.ndarray]:
    """Timoshenko shape functions at ``xi = z / L`` in [0, 1] for the standard plane [w1 b1 w2 b2].

    Returns ``(N_w, N_beta)``, each (len(xi), 4): displacement and cross-section rotation. The
    element matrices above are ``int rho A N_w^T N_w + rho I N_b^T N_b`` and
    ``int E I N_b'^T N_b' + kappa G A (N_w' - N_b)^T (N_w' - N_b)``.
    """
    x = np.asarray(xi, dtype=float)
    L, p = float(length), float(phi)
    c = 1.0 / (1.0 + p)
    nw = c * np.stack(
        [
            1 - 3 * x**2 + 2 * x**3 + p * (1 - x),
            L * (x - 2 * x**2 + x**3 + p / 2 * (x - x**2)),
            3 * x**2 - 2 * x**3 + p * x,
            L * (-(x**2) + x**3 - p / 2 * (x - x**2)),
        ],
        axis=-1,
    )
    nb = c * np.stack(
        [
            6 / L * (-x + x**2),
            1 - 4 * x + 3 * x**2 + p * (1 - x),
            6 / L * (x - x**2),
            -2 * x + 3 * x**2 + p * x,
        ],
        axis=-1,
    )
    return nw, nb


# --------------------------------------------------------------------------------------------
# point elements (4x4 at one node)


@dataclass(frozen=True)
class RigidDisc:
    """Rigid disc at a node: mass (kg), transverse and polar inertia (kg m^2)."""

    mass: float
    transverse_inertia: float
    polar_inertia: float

    def mass_matrix(self) -> np.ndarray:
        """diag(m, m, Id, Id), (4, 4)."""
        return np.diag([self.mass, self.mass, self.transverse_inertia, self.transverse_inertia])

    def gyroscopic(self) -> np.ndarray:
        """Per unit spin: G[theta, psi] = +Ip, G[psi, theta] = -Ip, (4, 4)."""
        g = np.zeros((4, 4))
        g[2, 3] = self.polar_inertia
        g[3, 2] = -self.polar_inertia
        return g


@dataclass(frozen=True)
class PointSupport:
    """Linear support from a node to ground (bearing or station spring), at one speed.

    ``k``/``c`` are the 2x2 translational blocks [[xx, xy], [yx, yy]] (N/m, N s/m); ``k_rot`` a
    rotational stiffness on theta and psi (N m/rad).
    """

    k: np.ndarray
    c: np.ndarray
    k_rot: float = 0.0

    @classmethod
    def from_coefficients(cls, coef: dict[str, float], k_rot: float = 0.0) -> PointSupport:
        """From a dict with keys kxx, kxy, kyx, kyy, cxx, cxy, cyx, cyy (missing keys are 0)."""
        g = lambda n: float(coef.get(n, 0.0))  # noqa: E731
        return cls(
            k=np.array([[g("kxx"), g("kxy")], [g("kyx"), g("kyy")]]),
            c=np.array([[g("cxx"), g("cxy")], [g("cyx"), g("cyy")]]),
            k_rot=k_rot,
        )

    def stiffness(self) -> np.ndarray:
        """(4, 4) stiffness at the node."""
        out = np.zeros((4, 4))
        out[:2, :2] = self.k
        out[2, 2] = out[3, 3] = self.k_rot
        return out

    def damping(self) -> np.ndarray:
        """(4, 4) damping at the node."""
        out = np.zeros((4, 4))
        out[:2, :2] = self.c
        return out
