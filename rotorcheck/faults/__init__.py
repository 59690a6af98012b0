"""Faults of the rotor: open and breathing cracks (Madden 2016, chapter V, eq. 5.1-5.26).

- :mod:`~rotorcheck.faults.breathing`: steering laws (Mayes-Davies, Gasch, Jun et al.) and their
  Fourier series; the resolved sign of eq. 5.21 (crack closed at theta = 0).
- :mod:`~rotorcheck.faults.crack`: eq. 5.25, the element reduction (eq. 5.24) in the rotating and
  fixed frames, its Fourier coefficients, the open-crack system.
- :mod:`~rotorcheck.faults.harmonic_balance`: Hill's method for the LTP cracked rotor (receptances
  from the engine :mod:`rotorcheck.fe.frf`), the plant callable and the synchronous disturbance tones.
- :mod:`~rotorcheck.faults.analysis`: critical speeds, unbalance harmonics and orbits.

The simulator hooks and the time integration are in :mod:`rotorcheck.sim` (above faults and sweep).
"""

from rotorcheck.faults.crack import (
    UP_ANGLE,
    CrackStiffness,
    crack_stiffness,
    delta_i_ratio,
    open_crack_system,
)
from rotorcheck.faults.harmonic_balance import (
    CrackedPlant,
    HBResult,
    cracked_disturbance_tones,
    cracked_tones,
    fold_tones,
    solve_hb,
)

__all__ = [
    "UP_ANGLE",
    "CrackStiffness",
    "CrackedPlant",
    "HBResult",
    "crack_stiffness",
    "cracked_disturbance_tones",
    "cracked_tones",
    "delta_i_ratio",
    "fold_tones",
    "open_crack_system",
    "solve_hb",
]
