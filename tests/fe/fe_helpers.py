"""Helpers for the FE tests: small rotor configs, clamping and exact condensation of massless DOF."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.config import RigConfig, parse_config
from rotorcheck.fe.system import MechanicalSystem

REPO = Path(__file__).resolve().parents[2]
CONFIGS = REPO / "configs"


def rotor_config(
    stations: Sequence[float],
    diameter: float,
    density: float = 7800.0,
    youngs_modulus: float = 2.0e11,
    shear_modulus: float | None = None,
    poisson: float = 0.3,
    refine: int = 1,
    discs: Sequence[dict[str, Any]] = (),
    bearings: Sequence[dict[str, Any]] = (),
    springs: Sequence[dict[str, Any]] = (),
    damping: dict[str, Any] | None = None,
) -> RigConfig:
    """A uniform shaft config (SI) with optional discs, bearings and springs."""
    mat: dict[str, Any] = {"density": density, "youngs_modulus": youngs_modulus, "poisson": poisson}
    if shear_modulus is not None:
        mat["shear_modulus"] = shear_modulus
    n = len(stations)
    doc: dict[str, Any] = {
        "rig_id": "test",
        "kind": "rotor",
        "materials": {"m": mat},
        "stations": list(stations),
        "shaft": [
            {"start": i, "end": i + 1, "material": "m", "outer_diameter": diameter, "refine": refine}
            for i in range(1, n)
        ],
        "discs": list(discs),
        "bearings": list(bearings),
        "springs": list(springs),
        "ports": {"actuator": {"station": 1}, "sensor": {"station": n}},
    }
    if damping is not None:
        doc["damping"] = damping
    return parse_config(doc)


def reduced(system: MechanicalSystem, keep: np.ndarray) -> MechanicalSystem:
    """System restricted to DOF ``keep`` (the others clamped)."""
    keep = np.asarray(keep)

    def mats(speed: float) -> tuple[np.ndarray, ...]:
        return tuple(A[np.ix_(keep, keep)] for A in system.matrices(speed))  # type: ignore[return-value]

    return MechanicalSystem(
        kind=system.kind, n_dof=keep.size, labels=tuple(system.labels[i] for i in keep), _matrices=mats
    )


def condensed(
    system: MechanicalSystem, keep_nodes: Sequence[int], clamp: Sequence[int] = ()
) -> MechanicalSystem:
    """Guyan condensation onto ``keep_nodes`` (exact when the dropped DOF carry no mass).

    ``clamp``: global DOF fixed to zero before condensing. The result is a rotor with
    ``len(keep_nodes)`` nodes (4 DOF each), so whirl analysis applies.
    """
    keep = np.concatenate([np.arange(4 * k, 4 * k + 4) for k in keep_nodes])
    drop = np.setdiff1d(np.setdiff1d(np.arange(system.n_dof), keep), np.asarray(clamp, dtype=int))

    def mats(speed: float) -> tuple[np.ndarray, ...]:
        M, C, G, K = system.matrices(speed)
        Kab = K[np.ix_(keep, drop)]
        Kc = K[np.ix_(keep, keep)] - Kab @ np.linalg.solve(K[np.ix_(drop, drop)], K[np.ix_(drop, keep)])
        sub = np.ix_(keep, keep)
        return M[sub], C[sub], G[sub], Kc

    return MechanicalSystem(
        kind="rotor",
        n_dof=keep.size,
        labels=tuple(system.labels[i] for i in keep),
        _matrices=mats,
        node_positions=np.asarray(system.node_positions)[list(keep_nodes)],
    )
