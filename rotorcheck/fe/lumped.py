"""Lumped mass-spring-damper models (``kind: lumped``, e.g. the ECP 210a three-mass system).

One DOF per mass, in config order. A spring between masses ``a`` and ``b`` adds
``k [[1, -1], [-1, 1]]`` on ``(a, b)``; a spring to ``ground`` adds ``k`` on the diagonal. Dampers
alongside springs likewise. The config damping model (modal / Rayleigh), when given, is added on
top of the discrete dampers. No gyroscopic effect (G = 0), nothing speed dependent.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rotorcheck.config import ModalDamping, RayleighDamping
from rotorcheck.fe.damping import modal_damping_matrix, rayleigh_damping_matrix
from rotorcheck.fe.description import MechanicalDescription
from rotorcheck.fe.system import MechanicalSystem


def _incidence(config: MechanicalDescription, index: dict[str, int]) -> np.ndarray:
    """(n_springs, n_mass) incidence: +1 at the first end, -1 at the second, none for ground."""
    B = np.zeros((len(config.lumped_springs), len(index)))
    for i, s in enumerate(config.lumped_springs):
        a, b = s.between
        if a != "ground":
            B[i, index[a]] += 1.0
        if b != "ground":
            B[i, index[b]] -= 1.0
    return B


def build_lumped(
    config: MechanicalDescription,
    stiffness_overrides: Mapping[str, float] | None = None,
    mass_overrides: Mapping[str, float] | None = None,
    damping_overrides: Mapping[str, float] | None = None,
) -> MechanicalSystem:
    """Assemble a lumped model; overrides replace spring stiffness (N/m), mass (kg), damper (N s/m)."""
    names = [m.name for m in config.masses]
    index = {n: i for i, n in enumerate(names)}
    springs = [s.name for s in config.lumped_springs]
    for label, ov, known in (
        ("spring", stiffness_overrides, springs),
        ("mass", mass_overrides, names),
        ("spring", damping_overrides, springs),
    ):
        for key in ov or {}:
            if key not in known:
                raise KeyError(f"unknown {label} {key!r} (known: {', '.join(known)})")
    m = np.array([(mass_overrides or {}).get(x.name, x.mass) for x in config.masses], dtype=float)
    k = np.array([(stiffness_overrides or {}).get(s.name, s.stiffness) for s in config.lumped_springs], float)
    c = np.array([(damping_overrides or {}).get(s.name, s.damping) for s in config.lumped_springs], float)
    B = _incidence(config, index)
    M = np.diag(m)
    K = (B.T * k) @ B
    C = (B.T * c) @ B
    damping = config.damping
    if isinstance(damping, ModalDamping):
        C = C + modal_damping_matrix(M, K, damping.ratios, planes=None)
    elif isinstance(damping, RayleighDamping):
        C = C + rayleigh_damping_matrix(M, K, damping.alpha, damping.beta)
    G = np.zeros_like(M)

    def matrices(speed_rpm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return M.copy(), C.copy(), G.copy(), K.copy()

    return MechanicalSystem(
        kind="lumped",
        n_dof=len(names),
        labels=tuple(names),
        _matrices=matrices,
        mass_index=index,
        _key=_speed_independent,
    )


def _speed_independent(speed_rpm: float) -> tuple[()]:
    """Lumped models do not depend on speed: one matrix key for all speeds."""
    return ()
