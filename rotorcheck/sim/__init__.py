"""Simulators, above the FE engine, the faults and the sweep format.

- :mod:`rotorcheck.sim.simulator`: the stepped-sine simulator (tone fast path, per-period noise,
  the shared timeline); time-invariant plants from the FE receptance engine.
- :mod:`rotorcheck.sim.plants`: the cracked rotor as a simulator plant (harmonic balance) and its
  synchronous disturbance tones.
- :mod:`rotorcheck.sim.rig_sim`: a rig config (usually a "truth" rig) played as a sweep.
- :mod:`rotorcheck.sim.time_sim`: time integration of the cracked rotor (Magnus-4), for
  verification, orbits and spectra.
"""
