"""Finite element rotor and lumped models: elements, assembly, modal analysis, the receptance engine.

Main entry points: :func:`rotorcheck.fe.assembly.build_system`, :func:`rotorcheck.fe.modal.modes`,
:func:`rotorcheck.fe.modal.campbell`, and the engine :mod:`rotorcheck.fe.frf`
(:class:`~rotorcheck.fe.frf.Receptance`, :func:`~rotorcheck.fe.frf.receptance`,
:func:`~rotorcheck.fe.frf.state_matrix`) that every receptance of rotorcheck comes from.
"""
