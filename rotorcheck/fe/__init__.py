"""Finite element rotor and lumped models: elements, assembly, modal analysis, FRF.

Main entry points: :func:`rotorcheck.fe.assembly.build_system`, :func:`rotorcheck.fe.modal.modes`,
:func:`rotorcheck.fe.modal.campbell`, :func:`rotorcheck.fe.frf.receptance`.
"""
