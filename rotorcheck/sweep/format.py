"""The HDF5 sweep file, version 1 (``/work/shared/spec/sweep-format.md``): the data model.

Layout (the contract)::

    /                 attrs schema, schema_version, rig_id, created_utc, excitation,
                      phasor_convention, source, generator
    /channels/        parallel 1-D datasets name, role, node, direction, quantity, unit
                      (a compound dataset ``/channels`` with those fields is also accepted on read)
    /runs/<run_id>/   attrs speed_rpm [, notes]; datasets frequency (f) float64 Hz,
                      input_phasor (f, n_in) complex128 N, output_phasor (f, n_out) complex128 m,
                      output_var (f, n_out) float64 m^2, n_periods (f) int32,
                      frf (f, n_out, n_in) complex128 m/N [, period_phasor (f, p, n_chan) complex128]

Column conventions: the ``i``-th column of ``input_phasor`` is the ``i``-th channel of role
``"input"`` in channel-table order (likewise outputs); ``frf[:, o, i] = output_phasor[:, o] /
input_phasor[:, i]``; the last axis of ``period_phasor`` follows the full channel table, rows past
``n_periods`` are NaN.

Schema constants, :class:`Channel`, :class:`Run`, :class:`Sweep`, :class:`FrfTable` and
:class:`SweepFormatError`; no I/O here. Checks live in :mod:`rotorcheck.sweep.validation`, the
reader and writer in :mod:`rotorcheck.sweep.hdf5io`, comparison in :mod:`rotorcheck.sweep.compare`.
"""

from __future__ import annotations

import datetime as _dt
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck.errors import UserInputError

SCHEMA = "rotorcheck.sweep"
SCHEMA_VERSION = 1
EXCITATION = "stepped_sine"
PHASOR_CONVENTION = "x(t) = Re{X exp(j 2 pi f t)}, peak"
SOURCES = ("simulated", "measured")
ROLES = ("input", "output")
DIRECTIONS = ("x", "y")
QUANTITY_UNIT = {"force": "N", "displacement": "m"}
ROLE_QUANTITY = {"input": "force", "output": "displacement"}
CHANNEL_FIELDS = ("name", "role", "node", "direction", "quantity", "unit")
RUN_DATASETS = ("frequency", "input_phasor", "output_phasor", "output_var", "n_periods", "frf")


class SweepFormatError(UserInputError):
    """A sweep file (or an in-memory sweep about to be written) breaks the format contract.

    ``str(err)`` is ``"<file>: <path inside>: <reason>"``.
    """

    def __init__(self, file: str | os.PathLike[str], path_inside: str, reason: str) -> None:
        self.file = str(file)
        self.path_inside = path_inside
        self.reason = reason
        super().__init__(f"{self.file}: {path_inside}: {reason}")


@dataclass(frozen=True)
class Channel:
    """One row of the channel table.

    ``node`` is the 1-based model station; ``direction`` ``"x"``/``"y"``; ``quantity``
    ``"force"`` (unit ``"N"``, role ``"input"``) or ``"displacement"`` (unit ``"m"``, role
    ``"output"``).
    """

    name: str
    role: str
    node: int
    direction: str
    quantity: str
    unit: str


@dataclass
class Run:
    """One operating point (one stepped-sine sweep at one speed).

    Arrays: ``frequency`` (f,) Hz; ``input_phasor`` (f, n_in) N; ``output_phasor`` (f, n_out) m;
    ``output_var`` (f, n_out) m^2, variance of the mean output phasor (E|mean - truth|^2);
    ``n_periods`` (f,) periods averaged; ``frf`` (f, n_out, n_in) m/N;
    ``period_phasor`` (f, p, n_chan) optional per-period phasors, NaN padded.
    """

    run_id: str
    speed_rpm: float
    frequency: np.ndarray
    input_phasor: np.ndarray
    output_phasor: np.ndarray
    output_var: np.ndarray
    n_periods: np.ndarray
    frf: np.ndarray
    period_phasor: np.ndarray | None = None
    notes: str = ""

    @classmethod
    def from_phasors(
        cls,
        run_id: str,
        speed_rpm: float,
        frequency: np.ndarray,
        input_phasor: np.ndarray,
        output_phasor: np.ndarray,
        output_var: np.ndarray,
        n_periods: np.ndarray | int,
        period_phasor: np.ndarray | None = None,
        notes: str = "",
    ) -> Run:
        """Build a run and derive ``frf[:, o, i] = output_phasor[:, o] / input_phasor[:, i]``."""
        freq = np.asarray(frequency, dtype=np.float64)
        inp = np.asarray(input_phasor, dtype=np.complex128)
        out = np.asarray(output_phasor, dtype=np.complex128)
        if inp.ndim == 1:
            inp = inp[:, None]
        if out.ndim == 1:
            out = out[:, None]
        var = np.asarray(output_var, dtype=np.float64)
        if var.ndim == 1:
            var = var[:, None]
        n = np.broadcast_to(np.asarray(n_periods), freq.shape).astype(np.int32)
        with np.errstate(divide="ignore", invalid="ignore"):
            frf = out[:, :, None] / inp[:, None, :]
        pp = None if period_phasor is None else np.asarray(period_phasor, dtype=np.complex128)
        return cls(run_id, float(speed_rpm), freq, inp, out, var, n, frf, pp, notes)


@dataclass
class Sweep:
    """One measurement campaign of one rig: metadata, channel table and runs keyed by run id."""

    rig_id: str
    source: str
    generator: str
    created_utc: str
    channels: list[Channel]
    runs: dict[str, Run] = field(default_factory=dict)

    @property
    def inputs(self) -> list[Channel]:
        """Input channels in table order (columns of ``input_phasor``)."""
        return [c for c in self.channels if c.role == "input"]

    @property
    def outputs(self) -> list[Channel]:
        """Output channels in table order (columns of ``output_phasor``)."""
        return [c for c in self.channels if c.role == "output"]


@dataclass
class FrfTable:
    """FRF-only content of an imported file (UFF58 or tidy CSV) for one run.

    ``frf`` (f, n_out, n_in) m/N at ``frequency`` (f,) Hz; ``outputs``/``inputs`` give the
    channel of each axis; ``output_var`` (f, n_out) m^2 and ``n_periods`` (f,) when present.
    """

    run_id: str
    speed_rpm: float
    frequency: np.ndarray
    outputs: list[Channel]
    inputs: list[Channel]
    frf: np.ndarray
    output_var: np.ndarray | None = None
    n_periods: np.ndarray | None = None


def utc_now_iso() -> str:
    """Current UTC time as ISO 8601 with ``Z``, to the second (for ``created_utc``)."""
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def sweep_from_mapping(meta: Mapping[str, Any], channels: list[Channel], runs: list[Run]) -> Sweep:
    """Convenience: build a :class:`Sweep` from header fields and a list of runs (order kept)."""
    return Sweep(
        rig_id=str(meta["rig_id"]),
        source=str(meta["source"]),
        generator=str(meta.get("generator", "")),
        created_utc=str(meta["created_utc"]),
        channels=list(channels),
        runs={r.run_id: r for r in runs},
    )


__all__ = [
    "CHANNEL_FIELDS",
    "DIRECTIONS",
    "EXCITATION",
    "PHASOR_CONVENTION",
    "QUANTITY_UNIT",
    "ROLES",
    "ROLE_QUANTITY",
    "RUN_DATASETS",
    "SCHEMA",
    "SCHEMA_VERSION",
    "SOURCES",
    "Channel",
    "FrfTable",
    "Run",
    "Sweep",
    "SweepFormatError",
    "sweep_from_mapping",
    "utc_now_iso",
]
