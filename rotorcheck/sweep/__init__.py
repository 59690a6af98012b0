"""Stepped-sine sweeps: the HDF5 sweep format, importers/exporters, lock-in and a simulator.

Public entry points:

- :mod:`rotorcheck.sweep.format`: ``Channel``, ``Run``, ``Sweep``, ``read_sweep``, ``write_sweep``,
  ``sweep_sha256``, ``compare_sweeps``, ``SweepFormatError``.
- :mod:`rotorcheck.sweep.uff`: Universal File Format dataset 58 export/import (pyuff).
- :mod:`rotorcheck.sweep.tidy_csv`: tidy CSV export/import.
- :mod:`rotorcheck.sweep.lockin`: per-period lock-in, averaging, closed-form multi-tone lock-in.
- :mod:`rotorcheck.sweep.simulator`: stepped-sine simulator (fast tone path and time-domain path).
- :mod:`rotorcheck.sweep.summary`: ``summarize`` for ``rotorcheck info``.
"""

from rotorcheck.sweep.format import (
    Channel,
    Run,
    Sweep,
    SweepFormatError,
    compare_sweeps,
    read_sweep,
    sweep_sha256,
    write_sweep,
)

__all__ = [
    "Channel",
    "Run",
    "Sweep",
    "SweepFormatError",
    "compare_sweeps",
    "read_sweep",
    "sweep_sha256",
    "write_sweep",
]
