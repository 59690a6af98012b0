"""The HDF5 sweep file, versions 1, 2 and 3 (``/work/shared/spec/sweep-format.md``; version 3 in
``docs/sweep-format-v3.md``): the data model.

Layout (the contract)::

    /                 attrs schema, schema_version (1 or 2), rig_id, created_utc, excitation,
                      phasor_convention, source, generator
    /channels/        parallel 1-D datasets name, role, node, direction, quantity, unit
                      (a compound dataset ``/channels`` with those fields is also accepted on read)
    /runs/<run_id>/   version 1: attrs speed_rpm [, notes]; datasets frequency (f) float64 Hz,
                      input_phasor (f, n_in) complex128 N, output_phasor (f, n_out) complex128 m,
                      output_var (f, n_out) float64 m^2, n_periods (f) int32,
                      frf (f, n_out, n_in) complex128 m/N [, period_phasor (f, p, n_chan) complex128]
                      version 2: attrs speed_rpm [, notes] [, noise_source]; the phasor datasets
                      gain the pattern axis: input_phasor (f, n_exc, n_in), output_phasor
                      (f, n_exc, n_out), output_var (f, n_exc, n_out), n_periods (f, n_exc)
                      [, input_var (f, n_exc, n_in) N^2] [, period_phasor (f, n_exc, p, n_chan)];
                      frf (f, n_out, n_in) = Y X^+ [, frf_var (f, n_out, n_in) (m/N)^2].
                      An FRF-only run holds frequency, frf [, frf_var] and the attr noise_source.
                      version 3: version 2 plus, on a run with phasors, the three datasets
                      sideband_order (K) int32, sideband_phasor (f, n_exc, K, n_out) complex128 m and
                      sideband_var (f, n_exc, K, n_out) float64 m^2 (all or none): the output tone
                      at f + k speed/60 of each pattern, referenced to the shaft (below).

Column conventions: the ``i``-th column of ``input_phasor`` is the ``i``-th channel of role
``"input"`` in channel-table order (likewise outputs); in version 1 ``frf[:, o, i] =
output_phasor[:, o] / input_phasor[:, i]``; the last axis of ``period_phasor`` follows the full
channel table, rows past ``n_periods`` are NaN.

Sidebands (version 3). ``sideband_phasor[j, e, i, o]`` is output ``o``'s tone at ``f_j + k_i n / 60`` Hz
(``k_i = sideband_order[i]``, a nonzero integer; n the run's speed, rpm; a negative frequency is the
tone at ``|f_j + k_i n / 60|`` with the conjugate phasor) while pattern ``e`` drives at ``f_j``, in the
point's local time (the excitation's phasor convention) times ``exp(-j k_i theta_j)``, ``theta_j`` the
shaft angle (rad, key-phasor mark = 0) at the point's time origin: so referenced, a linear
time-periodic rotor gives the same phasor whatever angle the shaft had when the point began.
``sideband_var`` is the variance of that estimate (``E|dS|^2``). A tone that the record cannot
separate from another one it holds (the excitation, another sideband, a shaft harmonic k n / 60,
k = 1 .. 4: closer than the resolution ``f / N``) is NaN in both. A time-invariant rotor has no
sidebands: their phasors are noise.

The in-memory :class:`Run` (one data model for both versions)
----------------------------------------------------------------

A run stores the pattern axis (``n_exc`` excitation patterns at every frequency):

=====================  ========================  ======================================
attribute              shape                     meaning
=====================  ========================  ======================================
``frequency``          (f,)                      Hz
``frf``                (f, n_out, n_in)          m/N, ``Y X^+`` per frequency
``frf_var``            (f, n_out, n_in) or None  (m/N)^2, variance of each frf entry
``input_phasor_exc``   (f, n_exc, n_in) or None  N, force phasors of each pattern
``output_phasor_exc``  (f, n_exc, n_out) or None m, mean over the pattern's periods
``output_var_exc``     (f, n_exc, n_out) or None m^2, variance of that mean
``input_var_exc``      (f, n_exc, n_in) or None  N^2, optional measured force noise
``n_periods_exc``      (f, n_exc) or None        periods averaged
``period_phasor_exc``  (f, n_exc, p, n_chan)     optional per-period phasors (NaN padded)
``noise_source``       str or None               FRF-only runs: "measured" | "assumed: <rule>"
``sideband_order``     (K,) int or None          version 3: the orders k of the sidebands
``sideband_phasor_exc`` (f, n_exc, K, n_out)     m, shaft-referenced tone at f + k n/60 (NaN: not
                                                 separable)
``sideband_var_exc``   (f, n_exc, K, n_out)      m^2, its variance
=====================  ========================  ======================================

The phasor arrays are all ``None`` for an FRF-only run (:attr:`Run.is_frf_only`). A version-1 run is
a run with ``n_exc = 1``. The version-1 names are single-pattern views, kept with exactly their
version-1 shapes for the code that reads one pattern: ``input_phasor`` (f, n_in),
``output_phasor`` (f, n_out), ``output_var`` (f, n_out), ``n_periods`` (f,), ``period_phasor``
(f, p, n_chan) or None. They are views of the ``*_exc`` arrays (axis 1 dropped), settable, and raise
:class:`SweepFormatError` (naming the run and what to use instead) on a run with several patterns
or, except ``period_phasor`` (None), on an FRF-only run.

Schema constants, :class:`Channel`, :class:`Run`, :class:`Sweep`, :class:`FrfTable`,
:class:`SweepFormatError`, the least-squares FRF (:func:`ls_frf`, :func:`ls_frf_var`) and
:func:`sweep_schema_version`; no I/O here. Checks live in :mod:`rotorcheck.sweep.validation`, the
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
#: the version-1 layout (single pattern, phasors without the pattern axis)
SCHEMA_VERSION_V1 = 1
#: the version-2 layout (pattern axis, FRF-only runs)
SCHEMA_VERSION_V2 = 2
#: the version-3 layout (version 2 and the shaft-referenced sidebands of a rotating run)
SCHEMA_VERSION_V3 = 3
#: the newest version this package reads and writes
SCHEMA_VERSION = SCHEMA_VERSION_V3
#: versions the reader knows
SCHEMA_VERSIONS = (SCHEMA_VERSION_V1, SCHEMA_VERSION_V2, SCHEMA_VERSION_V3)
EXCITATION = "stepped_sine"
PHASOR_CONVENTION = "x(t) = Re{X exp(j 2 pi f t)}, peak"
SOURCES = ("simulated", "measured")
ROLES = ("input", "output")
DIRECTIONS = ("x", "y")
QUANTITY_UNIT = {"force": "N", "displacement": "m"}
ROLE_QUANTITY = {"input": "force", "output": "displacement"}
CHANNEL_FIELDS = ("name", "role", "node", "direction", "quantity", "unit")
#: required datasets of a version-1 run (and of a version-2 run with phasors)
RUN_DATASETS = ("frequency", "input_phasor", "output_phasor", "output_var", "n_periods", "frf")
#: optional datasets of a version-2 run
RUN_OPTIONAL_V2 = ("input_var", "frf_var", "period_phasor")
#: the optional datasets of a version-3 run (all three or none) and the :class:`Run` attributes holding them
SIDEBAND_ATTRS = {"sideband_order": "sideband_order", "sideband_phasor": "sideband_phasor_exc",
                  "sideband_var": "sideband_var_exc"}
#: required datasets of a version-2 FRF-only run (``frf_var`` optional)
FRF_ONLY_DATASETS = ("frequency", "frf")
#: the phasor datasets (file names) and the :class:`Run` attributes holding them with the pattern axis
PATTERN_ATTRS = {
    "input_phasor": "input_phasor_exc",
    "output_phasor": "output_phasor_exc",
    "output_var": "output_var_exc",
    "input_var": "input_var_exc",
    "n_periods": "n_periods_exc",
    "period_phasor": "period_phasor_exc",
}
#: ``noise_source`` is "measured" or starts with this prefix followed by the rule
NOISE_ASSUMED_PREFIX = "assumed: "


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


def noise_source_problem(value: object) -> str | None:
    """Why ``value`` is not a valid ``noise_source`` ("measured" or "assumed: <rule>"), else None."""
    if not isinstance(value, str):
        return f"noise_source must be text, got {type(value).__name__}"
    if value == "measured":
        return None
    if value.startswith(NOISE_ASSUMED_PREFIX) and value[len(NOISE_ASSUMED_PREFIX):].strip():
        return None
    return (f"noise_source {value!r} is neither 'measured' nor 'assumed: <rule>' "
            "(e.g. 'assumed: 1 % of |H| floor')")


def _add_pattern_axis(a: Any) -> np.ndarray | None:
    """A version-1 array with the pattern axis (length 1) inserted at axis 1 (a view)."""
    if a is None:
        return None
    arr = np.asarray(a)
    return np.expand_dims(arr, 1) if arr.ndim >= 1 else arr


def ls_frf(input_phasor_exc: np.ndarray, output_phasor_exc: np.ndarray) -> np.ndarray:
    """Least-squares FRF ``H = Y X^+`` at every frequency, (f, n_out, n_in) m/N.

    ``X = input_phasor_exc[k].T`` (n_in x n_exc), ``Y = output_phasor_exc[k].T`` (n_out x n_exc),
    ``X^+ = X^H (X X^H)^-1`` (Moore-Penrose, by SVD: :func:`numpy.linalg.pinv`); exact when
    ``n_exc = n_in`` and X is invertible, the least-squares fit over the patterns when ``n_exc > n_in``.
    """
    x = np.swapaxes(np.asarray(input_phasor_exc, dtype=np.complex128), 1, 2)  # (f, n_in, n_exc)
    y = np.swapaxes(np.asarray(output_phasor_exc, dtype=np.complex128), 1, 2)  # (f, n_out, n_exc)
    return np.asarray(y @ np.linalg.pinv(x))


def ls_frf_var(input_phasor_exc: np.ndarray, output_var_exc: np.ndarray) -> np.ndarray:
    """Variance of each entry of ``H = Y X^+`` from the output variances, (f, n_out, n_in) (m/N)^2.

    With independent circular output noise per pattern and output (``E|dY[o, e]|^2 =
    output_var[e, o]``) and X taken as exact (input noise is not propagated, as in version 1)::

        var(H[o, i]) = sum_e output_var[e, o] |X^+[e, i]|^2

    For one input driven per pattern (pattern e drives input i only) this is
    ``output_var[e, o] / |X[i, e]|^2``, the version-1 ``output_var / |W|^2``.
    """
    x = np.swapaxes(np.asarray(input_phasor_exc, dtype=np.complex128), 1, 2)  # (f, n_in, n_exc)
    p2 = np.abs(np.linalg.pinv(x)) ** 2  # (f, n_exc, n_in)
    var = np.asarray(output_var_exc, dtype=np.float64)  # (f, n_exc, n_out)
    return np.asarray(np.einsum("feo,fei->foi", var, p2))


@dataclass
class Run:
    """One operating point (one stepped-sine sweep at one speed): see the module docstring for the
    attributes (pattern axis ``*_exc``) and the single-pattern views (``input_phasor`` ...).

    Build with :meth:`from_phasors` (one pattern, version 1), :meth:`from_patterns` (several
    patterns: frf by least squares, frf_var propagated), :meth:`frf_only` or :meth:`from_v1`
    (version-1 arrays as stored, frf not recomputed). ``origin`` names the file a run was read from
    (for error messages).
    """

    run_id: str
    speed_rpm: float
    frequency: np.ndarray
    frf: np.ndarray
    input_phasor_exc: np.ndarray | None = None
    output_phasor_exc: np.ndarray | None = None
    output_var_exc: np.ndarray | None = None
    n_periods_exc: np.ndarray | None = None
    period_phasor_exc: np.ndarray | None = None
    input_var_exc: np.ndarray | None = None
    frf_var: np.ndarray | None = None
    noise_source: str | None = None
    notes: str = ""
    origin: str = field(default="<memory>", repr=False, compare=False)
    sideband_order: np.ndarray | None = None
    sideband_phasor_exc: np.ndarray | None = None
    sideband_var_exc: np.ndarray | None = None

    # ---------------------------------------------------------------- constructors

    @classmethod
    def from_v1(
        cls,
        run_id: str,
        speed_rpm: float,
        frequency: np.ndarray,
        input_phasor: np.ndarray,
        output_phasor: np.ndarray,
        output_var: np.ndarray,
        n_periods: np.ndarray,
        frf: np.ndarray,
        period_phasor: np.ndarray | None = None,
        notes: str = "",
        origin: str = "<memory>",
    ) -> Run:
        """A one-pattern run from version-1 arrays as given (no dtype change, frf kept): the
        phasor arrays get the pattern axis (length 1) as views."""
        def ax(a: Any) -> np.ndarray:
            out = _add_pattern_axis(a)
            assert out is not None
            return out

        return cls(
            run_id=run_id,
            speed_rpm=speed_rpm,
            frequency=frequency,
            frf=frf,
            input_phasor_exc=ax(input_phasor),
            output_phasor_exc=ax(output_phasor),
            output_var_exc=ax(output_var),
            n_periods_exc=ax(n_periods),
            period_phasor_exc=_add_pattern_axis(period_phasor),
            notes=notes,
            origin=origin,
        )

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
        """Build a one-pattern (version-1) run and derive
        ``frf[:, o, i] = output_phasor[:, o] / input_phasor[:, i]``."""
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
        return cls.from_v1(run_id, float(speed_rpm), freq, inp, out, var, n, frf, pp, notes)

    @classmethod
    def from_patterns(
        cls,
        run_id: str,
        speed_rpm: float,
        frequency: np.ndarray,
        input_phasor: np.ndarray,
        output_phasor: np.ndarray,
        output_var: np.ndarray,
        n_periods: np.ndarray | int,
        *,
        input_var: np.ndarray | None = None,
        period_phasor: np.ndarray | None = None,
        notes: str = "",
    ) -> Run:
        """A run of ``n_exc >= n_in`` excitation patterns (a version-2 run).

        ``input_phasor`` (f, n_exc, n_in) N (an input a pattern does not drive is 0),
        ``output_phasor`` (f, n_exc, n_out) m, ``output_var`` (f, n_exc, n_out) m^2, ``n_periods``
        an int, (f,) or (f, n_exc); ``input_var`` (f, n_exc, n_in) N^2 and ``period_phasor``
        (f, n_exc, p, n_chan) optional.

        ``frf = Y X^+`` per frequency (least squares, :func:`ls_frf`; X: n_in x n_exc, Y:
        n_out x n_exc) and ``frf_var[o, i] = sum_e output_var[e, o] |X^+[e, i]|^2``
        (:func:`ls_frf_var`: independent output noise per pattern and output, X exact), which for
        pattern e driving input i alone is ``output_var[e, o] / |X[i, e]|^2``.
        """
        freq = np.asarray(frequency, dtype=np.float64)
        inp = np.asarray(input_phasor, dtype=np.complex128)
        out = np.asarray(output_phasor, dtype=np.complex128)
        var = np.asarray(output_var, dtype=np.float64)
        if inp.ndim != 3 or out.ndim != 3 or var.ndim != 3:
            raise ValueError(
                f"input_phasor {inp.shape}, output_phasor {out.shape}, output_var {var.shape}: "
                "expected (f, n_exc, n_in), (f, n_exc, n_out), (f, n_exc, n_out)"
            )
        nf, n_exc, n_in = inp.shape
        if n_exc < n_in:
            raise ValueError(f"{n_exc} excitation patterns for {n_in} inputs: need n_exc >= n_in")
        n_arr = np.asarray(n_periods)
        if n_arr.ndim == 1:
            n_arr = n_arr[:, None]
        n = np.broadcast_to(n_arr, (nf, n_exc)).astype(np.int32)
        iv = None if input_var is None else np.asarray(input_var, dtype=np.float64)
        pp = None if period_phasor is None else np.asarray(period_phasor, dtype=np.complex128)
        return cls(
            run_id=run_id,
            speed_rpm=float(speed_rpm),
            frequency=freq,
            frf=ls_frf(inp, out),
            input_phasor_exc=inp,
            output_phasor_exc=out,
            output_var_exc=var,
            n_periods_exc=n,
            period_phasor_exc=pp,
            input_var_exc=iv,
            frf_var=ls_frf_var(inp, var),
            notes=notes,
        )

    @classmethod
    def frf_only(
        cls,
        run_id: str,
        speed_rpm: float,
        frequency: np.ndarray,
        frf: np.ndarray,
        frf_var: np.ndarray | None = None,
        *,
        noise_source: str,
        notes: str = "",
    ) -> Run:
        """An FRF-only run (version 2): ``frf`` (f, n_out, n_in) m/N, ``frf_var`` (m/N)^2 where
        known, and ``noise_source`` ("measured" or "assumed: <rule>") saying where it came from."""
        why = noise_source_problem(noise_source)
        if why is not None:
            raise ValueError(f"run {run_id!r}: {why}")
        return cls(
            run_id=run_id,
            speed_rpm=float(speed_rpm),
            frequency=np.asarray(frequency, dtype=np.float64),
            frf=np.asarray(frf, dtype=np.complex128),
            frf_var=None if frf_var is None else np.asarray(frf_var, dtype=np.float64),
            noise_source=noise_source,
            notes=notes,
        )

    # ---------------------------------------------------------------- shape facts

    @property
    def is_frf_only(self) -> bool:
        """True when the run holds no phasors (FRF and, where known, its variance only)."""
        return all(getattr(self, a) is None for a in ("input_phasor_exc", "output_phasor_exc",
                                                      "output_var_exc", "n_periods_exc"))

    @property
    def n_exc(self) -> int:
        """Excitation patterns per frequency (0 for an FRF-only run)."""
        if self.input_phasor_exc is None:
            return 0
        shape = np.shape(self.input_phasor_exc)
        return int(shape[1]) if len(shape) >= 2 else 1

    @property
    def needs_v2(self) -> bool:
        """True when the run cannot be written as version 1: several patterns, FRF-only, or a
        dataset version 1 lacks (``input_var``, ``frf_var``, ``noise_source``)."""
        return (self.is_frf_only or self.n_exc != 1 or self.input_var_exc is not None
                or self.frf_var is not None or self.noise_source is not None)

    @property
    def needs_v3(self) -> bool:
        """True when the run holds any of the version-3 sideband datasets (the checks then ask for all three)."""
        return any(getattr(self, a) is not None for a in SIDEBAND_ATTRS.values())

    @property
    def has_sidebands(self) -> bool:
        """True when the run holds sideband phasors (version 3)."""
        return self.sideband_order is not None and self.sideband_phasor_exc is not None

    def with_sidebands(self, order: np.ndarray, phasor_exc: np.ndarray, var_exc: np.ndarray) -> Run:
        """This run (the same object) holding the sidebands ``order`` (K,), ``phasor_exc`` (f, n_exc, K, n_out) m
        and ``var_exc`` m^2 (module docstring: shaft-referenced, NaN where not separable)."""
        self.sideband_order = np.asarray(order, dtype=np.int32).reshape(-1)
        self.sideband_phasor_exc = np.asarray(phasor_exc, dtype=np.complex128)
        self.sideband_var_exc = np.asarray(var_exc, dtype=np.float64)
        return self

    def sideband_frf(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The sideband receptances ``S_k = Y_k X^+`` (f, K, n_out, n_in) m/N and their variances (m/N)^2
        (:func:`ls_frf`, :func:`ls_frf_var` per order, the input phasors at ``f``), None without sidebands."""
        if not self.has_sidebands or self.input_phasor_exc is None:
            return None
        assert self.sideband_phasor_exc is not None and self.sideband_var_exc is not None
        y = np.asarray(self.sideband_phasor_exc)
        nf, ne, kk, n_out = y.shape
        # every order's outputs as more outputs of one least-squares solve (one pseudo-inverse per frequency)
        frf = ls_frf(self.input_phasor_exc, y.reshape(nf, ne, kk * n_out))
        var = ls_frf_var(self.input_phasor_exc, np.asarray(self.sideband_var_exc).reshape(nf, ne, kk * n_out))
        n_in = frf.shape[2]
        return frf.reshape(nf, kk, n_out, n_in), var.reshape(nf, kk, n_out, n_in)

    def frf_variance(self) -> np.ndarray | None:
        """``frf_var`` if stored, else propagated from the phasors (:func:`ls_frf_var`; for one
        pattern ``output_var / |input_phasor|^2``), else None (FRF-only without variance)."""
        if self.frf_var is not None:
            return np.asarray(self.frf_var, dtype=np.float64)
        if self.is_frf_only:
            return None
        assert self.input_phasor_exc is not None and self.output_var_exc is not None
        return ls_frf_var(self.input_phasor_exc, self.output_var_exc)

    # ---------------------------------------------------------------- single-pattern views

    def _single(self, name: str, allow_none: bool = False) -> np.ndarray | None:
        arr = getattr(self, PATTERN_ATTRS[name])
        if self.is_frf_only:
            if allow_none:
                return None
            raise SweepFormatError(
                self.origin, f"/runs/{self.run_id}/{name}",
                f"FRF-only run (noise_source {self.noise_source!r}) has no {name}; use frf and frf_var",
            )
        if self.n_exc != 1:
            raise SweepFormatError(
                self.origin, f"/runs/{self.run_id}/{name}",
                f"run has {self.n_exc} excitation patterns: the single-pattern view {name} needs "
                f"n_exc = 1; use {PATTERN_ATTRS[name]} (pattern axis 1) or frf",
            )
        if arr is None:
            return None
        a = np.asarray(arr)
        return a[:, 0] if a.ndim >= 2 else a

    def _set_single(self, name: str, value: np.ndarray | None) -> None:
        setattr(self, PATTERN_ATTRS[name], _add_pattern_axis(value))

    @property
    def input_phasor(self) -> np.ndarray:
        """(f, n_in) N, the single pattern's input phasors (``input_phasor_exc[:, 0]``)."""
        out = self._single("input_phasor")
        assert out is not None
        return out

    @input_phasor.setter
    def input_phasor(self, value: np.ndarray) -> None:
        self._set_single("input_phasor", value)

    @property
    def output_phasor(self) -> np.ndarray:
        """(f, n_out) m, the single pattern's mean output phasors."""
        out = self._single("output_phasor")
        assert out is not None
        return out

    @output_phasor.setter
    def output_phasor(self, value: np.ndarray) -> None:
        self._set_single("output_phasor", value)

    @property
    def output_var(self) -> np.ndarray:
        """(f, n_out) m^2, variance of the single pattern's mean output phasor."""
        out = self._single("output_var")
        assert out is not None
        return out

    @output_var.setter
    def output_var(self, value: np.ndarray) -> None:
        self._set_single("output_var", value)

    @property
    def n_periods(self) -> np.ndarray:
        """(f,) periods averaged in the single pattern."""
        out = self._single("n_periods")
        assert out is not None
        return out

    @n_periods.setter
    def n_periods(self, value: np.ndarray) -> None:
        self._set_single("n_periods", value)

    @property
    def period_phasor(self) -> np.ndarray | None:
        """(f, p, n_chan) per-period phasors of the single pattern, or None (none stored, or an
        FRF-only run)."""
        return self._single("period_phasor", allow_none=True)

    @period_phasor.setter
    def period_phasor(self, value: np.ndarray | None) -> None:
        self._set_single("period_phasor", value)


def sweep_schema_version(sweep: Sweep) -> int:
    """The version a writer uses: 3 where any run holds sidebands, 2 where any run needs it (:attr:`Run.needs_v2`),
    else 1."""
    if any(r.needs_v3 for r in sweep.runs.values()):
        return SCHEMA_VERSION_V3
    return SCHEMA_VERSION_V2 if any(r.needs_v2 for r in sweep.runs.values()) else SCHEMA_VERSION_V1


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
    channel of each axis; ``output_var`` (f, n_out) m^2 and ``n_periods`` (f,) when present;
    ``frf_var`` (f, n_out, n_in) (m/N)^2 and ``noise_source`` when the file states them.
    """

    run_id: str
    speed_rpm: float
    frequency: np.ndarray
    outputs: list[Channel]
    inputs: list[Channel]
    frf: np.ndarray
    output_var: np.ndarray | None = None
    n_periods: np.ndarray | None = None
    frf_var: np.ndarray | None = None
    noise_source: str | None = None


def imported_frf_only(file: str | os.PathLike[str], table: FrfTable, frf: np.ndarray, frf_var: np.ndarray | None,
                      noise_source: str | None, what: str, reader: str) -> Run:
    """An importer's FRF-only run from ``table`` (``what``: what it holds instead of phasors, e.g. "file
    (no phasor records)"; ``reader``: the FRF-only reader to suggest): ``noise_source`` (else the
    table's own) is required and checked."""
    ns = noise_source if noise_source is not None else table.noise_source
    if ns is None:
        raise SweepFormatError(
            file, "/",
            f"run {table.run_id!r}: FRF-only {what} and no noise_source: pass noise_source ('measured' "
            f"or 'assumed: <rule>', e.g. 'assumed: 1 % of |H| floor') to import it as an FRF-only run, or use "
            f"{reader}",
        )
    why = noise_source_problem(ns)
    if why is not None:
        raise SweepFormatError(file, "/", f"run {table.run_id!r}: {why}")
    return Run.frf_only(table.run_id, table.speed_rpm, table.frequency, frf, frf_var, noise_source=ns)


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
    "FRF_ONLY_DATASETS",
    "NOISE_ASSUMED_PREFIX",
    "PATTERN_ATTRS",
    "PHASOR_CONVENTION",
    "QUANTITY_UNIT",
    "ROLES",
    "ROLE_QUANTITY",
    "RUN_DATASETS",
    "RUN_OPTIONAL_V2",
    "SCHEMA",
    "SCHEMA_VERSION",
    "SCHEMA_VERSIONS",
    "SCHEMA_VERSION_V1",
    "SCHEMA_VERSION_V2",
    "SCHEMA_VERSION_V3",
    "SIDEBAND_ATTRS",
    "SOURCES",
    "Channel",
    "FrfTable",
    "Run",
    "Sweep",
    "SweepFormatError",
    "ls_frf",
    "ls_frf_var",
    "noise_source_problem",
    "sweep_from_mapping",
    "sweep_schema_version",
    "utc_now_iso",
]
