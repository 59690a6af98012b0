"""Helpers for the crack tests: a small self-built rotor (same DOF layout as rotorcheck.fe, built
without rotorcheck.fe.assembly) and the rig's breathing crack."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from rotorcheck.config import Crack
from rotorcheck.faults.crack import eb_plane_stiffness, plane_selectors, timoshenko_plane_stiffness
from rotorcheck.fe.system import BeamElementInfo, MechanicalSystem

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
HAVE_ASSEMBLY = importlib.util.find_spec("rotorcheck.fe.assembly") is not None


def _plane_mass(rho_a: float, rho_i: float, l: float) -> np.ndarray:
    mt = (
        rho_a
        * l
        / 420.0
        * np.array(
            [
                [156, 22 * l, 54, -13 * l],
                [22 * l, 4 * l**2, 13 * l, -3 * l**2],
                [54, 13 * l, 156, -22 * l],
                [-13 * l, -3 * l**2, -22 * l, 4 * l**2],
            ]
        )
    )
    mr = (
        rho_i
        / (30.0 * l)
        * np.array(
            [
                [36, 3 * l, -36, 3 * l],
                [3 * l, 4 * l**2, -3 * l, -(l**2)],
                [-36, -3 * l, 36, -3 * l],
                [3 * l, -(l**2), -3 * l, 4 * l**2],
            ]
        )
    )
    return mt + mr


def small_rotor(
    stations: tuple[float, ...] = (0.0, 0.015, 0.175, 0.295, 0.335, 0.450, 0.471, 0.486, 0.615, 0.660),
    diameter: float = 0.016,
    discs: dict[int, tuple[float, float, float]] | None = None,
    bearings: dict[int, float] | None = None,
    zeta: float = 0.01,
    timoshenko: bool = True,
) -> MechanicalSystem:
    """A Timoshenko rotor shaped like the crack rig (stations 1-based), modal damping ``zeta``."""
    if discs is None:
        discs = {3: (0.9299, 0.0025, 0.0011), 7: (0.7521, 2.3938e-4, 3.5264e-4)}
    if bearings is None:
        bearings = {2: 1.65e7, 9: 1.65e7}
    E, Gs, rho, nu = 224.08e9, 83e9, 7809.0, 0.3
    nn = len(stations)
    n = 4 * nn
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    G = np.zeros((n, n))
    psel = plane_selectors()
    els = []
    area = np.pi / 4 * diameter**2
    inertia = np.pi / 64 * diameter**4
    for e in range(nn - 1):
        l = stations[e + 1] - stations[e]
        info = BeamElementInfo(e, e + 1, e, e + 1, l, E, Gs, rho, diameter, 0.0, nu)
        els.append(info)
        kappa = 6 * (1 + nu) / (7 + 6 * nu)
        kb = (
            timoshenko_plane_stiffness(E * inertia, l, kappa * Gs * area)
            if timoshenko
            else eb_plane_stiffness(E * inertia, l)
        )
        mb = _plane_mass(rho * area, rho * inertia, l)
        d = info.dofs
        for p in psel:
            K[np.ix_(d, d)] += p.T @ kb @ p
            M[np.ix_(d, d)] += p.T @ mb @ p
    for s, (m, ip, it) in discs.items():
        b = 4 * (s - 1)
        M[b, b] += m
        M[b + 1, b + 1] += m
        M[b + 2, b + 2] += it
        M[b + 3, b + 3] += it
        G[b + 2, b + 3] += ip
        G[b + 3, b + 2] -= ip
    for s, k in bearings.items():
        b = 4 * (s - 1)
        K[b, b] += k
        K[b + 1, b + 1] += k
    lc_inv = np.linalg.inv(np.linalg.cholesky(M))
    w2, phi = np.linalg.eigh(lc_inv @ K @ lc_inv.T)
    modes = lc_inv.T @ phi  # mass-normalized
    wn = np.sqrt(np.maximum(w2, 0.0))
    C = M @ modes @ np.diag(2 * zeta * wn) @ modes.T @ M
    labels = tuple(f"s{i + 1}.{d}" for i in range(nn) for d in ("x", "y", "theta", "psi"))

    def mats(speed_rpm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return M.copy(), C.copy(), G.copy(), K.copy()

    return MechanicalSystem(
        kind="rotor",
        n_dof=n,
        labels=labels,
        _matrices=mats,
        station_node=tuple(range(nn)),
        node_positions=np.array(stations),
        elements=tuple(els),
    )


RIG_CRACK = Crack(
    element=4,
    model="mayes_davies",
    compliance_xi=3.0,
    compliance_eta=0.47,
    section_length=0.020,
    poisson=0.3,
    angle=0.0,
)


def eq_5_24(e: float, l: float, i_xi: float, i_eta: float) -> np.ndarray:
    """Eq. 5.24 as printed in the dissertation (typed in independently)."""
    a, b = i_xi, i_eta
    return (e / l**3) * np.array(
        [
            [12 * a, 0, 0, 6 * l * a, -12 * a, 0, 0, 6 * l * a],
            [0, 12 * b, -6 * l * b, 0, 0, -12 * b, -6 * l * b, 0],
            [0, -6 * l * b, 4 * l**2 * b, 0, 0, 6 * l * b, 2 * l**2 * b, 0],
            [6 * l * a, 0, 0, 4 * l**2 * a, -6 * l * a, 0, 0, 2 * l**2 * a],
            [-12 * a, 0, 0, -6 * l * a, 12 * a, 0, 0, -6 * l * a],
            [0, -12 * b, 6 * l * b, 0, 0, 12 * b, 6 * l * b, 0],
            [0, -6 * l * b, 2 * l**2 * b, 0, 0, 6 * l * b, 4 * l**2 * b, 0],
            [6 * l * a, 0, 0, 2 * l**2 * a, -6 * l * a, 0, 0, 4 * l**2 * a],
        ]
    )


def t8(angle: float) -> np.ndarray:
    """Eq. 5.26: four copies of the 2x2 rotation of eq. 5.3 on (u1,v1), (th1,psi1), (u2,v2), ..."""
    c, s = np.cos(angle), np.sin(angle)
    t2 = np.array([[c, -s], [s, c]])
    return np.kron(np.eye(4), t2)
