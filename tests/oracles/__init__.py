"""Test oracles: second, independent methods that exist only to check the product's engines.

Importable by the tests (``from tests.oracles.frf import dense_receptance``), never by the package:

- :mod:`tests.oracles.frf`: receptance by dense per-frequency solves of Z(w) and by (optionally
  truncated) state-space modal superposition, each built here from the system matrices;
- :mod:`tests.oracles.hb`: the full Hill matrix of the cracked rotor and an independent dense
  harmonic balance as a simulator plant;
- :mod:`tests.oracles.time_domain`: the stepped-sine sweep by time integration on the simulator's
  timeline (exact LTI propagation, DOP853 with a time-varying stiffness) and a ``solve_ivp``
  reference of the cracked rotor.
"""
