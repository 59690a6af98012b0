"""Bit-for-bit comparison of two sweeps (in memory or as files), versions 1 and 2.

Arrays are compared under their file names (``/runs/<id>/input_phasor`` ...). When both runs have
one pattern the single-pattern views are compared (indices as in a version-1 file); otherwise the
pattern-axis arrays (a one-pattern run against a several-pattern run differs in shape).
"""

from __future__ import annotations

import os
from collections.abc import Iterable

import numpy as np

from rotorcheck.sweep.format import PATTERN_ATTRS, RUN_DATASETS, RUN_OPTIONAL_V2, Run, Sweep
from rotorcheck.sweep.hdf5io import read_sweep


def _bits_equal(a: np.ndarray, b: np.ndarray) -> np.ndarray | np.bool_:
    """Element-wise bit-for-bit equality (NaN == NaN with equal payload, 0.0 != -0.0); a NumPy
    bool scalar for 0-d inputs."""
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
        if ra.noise_source != rb.noise_source:
            diffs.append(f"{base}@noise_source: {ra.noise_source!r} != {rb.noise_source!r}")
        single = ra.n_exc == 1 and rb.n_exc == 1
        for name in (*RUN_DATASETS, *RUN_OPTIONAL_V2):
            diffs += _compare_array(f"{base}/{name}", _array(ra, name, single), _array(rb, name, single))
    return diffs


def _array(run: Run, name: str, single: bool) -> np.ndarray | None:
    """Dataset ``name`` of ``run``: the pattern-axis array, or its single-pattern view."""
    if name not in PATTERN_ATTRS:
        return getattr(run, name)  # frequency, frf, frf_var
    a = getattr(run, PATTERN_ATTRS[name])
    if a is None or not single:
        return a
    return np.asarray(a)[:, 0]


def compare_sweep_files(
    a: str | os.PathLike[str], b: str | os.PathLike[str], ignore: Iterable[str] = ()
) -> list[str]:
    """:func:`compare_sweeps` on two files (both are validated on read)."""
    return compare_sweeps(read_sweep(a), read_sweep(b), ignore=ignore)

__all__ = ["compare_sweep_files", "compare_sweeps"]
