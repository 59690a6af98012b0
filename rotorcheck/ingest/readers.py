"""Readers of time recordings into :class:`~rotorcheck.ingest.record.TimeRecord` s.

Formats (by extension, or ``fmt``): MATLAB ``.mat`` v5 (scipy) and v7.3 (HDF5, h5py), NI ``.tdms``
(npTDMS), ``.wav`` (several channels, scipy), ``.csv`` (a time column or a given sample rate),
``.parquet`` (only when pyarrow is installed), UFF58 ``.uff``/``.unv`` function type 1 (time
response, pyuff) and ``.h5``/``.hdf5`` time series. HDF5, v7.3, TDMS, WAV and CSV are read on demand
(the record holds open files, a memory map or a line index; a step reads only its samples); mat v5,
Parquet and UFF58 are loaded whole.

Layouts: a channel is a 1-D numeric variable/dataset/column named by the channel map. The sample
rate is ``sample_rate_hz`` (or ``fs``; mat, HDF5 attribute), NI's ``wf_increment`` (TDMS), the WAV
header, UFF58's abscissa increment, a ``time`` vector/column (uniform; a gap splits the record) or
``sample_rate_hz`` given by the caller. The start time is ``start_s`` (or ``t0``), ``wf_start_offset``,
the first time value or UFF58's abscissa minimum, else 0 s.
"""

from __future__ import annotations

import io
import itertools
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rotorcheck.errors import InputError
from rotorcheck.ingest.record import Column, TimeRecord

__all__ = ["FORMATS", "detect_format", "open_record", "parquet_available"]

FORMATS = ("mat", "tdms", "wav", "csv", "parquet", "uff", "hdf5")
_EXT = {".mat": "mat", ".tdms": "tdms", ".wav": "wav", ".csv": "csv", ".parquet": "parquet", ".pq": "parquet",
        ".uff": "uff", ".unv": "uff", ".h5": "hdf5", ".hdf5": "hdf5"}
RATE_NAMES = ("sample_rate_hz", "fs")
START_NAMES = ("start_s", "t0")
TIME_NAMES = ("time", "t", "time_s")


def parquet_available() -> bool:
    """True when pyarrow can be imported (Parquet support is optional)."""
    try:
        import pyarrow  # noqa: F401  # lazy: an optional dependency, only to ask whether it is installed
    except ImportError:
        return False
    return True


def detect_format(path: str | os.PathLike[str], fmt: str | None = None) -> str:
    """The format name of ``path`` (``fmt`` wins), else an InputError listing the known extensions."""
    if fmt is not None:
        if fmt not in FORMATS:
            raise InputError(os.fspath(path), "format", f"unknown format {fmt!r} (known: {', '.join(FORMATS)})")
        return fmt
    ext = Path(path).suffix.lower()
    if ext not in _EXT:
        raise InputError(os.fspath(path), "format", f"unknown extension {ext!r} (known: {', '.join(sorted(_EXT))})")
    return _EXT[ext]


def open_record(path: str | os.PathLike[str], fmt: str | None = None, sample_rate_hz: float | None = None,
                group: str | None = None) -> list[TimeRecord]:
    """Open one recording: a list of uniformly sampled records (more than one only when the file's
    time column has gaps). ``sample_rate_hz``: for CSV/Parquet without a time column (overrides a
    file's own rate elsewhere only when the file states none); ``group``: the TDMS/HDF5 group."""
    p = os.fspath(path)
    if not os.path.exists(p):
        raise InputError(p, "", "no such file")
    kind = detect_format(p, fmt)
    readers: dict[str, Callable[[], list[TimeRecord]]] = {
        "mat": lambda: _mat(p, sample_rate_hz),
        "tdms": lambda: [_tdms(p, sample_rate_hz, group)],
        "wav": lambda: [_wav(p)],
        "csv": lambda: _csv(p, sample_rate_hz),
        "parquet": lambda: _parquet(p, sample_rate_hz),
        "uff": lambda: [_uff(p)],
        "hdf5": lambda: [_hdf5(p, sample_rate_hz, group)],
    }
    return readers[kind]()


# ---------------------------------------------------------------------------------------- helpers


def _rate(path: str, found: float | None, given: float | None, where: str) -> float:
    fs = found if found is not None else given
    if fs is None:
        raise InputError(path, where, "no sample rate: store sample_rate_hz (or a time vector) or give "
                                      "sample_rate_hz in the channel map")
    if not np.isfinite(fs) or fs <= 0:
        raise InputError(path, where, f"sample rate must be finite and > 0 Hz, got {fs!r}")
    return float(fs)


class _Slice:
    """Samples ``start:stop`` of a column (a segment of a record split at a gap)."""

    def __init__(self, col: Column, start: int, stop: int):
        self.col, self.start, self.stop = col, start, stop

    def __len__(self) -> int:
        return self.stop - self.start

    def __getitem__(self, key: slice) -> np.ndarray:
        a, b, _ = key.indices(len(self))
        return np.asarray(self.col[self.start + a : self.start + b])


class _Row:
    """Row ``k`` of a 2-D dataset (MATLAB v7.3 stores an n-vector as (1, n) or (n, 1))."""

    def __init__(self, ds: Any, transpose: bool):
        self.ds, self.t = ds, transpose

    def __len__(self) -> int:
        return int(self.ds.shape[0] if self.t else self.ds.shape[1])

    def __getitem__(self, key: slice) -> np.ndarray:
        return np.asarray(self.ds[key, 0] if self.t else self.ds[0, key])


def _from_time(path: str, time: Column, cols: dict[str, Column], closers: list[Callable[[], None]],
               block: int = 1 << 20) -> list[TimeRecord]:
    """Records from a time vector: the sample rate from its span, split where a step exceeds 1.5 dt;
    a non-increasing or irregular time is refused (InputError naming the file and the time)."""
    n = len(time)
    if n < 2:
        raise InputError(path, "time", "fewer than 2 samples")
    # median step of the first block: the nominal dt; gaps are steps > 1.5 dt
    head = np.asarray(time[0 : min(n, block)], dtype=np.float64)
    dt = float(np.median(np.diff(head)))
    if not dt > 0:
        raise InputError(path, "time", "time is not increasing")
    cuts = [0]
    for s in range(0, n - 1, block):
        t = np.asarray(time[s : min(n, s + block + 1)], dtype=np.float64)
        d = np.diff(t)
        bad = np.flatnonzero((d < 0.5 * dt) | (d > 1.5 * dt))
        for i in bad:
            if d[i] < 0.5 * dt:
                raise InputError(path, "time", f"t = {t[i]:.6f} s: time step {d[i]:.3g} s is not the sample "
                                               f"interval {dt:.3g} s (time must increase uniformly)")
            cuts.append(s + int(i) + 1)
    cuts.append(n)
    out = []
    for a, b in itertools.pairwise(cuts):
        t0 = float(np.asarray(time[a : a + 1])[0])
        t1 = float(np.asarray(time[b - 1 : b])[0])
        fs = (b - a - 1) / (t1 - t0) if b - a > 1 else 1.0 / dt
        seg = cols if (a, b) == (0, n) else {k: _Slice(c, a, b) for k, c in cols.items()}
        out.append(TimeRecord(path, fs, t0, seg, closers if a == 0 else []))
    return out


# ---------------------------------------------------------------------------------------- formats


def _mat(path: str, fs_given: float | None) -> list[TimeRecord]:
    if h5py.is_hdf5(path):  # MATLAB v7.3
        f = h5py.File(path, "r")
        cols: dict[str, Column] = {}
        scalars: dict[str, float] = {}
        for name, ds in f.items():
            if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in "fiu" or ds.ndim != 2:
                continue
            if ds.size == 1:
                scalars[name] = float(ds[()].reshape(-1)[0])
            elif 1 in ds.shape:
                cols[name] = _Row(ds, transpose=ds.shape[1] == 1)
        return _mat_records(path, cols, scalars, fs_given, [f.close])
    import scipy.io  # lazy: scipy.io only for a MATLAB v5 file

    try:
        data = scipy.io.loadmat(path, squeeze_me=True)
    except Exception as exc:
        raise InputError(path, "", f"not a readable MATLAB file: {exc}") from exc
    cols, scalars = {}, {}
    for name, val in data.items():
        if name.startswith("__"):
            continue
        a = np.asarray(val)
        if a.dtype.kind not in "fiu":
            continue
        if a.size == 1:
            scalars[name] = float(a.reshape(-1)[0])
        elif a.ndim == 1:
            cols[name] = a
    return _mat_records(path, cols, scalars, fs_given, [])


def _mat_records(path: str, cols: dict[str, Column], scalars: dict[str, float], fs_given: float | None,
                 closers: list[Callable[[], None]]) -> list[TimeRecord]:
    tname = next((t for t in TIME_NAMES if t in cols), None)
    if tname is not None:
        time = cols.pop(tname)
        return _from_time(path, time, cols, closers)
    fs = _rate(path, next((scalars[k] for k in RATE_NAMES if k in scalars), None), fs_given, "sample_rate_hz")
    t0 = next((scalars[k] for k in START_NAMES if k in scalars), 0.0)
    return [TimeRecord(path, fs, t0, cols, closers)]


def _tdms(path: str, fs_given: float | None, group: str | None) -> TimeRecord:
    from nptdms import TdmsFile  # lazy: npTDMS only for a TDMS file

    try:
        f = TdmsFile.open(path)
        groups = f.groups()
    except Exception as exc:
        raise InputError(path, "", f"not a readable TDMS file (truncated or corrupt?): {exc}") from exc
    if not groups:
        raise InputError(path, "", "no groups in the TDMS file")
    names = [g.name for g in groups]
    if group is not None and group not in names:
        f.close()
        raise InputError(path, f"group {group!r}", f"not in the file (groups: {', '.join(names)})")
    g = f[group] if group is not None else groups[0]
    chans = g.channels()
    cols: dict[str, Column] = {}
    fs_found = None
    t0 = 0.0
    lengths = set()
    for ch in chans:
        cols[ch.name] = ch
        lengths.add(len(ch))
        inc = ch.properties.get("wf_increment")
        if inc:
            fs_found = 1.0 / float(inc)
            t0 = float(ch.properties.get("wf_start_offset", 0.0))
    if len(lengths) > 1:
        f.close()
        raise InputError(path, f"group {g.name!r}", f"channels have different lengths {sorted(lengths)} "
                                                    "(truncated file?)")
    declared = g.properties.get("n_samples")
    if declared is not None and lengths and int(declared) != lengths.pop():
        f.close()
        raise InputError(path, f"group {g.name!r}", f"file holds fewer samples than its n_samples {int(declared)} "
                                                    "(truncated file)")
    fs = _rate(path, fs_found, fs_given, "wf_increment")
    return TimeRecord(path, fs, t0, cols, [f.close])


def _wav(path: str) -> TimeRecord:
    import scipy.io.wavfile  # lazy: scipy.io only for a WAV file

    try:
        fs, data = scipy.io.wavfile.read(path, mmap=True)
    except Exception as exc:
        raise InputError(path, "", f"not a readable WAV file: {exc}") from exc
    a = np.asarray(data) if data.ndim == 2 else np.asarray(data)[:, None]
    cols: dict[str, Column] = {str(k): a[:, k] for k in range(a.shape[1])}
    return TimeRecord(path, float(fs), 0.0, cols)


class _CsvTable:
    """A CSV file read on demand: the byte offset of every ``stride``-th data line, the last block
    parsed (all columns) cached."""

    def __init__(self, path: str, stride: int = 1 << 14):
        self.path, self.stride = path, stride
        with open(path, "rb") as fh:
            header = fh.readline()
            self.names = [h.strip().strip('"') for h in header.decode("utf-8").strip().split(",")]
            starts = [fh.tell()]
            n = 0
            pos = fh.tell()
            tail = b""
            while True:
                chunk = fh.read(1 << 24)
                if not chunk:
                    break
                nl = np.flatnonzero(np.frombuffer(chunk, np.uint8) == 10)
                first = n
                n += nl.size
                # data line k starts after newline k-1 (newlines counted from the data start)
                for k in range(((first + stride) // stride) * stride, n + 1, stride):
                    starts.append(pos + int(nl[k - 1 - first]) + 1)
                pos += len(chunk)
                tail = chunk[-1:]
            if tail and tail != b"\n":
                n += 1
        self.n = n
        self.starts = starts
        self.cache: tuple[int, int, np.ndarray] | None = None

    def rows(self, start: int, stop: int) -> np.ndarray:
        if self.cache is not None and self.cache[0] <= start and stop <= self.cache[1]:
            c = self.cache
            return c[2][start - c[0] : stop - c[0]]
        b = start // self.stride
        with open(self.path, "rb") as fh:
            fh.seek(self.starts[b])
            skip = start - b * self.stride
            lines = [fh.readline() for _ in range(skip + stop - start)][skip:]
        try:
            arr = np.loadtxt(io.BytesIO(b"".join(lines)), delimiter=",", ndmin=2, dtype=np.float64)
        except ValueError as exc:
            raise InputError(self.path, f"rows {start + 2}-{stop + 1}", f"not numeric CSV: {exc}") from exc
        self.cache = (start, stop, arr)
        return arr


class _CsvColumn:
    def __init__(self, table: _CsvTable, k: int):
        self.table, self.k = table, k

    def __len__(self) -> int:
        return self.table.n

    def __getitem__(self, key: slice) -> np.ndarray:
        a, b, _ = key.indices(self.table.n)
        return self.table.rows(a, b)[:, self.k] if b > a else np.empty(0)


def _csv(path: str, fs_given: float | None) -> list[TimeRecord]:
    table = _CsvTable(path)
    if len(set(table.names)) != len(table.names):
        raise InputError(path, "header", f"repeated column names {table.names}")
    cols: dict[str, Column] = {n: _CsvColumn(table, k) for k, n in enumerate(table.names)}
    return _tabular(path, cols, fs_given)


def _tabular(path: str, cols: dict[str, Column], fs_given: float | None) -> list[TimeRecord]:
    tname = next((t for t in TIME_NAMES if t in cols), None)
    if tname is not None and fs_given is None:
        time = cols.pop(tname)
        return _from_time(path, time, cols, [])
    if tname is not None:
        cols.pop(tname)
    return [TimeRecord(path, _rate(path, None, fs_given, "sample_rate_hz"), 0.0, cols)]


def _parquet(path: str, fs_given: float | None) -> list[TimeRecord]:
    if not parquet_available():
        raise InputError(path, "format", "Parquet needs pyarrow (pip install pyarrow)")
    import pyarrow.parquet as pq  # lazy: an optional dependency, only for a Parquet file

    table = pq.read_table(path)
    cols: dict[str, Column] = {n: table.column(n).to_numpy() for n in table.column_names}
    meta = table.schema.metadata or {}
    fs = meta.get(b"sample_rate_hz")
    if fs is not None and fs_given is None and not any(t in cols for t in TIME_NAMES):
        fs_given = float(fs)
    recs = _tabular(path, cols, fs_given)
    t0 = meta.get(b"start_s")
    if t0 is not None and len(recs) == 1 and not any(t in table.column_names for t in TIME_NAMES):
        recs[0].t0_s = float(t0)
    return recs


def _uff(path: str) -> TimeRecord:
    from rotorcheck.sweep.uff import _load_sets  # lazy: pyuff only for a UFF58 file

    cols: dict[str, Column] = {}
    fs: float | None = None
    t0 = 0.0
    for i, s in enumerate(_load_sets(path)):
        if int(s.get("func_type", -1)) != 1:
            continue
        name = str(s.get("id1", "")).strip() or f"dataset{i + 1}"
        x = np.asarray(s["x"], dtype=np.float64)
        if x.size < 2:
            raise InputError(path, f"dataset #{i + 1}", "fewer than 2 samples")
        inc = float(x[1] - x[0])
        this_fs = 1.0 / inc
        if fs is not None and not np.isclose(this_fs, fs, rtol=1e-9):
            raise InputError(path, f"dataset #{i + 1} ({name})", f"sample rate {this_fs:g} Hz differs from {fs:g} Hz")
        fs, t0 = this_fs, float(x[0])
        cols[name] = np.asarray(s["data"]).real.astype(np.float64)
    if not cols:
        raise InputError(path, "", "no UFF58 time-response records (function type 1)")
    assert fs is not None
    return TimeRecord(path, fs, t0, cols)


def _hdf5(path: str, fs_given: float | None, group: str | None) -> TimeRecord:
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise InputError(path, "", f"not a readable HDF5 file: {exc}") from exc
    gname = group or "/"
    if gname not in f:
        f.close()
        raise InputError(path, f"group {gname!r}", "not in the file")
    g = f[gname]
    cols: dict[str, Column] = {n: ds for n, ds in g.items()
                               if isinstance(ds, h5py.Dataset) and ds.ndim == 1 and ds.dtype.kind in "fiu"}
    fs_found = next((float(g.attrs[k]) for k in RATE_NAMES if k in g.attrs), None)
    t0 = next((float(g.attrs[k]) for k in START_NAMES if k in g.attrs), 0.0)
    tname = next((t for t in TIME_NAMES if t in cols), None)
    if tname is not None and fs_found is None:
        time = cols.pop(tname)
        recs = _from_time(path, time, cols, [f.close])
        if len(recs) > 1:
            f.close()
            raise InputError(path, "time", "gaps in an HDF5 time vector are not supported: split the file")
        return recs[0]
    return TimeRecord(path, _rate(path, fs_found, fs_given, "sample_rate_hz"), t0, cols, [f.close])

