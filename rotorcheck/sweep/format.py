"""The HDF5 sweep file, version 1 (``/work/shared/spec/sweep-format.md``): data model, reader, writer.

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

The reader validates everything on open and raises :class:`SweepFormatError` naming the file, the
path inside it and the reason; it never guesses (no dtype coercion, no reordering, no repair).
The writer is atomic and refuses to overwrite unless ``force=True``.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import hashlib
import os
import re
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import h5py
import numpy as np

from rotorcheck.fileio import umask_mode

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
#: Default relative tolerance of the ``frf == output / input`` consistency check.
FRF_RTOL = 1e-9
#: Default relative tolerance of the ``period_phasor`` vs. mean/variance consistency check.
PERIOD_RTOL = 1e-9

_ISO_Z = re.compile(r"^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d{1,9})?Z$")
_RUN_ID = re.compile(r"^[A-Za-z0-9_.+-]+$")


class SweepFormatError(ValueError):
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


# --------------------------------------------------------------------------------------------
# validation shared by reader and writer
# --------------------------------------------------------------------------------------------


def _check_text(file: str, where: str, value: Any, what: str) -> str:
    if isinstance(value, bytes | np.bytes_):
        try:
            value = bytes(value).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SweepFormatError(file, where, f"{what} is not valid UTF-8 text") from exc
    if not isinstance(value, str):
        raise SweepFormatError(file, where, f"{what} must be text, got {type(value).__name__}")
    return value


def _validate_header(file: str, rig_id: Any, source: Any, generator: Any, created: Any) -> None:
    rig = _check_text(file, "/@rig_id", rig_id, "rig_id")
    if not rig.strip():
        raise SweepFormatError(file, "/@rig_id", "rig_id is empty")
    src = _check_text(file, "/@source", source, "source")
    if src not in SOURCES:
        raise SweepFormatError(file, "/@source", f"source {src!r} is not one of {SOURCES}")
    _check_text(file, "/@generator", generator, "generator")
    cre = _check_text(file, "/@created_utc", created, "created_utc")
    if not _ISO_Z.match(cre):
        raise SweepFormatError(
            file, "/@created_utc", f"created_utc {cre!r} is not ISO 8601 UTC 'YYYY-MM-DDTHH:MM:SSZ'"
        )
    try:
        _dt.datetime.strptime(cre[:19], "%Y-%m-%dT%H:%M:%S")
    except ValueError as exc:
        raise SweepFormatError(file, "/@created_utc", f"created_utc {cre!r}: {exc}") from exc


def _validate_channels(file: str, where: str, channels: list[Channel]) -> None:
    if len(channels) == 0:
        raise SweepFormatError(file, where, "channel table is empty")
    names = [c.name for c in channels]
    for c in channels:
        if not isinstance(c.name, str) or not c.name.strip():
            raise SweepFormatError(file, f"{where}/name", "empty channel name")
        if c.role not in ROLES:
            raise SweepFormatError(
                file, f"{where}/role", f"channel {c.name!r}: role {c.role!r} not in {ROLES}"
            )
        if isinstance(c.node, bool) or not isinstance(c.node, int | np.integer) or c.node < 1:
            raise SweepFormatError(
                file, f"{where}/node", f"channel {c.name!r}: node {c.node!r} is not an integer >= 1"
            )
        if c.direction not in DIRECTIONS:
            raise SweepFormatError(
                file,
                f"{where}/direction",
                f"channel {c.name!r}: direction {c.direction!r} not in {DIRECTIONS}",
            )
        if c.quantity not in QUANTITY_UNIT:
            raise SweepFormatError(
                file,
                f"{where}/quantity",
                f"channel {c.name!r}: quantity {c.quantity!r} not in {tuple(QUANTITY_UNIT)}",
            )
        if c.unit != QUANTITY_UNIT[c.quantity]:
            raise SweepFormatError(
                file,
                f"{where}/unit",
                f"channel {c.name!r}: unit {c.unit!r} does not match quantity {c.quantity!r} "
                f"(expected {QUANTITY_UNIT[c.quantity]!r})",
            )
        if c.quantity != ROLE_QUANTITY[c.role]:
            raise SweepFormatError(
                file,
                f"{where}/quantity",
                f"channel {c.name!r}: role {c.role!r} requires quantity {ROLE_QUANTITY[c.role]!r}, "
                f"got {c.quantity!r}",
            )
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise SweepFormatError(file, f"{where}/name", f"duplicate channel names {dup}")
    if not any(c.role == "input" for c in channels):
        raise SweepFormatError(file, f"{where}/role", "no input channel")
    if not any(c.role == "output" for c in channels):
        raise SweepFormatError(file, f"{where}/role", "no output channel")


def _dtype_name(a: np.ndarray) -> str:
    return str(a.dtype) if a.dtype.names is None else f"compound {a.dtype.names}"


def _validate_run(
    file: str,
    run: Run,
    channels: list[Channel],
    *,
    frf_rtol: float,
    period_rtol: float,
    exact_dtypes: bool,
) -> None:
    """Check one run's arrays. ``exact_dtypes`` demands the file dtypes (reader)."""
    base = f"/runs/{run.run_id}"
    if not isinstance(run.run_id, str) or not _RUN_ID.match(run.run_id):
        raise SweepFormatError(
            file, base, f"run id {run.run_id!r} must match [A-Za-z0-9_.+-]+ (it is a group name)"
        )
    speed = run.speed_rpm
    if isinstance(speed, bool) or not isinstance(speed, int | float | np.integer | np.floating):
        raise SweepFormatError(file, f"{base}@speed_rpm", f"speed_rpm {speed!r} is not a number")
    if not np.isfinite(speed):
        raise SweepFormatError(file, f"{base}@speed_rpm", f"speed_rpm {speed!r} is not finite")
    _check_text(file, f"{base}@notes", run.notes, "notes")

    n_in = sum(c.role == "input" for c in channels)
    n_out = sum(c.role == "output" for c in channels)
    n_chan = len(channels)

    want = {
        "frequency": ("f", np.float64),
        "input_phasor": ("c", np.complex128),
        "output_phasor": ("c", np.complex128),
        "output_var": ("f", np.float64),
        "n_periods": ("i", np.int32),
        "frf": ("c", np.complex128),
    }
    arrays: dict[str, np.ndarray] = {}
    for name, (kind, dt) in want.items():
        a = getattr(run, name)
        if a is None:
            raise SweepFormatError(file, f"{base}/{name}", "missing dataset")
        a = np.asarray(a)
        if exact_dtypes:
            if a.dtype != dt:
                raise SweepFormatError(
                    file, f"{base}/{name}", f"wrong dtype {_dtype_name(a)}, expected {np.dtype(dt)}"
                )
        else:
            ok = np.can_cast(a.dtype, dt, casting="safe") or (kind == "i" and a.dtype.kind in "iu")
            if not ok:
                raise SweepFormatError(
                    file, f"{base}/{name}", f"dtype {_dtype_name(a)} cannot be stored as {dt}"
                )
        arrays[name] = a

    freq = arrays["frequency"]
    if freq.ndim != 1 or freq.shape[0] < 1:
        raise SweepFormatError(
            file, f"{base}/frequency", f"wrong shape {freq.shape}, expected (f,) with f >= 1"
        )
    nf = freq.shape[0]
    shapes = {
        "input_phasor": (nf, n_in),
        "output_phasor": (nf, n_out),
        "output_var": (nf, n_out),
        "n_periods": (nf,),
        "frf": (nf, n_out, n_in),
    }
    for name, shp in shapes.items():
        if arrays[name].shape != shp:
            raise SweepFormatError(
                file,
                f"{base}/{name}",
                f"wrong shape {arrays[name].shape}, expected {shp} "
                f"(f={nf}, n_in={n_in}, n_out={n_out} from /channels)",
            )
    for name in ("frequency", "input_phasor", "output_phasor", "output_var", "frf"):
        bad = ~np.isfinite(arrays[name])
        if np.any(bad):
            idx = tuple(int(i) for i in np.argwhere(bad)[0])
            raise SweepFormatError(
                file,
                f"{base}/{name}",
                f"non-finite value at index {idx} ({int(bad.sum())} non-finite in total)",
            )
    if np.any(freq <= 0):
        i = int(np.argmax(freq <= 0))
        raise SweepFormatError(
            file, f"{base}/frequency", f"frequency must be > 0 Hz, got {float(freq[i]):.9g} at index {i}"
        )
    d = np.diff(freq)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0))
        raise SweepFormatError(
            file,
            f"{base}/frequency",
            f"frequency not strictly increasing at index {i + 1} "
            f"({float(freq[i]):.9g} Hz then {float(freq[i + 1]):.9g} Hz)",
        )
    inp = arrays["input_phasor"]
    zero = inp == 0
    if np.any(zero):
        k, i = (int(v) for v in np.argwhere(zero)[0])
        raise SweepFormatError(
            file,
            f"{base}/input_phasor",
            f"zero input phasor at index ({k}, {i}), frequency {float(freq[k]):.9g} Hz",
        )
    var = arrays["output_var"]
    if np.any(var < 0):
        k, o = (int(v) for v in np.argwhere(var < 0)[0])
        raise SweepFormatError(
            file, f"{base}/output_var", f"negative variance {float(var[k, o]):.9g} at index ({k}, {o})"
        )
    nper = arrays["n_periods"]
    if np.any(nper < 1):
        k = int(np.argmax(nper < 1))
        raise SweepFormatError(
            file, f"{base}/n_periods", f"n_periods must be >= 1, got {int(nper[k])} at index {k}"
        )
    out = arrays["output_phasor"]
    expected = out.astype(np.complex128)[:, :, None] / inp.astype(np.complex128)[:, None, :]
    frf = arrays["frf"].astype(np.complex128)
    err = np.abs(frf - expected)
    tol = frf_rtol * np.maximum(np.abs(expected), np.abs(frf))
    bad = err > tol
    if np.any(bad):
        k, o, i = (int(v) for v in np.argwhere(bad)[0])
        rel = err[k, o, i] / max(abs(expected[k, o, i]), 1e-300)
        raise SweepFormatError(
            file,
            f"{base}/frf",
            f"frf inconsistent with output_phasor/input_phasor at index ({k}, {o}, {i}), "
            f"frequency {float(freq[k]):.9g} Hz: relative difference {rel:.3g} > {frf_rtol:g}",
        )

    if run.period_phasor is not None:
        _validate_periods(
            file, base, run.period_phasor, arrays, n_in, n_chan, channels, exact_dtypes, period_rtol
        )


def _validate_periods(
    file: str,
    base: str,
    pp_in: np.ndarray,
    arrays: dict[str, np.ndarray],
    n_in: int,
    n_chan: int,
    channels: list[Channel],
    exact_dtypes: bool,
    rtol: float,
) -> None:
    where = f"{base}/period_phasor"
    pp = np.asarray(pp_in)
    if exact_dtypes and pp.dtype != np.complex128:
        raise SweepFormatError(file, where, f"wrong dtype {_dtype_name(pp)}, expected complex128")
    if not exact_dtypes and not np.can_cast(pp.dtype, np.complex128, casting="safe"):
        raise SweepFormatError(file, where, f"dtype {_dtype_name(pp)} cannot be stored as complex128")
    nf = arrays["frequency"].shape[0]
    nper = arrays["n_periods"].astype(np.int64)
    if pp.ndim != 3 or pp.shape[0] != nf or pp.shape[2] != n_chan or pp.shape[1] < nper.max():
        raise SweepFormatError(
            file,
            where,
            f"wrong shape {pp.shape}, expected ({nf}, p >= {int(nper.max())}, {n_chan})",
        )
    pp = pp.astype(np.complex128)
    k_idx = np.arange(pp.shape[1])[None, :]
    inside = k_idx < nper[:, None]  # (f, p)
    fin = np.isfinite(pp).all(axis=2)
    nan = (np.isnan(pp.real) | np.isnan(pp.imag)).all(axis=2)
    if np.any(inside & ~fin):
        k, p = (int(v) for v in np.argwhere(inside & ~fin)[0])
        raise SweepFormatError(
            file, where, f"non-finite value at index ({k}, {p}, :) within n_periods={nper[k]}"
        )
    if np.any(~inside & ~nan):
        k, p = (int(v) for v in np.argwhere(~inside & ~nan)[0])
        raise SweepFormatError(
            file, where, f"padding at index ({k}, {p}, :) beyond n_periods={nper[k]} is not NaN"
        )
    in_cols = [j for j, c in enumerate(channels) if c.role == "input"]
    out_cols = [j for j, c in enumerate(channels) if c.role == "output"]
    w = inside[:, :, None]
    x = np.where(w, pp, 0)
    mean = x.sum(axis=1) / nper[:, None]
    for cols, name in ((in_cols, "input_phasor"), (out_cols, "output_phasor")):
        stored = arrays[name].astype(np.complex128)
        scale = np.max(np.abs(x[:, :, cols]), axis=1)
        bad = np.abs(mean[:, cols] - stored) > rtol * scale + 1e-300
        if np.any(bad):
            k, c = (int(v) for v in np.argwhere(bad)[0])
            raise SweepFormatError(
                file,
                where,
                f"mean over periods at index ({k}, :, {cols[c]}) differs from {name} "
                f"(relative tolerance {rtol:g})",
            )
    dev = np.where(w, pp - mean[:, None, :], 0)
    ss = (np.abs(dev[:, :, out_cols]) ** 2).sum(axis=1)
    n = nper[:, None].astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.where(n > 1, ss / (n * (n - 1)), np.nan)
    stored_var = arrays["output_var"].astype(np.float64)
    scale = (np.max(np.abs(x[:, :, out_cols]), axis=1) ** 2) / n
    check = n[:, 0] > 1
    bad = (np.abs(var - stored_var) > 1e3 * rtol * scale + 1e-300) & check[:, None]
    if np.any(bad):
        k, o = (int(v) for v in np.argwhere(bad)[0])
        raise SweepFormatError(
            file,
            where,
            f"period-to-period variance of the mean at index ({k}, {o}) = {float(var[k, o]):.9g} differs "
            f"from output_var = {stored_var[k, o]!r}",
        )


def validate_sweep(
    sweep: Sweep,
    file: str | os.PathLike[str] = "<memory>",
    *,
    frf_rtol: float = FRF_RTOL,
    period_rtol: float = PERIOD_RTOL,
) -> None:
    """Validate an in-memory sweep; raise :class:`SweepFormatError` on the first problem."""
    f = str(file)
    _validate_header(f, sweep.rig_id, sweep.source, sweep.generator, sweep.created_utc)
    _validate_channels(f, "/channels", list(sweep.channels))
    if len(sweep.runs) == 0:
        raise SweepFormatError(f, "/runs", "no runs")
    for key, run in sweep.runs.items():
        if key != run.run_id:
            raise SweepFormatError(f, f"/runs/{key}", f"dict key {key!r} != run_id {run.run_id!r}")
        _validate_run(
            f,
            run,
            list(sweep.channels),
            frf_rtol=frf_rtol,
            period_rtol=period_rtol,
            exact_dtypes=False,
        )


# --------------------------------------------------------------------------------------------
# reader
# --------------------------------------------------------------------------------------------


def _attr(file: str, obj: h5py.HLObject, name: str, where: str) -> Any:
    if name not in obj.attrs:
        raise SweepFormatError(file, f"{where}@{name}", "missing attribute")
    try:
        return obj.attrs[name]
    except Exception as exc:  # unreadable attribute: report, do not guess
        raise SweepFormatError(file, f"{where}@{name}", f"unreadable attribute: {exc}") from exc


def _read_ds(file: str, grp: h5py.Group, name: str, where: str) -> np.ndarray:
    path = f"{where}/{name}"
    if name not in grp:
        raise SweepFormatError(file, path, "missing dataset")
    obj = grp.get(name)
    if not isinstance(obj, h5py.Dataset):
        raise SweepFormatError(file, path, f"expected a dataset, found {type(obj).__name__}")
    try:
        if obj.dtype.kind in "OS" or h5py.check_string_dtype(obj.dtype) is not None:
            return np.asarray(obj.asstr()[()], dtype=object)
        return np.asarray(obj[()])
    except Exception as exc:
        raise SweepFormatError(file, path, f"unreadable dataset (truncated or corrupt?): {exc}") from exc


def _as_text_array(file: str, path: str, a: np.ndarray, n: int) -> list[str]:
    if a.ndim != 1 or a.shape[0] != n:
        raise SweepFormatError(file, path, f"wrong shape {a.shape}, expected ({n},)")
    return [_check_text(file, path, v, "value") for v in a.tolist()]


def _read_channels(file: str, h5: h5py.File) -> list[Channel]:
    if "channels" not in h5:
        raise SweepFormatError(file, "/channels", "missing dataset")
    obj = h5["channels"]
    cols: dict[str, np.ndarray] = {}
    if isinstance(obj, h5py.Group):
        for fld in CHANNEL_FIELDS:
            cols[fld] = _read_ds(file, obj, fld, "/channels")
        n = cols["name"].shape[0] if cols["name"].ndim == 1 else -1
        if n < 0:
            raise SweepFormatError(file, "/channels/name", f"wrong shape {cols['name'].shape}")
        paths = {fld: f"/channels/{fld}" for fld in CHANNEL_FIELDS}
    elif isinstance(obj, h5py.Dataset) and obj.dtype.names is not None:
        missing = [fld for fld in CHANNEL_FIELDS if fld not in obj.dtype.names]
        if missing:
            raise SweepFormatError(file, "/channels", f"compound table lacks fields {missing}")
        try:
            table = obj[()]
        except Exception as exc:
            raise SweepFormatError(file, "/channels", f"unreadable: {exc}") from exc
        if table.ndim != 1:
            raise SweepFormatError(file, "/channels", f"wrong shape {table.shape}, expected (n,)")
        n = table.shape[0]
        cols = {fld: np.asarray(table[fld]) for fld in CHANNEL_FIELDS}
        paths = {fld: f"/channels[{fld}]" for fld in CHANNEL_FIELDS}
    else:
        raise SweepFormatError(file, "/channels", "expected a group of 1-D datasets or a compound dataset")
    text = {fld: _as_text_array(file, paths[fld], cols[fld], n) for fld in CHANNEL_FIELDS if fld != "node"}
    node = cols["node"]
    if node.ndim != 1 or node.shape[0] != n:
        raise SweepFormatError(file, paths["node"], f"wrong shape {node.shape}, expected ({n},)")
    if node.dtype.kind not in "iu":
        raise SweepFormatError(
            file, paths["node"], f"wrong dtype {_dtype_name(node)}, expected an integer type"
        )
    chans = [
        Channel(
            name=text["name"][i],
            role=text["role"][i],
            node=int(node[i]),
            direction=text["direction"][i],
            quantity=text["quantity"][i],
            unit=text["unit"][i],
        )
        for i in range(n)
    ]
    _validate_channels(file, "/channels", chans)
    return chans


def read_sweep(
    path: str | os.PathLike[str],
    *,
    frf_rtol: float = FRF_RTOL,
    period_rtol: float = PERIOD_RTOL,
) -> Sweep:
    """Open, validate and load a sweep file; raise :class:`SweepFormatError` if it is not valid."""
    file = str(path)
    if not os.path.exists(file):
        raise SweepFormatError(file, "/", "no such file")
    if os.path.isdir(file):
        raise SweepFormatError(file, "/", "is a directory, not a sweep file")
    try:
        is_h5 = h5py.is_hdf5(file)
    except Exception as exc:
        raise SweepFormatError(file, "/", f"cannot read file: {exc}") from exc
    if not is_h5:
        raise SweepFormatError(file, "/", "not an HDF5 file (no HDF5 signature)")
    try:
        h5 = h5py.File(file, "r")
    except Exception as exc:
        raise SweepFormatError(file, "/", f"cannot open as HDF5 (truncated or corrupt file): {exc}") from exc
    with h5:
        schema = _check_text(file, "/@schema", _attr(file, h5, "schema", ""), "schema")
        if schema != SCHEMA:
            raise SweepFormatError(file, "/@schema", f"schema {schema!r}, expected {SCHEMA!r}")
        ver = _attr(file, h5, "schema_version", "")
        if isinstance(ver, np.ndarray) and ver.shape in ((), (1,)):
            ver = ver.reshape(()).item() if ver.dtype.kind in "iu" else ver
        if isinstance(ver, bool) or not isinstance(ver, int | np.integer):
            raise SweepFormatError(file, "/@schema_version", f"schema_version {ver!r} is not an integer")
        if int(ver) != SCHEMA_VERSION:
            raise SweepFormatError(
                file,
                "/@schema_version",
                f"unknown schema_version {int(ver)} (this reader knows {SCHEMA_VERSION})",
            )
        exc_attr = _check_text(file, "/@excitation", _attr(file, h5, "excitation", ""), "excitation")
        if exc_attr != EXCITATION:
            raise SweepFormatError(file, "/@excitation", f"excitation {exc_attr!r}, expected {EXCITATION!r}")
        conv = _check_text(
            file, "/@phasor_convention", _attr(file, h5, "phasor_convention", ""), "convention"
        )
        if conv != PHASOR_CONVENTION:
            raise SweepFormatError(
                file,
                "/@phasor_convention",
                f"phasor_convention {conv!r}, expected {PHASOR_CONVENTION!r}",
            )
        rig_id = _check_text(file, "/@rig_id", _attr(file, h5, "rig_id", ""), "rig_id")
        source = _check_text(file, "/@source", _attr(file, h5, "source", ""), "source")
        generator = _check_text(file, "/@generator", _attr(file, h5, "generator", ""), "generator")
        created = _check_text(file, "/@created_utc", _attr(file, h5, "created_utc", ""), "created_utc")
        _validate_header(file, rig_id, source, generator, created)
        channels = _read_channels(file, h5)

        if "runs" not in h5:
            raise SweepFormatError(file, "/runs", "missing group")
        runs_grp = h5["runs"]
        if not isinstance(runs_grp, h5py.Group):
            raise SweepFormatError(file, "/runs", "expected a group")
        if len(runs_grp) == 0:
            raise SweepFormatError(file, "/runs", "no runs")
        runs: dict[str, Run] = {}
        for run_id in runs_grp:
            where = f"/runs/{run_id}"
            g = runs_grp.get(run_id)
            if not isinstance(g, h5py.Group):
                raise SweepFormatError(file, where, "expected a group (one per run)")
            speed = _attr(file, g, "speed_rpm", where)
            if isinstance(speed, np.ndarray) and speed.shape in ((), (1,)):
                speed = speed.reshape(()).item()
            if isinstance(speed, np.generic):
                speed = speed.item()
            notes = ""
            if "notes" in g.attrs:
                notes = _check_text(file, f"{where}@notes", _attr(file, g, "notes", where), "notes")
            data = {name: _read_ds(file, g, name, where) for name in RUN_DATASETS}
            pp = _read_ds(file, g, "period_phasor", where) if "period_phasor" in g else None
            run = Run(
                run_id=run_id,
                speed_rpm=speed,
                frequency=data["frequency"],
                input_phasor=data["input_phasor"],
                output_phasor=data["output_phasor"],
                output_var=data["output_var"],
                n_periods=data["n_periods"],
                frf=data["frf"],
                period_phasor=pp,
                notes=notes,
            )
            _validate_run(
                file,
                run,
                channels,
                frf_rtol=frf_rtol,
                period_rtol=period_rtol,
                exact_dtypes=True,
            )
            run.speed_rpm = float(speed)
            runs[run_id] = run
    return Sweep(
        rig_id=rig_id,
        source=source,
        generator=generator,
        created_utc=created,
        channels=channels,
        runs=runs,
    )


# --------------------------------------------------------------------------------------------
# writer
# --------------------------------------------------------------------------------------------


def _new_group(parent: h5py.Group, name: str) -> h5py.Group:
    """Create a group with link/attribute creation order tracked and no object timestamps."""
    gcpl = h5py.h5p.create(h5py.h5p.GROUP_CREATE)
    gcpl.set_link_creation_order(h5py.h5p.CRT_ORDER_TRACKED | h5py.h5p.CRT_ORDER_INDEXED)
    gcpl.set_attr_creation_order(h5py.h5p.CRT_ORDER_TRACKED | h5py.h5p.CRT_ORDER_INDEXED)
    gcpl.set_obj_track_times(False)
    gid = h5py.h5g.create(parent.id, name.encode("utf-8"), gcpl=gcpl)
    return h5py.Group(gid)


def _put(grp: h5py.Group, name: str, data: np.ndarray) -> None:
    grp.create_dataset(name, data=data, track_times=False)


def _publish(tmp: str, path: str, force: bool) -> None:
    """Move a finished temp file onto ``path`` atomically (no overwrite unless ``force``)."""
    if force:
        os.replace(tmp, path)
    else:
        try:
            os.link(tmp, path)  # atomic create-if-absent
        except FileExistsError:
            raise FileExistsError(
                f"{path}: exists; refusing to overwrite (pass force=True / --force)"
            ) from None
        except OSError:
            # file system without hard links: best effort check-then-rename
            if os.path.exists(path):
                raise FileExistsError(
                    f"{path}: exists; refusing to overwrite (pass force=True / --force)"
                ) from None
            os.replace(tmp, path)
        else:
            os.unlink(tmp)
    dir_fd = None
    with contextlib.suppress(OSError):
        dir_fd = os.open(os.path.dirname(os.path.abspath(path)) or ".", os.O_RDONLY)
        os.fsync(dir_fd)
    if dir_fd is not None:
        os.close(dir_fd)


def _fsync_path(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_target(path: str | os.PathLike[str], force: bool = False, suffix: str = ""):
    """Yield a temp path in the target folder; on success fsync and publish it atomically.

    Refuses (``FileExistsError``) before doing any work if ``path`` exists and not ``force``.
    """
    target = os.fspath(path)
    if os.path.exists(target) and not force:
        raise FileExistsError(f"{target}: exists; refusing to overwrite (pass force=True / --force)")
    folder = os.path.dirname(os.path.abspath(target))
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=suffix, dir=folder)
    umask_mode(tmp)
    os.close(fd)
    try:
        yield tmp
        _fsync_path(tmp)
        _publish(tmp, target, force)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_sweep(sweep: Sweep, path: str | os.PathLike[str], force: bool = False) -> None:
    """Validate and write ``sweep`` atomically (temp file in the same folder, fsync, rename).

    Deterministic: the content depends only on ``sweep`` (``created_utc`` comes from the caller),
    no object timestamps are stored, so two writes of the same sweep are byte-identical.
    Raises ``FileExistsError`` if ``path`` exists and ``force`` is false.
    """
    target = os.fspath(path)
    validate_sweep(sweep, target)
    str_dt = h5py.string_dtype("utf-8")
    with atomic_target(target, force=force, suffix=".h5") as tmp:
        with h5py.File(tmp, "w", track_order=True, libver=("earliest", "v110")) as h5:
            h5.attrs["schema"] = SCHEMA
            h5.attrs["schema_version"] = np.int32(SCHEMA_VERSION)
            h5.attrs["rig_id"] = sweep.rig_id
            h5.attrs["created_utc"] = sweep.created_utc
            h5.attrs["excitation"] = EXCITATION
            h5.attrs["phasor_convention"] = PHASOR_CONVENTION
            h5.attrs["source"] = sweep.source
            h5.attrs["generator"] = sweep.generator
            ch = _new_group(h5, "channels")
            for fld in CHANNEL_FIELDS:
                vals = [getattr(c, fld) for c in sweep.channels]
                if fld == "node":
                    _put(ch, fld, np.asarray(vals, dtype=np.int32))
                else:
                    _put(ch, fld, np.asarray(vals, dtype=str_dt))
            runs = _new_group(h5, "runs")
            for run_id, run in sweep.runs.items():
                g = _new_group(runs, run_id)
                g.attrs["speed_rpm"] = np.float64(run.speed_rpm)
                if run.notes:
                    g.attrs["notes"] = run.notes
                _put(g, "frequency", np.asarray(run.frequency, dtype=np.float64))
                _put(g, "input_phasor", np.asarray(run.input_phasor, dtype=np.complex128))
                _put(g, "output_phasor", np.asarray(run.output_phasor, dtype=np.complex128))
                _put(g, "output_var", np.asarray(run.output_var, dtype=np.float64))
                _put(g, "n_periods", np.asarray(run.n_periods, dtype=np.int32))
                _put(g, "frf", np.asarray(run.frf, dtype=np.complex128))
                if run.period_phasor is not None:
                    _put(g, "period_phasor", np.asarray(run.period_phasor, dtype=np.complex128))


def sweep_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 hex digest of the file bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


# --------------------------------------------------------------------------------------------
# comparison
# --------------------------------------------------------------------------------------------


def _bits_equal(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Element-wise bit-for-bit equality (NaN == NaN with equal payload, 0.0 != -0.0)."""
    a = np.ascontiguousarray(a)
    b = np.ascontiguousarray(b)
    if a.dtype.kind == "c":
        a = a.view(a.real.dtype).reshape(*a.shape, 2)
        b = b.view(b.real.dtype).reshape(*b.shape, 2)
        return _bits_equal(a, b).all(axis=-1)
    width = a.dtype.itemsize
    ui = {1: np.uint8, 2: np.uint16, 4: np.uint32, 8: np.uint64}[width]
    return a.view(ui) == b.view(ui)


def _compare_array(where: str, a: np.ndarray | None, b: np.ndarray | None) -> list[str]:
    if a is None and b is None:
        return []
    if a is None or b is None:
        return [f"{where}: present in {'b' if a is None else 'a'} only"]
    a = np.asarray(a)
    b = np.asarray(b)
    if a.dtype != b.dtype:
        return [f"{where}: dtype {a.dtype} != {b.dtype}"]
    if a.shape != b.shape:
        return [f"{where}: shape {a.shape} != {b.shape}"]
    eq = _bits_equal(a, b)
    n = int(eq.size - np.count_nonzero(eq))
    if n == 0:
        return []
    msg = f"{where}: {n} of {eq.size} elements differ"
    if a.dtype.kind in "fciu":
        with np.errstate(invalid="ignore", over="ignore"):
            d = np.abs(a.astype(np.complex128) - b.astype(np.complex128))
        if np.any(np.isfinite(d)):
            msg += f" (max abs difference {np.nanmax(d):.6g})"
        first = tuple(int(i) for i in np.argwhere(~eq)[0])
        msg += f", first at index {first}"
    return [msg]


def compare_sweeps(a: Sweep, b: Sweep, ignore: Iterable[str] = ()) -> list[str]:
    """Differences between two sweeps, bit for bit on arrays; empty list if identical.

    ``ignore`` may name header fields to skip (e.g. ``("created_utc", "generator")``).
    """
    skip = set(ignore)
    diffs: list[str] = []
    for fld in ("rig_id", "source", "generator", "created_utc"):
        if fld in skip:
            continue
        va, vb = getattr(a, fld), getattr(b, fld)
        if va != vb:
            diffs.append(f"/@{fld}: {va!r} != {vb!r}")
    if list(a.channels) != list(b.channels):
        diffs.append(f"/channels: {a.channels!r} != {b.channels!r}")
    ka, kb = list(a.runs), list(b.runs)
    for k in ka:
        if k not in b.runs:
            diffs.append(f"/runs/{k}: in a only")
    for k in kb:
        if k not in a.runs:
            diffs.append(f"/runs/{k}: in b only")
    common = [k for k in ka if k in b.runs]
    if [k for k in ka if k in common] != [k for k in kb if k in common]:
        diffs.append(f"/runs: order differs ({ka} vs {kb})")
    for k in common:
        ra, rb = a.runs[k], b.runs[k]
        base = f"/runs/{k}"
        sa, sb = np.float64(ra.speed_rpm), np.float64(rb.speed_rpm)
        if not _bits_equal(np.asarray(sa), np.asarray(sb)):
            diffs.append(f"{base}@speed_rpm: {ra.speed_rpm!r} != {rb.speed_rpm!r}")
        if ra.notes != rb.notes:
            diffs.append(f"{base}@notes: {ra.notes!r} != {rb.notes!r}")
        for name in (*RUN_DATASETS, "period_phasor"):
            diffs += _compare_array(f"{base}/{name}", getattr(ra, name), getattr(rb, name))
    return diffs


def compare_sweep_files(
    a: str | os.PathLike[str], b: str | os.PathLike[str], ignore: Iterable[str] = ()
) -> list[str]:
    """:func:`compare_sweeps` on two files (both are validated on read)."""
    return compare_sweeps(read_sweep(a), read_sweep(b), ignore=ignore)


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
    "EXCITATION",
    "PHASOR_CONVENTION",
    "SCHEMA",
    "SCHEMA_VERSION",
    "Channel",
    "FrfTable",
    "Run",
    "Sweep",
    "SweepFormatError",
    "atomic_target",
    "compare_sweep_files",
    "compare_sweeps",
    "read_sweep",
    "sweep_from_mapping",
    "sweep_sha256",
    "utc_now_iso",
    "validate_sweep",
    "write_sweep",
]

