"""The linear second-order model every other part of rotorcheck consumes.

    M q'' + (C(Omega) + Omega G) q' + K(Omega) q = f(t)

SI units; Omega in rad/s. Rotor models carry four lateral DOF per node, ordered as in Friswell et
al. (eq. 5.23): ``[u (x), v (y), theta (rotation about x), psi (rotation about y)]``; node ``s``
(1-based station index after refinement maps, see :attr:`MechanicalSystem.station_node`) owns DOF
``4*(node) .. 4*(node)+3``. Lumped models carry one DOF per mass.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck.config import TaperedSection

RPM_TO_RAD_S = 2.0 * np.pi / 60.0
DIRECTION_OFFSET = {"x": 0, "y": 1, "theta": 2, "psi": 3}


def section_area(outer_diameter: float, inner_diameter: float = 0.0) -> float:
    """Area of a (hollow) circular section (m^2)."""
    return np.pi / 4.0 * (outer_diameter**2 - inner_diameter**2)


def section_second_moment(outer_diameter: float, inner_diameter: float = 0.0) -> float:
    """Second moment of area I of a (hollow) circular section (m^4); the polar moment is 2 I."""
    return np.pi / 64.0 * (outer_diameter**4 - inner_diameter**4)


@dataclass(frozen=True)
class BeamElementInfo(TaperedSection):
    """Geometry and material of one finite beam element (after refinement).

    ``segment`` is the 1-based config element (between config stations ``segment`` and
    ``segment + 1``) that this element belongs to.
    """

    index: int  # 0-based element index in the mesh
    segment: int  # 1-based config element it came from
    node_i: int  # 0-based mesh node
    node_j: int
    length: float  # m
    youngs_modulus: float  # Pa (after modulus_factor)
    shear_modulus: float  # Pa
    density: float  # kg/m^3
    outer_diameter: float  # m (at node_i)
    inner_diameter: float  # m (at node_i)
    poisson: float
    outer_diameter_right: float | None = None  # m at node_j (a taper); None: as at node_i
    inner_diameter_right: float | None = None
    kappa: float | None = None  # shear coefficient; None: Hutchinson's of the section
    shear: bool = True  # shear deformation (False: Euler-Bernoulli stiffness)
    rotary_inertia: bool = True
    gyroscopic: bool = True
    axial_force: float = 0.0  # N, tension positive
    torque: float = 0.0  # N m
    layer: int = 0  # 0: the shaft; 1, 2, ...: concentric layers on the same nodes (sleeves, hubs)
    taper: str = "exact"  # stiffness of a tapered element: "exact" | "greenhill" (rotorcheck.fe.shaft)

    @property
    def mean_outer_diameter(self) -> float:
        """Outer diameter of the mid-length section (m)."""
        return 0.5 * (self.outer_diameter + self.outer_right)

    @property
    def mean_inner_diameter(self) -> float:
        """Inner diameter of the mid-length section (m)."""
        return 0.5 * (self.inner_diameter + self.inner_right)

    @property
    def area(self) -> float:
        """Cross-section area of the mid-length section (m^2)."""
        return section_area(self.mean_outer_diameter, self.mean_inner_diameter)

    @property
    def second_moment(self) -> float:
        """Second moment of area I of the mid-length section (m^4)."""
        return section_second_moment(self.mean_outer_diameter, self.mean_inner_diameter)

    @property
    def dofs(self) -> np.ndarray:
        """The element's 8 global DOF indices (u1, v1, theta1, psi1, u2, v2, theta2, psi2)."""
        return np.r_[4 * self.node_i : 4 * self.node_i + 4, 4 * self.node_j : 4 * self.node_j + 4]


def rotor_dof(station_node: Sequence[int], n_nodes: int, n_support: int, station: int, direction: str) -> int:
    """Global DOF of a rotor's shaft ``station`` (1-based; 4 DOF per mesh node: u, v, theta, psi) or of a
    support node (numbered after the last station; 2 DOF, x and y, after every shaft DOF)."""
    n = len(station_node)
    if n < station <= n + n_support and direction in ("x", "y"):
        return 4 * n_nodes + 2 * (station - n - 1) + DIRECTION_OFFSET[direction]
    if not 1 <= station <= n:
        raise KeyError(f"station {station} out of range 1..{n}")
    return 4 * station_node[station - 1] + DIRECTION_OFFSET[direction]


def rotor_plane_dofs(n_nodes: int, n_support: int) -> tuple[np.ndarray, np.ndarray]:
    """DOF indices of the x plane (u, psi) and the y plane (v, theta) of a rotor of ``n_nodes`` mesh nodes
    and ``n_support`` support nodes (x and y each, after the shaft's DOF)."""
    base = 4 * np.arange(n_nodes)
    sup = 4 * n_nodes + 2 * np.arange(n_support)
    return np.sort(np.r_[base, base + 3, sup]), np.sort(np.r_[base + 1, base + 2, sup + 1])


@dataclass(frozen=True)
class MechanicalSystem:
    """Assembled matrices of a rig at any speed.

    ``matrices(speed_rpm)`` returns ``(M, C, G, K)`` with C the (modal or Rayleigh) structural
    damping plus bearing damping at that speed, G the gyroscopic matrix per unit spin speed
    (multiply by Omega in rad/s), K the stiffness including bearings at that speed.

    ``matrix_key(speed_rpm)``: speeds with equal keys have equal ``(M, C, G, K)`` (a rotor's bearing
    coefficients at that speed; the speed itself when unknown), so work that depends on the matrices
    only (reduced bases, undamped modes) is done once per key and kept in the per-object
    :attr:`cache` (never shared with a ``dataclasses.replace`` copy).
    """

    kind: str  # "rotor" | "lumped"
    n_dof: int
    labels: tuple[str, ...]  # one per DOF, e.g. "s6.x" or "m1"
    _matrices: Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
    station_node: tuple[int, ...] = ()  # config station (1-based) -> 0-based mesh node
    node_positions: np.ndarray = field(default_factory=lambda: np.zeros(0))  # m, per mesh node
    elements: tuple[BeamElementInfo, ...] = ()  # the shaft's own elements, one per mesh element
    layers: tuple[BeamElementInfo, ...] = ()  # concentric layers on the same nodes (sleeves, hubs)
    n_support: int = 0  # support (pedestal) nodes after the shaft nodes: 2 DOF each (x, y)
    mass_index: dict[str, int] = field(default_factory=dict)  # lumped: mass name -> DOF
    # (kind, name, station): "bearing" | "disc" | "spring" parts of a rotor, for plots and reports
    features: tuple[tuple[str, str, int], ...] = ()
    _key: Callable[[float], Hashable] | None = None
    cache: dict[Any, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    def matrix_key(self, speed_rpm: float = 0.0) -> Hashable:
        """Equal keys, equal matrices (see the class docstring)."""
        return float(speed_rpm) if self._key is None else self._key(float(speed_rpm))

    def matrices(self, speed_rpm: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(M, C, G, K) at ``speed_rpm``; dense float arrays of shape (n_dof, n_dof)."""
        return self._matrices(float(speed_rpm))

    def dof(self, station: int | None = None, direction: str = "x", mass: str | None = None) -> int:
        """Global DOF index of a port: rotor ``station`` (1-based) and direction, or lumped ``mass``."""
        if self.kind == "lumped":
            if mass is None or mass not in self.mass_index:
                raise KeyError(f"unknown mass {mass!r}")
            return self.mass_index[mass]
        if station is None:
            raise KeyError(f"station {station} out of range 1..{len(self.station_node)}")
        return rotor_dof(self.station_node, self.n_nodes, self.n_support, station, direction)

    def port_dof(self, port: object) -> int:
        """DOF of a config :class:`rotorcheck.config.Port`."""
        return self.dof(
            getattr(port, "station", None), getattr(port, "direction", "x"), getattr(port, "mass", None)
        )

    @property
    def n_nodes(self) -> int:
        """Shaft mesh nodes of a rotor (0 for lumped models); support nodes not counted."""
        return (self.n_dof - 2 * self.n_support) // 4 if self.kind == "rotor" else 0

    @property
    def n_shaft_dof(self) -> int:
        """DOF of the shaft nodes (4 per node); support-node DOF follow them."""
        return 4 * self.n_nodes if self.kind == "rotor" else self.n_dof

    @property
    def station_positions(self) -> np.ndarray:
        """Axial position (m) of each config station (rotor)."""
        return np.asarray(self.node_positions)[list(self.station_node)]

    def plane_dofs(self) -> tuple[np.ndarray, np.ndarray]:
        """DOF indices of the x plane (u, psi) and the y plane (v, theta) of a rotor."""
        return rotor_plane_dofs(self.n_nodes, self.n_support)

    def plane_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A rotor's DOF under a quarter turn about the shaft axis: ``(ix, iy, sign)`` with
        ``ix`` the x-plane DOF (u, psi of each node), ``iy`` their images (v, theta) and ``sign``
        (+1 for u -> v, -1 for psi -> theta: the slopes are du/dz = psi, dv/dz = -theta)."""
        hit = self.cache.get("plane_pairs")
        if hit is None:
            base = 4 * np.arange(self.n_nodes)
            sup = self.n_shaft_dof + 2 * np.arange(self.n_support)
            ix = np.r_[np.stack([base, base + 3], axis=1).reshape(-1), sup]
            iy = np.r_[np.stack([base + 1, base + 2], axis=1).reshape(-1), sup + 1]
            sign = np.r_[np.tile([1.0, -1.0], self.n_nodes), np.ones(self.n_support)]
            hit = self.cache["plane_pairs"] = (ix, iy, sign)
        return hit

    def static_stiffness_margin(self, speed_rpm: float = 0.0) -> float:
        """Smallest eigenvalue of the symmetric part of K scaled to unit diagonal, ``D^-1/2 K_s D^-1/2``.

        Positive: the static stiffness is positive definite. Zero (to round-off, below about 1e-9) or
        negative: a free rigid-body motion or a statically unstable support (negative direct stiffness
        of a seal or a magnetic bearing); the dynamics may still be stable (gyroscopics, damping) but
        the modal-damping construction and the static response are then not defined.
        """
        K = self.matrices(speed_rpm)[3]
        Ks = 0.5 * (K + K.T)
        d = np.abs(np.diag(Ks))
        d = np.where(d > 0, d, 1.0)
        s = 1.0 / np.sqrt(d)
        return float(np.linalg.eigvalsh(s[:, None] * Ks * s[None, :])[0])

    def dynamic_stiffness(self, freq_hz: np.ndarray, speed_rpm: float = 0.0) -> np.ndarray:
        """Z(w) = K - w^2 M + j w (C + Omega G), shape (f, n, n), complex (N/m).

        Dense over the whole grid: for checks on a few frequencies. Receptances come from
        :mod:`rotorcheck.fe.frf`, which never forms this stack.
        """
        M, C, G, K = self.matrices(speed_rpm)
        w = 2.0 * np.pi * np.atleast_1d(np.asarray(freq_hz, dtype=float))
        D = C + speed_rpm * RPM_TO_RAD_S * G
        return K[None] - (w**2)[:, None, None] * M[None] + 1j * w[:, None, None] * D[None]
