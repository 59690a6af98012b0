"""Stepped-sine sweeps: the HDF5 sweep format and its importers/exporters (the lock-in lives in
:mod:`rotorcheck.signal`, the simulators in :mod:`rotorcheck.sim`).

Public entry points (re-exported here: ``Channel``, ``Run``, ``Sweep``, ``SweepFormatError``,
``compare_sweeps``, ``read_sweep``, ``sweep_sha256``, ``write_sweep``):

- :mod:`rotorcheck.sweep.format`: the data model: ``Channel``, ``Run``, ``Sweep``, ``FrfTable``,
  ``SweepFormatError`` and the schema constants. Version 1 (one excitation pattern) and version 2
  (several inputs driven in ``n_exc`` patterns, frf by least squares; FRF-only runs with
  ``noise_source``): ``Run`` holds the pattern axis (``input_phasor_exc`` ...) and keeps the
  version-1 single-pattern views (``input_phasor`` ...).
- :mod:`rotorcheck.sweep.validation`: checks of a sweep's content (``validate_sweep``).
- :mod:`rotorcheck.sweep.hdf5io`: ``read_sweep``, ``write_sweep`` (atomic), ``sweep_sha256``.
- :mod:`rotorcheck.sweep.compare`: ``compare_sweeps``, ``compare_sweep_files`` (bit for bit).
- :mod:`rotorcheck.sweep.uff`: Universal File Format dataset 58 export/import (pyuff).
- :mod:`rotorcheck.sweep.tidy_csv`: tidy CSV export/import.
- :mod:`rotorcheck.sweep.wide_csv`: wide CSV (one row per frequency, as analysers write) with a
  column map (YAML/JSON); imports give an FRF-only run.
- :mod:`rotorcheck.sweep.convert`: ``convert`` between all of these, for ``rotorcheck convert``.
- :mod:`rotorcheck.sweep.summary`: ``summarize`` for ``rotorcheck info``.

The HDF5 files also open as netCDF-4 in xarray (``engine="h5netcdf"``, ``group="runs/<run_id>"``):
see :mod:`rotorcheck.sweep.hdf5io`.

Imports run downwards only: format <- validation <- hdf5io <- compare <- uff, tidy_csv, wide_csv
<- convert.
"""

from rotorcheck.sweep.compare import compare_sweeps
from rotorcheck.sweep.format import Channel, Run, Sweep, SweepFormatError
from rotorcheck.sweep.hdf5io import read_sweep, sweep_sha256, write_sweep

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
