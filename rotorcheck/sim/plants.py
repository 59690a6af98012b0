"""The cracked rotor as a simulator plant: the hooks :mod:`rotorcheck.sim.simulator` takes.

- :func:`simulator_plant`: the linear time-periodic plant by harmonic balance
  (:func:`rotorcheck.faults.harmonic_balance.cracked_tones`; tones at ``f + k * speed``);
- :func:`simulator_disturbances`: the synchronous output tones (1X unbalance, 2X misalignment and
  the crack's harmonics) as fixed ``Tone`` s;
- :func:`dk_fourier`, :func:`stiffness_perturbation`: the stiffness change ``dK(t) = -K_c(Omega t)``
  as Fourier coefficients and as a function of time (for an independent dense harmonic balance or a
  time integration that adds ``dK`` to ``K``).

SI units; frequencies in Hz and speeds in rpm at the interface.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from rotorcheck.config import Crack, Misalignment, UnbalanceMass
from rotorcheck.faults.crack import CrackStiffness, crack_stiffness
from rotorcheck.faults.harmonic_balance import cracked_disturbance_tones, cracked_tones
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.sim.simulator import Plant, Tone

__all__ = ["dk_fourier", "simulator_disturbances", "simulator_plant", "stiffness_perturbation"]


def _ck(system: MechanicalSystem, crack: Crack | CrackStiffness) -> CrackStiffness:
    return crack if isinstance(crack, CrackStiffness) else crack_stiffness(system, crack)


def dk_fourier(system: MechanicalSystem, crack: Crack | CrackStiffness) -> dict[int, np.ndarray]:
    """``dK(t) = -K_c(t) = sum_l dK_l e^{j l Omega t}`` as global (n, n) complex matrices (for a
    harmonic balance that adds ``dK`` to ``K``)."""
    ck = _ck(system, crack)
    orders, kp = ck.harmonics()
    return {int(p): -ck.scatter(k, system.n_dof) for p, k in zip(orders, kp)}


def stiffness_perturbation(
    system: MechanicalSystem, crack: Crack | CrackStiffness, speed_rpm: float
) -> Callable[[float], np.ndarray]:
    """``t -> dK(t) = -K_c(Omega t)`` (n, n) N/m, for a time integration."""
    ck = _ck(system, crack)
    om = speed_rpm * RPM_TO_RAD_S
    n = system.n_dof

    def dk(t: float) -> np.ndarray:
        return -ck.scatter(ck.at_rotation(om * float(t))[0], n)

    return dk


def simulator_plant(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    in_dof: int,
    out_dofs: Sequence[int] | int,
    n_harmonics: int = 8,
    name: str = "cracked_rotor_hb",
) -> Plant:
    """:class:`rotorcheck.sim.simulator.Plant` wrapping :func:`cracked_tones`."""
    plant = cracked_tones(system, crack, speed_rpm, in_dof, out_dofs, n_harmonics)
    return Plant(tones=plant, n_out=int(plant.out_dofs.size), name=name)


def simulator_disturbances(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    out_dofs: Sequence[int] | int,
    unbalance: Sequence[UnbalanceMass] = (),
    misalignment: Misalignment | None = None,
    n_harmonics: int = 8,
    misalignment_whirl: str = "forward",
) -> list[Tone]:
    """Synchronous output tones as simulator ``Tone`` s (signed frequencies, absolute time, m)."""
    f, a = cracked_disturbance_tones(
        system, crack, speed_rpm, out_dofs, unbalance, misalignment, n_harmonics, misalignment_whirl
    )
    return [Tone(float(fi), ai) for fi, ai in zip(f, a) if np.any(ai != 0)]

