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

from rotorcheck.errors import InputError, check_rig_id
from rotorcheck.sweep.format import (
    DIRECTIONS,
    FRF_ONLY_DATASETS,
    QUANTITY_UNIT,
    ROLE_QUANTITY,
    ROLES,
    RUN_DATASETS,
    SCHEMA_VERSION_V1,
    SCHEMA_VERSION_V2,
    SCHEMA_VERSION_V3,
    SIDEBAND_ATTRS,
    SOURCES,
    Channel,
    Run,
    Sweep,
    SweepFormatError,
    ls_frf,
    noise_source_problem,
    sweep_schema_version,
)

#: Default relative tolerance of the ``frf == output / input`` consistency check.
FRF_RTOL = 1e-9
#: Default relative tolerance of the ``period_phasor`` vs. mean/variance consistency check.
PERIOD_RTOL = 1e-9
#: Version 2: X (n_in x n_exc) is rank-deficient where its smallest singular value is <= this times
#: its largest (two patterns the same up to scale, or an input no pattern drives).
RANK_RCOND = 1e-10

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
    try:
        check_rig_id(rig, file, "/@rig_id")
    except InputError as exc:  # a rig_id names a bundled rig, never a file elsewhere on disk
        raise SweepFormatError(file, "/@rig_id", exc.message) from None
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


#: file dataset -> (Run attribute, dtype kind, dtype, has the pattern axis)
_RUN_ARRAYS: dict[str, tuple[str, str, type, bool]] = {
    "frequency": ("frequency", "f", np.float64, False),
    "input_phasor": ("input_phasor_exc", "c", np.complex128, True),
    "output_phasor": ("output_phasor_exc", "c", np.complex128, True),
    "output_var": ("output_var_exc", "f", np.float64, True),
    "input_var": ("input_var_exc", "f", np.float64, True),
    "n_periods": ("n_periods_exc", "i", np.int32, True),
    "frf": ("frf", "c", np.complex128, False),
    "frf_var": ("frf_var", "f", np.float64, False),
}
_PHASOR_REQUIRED = ("input_phasor", "output_phasor", "output_var", "n_periods")


def _drop_axis1(t: tuple[int, ...]) -> tuple[int, ...]:
    return t[:1] + t[2:] if len(t) >= 2 else t


def validate_run(
    file: str,
    run: Run,
    channels: list[Channel],
    *,
    frf_rtol: float,
    period_rtol: float,
    exact_dtypes: bool,
    version: int | None = None,
) -> None:
    """Check one run's arrays. ``exact_dtypes`` demands the file dtypes (reader).

    ``version`` is the file's schema version (default: 2 if the run needs it, else 1). In version 1
    the run has one pattern and shapes and indices are reported without the pattern axis; the frf
    must equal ``output_phasor / input_phasor`` (relative ``frf_rtol``) and no input phasor may be
    zero. In version 2 the input matrix X (n_in x n_exc) must have full row rank at every frequency
    (smallest singular value > ``RANK_RCOND`` times the largest) and, per frequency ``k`` and output
    ``o``, ``max_i |frf[k, o, i] - (Y X^+)[o, i]| <= frf_rtol cond(X_k) max(max_i |(Y X^+)[o, i]|,
    max_i |frf[k, o, i]|)`` (the rounding of an independent least-squares solve grows with the
    condition number of X; with one input and one pattern this is the version-1 rule).
    """
    base = f"/runs/{run.run_id}"
    if version is None:
        version = SCHEMA_VERSION_V3 if run.needs_v3 else SCHEMA_VERSION_V2 if run.needs_v2 else SCHEMA_VERSION_V1
    v1 = version == SCHEMA_VERSION_V1
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

    present = {name for name, (attr, *_rest) in _RUN_ARRAYS.items() if getattr(run, attr) is not None}
    frf_only = not any(name in present for name in _PHASOR_REQUIRED)
    if v1:
        extra: list[str] = [n for n in ("input_var", "frf_var") if n in present]
        if run.noise_source is not None:
            extra.append("noise_source")
        if extra and not frf_only:
            raise SweepFormatError(file, f"{base}/{extra[0]}", "not part of schema_version 1 (needs version 2)")
    if run.noise_source is not None:
        ns = check_text(file, f"{base}@noise_source", run.noise_source, "noise_source")
        why = noise_source_problem(ns)
        if why is not None:
            raise SweepFormatError(file, f"{base}@noise_source", why)
    if frf_only and not v1:
        if run.noise_source is None:
            raise SweepFormatError(
                file, f"{base}@noise_source",
                "missing attribute: an FRF-only run (no phasors) must say where frf_var came from "
                "('measured' or 'assumed: <rule>')",
            )
        for name, attr in (("input_var", "input_var_exc"), ("period_phasor", "period_phasor_exc")):
            if getattr(run, attr) is not None:
                raise SweepFormatError(
                    file, f"{base}/{name}", "an FRF-only run (no input/output phasors) cannot hold it"
                )
        required: tuple[str, ...] = FRF_ONLY_DATASETS
    else:
        required = RUN_DATASETS
    for name in required:
        if name not in present:
            raise SweepFormatError(file, f"{base}/{name}", "missing dataset")

    arrays: dict[str, np.ndarray] = {}
    for name, (attr, kind, dt, _pat) in _RUN_ARRAYS.items():
        if name not in present:
            continue
        a = np.asarray(getattr(run, attr))
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

    def show(name: str, t: tuple[int, ...]) -> tuple[int, ...]:
        """A shape or index as the file holds it (version 1: no pattern axis)."""
        return _drop_axis1(t) if v1 and _RUN_ARRAYS.get(name, ("", "", float, False))[3] else t

    freq = arrays["frequency"]
    if freq.ndim != 1 or freq.shape[0] < 1:
        raise SweepFormatError(
            file, f"{base}/frequency", f"wrong shape {freq.shape}, expected (f,) with f >= 1"
        )
    nf = freq.shape[0]
    n_exc = 0
    if not frf_only:
        ip = arrays["input_phasor"]
        n_exc = int(ip.shape[1]) if ip.ndim == 3 and not v1 else 1
        if not v1 and (ip.ndim != 3 or n_exc < 1):
            raise SweepFormatError(
                file, f"{base}/input_phasor",
                f"wrong shape {ip.shape}, expected (f={nf}, n_exc >= 1, n_in={n_in}): schema_version 2 "
                "stores the excitation-pattern axis second (a version-1 layout under schema_version 2?)",
            )
    shapes: dict[str, tuple[int, ...]] = {
        "input_phasor": (nf, n_exc, n_in),
        "output_phasor": (nf, n_exc, n_out),
        "output_var": (nf, n_exc, n_out),
        "input_var": (nf, n_exc, n_in),
        "n_periods": (nf, n_exc),
        "frf": (nf, n_out, n_in),
        "frf_var": (nf, n_out, n_in),
    }
    for name, shp in shapes.items():
        if name in arrays and arrays[name].shape != shp:
            if v1:
                counts = f"f={nf}, n_in={n_in}, n_out={n_out} from /channels"
            else:
                counts = f"f={nf}, n_exc={n_exc} from input_phasor, n_in={n_in}, n_out={n_out} from /channels"
            raise SweepFormatError(
                file,
                f"{base}/{name}",
                f"wrong shape {show(name, arrays[name].shape)}, expected {show(name, shp)} ({counts})",
            )
    for name in ("frequency", "input_phasor", "output_phasor", "output_var", "input_var", "frf", "frf_var"):
        if name not in arrays:
            continue
        bad = ~np.isfinite(arrays[name])
        if np.any(bad):
            idx = show(name, tuple(int(i) for i in np.argwhere(bad)[0]))
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
    for name in ("output_var", "input_var", "frf_var"):
        if name not in arrays:
            continue
        var = arrays[name]
        if np.any(var < 0):
            idx = tuple(int(v) for v in np.argwhere(var < 0)[0])
            raise SweepFormatError(
                file, f"{base}/{name}", f"negative variance {float(var[idx]):.9g} at index {show(name, idx)}"
            )
    _validate_sidebands(file, base, run, version, frf_only, nf, n_exc, n_out, exact_dtypes)
    if frf_only:
        return
    nper = arrays["n_periods"]
    if np.any(nper < 1):
        idx = tuple(int(v) for v in np.argwhere(nper < 1)[0])
        k = show("n_periods", idx)
        shown = k[0] if len(k) == 1 else k
        raise SweepFormatError(
            file, f"{base}/n_periods", f"n_periods must be >= 1, got {int(nper[idx])} at index {shown}"
        )
    inp = arrays["input_phasor"].astype(np.complex128)
    out = arrays["output_phasor"].astype(np.complex128)
    frf = arrays["frf"].astype(np.complex128)
    if v1:
        _check_frf_v1(file, base, freq, inp[:, 0], out[:, 0], frf, frf_rtol)
    else:
        in_names = [c.name for c in channels if c.role == "input"]
        cond = _check_rank(file, base, freq, inp, in_names)
        _check_frf_ls(file, base, freq, inp, out, frf, cond, frf_rtol)

    pp = run.period_phasor_exc
    if pp is not None:
        _validate_periods(
            file, base, np.asarray(pp), arrays, n_chan, channels, exact_dtypes, period_rtol, v1
        )


def _validate_sidebands(file: str, base: str, run: Run, version: int, frf_only: bool, nf: int, n_exc: int,
                        n_out: int, exact_dtypes: bool) -> None:
    """The version-3 sidebands: all three datasets or none, on a run with phasors; ``sideband_order`` (K,) distinct
    nonzero integers; ``sideband_phasor`` and ``sideband_var`` (f, n_exc, K, n_out), NaN at the same places (a tone
    not separable), the variances > 0 elsewhere."""
    given = {name: getattr(run, attr) for name, attr in SIDEBAND_ATTRS.items()}
    have = [name for name, a in given.items() if a is not None]
    if not have:
        return
    if version < SCHEMA_VERSION_V3:
        raise SweepFormatError(file, f"{base}/{have[0]}", f"not part of schema_version {version} (needs version 3)")
    if frf_only:
        raise SweepFormatError(file, f"{base}/{have[0]}", "an FRF-only run (no input/output phasors) cannot hold it")
    for name, a in given.items():
        if a is None:
            raise SweepFormatError(file, f"{base}/{name}", f"missing dataset (the sidebands need all of "
                                   f"{', '.join(SIDEBAND_ATTRS)})")
    kinds = {"sideband_order": (np.int32, "iu"), "sideband_phasor": (np.complex128, "c"),
             "sideband_var": (np.float64, "f")}
    arr = {name: np.asarray(a) for name, a in given.items()}
    for name, (dt, ok_kinds) in kinds.items():
        a = arr[name]
        if (exact_dtypes and a.dtype != dt) or a.dtype.kind not in ok_kinds:
            raise SweepFormatError(file, f"{base}/{name}", f"wrong dtype {dtype_name(a)}, expected {np.dtype(dt)}")
    order = arr["sideband_order"]
    if order.ndim != 1 or order.size < 1:
        raise SweepFormatError(file, f"{base}/sideband_order", f"wrong shape {order.shape}, expected (K,) with K >= 1")
    if np.any(order == 0) or np.unique(order).size != order.size:
        raise SweepFormatError(file, f"{base}/sideband_order",
                               f"orders must be distinct nonzero integers, got {order.tolist()}")
    if run.speed_rpm == 0:
        raise SweepFormatError(file, f"{base}/sideband_order", "a run at standstill (speed_rpm 0) has no sidebands")
    shp = (nf, n_exc, order.size, n_out)
    for name in ("sideband_phasor", "sideband_var"):
        if arr[name].shape != shp:
            raise SweepFormatError(file, f"{base}/{name}", f"wrong shape {arr[name].shape}, expected {shp} "
                                   f"(f={nf}, n_exc={n_exc}, K={order.size} from sideband_order, n_out={n_out})")
    ph, var = arr["sideband_phasor"], arr["sideband_var"]
    nan_ph, nan_var = np.isnan(ph), np.isnan(var)
    if np.any(nan_ph != nan_var):
        idx = tuple(int(v) for v in np.argwhere(nan_ph != nan_var)[0])
        raise SweepFormatError(file, f"{base}/sideband_var", f"NaN in one of sideband_phasor and sideband_var but "
                               f"not the other at index {idx} (NaN in both marks a tone that was not separable)")
    bad = ~nan_var & ~(np.isfinite(var) & (var > 0))
    bad |= ~nan_ph & ~np.isfinite(ph)
    if np.any(bad):
        idx = tuple(int(v) for v in np.argwhere(bad)[0])
        raise SweepFormatError(file, f"{base}/sideband_var", f"a sideband at index {idx} has phasor {ph[idx]} and "
                               f"variance {var[idx]}: the variance must be > 0 and both finite (or both NaN)")


def _check_frf_v1(
    file: str, base: str, freq: np.ndarray, inp: np.ndarray, out: np.ndarray, frf: np.ndarray, frf_rtol: float
) -> None:
    """Version 1: no zero input phasor; ``frf == output / input`` entry by entry."""
    zero = inp == 0
    if np.any(zero):
        k, i = (int(v) for v in np.argwhere(zero)[0])
        raise SweepFormatError(
            file,
            f"{base}/input_phasor",
            f"zero input phasor at index ({k}, {i}), frequency {float(freq[k]):.9g} Hz",
        )
    expected = out[:, :, None] / inp[:, None, :]
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


def _check_rank(file: str, base: str, freq: np.ndarray, inp: np.ndarray, in_names: list[str]) -> np.ndarray:
    """Version 2: X (n_in x n_exc) of full row rank at every frequency; returns cond(X) (f,)."""
    _nf, n_exc, n_in = inp.shape
    where = f"{base}/input_phasor"
    if n_exc < n_in:
        raise SweepFormatError(
            file, where,
            f"{n_exc} excitation pattern(s) for {n_in} inputs {in_names}: the input matrix X "
            f"(n_in x n_exc) cannot have full row rank (need n_exc >= n_in)",
        )
    x = np.swapaxes(inp, 1, 2)  # (f, n_in, n_exc)
    u, sv, _ = np.linalg.svd(x)  # sv (f, n_in) descending, u (f, n_in, n_in)
    smax, s_min = sv[:, 0], sv[:, -1]
    bad = ~(s_min > RANK_RCOND * smax)
    if np.any(bad):
        k = int(np.argmax(bad))
        zero_rows = [in_names[i] for i in range(n_in) if np.all(x[k, i] == 0)]
        zeros = [(e, in_names[i]) for e in range(n_exc) for i in range(n_in) if inp[k, e, i] == 0]
        if zero_rows:
            detail = f"input(s) {zero_rows} zero in every pattern (not driven)"
        else:
            null = np.abs(u[k, :, -1])
            dep = [in_names[i] for i in range(n_in) if null[i] > 1e-3 * null.max()]
            ratio = float(s_min[k] / smax[k]) if smax[k] > 0 else 0.0
            detail = (f"the rows of inputs {dep} are linearly dependent (smallest/largest singular value "
                      f"{ratio:.3g} <= {RANK_RCOND:g}): no pattern set separates them")
        if zeros:
            detail += "; zero input phasors at (pattern, input) " + ", ".join(f"({e}, {n!r})" for e, n in zeros)
        raise SweepFormatError(
            file, where,
            f"input matrix X (n_in x n_exc = {n_in} x {n_exc}) rank-deficient at frequency "
            f"{float(freq[k]):.9g} Hz (index {k}): {detail}",
        )
    return np.asarray(smax / s_min)


def _check_frf_ls(
    file: str, base: str, freq: np.ndarray, inp: np.ndarray, out: np.ndarray, frf: np.ndarray,
    cond: np.ndarray, frf_rtol: float,
) -> None:
    """Version 2: frf against ``Y X^+`` row by row (tolerance in :func:`validate_run`)."""
    expected = ls_frf(inp, out)
    err = np.abs(frf - expected).max(axis=2)  # (f, n_out)
    scale = np.maximum(np.abs(expected).max(axis=2), np.abs(frf).max(axis=2))
    tol = frf_rtol * cond[:, None] * scale
    bad = err > tol
    if np.any(bad):
        k, o = (int(v) for v in np.argwhere(bad)[0])
        i = int(np.argmax(np.abs(frf[k, o] - expected[k, o])))
        rel = err[k, o] / max(scale[k, o], 1e-300)
        raise SweepFormatError(
            file,
            f"{base}/frf",
            f"frf inconsistent with Y X^+ (output_phasor times the pseudo-inverse of input_phasor) at "
            f"index ({k}, {o}, {i}), frequency {float(freq[k]):.9g} Hz: relative difference {rel:.3g} "
            f"> {frf_rtol:g} x cond(X) = {float(frf_rtol * cond[k]):.3g}",
        )


def _validate_periods(
    file: str,
    base: str,
    pp_in: np.ndarray,
    arrays: dict[str, np.ndarray],
    n_chan: int,
    channels: list[Channel],
    exact_dtypes: bool,
    rtol: float,
    v1: bool,
) -> None:
    """Check period_phasor (f, n_exc, p, n_chan): shape, NaN padding past n_periods, mean and
    variance vs. the stored ones (version 1: (f, p, n_chan), shown without the pattern axis)."""
    where = f"{base}/period_phasor"
    pp = np.asarray(pp_in)
    if exact_dtypes and pp.dtype != np.complex128:
        raise SweepFormatError(file, where, f"wrong dtype {dtype_name(pp)}, expected complex128")
    if not exact_dtypes and not np.can_cast(pp.dtype, np.complex128, casting="safe"):
        raise SweepFormatError(file, where, f"dtype {dtype_name(pp)} cannot be stored as complex128")
    nf = arrays["frequency"].shape[0]
    ne = arrays["n_periods"].shape[1]
    nper4 = arrays["n_periods"].astype(np.int64)  # (f, n_exc)
    if pp.ndim != 4 or pp.shape[:2] != (nf, ne) or pp.shape[3] != n_chan or pp.shape[2] < nper4.max():
        shown = _drop_axis1(pp.shape) if v1 else pp.shape
        want = f"({nf}, p >= {int(nper4.max())}, {n_chan})" if v1 else (
            f"({nf}, {ne}, p >= {int(nper4.max())}, {n_chan})")
        raise SweepFormatError(file, where, f"wrong shape {shown}, expected {want}")

    def at(j: int, *rest: str) -> str:
        """Index of flat point j (= k n_exc + e) as the file shows it."""
        k, e = divmod(j, ne)
        head = [str(k)] if v1 else [str(k), str(e)]
        return "(" + ", ".join([*head, *rest]) + ")"

    p = pp.shape[2]
    pp = pp.astype(np.complex128).reshape(nf * ne, p, n_chan)
    nper = nper4.reshape(-1)
    k_idx = np.arange(p)[None, :]
    inside = k_idx < nper[:, None]  # (f n_exc, p)
    fin = np.isfinite(pp).all(axis=2)
    nan = (np.isnan(pp.real) | np.isnan(pp.imag)).all(axis=2)
    if np.any(inside & ~fin):
        j, q = (int(v) for v in np.argwhere(inside & ~fin)[0])
        raise SweepFormatError(
            file, where, f"non-finite value at index {at(j, str(q), ':')} within n_periods={nper[j]}"
        )
    if np.any(~inside & ~nan):
        j, q = (int(v) for v in np.argwhere(~inside & ~nan)[0])
        raise SweepFormatError(
            file, where, f"padding at index {at(j, str(q), ':')} beyond n_periods={nper[j]} is not NaN"
        )
    in_cols = [j for j, c in enumerate(channels) if c.role == "input"]
    out_cols = [j for j, c in enumerate(channels) if c.role == "output"]
    w = inside[:, :, None]
    x = np.where(w, pp, 0)
    mean = x.sum(axis=1) / nper[:, None]
    for cols, name in ((in_cols, "input_phasor"), (out_cols, "output_phasor")):
        stored = arrays[name].astype(np.complex128).reshape(nf * ne, -1)
        scale = np.max(np.abs(x[:, :, cols]), axis=1)
        bad = np.abs(mean[:, cols] - stored) > rtol * scale + 1e-300
        if np.any(bad):
            j, c = (int(v) for v in np.argwhere(bad)[0])
            raise SweepFormatError(
                file,
                where,
                f"mean over periods at index {at(j, ':', str(cols[c]))} differs from {name} "
                f"(relative tolerance {rtol:g})",
            )
    dev = np.where(w, pp - mean[:, None, :], 0)
    ss = (np.abs(dev[:, :, out_cols]) ** 2).sum(axis=1)
    n = nper[:, None].astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.where(n > 1, ss / (n * (n - 1)), np.nan)
    stored_var = arrays["output_var"].astype(np.float64).reshape(nf * ne, -1)
    scale = (np.max(np.abs(x[:, :, out_cols]), axis=1) ** 2) / n
    check = n[:, 0] > 1
    bad = (np.abs(var - stored_var) > 1e3 * rtol * scale + 1e-300) & check[:, None]
    if np.any(bad):
        j, o = (int(v) for v in np.argwhere(bad)[0])
        raise SweepFormatError(
            file,
            where,
            f"period-to-period variance of the mean at index {at(j, str(o))} = {float(var[j, o]):.9g} "
            f"differs from output_var = {stored_var[j, o]!r}",
        )


def validate_sweep(
    sweep: Sweep,
    file: str | os.PathLike[str] = "<memory>",
    *,
    frf_rtol: float = FRF_RTOL,
    period_rtol: float = PERIOD_RTOL,
) -> None:
    """Validate an in-memory sweep; raise :class:`SweepFormatError` on the first problem.

    The runs are checked against the version a writer would use (:func:`sweep_schema_version`)."""
    f = str(file)
    validate_header(f, sweep.rig_id, sweep.source, sweep.generator, sweep.created_utc)
    validate_channels(f, "/channels", list(sweep.channels))
    if len(sweep.runs) == 0:
        raise SweepFormatError(f, "/runs", "no runs")
    version = sweep_schema_version(sweep)
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
            version=version,
        )

__all__ = [
    "FRF_RTOL",
    "PERIOD_RTOL",
    "RANK_RCOND",
    "check_text",
    "dtype_name",
    "validate_channels",
    "validate_header",
    "validate_run",
    "validate_sweep",
]
