"""Checks of a sweep's content: header, channel table, run shapes, dtypes, values, consistency.

Shared by the reader (``exact_dtypes=True``: the file's dtypes must be the contract's) and the
writers (in-memory arrays that can be stored losslessly). Every failure raises
:class:`~rotorcheck.sweep.format.SweepFormatError` naming the file, the path inside it and the
reason.
"""

from __future__ import annotations

import datetime as _dt
import os
import re
from typing import Any

import numpy as np

from rotorcheck.sweep.format import (
    DIRECTIONS,
    QUANTITY_UNIT,
    ROLE_QUANTITY,
    ROLES,
    SOURCES,
    Channel,
    Run,
    Sweep,
    SweepFormatError,
)

#: Default relative tolerance of the ``frf == output / input`` consistency check.
FRF_RTOL = 1e-9
#: Default relative tolerance of the ``period_phasor`` vs. mean/variance consistency check.
PERIOD_RTOL = 1e-9

_ISO_Z = re.compile(r"^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d{1,9})?Z$")
_RUN_ID = re.compile(r"^[A-Za-z0-9_.+-]+$")


def check_text(file: str, where: str, value: Any, what: str) -> str:
    """``value`` as text (UTF-8 bytes are decoded); anything else is refused."""
    if isinstance(value, bytes | np.bytes_):
        try:
            value = bytes(value).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SweepFormatError(file, where, f"{what} is not valid UTF-8 text") from exc
    if not isinstance(value, str):
        raise SweepFormatError(file, where, f"{what} must be text, got {type(value).__name__}")
    return value


def validate_header(file: str, rig_id: Any, source: Any, generator: Any, created: Any) -> None:
    """Check the root attributes rig_id, source, generator and created_utc."""
    rig = check_text(file, "/@rig_id", rig_id, "rig_id")
    if not rig.strip():
        raise SweepFormatError(file, "/@rig_id", "rig_id is empty")
    src = check_text(file, "/@source", source, "source")
    if src not in SOURCES:
        raise SweepFormatError(file, "/@source", f"source {src!r} is not one of {SOURCES}")
    check_text(file, "/@generator", generator, "generator")
    cre = check_text(file, "/@created_utc", created, "created_utc")
    if not _ISO_Z.match(cre):
        raise SweepFormatError(
            file, "/@created_utc", f"created_utc {cre!r} is not ISO 8601 UTC 'YYYY-MM-DDTHH:MM:SSZ'"
        )
    try:
        _dt.datetime.strptime(cre[:19], "%Y-%m-%dT%H:%M:%S")
    except ValueError as exc:
        raise SweepFormatError(file, "/@created_utc", f"created_utc {cre!r}: {exc}") from exc


def validate_channels(file: str, where: str, channels: list[Channel]) -> None:
    """Check the channel table: fields, unit/quantity/role agreement, unique names, >= 1 in and out."""
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


def dtype_name(a: np.ndarray) -> str:
    """The dtype as a message shows it (compound types by their field names)."""
    return str(a.dtype) if a.dtype.names is None else f"compound {a.dtype.names}"


def validate_run(
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
    check_text(file, f"{base}@notes", run.notes, "notes")

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
                    file, f"{base}/{name}", f"wrong dtype {dtype_name(a)}, expected {np.dtype(dt)}"
                )
        else:
            ok = np.can_cast(a.dtype, dt, casting="safe") or (kind == "i" and a.dtype.kind in "iu")
            if not ok:
                raise SweepFormatError(
                    file, f"{base}/{name}", f"dtype {dtype_name(a)} cannot be stored as {dt}"
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
    """Check period_phasor: shape, NaN padding past n_periods, mean and variance vs. the stored ones."""
    where = f"{base}/period_phasor"
    pp = np.asarray(pp_in)
    if exact_dtypes and pp.dtype != np.complex128:
        raise SweepFormatError(file, where, f"wrong dtype {dtype_name(pp)}, expected complex128")
    if not exact_dtypes and not np.can_cast(pp.dtype, np.complex128, casting="safe"):
        raise SweepFormatError(file, where, f"dtype {dtype_name(pp)} cannot be stored as complex128")
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
    validate_header(f, sweep.rig_id, sweep.source, sweep.generator, sweep.created_utc)
    validate_channels(f, "/channels", list(sweep.channels))
    if len(sweep.runs) == 0:
        raise SweepFormatError(f, "/runs", "no runs")
    for key, run in sweep.runs.items():
        if key != run.run_id:
            raise SweepFormatError(f, f"/runs/{key}", f"dict key {key!r} != run_id {run.run_id!r}")
        validate_run(
            f,
            run,
            list(sweep.channels),
            frf_rtol=frf_rtol,
            period_rtol=period_rtol,
            exact_dtypes=False,
        )

__all__ = [
    "FRF_RTOL",
    "PERIOD_RTOL",
    "check_text",
    "dtype_name",
    "validate_channels",
    "validate_header",
    "validate_run",
    "validate_sweep",
]
