"""Reader and writer of the HDF5 sweep file (``rotorcheck.sweep`` versions 1 and 2) and its SHA-256.

The reader validates everything on open and raises :class:`SweepFormatError` naming the file, the
path inside it and the reason; it never guesses (no dtype coercion, no reordering, no repair). It
reads version 1 (each run one pattern, ``n_exc = 1``) and version 2 (pattern axis, FRF-only runs).
The writer writes version 1 exactly as before unless a run needs version 2
(:attr:`~rotorcheck.sweep.format.Run.needs_v2`: several patterns, FRF-only, ``input_var``,
``frf_var`` or ``noise_source``); it is atomic (:func:`rotorcheck.fileio.atomic_path`) and refuses
to overwrite unless ``force=True``.

netCDF-4 view (xarray ``engine="h5netcdf"``, :mod:`rotorcheck.netcdf_view`): the writer names every axis
with an HDF5 dimension scale, so ``xarray.open_dataset(path, engine="h5netcdf", group="runs/<run_id>")``
shows the coordinates ``frequency`` (``units`` "Hz"), ``input`` and ``output`` (the names of the input and
output channels, the columns' order) and, with ``period_phasor``, ``channel`` (every channel's name, the
order of ``/channels``), and each data variable with its ``units`` (:data:`DATASET_UNITS`). The root holds
the coordinate ``channel`` (the channel names, the dimension of ``/channels/*``) and, as dimensions without
a variable, the axes whose length is per run: ``pattern_<n_exc>`` (version 2) and ``period_<p>``;
``xarray.open_datatree(path, engine="h5netcdf")`` opens the whole file. Inside a run group the writer adds
the coordinate variables ``input``, ``output`` and ``channel`` beside the contract's datasets (no
contract name is used, moved or changed); complex128 stays the h5py compound (r, i), which h5netcdf and
xarray read as complex. The reader ignores the labels (files written before them read the same).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np

from rotorcheck.fileio import (
    atomic_path,
    check_hdf5_global_heaps,
    file_sha256,
    hdf5_attr_problem,
    hdf5_vlen_problem,
)
from rotorcheck.netcdf_view import Dimensions, attach
from rotorcheck.sweep.format import (
    CHANNEL_FIELDS,
    EXCITATION,
    PATTERN_ATTRS,
    PHASOR_CONVENTION,
    RUN_DATASETS,
    RUN_OPTIONAL_V2,
    SCHEMA,
    SCHEMA_VERSION_V1,
    SCHEMA_VERSIONS,
    SIDEBAND_ATTRS,
    Channel,
    Run,
    Sweep,
    SweepFormatError,
    sweep_schema_version,
)
from rotorcheck.sweep.validation import (
    FRF_RTOL,
    PERIOD_RTOL,
    check_text,
    dtype_name,
    validate_channels,
    validate_header,
    validate_run,
    validate_sweep,
)

# --------------------------------------------------------------------------------------------
# reader
# --------------------------------------------------------------------------------------------


def _attr(file: str, obj: h5py.HLObject, name: str, where: str) -> Any:
    if name not in obj.attrs:
        raise SweepFormatError(file, f"{where}@{name}", "missing attribute")
    problem = hdf5_attr_problem(obj, name)  # libhdf5 can crash reading a corrupt datatype
    if problem:
        raise SweepFormatError(file, f"{where}@{name}", problem)
    try:
        return obj.attrs[name]
    except Exception as exc:  # unreadable attribute: report, do not guess
        raise SweepFormatError(file, f"{where}@{name}", f"unreadable attribute: {exc}") from exc


#: the global heaps of the file being read (fileio.check_hdf5_global_heaps), for :func:`_check_vlen`
_HEAPS: dict[str, dict[int, dict[int, int]]] = {}


def _check_vlen(file: str, path: str, obj: h5py.Dataset) -> None:
    """The variable-length strings of a contiguous dataset point into the file's global heaps (checked on
    the raw descriptors before HDF5 follows them)."""
    heaps = _HEAPS.get(file)
    info = h5py.check_string_dtype(obj.dtype)
    if heaps is None or info is None or info.length is not None:
        return
    offset = obj.id.get_offset()
    if offset is None:  # chunked or compact: no raw block to look at
        return
    base = obj.file.userblock_size
    with open(file, "rb") as fh:
        fh.seek(base + offset)
        raw = fh.read(16 * obj.size)
    if len(raw) < 16 * obj.size:
        raise SweepFormatError(file, path, "the strings' descriptors run past the end of the file (truncated?)")
    problem = hdf5_vlen_problem(raw, heaps, base)
    if problem:
        raise SweepFormatError(file, path, f"corrupt string data: {problem}")


def _read_ds(file: str, grp: h5py.Group, name: str, where: str) -> np.ndarray:
    path = f"{where}/{name}"
    if name not in grp:
        raise SweepFormatError(file, path, "missing dataset")
    obj = grp.get(name)
    if not isinstance(obj, h5py.Dataset):
        raise SweepFormatError(file, path, f"expected a dataset, found {type(obj).__name__}")
    _check_vlen(file, path, obj)
    try:
        if obj.dtype.kind in "OS" or h5py.check_string_dtype(obj.dtype) is not None:
            return np.asarray(obj.asstr()[()], dtype=object)
        return np.asarray(obj[()])
    except Exception as exc:
        raise SweepFormatError(file, path, f"unreadable dataset (truncated or corrupt?): {exc}") from exc


def _as_text_array(file: str, path: str, a: np.ndarray, n: int) -> list[str]:
    if a.ndim != 1 or a.shape[0] != n:
        raise SweepFormatError(file, path, f"wrong shape {a.shape}, expected ({n},)")
    return [check_text(file, path, v, "value") for v in a.tolist()]


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
            file, paths["node"], f"wrong dtype {dtype_name(node)}, expected an integer type"
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
    validate_channels(file, "/channels", chans)
    return chans


def _read_run_v2(file: str, g: h5py.Group, where: str, run_id: str, speed: Any, notes: str) -> Run:
    """A version-2 run as stored: the datasets present (the validator names a missing one)."""
    noise = None
    if "noise_source" in g.attrs:
        noise = check_text(file, f"{where}@noise_source", _attr(file, g, "noise_source", where), "noise_source")
    names = (*RUN_DATASETS, *RUN_OPTIONAL_V2, *SIDEBAND_ATTRS)
    data = {name: _read_ds(file, g, name, where) for name in names if name in g}
    if "frequency" not in data:
        raise SweepFormatError(file, f"{where}/frequency", "missing dataset")
    if "frf" not in data:
        raise SweepFormatError(file, f"{where}/frf", "missing dataset")
    return Run(
        run_id=run_id,
        speed_rpm=speed,
        frequency=data["frequency"],
        frf=data["frf"],
        frf_var=data.get("frf_var"),
        noise_source=noise,
        notes=notes,
        origin=file,
        **{PATTERN_ATTRS[n]: data.get(n) for n in PATTERN_ATTRS},
        **{SIDEBAND_ATTRS[n]: data.get(n) for n in SIDEBAND_ATTRS},
    )


#: a sweep whose datasets hold more than this many bytes is refused before anything is read
MAX_SWEEP_BYTES = 256 * 2**20


def check_self_contained(file: str, h5: h5py.File, max_bytes: int = MAX_SWEEP_BYTES) -> None:
    """Refuse what would make a sweep read outside itself or more than it should: external links,
    soft links (a loop among them hung or crashed the reader), virtual datasets and datasets with
    external raw storage (each can map another file of the machine into the sweep), and datasets
    totalling more than ``max_bytes``. Raises :class:`SweepFormatError` naming the path."""
    total = 0
    seen: set[Any] = set()

    def walk(group: h5py.Group, prefix: str) -> None:
        nonlocal total
        for name in group:
            path = f"{prefix}/{name}" if prefix != "/" else f"/{name}"
            link = group.get(name, getlink=True)
            if isinstance(link, h5py.ExternalLink):
                raise SweepFormatError(file, path, f"an external link to {link.filename}:{link.path}: a sweep "
                                       "file must hold its own data")
            if isinstance(link, h5py.SoftLink):
                raise SweepFormatError(file, path, f"a soft link to {link.path}: not part of the sweep format")
            try:
                obj = group[name]
            except (KeyError, OSError, RuntimeError, ValueError) as exc:  # HDF5 cannot open it: a corrupt header
                raise SweepFormatError(file, path, f"unreadable HDF5 object (truncated or corrupt file): {exc}"
                                       ) from None
            key = obj.id.__hash__()
            if key in seen:
                continue
            seen.add(key)
            if isinstance(obj, h5py.Group):
                walk(obj, path)
                continue
            if isinstance(obj, h5py.Dataset):
                if obj.is_virtual:
                    raise SweepFormatError(file, path, "a virtual dataset (it maps other files): not allowed in a "
                                           "sweep file")
                plist = obj.id.get_create_plist()
                if plist.get_external_count() > 0:
                    names = [plist.get_external(i)[0].decode(errors="replace")
                             for i in range(plist.get_external_count())]
                    raise SweepFormatError(file, path, f"external raw storage in {', '.join(names)}: a sweep file "
                                           "must hold its own data")
                total += int(obj.size) * int(obj.dtype.itemsize)
                if total > max_bytes:
                    raise SweepFormatError(file, path, f"the datasets exceed {max_bytes // 2**20} MiB: refused "
                                           "before reading (split the sweep into several files)")

    walk(h5, "/")


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
    heaps = check_hdf5_global_heaps(file, SweepFormatError)  # before the HDF5 library loops on a corrupt heap
    try:
        h5 = h5py.File(file, "r")
    except Exception as exc:
        raise SweepFormatError(file, "/", f"cannot open as HDF5 (truncated or corrupt file): {exc}") from exc
    with h5:
        _HEAPS[file] = heaps
        try:
            return _read_open(file, h5, frf_rtol, period_rtol)
        except SweepFormatError:
            raise
        except (KeyError, OSError, RuntimeError, ValueError, TypeError, IndexError) as exc:  # h5py on a corrupt file
            raise SweepFormatError(file, "/", f"unreadable HDF5 content (truncated or corrupt file): "
                                   f"{type(exc).__name__}: {exc}") from None
        finally:
            _HEAPS.pop(file, None)


def _read_open(file: str, h5: h5py.File, frf_rtol: float, period_rtol: float) -> Sweep:
    """:func:`read_sweep` of the opened file."""
    check_self_contained(file, h5)
    schema = check_text(file, "/@schema", _attr(file, h5, "schema", ""), "schema")
    if schema != SCHEMA:
        raise SweepFormatError(file, "/@schema", f"schema {schema!r}, expected {SCHEMA!r}")
    ver = _attr(file, h5, "schema_version", "")
    if isinstance(ver, np.ndarray) and ver.shape in ((), (1,)):
        ver = ver.reshape(()).item() if ver.dtype.kind in "iu" else ver
    if isinstance(ver, bool) or not isinstance(ver, int | np.integer):
        raise SweepFormatError(file, "/@schema_version", f"schema_version {ver!r} is not an integer")
    if int(ver) not in SCHEMA_VERSIONS:
        raise SweepFormatError(
            file,
            "/@schema_version",
            f"unknown schema_version {int(ver)} (this reader knows "
            f"{', '.join(str(v) for v in SCHEMA_VERSIONS)})",
        )
    version = int(ver)
    exc_attr = check_text(file, "/@excitation", _attr(file, h5, "excitation", ""), "excitation")
    if exc_attr != EXCITATION:
        raise SweepFormatError(file, "/@excitation", f"excitation {exc_attr!r}, expected {EXCITATION!r}")
    conv = check_text(
        file, "/@phasor_convention", _attr(file, h5, "phasor_convention", ""), "convention"
    )
    if conv != PHASOR_CONVENTION:
        raise SweepFormatError(
            file,
            "/@phasor_convention",
            f"phasor_convention {conv!r}, expected {PHASOR_CONVENTION!r}",
        )
    rig_id = check_text(file, "/@rig_id", _attr(file, h5, "rig_id", ""), "rig_id")
    source = check_text(file, "/@source", _attr(file, h5, "source", ""), "source")
    generator = check_text(file, "/@generator", _attr(file, h5, "generator", ""), "generator")
    created = check_text(file, "/@created_utc", _attr(file, h5, "created_utc", ""), "created_utc")
    validate_header(file, rig_id, source, generator, created)
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
            notes = check_text(file, f"{where}@notes", _attr(file, g, "notes", where), "notes")
        if version == SCHEMA_VERSION_V1:
            data = {name: _read_ds(file, g, name, where) for name in RUN_DATASETS}
            pp = _read_ds(file, g, "period_phasor", where) if "period_phasor" in g else None
            run = Run.from_v1(
                run_id,
                speed,
                data["frequency"],
                data["input_phasor"],
                data["output_phasor"],
                data["output_var"],
                data["n_periods"],
                data["frf"],
                period_phasor=pp,
                notes=notes,
                origin=file,
            )
        else:
            run = _read_run_v2(file, g, where, run_id, speed, notes)
        validate_run(
            file,
            run,
            channels,
            frf_rtol=frf_rtol,
            period_rtol=period_rtol,
            exact_dtypes=True,
            version=version,
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


#: ``units`` attribute of each run dataset (the netCDF view)
DATASET_UNITS = {
    "frequency": "Hz",
    "input_phasor": "N",
    "output_phasor": "m",
    "output_var": "m^2",
    "input_var": "N^2",
    "n_periods": "1",
    "frf": "m/N",
    "frf_var": "m^2/N^2",
    "period_phasor": "N (input channels), m (output channels)",
    "sideband_order": "1",
    "sideband_phasor": "m",
    "sideband_var": "m^2",
}
#: the axes after ``frequency`` of each run dataset (``pattern``/``period`` get their length appended);
#: in version 2 the phasor datasets (:data:`PATTERN_ATTRS`) have ``pattern`` first
_AXES = {
    "input_phasor": ("input",),
    "output_phasor": ("output",),
    "output_var": ("output",),
    "input_var": ("input",),
    "n_periods": (),
    "frf": ("output", "input"),
    "frf_var": ("output", "input"),
    "period_phasor": ("period", "channel"),
    "sideband_phasor": ("pattern", "order", "output"),
    "sideband_var": ("pattern", "order", "output"),
}
#: ``long_name`` of the channel-name coordinates
_LABEL_NAMES = {"channel": "channel name (/channels/name)", "input": "input channel name (force, N)",
                "output": "output channel name (displacement, m)"}


def _label_for_netcdf(h5: h5py.File, version: int, channels: list[Channel]) -> None:
    """Attach dimension scales, channel-name coordinates and ``units`` (module docstring: the netCDF-4 view)."""
    root = Dimensions(h5)
    names = {"channel": [c.name for c in channels], "input": [c.name for c in channels if c.role == "input"],
             "output": [c.name for c in channels if c.role == "output"]}
    channel = root.labels("channel", names["channel"], {"long_name": _LABEL_NAMES["channel"]})
    ch = h5["channels"]
    for fld in CHANNEL_FIELDS:
        attach(ch[fld], [channel], "1" if fld == "node" else None)
    for g in h5["runs"].values():
        local = Dimensions(g)
        freq = local.coordinate(g["frequency"], DATASET_UNITS["frequency"])
        if "sideband_order" in g:  # the order axis's coordinate (version 3)
            order = local.coordinate(g["sideband_order"], DATASET_UNITS["sideband_order"])
        for name, axes in _AXES.items():
            if name not in g:
                continue
            ds = g[name]
            dims = ("pattern", *axes) if version != SCHEMA_VERSION_V1 and name in PATTERN_ATTRS else axes
            scales = [freq]
            for axis, dname in enumerate(dims, start=1):
                if dname in names:
                    scales.append(local.labels(dname, names[dname], {"long_name": _LABEL_NAMES[dname]}))
                elif dname == "order":
                    scales.append(order)
                else:  # the pattern and period axes: lengths per run, shared by the file's runs at the root
                    scales.append(root.plain(dname, int(ds.shape[axis]), suffix=True))
            attach(ds, scales, DATASET_UNITS[name])


def write_sweep(sweep: Sweep, path: str | os.PathLike[str], force: bool = False,
                extra_attrs: Mapping[str, str] | None = None) -> None:
    """Validate and write ``sweep`` atomically (temp file in the same folder, fsync, rename).

    ``extra_attrs``: more root attributes (text, e.g. an importer's provenance as JSON); they may not
    replace the contract's own.

    Deterministic: the content depends only on ``sweep`` (``created_utc`` comes from the caller),
    no object timestamps are stored, so two writes of the same sweep are byte-identical.
    Raises ``FileExistsError`` if ``path`` exists and ``force`` is false.
    """
    target = os.fspath(path)
    validate_sweep(sweep, target)
    version = sweep_schema_version(sweep)
    str_dt = h5py.string_dtype("utf-8")
    with atomic_path(target, overwrite=force) as tmp:
        with h5py.File(tmp, "w", track_order=True, libver=("earliest", "v110")) as h5:
            h5.attrs["schema"] = SCHEMA
            h5.attrs["schema_version"] = np.int32(version)
            h5.attrs["rig_id"] = sweep.rig_id
            h5.attrs["created_utc"] = sweep.created_utc
            h5.attrs["excitation"] = EXCITATION
            h5.attrs["phasor_convention"] = PHASOR_CONVENTION
            h5.attrs["source"] = sweep.source
            h5.attrs["generator"] = sweep.generator
            for key, value in (extra_attrs or {}).items():
                if key in h5.attrs:
                    raise ValueError(f"extra attribute {key!r} would replace the contract's own")
                h5.attrs[key] = value
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
                if version == SCHEMA_VERSION_V1:
                    _put(g, "frequency", np.asarray(run.frequency, dtype=np.float64))
                    _put(g, "input_phasor", np.asarray(run.input_phasor, dtype=np.complex128))
                    _put(g, "output_phasor", np.asarray(run.output_phasor, dtype=np.complex128))
                    _put(g, "output_var", np.asarray(run.output_var, dtype=np.float64))
                    _put(g, "n_periods", np.asarray(run.n_periods, dtype=np.int32))
                    _put(g, "frf", np.asarray(run.frf, dtype=np.complex128))
                    if run.period_phasor is not None:
                        _put(g, "period_phasor", np.asarray(run.period_phasor, dtype=np.complex128))
                else:
                    _write_run_v2(g, run)
            _label_for_netcdf(h5, version, sweep.channels)


def _write_run_v2(g: h5py.Group, run: Run) -> None:
    """A version-2 run: the phasors with the pattern axis, or an FRF-only run."""
    if run.noise_source is not None:
        g.attrs["noise_source"] = run.noise_source
    _put(g, "frequency", np.asarray(run.frequency, dtype=np.float64))
    arrays = (
        ("input_phasor", run.input_phasor_exc, np.complex128),
        ("output_phasor", run.output_phasor_exc, np.complex128),
        ("output_var", run.output_var_exc, np.float64),
        ("input_var", run.input_var_exc, np.float64),
        ("n_periods", run.n_periods_exc, np.int32),
        ("frf", run.frf, np.complex128),
        ("frf_var", run.frf_var, np.float64),
        ("period_phasor", run.period_phasor_exc, np.complex128),
        ("sideband_order", run.sideband_order, np.int32),
        ("sideband_phasor", run.sideband_phasor_exc, np.complex128),
        ("sideband_var", run.sideband_var_exc, np.float64),
    )
    for name, a, dt in arrays:
        if a is not None:
            _put(g, name, np.asarray(a, dtype=dt))


def sweep_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 hex digest of the file bytes."""
    return file_sha256(path)

__all__ = ["DATASET_UNITS", "read_sweep", "sweep_sha256", "write_sweep"]
