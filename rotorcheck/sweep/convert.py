"""Conversion between the sweep file formats: the library behind ``rotorcheck convert IN OUT``.

Formats (:data:`FORMATS`), chosen from the extension (``.h5``/``.hdf5``, ``.uff``/``.unv``,
``.csv``) or given as ``from_format``/``to_format``:

- ``hdf5``: the contract (:mod:`rotorcheck.sweep.hdf5io`);
- ``uff``: Universal File Format dataset 58 (:mod:`rotorcheck.sweep.uff`; binary 58b, bit-exact,
  or ASCII 58 with ``ascii=True``: 6 significant digits of the frequency);
- ``csv``: the tidy CSV (:mod:`rotorcheck.sweep.tidy_csv`) plus ``<stem>.columns.yaml`` beside it
  with what the CSV lacks (rig id, source, created_utc, generator, channel table, run notes);
- ``wide``: the wide CSV with its column map (:mod:`rotorcheck.sweep.wide_csv`).

What a foreign file lacks comes from the options (:class:`ConvertOptions`): ``speed_rpm`` (a
third-party UFF58 states a speed only as a z-axis value of type rpm), ``rig_id``, ``run_id``
(names the run of a file without run ids, ``"<speed:g>rpm"`` by default; selects one run of a file
with run ids), and the noise statement an FRF-only run needs (spec "Version 2"):
``noise_source`` ("measured" or "assumed: <rule>", it replaces the file's) and ``noise_var``
(variance of every FRF entry, (m/N)^2). A run without ``frf_var`` gets one from ``noise_var`` or
from an assumed rule of the forms ``"X % of |H|"`` (std X % of |H| at each point) or
``"X % of max |H|"`` (std X % of the pair's largest |H|, at every point) (:func:`assumed_frf_var`).
A value the file states and an option contradicts, a required value that neither gives, an option
with nothing to act on: :class:`~rotorcheck.errors.InputError` / ``SweepFormatError`` naming the file
and what to pass (exit 2). A foreign file's ``created_utc`` is its modification time (UTC) and its
``source`` "measured". Writes are atomic and never replace a file unless ``force``.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rotorcheck.errors import InputError
from rotorcheck.fileio import atomic_write_text, check_writable
from rotorcheck.safeload import load_yaml
from rotorcheck.sweep import uff as _uff
from rotorcheck.sweep.format import (
    DIRECTIONS,
    ROLE_QUANTITY,
    SOURCES,
    Channel,
    Sweep,
    SweepFormatError,
    noise_source_problem,
    sweep_schema_version,
)
from rotorcheck.sweep.hdf5io import read_sweep, write_sweep
from rotorcheck.sweep.tidy_csv import export_tidy_csv, import_tidy_csv
from rotorcheck.sweep.validation import validate_sweep
from rotorcheck.sweep.wide_csv import MAX_MAP_BYTES, default_column_map_path, export_wide_csv, import_wide_csv

__all__ = [
    "FORMATS",
    "ConvertOptions",
    "assumed_frf_var",
    "convert",
    "format_of",
    "read_any",
    "write_any",
]

#: format names (``--from``/``--to``)
FORMATS = ("hdf5", "uff", "csv", "wide")
_ALIASES = {"hdf5": "hdf5", "h5": "hdf5", "uff": "uff", "uff58": "uff", "unv": "uff", "csv": "csv",
            "tidy": "csv", "wide": "wide"}
_EXTENSIONS = {".h5": "hdf5", ".hdf5": "hdf5", ".uff": "uff", ".unv": "uff", ".csv": "csv"}
#: UFF specific data type 19: rpm (z axis)
_UFF_RPM = 19
_RULE = re.compile(r"^\s*(?P<x>\d+(?:\.\d*)?(?:[eE][+-]?\d+)?)\s*%\s*of\s+(?P<max>max\s+)?\|H\|\s*$")
_NOISE_HELP = ("--noise-source 'measured' (the file's variance is the analyser's) | 'assumed: <rule>' "
               "(rules convert computes: 'X % of |H|', 'X % of max |H|'), or --noise-var VAR ((m/N)^2)")


@dataclass
class ConvertOptions:
    """What a foreign file lacks, and how to write (module docstring)."""

    speed_rpm: float | None = None
    noise_source: str | None = None
    noise_var: float | None = None
    rig_id: str | None = None
    run_id: str | None = None
    column_map: str | os.PathLike[str] | None = None
    ascii: bool = False
    force: bool = False


def format_of(path: str | os.PathLike[str], given: str | None, *, wide: bool = False, side: str = "IN") -> str:
    """The format of ``path``: ``given`` (a name or alias), else its extension; ``wide`` turns csv
    into wide."""
    if given is not None:
        fmt = _ALIASES.get(given.lower())
        if fmt is None:
            raise InputError(None, "--from" if side == "IN" else "--to",
                             f"unknown format {given!r} (one of {', '.join(FORMATS)})")
        return fmt
    ext = Path(path).suffix.lower()
    if ext not in _EXTENSIONS:
        raise InputError(os.fspath(path), "", f"cannot tell the format from the extension {ext or '(none)'!r}: use "
                         f".h5, .hdf5, .uff, .unv or .csv, or pass {'--from' if side == 'IN' else '--to'} "
                         f"({', '.join(FORMATS)})")
    fmt = _EXTENSIONS[ext]
    return "wide" if fmt == "csv" and wide else fmt


def _mtime_utc(path: str) -> str:
    t = os.stat(path).st_mtime
    return _dt.datetime.fromtimestamp(int(t), _dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def assumed_frf_var(rule: str, frf: np.ndarray) -> np.ndarray | None:
    """``frf_var`` (m/N)^2 from an assumed rule (the text after ``"assumed: "``), or None when the
    rule is not one of the computable forms: ``"X % of |H|"`` -> ``(X/100 |H|)^2`` at each point,
    ``"X % of max |H|"`` -> ``(X/100 max_f |H|)^2`` per output/input pair, at every point."""
    m = _RULE.match(rule)
    if m is None:
        return None
    x = float(m.group("x")) / 100.0
    mag = np.abs(np.asarray(frf, dtype=np.complex128))
    if m.group("max"):
        mag = np.broadcast_to(mag.max(axis=0, keepdims=True), mag.shape)
    return np.ascontiguousarray((x * mag) ** 2, dtype=np.float64)


# --------------------------------------------------------------------------------------------
# the tidy CSV's side file
# --------------------------------------------------------------------------------------------


def _tidy_side_doc(sweep: Sweep) -> dict[str, Any]:
    doc: dict[str, Any] = {
        "format": "tidy",
        "rig_id": sweep.rig_id,
        "source": sweep.source,
        "created_utc": sweep.created_utc,
        "generator": sweep.generator,
        "channels": [{"name": c.name, "role": c.role, "node": int(c.node), "direction": c.direction}
                     for c in sweep.channels],
    }
    notes = {rid: r.notes for rid, r in sweep.runs.items() if r.notes}
    if notes:
        doc["notes"] = notes
    return doc


def _read_tidy_side(path: str, csv_file: str) -> dict[str, Any]:
    if not os.path.exists(path):
        raise SweepFormatError(csv_file, "channels", "a tidy CSV names its channels only: pass --column-map FILE "
                               "with channels: [{name, role, node, direction}] (and rig_id, source, created_utc); "
                               f"none at {path}")
    try:
        with open(path, encoding="utf-8-sig") as fh:
            text = fh.read(MAX_MAP_BYTES + 1)
        if len(text) > MAX_MAP_BYTES:
            raise SweepFormatError(path, "/", f"over {MAX_MAP_BYTES} characters: no side file is that long")
        d = load_yaml(text)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:  # JSON is YAML too
        raise SweepFormatError(path, "/", f"not readable as YAML/JSON: {exc}") from None
    if not isinstance(d, Mapping):
        raise SweepFormatError(path, "/", "expected a mapping of keys")
    known = {"format", "rig_id", "source", "created_utc", "generator", "channels", "notes"}
    extra = sorted(str(k) for k in d if k not in known)
    if extra:
        raise SweepFormatError(path, "/", f"unknown keys {extra} (known: {sorted(known)})")
    if d.get("format", "tidy") != "tidy":
        raise SweepFormatError(path, "format", f"{d['format']!r}: not the side file of a tidy CSV")
    chans = d.get("channels")
    if not isinstance(chans, list) or not chans:
        raise SweepFormatError(path, "channels", "missing or empty: [{name, role, node, direction}]")
    out = []
    for i, c in enumerate(chans):
        where = f"channels[{i}]"
        if not isinstance(c, Mapping) or any(k not in c for k in ("name", "role", "node", "direction")):
            raise SweepFormatError(path, where, "expected {name, role, node, direction}")
        role, node, direction = c["role"], c["node"], c["direction"]
        if role not in ROLE_QUANTITY:
            raise SweepFormatError(path, f"{where}.role", f"expected input or output, got {role!r}")
        if isinstance(node, bool) or not isinstance(node, int) or node < 1:
            raise SweepFormatError(path, f"{where}.node", f"expected an integer >= 1, got {node!r}")
        if direction not in DIRECTIONS:
            raise SweepFormatError(path, f"{where}.direction", f"expected one of {list(DIRECTIONS)}, got {direction!r}")
        qty = ROLE_QUANTITY[role]
        out.append(Channel(str(c["name"]), role, node, direction, qty, "N" if qty == "force" else "m"))
    if "source" in d and d["source"] not in SOURCES:
        raise SweepFormatError(path, "source", f"expected one of {list(SOURCES)}, got {d['source']!r}")
    notes = d.get("notes", {})
    if not isinstance(notes, Mapping):
        raise SweepFormatError(path, "notes", "expected a mapping run id -> text")
    return {**d, "channels": out, "notes": notes}


# --------------------------------------------------------------------------------------------
# read
# --------------------------------------------------------------------------------------------


def _uff_facts(file: str) -> tuple[bool, float | None]:
    """(foreign, speed the file states or None) of a UFF58 file; a foreign file's FRF records must
    be receptance over frequency."""
    sets = _uff._load_sets(file)
    foreign = not any("kind" in _uff._parse(s.get("id1", "")) for s in sets)
    if not foreign:
        return False, None
    speeds: set[float] = set()
    stated = True
    for i, s in enumerate(sets):
        if int(s.get("func_type", -1)) != 4:
            continue
        _uff._frf_scale(file, f"dataset #{i + 1}", s)  # records 8-10: frequency, displacement per force
        if int(s.get("z_axis_spec_data_type", 0)) == _UFF_RPM:
            speeds.add(float(s.get("z_axis_value", 0.0)))
        else:
            stated = False
    if stated and len(speeds) > 1:
        raise SweepFormatError(file, "record 7/z-axis", f"FRF records at several speeds {sorted(speeds)} rpm: "
                               "one run per file for a foreign UFF58")
    return True, (speeds.pop() if stated and speeds else None)


def _import_noise(opts: ConvertOptions) -> str | None:
    """The noise statement handed to the importers (``noise_var`` alone states its own)."""
    if opts.noise_source is not None:
        return opts.noise_source
    if opts.noise_var is not None:
        return f"assumed: frf_var = {opts.noise_var!r} (m/N)^2 at every point"
    return None


def _read_foreign_uff(file: str, speed: float | None, opts: ConvertOptions) -> Sweep:
    if speed is not None and opts.speed_rpm is not None and float(opts.speed_rpm) != speed:
        raise InputError(file, "record 7/z-axis", f"the file states {speed!r} rpm, --speed gives {opts.speed_rpm!r}: "
                         "drop --speed or correct the file")
    speed = speed if speed is not None else opts.speed_rpm
    noise = _import_noise(opts)
    missing = []
    if speed is None:
        missing.append("the speed (pass --speed RPM)")
    if noise is None:
        missing.append(f"a noise statement for its FRF-only data (pass {_NOISE_HELP})")
    if opts.rig_id is None:
        missing.append("the rig id (pass --rig-id NAME, as in the rig YAML)")
    if missing:
        raise InputError(file, "", "foreign UFF58 file (no rotorcheck ID tokens) lacks " + "; ".join(missing))
    assert speed is not None
    rid = opts.run_id if opts.run_id is not None else f"{float(speed):g}rpm"
    sw = _uff.import_uff58(file, noise_source=noise, run_id=rid, rig_id=opts.rig_id, source="measured",
                           created_utc=_mtime_utc(file))
    for run in sw.runs.values():
        run.speed_rpm = float(speed)
    return sw


def read_any(path: str | os.PathLike[str], fmt: str, opts: ConvertOptions) -> Sweep:
    """Read ``path`` in format ``fmt`` with the options' fill-ins, select ``run_id`` and apply the
    noise options (module docstring)."""
    file = os.fspath(path)
    if not os.path.exists(file):
        raise InputError(file, "", "no such file")
    names_run = False  # True where run_id named the run (the file has none)
    if fmt == "hdf5":
        sw = read_sweep(file)
    elif fmt == "uff":
        foreign, speed = _uff_facts(file)
        if foreign:
            sw, names_run = _read_foreign_uff(file, speed, opts), True
        else:
            sw = _uff.import_uff58(file, noise_source=_import_noise(opts))
    elif fmt == "csv":
        side_path = os.fspath(opts.column_map) if opts.column_map is not None else os.fspath(
            default_column_map_path(file))
        side = _read_tidy_side(side_path, file)
        rig = side.get("rig_id")
        if rig is not None and opts.rig_id is not None and rig != opts.rig_id:
            raise InputError(side_path, "rig_id", f"states {rig!r}, --rig-id gives {opts.rig_id!r}")
        rig = rig if rig is not None else opts.rig_id
        if rig is None:
            raise InputError(file, "rig_id", f"no rig id: pass --rig-id NAME (or put rig_id: in {side_path})")
        sw = import_tidy_csv(file, side["channels"], rig_id=str(rig), source=str(side.get("source", "measured")),
                             created_utc=str(side.get("created_utc", _mtime_utc(file))),
                             generator=None if side.get("generator") is None else str(side["generator"]),
                             noise_source=_import_noise(opts))
        for rid, text in side["notes"].items():
            if rid in sw.runs:
                sw.runs[rid].notes = str(text)
    elif fmt == "wide":
        sw, names_run = import_wide_csv(file, opts.column_map, speed_rpm=opts.speed_rpm, run_id=opts.run_id,
                                        rig_id=opts.rig_id, noise_source=_import_noise(opts)), True
    else:
        raise InputError(None, "--from", f"unknown format {fmt!r}")
    if not names_run:
        _check_stated(file, sw, opts)
    _apply_noise(file, sw, opts)
    validate_sweep(sw, file)
    return sw


def _check_stated(file: str, sw: Sweep, opts: ConvertOptions) -> None:
    """A file with run ids, speeds and a rig id: ``run_id`` selects, ``speed_rpm``/``rig_id`` must agree."""
    if opts.run_id is not None:
        if opts.run_id not in sw.runs:
            raise InputError(file, "--run-id", f"no run {opts.run_id!r} (runs: {', '.join(sw.runs)})")
        sw.runs = {opts.run_id: sw.runs[opts.run_id]}
    if opts.speed_rpm is not None:
        for rid, run in sw.runs.items():
            if float(run.speed_rpm) != float(opts.speed_rpm):
                raise InputError(file, f"/runs/{rid}@speed_rpm", f"the file states {run.speed_rpm!r} rpm, --speed "
                                 f"gives {opts.speed_rpm!r}: drop --speed or pick the run with --run-id")
    if opts.rig_id is not None and opts.rig_id != sw.rig_id:
        raise InputError(file, "rig_id", f"the file states {sw.rig_id!r}, --rig-id gives {opts.rig_id!r}")


def _apply_noise(file: str, sw: Sweep, opts: ConvertOptions) -> None:
    if opts.noise_source is None and opts.noise_var is None:
        return
    frf_only = [r for r in sw.runs.values() if r.is_frf_only]
    if not frf_only:
        raise InputError(file, "--noise-source/--noise-var", "no FRF-only run here (its runs carry phasors and "
                         "their own variance): drop the option")
    for run in frf_only:
        where = f"/runs/{run.run_id}/frf_var"
        if opts.noise_var is not None:
            if run.frf_var is not None:
                raise InputError(file, where, "the file has the FRF's variance: drop --noise-var (state its origin "
                                 "with --noise-source)")
            run.frf_var = np.full(np.shape(run.frf), float(opts.noise_var))
            run.noise_source = _import_noise(opts)
            continue
        ns = str(opts.noise_source)
        run.noise_source = ns
        if run.frf_var is not None:
            continue
        if ns == "measured":
            raise InputError(file, where, "'measured' says the FRF's variance comes from the file, but it has none: "
                             "pass --noise-var VAR ((m/N)^2) or --noise-source 'assumed: X % of |H|'")
        var = assumed_frf_var(ns[len("assumed: "):], run.frf)
        if var is None:
            raise InputError(file, where, f"no variance of the FRF in the file, and {ns!r} is not a rule convert can "
                             "compute: pass --noise-var VAR ((m/N)^2) with it, or --noise-source "
                             "'assumed: X % of |H|' | 'assumed: X % of max |H|'")
        run.frf_var = var


# --------------------------------------------------------------------------------------------
# write
# --------------------------------------------------------------------------------------------


def _targets(path: str | os.PathLike[str], fmt: str, opts: ConvertOptions) -> list[Path]:
    p = Path(path)
    if fmt == "csv":
        return [p, default_column_map_path(p)]
    if fmt == "wide":
        return [p, Path(opts.column_map) if opts.column_map is not None else default_column_map_path(p)]
    return [p]


def write_any(sweep: Sweep, path: str | os.PathLike[str], fmt: str, opts: ConvertOptions) -> list[Path]:
    """Write ``sweep`` as ``fmt`` (atomic; refuses existing files unless ``opts.force``); the paths written."""
    targets = _targets(path, fmt, opts)
    check_writable(targets, opts.force)
    if fmt == "hdf5":
        write_sweep(sweep, path, force=opts.force)
    elif fmt == "uff":
        _uff.export_uff58(sweep, path, force=opts.force, binary=not opts.ascii)
    elif fmt == "csv":
        export_tidy_csv(sweep, path, force=opts.force)
        text = "# rotorcheck tidy CSV side file: what the CSV lacks\n" + yaml.safe_dump(
            _tidy_side_doc(sweep), sort_keys=False, allow_unicode=True)
        atomic_write_text(targets[1], text, overwrite=opts.force)
    elif fmt == "wide":
        if len(sweep.runs) != 1:
            raise InputError(None, "--run-id", f"a wide CSV holds one run; the input has {len(sweep.runs)} "
                             f"({', '.join(sweep.runs)}): pass --run-id")
        export_wide_csv(sweep, path, force=opts.force, column_map_path=targets[1])
    else:
        raise InputError(None, "--to", f"unknown format {fmt!r}")
    return targets


# --------------------------------------------------------------------------------------------
# the command
# --------------------------------------------------------------------------------------------


def convert(
    src: str | os.PathLike[str],
    dst: str | os.PathLike[str],
    *,
    from_format: str | None = None,
    to_format: str | None = None,
    wide: bool = False,
    options: ConvertOptions | None = None,
) -> dict[str, Any]:
    """Convert ``src`` into ``dst`` and return a summary (formats, files, runs, channels, points).

    ``wide``: the ``.csv`` side is a wide CSV (both sides ``.csv``: say which with
    ``from_format``/``to_format``). Options are checked before anything is read; an existing
    output is refused before anything is written (unless ``options.force``).
    """
    opts = options if options is not None else ConvertOptions()
    if wide:  # the .csv side whose format is not given
        csv_in = from_format is None and Path(src).suffix.lower() == ".csv"
        csv_out = to_format is None and Path(dst).suffix.lower() == ".csv"
        if csv_in and csv_out:
            raise InputError(None, "--wide", "IN and OUT are both .csv: say which is wide (--from wide or --to wide)")
        if not (csv_in or csv_out or "wide" in (from_format, to_format)):
            raise InputError(None, "--wide", "neither IN nor OUT is a .csv file")
    fin = format_of(src, from_format, wide=wide, side="IN")
    fout = format_of(dst, to_format, wide=wide, side="OUT")
    if opts.ascii and fout != "uff":
        raise InputError(None, "--ascii", f"applies to UFF58 output only (OUT is {fout})")
    if opts.column_map is not None and "wide" not in (fin, fout) and fin != "csv":
        raise InputError(None, "--column-map", "applies to a wide CSV (read or written) or a tidy CSV read")
    if opts.noise_source is not None:
        why = noise_source_problem(opts.noise_source)
        if why is not None:
            raise InputError(None, "--noise-source", why)
    if opts.noise_var is not None:
        if not (math.isfinite(opts.noise_var) and opts.noise_var > 0):
            raise InputError(None, "--noise-var", f"{opts.noise_var!r}: expected a variance > 0, (m/N)^2")
        if opts.noise_source == "measured":
            raise InputError(None, "--noise-var", "assumes a variance, --noise-source says 'measured': state the "
                             "assumption with --noise-source 'assumed: ...' or drop one of them")
    if opts.speed_rpm is not None and not (math.isfinite(opts.speed_rpm) and opts.speed_rpm >= 0):
        raise InputError(None, "--speed", f"{opts.speed_rpm!r}: expected a speed >= 0, rpm")
    # --column-map belongs to IN when IN is a CSV, else to a wide OUT (where its map is written)
    map_in = fin in ("csv", "wide")
    read_opts = dataclasses.replace(opts, column_map=opts.column_map if map_in else None)
    write_opts = dataclasses.replace(opts, column_map=None if map_in else opts.column_map)
    check_writable(_targets(dst, fout, write_opts), opts.force)
    sweep = read_any(src, fin, read_opts)
    written = write_any(sweep, dst, fout, write_opts)
    return summary(sweep, src, dst, fin, fout, written, ascii_uff=opts.ascii)


def summary(sweep: Sweep, src: str | os.PathLike[str], dst: str | os.PathLike[str], fin: str, fout: str,
            written: list[Path], *, ascii_uff: bool = False) -> dict[str, Any]:
    """The ``--json`` document of ``rotorcheck convert``."""
    runs: list[dict[str, Any]] = []
    for run in sweep.runs.values():
        f = np.asarray(run.frequency, dtype=np.float64)
        runs.append({
            "run_id": run.run_id,
            "speed_rpm": float(run.speed_rpm),
            "n_points": int(f.size),
            "f_min_hz": float(f[0]),
            "f_max_hz": float(f[-1]),
            "frf_only": bool(run.is_frf_only),
            "frf_var": run.frf_variance() is not None,
            "noise_source": run.noise_source,
        })
    return {
        "input": os.fspath(src),
        "output": os.fspath(dst),
        "format_in": fin,
        "format_out": fout,
        **({"uff_encoding": "ascii 58" if ascii_uff else "binary 58b"} if fout == "uff" else {}),
        "files": [os.fspath(p) for p in written],
        "rig_id": sweep.rig_id,
        "schema_version": sweep_schema_version(sweep),
        "channels": [{"name": c.name, "role": c.role, "node": int(c.node), "direction": c.direction, "unit": c.unit}
                     for c in sweep.channels],
        "runs": runs,
        "n_points": sum(int(r["n_points"]) for r in runs),
    }
