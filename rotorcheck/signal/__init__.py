"""Signal processing of stepped-sine measurements, below the simulators and the faults.

- :mod:`rotorcheck.signal.lockin`: per-period lock-in, averaging and phasor statistics (variance of
  the mean, white-noise phasor variance), the closed-form lock-in of tones, shaft-harmonic removal.
- :mod:`rotorcheck.signal.harmonics`: the grid points within the lock-in's resolution ``f/N`` of a shaft
  harmonic 1X..4X (flagged: kept out of every certified claim by the pipeline).

Imports only numpy (nothing of rotorcheck above it).
"""
