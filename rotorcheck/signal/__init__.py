"""Signal processing of stepped-sine measurements, below the simulators and the faults.

- :mod:`rotorcheck.signal.lockin`: per-period lock-in, averaging and phasor statistics (variance of
  the mean, white-noise phasor variance), the closed-form lock-in of tones, shaft-harmonic removal.

Imports only numpy (nothing of rotorcheck above it).
"""
